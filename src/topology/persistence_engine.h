#pragma once
// The lower-star persistence engine's state and steps, shared by persistence.cpp (classification, dims 0
// and 2, the driver) and persistence_dim1.cpp (the dim-1 reduction). Internal: not installed.
#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstdint>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "chokeloops/topology/complex.h"
#include "chokeloops/topology/persistence.h"
#include "link_table.h"
#include "common/huge_page_allocator.h"

namespace chokeloops::detail {

// The engine's grid-sized arrays (saddle lists, records, columns): those of a huge page or more are backed by
// huge pages (see common/huge_page_allocator.h). Per-thread scratch stays in std::vector.
template <class T>
using BigVector = std::vector<T, HugePageAllocator<T>>;

constexpr std::uint32_t kOutside = 0xFFFFFFFFu;  // the outside of the box: +inf, never dies
using Clock = std::chrono::steady_clock;
inline double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// A vertex's steepest-descent and steepest-ascent steps, a nibble each (low: down, high: up): the link slot of
// its lowest (highest) neighbour, or one of these. One byte a vertex instead of two 32-bit pointers: the
// chains are followed only from the saddles' lobes, and are short where saddles are many.
constexpr std::uint8_t kStepNone = 15;     // a minimum (down) or a maximum (up)
constexpr std::uint8_t kStepOutside = 14;  // up: the vertex touches the outside of the box

// An edge with its vertices' values inline, so that ordering a heap of edges reads no field memory.
struct EdgeKey {
  float fhi, flo;
  std::uint32_t hi, lo;
  bool operator==(const EdgeKey& o) const { return hi == o.hi && lo == o.lo; }
};
inline bool edge_less(const EdgeKey& a, const EdgeKey& b) {
  if (a.hi != b.hi) return a.fhi < b.fhi || (a.fhi == b.fhi && a.hi < b.hi);
  return a.lo != b.lo && (a.flo < b.flo || (a.flo == b.flo && a.lo < b.lo));
}

// What a lower-star reduction of vertex v's lower link says about the edges (v, x): x is the root of its
// lower-link component (a cross edge), or x died in the link's dim-0 persistence when `killer` joined it
// to the older root `older` (then (v,x) is paired inside the lower star of v).
struct LowerLinkInfo {
  std::uint16_t lower = 0;
  std::int8_t lowest = -1;                 // neighbour slot of the lowest lower neighbour
  std::array<std::int8_t, 14> killer{};    // link edge index that killed slot n, or -1 for a root
  std::array<std::int8_t, 14> older{};     // the older root it merged into
};

// A join saddle's link slots whose edges give birth to 1-cycles; base: the rank of its first such edge.
struct BirthSlots { std::uint32_t saddle; std::uint16_t mask; std::uint32_t base; };

class Engine {
 public:
  Engine(const ScalarGrid& grid, const ProgressFn& progress, std::size_t max_memory)
      : grid_(grid), f_(grid.values.data()), cx_(grid.dims), V_(cx_.vertex_count()), max_memory_(max_memory),
        progress_(progress),
        table_(detail::link_component_table()), link_(freudenthal::vertex_link()) {
    for (int n = 0; n < 14; ++n) {
      delta_[n] = cx_.neighbor_delta(n);
      std::size_t h = delta_hash(delta_[n]);
      while (slot_key_[h] != 0) h = (h + 1) & (kSlotTable - 1);
      slot_key_[h] = delta_[n];
      slot_of_key_[h] = std::int8_t(n);
    }
    for (int e = 0; e < 36; ++e) {
      link_edge_index_[link_.edges[e][0]][link_.edges[e][1]] = std::int8_t(e);
      link_edge_index_[link_.edges[e][1]][link_.edges[e][0]] = std::int8_t(e);
    }
  }

  PersistenceDiagram run();

 private:
  void report(const char* stage, double fraction) {
    if (progress_ && !progress_(stage, fraction)) throw Error("persistence interrupted");
  }
  bool less(Id a, Id b) const { return vertex_less(f_, a, b); }
  // With CHOKELOOPS_DEBUG_PERSISTENCE set, lap("step") prints the seconds since the previous lap (or since the
  // timer was made) to stderr: the split of each dimension's time that the README quotes.
  static auto step_timer() {
    static const bool on = std::getenv("CHOKELOOPS_DEBUG_PERSISTENCE") != nullptr;
    return [t = Clock::now()](const char* step) mutable {
      if (!on) return;
      std::fprintf(stderr, "persistence step %-36s %.3f s\n", step, seconds_since(t));
      t = Clock::now();
    };
  }

  // Lower mask and out-of-box mask of vertex v's 14 link slots.
  void masks(Id v, std::uint16_t& lower, std::uint16_t& outside) const {
    auto c = cx_.coords(v);
    bool border = c[0] == 0 || c[1] == 0 || c[2] == 0 || c[0] == grid_.dims[0] - 1 ||
                  c[1] == grid_.dims[1] - 1 || c[2] == grid_.dims[2] - 1;
    lower = outside = 0;
    if (!border) {
      // slots 0-6 have higher indices than v, 7-13 lower ones, which win ties: no branch on the field, whose
      // comparisons on a rough field are coin flips
      const float fv = f_[v];
      unsigned bits = 0;
      for (int n = 0; n < 7; ++n) bits |= unsigned(f_[v + delta_[n]] < fv) << n;
      for (int n = 7; n < 14; ++n) bits |= unsigned(f_[v + delta_[n]] <= fv) << n;
      lower = std::uint16_t(bits);
      return;
    }
    for (int n = 0; n < 14; ++n) {
      if (!cx_.neighbor_inside(c, n)) { outside |= std::uint16_t(1u << n); continue; }
      if (less(v + delta_[n], v)) lower |= std::uint16_t(1u << n);
    }
  }
  std::uint16_t lower_mask(Id v) const {
    std::uint16_t lower, outside;
    masks(v, lower, outside);
    return lower;
  }
  // The lower link slots of v from lowest to highest; returns how many.
  // Each slot's place is the count of slots below it, all compared without a branch: on a rough field the
  // comparisons are coin flips, and an insertion sort's mispredicted branches cost more than the ~n^2 tests.
  int lower_slots_in_order(Id v, std::uint16_t lower, std::array<int, 14>& order) const {
    std::array<int, 14> slots;
    std::array<float, 14> value;
    int n = 0;
    for (unsigned m = lower; m; m &= m - 1) {
      const int a = __builtin_ctz(m);
      slots[n] = a;
      value[n++] = f_[v + delta_[a]];
    }
    for (int i = 0; i < n; ++i) {
      int place = 0;
      for (int j = 0; j < n; ++j)
        place += int(value[j] < value[i]) | (int(value[j] == value[i]) & int(delta_[slots[j]] < delta_[slots[i]]));
      order[place] = slots[i];
    }
    return n;
  }
  // The lower-link neighbours of slot a that come before it in the order (rank below i), as a mask of their
  // ranks: a link vertex has 4 to 6 neighbours, so a replay of the lower link's edges in filtration order
  // visits those instead of testing all i earlier slots.
  unsigned earlier_link_neighbours(int a, int i, std::uint16_t lower, const std::array<std::int8_t, 14>& rank) const {
    unsigned earlier = 0;
    for (unsigned m = link_.adjacency[a] & lower; m; m &= m - 1) {
      const int r = rank[__builtin_ctz(m)];
      if (r < i) earlier |= 1u << r;
    }
    return earlier;
  }
  // The link slot of neighbour x of v, from their index difference (distinct for the 14 slots: every axis
  // has at least 2 vertices) through a small hash, where the coordinates cost six divisions.
  int slot(Id v, Id x) const {
    const Id d = x - v;
    for (std::size_t h = delta_hash(d);; h = (h + 1) & (kSlotTable - 1)) {
      if (slot_key_[h] == d) return slot_of_key_[h];
      if (slot_key_[h] == 0) throw InternalError("persistence asked the link slot of a vertex that is not a neighbour");
    }
  }
  static constexpr std::size_t kSlotTable = 32;
  static std::size_t delta_hash(Id d) { return std::size_t(std::uint64_t(d) * 0x9E3779B97F4A7C15ull >> 59); }

  void classify();
  // The lower masks and steepest steps (slots, -1 for none) of `count` interior vertices of a row from `first`.
  struct RowScratch {
    std::vector<std::uint32_t> lower;
    std::vector<std::int32_t> lo, hi;
    std::vector<float> lowest, highest;
    void resize(std::size_t n) { lower.resize(n), lo.resize(n), hi.resize(n), lowest.resize(n), highest.resize(n); }
  };
  void classify_interior_row(Id first, int count, RowScratch& out) const;
  void sort_in_filtration_order(BigVector<std::uint32_t>& vertices, bool descending) const;
  // Estimates the peak from the classification's counts; throws Error (exit code 3) over max_memory_.
  void guard_memory(PersistenceDiagram& out);

  // A thread's memory of where descents (or ascents) ended, direct-mapped by vertex: on a smooth field the
  // walks from many saddles run down the same long paths, and a vertex seen before ends a walk early.
  struct RootCache {
    static constexpr int kBits = 14;
    std::vector<std::uint32_t> key = std::vector<std::uint32_t>(std::size_t(1) << kBits, kOutside);
    std::vector<std::uint32_t> root = std::vector<std::uint32_t>(std::size_t(1) << kBits);
    static std::size_t slot(std::uint32_t v) { return std::size_t(std::uint64_t(v) * 0x9E3779B97F4A7C15ull >> (64 - kBits)); }
  };
  // The minimum a steepest descent from v ends at (kDown), or the maximum an ascent ends at, or kOutside.
  // Every fourth vertex of the walk's last 128 steps is remembered with the answer.
  template <bool kDown>
  std::uint32_t walk(Id v, RootCache& cache) const {
    std::array<std::uint32_t, 32> seen;
    unsigned n = 0;
    std::uint32_t r;
    for (unsigned step = 0;; ++step) {
      const std::size_t h = RootCache::slot(std::uint32_t(v));
      if (cache.key[h] == std::uint32_t(v)) { r = cache.root[h]; break; }
      const std::uint8_t c = kDown ? codes_[std::size_t(v)] & 15 : codes_[std::size_t(v)] >> 4;
      if (c == kStepNone) { r = std::uint32_t(v); break; }
      if (!kDown && c == kStepOutside) { r = kOutside; break; }
      if ((step & 3) == 0) seen[n++ & 31] = std::uint32_t(v);
      v += delta_[c];
    }
    for (unsigned k = 0; k < std::min(n, 32u); ++k) {
      const std::size_t h = RootCache::slot(seen[k]);
      cache.key[h] = seen[k];
      cache.root[h] = r;
    }
    return r;
  }
  // Index of an extremum in its sorted list (the union-find's node), through buckets of vertex ids sized so
  // that a bucket holds about one extremum: two cache misses, where a binary search takes ~20 steps.
  // kOutside stays kOutside.
  struct ExtremumIndex {
    const BigVector<std::uint32_t>* list = nullptr;
    BigVector<std::uint32_t> start;
    int shift = 0;
    void build(const BigVector<std::uint32_t>& sorted, Id vertex_count) {
      list = &sorted;
      shift = 0;
      while ((std::uint64_t(vertex_count) >> (shift + 1)) >= sorted.size() && shift < 31) ++shift;
      start.assign(std::size_t(std::uint64_t(vertex_count) >> shift) + 2, 0);
      for (std::uint32_t v : sorted) ++start[(v >> shift) + 1];
      for (std::size_t b = 1; b < start.size(); ++b) start[b] += start[b - 1];
    }
    std::uint32_t operator()(std::uint32_t v) const {
      if (v == kOutside) return kOutside;
      const std::size_t b = v >> shift;
      for (std::uint32_t i = start[b];; ++i)
        if ((*list)[i] == v) return i;
    }
  };
  // Union-find over extrema; a root's parent is itself, or kOutside for a set merged into the outside.
  static std::uint32_t find(BigVector<std::uint32_t>& parent, std::uint32_t x) {
    while (x != kOutside && parent[x] != x) {
      std::uint32_t up = parent[x];
      if (up != kOutside && parent[up] != up) parent[x] = parent[up];
      x = parent[x];
    }
    return x;
  }

  // Each saddle's records (a few each: its lobes, its cross triangles), found in parallel and returned in the
  // order of `saddles` (filtration order): saddle i's are [place[i], place[i+1]). count(s) says how many saddle
  // s has; write(s, out, count, roots) writes them (roots: the thread's RootCache). Both run with the saddles
  // in grid order, where neighbours share their stars' and walks' memory (filtration order scatters them over
  // the grid); the records are then moved to their places in a pass of copies.
  template <class Record, class Count, class Write>
  static BigVector<Record> records_in_grid_order(const BigVector<std::uint32_t>& saddles, Count&& count,
                                                   Write&& write, BigVector<std::uint32_t>& place) {
    const std::size_t n = saddles.size();
    struct Visit { std::uint32_t vertex, index; };
    BigVector<Visit> visits(n);
    tbb::parallel_for(std::size_t(0), n, [&](std::size_t i) { visits[i] = {saddles[i], std::uint32_t(i)}; });
    tbb::parallel_sort(visits.begin(), visits.end(), [](const Visit& a, const Visit& b) { return a.vertex < b.vertex; });
    auto in_parallel = [&](auto&& body) {
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t k = r.begin(); k != r.end(); ++k) body(k);
      });
    };
    BigVector<std::uint32_t> at(n + 1, 0);  // where visit k's records are in grid order
    in_parallel([&](std::size_t k) { at[k + 1] = std::uint32_t(count(visits[k].vertex)); });
    for (std::size_t k = 0; k < n; ++k) at[k + 1] += at[k];
    BigVector<Record> in_grid(at[n]);
    tbb::enumerable_thread_specific<RootCache> caches;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
      RootCache& roots = caches.local();
      for (std::size_t k = r.begin(); k != r.end(); ++k)
        write(visits[k].vertex, in_grid.data() + at[k], int(at[k + 1] - at[k]), roots);
    });
    place.assign(n + 1, 0);
    in_parallel([&](std::size_t k) { place[visits[k].index + 1] = at[k + 1] - at[k]; });
    for (std::size_t i = 0; i < n; ++i) place[i + 1] += place[i];
    BigVector<Record> records(place[n]);
    in_parallel([&](std::size_t k) {
      std::copy(in_grid.begin() + at[k], in_grid.begin() + at[k + 1], records.begin() + place[visits[k].index]);
    });
    return records;
  }

  void dim0(PersistenceDiagram& out);

  // The join saddles with births by vertex, found with one cache miss past the saddle's bit: a bit per vertex
  // with, per 64 vertices, how many saddles come before (rank), and then the saddle's entry in vertex order.
  void index_birth_list();
  struct BirthBlock { std::uint64_t bits; std::uint32_t before; };
  struct BirthEntry { std::uint16_t mask; std::uint32_t base; };
  const BirthEntry* birth_slots(Id s) const {
    const BirthBlock& block = birth_blocks_[std::size_t(s) >> 6];
    const std::uint64_t bit = std::uint64_t(1) << (s & 63);
    if (!(block.bits & bit)) return nullptr;
    return &birth_by_vertex_[block.before + std::uint32_t(__builtin_popcountll(block.bits & (bit - 1)))];
  }

  // The last tetrahedron (in filtration order) of the star of a maximum m.
  Id last_tet(Id m) const;

  // A triangle of a split saddle's lower star that joins two upper-link components: it either gives
  // birth to a void (the components' maxima differ) or kills a 1-cycle. rep = each component's maximum
  // (its index in maxima_list_) or kOutside.
  // lobe = the link slot of an in-box vertex of each component (-1 if the component lies wholly outside the
  // box). 16 bytes: there is one per extra upper-link component of every split saddle.
  struct CrossTriangle { std::uint32_t s; std::uint8_t a, b; std::int8_t lobe1, lobe2; std::uint32_t rep1, rep2; };
  Id lobe_vertex(std::uint32_t s, std::int8_t lobe) const { return lobe < 0 ? Id(-2) : Id(s) + delta_[lobe]; }

  // Replays the lower star of split saddle s on the dual graph, in reverse filtration order, with each
  // upper-link component as one old node; needs no global state, so all saddles run in parallel. Writes
  // one cross triangle per extra upper-link component to `out`; returns how many.
  int split_saddle_cross_triangles(std::uint32_t s, CrossTriangle* out, RootCache& roots) const;

  void dim2(PersistenceDiagram& out);

  LowerLinkInfo compute_lower_link(Id v) const;
  // A thread's cache of lower links, direct-mapped by a hash of the vertex: the columns are reduced in grid
  // order, so the links they need are mostly recent ones, and a miss only recomputes.
  struct LinkCache {
    static constexpr int kBits = 14;
    // the key beside its link: one cache line read where two arrays cost two misses
    struct Entry { std::uint32_t key = kOutside; LowerLinkInfo info; };
    BigVector<Entry> entries = BigVector<Entry>(std::size_t(1) << kBits);
    const LowerLinkInfo& get(const Engine& engine, Id v);
    static std::size_t slot(Id v) { return std::size_t(std::uint64_t(v) * 0x9E3779B97F4A7C15ull >> (64 - kBits)); }
  };
  EdgeKey make_edge(Id a, Id b) const {
    float fa = f_[a], fb = f_[b];
    bool a_lower = fa < fb || (fa == fb && a < b);
    return a_lower ? EdgeKey{fb, fa, std::uint32_t(b), std::uint32_t(a)} : EdgeKey{fa, fb, std::uint32_t(a), std::uint32_t(b)};
  }

  // Replaces the pivot (v, x), paired inside v's lower star, by the rest of that pair's cone: the edge
  // (v, older root) and a lower-link path from x to that root through edges no later than the killer.
  template <class Push>
  void expand_local_pair(Id v, const LowerLinkInfo& info, int x, Push&& push);

  // Rank of birth edge (b.saddle, x) among all dim-1 birth edges in filtration order: the saddles' order,
  // then each saddle's lower ends in order.
  std::uint32_t birth_rank_in(Id saddle, const BirthEntry& b, Id x) const {
    std::uint32_t r = b.base;
    for (unsigned m = b.mask; m; m &= m - 1)
      if (less(saddle + delta_[__builtin_ctz(m)], x)) ++r;
    return r;
  }

  // Pops the chain's edges from the top until one is a dim-1 birth edge, which is returned (popped): an edge
  // paired inside its own lower star is replaced by the rest of that pair's cone (this adds a boundary, so
  // the pivot is the one the full boundary matrix gives); a negative edge is dropped (compression).
  // rank: the birth edge's rank.
  // budget: how many more edges may be popped; at 0 it returns false with the heap as it is.
  template <class Heap>
  bool pop_to_birth_pivot(Heap& heap, LinkCache& links, EdgeKey& p, std::uint32_t& rank, std::size_t& budget);
  // The birth edge of a rank (birth_rank_in's inverse).
  EdgeKey birth_edge(std::uint32_t rank) const;
  // The link slot of v's lowest lower neighbour.
  int lowest_slot(Id v) const {
    std::uint16_t lower, outside;
    masks(v, lower, outside);
    int best = -1;
    for (unsigned m = lower; m; m &= m - 1) {
      int n = __builtin_ctz(m);
      if (best < 0 || less(v + delta_[n], v + delta_[best])) best = n;
    }
    return best;
  }

  void dim1(PersistenceDiagram& out);

  // end0, end2: where the dim-0 and dim-2 pairs end in out.pairs (dims 0, 2 and 1 come in that order).
  void finish(PersistenceDiagram& out, std::size_t end0, std::size_t end2);

  const ScalarGrid& grid_;
  const float* f_;
  FreudenthalComplex cx_;
  Id V_;
  std::size_t max_memory_;
  ProgressFn progress_;
  const std::vector<detail::LinkComponents>& table_;
  const freudenthal::Link& link_;
  std::array<Id, 14> delta_{};
  std::array<Id, kSlotTable> slot_key_{};  // 0: empty (no slot's delta is 0)
  std::array<std::int8_t, kSlotTable> slot_of_key_{};
  std::array<std::array<std::int8_t, 14>, 14> link_edge_index_{};
  BigVector<std::uint8_t> codes_;  // steps down and up, freed after dim 2
  BigVector<std::uint32_t> joins_, splits_;
  BigVector<std::uint32_t> minima_list_, maxima_list_;  // sorted by vertex; freed after their dimension
  ExtremumIndex minimum_index_, maximum_index_;
  Id minima_ = 0, maxima_ = 0;
  Id global_min_ = 0;
  std::size_t extra_lower_ = 0, extra_upper_ = 0;  // extra link components of join and split saddles
  BigVector<BirthSlots> birth_list_;  // join saddles with dim-1 birth edges, in filtration order
  BigVector<BirthBlock> birth_blocks_;    // a bit per vertex: in birth_list_ (most lookups are misses)
  BigVector<BirthEntry> birth_by_vertex_;  // birth_list_'s entries in vertex order
  std::size_t births1_ = 0;
  // A dim-1 death triangle (s, s + delta_[a], s + delta_[b]) of split saddle s, its highest vertex, and the
  // link slots of the two sides it joins (-1: outside the box). 8 bytes: one per dim-1 pair.
  struct Death1 { std::uint32_t s; std::uint8_t a, b; std::int8_t lobe1, lobe2; };
  BigVector<Death1> deaths1_;
};

}  // namespace chokeloops::detail

// Lower-star persistence on the implicit Freudenthal complex, without a global boundary matrix.
//
// Why it is fast: a vertex whose lower link (the part of its 14-neighbour link sphere below it) is a
// disk changes no homology, so every pair between two different lower stars starts and ends at a
// vertex whose lower link has several components (join saddle: dim-0 deaths, dim-1 births), whose
// upper link has several components (split saddle: dim-2 births, dim-1 deaths), or at an extremum.
// A 14-bit mask and a table of link components classify every vertex in one parallel pass.
//  * dim 0: each vertex points to its lowest neighbour; pointer jumping gives every vertex its minimum.
//    Join saddles, in filtration order, merge the minima of their lower-link components with the elder
//    rule (union-find). The cross edge of a lower-link component is (s, lowest vertex of the component).
//  * dim 2: the same upside down on the dual graph (tetrahedra joined by triangles, the outside of the box
//    one node that never dies): each vertex points up, maxima own the last tetrahedron of their star, and
//    split saddles, in reverse order, replay their lower star's tetrahedra and triangles locally.
//  * dim 1: the edges left by dim 0 and the triangles left by dim 2 are paired by reducing only the
//    boundaries of those triangles; a pivot edge paired inside its own lower star is replaced by the rest
//    of that pair's cone (a path in the lower link), negative edges are compressed away. That needs no
//    other column until the first birth edge becomes the pivot, so every death triangle gets that far in
//    parallel (DMS-style); only the ~15% of columns whose pivot is already owned continue sequentially.
// Everything but that sequential remainder of dim 1 and the union-find merges runs in parallel; every step
// is deterministic.
#include "chokeloops/persistence.h"

#include <tbb/blocked_range.h>
#include <tbb/concurrent_vector.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <atomic>
#include <iterator>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <deque>
#include <queue>
#include <unordered_map>

#include "link_table.h"

namespace chokeloops {

std::size_t PersistenceDiagram::count(int dim) const {
  std::size_t n = 0;
  for (auto& p : pairs) n += p.dim == dim;
  return n;
}

namespace {

constexpr std::uint32_t kOutside = 0xFFFFFFFFu;  // the outside of the box: +inf, never dies
using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

inline std::uint32_t load(const std::uint32_t& x) { return __atomic_load_n(&x, __ATOMIC_RELAXED); }
inline void store(std::uint32_t& x, std::uint32_t v) { __atomic_store_n(&x, v, __ATOMIC_RELAXED); }

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
  Engine(const ScalarGrid& grid, const ProgressFn& progress)
      : grid_(grid), f_(grid.values.data()), cx_(grid.dims), V_(cx_.vertex_count()), progress_(progress),
        table_(detail::link_component_table()), link_(freudenthal::vertex_link()) {
    for (int n = 0; n < 14; ++n) {
      delta_[n] = cx_.neighbor_delta(n);
      auto o = freudenthal::neighbor_offset(n);
      slot_of_offset_[(o[0] + 1) + 3 * (o[1] + 1) + 9 * (o[2] + 1)] = std::int8_t(n);
    }
    for (int e = 0; e < 36; ++e) {
      link_edge_index_[link_.edges[e][0]][link_.edges[e][1]] = std::int8_t(e);
      link_edge_index_[link_.edges[e][1]][link_.edges[e][0]] = std::int8_t(e);
    }
  }

  PersistenceDiagram run() {
    PersistenceDiagram out;
    out.dims = grid_.dims;
    auto t0 = Clock::now();
    report("classify", 0);
    classify();
    jump(desc_);
    jump(asc_);
    out.stats.seconds_classify = seconds_since(t0);
    auto t = Clock::now();
    report("dim 0", 0.3);
    dim0(out);
    out.stats.seconds_dim0 = seconds_since(t);
    t = Clock::now();
    report("dim 2", 0.45);
    dim2(out);
    out.stats.seconds_dim2 = seconds_since(t);
    t = Clock::now();
    report("dim 1", 0.6);
    dim1(out);
    out.stats.seconds_dim1 = seconds_since(t);
    finish(out);
    out.stats.join_saddles = Id(joins_.size());
    out.stats.split_saddles = Id(splits_.size());
    out.stats.minima = minima_;
    out.stats.maxima = maxima_;
    out.stats.seconds_total = seconds_since(t0);
    report("done", 1);
    return out;
  }

 private:
  void report(const char* stage, double fraction) {
    if (progress_ && !progress_(stage, fraction)) throw Error("persistence interrupted");
  }
  bool less(Id a, Id b) const { return vertex_less(f_, a, b); }

  // Lower mask and out-of-box mask of vertex v's 14 link slots.
  void masks(Id v, std::uint16_t& lower, std::uint16_t& outside) const {
    auto c = cx_.coords(v);
    bool border = c[0] == 0 || c[1] == 0 || c[2] == 0 || c[0] == grid_.dims[0] - 1 ||
                  c[1] == grid_.dims[1] - 1 || c[2] == grid_.dims[2] - 1;
    lower = outside = 0;
    for (int n = 0; n < 14; ++n) {
      if (border && !cx_.neighbor_inside(c, n)) { outside |= std::uint16_t(1u << n); continue; }
      if (less(v + delta_[n], v)) lower |= std::uint16_t(1u << n);
    }
  }
  // The lower link slots of v from lowest to highest; returns how many.
  int lower_slots_in_order(Id v, std::uint16_t lower, std::array<int, 14>& order) const {
    int n = 0;
    for (unsigned m = lower; m; m &= m - 1) order[n++] = __builtin_ctz(m);
    for (int i = 1; i < n; ++i)
      for (int j = i; j > 0 && less(v + delta_[order[j]], v + delta_[order[j - 1]]); --j) std::swap(order[j], order[j - 1]);
    return n;
  }
  int slot(Id v, Id x) const {
    auto a = cx_.coords(v), b = cx_.coords(x);
    return slot_of_offset_[(b[0] - a[0] + 1) + 3 * (b[1] - a[1] + 1) + 9 * (b[2] - a[2] + 1)];
  }

  void classify() {
    desc_.resize(V_);
    asc_.resize(V_);
    const int nx = grid_.dims[0], ny = grid_.dims[1], nz = grid_.dims[2];
    struct Local { std::vector<std::uint32_t> joins, splits; Id minima = 0, maxima = 0; };
    tbb::enumerable_thread_specific<Local> locals;
    tbb::parallel_for(tbb::blocked_range<int>(0, nz * ny), [&](const tbb::blocked_range<int>& r) {
      Local& L = locals.local();
      for (int row = r.begin(); row != r.end(); ++row) {
        int j = row % ny, k = row / ny;
        for (int i = 0; i < nx; ++i) {
          Id v = cx_.vertex(i, j, k);
          bool border = i == 0 || j == 0 || k == 0 || i == nx - 1 || j == ny - 1 || k == nz - 1;
          std::uint16_t lower = 0, outside = 0;
          Id lo = v, hi = v;
          for (int n = 0; n < 14; ++n) {
            if (border && !cx_.neighbor_inside({i, j, k}, n)) { outside |= std::uint16_t(1u << n); continue; }
            Id u = v + delta_[n];
            if (less(u, v)) {
              lower |= std::uint16_t(1u << n);
              if (lo == v || less(u, lo)) lo = u;
            } else if (hi == v || less(hi, u)) {
              hi = u;
            }
          }
          std::uint16_t upper = std::uint16_t(~lower & 0x3FFF);
          desc_[v] = std::uint32_t(lo);
          asc_[v] = outside ? kOutside : std::uint32_t(hi);
          if (lower == 0) ++L.minima;
          if (upper == 0) ++L.maxima;
          if (table_[lower].count >= 2) L.joins.push_back(std::uint32_t(v));
          if (table_[upper].count >= 2) L.splits.push_back(std::uint32_t(v));
        }
      }
    });
    for (auto& L : locals) {
      joins_.insert(joins_.end(), L.joins.begin(), L.joins.end());
      splits_.insert(splits_.end(), L.splits.begin(), L.splits.end());
      minima_ += L.minima;
      maxima_ += L.maxima;
    }
    auto by_order = [this](std::uint32_t a, std::uint32_t b) { return less(a, b); };
    tbb::parallel_sort(joins_.begin(), joins_.end(), by_order);
    tbb::parallel_sort(splits_.begin(), splits_.end(), [&](std::uint32_t a, std::uint32_t b) { return less(b, a); });
  }

  // Every pointer ends at the root of its chain (a minimum, a maximum, or the outside).
  void jump(std::vector<std::uint32_t>& p) {
    for (;;) {
      std::atomic<bool> changed{false};
      tbb::parallel_for(tbb::blocked_range<Id>(0, V_, 1 << 15), [&](const tbb::blocked_range<Id>& r) {
        bool ch = false;
        for (Id v = r.begin(); v != r.end(); ++v) {
          std::uint32_t a = load(p[v]);
          if (a == kOutside || a == v) continue;
          std::uint32_t b = load(p[a]);
          if (b != a) { store(p[v], b); ch = true; }
        }
        if (ch) changed = true;
      });
      if (!changed) break;
    }
  }

  std::uint32_t find(std::vector<std::uint32_t>& p, std::uint32_t x) const {
    while (x != kOutside && p[x] != x) {
      std::uint32_t up = p[x];
      if (up != kOutside && p[up] != up) p[x] = p[up];
      x = p[x];
    }
    return x;
  }

  void dim0(PersistenceDiagram& out) {
    for (std::uint32_t s : joins_) {
      std::uint16_t lower, outside;
      masks(s, lower, outside);
      const auto& comps = table_[lower];
      std::array<Id, 7> low{};
      for (int c = 0; c < comps.count; ++c) {
        Id best = -1;
        for (unsigned m = comps.masks[c]; m; m &= m - 1) {
          Id u = s + delta_[__builtin_ctz(m)];
          if (best < 0 || less(u, best)) best = u;
        }
        low[c] = best;
      }
      std::sort(low.begin(), low.begin() + comps.count, [this](Id a, Id b) { return less(a, b); });
      BirthSlots births{s, 0, std::uint32_t(births1_)};
      for (int c = 1; c < comps.count; ++c) {
        std::uint32_t rs = find(desc_, desc_[low[0]]), r = find(desc_, desc_[low[c]]);
        if (r == rs) {
          births.mask |= std::uint16_t(1u << slot(s, low[c]));
          ++births1_;
          continue;
        }
        std::uint32_t young = less(r, rs) ? rs : r, old = young == r ? rs : r;
        desc_[young] = old;
        Id edge = cx_.edge_id(s, low[c]);
        PersistencePair p;
        p.dim = 0;
        p.birth = f_[young];
        p.death = f_[s];
        p.birth_simplex = p.birth_vertex = young;
        p.death_simplex = edge;
        p.death_vertex = s;
        p.death_lobes = {low[0], low[c]};
        out.pairs.push_back(p);
      }
      if (births.mask) birth_list_.push_back(births);
    }
    index_birth_list();
  }

  // An open-addressing table from join saddle to its entry in birth_list_: one cache miss per lookup.
  void index_birth_list() {
    std::size_t cap = 16;
    while (cap < 2 * birth_list_.size()) cap *= 2;
    birth_table_.assign(cap, kOutside);
    for (std::uint32_t i = 0; i < birth_list_.size(); ++i) {
      std::size_t h = hash_vertex(birth_list_[i].saddle);
      while (birth_table_[h] != kOutside) h = (h + 1) & (cap - 1);
      birth_table_[h] = i;
    }
  }
  std::size_t hash_vertex(std::uint32_t v) const {
    return (std::uint64_t(v) * 0x9E3779B97F4A7C15ull >> 32) & (birth_table_.size() - 1);
  }
  const BirthSlots* birth_slots(Id s) const {
    for (std::size_t h = hash_vertex(std::uint32_t(s));; h = (h + 1) & (birth_table_.size() - 1)) {
      std::uint32_t i = birth_table_[h];
      if (i == kOutside) return nullptr;
      if (birth_list_[i].saddle == std::uint32_t(s)) return &birth_list_[i];
    }
  }

  // The last tetrahedron (in filtration order) of the star of a maximum m.
  Id last_tet(Id m) const {
    std::array<Id, 3> best{-1, -1, -1};
    for (auto& tr : link_.triangles) {
      auto d = sorted_descending(f_, std::array<Id, 3>{m + delta_[tr[0]], m + delta_[tr[1]], m + delta_[tr[2]]});
      if (best[0] < 0 || simplex_less(f_, best, d)) best = d;
    }
    return cx_.tet_id(m, best[0], best[1], best[2]);
  }

  // A triangle of a split saddle's lower star that joins two upper-link components: it either gives
  // birth to a void (the components' maxima differ) or kills a 1-cycle. rep = a vertex of each component.
  // lobe = an in-box vertex of each component (-2 if the component lies wholly outside the box).
  struct CrossTriangle { std::uint32_t s; std::uint8_t a, b; std::uint32_t rep1, rep2; std::int64_t lobe1, lobe2; };

  // Replays the lower star of split saddle s on the dual graph, in reverse filtration order, with each
  // upper-link component as one old node; needs no global state, so all saddles run in parallel.
  void split_saddle_cross_triangles(std::uint32_t s, std::vector<CrossTriangle>& out) const {
    std::uint16_t lower, outside;
    masks(s, lower, outside);
    std::uint16_t upper = std::uint16_t(~lower & 0x3FFF);
    const auto& ucomps = table_[upper];
    std::array<int, 14> comp_of;
    comp_of.fill(-1);
    std::array<std::uint32_t, 7> rep{};
    std::array<std::int64_t, 7> lobe{};
    for (int c = 0; c < ucomps.count; ++c) {
      for (unsigned m = ucomps.masks[c]; m; m &= m - 1) comp_of[__builtin_ctz(m)] = c;
      rep[c] = (ucomps.masks[c] & outside) ? kOutside : std::uint32_t(s + delta_[__builtin_ctz(ucomps.masks[c])]);
      unsigned in_box = ucomps.masks[c] & ~outside;
      lobe[c] = in_box ? s + delta_[__builtin_ctz(in_box)] : -2;
    }
    // Only the star's triangles (link edges) can join nodes: a tetrahedron is born as its own node. In reverse
    // filtration order they are (order[i], order[j]) for i descending, then j < i descending.
    std::array<int, 14> order;
    const int n_lower = lower_slots_in_order(s, lower, order);
    std::array<int, 31> parent;
    std::array<int, 31> comp_rep;  // for a root holding an upper component: that component, else -1
    for (int n = 0; n < 31; ++n) { parent[n] = n; comp_rep[n] = n >= 24 ? n - 24 : -1; }
    auto node_of = [&](int tri) {
      auto& t = link_.triangles[tri];
      for (int q = 0; q < 3; ++q)
        if (!(lower >> t[q] & 1)) return 24 + comp_of[t[q]];
      return tri;
    };
    auto lfind = [&](int x) { while (parent[x] != x) x = parent[x] = parent[parent[x]]; return x; };
    for (int i = n_lower - 1; i > 0; --i)
      for (int j = i - 1; j >= 0; --j) {
        if (!(link_.adjacency[order[i]] >> order[j] & 1)) continue;
        const int e = link_edge_index_[order[i]][order[j]];
        const auto& et = link_.edge_triangles[e];
        int r1 = lfind(node_of(et[0])), r2 = lfind(node_of(et[1]));
        if (r1 == r2) continue;
        if (comp_rep[r1] >= 0 && comp_rep[r2] >= 0)
          out.push_back({s, std::uint8_t(link_.edges[e][0]), std::uint8_t(link_.edges[e][1]), rep[comp_rep[r1]],
                         rep[comp_rep[r2]], lobe[comp_rep[r1]], lobe[comp_rep[r2]]});
        parent[r2] = r1;
        if (comp_rep[r1] < 0) comp_rep[r1] = comp_rep[r2];
      }
  }

  void dim2(PersistenceDiagram& out) {
    // Cross triangles of all split saddles, computed in parallel, kept in saddle order.
    const std::size_t chunk = 4096, nchunks = (splits_.size() + chunk - 1) / chunk;
    std::vector<std::vector<CrossTriangle>> found(nchunks);
    tbb::parallel_for(std::size_t(0), nchunks, [&](std::size_t c) {
      for (std::size_t i = c * chunk; i < std::min(splits_.size(), (c + 1) * chunk); ++i)
        split_saddle_cross_triangles(splits_[i], found[c]);
    });
    for (auto& list : found)
      for (const CrossTriangle& ct : list) {
        std::uint32_t g1 = find(asc_, root_up(ct.rep1)), g2 = find(asc_, root_up(ct.rep2));
        Id s = ct.s, a = s + delta_[ct.a], b = s + delta_[ct.b];
        if (g1 == g2) {
          auto d = sorted_descending(f_, std::array<Id, 3>{s, a, b});
          deaths1_.push_back({d, {ct.lobe1, ct.lobe2}});
          continue;
        }
        bool g1_younger = g2 == kOutside || (g1 != kOutside && less(g1, g2));
        std::uint32_t young = g1_younger ? g1 : g2, old = g1_younger ? g2 : g1;
        asc_[young] = old;
        PersistencePair p;
        p.dim = 2;
        p.birth = f_[s];
        p.death = f_[young];
        p.birth_simplex = cx_.triangle_id(s, a, b);
        p.birth_vertex = s;
        p.death_simplex = last_tet(young);
        p.death_vertex = young;
        p.birth_lobes = {ct.lobe1, ct.lobe2};
        out.pairs.push_back(p);
      }
    std::reverse(deaths1_.begin(), deaths1_.end());  // ascending filtration order
  }
  std::uint32_t root_up(std::uint32_t w) const { return w == kOutside ? kOutside : asc_[w]; }

  // Thread-safe memo: the first thread to publish an index wins; a loser's copy is identical and unused.
  const LowerLinkInfo& lower_link(Id v) {
    std::uint32_t index = __atomic_load_n(&link_index_[v], __ATOMIC_ACQUIRE);
    if (index != kOutside) return link_infos_[index];
    LowerLinkInfo info;
    std::uint16_t outside;
    masks(v, info.lower, outside);
    info.killer.fill(-1);
    info.older.fill(-1);
    // Link edges in filtration order are (order[i], order[j]) for i ascending, then j < i ascending.
    std::array<int, 14> order;
    const int n_lower = lower_slots_in_order(v, info.lower, order);
    std::array<std::int8_t, 14> rank;
    for (int i = 0; i < n_lower; ++i) rank[order[i]] = std::int8_t(i);
    std::array<int, 14> parent;
    for (int n = 0; n < 14; ++n) parent[n] = n;
    auto lfind = [&](int x) { while (parent[x] != x) x = parent[x] = parent[parent[x]]; return x; };
    for (int i = 1; i < n_lower; ++i) {
      const int a = order[i];
      const unsigned adjacent = link_.adjacency[a];
      for (int j = 0; j < i; ++j) {
        const int b = order[j];
        if (!(adjacent >> b & 1)) continue;
        int ra = lfind(a), rb = lfind(b);
        if (ra == rb) continue;
        bool a_younger = rank[ra] > rank[rb];
        int young = a_younger ? ra : rb, old = a_younger ? rb : ra;
        parent[young] = old;
        info.killer[young] = link_edge_index_[a][b];
        info.older[young] = std::int8_t(old);
      }
    }
    if (n_lower) info.lowest = std::int8_t(order[0]);
    auto it = link_infos_.push_back(info);
    std::uint32_t mine = std::uint32_t(it - link_infos_.begin()), expected = kOutside;
    if (__atomic_compare_exchange_n(&link_index_[v], &expected, mine, false, __ATOMIC_ACQ_REL, __ATOMIC_ACQUIRE))
      return *it;
    return link_infos_[expected];
  }
  EdgeKey make_edge(Id a, Id b) const {
    float fa = f_[a], fb = f_[b];
    bool a_lower = fa < fb || (fa == fb && a < b);
    return a_lower ? EdgeKey{fb, fa, std::uint32_t(b), std::uint32_t(a)} : EdgeKey{fa, fb, std::uint32_t(a), std::uint32_t(b)};
  }

  // Replaces the pivot (v, x), paired inside v's lower star, by the rest of that pair's cone: the edge
  // (v, older root) and a lower-link path from x to that root through edges no later than the killer.
  template <class Push>
  void expand_local_pair(Id v, const LowerLinkInfo& info, int x, Push&& push) {
    int killer = info.killer[x], target = info.older[x];
    auto killer_key = make_edge(v + delta_[link_.edges[killer][0]], v + delta_[link_.edges[killer][1]]);
    std::array<int, 14> prev;
    prev.fill(-2);
    prev[x] = -1;
    std::array<int, 14> queue;
    int head = 0, tail = 0;
    queue[tail++] = x;
    while (head < tail && prev[target] == -2) {
      int a = queue[head++];
      for (unsigned m = link_.adjacency[a] & info.lower; m; m &= m - 1) {
        int b = __builtin_ctz(m);
        if (prev[b] != -2) continue;
        if (edge_less(killer_key, make_edge(v + delta_[a], v + delta_[b]))) continue;
        prev[b] = a;
        queue[tail++] = b;
      }
    }
    if (prev[target] == -2) throw std::logic_error("lower-link path not found in dim-1 reduction");
    push(make_edge(v, v + delta_[target]));
    for (int b = target; prev[b] >= 0; b = prev[b]) push(make_edge(v + delta_[b], v + delta_[prev[b]]));
  }

  // Rank of birth edge (s, x) among all dim-1 birth edges in filtration order: the saddles' order, then
  // each saddle's lower ends in order.
  std::uint32_t birth_rank(Id s, Id x) const {
    const BirthSlots* b = birth_slots(s);
    std::uint32_t r = b->base;
    for (unsigned m = b->mask; m; m &= m - 1)
      if (less(s + delta_[__builtin_ctz(m)], x)) ++r;
    return r;
  }
  bool is_birth_edge(Id s, int slot_of_x) const {
    const BirthSlots* b = birth_slots(s);
    return b && (b->mask >> slot_of_x & 1);
  }

  // Pops the chain's edges from the top until one is a dim-1 birth edge, which is returned (popped): an edge
  // paired inside its own lower star is replaced by the rest of that pair's cone (this adds a boundary, so
  // the pivot is the one the full boundary matrix gives); a negative edge is dropped (compression).
  template <class Heap>
  bool pop_to_birth_pivot(Heap& heap, EdgeKey& p) {
    while (!heap.empty()) {
      p = heap.top();
      heap.pop();
      bool odd = true;
      while (!heap.empty() && heap.top() == p) { heap.pop(); odd = !odd; }
      if (!odd) continue;
      const LowerLinkInfo& info = lower_link(p.hi);
      int x = slot(p.hi, p.lo);
      if (info.killer[x] >= 0) {
        expand_local_pair(p.hi, info, x, [&](const EdgeKey& e) { heap.push(e); });
        continue;
      }
      // A root's edge is negative (it attaches p.hi, or merges two components) unless dim 0 left it as a
      // birth; the lowest root's edge always attaches. Negative edges are compressed away.
      if (x != info.lowest && is_birth_edge(p.hi, x)) return true;
    }
    return false;
  }
  // Appends the pivot and the rest of the chain, descending, cancelling pairs.
  template <class Heap>
  static void drain(Heap& heap, const EdgeKey& pivot, std::vector<EdgeKey>& out) {
    out.push_back(pivot);
    while (!heap.empty()) {
      EdgeKey q = heap.top();
      heap.pop();
      bool odd = true;
      while (!heap.empty() && heap.top() == q) { heap.pop(); odd = !odd; }
      if (odd) out.push_back(q);
    }
  }

  void dim1(PersistenceDiagram& out) {
    if (births1_ != deaths1_.size())
      throw std::logic_error("dim-1 births and deaths do not balance (" + std::to_string(births1_) + " vs " +
                             std::to_string(deaths1_.size()) + ")");
    link_index_.assign(V_, kOutside);
    auto heap_less = [this](const EdgeKey& a, const EdgeKey& b) { return edge_less(a, b); };
    using Heap = std::priority_queue<EdgeKey, std::vector<EdgeKey>, decltype(heap_less)>;
    // In parallel: each death triangle's boundary up to its first birth pivot, which needs no other column.
    // Most columns end there (their pivot is not owned yet); the rest continue below in filtration order.
    struct Columns { std::vector<EdgeKey> entries; std::vector<std::uint32_t> start{0}; };
    const std::size_t chunk = 2048, nchunks = (deaths1_.size() + chunk - 1) / chunk;
    std::vector<Columns> first(nchunks);
    tbb::parallel_for(std::size_t(0), nchunks, [&](std::size_t c) {
      Heap heap(heap_less);
      Columns& cols = first[c];
      for (std::size_t i = c * chunk; i < std::min(deaths1_.size(), (c + 1) * chunk); ++i) {
        const auto& tau = deaths1_[i].v;
        heap.push(make_edge(tau[0], tau[1]));
        heap.push(make_edge(tau[0], tau[2]));
        heap.push(make_edge(tau[1], tau[2]));
        EdgeKey p;
        if (pop_to_birth_pivot(heap, p)) drain(heap, p, cols.entries);
        cols.start.push_back(std::uint32_t(cols.entries.size()));
      }
    });
    report("dim 1", 0.8);
    // In filtration order: a column whose pivot is owned adds the owner's column and goes on reducing.
    struct Span { const EdgeKey* begin; const EdgeKey* end; };
    std::vector<Span> owner(births1_, Span{nullptr, nullptr});
    std::deque<std::vector<EdgeKey>> continued;  // columns that needed additions (stable addresses)
    Heap heap(heap_less);
    for (std::size_t c = 0, i = 0; c < nchunks; ++c) {
      const Columns& cols = first[c];
      for (std::size_t k = 0; k + 1 < cols.start.size(); ++k, ++i) {
        if (cols.start[k] == cols.start[k + 1]) throw std::logic_error("a dim-1 death triangle reduced to zero");
        Span column{cols.entries.data() + cols.start[k], cols.entries.data() + cols.start[k + 1]};
        EdgeKey p = *column.begin;
        std::uint32_t r = birth_rank(p.hi, p.lo);
        if (owner[r].begin) {
          for (const EdgeKey* e = column.begin + 1; e != column.end; ++e) heap.push(*e);
          for (;;) {
            for (const EdgeKey* e = owner[r].begin + 1; e != owner[r].end; ++e) heap.push(*e);
            if (!pop_to_birth_pivot(heap, p)) throw std::logic_error("a dim-1 death triangle reduced to zero");
            r = birth_rank(p.hi, p.lo);
            if (!owner[r].begin) break;
          }
          continued.emplace_back();
          drain(heap, p, continued.back());
          column = {continued.back().data(), continued.back().data() + continued.back().size()};
        }
        owner[r] = column;
        const auto& tau = deaths1_[i].v;
        PersistencePair pr;
        pr.dim = 1;
        pr.birth = f_[p.hi];
        pr.death = f_[tau[0]];
        pr.birth_simplex = cx_.edge_id(p.hi, p.lo);
        pr.birth_vertex = p.hi;
        pr.death_simplex = cx_.triangle_id(tau[0], tau[1], tau[2]);
        pr.death_vertex = tau[0];
        pr.birth_lobes = {p.hi + delta_[lower_link(p.hi).lowest], p.lo};
        pr.death_lobes = deaths1_[i].lobes;
        out.pairs.push_back(pr);
      }
    }
  }

  void finish(PersistenceDiagram& out) {
    Id gmin = 0;
    for (Id v = 1; v < V_; ++v)
      if (less(v, gmin)) gmin = v;
    PersistencePair e;
    e.dim = 0;
    e.birth = f_[gmin];
    e.death = std::numeric_limits<float>::infinity();
    e.birth_simplex = e.birth_vertex = gmin;
    out.essential.push_back(e);
    // Discovery order is deterministic (saddles in filtration order); group by dimension.
    std::stable_sort(out.pairs.begin(), out.pairs.end(),
                     [](const PersistencePair& a, const PersistencePair& b) { return a.dim < b.dim; });
  }

  const ScalarGrid& grid_;
  const float* f_;
  FreudenthalComplex cx_;
  Id V_;
  ProgressFn progress_;
  const std::vector<detail::LinkComponents>& table_;
  const freudenthal::Link& link_;
  std::array<Id, 14> delta_{};
  std::array<std::int8_t, 27> slot_of_offset_{};
  std::array<std::array<std::int8_t, 14>, 14> link_edge_index_{};
  std::vector<std::uint32_t> desc_, asc_, joins_, splits_;
  Id minima_ = 0, maxima_ = 0;
  std::vector<BirthSlots> birth_list_;  // join saddles with dim-1 birth edges, in filtration order
  std::vector<std::uint32_t> birth_table_;  // hash of birth_list_ by saddle
  std::size_t births1_ = 0;
  struct Death1 { std::array<Id, 3> v; std::array<Id, 2> lobes; };  // v: highest to lowest vertex
  std::vector<Death1> deaths1_;
  std::vector<std::uint32_t> link_index_;  // per vertex: index into link_infos_, or kOutside if not computed
  tbb::concurrent_vector<LowerLinkInfo> link_infos_;
};

}  // namespace

PersistenceDiagram lower_star_persistence(const ScalarGrid& grid, const ProgressFn& progress) {
  validate_grid(grid);
  Engine engine(grid, progress);
  return engine.run();
}

void write_pairs_csv(const PersistenceDiagram& diagram, const std::string& path) {
  std::FILE* fp = std::fopen(path.c_str(), "w");
  if (!fp) throw Error("cannot write '" + path + "'");
  std::fprintf(fp, "dim,birth,death\n");
  for (auto& p : diagram.essential) std::fprintf(fp, "%d,%.9g,inf\n", p.dim, p.birth);
  for (auto& p : diagram.pairs) std::fprintf(fp, "%d,%.9g,%.9g\n", p.dim, p.birth, p.death);
  if (std::fclose(fp) != 0) throw Error("cannot write '" + path + "' (disk full?)");
}

}  // namespace chokeloops

// Dimension 1 of the lower-star persistence engine (see persistence.cpp for the whole): the edges left by
// dim 0 and the triangles left by dim 2 are paired by reducing only the boundaries of those triangles.
#include <tbb/parallel_for.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <atomic>
#include <limits>
#include <memory>
#include <queue>
#include <stdexcept>
#include <string>
#include <unordered_map>

#include <sys/mman.h>
#include <unistd.h>

#include "persistence_engine.h"

namespace chokeloops::detail {

// How many edges a death triangle's column may pop in the parallel pass when some columns run long (see dim1).
constexpr std::size_t kColumnBudget = 16;
constexpr std::size_t kSharedBudget = 256;
// A column popping more than kLongColumn edges is long; a field with over 1% long columns among a sample of
// every kSampleStride-th (or of about kSamples, where there are more) is reduced lazily.
constexpr std::size_t kLongColumn = 128, kSampleStride = 64, kSamples = 8192;

LowerLinkInfo Engine::compute_lower_link(Id v) const {
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
  // the link's components end as the table says: once that many are left, no later edge kills a slot
  int merges_left = n_lower - table_[info.lower].count;
  for (int i = 1; i < n_lower && merges_left > 0; ++i) {
    const int a = order[i];
    for (unsigned earlier = earlier_link_neighbours(a, i, info.lower, rank); earlier; earlier &= earlier - 1) {
      const int b = order[__builtin_ctz(earlier)];
      int ra = lfind(a), rb = lfind(b);
      if (ra == rb) continue;
      bool a_younger = rank[ra] > rank[rb];
      int young = a_younger ? ra : rb, old = a_younger ? rb : ra;
      parent[young] = old;
      info.killer[young] = link_edge_index_[a][b];
      info.older[young] = std::int8_t(old);
      --merges_left;
    }
  }
  if (n_lower) info.lowest = std::int8_t(order[0]);
  return info;
}

const LowerLinkInfo& Engine::LinkCache::get(const Engine& engine, Id v) {
  Entry& e = entries[slot(v)];
  if (e.key != std::uint32_t(v)) {
    e.key = std::uint32_t(v);
    e.info = engine.compute_lower_link(v);
  }
  return e.info;
}

template <class Push>
void Engine::expand_local_pair(Id v, const LowerLinkInfo& info, int x, Push&& push) {
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
  if (prev[target] == -2) throw InternalError("lower-link path not found in dim-1 reduction");
  // (v, lowest) attaches v: a negative edge, which the reduction drops wherever it pops, so it is not pushed
  // (on rough fields most expansions end at the lowest root)
  if (target != info.lowest) push(make_edge(v, v + delta_[target]));
  for (int b = target; prev[b] >= 0; b = prev[b]) push(make_edge(v + delta_[b], v + delta_[prev[b]]));
}

// Asks the kernel for the pages of [begin, begin + bytes) in parallel, 64 MB a task (whole pages only). Where
// madvise cannot (a kernel before 5.14), the first touch faults them in as before.
static void populate_in_parallel(void* begin, std::size_t bytes) {
  const std::uintptr_t page = std::uintptr_t(sysconf(_SC_PAGESIZE));
  const std::uintptr_t from = (std::uintptr_t(begin) + page - 1) & ~(page - 1);
  const std::uintptr_t to = (std::uintptr_t(begin) + bytes) & ~(page - 1);
  if (to <= from) return;
  const std::uintptr_t chunk = std::uintptr_t(64) << 20;
  tbb::parallel_for(std::uintptr_t(0), (to - from + chunk - 1) / chunk, [&](std::uintptr_t k) {
    const std::uintptr_t a = from + k * chunk, b = std::min(to, a + chunk);
    madvise(reinterpret_cast<void*>(a), b - a, MADV_POPULATE_WRITE);
  });
}

// Interleaves the bits of a vertex's coordinates (Z-order): vertices close in the grid get close keys at
// every scale, so a run of keys stays in a compact brick whatever the grid's slice size.
static std::uint64_t morton_key(std::array<int, 3> c) {
  auto spread = [](std::uint64_t x) {
    x &= 0x1FFFFF;
    x = (x | x << 32) & 0x1F00000000FFFFull;
    x = (x | x << 16) & 0x1F0000FF0000FFull;
    x = (x | x << 8) & 0x100F00F00F00F00Full;
    x = (x | x << 4) & 0x10C30C30C30C30C3ull;
    x = (x | x << 2) & 0x1249249249249249ull;
    return x;
  };
  return spread(std::uint64_t(c[0])) | spread(std::uint64_t(c[1])) << 1 | spread(std::uint64_t(c[2])) << 2;
}

template <class Heap>
bool Engine::pop_to_birth_pivot(Heap& heap, LinkCache& links, EdgeKey& p, std::uint32_t& rank,
                                std::size_t& budget) {
  while (!heap.empty() && budget > 0) {
    --budget;
    p = heap.top();
    heap.pop();
    bool odd = true;
    while (!heap.empty() && heap.top() == p) { heap.pop(); odd = !odd; }
    if (!odd) continue;
    const LowerLinkInfo& info = links.get(*this, p.hi);
    int x = slot(p.hi, p.lo);
    if (info.killer[x] >= 0) {
      expand_local_pair(p.hi, info, x, [&](const EdgeKey& e) { heap.push(e); });
      continue;
    }
    // A root's edge is negative (it attaches p.hi, or merges two components) unless dim 0 left it as a
    // birth; the lowest root's edge always attaches. Negative edges are compressed away.
    if (x == info.lowest) continue;
    const BirthEntry* b = birth_slots(p.hi);
    if (b && (b->mask >> x & 1)) {
      rank = birth_rank_in(p.hi, *b, p.lo);
      return true;
    }
  }
  return false;
}

EdgeKey Engine::birth_edge(std::uint32_t rank) const {
  auto after = std::upper_bound(birth_list_.begin(), birth_list_.end(), rank,
                                [](std::uint32_t r, const BirthSlots& b) { return r < b.base; });
  const BirthSlots& b = *(after - 1);
  std::array<int, 14> order;
  const int n = lower_slots_in_order(b.saddle, b.mask, order);
  const std::uint32_t k = rank - b.base;
  if (k >= std::uint32_t(n)) throw InternalError("dim-1 birth rank out of range");
  return make_edge(b.saddle, b.saddle + delta_[order[k]]);
}

// Adds `add` to the column `col` (both in descending rank order) modulo 2, into `out`.
static void add_columns(const std::uint32_t* a, const std::uint32_t* a_end, const std::uint32_t* b,
                        const std::uint32_t* b_end, BigVector<std::uint32_t>& out) {
  out.clear();
  while (a != a_end && b != b_end) {
    if (*a > *b) out.push_back(*a++);
    else if (*b > *a) out.push_back(*b++);
    else { ++a; ++b; }
  }
  out.insert(out.end(), a, a_end);
  out.insert(out.end(), b, b_end);
}

void Engine::dim1(PersistenceDiagram& out) {
  if (births1_ != deaths1_.size())
    throw InternalError("dim-1 births and deaths do not balance (" + std::to_string(births1_) + " vs " +
                           std::to_string(deaths1_.size()) + ")");
  const std::size_t n = deaths1_.size();
  auto lap = step_timer();
  // the death half of each pair now, in parallel; the sequential pass adds the birth
  const std::size_t base = out.pairs.size();
  // The pairs' storage was reserved for the whole diagram but never touched: fault it in from every thread
  // first, where the resize would take each fresh page's fault and clearing in one.
  populate_in_parallel(out.pairs.data() + base, (out.pairs.capacity() - base) * sizeof(PersistencePair));
  out.pairs.resize(base + n);
  tbb::parallel_for(std::size_t(0), n, [&](std::size_t i) {
    PersistencePair& pr = out.pairs[base + i];
    pr.dim = 1;
    const Death1& d = deaths1_[i];
    const Id s = d.s;
    pr.death_simplex = cx_.triangle_id(s, s + delta_[d.a], s + delta_[d.b]);
    pr.death_vertex = s;  // a cross triangle lies in its saddle's lower star
    pr.death = f_[s];
    pr.death_lobes = {lobe_vertex(d.s, d.lobe1), lobe_vertex(d.s, d.lobe2)};
  });
  lap("dim 1: death halves (parallel)");
  struct EdgeLess {
    bool operator()(const EdgeKey& a, const EdgeKey& b) const { return edge_less(a, b); }
  };
  using Heap = std::priority_queue<EdgeKey, std::vector<EdgeKey>, EdgeLess>;
  // In parallel: each death triangle's boundary reduced to birth edges alone (each edge paired inside its
  // own lower star is replaced by the rest of its pair's cone; negative edges are dropped), kept as the birth
  // edges' ranks in descending order; the sequential pass below then only merges sorted rank lists. On rough
  // fields that is nearly every column. A column that needs more than kColumnBudget pops (smooth fields with
  // sparse noise: the boundary runs far down) keeps only the ranks found so far and stays lazy: if its first
  // rank is also another's, it is reduced further (kSharedBudget); otherwise the sequential pass reduces it,
  // from its triangle, only as far as it must. This part is order-free, so it runs in grid order:
  // neighbouring triangles share lower links and field memory, which the filtration order scatters.
  BigVector<std::uint32_t> grid_order(n);
  {
    struct Keyed { std::uint64_t key; std::uint32_t index; };
    BigVector<Keyed> keyed(n);
    tbb::parallel_for(std::size_t(0), n, [&](std::size_t i) {
      keyed[i] = {morton_key(cx_.coords(out.pairs[base + i].death_vertex)), std::uint32_t(i)};
    });
    tbb::parallel_sort(keyed.begin(), keyed.end(), [](const Keyed& a, const Keyed& b) {
      return a.key < b.key || (a.key == b.key && a.index < b.index);
    });
    tbb::parallel_for(std::size_t(0), n, [&](std::size_t k) { grid_order[k] = keyed[k].index; });
  }
  lap("dim 1: Z-order of the columns");
  // Where a column's ranks are: chunk `chunk`'s list, or the pool; kLazy marks a column known only as far
  // as its ranks go (its triangle gives the rest).
  constexpr std::uint32_t kPool = 0xFFFFFFFFu, kLazy = 0x80000000u;
  struct Where { std::uint32_t chunk, begin, end; };
  BigVector<Where> where(n);
  const std::size_t chunk = 2048, nchunks = (n + chunk - 1) / chunk;
  BigVector<BigVector<std::uint32_t>> first(nchunks);
  tbb::enumerable_thread_specific<std::unique_ptr<LinkCache>> caches;
  // From the death's 8-byte record, kept until the additions: in grid order the columns read their deaths
  // at random, and the 80-byte pairs missed the cache at each.
  auto push_triangle = [&](Heap& heap, std::uint32_t i) {
    const Death1& d = deaths1_[i];
    const Id a = d.s + delta_[d.a], b = d.s + delta_[d.b];
    heap.push(make_edge(d.s, a));
    heap.push(make_edge(d.s, b));
    heap.push(make_edge(a, b));
  };
  // Reduces column i from its triangle, appending its ranks to `entries`, popping at most `budget` edges;
  // true if it was reduced in full.
  // With `first_only`, it stops at the first rank (the pivot) as well.
  auto reduce_column = [&](Heap& heap, LinkCache& links, std::uint32_t i, std::size_t budget,
                           BigVector<std::uint32_t>& entries, bool first_only = false) {
    while (!heap.empty()) heap.pop();
    push_triangle(heap, i);
    EdgeKey p;
    std::uint32_t r;
    while (pop_to_birth_pivot(heap, links, p, r, budget)) {
      entries.push_back(r);
      if (first_only) break;
    }
    return heap.empty();
  };
  std::atomic<std::size_t> lazy_columns{0};
  auto in_parallel = [&](auto&& body) {
    tbb::parallel_for(std::size_t(0), nchunks, [&](std::size_t c) {
      std::unique_ptr<LinkCache>& links = caches.local();
      if (!links) links = std::make_unique<LinkCache>();
      Heap heap;
      for (std::size_t k = c * chunk; k < std::min(n, (c + 1) * chunk); ++k) body(c, grid_order[k], heap, *links);
      first[c].shrink_to_fit();
    });
  };
  // Full reduction pays on rough fields, where a quarter of the columns get others added and nearly all are
  // short; on smooth fields with sparse noise most columns are long (the boundary runs far down) and few are
  // ever added to: there only the ranks the sequential pass asks for are found. A sample decides which.
  std::atomic<std::size_t> sampled{0}, long_ones{0};
  const std::size_t stride = std::max(kSampleStride, n / kSamples);
  tbb::parallel_for(std::size_t(0), (n + stride - 1) / stride, [&](std::size_t k) {
    std::unique_ptr<LinkCache>& links = caches.local();
    if (!links) links = std::make_unique<LinkCache>();
    Heap heap;
    BigVector<std::uint32_t> ranks;
    if (!reduce_column(heap, *links, grid_order[k * stride], kLongColumn, ranks)) ++long_ones;
    ++sampled;
  });
  const bool lazy_pass = long_ones * 100 > sampled;
  lap("dim 1: sample of column lengths");
  const std::size_t budget = lazy_pass ? kColumnBudget : std::numeric_limits<std::size_t>::max();
  in_parallel([&](std::size_t c, std::uint32_t i, Heap& heap, LinkCache& links) {
    BigVector<std::uint32_t>& entries = first[c];
    const std::size_t begin = entries.size();
    const bool full = reduce_column(heap, links, i, budget, entries, lazy_pass);
    if (full && entries.size() == begin) throw InternalError("a dim-1 death triangle reduced to zero");
    where[i] = {std::uint32_t(c) | (full ? 0 : kLazy), std::uint32_t(begin), std::uint32_t(entries.size())};
    if (!full) ++lazy_columns;
  });
  lap("dim 1: columns (parallel)");
  if (lazy_columns > 0) {
    BigVector<std::uint8_t> firsts(births1_, 0);  // how many columns start with each rank (0, 1, 2+)
    for (std::size_t i = 0; i < n; ++i)
      if (where[i].begin != where[i].end) {
        std::uint8_t& f = firsts[first[where[i].chunk & ~kLazy][where[i].begin]];
        if (f < 2) ++f;
      }
    in_parallel([&](std::size_t c, std::uint32_t i, Heap& heap, LinkCache& links) {
      Where& w = where[i];
      if (!(w.chunk & kLazy)) return;
      BigVector<std::uint32_t>& entries = first[c];
      if (w.begin != w.end && firsts[entries[w.begin]] < 2) return;
      const std::size_t begin = entries.size();
      const bool full = reduce_column(heap, links, i, kSharedBudget, entries);
      if (full && entries.size() == begin) throw InternalError("a dim-1 death triangle reduced to zero");
      w = {std::uint32_t(c) | (full ? 0 : kLazy), std::uint32_t(begin), std::uint32_t(entries.size())};
      if (full) --lazy_columns;
    });
  }
  BigVector<std::uint32_t>().swap(grid_order);
  lap("dim 1: lazy columns (parallel)");
  out.stats.dim1_lazy_columns = Id(lazy_columns.load());
  if (lazy_columns == 0) {  // every rank is known: no birth edge is looked up again
    BigVector<BirthBlock>().swap(birth_blocks_);
    BigVector<BirthEntry>().swap(birth_by_vertex_);
  }
  report("dim 1", 0.8);
  // In filtration order: a column whose pivot is owned adds the owner's column until its pivot is free.
  // owner: per birth rank, the death whose column has it as pivot. Columns that needed additions move to
  // the pool (chunk kPool); one reduced on a heap keeps what is left below its pivot as raw edges.
  BigVector<std::uint32_t> owner(births1_, kOutside), pool, sum, scratch;
  BigVector<std::array<std::uint32_t, 2>> edge_pool;
  std::unordered_map<std::uint32_t, std::array<std::uint32_t, 2>> raw_edges;  // column -> its range in edge_pool
  auto column_of = [&](std::uint32_t i) {
    const Where& w = where[i];
    const std::uint32_t* data = w.chunk == kPool ? pool.data() : first[w.chunk & ~kLazy].data();
    return std::make_pair(data + w.begin, data + w.end);
  };
  auto is_lazy = [&](std::uint32_t i) { return where[i].chunk != kPool && (where[i].chunk & kLazy); };
  auto is_ranks_only = [&](std::uint32_t i) { return !is_lazy(i) && !raw_edges.count(i); };
  auto to_pool = [&](std::uint32_t i, const std::uint32_t* ranks, std::size_t count) {
    if (pool.size() + count > kPool)
      throw Error("the dim-1 reduction outgrew its 32-bit column pool; use a coarser resolution", 3);
    where[i] = {kPool, std::uint32_t(pool.size()), std::uint32_t(pool.size() + count)};
    pool.insert(pool.end(), ranks, ranks + count);
  };
  // The textbook reduction on a heap of edges, as far as the pivot only: while the pivot p is owned, the
  // owner's column is added (its other ranks as birth edges and its raw edges; or, for a lazy owner, its
  // triangle and p once more, which its reduction cancels); what is left below the free pivot stays raw.
  LinkCache sequential_links;
  Heap heap;
  auto reduce_on_heap = [&](std::uint32_t i) {
    EdgeKey p;
    std::uint32_t r;
    for (;;) {
      std::size_t unlimited = std::numeric_limits<std::size_t>::max();
      if (!pop_to_birth_pivot(heap, sequential_links, p, r, unlimited))
        throw InternalError("a dim-1 death triangle reduced to zero");
      const std::uint32_t o = owner[r];
      if (o == kOutside) break;
      if (is_lazy(o)) {
        heap.push(p);
        push_triangle(heap, o);
        continue;
      }
      auto [ob, oe] = column_of(o);  // *ob == r cancels the pivot just popped
      for (++ob; ob != oe; ++ob) heap.push(birth_edge(*ob));
      auto raw = raw_edges.find(o);
      if (raw != raw_edges.end())
        for (std::uint32_t e = raw->second[0]; e < raw->second[1]; ++e)
          heap.push(make_edge(edge_pool[e][0], edge_pool[e][1]));
    }
    to_pool(i, &r, 1);
    const std::uint32_t edges_begin = std::uint32_t(edge_pool.size());
    while (!heap.empty()) {
      const EdgeKey e = heap.top();
      heap.pop();
      if (!heap.empty() && heap.top() == e) { heap.pop(); continue; }
      edge_pool.push_back({e.hi, e.lo});
    }
    if (edge_pool.size() > kPool) throw Error("the dim-1 reduction outgrew its 32-bit edge pool; use a coarser resolution", 3);
    if (edge_pool.size() > edges_begin) raw_edges[i] = {edges_begin, std::uint32_t(edge_pool.size())};
    return r;
  };
  for (std::size_t k = 0; k < n; ++k) {
    const std::uint32_t i = std::uint32_t(k);
    auto [begin, end] = column_of(i);
    std::uint32_t r = begin != end ? *begin : kOutside;
    if (r != kOutside && owner[r] == kOutside) {
      // its pivot is free: nothing to add, whatever is known of the rest
    } else if (is_lazy(i)) {
      push_triangle(heap, i);
      r = reduce_on_heap(i);
    } else {
      // ranks only: adding columns merges sorted rank lists while the owners are ranks only too
      sum.assign(begin, end);
      while (owner[r] != kOutside && is_ranks_only(owner[r])) {
        auto [obegin, oend] = column_of(owner[r]);
        add_columns(sum.data(), sum.data() + sum.size(), obegin, oend, scratch);
        sum.swap(scratch);
        if (sum.empty()) throw InternalError("a dim-1 death triangle reduced to zero");
        r = sum.front();
      }
      if (owner[r] != kOutside) {
        for (std::uint32_t q : sum) heap.push(birth_edge(q));
        r = reduce_on_heap(i);
      } else {
        to_pool(i, sum.data(), sum.size());
      }
    }
    owner[r] = i;
  }
  BigVector<Death1>().swap(deaths1_);
  lap("dim 1: additions (sequential)");
  // the birth half of each pair, a join saddle at a time: its birth edges are its lower slots in order
  tbb::parallel_for(std::size_t(0), birth_list_.size(), [&](std::size_t q) {
    const BirthSlots& b = birth_list_[q];
    const Id s = b.saddle;
    std::array<int, 14> order;
    const int count = lower_slots_in_order(s, b.mask, order);
    const Id lowest = s + delta_[lowest_slot(s)];
    for (int k = 0; k < count; ++k) {
      const std::uint32_t i = owner[b.base + std::uint32_t(k)];
      if (i == kOutside) throw InternalError("a dim-1 birth edge left unpaired");
      PersistencePair& pr = out.pairs[base + i];
      const Id lo = s + delta_[order[k]];
      pr.birth = f_[s];
      pr.birth_simplex = cx_.edge_id(s, lo);
      pr.birth_vertex = s;
      pr.birth_lobes = {lowest, lo};
    }
  });
  lap("dim 1: birth halves (parallel)");
}

}  // namespace chokeloops::detail

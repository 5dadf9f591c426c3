// Lower-star persistence on the implicit Freudenthal complex, without a global boundary matrix.
//
// Why it is fast: a vertex whose lower link (the part of its 14-neighbour link sphere below it) is a
// disk changes no homology, so every pair between two different lower stars starts and ends at a
// vertex whose lower link has several components (join saddle: dim-0 deaths, dim-1 births), whose
// upper link has several components (split saddle: dim-2 births, dim-1 deaths), or at an extremum.
// A 14-bit mask and a table of link components classify every vertex in one parallel pass.
//  * dim 0: each vertex keeps the link slot of its lowest neighbour (4 bits, no 32-bit pointer a vertex); the
//    descents from the lobes of the join saddles, followed in parallel, give their minima. Join saddles, in
//    filtration order, merge those minima with the elder rule (union-find over the minima). The cross edge
//    of a lower-link component is (s, lowest vertex of the component).
//  * dim 2: the same upside down on the dual graph (tetrahedra joined by triangles, the outside of the box
//    one node that never dies): each vertex keeps its step up, maxima own the last tetrahedron of their
//    star, and split saddles, in reverse order, replay their lower star's tetrahedra and triangles locally.
//  * dim 1: the edges left by dim 0 and the triangles left by dim 2 are paired by reducing only the
//    boundaries of those triangles; a pivot edge paired inside its own lower star is replaced by the rest
//    of that pair's cone (a path in the lower link), negative edges are compressed away. That needs no
//    other column, so every death triangle's boundary is reduced in parallel (DMS-style) until only birth
//    edges are left, kept as their ranks; the ~25% of columns (on rough fields) whose pivot is already
//    owned then add other columns sequentially, as merges of short sorted rank lists.
// Everything but that sequential remainder of dim 1 and the union-find merges runs in parallel; every step
// is deterministic.
#include "chokeloops/topology/persistence.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <functional>
#include <limits>
#include <cstdio>
#include <cstring>
#include <string>

#include "chokeloops/field/memory_budget.h"
#include "persistence_engine.h"

namespace chokeloops {

std::size_t PersistenceDiagram::count(int dim) const {
  std::size_t n = 0;
  for (auto& p : pairs) n += p.dim == dim;
  return n;
}

namespace detail {

PersistenceDiagram Engine::run() {
  PersistenceDiagram out;
  out.dims = grid_.dims;
  auto t0 = Clock::now();
  report("classify", 0);
  classify();
  guard_memory(out);
  out.stats.seconds_classify = seconds_since(t0);
  auto t = Clock::now();
  report("dim 0", 0.3);
  out.pairs.reserve(std::size_t(minima_));
  advise_huge_pages(out.pairs.data(), out.pairs.capacity() * sizeof(PersistencePair));
  dim0(out);
  // each pointer array and saddle list is read by its own dimension only
  out.stats.join_saddles = Id(joins_.size());
  BigVector<std::uint32_t>().swap(joins_);
  BigVector<std::uint32_t>().swap(minima_list_);
  minimum_index_ = {};
  const std::size_t end0 = out.pairs.size();
  out.stats.seconds_dim0 = seconds_since(t);
  t = Clock::now();
  report("dim 2", 0.45);
  // the whole diagram at once (a maximum dies at most once; every dim-1 birth dies): no doubling, and
  // no copy of the largest array while it is full
  out.pairs.reserve(out.pairs.size() + std::size_t(maxima_) + births1_);
  advise_huge_pages(out.pairs.data() + out.pairs.size(), (out.pairs.capacity() - out.pairs.size()) * sizeof(PersistencePair));
  dim2(out);
  out.stats.split_saddles = Id(splits_.size());
  BigVector<std::uint8_t>().swap(codes_);
  BigVector<std::uint32_t>().swap(splits_);
  BigVector<std::uint32_t>().swap(maxima_list_);
  maximum_index_ = {};
  const std::size_t end2 = out.pairs.size();
  out.stats.seconds_dim2 = seconds_since(t);
  t = Clock::now();
  report("dim 1", 0.6);
  dim1(out);
  out.stats.seconds_dim1 = seconds_since(t);
  finish(out, end0, end2);
  out.stats.minima = minima_;
  out.stats.maxima = maxima_;
  out.stats.seconds_total = seconds_since(t0);
  report("done", 1);
  return out;
}

namespace {
// One slot of classify_interior_row's pass in rising index order, over `count` vertices. All-ones masks and
// bitwise selects: written with ?: or as float selects, GCC keeps a branch and does not vectorise.
void take_lowest_and_highest(int count, std::int32_t slot, const float* __restrict x, const std::uint32_t* __restrict lower,
                             std::int32_t* __restrict lo, std::int32_t* __restrict hi, float* __restrict lowest,
                             float* __restrict highest) {
  for (int i = 0; i < count; ++i) {
    const float xi = x[i], low = lowest[i], high = highest[i];
    const std::int32_t is_lower = -std::int32_t((lower[i] >> slot) & 1u);
    const std::int32_t take_lo = is_lower & -std::int32_t(xi < low);
    const std::int32_t take_hi = ~is_lower & -std::int32_t(xi >= high);
    lo[i] = (lo[i] & ~take_lo) | (slot & take_lo);
    hi[i] = (hi[i] & ~take_hi) | (slot & take_hi);
    std::int32_t bits_x, bits_low, bits_high;
    std::memcpy(&bits_x, &xi, 4), std::memcpy(&bits_low, &low, 4), std::memcpy(&bits_high, &high, 4);
    bits_low = (bits_low & ~take_lo) | (bits_x & take_lo);
    bits_high = (bits_high & ~take_hi) | (bits_x & take_hi);
    std::memcpy(&lowest[i], &bits_low, 4), std::memcpy(&highest[i], &bits_high, 4);
  }
}

void add_lower_bits(int count, std::uint32_t bit, bool ties_lower, const float* __restrict x,
                    const float* __restrict centre, std::uint32_t* __restrict lower) {
  if (!ties_lower)
    for (int i = 0; i < count; ++i) lower[i] |= x[i] < centre[i] ? bit : 0u;
  else
    for (int i = 0; i < count; ++i) lower[i] |= x[i] <= centre[i] ? bit : 0u;
}
}  // namespace

// Inside the box a neighbour's index is above v's for slots 0-6 and below it for slots 7-13, and the slots in
// rising index order are 13..7, 0..6: the order's tie on equal values needs no index comparison, and the
// lowest lower and highest upper neighbours come from one pass over the slots in that order (a strictly lower
// value replaces the lowest, an equal or higher one the highest). Slot by slot over a whole row, each step is
// the same for every vertex, without a branch: the compiler vectorises it, where the field's comparisons as
// branches were unpredictable and cost most of the classification.
void Engine::classify_interior_row(Id first, int count, RowScratch& out) const {
  static constexpr int kRising[14] = {13, 12, 11, 10, 9, 8, 7, 0, 1, 2, 3, 4, 5, 6};
  const float* centre = f_ + first;
  for (int i = 0; i < count; ++i) {
    out.lower[std::size_t(i)] = 0, out.lo[std::size_t(i)] = -1, out.hi[std::size_t(i)] = -1;
    out.lowest[std::size_t(i)] = std::numeric_limits<float>::infinity();
    out.highest[std::size_t(i)] = -std::numeric_limits<float>::infinity();
  }
  for (int n = 0; n < 14; ++n) add_lower_bits(count, 1u << n, n >= 7, centre + delta_[n], centre, out.lower.data());
  for (int t = 0; t < 14; ++t)
    take_lowest_and_highest(count, kRising[t], centre + delta_[kRising[t]], out.lower.data(), out.lo.data(),
                            out.hi.data(), out.lowest.data(), out.highest.data());
}

void Engine::classify() {
  codes_.resize(std::size_t(V_));
  const int nx = grid_.dims[0], ny = grid_.dims[1], nz = grid_.dims[2];
  struct Local { BigVector<std::uint32_t> joins, splits, minima, maxima; std::size_t extra_lower = 0, extra_upper = 0; };
  tbb::enumerable_thread_specific<Local> locals;
  tbb::enumerable_thread_specific<RowScratch> scratch;
  tbb::parallel_for(tbb::blocked_range<int>(0, nz * ny), [&](const tbb::blocked_range<int>& r) {
    Local& L = locals.local();
    RowScratch& row_scratch = scratch.local();
    row_scratch.resize(std::size_t(nx));
    for (int row = r.begin(); row != r.end(); ++row) {
      int j = row % ny, k = row / ny;
      const bool border_row = j == 0 || k == 0 || j == ny - 1 || k == nz - 1;
      if (!border_row && nx > 2) classify_interior_row(cx_.vertex(1, j, k), nx - 2, row_scratch);
      for (int i = 0; i < nx; ++i) {
        Id v = cx_.vertex(i, j, k);
        std::uint16_t lower = 0, outside = 0;
        int lo = -1, hi = -1;
        const bool interior = !border_row && i > 0 && i < nx - 1;
        if (interior) {
          lower = std::uint16_t(row_scratch.lower[std::size_t(i - 1)]);
          lo = row_scratch.lo[std::size_t(i - 1)];
          hi = row_scratch.hi[std::size_t(i - 1)];
        }
        // a border vertex, or a lower neighbour as high as +inf (where the row's pass finds no lowest)
        if (!interior || (lower && lo < 0)) {
          lower = 0, lo = -1, hi = -1;
          for (int n = 0; n < 14; ++n) {
            if (!cx_.neighbor_inside({i, j, k}, n)) { outside |= std::uint16_t(1u << n); continue; }
            Id u = v + delta_[n];
            if (less(u, v)) {
              lower |= std::uint16_t(1u << n);
              if (lo < 0 || less(u, v + delta_[lo])) lo = n;
            } else if (hi < 0 || less(v + delta_[hi], u)) {
              hi = n;
            }
          }
        }
        std::uint16_t upper = std::uint16_t(~lower & 0x3FFF);
        const std::uint8_t down = lo < 0 ? kStepNone : std::uint8_t(lo);
        const std::uint8_t up = outside ? kStepOutside : hi < 0 ? kStepNone : std::uint8_t(hi);
        codes_[std::size_t(v)] = std::uint8_t(down | up << 4);
        if (lower == 0) L.minima.push_back(std::uint32_t(v));
        if (upper == 0) L.maxima.push_back(std::uint32_t(v));
        if (table_[lower].count >= 2) {
          L.joins.push_back(std::uint32_t(v));
          L.extra_lower += table_[lower].count - 1u;
        }
        if (table_[upper].count >= 2) {
          L.splits.push_back(std::uint32_t(v));
          L.extra_upper += table_[upper].count - 1u;
        }
      }
    }
  });
  for (auto& L : locals) {
    joins_.insert(joins_.end(), L.joins.begin(), L.joins.end());
    splits_.insert(splits_.end(), L.splits.begin(), L.splits.end());
    minima_list_.insert(minima_list_.end(), L.minima.begin(), L.minima.end());
    maxima_list_.insert(maxima_list_.end(), L.maxima.begin(), L.maxima.end());
    extra_lower_ += L.extra_lower;
    extra_upper_ += L.extra_upper;
  }
  minima_ = Id(minima_list_.size());
  maxima_ = Id(maxima_list_.size());
  tbb::parallel_sort(minima_list_.begin(), minima_list_.end());
  tbb::parallel_sort(maxima_list_.begin(), maxima_list_.end());
  minimum_index_.build(minima_list_, V_);
  maximum_index_.build(maxima_list_, V_);
  sort_in_filtration_order(joins_, false);
  sort_in_filtration_order(splits_, true);
}

// Sorted as 64-bit keys (the value's bits made to order as the value, then the index: the filtration order
// of vertex_less), where a comparison of two vertices reads the field at two scattered places.
void Engine::sort_in_filtration_order(BigVector<std::uint32_t>& vertices, bool descending) const {
  BigVector<std::uint64_t> keys(vertices.size());
  tbb::parallel_for(std::size_t(0), vertices.size(), [&](std::size_t i) {
    float value = f_[vertices[i]];
    if (value == 0.0f) value = 0.0f;  // -0 ties +0 in the field's order
    std::uint32_t bits;
    std::memcpy(&bits, &value, 4);
    bits = (bits & 0x80000000u) ? ~bits : bits | 0x80000000u;
    keys[i] = std::uint64_t(bits) << 32 | vertices[i];
  });
  if (descending)
    tbb::parallel_sort(keys.begin(), keys.end(), std::greater<std::uint64_t>());
  else
    tbb::parallel_sort(keys.begin(), keys.end());
  tbb::parallel_for(std::size_t(0), vertices.size(), [&](std::size_t i) { vertices[i] = std::uint32_t(keys[i]); });
}

void Engine::guard_memory(PersistenceDiagram& out) {
  // Every extra lower-link component of a join saddle kills a minimum or gives birth to a 1-cycle; every
  // extra upper-link component of a split saddle is a cross triangle: a dim-2 birth or a dim-1 death.
  const std::size_t minima = std::size_t(std::max<Id>(minima_, 1));
  const std::size_t births1 = extra_lower_ > minima - 1 ? extra_lower_ - (minima - 1) : 0;
  const std::size_t pairs = minima - 1 + extra_upper_;
  // The peak is that of dim 0, dim 2 or dim 1, from the arrays each holds (bytes per item): the field and the
  // steps (4 + 1 a vertex), the index of the saddles with births (a bit and a rank share: 2 bits a vertex),
  // the extrema's lists and their bucket indexes (4 + ~8), a union-find (4), the saddle lists, the pairs so
  // far, the birth slots of the join saddles (20 with their entry in vertex order); while a dimension's
  // saddles are visited in grid order, their visit order and two places (16) and each record twice (dim 0: a
  // lobe and its minimum, 8; dim 2: a cross triangle, 16); at the end of dim 2 the cross triangles and the
  // dim-1 deaths (8); then the field, the whole diagram and per dim-1 death its record, Z-order key, column
  // place, ~3 ranks, owner and pool share (44).
  const std::size_t V = std::size_t(V_), bits = V / 4, birth_slots = joins_.size() * 20;
  const std::size_t pair = sizeof(PersistencePair), extrema = std::size_t(minima_ + maxima_) * 12;
  const std::size_t classify = V * 5 + extrema + (joins_.size() + splits_.size()) * 4;
  const std::size_t lobes = (joins_.size() + extra_lower_) * 8 * 2 + joins_.size() * 16;
  const std::size_t dim0 = classify + bits + std::size_t(minima_) * 4 + (minima - 1) * pair + birth_slots + lobes;
  const std::size_t cross = extra_upper_ * sizeof(CrossTriangle);
  const std::size_t dim2 = V * 5 + bits + std::size_t(maxima_) * 8 + splits_.size() * 4 + birth_slots +
                           (minima - 1) * pair +
                           std::max(cross * 2 + splits_.size() * 16, cross + (pairs - births1) * pair + births1 * 8);
  const std::size_t dim1 = V * 4 + bits + pairs * pair + births1 * 44 + birth_slots;
  const std::size_t need = std::max({dim0, dim2, dim1}) + (std::size_t(32) << 20);
  out.stats.estimated_bytes = need;
  if (need <= max_memory_) return;
  auto mb = [](std::size_t b) { return std::to_string((b + (1u << 20) - 1) >> 20) + " MB"; };
  throw Error("persistence of this " + std::to_string(grid_.dims[0]) + "x" + std::to_string(grid_.dims[1]) + "x" +
                  std::to_string(grid_.dims[2]) + " field needs about " + mb(need) + " (" + std::to_string(pairs) +
                  " pairs: a rough field), more than the " + mb(max_memory_) +
                  " allowed; smooth or coarsen the field, or raise --max-memory",
              3);
}

void Engine::dim0(PersistenceDiagram& out) {
  global_min_ = Id(minima_list_.front());  // a box has at least one minimum
  for (std::uint32_t m : minima_list_)
    if (less(m, global_min_)) global_min_ = m;
  BigVector<std::uint32_t> parent(minima_list_.size());
  for (std::uint32_t i = 0; i < parent.size(); ++i) parent[i] = i;
  // Per join saddle, its lobes (the lowest vertex of each lower-link component, in filtration order) and the
  // minima their descents reach, found in parallel with the saddles in grid order (in filtration order they
  // are scattered over the grid), each written to its own place; merged in filtration order.
  const std::size_t J = joins_.size();
  auto lap = step_timer();
  struct Lobe { std::uint32_t low, root; };
  BigVector<std::uint32_t> place;
  const BigVector<Lobe> lobes = records_in_grid_order<Lobe>(
      joins_,
      [&](std::uint32_t s) { return table_[lower_mask(s)].count; },
      [&](std::uint32_t s, Lobe* L, int count, RootCache& roots) {
        const auto& comps = table_[lower_mask(s)];
        for (int c = 0; c < count; ++c) {
          Id best = -1;
          for (unsigned m = comps.masks[c]; m; m &= m - 1) {
            Id u = Id(s) + delta_[__builtin_ctz(m)];
            if (best < 0 || less(u, best)) best = u;
          }
          L[c].low = std::uint32_t(best);
        }
        std::sort(L, L + count, [this](const Lobe& a, const Lobe& b) { return less(a.low, b.low); });
        for (int c = 0; c < count; ++c) L[c].root = minimum_index_(walk<true>(L[c].low, roots));
      },
      place);
  lap("dim 0: lobes and minima (parallel)");
  // the union-find reads scattered minima: their entries are asked for a few saddles ahead
  constexpr std::size_t kAhead = 32;
  for (std::size_t i = 0; i < J; ++i) {
    if (place[i] + kAhead < lobes.size()) __builtin_prefetch(&parent[lobes[place[i] + kAhead].root]);
    const std::uint32_t s = joins_[i];
    const Lobe* L = lobes.data() + place[i];
    const int count = int(place[i + 1] - place[i]);
    BirthSlots births{s, 0, std::uint32_t(births1_)};
    for (int c = 1; c < count; ++c) {
      std::uint32_t rs = find(parent, L[0].root), r = find(parent, L[c].root);
      if (r == rs) {
        births.mask |= std::uint16_t(1u << slot(s, L[c].low));
        ++births1_;
        continue;
      }
      std::uint32_t young = less(minima_list_[r], minima_list_[rs]) ? rs : r, old = young == r ? rs : r;
      parent[young] = old;
      const Id young_vertex = minima_list_[young];
      PersistencePair p;
      p.dim = 0;
      p.birth = f_[young_vertex];
      p.death = f_[s];
      p.birth_simplex = p.birth_vertex = young_vertex;
      p.death_simplex = cx_.edge_id(s, L[c].low);
      p.death_vertex = s;
      p.death_lobes = {L[0].low, L[c].low};
      out.pairs.push_back(p);
    }
    if (births.mask) birth_list_.push_back(births);
  }
  lap("dim 0: merges (sequential)");
  index_birth_list();
  lap("dim 0: birth index");
}

void Engine::index_birth_list() {
  birth_blocks_.assign((std::size_t(V_) + 63) / 64, BirthBlock{0, 0});
  for (const BirthSlots& b : birth_list_) birth_blocks_[b.saddle >> 6].bits |= std::uint64_t(1) << (b.saddle & 63);
  std::uint32_t before = 0;
  for (BirthBlock& block : birth_blocks_) {
    block.before = before;
    before += std::uint32_t(__builtin_popcountll(block.bits));
  }
  birth_by_vertex_.resize(birth_list_.size());
  tbb::parallel_for(std::size_t(0), birth_list_.size(), [&](std::size_t i) {
    const BirthSlots& b = birth_list_[i];
    const BirthBlock& block = birth_blocks_[b.saddle >> 6];
    const std::uint64_t bit = std::uint64_t(1) << (b.saddle & 63);
    birth_by_vertex_[block.before + std::uint32_t(__builtin_popcountll(block.bits & (bit - 1)))] = {b.mask, b.base};
  });
}

Id Engine::last_tet(Id m) const {
  // A maximum is inside the box and above its 14 neighbours; its star's tetrahedra come in the order of their
  // other three vertices, highest first: with the neighbours ranked once, a triangle's key is its ranks.
  std::array<int, 14> order;
  const int n = lower_slots_in_order(m, 0x3FFF, order);
  std::array<unsigned, 14> rank{};
  for (int i = 0; i < n; ++i) rank[order[i]] = unsigned(i);
  unsigned best_key = 0;
  const std::array<int, 3>* best = &link_.triangles[0];
  for (auto& tr : link_.triangles) {
    unsigned r0 = rank[tr[0]], r1 = rank[tr[1]], r2 = rank[tr[2]];
    if (r0 < r1) std::swap(r0, r1);
    if (r1 < r2) std::swap(r1, r2);
    if (r0 < r1) std::swap(r0, r1);
    const unsigned key = r0 << 8 | r1 << 4 | r2;
    if (key > best_key) best_key = key, best = &tr;
  }
  return cx_.tet_id(m, m + delta_[(*best)[0]], m + delta_[(*best)[1]], m + delta_[(*best)[2]]);
}

int Engine::split_saddle_cross_triangles(std::uint32_t s, CrossTriangle* out, RootCache& roots) const {
  std::uint16_t lower, outside;
  masks(s, lower, outside);
  std::uint16_t upper = std::uint16_t(~lower & 0x3FFF);
  const auto& ucomps = table_[upper];
  std::array<int, 14> comp_of;
  comp_of.fill(-1);
  std::array<std::uint32_t, 7> rep{};
  std::array<std::int8_t, 7> lobe{};
  for (int c = 0; c < ucomps.count; ++c) {
    for (unsigned m = ucomps.masks[c]; m; m &= m - 1) comp_of[__builtin_ctz(m)] = c;
    rep[c] = (ucomps.masks[c] & outside)
                 ? kOutside
                 : maximum_index_(walk<false>(s + delta_[__builtin_ctz(ucomps.masks[c])], roots));
    unsigned in_box = ucomps.masks[c] & ~outside;
    lobe[c] = in_box ? std::int8_t(__builtin_ctz(in_box)) : std::int8_t(-1);
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
  int written = 0;
  std::array<std::int8_t, 14> rank;
  for (int i = 0; i < n_lower; ++i) rank[order[i]] = std::int8_t(i);
  for (int i = n_lower - 1; i > 0; --i) {
    // latest first: reverse filtration order
    for (unsigned earlier = earlier_link_neighbours(order[i], i, lower, rank); earlier;
         earlier &= ~(1u << (31 - __builtin_clz(earlier)))) {
      const int j = 31 - __builtin_clz(earlier);
      const int e = link_edge_index_[order[i]][order[j]];
      const auto& et = link_.edge_triangles[e];
      int r1 = lfind(node_of(et[0])), r2 = lfind(node_of(et[1]));
      if (r1 == r2) continue;
      if (comp_rep[r1] >= 0 && comp_rep[r2] >= 0) {
        out[written++] = {s, std::uint8_t(link_.edges[e][0]), std::uint8_t(link_.edges[e][1]), lobe[comp_rep[r1]],
                          lobe[comp_rep[r2]], rep[comp_rep[r1]], rep[comp_rep[r2]]};
        if (written == ucomps.count - 1) return written;  // the rest of the star joins nothing more
      }
      parent[r2] = r1;
      if (comp_rep[r1] < 0) comp_rep[r1] = comp_rep[r2];
    }
  }
  return written;
}

void Engine::dim2(PersistenceDiagram& out) {
  auto lap = step_timer();
  // Cross triangles of all split saddles, computed in parallel, kept in saddle order: as in dim 0, the saddles
  // are visited in grid order, each writing to its own place. A saddle has one cross triangle per extra
  // upper-link component, so the places are known from the masks alone.
  BigVector<std::uint32_t> place;
  const BigVector<CrossTriangle> cross = records_in_grid_order<CrossTriangle>(
      splits_,
      [&](std::uint32_t s) { return table_[std::uint16_t(~lower_mask(s) & 0x3FFF)].count - 1; },
      [&](std::uint32_t s, CrossTriangle* out, int count, RootCache& roots) {
        if (split_saddle_cross_triangles(s, out, roots) != count)
          throw InternalError("a split saddle's star has fewer cross triangles than upper-link components");
      },
      place);
  BigVector<std::uint32_t>().swap(place);
  lap("dim 2: cross triangles (parallel)");
  BigVector<std::uint32_t> parent(maxima_list_.size());
  for (std::uint32_t i = 0; i < parent.size(); ++i) parent[i] = i;
  const std::size_t first = out.pairs.size();
  constexpr std::size_t kAhead = 32;  // as in dim 0
  for (std::size_t k = 0; k < cross.size(); ++k) {
    const CrossTriangle& ct = cross[k];
    if (k + kAhead < cross.size()) {
      const CrossTriangle& next = cross[k + kAhead];
      if (next.rep1 != kOutside) __builtin_prefetch(&parent[next.rep1]);
      if (next.rep2 != kOutside) __builtin_prefetch(&parent[next.rep2]);
    }
    std::uint32_t g1 = find(parent, ct.rep1), g2 = find(parent, ct.rep2);
    Id s = ct.s, a = s + delta_[ct.a], b = s + delta_[ct.b];
    if (g1 == g2) {
      deaths1_.push_back({ct.s, ct.a, ct.b, ct.lobe1, ct.lobe2});
      continue;
    }
    bool g1_younger = g2 == kOutside || (g1 != kOutside && less(maxima_list_[g1], maxima_list_[g2]));
    std::uint32_t young = g1_younger ? g1 : g2, old = g1_younger ? g2 : g1;
    parent[young] = old;
    const Id young_vertex = maxima_list_[young];
    PersistencePair p;
    p.dim = 2;
    p.birth = f_[s];
    p.death = f_[young_vertex];
    p.birth_simplex = cx_.triangle_id(s, a, b);
    p.birth_vertex = s;
    p.death_vertex = young_vertex;
    p.birth_lobes = {lobe_vertex(ct.s, ct.lobe1), lobe_vertex(ct.s, ct.lobe2)};
    out.pairs.push_back(p);
  }
  lap("dim 2: merges (sequential)");
  // each maximum's last tetrahedron ranks its 14 neighbours: in parallel, after the merges
  tbb::parallel_for(first, out.pairs.size(), [&](std::size_t i) {
    out.pairs[i].death_simplex = last_tet(out.pairs[i].death_vertex);
  });
  lap("dim 2: last tetrahedra (parallel)");
  std::reverse(deaths1_.begin(), deaths1_.end());  // ascending filtration order
  deaths1_.shrink_to_fit();  // kept through the parallel pass of dim 1
}

void Engine::finish(PersistenceDiagram& out, std::size_t end0, std::size_t end2) {
  const Id gmin = global_min_;
  PersistencePair e;
  e.dim = 0;
  e.birth = f_[gmin];
  e.death = std::numeric_limits<float>::infinity();
  e.birth_simplex = e.birth_vertex = gmin;
  out.essential.push_back(e);
  // Discovery order is deterministic (saddles in filtration order); the pairs came as dims 0, 2, 1, each
  // block in its own order: grouped by dimension in place (a stable sort would copy the whole diagram).
  std::rotate(out.pairs.begin() + std::ptrdiff_t(end0), out.pairs.begin() + std::ptrdiff_t(end2), out.pairs.end());
}

}  // namespace detail

PersistenceDiagram lower_star_persistence(const ScalarGrid& grid, const ProgressFn& progress,
                                          std::size_t max_memory) {
  validate_grid(grid);
  detail::Engine engine(grid, progress, max_memory ? max_memory : default_max_memory());
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

// Dimension 1 of the lower-star persistence engine (see persistence.cpp for the whole): the edges left by
// dim 0 and the triangles left by dim 2 are paired by reducing only the boundaries of those triangles.
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <deque>
#include <queue>
#include <stdexcept>
#include <string>

#include "persistence_engine.h"

namespace chokeloops::detail {

const LowerLinkInfo& Engine::lower_link(Id v) {
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
  push(make_edge(v, v + delta_[target]));
  for (int b = target; prev[b] >= 0; b = prev[b]) push(make_edge(v + delta_[b], v + delta_[prev[b]]));
}

template <class Heap>
bool Engine::pop_to_birth_pivot(Heap& heap, EdgeKey& p) {
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

template <class Heap>
void Engine::drain(Heap& heap, const EdgeKey& pivot, std::vector<EdgeKey>& out) {
  out.push_back(pivot);
  while (!heap.empty()) {
    EdgeKey q = heap.top();
    heap.pop();
    bool odd = true;
    while (!heap.empty() && heap.top() == q) { heap.pop(); odd = !odd; }
    if (odd) out.push_back(q);
  }
}

void Engine::dim1(PersistenceDiagram& out) {
  if (births1_ != deaths1_.size())
    throw InternalError("dim-1 births and deaths do not balance (" + std::to_string(births1_) + " vs " +
                           std::to_string(deaths1_.size()) + ")");
  link_index_.assign(V_, kOutside);
  auto heap_less = [this](const EdgeKey& a, const EdgeKey& b) { return edge_less(a, b); };
  using Heap = std::priority_queue<EdgeKey, std::vector<EdgeKey>, decltype(heap_less)>;
  // In parallel: each death triangle's boundary up to its first birth pivot, which needs no other column.
  // Most columns end there (their pivot is not owned yet); the rest continue below in filtration order.
  // This part is order-free, so it runs in grid order: neighbouring triangles share lower links and
  // field memory, which the filtration order scatters.
  const std::size_t n = deaths1_.size();
  std::vector<std::uint32_t> grid_order(n);
  for (std::size_t i = 0; i < n; ++i) grid_order[i] = std::uint32_t(i);
  tbb::parallel_sort(grid_order.begin(), grid_order.end(), [this](std::uint32_t a, std::uint32_t b) {
    return deaths1_[a].v[0] < deaths1_[b].v[0] || (deaths1_[a].v[0] == deaths1_[b].v[0] && a < b);
  });
  struct Where { std::uint32_t chunk, begin, end; };
  std::vector<Where> where(n);
  const std::size_t chunk = 2048, nchunks = (n + chunk - 1) / chunk;
  std::vector<std::vector<EdgeKey>> first(nchunks);
  tbb::parallel_for(std::size_t(0), nchunks, [&](std::size_t c) {
    Heap heap(heap_less);
    std::vector<EdgeKey>& entries = first[c];
    for (std::size_t k = c * chunk; k < std::min(n, (c + 1) * chunk); ++k) {
      const std::uint32_t i = grid_order[k];
      const auto& tau = deaths1_[i].v;
      heap.push(make_edge(tau[0], tau[1]));
      heap.push(make_edge(tau[0], tau[2]));
      heap.push(make_edge(tau[1], tau[2]));
      where[i].chunk = std::uint32_t(c);
      where[i].begin = std::uint32_t(entries.size());
      EdgeKey p;
      if (pop_to_birth_pivot(heap, p)) drain(heap, p, entries);
      where[i].end = std::uint32_t(entries.size());
    }
  });
  std::vector<std::uint32_t>().swap(grid_order);
  report("dim 1", 0.8);
  // In filtration order: a column whose pivot is owned adds the owner's column and goes on reducing.
  struct Span { const EdgeKey* begin; const EdgeKey* end; };
  std::vector<Span> owner(births1_, Span{nullptr, nullptr});
  std::deque<std::vector<EdgeKey>> continued;  // columns that needed additions (stable addresses)
  Heap heap(heap_less);
  for (std::size_t i = 0; i < n; ++i) {
    const Where& w = where[i];
    if (w.begin == w.end) throw InternalError("a dim-1 death triangle reduced to zero");
    Span column{first[w.chunk].data() + w.begin, first[w.chunk].data() + w.end};
    EdgeKey p = *column.begin;
    std::uint32_t r = birth_rank(p.hi, p.lo);
    if (owner[r].begin) {
      for (const EdgeKey* e = column.begin + 1; e != column.end; ++e) heap.push(*e);
      for (;;) {
        for (const EdgeKey* e = owner[r].begin + 1; e != owner[r].end; ++e) heap.push(*e);
        if (!pop_to_birth_pivot(heap, p)) throw InternalError("a dim-1 death triangle reduced to zero");
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

}  // namespace chokeloops::detail

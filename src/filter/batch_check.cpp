#include "batch_check.h"

#include <algorithm>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace chokeloops::detail {

// Two passes of union-find (each vertex joins its seven backward Freudenthal neighbours of its side), the
// first on z slabs in parallel, then the planes between slabs; a set's root is its smallest vertex, so the
// ids, given in scan order, do not depend on the slabs or the threads.
SideLabels label_sides(const ScalarGrid& grid) {
  const FreudenthalComplex cx(grid.dims);
  const Id n = cx.vertex_count();
  if (n >= Id(1) << 31) throw Error("filter: the grid has more than 2^31 vertices", 3);
  const auto& d = grid.dims;
  std::vector<std::int32_t> parent(static_cast<std::size_t>(n));
  auto find = [&](std::int32_t x) {
    while (parent[std::size_t(x)] != x) {
      parent[std::size_t(x)] = parent[std::size_t(parent[std::size_t(x)])];
      x = parent[std::size_t(x)];
    }
    return x;
  };
  auto unite = [&](std::int32_t a, std::int32_t b) {
    a = find(a), b = find(b);
    if (a == b) return;
    if (a < b) std::swap(a, b);
    parent[std::size_t(a)] = b;
  };
  auto inside = [&](Id v) { return grid.values[std::size_t(v)] <= 0; };
  // Backward neighbour m (mask 1..7): (i,j,k) - mask(m), when it lies in the box and at z >= z_lo. Two backward
  // neighbours whose masks nest are Freudenthal neighbours of each other, joined when the later of them was
  // visited: so after joining v - M, the masks inside M are skipped (within a slab; across its lowest plane
  // every one is joined, `only_dz`).
  auto join_backward = [&](int i, int j, int k, int z_lo, bool only_dz) {
    static constexpr int kOrder[7] = {7, 6, 5, 3, 4, 2, 1};
    const Id v = cx.vertex(i, j, k);
    const bool side = inside(v);
    int joined[7], n_joined = 0;
    for (int m : kOrder) {
      const int dx = m & 1, dy = (m >> 1) & 1, dz = (m >> 2) & 1;
      if (only_dz && !dz) continue;
      if (i < dx || j < dy || k - dz < z_lo) continue;
      const Id u = v - cx.offset(m);
      if (inside(u) != side) continue;
      bool nested = false;
      for (int q = 0; q < n_joined && !only_dz; ++q) nested = nested || (m & joined[q]) == m;
      if (nested) continue;
      unite(std::int32_t(v), std::int32_t(u));
      joined[n_joined++] = m;
    }
  };
  const int slabs = std::max(1, std::min(d[2] / 8, 64));
  auto slab_lo = [&](int s) { return int(std::int64_t(d[2]) * s / slabs); };
  tbb::parallel_for(0, slabs, [&](int s) {
    for (int k = slab_lo(s); k < slab_lo(s + 1); ++k)
      for (int j = 0; j < d[1]; ++j)
        for (int i = 0; i < d[0]; ++i) {
          const Id v = cx.vertex(i, j, k);
          parent[std::size_t(v)] = std::int32_t(v);
          join_backward(i, j, k, slab_lo(s), false);
        }
  });
  for (int s = 1; s < slabs; ++s)
    for (int j = 0; j < d[1]; ++j)
      for (int i = 0; i < d[0]; ++i) join_backward(i, j, slab_lo(s), 0, true);
  // Ids in scan order, in parallel: every vertex finds its root (the set's smallest vertex; `parent` is only
  // read now), the roots of each slab count their sides, and the counts' prefix sums number them.
  SideLabels out;
  out.label.resize(static_cast<std::size_t>(n));
  tbb::parallel_for(tbb::blocked_range<Id>(0, n, 1 << 16), [&](const tbb::blocked_range<Id>& r) {
    for (Id v = r.begin(); v != r.end(); ++v) {
      std::int32_t x = std::int32_t(v);
      while (parent[std::size_t(x)] != x) x = parent[std::size_t(x)];
      out.label[std::size_t(v)] = x;
    }
  });
  const Id plane = Id(d[0]) * d[1];
  std::vector<std::array<std::int32_t, 2>> roots(static_cast<std::size_t>(slabs) + 1, {0, 0});
  tbb::parallel_for(0, slabs, [&](int s) {
    for (Id v = slab_lo(s) * plane; v < slab_lo(s + 1) * plane; ++v)
      if (parent[std::size_t(v)] == v) ++roots[std::size_t(s) + 1][inside(v) ? 0 : 1];
  });
  for (int s = 0; s < slabs; ++s)
    for (int side = 0; side < 2; ++side) roots[std::size_t(s) + 1][side] += roots[std::size_t(s)][side];
  tbb::parallel_for(0, slabs, [&](int s) {
    std::array<std::int32_t, 2> next = roots[std::size_t(s)];
    for (Id v = slab_lo(s) * plane; v < slab_lo(s + 1) * plane; ++v)
      if (parent[std::size_t(v)] == v) out.label[std::size_t(v)] = next[inside(v) ? 0 : 1]++;
  });
  tbb::parallel_for(tbb::blocked_range<Id>(0, n, 1 << 16), [&](const tbb::blocked_range<Id>& r) {
    for (Id v = r.begin(); v != r.end(); ++v)
      if (parent[std::size_t(v)] != v) out.label[std::size_t(v)] = out.label[std::size_t(out.label[std::size_t(v)])];
  });
  const std::int32_t next_inside = roots[std::size_t(slabs)][0];
  out.outside_reaches_border.assign(std::size_t(roots[std::size_t(slabs)][1]), 0);
  // The border: whole rows on the box's outer planes, the two ends of every other row.
  for (int k = 0; k < d[2]; ++k)
    for (int j = 0; j < d[1]; ++j) {
      const bool whole_row = k == 0 || j == 0 || k == d[2] - 1 || j == d[1] - 1;
      for (int i = 0; i < d[0]; i += whole_row ? 1 : d[0] - 1) {
        const Id v = cx.vertex(i, j, k);
        if (!inside(v)) out.outside_reaches_border[std::size_t(out.label[std::size_t(v)])] = 1;
      }
    }
  out.inside_components = next_inside;
  for (char b : out.outside_reaches_border) out.cavities += b ? 0 : 1;
  return out;
}

namespace {

// What judging a group needs from its surroundings: the vertices of each side around it, before and after the
// batch, and its local change of the Euler characteristic.
struct Surroundings {
  std::vector<Id> vertices[2][2];  // [before/after][inside/outside]: the group's vertices and their neighbours
  bool on_border = false;
  int euler_change = 0;
};

Surroundings look_around(const ScalarGrid& grid, const FreudenthalComplex& cx, const std::vector<Id>& group,
                         const SideChanges& changes) {
  Surroundings s;
  auto inside_after = [&](Id u) { return grid.values[std::size_t(u)] <= 0; };
  auto inside_before = [&](Id u) {
    const auto it = changes.find(u);
    return it != changes.end() ? it->second : inside_after(u);
  };
  const auto& link = freudenthal::vertex_link();
  for (Id v : group) {
    const auto c = cx.coords(v);
    s.on_border = s.on_border || !cx.inside(c[0] - 1, c[1] - 1, c[2] - 1) || !cx.inside(c[0] + 1, c[1] + 1, c[2] + 1);
    std::array<Id, 14> nb;
    for (int k = 0; k < 14; ++k) nb[std::size_t(k)] = cx.neighbor_inside(c, k) ? v + cx.neighbor_delta(k) : -1;
    auto look = [&](Id u) {
      s.vertices[0][inside_before(u) ? 0 : 1].push_back(u);
      s.vertices[1][inside_after(u) ? 0 : 1].push_back(u);
    };
    look(v);
    for (Id u : nb)
      if (u >= 0) look(u);
    // chi = V - E + F - T over the solid's simplices; a simplex with several changed vertices is counted at
    // its smallest one.
    auto here = [&](Id u) { return u >= 0 && !(u < v && changes.count(u)); };
    auto change = [&](std::initializer_list<Id> vs) {
      bool b = true, a = true;
      for (Id u : vs) b = b && inside_before(u), a = a && inside_after(u);
      return int(a) - int(b);
    };
    s.euler_change += change({v});
    for (Id u : nb)
      if (here(u)) s.euler_change -= change({v, u});
    for (const auto& e : link.edges) {
      const Id a = nb[std::size_t(e[0])], b = nb[std::size_t(e[1])];
      if (here(a) && here(b)) s.euler_change += change({v, a, b});
    }
    for (const auto& t : link.triangles) {
      const Id a = nb[std::size_t(t[0])], b = nb[std::size_t(t[1])], c3 = nb[std::size_t(t[2])];
      if (here(a) && here(b) && here(c3)) s.euler_change -= change({v, a, b, c3});
    }
  }
  for (auto& when : s.vertices)
    for (auto& side : when) {
      std::sort(side.begin(), side.end());
      side.erase(std::unique(side.begin(), side.end()), side.end());
    }
  return s;
}

// Whether `targets` (non-empty, all of one side: `same_side` true on them) are joined by Freudenthal edges
// through vertices of their side, searched within the box of the targets grown by `margin` voxels: Yes when the
// search from the first target reaches them all; No when a search (from the first, or from a target it missed)
// goes round its whole component without leaving the box and without the others (a split); else Unknown.
enum class Joined { Yes, No, Unknown };
template <class SameSide>
Joined joined_in_box(const FreudenthalComplex& cx, const std::vector<Id>& targets, SameSide same_side, int margin) {
  const auto& d = cx.dims();
  std::array<int, 3> lo{d[0], d[1], d[2]}, hi{-1, -1, -1};
  for (Id v : targets) {
    const auto c = cx.coords(v);
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], c[a]), hi[a] = std::max(hi[a], c[a]);
  }
  std::array<int, 3> size;
  for (int a = 0; a < 3; ++a) {
    lo[a] = std::max(0, lo[a] - margin), hi[a] = std::min(d[a] - 1, hi[a] + margin);
    size[a] = hi[a] - lo[a] + 1;
  }
  auto local = [&](const std::array<int, 3>& c) {
    return (std::size_t(c[2] - lo[2]) * std::size_t(size[1]) + std::size_t(c[1] - lo[1])) * std::size_t(size[0]) +
           std::size_t(c[0] - lo[0]);
  };
  enum : char { kUnseen = 0, kTarget = 1, kFirst = 2, kSecond = 3 };
  std::vector<char> state(std::size_t(size[0]) * std::size_t(size[1]) * std::size_t(size[2]), kUnseen);
  for (Id v : targets) state[local(cx.coords(v))] = kTarget;
  // One search, marking what it reaches `mark`; how many targets it reached, whether it met a vertex marked
  // `meets` and whether it was stopped by the box.
  struct Reach {
    std::size_t targets = 0;
    bool met = false, clipped = false;
  };
  std::vector<Id> queue;
  auto search = [&](Id from, char mark, char meets) {
    Reach r;
    queue.assign(1, from);
    state[local(cx.coords(from))] = mark;
    r.targets = 1;
    for (std::size_t q = 0; q < queue.size() && r.targets < targets.size(); ++q) {
      const Id v = queue[q];
      const auto c = cx.coords(v);
      for (int k = 0; k < 14; ++k) {
        const auto o = freudenthal::neighbor_offset(k);
        const std::array<int, 3> n{c[0] + o[0], c[1] + o[1], c[2] + o[2]};
        const bool in_grid = n[0] >= 0 && n[1] >= 0 && n[2] >= 0 && n[0] < d[0] && n[1] < d[1] && n[2] < d[2];
        if (!in_grid) continue;
        const Id u = v + cx.neighbor_delta(k);
        if (n[0] < lo[0] || n[1] < lo[1] || n[2] < lo[2] || n[0] > hi[0] || n[1] > hi[1] || n[2] > hi[2]) {
          r.clipped = r.clipped || same_side(u);
          continue;
        }
        char& st = state[local(n)];
        if (st == mark) continue;
        if (st == meets && meets != kUnseen) {
          r.met = true;
          continue;
        }
        if (!same_side(u)) continue;
        if (st == kTarget) ++r.targets;
        st = mark;
        queue.push_back(u);
      }
    }
    return r;
  };
  const Reach first = search(targets.front(), kFirst, kUnseen);
  if (first.targets == targets.size()) return Joined::Yes;
  if (!first.clipped) return Joined::No;
  for (Id t : targets)
    if (state[local(cx.coords(t))] == kTarget) {
      const Reach other = search(t, kSecond, kFirst);
      return !other.clipped && !other.met ? Joined::No : Joined::Unknown;
    }
  return Joined::Unknown;
}

}  // namespace

GroupVerdict judge_group(const ScalarGrid& grid, const FreudenthalComplex& cx, const std::vector<Id>& group,
                         const SideChanges& changes, const SideLabels& before, const SideLabels& after) {
  const Surroundings s = look_around(grid, cx, group, changes);
  GroupVerdict verdict;
  verdict.on_border = s.on_border;
  verdict.euler_change = s.euler_change;
  // One label per side each time keeps b0 and b2.
  auto one_label = [](const std::vector<Id>& vs, const SideLabels& labels) {
    if (vs.empty()) return false;
    for (Id u : vs)
      if (labels.label[std::size_t(u)] != labels.label[std::size_t(vs.front())]) return false;
    return true;
  };
  verdict.keeps_components = one_label(s.vertices[0][0], before) && one_label(s.vertices[1][0], after);
  verdict.keeps_cavities = one_label(s.vertices[0][1], before) && one_label(s.vertices[1][1], after);
  return verdict;
}


LocalVerdict judge_group_locally(const ScalarGrid& grid, const FreudenthalComplex& cx, const std::vector<Id>& group,
                                 const SideChanges& changes) {
  const Surroundings s = look_around(grid, cx, group, changes);
  LocalVerdict out;
  out.verdict.on_border = s.on_border;
  out.verdict.euler_change = s.euler_change;
  auto inside_after = [&](Id u) { return grid.values[std::size_t(u)] <= 0; };
  auto inside_before = [&](Id u) {
    const auto it = changes.find(u);
    return it != changes.end() ? it->second : inside_after(u);
  };
  // Each of the four sets joined within a small box, else a larger one; an empty set (no vertex of that side
  // around the group) fails at once.
  bool joined[2][2];
  for (int when = 0; when < 2; ++when)
    for (int side = 0; side < 2; ++side) {
      const std::vector<Id>& vs = s.vertices[when][side];
      bool& j = joined[when][side];
      j = vs.size() == 1;
      if (vs.empty() || j) continue;  // empty fails, as in judge_group: no label at all
      auto same = [&](Id u) {
        const bool in = when == 0 ? inside_before(u) : inside_after(u);
        return in == (side == 0);
      };
      Joined verdict = Joined::Unknown;
      for (int margin : {2, 6, 16, 40})
        if (verdict == Joined::Unknown) verdict = joined_in_box(cx, vs, same, margin);
      if (verdict == Joined::Unknown) return out;  // not settled here
      j = verdict == Joined::Yes;
    }
  out.decided = true;
  out.verdict.keeps_components = joined[0][0] && joined[1][0];
  out.verdict.keeps_cavities = joined[0][1] && joined[1][1];
  return out;
}

}  // namespace chokeloops::detail

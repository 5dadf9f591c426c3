// Linking numbers by projection crossings, and a generator's own cycle by a two-sided breadth-first search.
#include "chokeloops/loops/linking.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <memory>
#include <queue>
#include <string>
#include <vector>

#include "chokeloops/topology/complex.h"

namespace chokeloops {

namespace {

struct Projected { double x, y, h; };

// Sum over the crossings of the two projected polylines of (+1 when `a` passes over `b`, -1 under) times
// the crossing's orientation: twice the linking number. nullopt when a crossing is degenerate in this view.
std::optional<long> crossing_sum(const std::vector<Projected>& a, const std::vector<Projected>& b) {
  const std::size_t na = a.size(), nb = b.size();
  double x0 = 1e300, y0 = 1e300, x1 = -1e300, y1 = -1e300;
  for (const auto& p : b) x0 = std::min(x0, p.x), y0 = std::min(y0, p.y), x1 = std::max(x1, p.x), y1 = std::max(y1, p.y);
  const double span = std::max({x1 - x0, y1 - y0, 1e-300});
  // A uniform grid of b's segments: each crossing is counted in the one cell that holds its point.
  const int k = std::clamp(int(std::sqrt(double(nb))), 1, 1024);
  const double cell = span / k * (1 + 1e-9);
  auto cell_of = [&](double v, double origin) { return std::clamp(int(std::floor((v - origin) / cell)), 0, k - 1); };
  std::vector<std::vector<std::uint32_t>> bins(std::size_t(k) * k);
  for (std::size_t j = 0; j < nb; ++j) {
    const auto &p = b[j], &q = b[(j + 1) % nb];
    for (int cy = cell_of(std::min(p.y, q.y), y0); cy <= cell_of(std::max(p.y, q.y), y0); ++cy)
      for (int cx = cell_of(std::min(p.x, q.x), x0); cx <= cell_of(std::max(p.x, q.x), x0); ++cx)
        bins[std::size_t(cy) * k + cx].push_back(std::uint32_t(j));
  }
  constexpr double eps = 1e-9;
  long sum = 0;
  for (std::size_t i = 0; i < na; ++i) {
    const auto &p = a[i], &p2 = a[(i + 1) % na];
    if (std::max(p.x, p2.x) < x0 || std::min(p.x, p2.x) > x1 || std::max(p.y, p2.y) < y0 || std::min(p.y, p2.y) > y1) continue;
    const double rx = p2.x - p.x, ry = p2.y - p.y;
    for (int cy = cell_of(std::min(p.y, p2.y), y0); cy <= cell_of(std::max(p.y, p2.y), y0); ++cy)
      for (int cx = cell_of(std::min(p.x, p2.x), x0); cx <= cell_of(std::max(p.x, p2.x), x0); ++cx)
        for (std::uint32_t j : bins[std::size_t(cy) * k + cx]) {
          const auto &q = b[j], &q2 = b[(j + 1) % nb];
          const double sx = q2.x - q.x, sy = q2.y - q.y;
          const double denom = rx * sy - ry * sx;
          const double wx = q.x - p.x, wy = q.y - p.y;
          const double scale = std::sqrt((rx * rx + ry * ry) * (sx * sx + sy * sy));
          if (std::abs(denom) <= eps * scale) {
            // Parallel in the view: degenerate only if the two segments overlap on one line.
            if (std::abs(wx * ry - wy * rx) <= eps * (std::abs(wx) + std::abs(wy) + 1e-300) * std::sqrt(rx * rx + ry * ry) + 1e-300) {
              const double len2 = rx * rx + ry * ry;
              const double t0 = (wx * rx + wy * ry) / len2, t1 = ((q2.x - p.x) * rx + (q2.y - p.y) * ry) / len2;
              if (std::max(t0, t1) >= -eps && std::min(t0, t1) <= 1 + eps) return std::nullopt;
            }
            continue;
          }
          const double t = (wx * sy - wy * sx) / denom, s = (wx * ry - wy * rx) / denom;
          if (t < -eps || t > 1 + eps || s < -eps || s > 1 + eps) continue;
          if (t < eps || t > 1 - eps || s < eps || s > 1 - eps) return std::nullopt;  // through a vertex
          const double ix = p.x + t * rx, iy = p.y + t * ry;
          if (cell_of(ix, x0) != cx || cell_of(iy, y0) != cy) continue;  // counted in its own cell
          const double ha = p.h + t * (p2.h - p.h), hb = q.h + s * (q2.h - q.h);
          if (std::abs(ha - hb) <= 1e-9 * span) return std::nullopt;  // the curves (nearly) meet
          sum += (ha > hb ? 1 : -1) * (denom > 0 ? 1 : -1);
        }
  }
  return sum;
}

}  // namespace

std::optional<int> linking_number(const Polyline3& a, const Polyline3& b) {
  if (a.size() < 3 || b.size() < 3) return 0;
  // Generic directions, tried in turn until no crossing is degenerate.
  static const double dirs[4][3] = {{0.5712, 0.4233, 0.7033}, {-0.3107, 0.8422, 0.4407}, {0.7741, -0.2213, 0.5930},
                                    {0.1379, 0.2917, -0.9465}};
  for (const auto& d0 : dirs) {
    const double dn = std::sqrt(d0[0] * d0[0] + d0[1] * d0[1] + d0[2] * d0[2]);
    const double d[3] = {d0[0] / dn, d0[1] / dn, d0[2] / dn};
    // u, w: an orthonormal basis of the view plane (u x w = d, so crossings keep one orientation).
    double u[3] = {d[1], -d[0], 0};
    const double un = std::hypot(u[0], u[1]);
    u[0] /= un, u[1] /= un;
    const double w[3] = {d[1] * u[2] - d[2] * u[1], d[2] * u[0] - d[0] * u[2], d[0] * u[1] - d[1] * u[0]};
    auto project = [&](const Polyline3& c) {
      std::vector<Projected> out(c.size());
      for (std::size_t i = 0; i < c.size(); ++i) {
        const auto& p = c[i];
        out[i] = {p[0] * u[0] + p[1] * u[1] + p[2] * u[2], p[0] * w[0] + p[1] * w[1] + p[2] * w[2],
                  p[0] * d[0] + p[1] * d[1] + p[2] * d[2]};
      }
      return out;
    };
    const auto sum = crossing_sum(project(a), project(b));
    if (sum && *sum % 2 == 0) return int(*sum / 2);
  }
  return std::nullopt;
}

namespace {

// Where a cycle leaves the grid (the persistence joins every border vertex of the outside through the
// outside of the box): from one border vertex radially out to a sphere around the box, along the sphere,
// and back in to the other. The whole detour is outside the box, where no loop goes.
void detour_outside(const ScalarGrid& grid, const std::array<double, 3>& from, const std::array<double, 3>& to, Polyline3& out) {
  std::array<double, 3> centre, half;
  for (int a = 0; a < 3; ++a) {
    half[a] = 0.5 * grid.h(a) * (grid.dims[a] - 1);
    centre[a] = grid.origin[a] + half[a];
  }
  const double radius = 2 * std::sqrt(half[0] * half[0] + half[1] * half[1] + half[2] * half[2]) + grid.voxel_size;
  auto direction = [&](const std::array<double, 3>& p) {
    std::array<double, 3> d{p[0] - centre[0], p[1] - centre[1], p[2] - centre[2]};
    double n = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    if (n == 0) d = {1, 0, 0}, n = 1;
    return std::array<double, 3>{d[0] / n, d[1] / n, d[2] / n};
  };
  auto on_sphere = [&](const std::array<double, 3>& d) {
    out.push_back({centre[0] + radius * d[0], centre[1] + radius * d[1], centre[2] + radius * d[2]});
  };
  auto arc = [&](const std::array<double, 3>& a, const std::array<double, 3>& b) {  // a, b not opposite
    const double cosine = std::clamp(a[0] * b[0] + a[1] * b[1] + a[2] * b[2], -1.0, 1.0);
    const double angle = std::acos(cosine);
    // Chords of at most 10 degrees stay outside the box (radius * cos 5 deg > the half diagonal).
    const int steps = std::max(1, int(std::ceil(angle / (10 * M_PI / 180))));
    for (int k = 1; k <= steps; ++k) {
      const double t = double(k) / steps;
      std::array<double, 3> d;
      for (int q = 0; q < 3; ++q) d[q] = (1 - t) * a[q] + t * b[q];
      const double n = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
      on_sphere({d[0] / n, d[1] / n, d[2] / n});
    }
  };
  const auto a = direction(from), b = direction(to);
  on_sphere(a);
  if (a[0] * b[0] + a[1] * b[1] + a[2] * b[2] < -0.5) {  // far apart: through a point between them
    std::array<double, 3> m{a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
    double n = std::sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
    if (n < 1e-9) {  // opposite: any direction square to a
      m = std::abs(a[0]) < 0.9 ? std::array<double, 3>{0, -a[2], a[1]} : std::array<double, 3>{-a[2], 0, a[0]};
      n = std::sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
    }
    for (auto& v : m) v /= n;
    arc(a, m);
    arc(m, b);
  } else {
    arc(a, b);
  }
}

}  // namespace

Polyline3 generator_cycle(const ScalarGrid& grid, const Choke& c) {
  if (c.kind != Kind::Generator || c.saddle < 0 || c.lobes[0] < -2 || c.lobes[1] < -2 || c.lobes[0] == -1 || c.lobes[1] == -1) return {};
  const FreudenthalComplex cx(grid.dims);
  const float* f = grid.values.data();
  const bool handle = c.side == Side::Handle;
  const Id s = c.saddle;
  // Strictly on the side: a path through a vertex on the level set could touch the loop.
  auto strict = [&](Id v) { return handle ? f[v] < 0 : f[v] > 0; };
  auto beyond = [&](Id v) { return (handle ? vertex_less(f, v, s) : vertex_less(f, s, v)) && strict(v); };
  // The outside of the grid is one node beyond every level, joined to every border vertex: the outside of
  // the solid goes on past the box (the persistence counts it so). Id kOut stands for it in paths.
  constexpr Id kOut = -2;
  auto on_border = [&](const std::array<int, 3>& p) {
    for (int a = 0; a < 3; ++a)
      if (p[a] == 0 || p[a] == grid.dims[a] - 1) return true;
    return false;
  };
  if (!strict(s)) return {};
  for (Id lobe : c.lobes)
    if (lobe == kOut ? handle : !beyond(lobe)) return {};

  // One mark per grid vertex, from calloc: pages are only touched where the search goes (a handle's core is
  // a thin tube; a tunnel's outside can be most of the grid). Per thread, reused; cleared after each search.
  struct Marks {
    std::unique_ptr<std::uint8_t, decltype(&std::free)> data{nullptr, &std::free};
    std::size_t size = 0;
  };
  static thread_local Marks marks;
  const std::size_t n = std::size_t(cx.vertex_count());
  if (marks.size != n) {
    marks.data.reset(static_cast<std::uint8_t*>(std::calloc(n, 1)));
    if (!marks.data) throw Error("out of memory for the marks of a generator's cycle (" + std::to_string(n) + " bytes): lower the resolution", 3);
    marks.size = n;
  }
  std::uint8_t* mark = marks.data.get();
  // mark: 0 unreached; else kSeen | side * 16 | code, code = 1 + the neighbour index it was reached by,
  // kRoot at a lobe.
  constexpr std::uint8_t kRoot = 15, kSeen = 0x80;
  int out_side = -1;  // the side that reached the outside node first
  Id out_parent = -1;  // and from which border vertex (-1: it is that side's lobe)
  std::vector<Id> touched;
  std::array<std::vector<Id>, 2> frontier;
  for (int side = 0; side < 2; ++side) {
    const Id lobe = c.lobes[side];
    if (lobe == kOut) {
      if (out_side >= 0) return {};
      out_side = side;
    } else {
      mark[lobe] = std::uint8_t(kSeen | side * 16 | kRoot);
      touched.push_back(lobe);
    }
    frontier[side].push_back(lobe);
  }
  auto side_of = [&](Id v) { return (mark[v] >> 4) & 1; };  // of a marked grid vertex
  auto chain = [&](Id v) {  // from v back to its root
    std::vector<Id> out{v};
    for (;;) {
      if (v == kOut) {
        if (out_parent < 0) break;
        v = out_parent;
      } else {
        const int code = mark[v] & 15;
        if (code == kRoot) break;
        v -= cx.neighbor_delta(code - 1);
      }
      out.push_back(v);
    }
    return out;
  };
  std::vector<Id> path;
  auto meet = [&](int side, Id x, Id u) {  // x reached by `side`, u by the other
    std::vector<Id> from_x = chain(x), from_u = chain(u);
    std::vector<Id>& to0 = side == 0 ? from_x : from_u;
    std::vector<Id>& to1 = side == 0 ? from_u : from_x;
    path.assign(to0.rbegin(), to0.rend());
    path.insert(path.end(), to1.begin(), to1.end());
  };
  // Marks x's unmarked neighbours beyond the level as reached by `side` (each then handed to `reached`), and
  // meets the other side at the first neighbour it holds.
  auto expand = [&](int side, Id x, const std::array<int, 3>& xc, auto&& reached) {
    for (int nb = 0; nb < 14 && path.empty(); ++nb) {
      if (!cx.neighbor_inside(xc, nb)) continue;
      const Id u = x + cx.neighbor_delta(nb);
      if (mark[u] == 0) {
        if (!beyond(u)) continue;
        mark[u] = std::uint8_t(kSeen | side * 16 | (1 + nb));
        touched.push_back(u);
        reached(u);
      } else if (side_of(u) != side) {
        meet(side, x, u);
      }
    }
  };
  // A tunnel's two sides usually meet only past the grid, through the outside node: a breadth-first search
  // grew each into a ball reaching the border, then the outside node into the whole border (most of a
  // molecule's box, ~0.1 s a tunnel on maltoporin). Each side instead heads for the nearest border first
  // (best first, by distance to the border, ties by id: the same path on any thread count), and a side that
  // has reached it waits while the other still can move; neither is stopped, so a meeting inside the grid is
  // still found where there is one. The cycle is any in the generator's class, as before.
  if (!handle) {
    auto to_border = [&](Id v) {
      const auto p = cx.coords(v);
      int d = p[0];
      for (int a = 0; a < 3; ++a) d = std::min({d, p[a], grid.dims[a] - 1 - p[a]});
      return d;
    };
    using Open = std::priority_queue<std::pair<int, Id>, std::vector<std::pair<int, Id>>, std::greater<>>;
    std::array<Open, 2> open;
    for (int side = 0; side < 2; ++side)
      if (c.lobes[side] != kOut) open[side].push({to_border(c.lobes[side]), c.lobes[side]});
    int turn = 0;
    while (path.empty()) {
      int side = out_side >= 0 ? 1 - out_side : turn;
      turn ^= 1;
      // A side that has not reached the border and has nothing left to visit has walked its whole piece
      // without meeting the other: no cycle, whatever the other would still visit. (On the grey-matter map
      // at 128, 20 of 882 tunnel generators are such; the other side went on through the whole outside,
      // 15M vertices each, 40 s of the loop stage's CPU, to the same end.)
      if (open[side].empty() && c.lobes[side] != kOut && side != out_side) break;
      if (open[side].empty()) side = 1 - side;
      if (open[side].empty()) break;
      const Id x = open[side].top().second;
      open[side].pop();
      const auto xc = cx.coords(x);
      if (on_border(xc)) {
        if (out_side < 0) {
          out_side = side, out_parent = x;
        } else if (out_side != side) {
          meet(side, x, kOut);
          break;
        }
      }
      expand(side, x, xc, [&](Id u) { open[side].push({to_border(u), u}); });
    }
  }
  // A handle's sides meet inside the solid (its lobes are grid vertices): breadth first, the smaller
  // frontier growing.
  while (handle && path.empty() && !frontier[0].empty() && !frontier[1].empty()) {
    const int side = frontier[0].size() <= frontier[1].size() ? 0 : 1;
    std::vector<Id> next;
    for (Id x : frontier[side]) {
      expand(side, x, cx.coords(x), [&](Id u) { next.push_back(u); });
      if (!path.empty()) break;
    }
    frontier[side].swap(next);
  }
  for (Id v : touched) mark[v] = 0;
  if (path.empty()) return {};
  // saddle, lobe 0 ... lobe 1 (then back to the saddle); the outside node becomes a detour around the box.
  std::vector<Id> ids{s};
  ids.insert(ids.end(), path.begin(), path.end());
  Polyline3 cycle;
  cycle.reserve(ids.size() + 1);
  for (std::size_t k = 0; k < ids.size(); ++k) {
    if (ids[k] != kOut) {
      cycle.push_back(grid.world(cx.coords(ids[k])));
      continue;
    }
    const Id before = ids[(k + ids.size() - 1) % ids.size()], after = ids[(k + 1) % ids.size()];
    detour_outside(grid, grid.world(cx.coords(before)), grid.world(cx.coords(after)), cycle);
  }
  return cycle;
}

}  // namespace chokeloops

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

// Generic directions, tried in turn until no crossing is degenerate.
constexpr double kDirections[4][3] = {{0.5712, 0.4233, 0.7033}, {-0.3107, 0.8422, 0.4407}, {0.7741, -0.2213, 0.5930},
                                      {0.1379, 0.2917, -0.9465}};

// The view along direction `dir`: u, w span its plane (u x w = d, so crossings keep one orientation), d is
// the height.
struct ViewFrame {
  double u[3], w[3], d[3];
  explicit ViewFrame(int dir) {
    const double* d0 = kDirections[dir];
    const double dn = std::sqrt(d0[0] * d0[0] + d0[1] * d0[1] + d0[2] * d0[2]);
    for (int a = 0; a < 3; ++a) d[a] = d0[a] / dn;
    u[0] = d[1], u[1] = -d[0], u[2] = 0;
    const double un = std::hypot(u[0], u[1]);
    u[0] /= un, u[1] /= un;
    w[0] = d[1] * u[2] - d[2] * u[1], w[1] = d[2] * u[0] - d[0] * u[2], w[2] = d[0] * u[1] - d[1] * u[0];
  }
  LinkingCurve::Point project(const std::array<double, 3>& p) const {
    return {p[0] * u[0] + p[1] * u[1] + p[2] * u[2], p[0] * w[0] + p[1] * w[1] + p[2] * w[2], p[0] * d[0] + p[1] * d[1] + p[2] * d[2]};
  }
};

}  // namespace

LinkingCurve::LinkingCurve(const Polyline3& curve) : curve_(curve) {}
LinkingCurve::~LinkingCurve() = default;

const LinkingCurve::View& LinkingCurve::view(int dir) const {
  std::unique_ptr<View>& v = views_[std::size_t(dir)];
  if (v) return *v;
  v = std::make_unique<View>();
  const ViewFrame frame(dir);
  const std::size_t n = curve_.size();
  v->points.resize(n);
  for (std::size_t i = 0; i < n; ++i) v->points[i] = frame.project(curve_[i]);
  for (const Point& p : v->points)
    v->x0 = std::min(v->x0, p.x), v->y0 = std::min(v->y0, p.y), v->x1 = std::max(v->x1, p.x), v->y1 = std::max(v->y1, p.y);
  const double span = std::max({v->x1 - v->x0, v->y1 - v->y0, 1e-300});
  v->span = span;
  v->k = std::clamp(int(std::sqrt(double(n))), 1, 1024);
  v->cell = span / v->k * (1 + 1e-9);
  // Segments bucketed by the cells their boxes cover, in a counting pass (one array, not a vector per cell).
  const std::size_t cells = std::size_t(v->k) * std::size_t(v->k);
  v->start.assign(cells + 1, 0);
  auto for_cells = [&](std::size_t j, auto&& fn) {
    const Point &p = v->points[j], &q = v->points[(j + 1) % n];
    const int cx0 = v->cell_x(std::min(p.x, q.x)), cx1 = v->cell_x(std::max(p.x, q.x));
    const int cy0 = v->cell_y(std::min(p.y, q.y)), cy1 = v->cell_y(std::max(p.y, q.y));
    for (int cy = cy0; cy <= cy1; ++cy)
      for (int cx = cx0; cx <= cx1; ++cx) fn(std::size_t(cy) * std::size_t(v->k) + std::size_t(cx));
  };
  for (std::size_t j = 0; j < n; ++j) for_cells(j, [&](std::size_t c) { ++v->start[c + 1]; });
  for (std::size_t c = 0; c < cells; ++c) v->start[c + 1] += v->start[c];
  v->segments.resize(v->start[cells]);
  std::vector<std::uint32_t> fill(v->start.begin(), v->start.end() - 1);
  for (std::size_t j = 0; j < n; ++j) for_cells(j, [&](std::size_t c) { v->segments[fill[c]++] = std::uint32_t(j); });
  return *v;
}

std::optional<long> LinkingCurve::crossing_sum(const View& a, const std::vector<Point>& b) const {
  // Sum over the crossings of the two projected polylines of (+1 when this curve passes over `b`, -1 under)
  // times the crossing's orientation: twice the linking number. nullopt when a crossing is degenerate in
  // this view. Each pair of segments whose boxes share cells is met once per shared cell and counted in the
  // first of them (the lowest row, then column, of the two cell ranges' overlap).
  const std::size_t na = a.points.size(), nb = b.size();
  const double span = a.span;
  constexpr double eps = 1e-9;
  long sum = 0;
  for (std::size_t i = 0; i < nb; ++i) {
    const Point &q = b[i], &q2 = b[(i + 1) % nb];
    if (std::max(q.x, q2.x) < a.x0 || std::min(q.x, q2.x) > a.x1 || std::max(q.y, q2.y) < a.y0 || std::min(q.y, q2.y) > a.y1) continue;
    const double sx = q2.x - q.x, sy = q2.y - q.y;
    const int bx0 = a.cell_x(std::min(q.x, q2.x)), bx1 = a.cell_x(std::max(q.x, q2.x));
    const int by0 = a.cell_y(std::min(q.y, q2.y)), by1 = a.cell_y(std::max(q.y, q2.y));
    for (int cy = by0; cy <= by1; ++cy)
      for (int cx = bx0; cx <= bx1; ++cx) {
        const std::size_t c = std::size_t(cy) * std::size_t(a.k) + std::size_t(cx);
        for (std::uint32_t s = a.start[c]; s < a.start[c + 1]; ++s) {
          const std::size_t j = a.segments[s];
          const Point &p = a.points[j], &p2 = a.points[(j + 1) % na];
          const double rx = p2.x - p.x, ry = p2.y - p.y;
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
          const double t = (wx * sy - wy * sx) / denom, u = (wx * ry - wy * rx) / denom;
          if (t < -eps || t > 1 + eps || u < -eps || u > 1 + eps) continue;
          if (t < eps || t > 1 - eps || u < eps || u > 1 - eps) return std::nullopt;  // through a vertex
          const int ax0 = a.cell_x(std::min(p.x, p2.x)), ay0 = a.cell_y(std::min(p.y, p2.y));
          if (cx != std::max(ax0, bx0) || cy != std::max(ay0, by0)) continue;  // counted in the first shared cell
          const double ha = p.h + t * (p2.h - p.h), hb = q.h + u * (q2.h - q.h);
          if (std::abs(ha - hb) <= 1e-9 * span) return std::nullopt;  // the curves (nearly) meet
          sum += (ha > hb ? 1 : -1) * (denom > 0 ? 1 : -1);
        }
      }
  }
  return sum;
}

std::optional<int> LinkingCurve::with(const Polyline3& other) const {
  if (curve_.size() < 3 || other.size() < 3) return 0;
  std::vector<Point> b(other.size());
  for (int dir = 0; dir < 4; ++dir) {
    const ViewFrame frame(dir);
    for (std::size_t i = 0; i < other.size(); ++i) b[i] = frame.project(other[i]);
    const auto sum = crossing_sum(view(dir), b);
    if (sum && *sum % 2 == 0) return int(*sum / 2);
  }
  return std::nullopt;
}

std::optional<int> linking_number(const Polyline3& a, const Polyline3& b) { return LinkingCurve(a).with(b); }

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

// Tunnels of molecules: exact bottlenecks, profiles, lining and cross-section loops (see channels.h).
#include "chokeloops/loops/channels.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <queue>
#include <unordered_map>

#include <Eigen/Dense>
#include <tbb/parallel_for.h>

#include "chokeloops/loops/shorten.h"
#include "chokeloops/surface/topology.h"
#include "plane_sections.h"

namespace chokeloops {

namespace {

using V3 = Eigen::Vector3d;
V3 v3(const std::array<double, 3>& a) { return V3(a[0], a[1], a[2]); }
std::array<double, 3> arr(const V3& v) { return {v[0], v[1], v[2]}; }

// Points x in the plane of c[0..2] with |x - c_i| - R_i = t for all three (Apollonius), as (x, t).
std::vector<std::pair<V3, double>> apollonius(const V3 c[3], const double R[3]) {
  std::vector<std::pair<V3, double>> out;
  V3 e1 = c[1] - c[0];
  const double d12 = e1.norm();
  if (d12 < 1e-9) return out;
  e1 /= d12;
  V3 w = c[2] - c[0];
  V3 e2 = w - w.dot(e1) * e1;
  const double n2 = e2.norm();
  if (n2 < 1e-6 * w.norm() || n2 < 1e-9) return out;  // collinear
  e2 /= n2;
  Eigen::Vector2d a2(d12, 0), a3(w.dot(e1), w.dot(e2));
  Eigen::Matrix2d M;
  M.row(0) = a2;
  M.row(1) = a3;
  // a_i . x = (|a_i|^2 - R_i^2 + R_0^2)/2 - t (R_i - R_0)
  Eigen::Vector2d b((a2.squaredNorm() - R[1] * R[1] + R[0] * R[0]) / 2, (a3.squaredNorm() - R[2] * R[2] + R[0] * R[0]) / 2);
  Eigen::Vector2d d(-(R[1] - R[0]), -(R[2] - R[0]));
  Eigen::Matrix2d Mi = M.inverse();
  Eigen::Vector2d P = Mi * b, Q = Mi * d;
  // |P + tQ|^2 = (R_0 + t)^2
  const double A = Q.squaredNorm() - 1, B = 2 * (P.dot(Q) - R[0]), C = P.squaredNorm() - R[0] * R[0];
  std::vector<double> ts;
  if (std::abs(A) < 1e-12) {
    if (std::abs(B) > 1e-12) ts.push_back(-C / B);
  } else {
    const double disc = B * B - 4 * A * C;
    if (disc >= 0) {
      const double s = std::sqrt(disc);
      ts.push_back((-B - s) / (2 * A));
      ts.push_back((-B + s) / (2 * A));
    }
  }
  for (double t : ts) {
    if (R[0] + t <= 0 || R[1] + t <= 0 || R[2] + t <= 0) continue;
    Eigen::Vector2d x = P + t * Q;
    out.push_back({c[0] + x[0] * e1 + x[1] * e2, t});
  }
  return out;
}

// 0 strictly inside the triangle of the unit directions from the three centres (in their plane).
bool surrounded(const V3& x, const V3 c[3]) {
  V3 u[3];
  for (int i = 0; i < 3; ++i) {
    u[i] = x - c[i];
    const double n = u[i].norm();
    if (n < 1e-12) return false;
    u[i] /= n;
  }
  V3 nrm = (c[1] - c[0]).cross(c[2] - c[0]);
  auto side = [&](const V3& a, const V3& b) { return (b - a).cross(-a).dot(nrm); };
  const double s0 = side(u[0], u[1]), s1 = side(u[1], u[2]), s2 = side(u[2], u[0]);
  // on the boundary counts: symmetric rings (a square of atoms) put the centre on an edge of every triple
  const double eps = 1e-9;
  return (s0 > -eps && s1 > -eps && s2 > -eps) || (s0 < eps && s1 < eps && s2 < eps);
}

struct HalfPath {
  std::vector<V3> path;  // from next to the bottleneck outwards
  bool open = false;
};

// Cheapest path (length / f^2) from next to the bottleneck to the bulk on one side of the disc.
HalfPath trace_side(const ScalarGrid& g, const V3& p, const V3& n, int sigma, double floor_value, double bulk, double disc) {
  HalfPath out;
  const double h = g.voxel_size;
  // The path only locates the channel (radii are exact on it): a lattice of about 0.4 Å is enough, and on
  // fine grids it visits 8 times fewer vertices.
  const int S = std::max(1, int(std::lround(0.4 / h)));
  auto world = [&](std::int64_t v) {
    const std::int64_t nx = g.dims[0], ny = g.dims[1];
    return V3(g.origin[0] + h * double(v % nx), g.origin[1] + h * double((v / nx) % ny), g.origin[2] + h * double(v / (nx * ny)));
  };
  auto allowed = [&](std::int64_t v) {
    if (g.values[std::size_t(v)] < floor_value) return false;
    V3 d = world(v) - p;
    const double along = d.dot(n) * sigma;
    if (along >= 0.5 * h) return true;
    return (d - d.dot(n) * n).norm() > disc;
  };
  V3 s = p + sigma * 1.0 * h * n;
  std::array<int, 3> ijk;
  for (int a = 0; a < 3; ++a) ijk[a] = std::clamp(int(std::lround((s[a] - g.origin[a]) / h)), 0, g.dims[a] - 1);
  // the start: the allowed vertex nearest s among its 5^3 neighbourhood
  std::int64_t start = -1;
  double best = 1e300;
  for (int dz = -2; dz <= 2; ++dz)
    for (int dy = -2; dy <= 2; ++dy)
      for (int dx = -2; dx <= 2; ++dx) {
        int q[3] = {ijk[0] + dx, ijk[1] + dy, ijk[2] + dz};
        bool in = true;
        for (int a = 0; a < 3; ++a) in &= q[a] >= 0 && q[a] < g.dims[a];
        if (!in) continue;
        std::int64_t v = g.index(q[0], q[1], q[2]);
        if (!allowed(v)) continue;
        double d = (world(v) - s).norm();
        if (d < best) best = d, start = v;
      }
  if (start < 0) return out;
  struct Node {
    double dist;
    std::int64_t prev;
    bool done;
  };
  std::unordered_map<std::int64_t, Node> nodes;
  using Item = std::pair<double, std::int64_t>;
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> pq;
  nodes[start] = {0, -1, false};
  pq.push({0, start});
  std::int64_t goal = -1, widest = start;
  const std::size_t kMaxVisited = 4000000;
  std::size_t visited = 0;
  while (!pq.empty()) {
    auto [d, v] = pq.top();
    pq.pop();
    Node& nv = nodes[v];
    if (nv.done || d > nv.dist) continue;
    nv.done = true;
    const float fv = g.values[std::size_t(v)];
    if (fv > g.values[std::size_t(widest)]) widest = v;
    const int i = int(v % g.dims[0]), j = int((v / g.dims[0]) % g.dims[1]), k = int(v / (std::int64_t(g.dims[0]) * g.dims[1]));
    if (fv >= bulk || i < S || j < S || k < S || i > g.dims[0] - 1 - S || j > g.dims[1] - 1 - S || k > g.dims[2] - 1 - S) {
      goal = v;
      out.open = true;
      break;
    }
    if (++visited > kMaxVisited) break;
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          if (!dx && !dy && !dz) continue;
          const std::int64_t w = g.index(i + S * dx, j + S * dy, k + S * dz);
          if (!allowed(w)) continue;
          const double fw = std::max(0.05, double(g.values[std::size_t(w)])), fm = std::max(0.05, double(fv));
          const double len = S * h * std::sqrt(double(dx * dx + dy * dy + dz * dz));
          const double nd = d + len * 0.5 * (1 / (fw * fw) + 1 / (fm * fm));
          auto it = nodes.find(w);
          if (it == nodes.end()) {
            nodes[w] = {nd, v, false};
            pq.push({nd, w});
          } else if (!it->second.done && nd < it->second.dist) {
            it->second = {nd, v, false};
            pq.push({nd, w});
          }
        }
  }
  if (goal < 0) goal = widest;
  for (std::int64_t v = goal; v >= 0; v = nodes[v].prev) out.path.push_back(world(v));
  std::reverse(out.path.begin(), out.path.end());
  return out;
}

void lining_at(const AtomLocator& vdw, const V3& q, double radius, double margin, std::map<int, double>& best) {
  for (int a : vdw.within(arr(q), radius + margin)) {
    const double d = (q - v3(vdw.centre(a))).norm() - vdw.radius(a);
    auto it = best.find(a);
    if (it == best.end() || d < it->second) best[a] = d;
  }
}

std::vector<LiningAtom> sorted_lining(const std::map<int, double>& m) {
  std::vector<LiningAtom> v;
  for (auto& [a, d] : m) v.push_back({a, d});
  std::sort(v.begin(), v.end(), [](const LiningAtom& x, const LiningAtom& y) {
    return x.distance != y.distance ? x.distance < y.distance : x.atom < y.atom;
  });
  return v;
}

}  // namespace

Loop section_loop(const Choke& choke, const Polyline3& section, const SurfaceMesh& surface, const MeshAdjacency& adjacency) {
  Loop loop;
  loop.choke = choke;
  loop.points = section;
  loop.found = true;
  loop.raw_length = closed_length(section);
  loop.note = "the surface's cross-section at the exact bottleneck";
  // A planar section of a bumpy lumen dips into every groove between atoms; shortening within a band of a
  // few edge rings (and 2 Å) pulls it over the atoms while it stays in the pore.
  try {
    ShortenOptions so;
    so.max_move = 2.0;
    ShortenResult s = shorten_polyline(surface, adjacency, section, so);
    loop.edge_path = s.edge_path;
    if (s.rings > 0 && !s.points.empty() && s.length < loop.raw_length) {
      loop.points = s.points;
      loop.note += ", shortened";
    }
  } catch (const std::exception&) {
    try {
      loop.edge_path = snap_polyline_to_edge_path(surface, adjacency, section);
    } catch (const std::exception&) {
      loop.edge_path.clear();
    }
  }
  describe_loop(loop);
  return loop;
}

bool refine_bottleneck(const AtomLocator& locator, const std::array<double, 3>& x0, double search_radius, Channel& out) {
  const double f0 = locator.distance(x0);
  std::vector<int> near = locator.within(x0, std::max(0.0, f0) + search_radius + 0.5);
  std::sort(near.begin(), near.end(), [&](int a, int b) {
    const double da = (v3(x0) - v3(locator.centre(a))).norm() - locator.radius(a);
    const double db = (v3(x0) - v3(locator.centre(b))).norm() - locator.radius(b);
    return da != db ? da < db : a < b;
  });
  if (near.size() > 20) near.resize(20);
  double best = search_radius;
  bool found = false;
  for (std::size_t a = 0; a < near.size(); ++a)
    for (std::size_t b = a + 1; b < near.size(); ++b)
      for (std::size_t c = b + 1; c < near.size(); ++c) {
        const int id[3] = {near[a], near[b], near[c]};
        V3 C[3];
        double R[3];
        for (int i = 0; i < 3; ++i) C[i] = v3(locator.centre(id[i])), R[i] = locator.radius(id[i]);
        for (auto& [x, t] : apollonius(C, R)) {
          const double shift = (x - v3(x0)).norm();
          if (shift >= best || !surrounded(x, C)) continue;
          if (locator.distance(arr(x)) < t - 1e-7) continue;  // another sphere is nearer: not this triple's point
          best = shift;
          found = true;
          out.bottleneck = arr(x);
          out.bottleneck_radius = t;
          V3 n = (C[1] - C[0]).cross(C[2] - C[0]).normalized();
          int big = 0;
          for (int k = 1; k < 3; ++k)
            if (std::abs(n[k]) > std::abs(n[big])) big = k;
          if (n[big] < 0) n = -n;
          out.axis = arr(n);
          std::array<int, 3> s = {id[0], id[1], id[2]};
          std::sort(s.begin(), s.end());
          out.atoms = s;
        }
      }
  out.refined = found;
  return found;
}


namespace {
// On a bumpy wall with gaps between atoms the plane normal to the axis can leak out through a gap; planes
// tilted up to 40 degrees are tried too and the shortest closed curve around the bottleneck is kept.
Polyline3 best_section(const SurfaceMesh& surface, const detail::FaceCells& cells, const V3& p, const V3& axis, double rb) {
  const double R = rb + 3.5;
  std::vector<int> faces = cells.near(surface, arr(p), R + 1);
  V3 e1 = std::abs(axis[0]) < 0.9 ? V3(1, 0, 0) : V3(0, 1, 0);
  e1 = (e1 - e1.dot(axis) * axis).normalized();
  const V3 e2 = axis.cross(e1);
  Polyline3 best;
  double best_len = 1e300;
  for (int tilt = 0; tilt <= 30; tilt += 15)
    for (int k = 0; k < (tilt ? 6 : 1); ++k) {
      const double t = tilt * M_PI / 180, ph = k * M_PI / 3;
      const V3 n = std::cos(t) * axis + std::sin(t) * (std::cos(ph) * e1 + std::sin(ph) * e2);
      Polyline3 sec = detail::section_of(surface, faces, arr(p), arr(n), R);
      if (sec.empty()) continue;
      const double len = closed_length(sec);
      if (len < best_len) best_len = len, best = std::move(sec);
      if (tilt == 0) return best;
    }
  return best;
}
}  // namespace

namespace {
std::string narrower_note(double min_radius) {
  char buf[120];
  std::snprintf(buf, sizeof buf, "narrower than --min-radius %g A: no probe passes; not traced", min_radius);
  return buf;
}
}  // namespace

std::vector<Channel> analyze_channels(const ScalarGrid& grid, const SurfaceMesh& surface, const AtomLocator& locator,
                                      const AtomLocator& vdw, const std::vector<Choke>& chokes, const ChannelOptions& o) {
  std::vector<int> tunnel;
  for (std::size_t i = 0; i < chokes.size(); ++i)
    if (chokes[i].side == Side::Tunnel) tunnel.push_back(int(i));
  std::vector<Channel> out(tunnel.size());
  const double h = grid.voxel_size;
  const detail::FaceCells cells(surface, 2.0);
  tbb::parallel_for(std::size_t(0), tunnel.size(), [&](std::size_t t) {
    Channel& ch = out[t];
    const Choke& choke = chokes[std::size_t(tunnel[t])];
    ch.loop = tunnel[t];
    ch.grid_radius = choke.depth;
    const double search = std::max(o.search_radius, 3 * h);
    if (!refine_bottleneck(locator, choke.point, search, ch)) {
      ch.bottleneck = choke.point;
      ch.bottleneck_radius = locator.distance(choke.point);
      char buf[120];
      std::snprintf(buf, sizeof buf, "no exact bottleneck within %.2f A of the grid's choke; the grid's choke point is reported", search);
      ch.note = buf;
    }
    const V3 p = v3(ch.bottleneck), n = v3(ch.axis).normalized();
    const double rb = ch.bottleneck_radius;
    if (rb < o.min_radius) {
      std::map<int, double> at_bottleneck;
      lining_at(vdw, p, vdw.distance(arr(p)), o.lining_margin, at_bottleneck);
      ch.bottleneck_lining = sorted_lining(at_bottleneck);
      ch.traced = false;
      ch.note = narrower_note(o.min_radius) + (ch.note.empty() ? "" : "; " + ch.note);
      return;
    }
    const double floor_value = std::min(0.5 * ch.grid_radius, 0.5 * rb);
    const double bulk = std::max(o.bulk_radius, 1.5 * rb);
    const double disc = rb + 4.0;
    HalfPath sides[2];
    for (int s = 0; s < 2; ++s) sides[s] = trace_side(grid, p, n, s ? 1 : -1, floor_value, bulk, disc);
    std::vector<V3> path;
    for (auto it = sides[0].path.rbegin(); it != sides[0].path.rend(); ++it) path.push_back(*it);
    const std::size_t mid = path.size();
    path.push_back(p);
    for (auto& q : sides[1].path) path.push_back(q);
    // smooth the grid's staircase, keeping the ends and the bottleneck
    for (int it = 0; it < 4; ++it) {
      std::vector<V3> q = path;
      for (std::size_t i = 1; i + 1 < path.size(); ++i)
        if (i != mid) q[i] = 0.25 * path[i - 1] + 0.5 * path[i] + 0.25 * path[i + 1];
      path.swap(q);
    }
    std::vector<double> s(path.size(), 0);
    for (std::size_t i = mid + 1; i < path.size(); ++i) s[i] = s[i - 1] + (path[i] - path[i - 1]).norm();
    for (std::size_t i = mid; i-- > 0;) s[i] = s[i + 1] - (path[i + 1] - path[i]).norm();
    std::map<int, double> lining, at_bottleneck;
    for (std::size_t i = 0; i < path.size(); ++i) {
      const double r = i == mid ? rb : locator.distance(arr(path[i]));
      ch.profile.push_back({s[i], arr(path[i]), r});
      lining_at(vdw, path[i], vdw.distance(arr(path[i])), o.lining_margin, lining);
    }
    lining_at(vdw, p, vdw.distance(arr(p)), o.lining_margin, at_bottleneck);
    ch.lining = sorted_lining(lining);
    ch.bottleneck_lining = sorted_lining(at_bottleneck);
    ch.length = path.empty() ? 0 : s.back() - s.front();
    ch.open[0] = sides[0].open;
    ch.open[1] = sides[1].open;
    if (o.section_loops && ch.refined) {
      ch.section = best_section(surface, cells, p, n, rb);
      ch.section_length = ch.section.empty() ? 0 : closed_length(ch.section);
    }
  });
  return out;
}

}  // namespace chokeloops

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
Polyline3 section_of(const SurfaceMesh& surface, const std::vector<int>& faces, const std::array<double, 3>& pa,
                     const std::array<double, 3>& na, double max_radius) {
  const V3 p = v3(pa), n = v3(na).normalized();
  V3 e1 = std::abs(n[0]) < 0.9 ? V3(1, 0, 0) : V3(0, 1, 0);
  e1 = (e1 - e1.dot(n) * n).normalized();
  const V3 e2 = n.cross(e1);
  // crossing point on each cut mesh edge, keyed by its vertex pair; a segment per cut face. A hash map: a
  // plane across a large surface cuts tens of thousands of edges, and a tree's lookups were a tenth of
  // the pierced block's loop stage (ids follow the faces' order, so the hashing order never shows)
  std::unordered_map<std::uint64_t, int> point_id;
  point_id.reserve(faces.size());
  std::vector<V3> pts;
  std::vector<std::array<int, 2>> seg;
  auto sd = [&](int v) {
    double s = (v3(surface.vertices[std::size_t(v)]) - p).dot(n);
    return s == 0 ? 1e-300 : s;
  };
  auto cut = [&](int a, int b) {
    const int lo = std::min(a, b), hi = std::max(a, b);
    const auto [it, inserted] = point_id.try_emplace(std::uint64_t(std::uint32_t(lo)) << 32 | std::uint32_t(hi), int(pts.size()));
    if (!inserted) return it->second;
    const double sa = sd(lo), sb = sd(hi);
    const double t = sa / (sa - sb);
    pts.push_back(v3(surface.vertices[std::size_t(lo)]) * (1 - t) + v3(surface.vertices[std::size_t(hi)]) * t);
    return it->second;
  };
  for (int fi : faces) {
    const auto& f = surface.faces[std::size_t(fi)];
    const V3 a = v3(surface.vertices[std::size_t(f[0])]);
    if ((a - p).norm() > max_radius) continue;
    int crossing[2], m = 0;
    for (int e = 0; e < 3; ++e) {
      const int u = f[e], w = f[(e + 1) % 3];
      if ((sd(u) > 0) != (sd(w) > 0) && m < 2) crossing[m++] = cut(u, w);
    }
    if (m == 2) seg.push_back({crossing[0], crossing[1]});
  }
  std::vector<std::vector<int>> at(pts.size());
  for (std::size_t s = 0; s < seg.size(); ++s)
    for (int e : seg[s]) at[std::size_t(e)].push_back(int(s));
  std::vector<char> used(seg.size(), 0);
  Polyline3 best;
  double best_area = 1e300;
  for (std::size_t s0 = 0; s0 < seg.size(); ++s0) {
    if (used[s0]) continue;
    std::vector<int> cyc;
    bool closed = false;
    std::size_t s = s0;
    int cur = seg[s][0];
    for (;;) {
      used[s] = 1;
      cyc.push_back(cur);
      const int next = seg[s][0] == cur ? seg[s][1] : seg[s][0];
      if (at[std::size_t(next)].size() != 2) break;  // cut off by max_radius (or non-manifold)
      const int t = at[std::size_t(next)][0] == int(s) ? at[std::size_t(next)][1] : at[std::size_t(next)][0];
      cur = next;
      if (std::size_t(t) == s0) { closed = true; break; }
      if (used[std::size_t(t)]) break;
      s = std::size_t(t);
    }
    if (!closed || cyc.size() < 3) continue;
    // winding number of the curve around p and its area, in the plane
    double wind = 0, area = 0;
    for (std::size_t i = 0; i < cyc.size(); ++i) {
      const V3 a = pts[std::size_t(cyc[i])] - p, b = pts[std::size_t(cyc[(i + 1) % cyc.size()])] - p;
      const double ax = a.dot(e1), ay = a.dot(e2), bx = b.dot(e1), by = b.dot(e2);
      wind += std::atan2(ax * by - ay * bx, ax * bx + ay * by);
      area += ax * by - ay * bx;
    }
    if (std::abs(wind) < M_PI) continue;
    area = std::abs(area) / 2;
    if (area < best_area) {
      best_area = area;
      best.clear();
      for (int i : cyc) best.push_back(arr(pts[std::size_t(i)]));
    }
  }
  return best;
}

// Faces bucketed by their first vertex in cubic cells, so that each tunnel looks only at the faces near it.
class FaceCells {
 public:
  FaceCells(const SurfaceMesh& surface, double cell) : cell_(cell) {
    lo_ = {1e300, 1e300, 1e300};
    std::array<double, 3> hi{-1e300, -1e300, -1e300};
    for (auto& v : surface.vertices)
      for (int a = 0; a < 3; ++a) lo_[a] = std::min(lo_[a], v[a]), hi[a] = std::max(hi[a], v[a]);
    if (surface.vertices.empty()) lo_ = hi = {0, 0, 0};
    for (int a = 0; a < 3; ++a) n_[a] = std::max(1, int((hi[a] - lo_[a]) / cell_) + 1);
    std::vector<int> id(surface.faces.size());
    start_.assign(std::size_t(n_[0]) * n_[1] * n_[2] + 1, 0);
    for (std::size_t f = 0; f < surface.faces.size(); ++f) {
      id[f] = cell_of(surface.vertices[std::size_t(surface.faces[f][0])]);
      start_[std::size_t(id[f]) + 1]++;
    }
    for (std::size_t k = 1; k < start_.size(); ++k) start_[k] += start_[k - 1];
    items_.resize(surface.faces.size());
    std::vector<int> fill(start_.begin(), start_.end() - 1);
    for (std::size_t f = 0; f < surface.faces.size(); ++f) items_[std::size_t(fill[std::size_t(id[f])]++)] = int(f);
  }
  // Faces in the cells the plane (p, n) crosses within r of p (their first vertex is within r), in a fixed
  // order: a slab of cells instead of the ball's volume. Needs cells at least as wide as any face.
  std::vector<int> near_plane(const SurfaceMesh& surface, const std::array<double, 3>& p, const std::array<double, 3>& nrm,
                              double r) const {
    std::vector<int> out;
    int a = 0;
    for (int q = 1; q < 3; ++q)
      if (std::abs(nrm[q]) > std::abs(nrm[a])) a = q;
    const int u = (a + 1) % 3, v = (a + 2) % 3;
    int lo_i[3], hi_i[3];
    for (int q = 0; q < 3; ++q) {
      lo_i[q] = std::max(0, int(std::floor((p[q] - r - lo_[q]) / cell_)));
      hi_i[q] = std::min(n_[q] - 1, int(std::floor((p[q] + r - lo_[q]) / cell_)));
      if (lo_i[q] > hi_i[q]) return out;
    }
    const double r2 = r * r;
    for (int iu = lo_i[u]; iu <= hi_i[u]; ++iu)
      for (int iv = lo_i[v]; iv <= hi_i[v]; ++iv) {
        // The plane's height along axis a over this column's four corners.
        double amin = 1e300, amax = -1e300;
        for (int corner = 0; corner < 4; ++corner) {
          const double xu = lo_[u] + (iu + (corner & 1)) * cell_, xv = lo_[v] + (iv + (corner >> 1)) * cell_;
          const double xa = p[a] - (nrm[u] * (xu - p[u]) + nrm[v] * (xv - p[v])) / nrm[a];
          amin = std::min(amin, xa), amax = std::max(amax, xa);
        }
        const int ia0 = std::max(lo_i[a], int(std::floor((amin - lo_[a]) / cell_)) - 1);
        const int ia1 = std::min(hi_i[a], int(std::floor((amax - lo_[a]) / cell_)) + 1);
        for (int ia = ia0; ia <= ia1; ++ia) {
          int ijk[3];
          ijk[a] = ia, ijk[u] = iu, ijk[v] = iv;
          const std::size_t c = std::size_t(ijk[0] + n_[0] * (ijk[1] + n_[1] * ijk[2]));
          for (int t = start_[c]; t < start_[c + 1]; ++t) {
            const int f = items_[std::size_t(t)];
            const auto& w = surface.vertices[std::size_t(surface.faces[std::size_t(f)][0])];
            const double d2 = (w[0] - p[0]) * (w[0] - p[0]) + (w[1] - p[1]) * (w[1] - p[1]) + (w[2] - p[2]) * (w[2] - p[2]);
            if (d2 > r2) continue;
            // Only faces the plane cuts hold a piece of the section.
            int above = 0;
            for (int q = 0; q < 3; ++q) {
              const auto& x = surface.vertices[std::size_t(surface.faces[std::size_t(f)][q])];
              above += (x[0] - p[0]) * nrm[0] + (x[1] - p[1]) * nrm[1] + (x[2] - p[2]) * nrm[2] >= 0;  // as section_of counts 0
            }
            if (above == 1 || above == 2) out.push_back(f);
          }
        }
      }
    return out;
  }

  // faces whose first vertex is within r of p, in increasing order
  std::vector<int> near(const SurfaceMesh& surface, const std::array<double, 3>& p, double r) const {
    std::vector<int> out;
    int a0[3], a1[3];
    for (int a = 0; a < 3; ++a) {
      a0[a] = std::max(0, int(std::floor((p[a] - r - lo_[a]) / cell_)));
      a1[a] = std::min(n_[a] - 1, int(std::floor((p[a] + r - lo_[a]) / cell_)));
      if (a0[a] > a1[a]) return out;
    }
    for (int k = a0[2]; k <= a1[2]; ++k)
      for (int j = a0[1]; j <= a1[1]; ++j)
        for (int i = a0[0]; i <= a1[0]; ++i) {
          const std::size_t c = std::size_t(i + n_[0] * (j + n_[1] * k));
          for (int t = start_[c]; t < start_[c + 1]; ++t) {
            const int f = items_[std::size_t(t)];
            const auto& v = surface.vertices[std::size_t(surface.faces[std::size_t(f)][0])];
            const double d2 = (v[0] - p[0]) * (v[0] - p[0]) + (v[1] - p[1]) * (v[1] - p[1]) + (v[2] - p[2]) * (v[2] - p[2]);
            if (d2 <= r * r) out.push_back(f);
          }
        }
    std::sort(out.begin(), out.end());
    return out;
  }

 private:
  int cell_of(const std::array<double, 3>& v) const {
    int ijk[3];
    for (int a = 0; a < 3; ++a) ijk[a] = std::clamp(int((v[a] - lo_[a]) / cell_), 0, n_[a] - 1);
    return ijk[0] + n_[0] * (ijk[1] + n_[1] * ijk[2]);
  }
  double cell_;
  std::array<double, 3> lo_{};
  std::array<int, 3> n_{};
  std::vector<int> start_, items_;
};
}  // namespace

Polyline3 cross_section_loop(const SurfaceMesh& surface, const std::array<double, 3>& p, const std::array<double, 3>& n,
                             double max_radius) {
  return section_of(surface, FaceCells(surface, 2.0).near(surface, p, max_radius + 1), p, n, max_radius);
}

struct SurfaceSections::Cells {
  FaceCells cells;
};

namespace {
// Cells as wide as the longest face edge (near_plane's one-cell margin covers a face) and at least 1/128
// of the surface's extent (so that a wide section reads few thousand columns).
double section_cell_size(const SurfaceMesh& surface) {
  double longest = 0, extent = 0;
  for (const auto& f : surface.faces)
    for (int e = 0; e < 3; ++e) {
      const auto &a = surface.vertices[std::size_t(f[e])], &b = surface.vertices[std::size_t(f[(e + 1) % 3])];
      longest = std::max(longest, std::hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]));
    }
  std::array<double, 3> lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
  for (const auto& w : surface.vertices)
    for (int q = 0; q < 3; ++q) lo[q] = std::min(lo[q], w[q]), hi[q] = std::max(hi[q], w[q]);
  for (int q = 0; q < 3; ++q) extent = std::max(extent, hi[q] - lo[q]);
  return std::max({longest * 1.001, extent / 128, 1e-12});
}
}  // namespace

SurfaceSections::SurfaceSections(const SurfaceMesh& surface)
    : surface_(surface), cells_(new Cells{FaceCells(surface, section_cell_size(surface))}) {}
SurfaceSections::~SurfaceSections() = default;

Polyline3 SurfaceSections::around(const std::array<double, 3>& p, const std::array<double, 3>& n, double max_radius) const {
  const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  if (!(len > 0) || surface_.faces.empty()) return {};
  const std::array<double, 3> unit{n[0] / len, n[1] / len, n[2] / len};
  return section_of(surface_, cells_->cells.near_plane(surface_, p, unit, max_radius), p, unit, max_radius);
}

namespace {
// On a bumpy wall with gaps between atoms the plane normal to the axis can leak out through a gap; planes
// tilted up to 40 degrees are tried too and the shortest closed curve around the bottleneck is kept.
Polyline3 best_section(const SurfaceMesh& surface, const FaceCells& cells, const V3& p, const V3& axis, double rb) {
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
      Polyline3 sec = section_of(surface, faces, arr(p), arr(n), R);
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
  const FaceCells cells(surface, 2.0);
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

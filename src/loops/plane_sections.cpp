// Plane sections of a surface (plane_sections.h): the faces in cells, the section of a face set, and the
// sections of many planes over one bucketing, found from the faces along a ray.
#include "plane_sections.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>

#include <Eigen/Dense>

#include "chokeloops/loops/plane_sections.h"
#include "flat_int_map.h"

namespace chokeloops {
namespace detail {

namespace {
using V3 = Eigen::Vector3d;
V3 v3(const std::array<double, 3>& a) { return V3(a[0], a[1], a[2]); }
std::array<double, 3> arr(const V3& v) { return {v[0], v[1], v[2]}; }

// Whether the closed curve winds around p in the plane of e1 and e2, and the area it encloses there.
bool winds_around(const std::vector<V3>& curve, const V3& p, const V3& e1, const V3& e2, double& area) {
  double wind = 0, twice_area = 0;
  for (std::size_t i = 0; i < curve.size(); ++i) {
    const V3 a = curve[i] - p, b = curve[(i + 1) % curve.size()] - p;
    const double ax = a.dot(e1), ay = a.dot(e2), bx = b.dot(e1), by = b.dot(e2);
    wind += std::atan2(ax * by - ay * bx, ax * bx + ay * by);
    twice_area += ax * by - ay * bx;
  }
  area = std::abs(twice_area) / 2;
  return std::abs(wind) >= M_PI;
}
}  // namespace

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
    std::vector<V3> curve;
    for (int i : cyc) curve.push_back(pts[std::size_t(i)]);
    double area;
    if (!winds_around(curve, p, e1, e2, area)) continue;
    if (area < best_area) {
      best_area = area;
      best.clear();
      for (const V3& x : curve) best.push_back(arr(x));
    }
  }
  return best;
}

FaceCells::FaceCells(const SurfaceMesh& surface, double cell) : cell_(cell) {
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

std::array<int, 3> FaceCells::cell_coords(const std::array<double, 3>& v) const {
  std::array<int, 3> ijk;
  for (int a = 0; a < 3; ++a) ijk[a] = std::clamp(int((v[a] - lo_[a]) / cell_), 0, n_[a] - 1);
  return ijk;
}

int FaceCells::cell_of(const std::array<double, 3>& v) const {
  const auto ijk = cell_coords(v);
  return ijk[0] + n_[0] * (ijk[1] + n_[1] * ijk[2]);
}

FaceCells::PlaneQuery FaceCells::plane_query(const std::array<double, 3>& p, const std::array<double, 3>& nrm, double r) const {
  PlaneQuery q;
  q.p = p, q.nrm = nrm, q.r = r;
  q.a = 0;
  for (int k = 1; k < 3; ++k)
    if (std::abs(nrm[k]) > std::abs(nrm[q.a])) q.a = k;
  q.u = (q.a + 1) % 3, q.v = (q.a + 2) % 3;
  q.empty = false;
  for (int k = 0; k < 3; ++k) {
    q.lo[k] = std::max(0, int(std::floor((p[k] - r - lo_[k]) / cell_)));
    q.hi[k] = std::min(n_[k] - 1, int(std::floor((p[k] + r - lo_[k]) / cell_)));
    if (q.lo[k] > q.hi[k]) q.empty = true;
  }
  return q;
}

void FaceCells::column_range(const PlaneQuery& q, int iu, int iv, int& ia0, int& ia1) const {
  const int a = q.a, u = q.u, v = q.v;
  const auto& p = q.p;
  const auto& nrm = q.nrm;
  // The plane's height along axis a over this column's four corners.
  double amin = 1e300, amax = -1e300;
  for (int corner = 0; corner < 4; ++corner) {
    const double xu = lo_[u] + (iu + (corner & 1)) * cell_, xv = lo_[v] + (iv + (corner >> 1)) * cell_;
    const double xa = p[a] - (nrm[u] * (xu - p[u]) + nrm[v] * (xv - p[v])) / nrm[a];
    amin = std::min(amin, xa), amax = std::max(amax, xa);
  }
  ia0 = std::max(q.lo[a], int(std::floor((amin - lo_[a]) / cell_)) - 1);
  ia1 = std::min(q.hi[a], int(std::floor((amax - lo_[a]) / cell_)) + 1);
}

namespace {
// Within r of p (by its first vertex) and cut by the plane: the faces that hold a piece of the section.
bool near_and_cut(const SurfaceMesh& surface, const FaceCells::PlaneQuery& q, int f) {
  const auto& p = q.p;
  const auto& nrm = q.nrm;
  const auto& w = surface.vertices[std::size_t(surface.faces[std::size_t(f)][0])];
  const double d2 = (w[0] - p[0]) * (w[0] - p[0]) + (w[1] - p[1]) * (w[1] - p[1]) + (w[2] - p[2]) * (w[2] - p[2]);
  if (d2 > q.r * q.r) return false;
  int above = 0;
  for (int k = 0; k < 3; ++k) {
    const auto& x = surface.vertices[std::size_t(surface.faces[std::size_t(f)][k])];
    above += (x[0] - p[0]) * nrm[0] + (x[1] - p[1]) * nrm[1] + (x[2] - p[2]) * nrm[2] >= 0;  // as section_of counts 0
  }
  return above == 1 || above == 2;
}
}  // namespace

std::vector<int> FaceCells::near_plane(const SurfaceMesh& surface, const std::array<double, 3>& p,
                                       const std::array<double, 3>& nrm, double r) const {
  std::vector<int> out;
  const PlaneQuery q = plane_query(p, nrm, r);
  if (q.empty) return out;
  for (int iu = q.lo[q.u]; iu <= q.hi[q.u]; ++iu)
    for (int iv = q.lo[q.v]; iv <= q.hi[q.v]; ++iv) {
      int ia0, ia1;
      column_range(q, iu, iv, ia0, ia1);
      for (int ia = ia0; ia <= ia1; ++ia) {
        int ijk[3];
        ijk[q.a] = ia, ijk[q.u] = iu, ijk[q.v] = iv;
        const std::size_t c = std::size_t(ijk[0] + n_[0] * (ijk[1] + n_[1] * ijk[2]));
        for (int t = start_[c]; t < start_[c + 1]; ++t)
          if (near_and_cut(surface, q, items_[std::size_t(t)])) out.push_back(items_[std::size_t(t)]);
      }
    }
  return out;
}

bool FaceCells::listed(const SurfaceMesh& surface, const PlaneQuery& q, int f, std::uint64_t& key) const {
  if (q.empty) return false;
  const auto ijk = cell_coords(surface.vertices[std::size_t(surface.faces[std::size_t(f)][0])]);
  for (int k = 0; k < 3; ++k)
    if (ijk[k] < q.lo[k] || ijk[k] > q.hi[k]) return false;
  int ia0, ia1;
  column_range(q, ijk[q.u], ijk[q.v], ia0, ia1);
  if (ijk[q.a] < ia0 || ijk[q.a] > ia1) return false;
  if (!near_and_cut(surface, q, f)) return false;
  // near_plane's order: columns by u then v, cells up the column, faces rising within a cell
  const std::uint64_t column = std::uint64_t(ijk[q.u]) * std::uint64_t(n_[q.v]) + std::uint64_t(ijk[q.v]);
  key = (column * std::uint64_t(n_[q.a]) + std::uint64_t(ijk[q.a])) << 32 | std::uint32_t(f);
  return true;
}

std::vector<int> FaceCells::near(const SurfaceMesh& surface, const std::array<double, 3>& p, double r) const {
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

void FaceCells::near_segment(const std::array<double, 3>& a, const std::array<double, 3>& b, double reach,
                             std::vector<int>& out) const {
  out.clear();
  // A first vertex within `reach` (at most a cell) of a point of the segment lies in the cell of that point
  // or a neighbouring one: the cells the segment passes through (a walk from cell to cell, Amanatides and
  // Woo) and their neighbours hold every such face.
  const int spread = std::max(1, int(std::ceil(reach / cell_)));
  V3 A = v3(a), B = v3(b);
  // Clip the segment to the cells' box grown by the spread: beyond it no point is near a first vertex.
  double t0 = 0, t1 = 1;
  const V3 d = B - A;
  for (int k = 0; k < 3; ++k) {
    const double lo = lo_[k] - spread * cell_, hi = lo_[k] + (n_[k] + spread) * cell_;
    if (d[k] == 0) {
      if (A[k] < lo || A[k] > hi) return;
      continue;
    }
    double ta = (lo - A[k]) / d[k], tb = (hi - A[k]) / d[k];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta), t1 = std::min(t1, tb);
  }
  if (t0 > t1) return;
  const V3 P = A + t0 * d, Q = A + t1 * d;
  std::array<long, 3> c, last, step;
  std::array<double, 3> t_max, t_delta;
  const V3 e = Q - P;
  for (int k = 0; k < 3; ++k) {
    c[k] = long(std::floor((P[k] - lo_[k]) / cell_));
    last[k] = long(std::floor((Q[k] - lo_[k]) / cell_));
    step[k] = e[k] > 0 ? 1 : (e[k] < 0 ? -1 : 0);
    if (step[k] == 0) {
      t_max[k] = t_delta[k] = std::numeric_limits<double>::infinity();
    } else {
      const double boundary = lo_[k] + (c[k] + (step[k] > 0 ? 1 : 0)) * cell_;
      t_max[k] = (boundary - P[k]) / e[k];
      t_delta[k] = cell_ / std::abs(e[k]);
    }
  }
  std::vector<std::size_t> cells;
  auto add_around = [&](const std::array<long, 3>& x) {
    long c0[3], c1[3];
    for (int k = 0; k < 3; ++k) {
      c0[k] = std::max(0L, x[k] - spread), c1[k] = std::min(long(n_[k]) - 1, x[k] + spread);
      if (c0[k] > c1[k]) return;
    }
    for (long z = c0[2]; z <= c1[2]; ++z)
      for (long y = c0[1]; y <= c1[1]; ++y)
        for (long i = c0[0]; i <= c1[0]; ++i) cells.push_back(std::size_t(i + n_[0] * (y + long(n_[1]) * z)));
  };
  // At most one step per cell boundary crossed on each axis (plus one for rounding).
  const long max_steps = std::abs(last[0] - c[0]) + std::abs(last[1] - c[1]) + std::abs(last[2] - c[2]) + 4;
  for (long s = 0; s <= max_steps; ++s) {
    add_around(c);
    if (c == last) break;
    int k = t_max[0] < t_max[1] ? (t_max[0] < t_max[2] ? 0 : 2) : (t_max[1] < t_max[2] ? 1 : 2);
    if (t_max[k] > 1) break;  // rounding: the last cell is within a step of here
    c[k] += step[k];
    t_max[k] += t_delta[k];
  }
  add_around(last);
  std::sort(cells.begin(), cells.end());
  cells.erase(std::unique(cells.begin(), cells.end()), cells.end());
  for (std::size_t cell : cells)
    for (int t = start_[cell]; t < start_[cell + 1]; ++t) out.push_back(items_[std::size_t(t)]);
}

namespace {

// The section of section_of over near_plane's faces, found without reading them all: a closed curve that
// winds around p crosses the ray from p along the plane's first axis, so only the curves through the faces
// that ray meets are followed, face to face across their cut edges. A plane across a large surface cuts
// tens of thousands of faces, the curves around p a few thousand. The curve, its first point and its
// direction, and the choice among curves (least area, first in near_plane's order on a tie) are section_of's:
// the same numbers. False where that cannot be promised (an edge of more than two faces): section_of then.
class RaySection {
 public:
  RaySection(const SurfaceMesh& surface, const MeshAdjacency& adjacency, const FaceCells& cells,
             const std::array<double, 3>& p, const std::array<double, 3>& unit, double max_radius)
      : S_(surface), A_(adjacency), cells_(cells), q_(cells.plane_query(p, unit, max_radius)), max_radius_(max_radius),
        p_(v3(p)), n_(v3(unit).normalized()) {
    // section_of's frame
    e1_ = std::abs(n_[0]) < 0.9 ? V3(1, 0, 0) : V3(0, 1, 0);
    e1_ = (e1_ - e1_.dot(n_) * n_).normalized();
    e2_ = n_.cross(e1_);
  }

  // `faces`, when given, gets the face of each segment out[k] -> out[k + 1] (the last closing the curve).
  bool run(Polyline3& out, std::vector<int>* faces = nullptr) {
    out.clear();
    if (faces) faces->clear();
    if (q_.empty) return true;
    // A face the curve crosses the ray in holds a point of the ray within a face's size of its first vertex,
    // and that vertex is within max_radius of p.
    const double cell = cells_.cell();
    const double ray_length = max_radius_ + 2 * cell;
    std::vector<int> candidates;
    cells_.near_segment(arr(p_), arr(p_ + ray_length * e1_), cell, candidates);
    const double tol = 1e-9 * (max_radius_ + cell);
    // Each seed with where its segment meets the ray (its distance from p along e1); sorted below, so the
    // candidates' order never shows.
    std::vector<std::pair<double, int>> seeds;
    for (int f : candidates) {
      // Most candidates lie in the cells beside the ray and farther than a cell from it: their faces (each
      // within a face's size of its first vertex, less than a cell) cannot meet it. Their first vertex
      // alone turns them down, before cut_of reads all three (on the grey-matter map the sections' time
      // went to those reads).
      const V3 first = v3(S_.vertices[std::size_t(S_.faces[std::size_t(f)][0])]) - p_;
      const double along = std::clamp(first.dot(e1_), 0.0, ray_length);
      if ((first - along * e1_).squaredNorm() > cell * cell) continue;
      Cut c;
      if (!cut_of(f, c)) continue;
      const V3 a = point_on(f, c.edge[0]) - p_, b = point_on(f, c.edge[1]) - p_;
      const double ax = a.dot(e1_), ay = a.dot(e2_), bx = b.dot(e1_), by = b.dot(e2_);
      if (std::min(ay, by) > tol || std::max(ay, by) < -tol || std::max(ax, bx) < -tol) continue;
      const double x = std::abs(ay - by) > tol ? ax + (bx - ax) * ay / (ay - by) : std::min(ax, bx);
      seeds.push_back({x, f});
    }
    // The curves that wind around p are disjoint simple curves of the plane, so they nest, and the innermost
    // (the least area) meets the ray nearest p: the seeds are followed from p outward and the first closed
    // curve that winds around p is the section; the curves beyond it, often most of a wide section's faces
    // (a block's outline, the walls of the holes past it), are not followed.
    std::sort(seeds.begin(), seeds.end());
    // A flat set rather than std::unordered_set: its node per face was a tenth of a wide section's time.
    FlatIntMap seen;
    std::vector<Step> walk;
    for (const auto& [x, f] : seeds) {
      if (seen.contains(f)) continue;
      std::size_t first = 0;
      bool is_closed = false;
      if (!follow(f, seen, is_closed, walk, first)) return false;
      if (!is_closed) continue;
      std::vector<V3> pts;
      points_from(walk, first, pts, faces);
      if (pts.size() < 3) continue;
      double area;
      if (!winds_around(pts, p_, e1_, e2_, area)) {
        if (faces) faces->clear();
        continue;
      }
      for (const V3& q : pts) out.push_back(arr(q));
      return true;
    }
    return true;
  }

 private:
  struct Cut {
    int edge[2];  // the face's cut edges (k: from corner k to k+1), in section_of's order
    std::uint64_t key;
  };

  double sd(int v) const {
    double s = (v3(S_.vertices[std::size_t(v)]) - p_).dot(n_);
    return s == 0 ? 1e-300 : s;
  }
  // section_of's segment of face f, if near_plane lists f and section_of keeps it.
  bool cut_of(int f, Cut& c) const {
    // The plane's cut first: it turns down most faces near the ray, and costs least.
    const auto& F = S_.faces[std::size_t(f)];
    int m = 0;
    for (int e = 0; e < 3; ++e)
      if ((sd(F[e]) > 0) != (sd(F[(e + 1) % 3]) > 0) && m < 2) c.edge[m++] = e;
    if (m != 2) return false;
    if ((v3(S_.vertices[std::size_t(F[0])]) - p_).norm() > max_radius_) return false;
    return cells_.listed(S_, q_, f, c.key);
  }
  V3 point_on(int f, int e) const {
    const auto& F = S_.faces[std::size_t(f)];
    const int lo = std::min(F[e], F[(e + 1) % 3]), hi = std::max(F[e], F[(e + 1) % 3]);
    const double sa = sd(lo), sb = sd(hi);
    const double t = sa / (sa - sb);
    return v3(S_.vertices[std::size_t(lo)]) * (1 - t) + v3(S_.vertices[std::size_t(hi)]) * t;
  }
  // Across edge e of face f: the next face of the curve and the edge it is entered by; false at the curve's
  // end (a boundary, or a face section_of leaves out); `fallback` at an edge of more than two faces.
  bool across(int f, int e, int& g, int& entry, Cut& cg, bool& fallback) const {
    const int t = A_.twin[std::size_t(3 * f + e)];
    if (t < 0) {
      const auto& F = S_.faces[std::size_t(f)];
      const int a = F[e], b = F[(e + 1) % 3];
      int sharing = 0;
      for (int k = A_.vf_start[std::size_t(a)]; k < A_.vf_start[std::size_t(a) + 1]; ++k) {
        const auto& G = S_.faces[std::size_t(A_.vf[std::size_t(k)])];
        sharing += G[0] == b || G[1] == b || G[2] == b;
      }
      fallback = sharing != 1;
      return false;
    }
    g = MeshAdjacency::face(t), entry = t % 3;
    if (!cut_of(g, cg)) return false;
    if (cg.edge[0] != entry && cg.edge[1] != entry) return fallback = true, false;
    return true;
  }
  // A face of a curve, with its cut edges in section_of's order and the edge the walk left it by.
  struct Step {
    int face;
    Cut cut;
    int exit;
  };
  // The curve through seed face f: marks its faces seen; when it closes, `walk` holds its faces in turn (from
  // f, leaving by its second cut edge) and `first` the place of its first face in near_plane's order.
  bool follow(int f, FlatIntMap& seen, bool& is_closed, std::vector<Step>& walk, std::size_t& first) const {
    Cut c0;
    cut_of(f, c0);
    seen.emplace(f, 0);
    walk.assign(1, Step{f, c0, c0.edge[1]});
    first = 0;
    const std::size_t limit = S_.faces.size() + 1;
    for (int dir = 1; dir >= 0; --dir) {
      int g = f, e = c0.edge[dir];
      for (std::size_t steps = 0;; ++steps) {
        int h, entry;
        Cut ch;
        bool fallback = false;
        if (!across(g, e, h, entry, ch, fallback)) {
          if (fallback) return false;
          break;  // an open end: walk the other way to mark the rest
        }
        if (h == f) { is_closed = true; return true; }
        if (steps > limit || !seen.emplace(h, 0)) return false;  // not a simple curve: leave it to section_of
        e = ch.edge[0] == entry ? ch.edge[1] : ch.edge[0];
        if (dir == 1) {
          walk.push_back(Step{h, ch, e});
          if (ch.key < walk[first].cut.key) first = walk.size() - 1;
        }
        g = h;
      }
    }
    return true;
  }
  // The closed curve's points as section_of lists them: from its first face's first cut edge, leaving by its
  // second (the walk's way round, or against it). Each point is that of the edge between two faces in turn;
  // `faces` (when given) the face between each point and the next.
  void points_from(const std::vector<Step>& walk, std::size_t first, std::vector<V3>& pts, std::vector<int>* faces) const {
    const std::size_t m = walk.size();
    auto exit_point = [&](std::size_t i) { return point_on(walk[i].face, walk[i].exit); };
    const Step& start = walk[first];
    pts.reserve(m);
    if (faces) faces->clear(), faces->reserve(m);
    if (start.cut.edge[1] == start.exit) {
      for (std::size_t k = 0; k < m; ++k) {
        pts.push_back(exit_point((first + m - 1 + k) % m));
        if (faces) faces->push_back(walk[(first + k) % m].face);
      }
    } else {
      for (std::size_t k = 0; k < m; ++k) {
        pts.push_back(exit_point((first + m - k) % m));
        if (faces) faces->push_back(walk[(first + m - k) % m].face);
      }
    }
  }

  const SurfaceMesh& S_;
  const MeshAdjacency& A_;
  const FaceCells& cells_;
  const FaceCells::PlaneQuery q_;
  const double max_radius_;
  const V3 p_, n_;
  V3 e1_, e2_;
};

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
}  // namespace detail

Polyline3 cross_section_loop(const SurfaceMesh& surface, const std::array<double, 3>& p, const std::array<double, 3>& n,
                             double max_radius) {
  return detail::section_of(surface, detail::FaceCells(surface, 2.0).near(surface, p, max_radius + 1), p, n, max_radius);
}

struct SurfaceSections::Cells {
  detail::FaceCells cells;
};

SurfaceSections::SurfaceSections(const SurfaceMesh& surface, const MeshAdjacency* adjacency)
    : surface_(surface), adjacency_(adjacency), cells_(new Cells{detail::FaceCells(surface, detail::section_cell_size(surface))}) {}
SurfaceSections::~SurfaceSections() = default;

Polyline3 SurfaceSections::around(const std::array<double, 3>& p, const std::array<double, 3>& n, double max_radius,
                                  bool by_ray, std::vector<int>* faces) const {
  if (faces) faces->clear();
  const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  if (!(len > 0) || surface_.faces.empty()) return {};
  const std::array<double, 3> unit{n[0] / len, n[1] / len, n[2] / len};
  if (adjacency_ && by_ray) {
    Polyline3 out;
    if (detail::RaySection(surface_, *adjacency_, cells_->cells, p, unit, max_radius).run(out, faces)) return out;
    if (faces) faces->clear();
  }
  return detail::section_of(surface_, cells_->cells.near_plane(surface_, p, unit, max_radius), p, unit, max_radius);
}

bool SurfaceSections::segment_clear(const std::array<double, 3>& a, const std::array<double, 3>& b) const {
  // A face the segment meets has its first vertex within a face's size (less than a cell) of the segment.
  using detail::V3, detail::v3;
  thread_local std::vector<int> faces;
  cells_->cells.near_segment(a, b, cells_->cells.cell(), faces);
  const V3 A = v3(a), B = v3(b), d = B - A;
  const double len = d.norm();
  // Values within a relative 1e-9 of zero count as meeting: a doubt is a meeting.
  constexpr double kTolerance = 1e-9;
  for (int f : faces) {
    const auto& F = surface_.faces[std::size_t(f)];
    const V3 P0 = v3(surface_.vertices[std::size_t(F[0])]), P1 = v3(surface_.vertices[std::size_t(F[1])]),
             P2 = v3(surface_.vertices[std::size_t(F[2])]);
    // The ends on one side of the face's plane: no meeting.
    const V3 normal = (P1 - P0).cross(P2 - P0);
    const double plane_tol = kTolerance * normal.norm() * (len + (P1 - P0).norm() + (P2 - P0).norm());
    const double va = normal.dot(A - P0), vb = normal.dot(B - P0);
    if ((va > plane_tol && vb > plane_tol) || (va < -plane_tol && vb < -plane_tol)) continue;
    // The line misses the triangle unless it passes on one side of all three edges' planes through it.
    const V3 Q[3] = {P0 - A, P1 - A, P2 - A};
    bool positive = true, negative = true;
    for (int k = 0; k < 3; ++k) {
      const V3 &u = Q[k], &w = Q[(k + 1) % 3];
      const double side = u.cross(w).dot(d), tol = kTolerance * u.norm() * w.norm() * len;
      positive &= side > -tol, negative &= side < tol;
    }
    if (positive || negative) return false;
  }
  return true;
}

}  // namespace chokeloops

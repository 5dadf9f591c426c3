// Molecular surfaces as signed distance grids (DESIGN §6).
#include "chokeloops/field/molecular_field.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "chokeloops/field/levelset.h"
#include "common/first_non_finite.h"
#include "feature_transform.h"

namespace chokeloops {

const char* to_string(MolecularSurface s) {
  return s == MolecularSurface::Vdw ? "vdw" : s == MolecularSurface::Sas ? "sas" : "ses";
}

AtomLocator::AtomLocator(std::vector<std::array<double, 3>> centres, std::vector<double> radii, double cell)
    : c_(std::move(centres)), r_(std::move(radii)), cell_(cell) {
  std::array<double, 3> hi{-1e300, -1e300, -1e300};
  lo_ = {1e300, 1e300, 1e300};
  for (std::size_t i = 0; i < c_.size(); ++i) {
    rmax_ = std::max(rmax_, r_[i]);
    for (int a = 0; a < 3; ++a) lo_[a] = std::min(lo_[a], c_[i][a]), hi[a] = std::max(hi[a], c_[i][a]);
  }
  if (c_.empty()) lo_ = hi = {0, 0, 0};
  for (int a = 0; a < 3; ++a) n_[a] = std::max(1, int(std::floor((hi[a] - lo_[a]) / cell_)) + 1);
  const std::size_t cells = std::size_t(n_[0]) * n_[1] * n_[2];
  std::vector<int> cell_of(c_.size());
  start_.assign(cells + 1, 0);
  for (std::size_t i = 0; i < c_.size(); ++i) {
    int ijk[3];
    for (int a = 0; a < 3; ++a) ijk[a] = std::min(n_[a] - 1, int((c_[i][a] - lo_[a]) / cell_));
    cell_of[i] = ijk[0] + n_[0] * (ijk[1] + n_[1] * ijk[2]);
    start_[std::size_t(cell_of[i]) + 1]++;
  }
  for (std::size_t k = 0; k < cells; ++k) start_[k + 1] += start_[k];
  items_.resize(c_.size());
  std::vector<int> fill(start_.begin(), start_.end() - 1);
  for (std::size_t i = 0; i < c_.size(); ++i) items_[std::size_t(fill[std::size_t(cell_of[i])]++)] = int(i);
}

template <class F>
void AtomLocator::visit_box(const std::array<double, 3>& lo, const std::array<double, 3>& hi, F&& f) const {
  int a0[3], a1[3];
  for (int a = 0; a < 3; ++a) {
    a0[a] = std::max(0, int(std::floor((lo[a] - lo_[a]) / cell_)));
    a1[a] = std::min(n_[a] - 1, int(std::floor((hi[a] - lo_[a]) / cell_)));
    if (a0[a] > a1[a]) return;
  }
  for (int k = a0[2]; k <= a1[2]; ++k)
    for (int j = a0[1]; j <= a1[1]; ++j)
      for (int i = a0[0]; i <= a1[0]; ++i) {
        const std::size_t cell = std::size_t(i + n_[0] * (j + n_[1] * k));
        for (int t = start_[cell]; t < start_[cell + 1]; ++t) f(items_[std::size_t(t)]);
      }
}

double AtomLocator::distance(const std::array<double, 3>& x, int* nearest) const {
  double best = std::numeric_limits<double>::infinity();
  int arg = -1;
  // Grow the search until the best sphere found is closer than anything outside the searched box could be.
  for (double R = cell_;; R *= 2) {
    const double reach = R + rmax_;
    visit_box({x[0] - reach, x[1] - reach, x[2] - reach}, {x[0] + reach, x[1] + reach, x[2] + reach}, [&](int i) {
      const auto& c = c_[std::size_t(i)];
      const double d = std::sqrt((x[0] - c[0]) * (x[0] - c[0]) + (x[1] - c[1]) * (x[1] - c[1]) +
                                 (x[2] - c[2]) * (x[2] - c[2])) - r_[std::size_t(i)];
      if (d < best || (d == best && i < arg)) best = d, arg = i;
    });
    bool covers = true;
    for (int a = 0; a < 3; ++a)
      covers &= x[a] - reach <= lo_[a] && x[a] + reach >= lo_[a] + n_[a] * cell_;
    if (best <= R || covers || c_.empty()) break;
  }
  if (nearest) *nearest = arg;
  return best;
}

std::vector<int> AtomLocator::within(const std::array<double, 3>& x, double d) const {
  std::vector<int> out;
  const double reach = d + rmax_;
  visit_box({x[0] - reach, x[1] - reach, x[2] - reach}, {x[0] + reach, x[1] + reach, x[2] + reach}, [&](int i) {
    const auto& c = c_[std::size_t(i)];
    const double e = std::sqrt((x[0] - c[0]) * (x[0] - c[0]) + (x[1] - c[1]) * (x[1] - c[1]) +
                               (x[2] - c[2]) * (x[2] - c[2])) - r_[std::size_t(i)];
    if (e <= d) out.push_back(i);
  });
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<double> surface_radii(const Molecule& mol, MolecularSurface surface, double probe) {
  std::vector<double> r;
  r.reserve(mol.atoms.size());
  for (auto& a : mol.atoms) r.push_back(a.radius + (surface == MolecularSurface::Sas ? probe : 0.0));
  return r;
}

std::size_t estimate_molecular_field_bytes(std::size_t voxels, MolecularSurface surface) {
  // the grid itself plus what persistence and the surface need after it (the mesh guard's model), and the
  // SES's feature transform (distance, site, known flag)
  return estimate_levelset_bytes(voxels) + (surface == MolecularSurface::Ses ? voxels * 9 : 0);
}

namespace {

// Exact min_i(|x - c_i| - R_i) on every vertex within `cut` of some sphere, +inf elsewhere. Each atom is
// written by the z-slabs it overlaps; slabs run in parallel and a min does not depend on the order.
void rasterise(ScalarGrid& g, const std::vector<std::array<double, 3>>& c, const std::vector<double>& R, double cut) {
  const int nx = g.dims[0], ny = g.dims[1], nz = g.dims[2];
  const double h = g.voxel_size;
  constexpr int kSlab = 8;
  const int slabs = (nz + kSlab - 1) / kSlab;
  std::vector<std::vector<int>> per_slab(static_cast<std::size_t>(slabs));
  for (std::size_t i = 0; i < c.size(); ++i) {
    const double reach = R[i] + cut;
    const int k0 = std::max(0, int(std::ceil((c[i][2] - reach - g.origin[2]) / h)));
    const int k1 = std::min(nz - 1, int(std::floor((c[i][2] + reach - g.origin[2]) / h)));
    for (int s = k0 / kSlab; s <= k1 / kSlab && k1 >= k0; ++s) per_slab[std::size_t(s)].push_back(int(i));
  }
  tbb::parallel_for(tbb::blocked_range<int>(0, slabs, 1), [&](const tbb::blocked_range<int>& r) {
    for (int s = r.begin(); s != r.end(); ++s) {
      const int ks = s * kSlab, ke = std::min(nz, ks + kSlab);
      for (int i : per_slab[std::size_t(s)]) {
        const auto& p = c[std::size_t(i)];
        const double reach = R[std::size_t(i)] + cut, reach2 = reach * reach;
        const int k0 = std::max(ks, int(std::ceil((p[2] - reach - g.origin[2]) / h)));
        const int k1 = std::min(ke - 1, int(std::floor((p[2] + reach - g.origin[2]) / h)));
        for (int k = k0; k <= k1; ++k) {
          const double dz = g.origin[2] + k * h - p[2];
          const double rz2 = reach2 - dz * dz;
          if (rz2 < 0) continue;
          const double rz = std::sqrt(rz2);
          const int j0 = std::max(0, int(std::ceil((p[1] - rz - g.origin[1]) / h)));
          const int j1 = std::min(ny - 1, int(std::floor((p[1] + rz - g.origin[1]) / h)));
          for (int j = j0; j <= j1; ++j) {
            const double dy = g.origin[1] + j * h - p[1];
            const double ry2 = rz2 - dy * dy;
            if (ry2 < 0) continue;
            const double ry = std::sqrt(ry2);
            const int i0 = std::max(0, int(std::ceil((p[0] - ry - g.origin[0]) / h)));
            const int i1 = std::min(nx - 1, int(std::floor((p[0] + ry - g.origin[0]) / h)));
            float* row = &g.values[std::size_t(g.index(0, j, k))];
            const double dyz2 = dy * dy + dz * dz, Ri = R[std::size_t(i)];
            // branch-free, so that it vectorises (CMakeLists.txt builds this file without -frounding-math)
            for (int x = i0; x <= i1; ++x) {
              const double dx = g.origin[0] + x * h - p[0];
              row[x] = std::min(row[x], float(std::sqrt(dx * dx + dyz2) - Ri));
            }
          }
        }
      }
    }
  });
}

// Vertices farther than `cut` from every sphere: the distance to the sphere of the nearest centre, found by
// the exact feature transform with the atom centres as sites.
void far_field(ScalarGrid& g, const std::vector<std::array<double, 3>>& c, const std::vector<double>& R) {
  // The vertices left to fill are those the rasterisation did not reach (+inf).
  if (detail::first_non_finite(g.values.data(), g.values.size()) == g.values.size()) return;
  const double h = g.voxel_size;
  // One site per vertex, the first atom there (two centres this close are one, seen from far away): the
  // atoms sorted by their vertex rather than a grid-sized mark array.
  std::vector<std::int64_t> vertex_of(c.size());
  std::vector<std::array<float, 3>> point_of(c.size());
  for (std::size_t i = 0; i < c.size(); ++i) {
    int ijk[3];
    for (int a = 0; a < 3; ++a) {
      point_of[i][a] = float((c[i][a] - g.origin[a]) / h);
      ijk[a] = std::clamp(int(std::lround(point_of[i][a])), 0, g.dims[a] - 1);
    }
    vertex_of[i] = g.index(ijk[0], ijk[1], ijk[2]);
  }
  std::vector<int> by_vertex(c.size());
  for (std::size_t i = 0; i < c.size(); ++i) by_vertex[i] = int(i);
  std::sort(by_vertex.begin(), by_vertex.end(), [&](int a, int b) {
    return vertex_of[std::size_t(a)] != vertex_of[std::size_t(b)] ? vertex_of[std::size_t(a)] < vertex_of[std::size_t(b)]
                                                                   : a < b;
  });
  std::vector<std::uint8_t> first_at_vertex(c.size(), 0);
  for (std::size_t n = 0; n < by_vertex.size(); ++n)
    first_at_vertex[std::size_t(by_vertex[n])] =
        n == 0 || vertex_of[std::size_t(by_vertex[n])] != vertex_of[std::size_t(by_vertex[n - 1])];
  std::vector<detail::Site> sites;  // in atom order
  std::vector<int> site_atom;
  for (std::size_t i = 0; i < c.size(); ++i) {
    if (!first_at_vertex[i]) continue;
    sites.push_back({vertex_of[i], {point_of[i][0], point_of[i][1], point_of[i][2]}});
    site_atom.push_back(int(i));
  }
  const detail::GridArray<std::int32_t> nearest = detail::nearest_sites(g, sites);
  tbb::parallel_for(tbb::blocked_range<int>(0, g.dims[2]), [&](const tbb::blocked_range<int>& r) {
    for (int k = r.begin(); k != r.end(); ++k)
      for (int j = 0; j < g.dims[1]; ++j)
        for (int i = 0; i < g.dims[0]; ++i) {
          const std::size_t v = std::size_t(g.index(i, j, k));
          if (std::isfinite(g.values[v]) || nearest[v] < 0) continue;
          const int a = site_atom[std::size_t(nearest[v])];
          const auto x = g.world({i, j, k});
          const double d = std::sqrt((x[0] - c[a][0]) * (x[0] - c[a][0]) + (x[1] - c[a][1]) * (x[1] - c[a][1]) +
                                     (x[2] - c[a][2]) * (x[2] - c[a][2])) - R[std::size_t(a)];
          g.values[v] = float(d);
        }
  });
}

// SES from the SAS field: accessible vertices (sas >= 0) get sas + p; the others p minus their distance to
// the SAS, from the feature transform of the SAS's zero crossings along grid edges.
void shrink_to_ses(ScalarGrid& g, double probe) {
  const std::size_t N = g.values.size();
  const float* f = g.values.data();
  // Sites on inside vertices; their points are the nearest crossings.
  const std::vector<detail::Site> sites = detail::collect_sites(g, [&](int i, int j, int k, std::int64_t v, detail::Site& site) {
    const int ijk[3] = {i, j, k};
    int axis, dir;
    double t;
    if (f[v] >= 0 || !detail::nearest_edge_crossing(g, v, ijk, axis, dir, t)) return false;
    float p[3] = {float(i), float(j), float(k)};
    p[axis] += float(t * dir);
    site = {v, {p[0], p[1], p[2]}};
    return true;
  });
  std::vector<std::uint8_t> known(N);
  for (std::size_t v = 0; v < N; ++v) known[v] = f[v] >= 0;
  if (sites.empty()) {  // no accessible space at all: everything is inside
    for (auto& x : g.values) x = x >= 0 ? float(x + probe) : float(-1);
    return;
  }
  detail::complete_by_feature_transform(g, known, sites);  // inside vertices: -distance to the SAS
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, N), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t v = r.begin(); v != r.end(); ++v)
      g.values[v] = known[v] ? float(g.values[v] + probe) : float(probe + g.values[v]);
  });
}

}  // namespace

ScalarGrid molecular_field(const Molecule& mol, const MolecularFieldOptions& o) {
  if (mol.atoms.empty()) throw Error(mol.path + ": no atoms", 2);
  if (!(o.voxel_size > 0) || !std::isfinite(o.voxel_size)) throw Error("--voxel-size must be positive", 2);
  if (o.surface != MolecularSurface::Vdw && !(o.probe > 0)) throw Error("--probe must be positive", 2);
  const double h = o.voxel_size;
  const double grow = o.surface == MolecularSurface::Vdw ? 0.0 : o.probe;
  std::vector<std::array<double, 3>> c;
  std::vector<double> R;
  for (auto& a : mol.atoms) c.push_back(a.pos), R.push_back(a.radius + grow);
  std::array<double, 3> lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
  for (std::size_t i = 0; i < c.size(); ++i)
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], c[i][a] - R[i]), hi[a] = std::max(hi[a], c[i][a] + R[i]);
  const double margin = o.margin >= 0 ? o.margin : std::max(6.0, 4 * h);
  ScalarGrid g;
  g.voxel_size = h;
  double voxels = 1;
  for (int a = 0; a < 3; ++a) {
    g.origin[a] = lo[a] - margin;
    const double n = std::ceil((hi[a] - lo[a] + 2 * margin) / h) + 1;
    voxels *= n;
    if (n > 1e5) throw Error(mol.path + ": the box is " + std::to_string(int(hi[a] - lo[a])) + " A long; --voxel-size " +
                             std::to_string(h) + " would need more than 100000 voxels along it", 3);
    g.dims[a] = int(n);
  }
  const std::size_t need = estimate_molecular_field_bytes(std::size_t(voxels), o.surface);
  const std::size_t limit = o.max_memory ? o.max_memory : default_max_memory();
  if (need > limit) {
    const double fit = h * std::cbrt(double(need) / double(limit)) * 1.05;
    std::ostringstream s;
    s.precision(3);
    s << mol.path << ": a " << g.dims[0] << "x" << g.dims[1] << "x" << g.dims[2] << " grid needs about "
      << need / (1 << 20) << " MB, more than the " << limit / (1 << 20) << " MB allowed; use --voxel-size "
      << fit << " (or raise --max-memory)";
    throw Error(s.str(), 3);
  }
  g.values.assign(std::size_t(voxels), std::numeric_limits<float>::infinity());
  rasterise(g, c, R, std::max(3.0, 4 * h));
  far_field(g, c, R);
  if (o.surface == MolecularSurface::Ses) shrink_to_ses(g, o.probe);
  return g;
}

}  // namespace chokeloops

// Stage `levelset` for .vdb input: a level set is checked against the exact distance to its own zero level
// set and redistanced where it is not one; a fog volume becomes a signed distance at its iso value.
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <sstream>

#include <openvdb/tools/FastSweeping.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include "chokeloops/field/levelset.h"
#include "chokeloops/io/vdb_io.h"
#include "levelset_internal.h"

namespace chokeloops {

using namespace levelset_detail;

namespace {

// Fraction of sampled near-surface voxels whose central-difference |grad phi| is within 15% of 1.
double eikonal_fraction(const openvdb::FloatGrid& g, std::size_t* sampled) {
  const double h = g.voxelSize()[0];
  std::vector<openvdb::Coord> near;
  for (auto it = g.tree().cbeginValueOn(); it; ++it) {
    if (!it.isVoxelValue()) continue;
    if (std::abs(*it) < 1.5 * h) near.push_back(it.getCoord());
  }
  std::mt19937 rng(12345);
  std::shuffle(near.begin(), near.end(), rng);
  if (near.size() > 20000) near.resize(20000);
  auto acc = g.getConstAccessor();
  std::size_t good = 0, n = 0;
  for (auto& c : near) {
    double grad2 = 0;
    bool ok = true;
    for (int k = 0; k < 3; ++k) {
      openvdb::Coord a = c, b = c;
      a[k] += 1;
      b[k] -= 1;
      if (!acc.isValueOn(a) || !acc.isValueOn(b)) { ok = false; break; }
      const double d = (acc.getValue(a) - acc.getValue(b)) / (2 * h);
      grad2 += d * d;
    }
    if (!ok) continue;
    ++n;
    const double gn = std::sqrt(grad2);
    if (gn > 0.85 && gn < 1.15) ++good;
  }
  *sampled = n;
  return n ? double(good) / double(n) : 0.0;
}

openvdb::CoordBBox surface_bbox(const openvdb::FloatGrid& g) {
  const double h = g.voxelSize()[0];
  openvdb::CoordBBox bb;
  for (auto it = g.tree().cbeginValueOn(); it; ++it) {
    if (!it.isVoxelValue()) continue;
    if (std::abs(*it) <= 0.87 * h) bb.expand(it.getCoord());
  }
  return bb;
}

// Bounding box of the voxels with an axis neighbour of the other sign: the surface of a level set whose
// values are not distances (their scale says nothing about how far a voxel is from it).
openvdb::CoordBBox crossing_bbox(const openvdb::FloatGrid& g) {
  std::vector<const openvdb::FloatTree::LeafNodeType*> leaves;
  for (auto it = g.tree().cbeginLeaf(); it; ++it) leaves.push_back(it.getLeaf());
  return tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, leaves.size(), 16), openvdb::CoordBBox(),
      [&](const tbb::blocked_range<std::size_t>& r, openvdb::CoordBBox bb) {
        auto acc = g.getConstAccessor();
        for (std::size_t l = r.begin(); l != r.end(); ++l)
          for (auto it = leaves[l]->cbeginValueOn(); it; ++it) {
            const openvdb::Coord c = it.getCoord();
            const bool neg = *it < 0;
            for (int a = 0; a < 3; ++a) {
              openvdb::Coord d(0);
              d[a] = 1;
              if ((acc.getValue(c + d) < 0) != neg || (acc.getValue(c - d) < 0) != neg) {
                bb.expand(c);
                break;
              }
            }
          }
        return bb;
      },
      [](openvdb::CoordBBox a, const openvdb::CoordBBox& b) {
        a.expand(b);
        return a;
      });
}


// A level set can be a distance near its surface only: min/max (CSG) of exact distances, a narrow band
// grown by another tool. Its eikonal residual is fine almost everywhere, so the one test that catches it is
// the exact distance to its own zero level set, computed over the whole box and compared at every vertex
// whose value the input gave. Beyond one voxel anywhere, the exact distance replaces the input's values
// (their signs, and so the surface, are kept).
void replace_values_that_are_not_the_distance(LevelSetResult& res, const std::vector<std::uint8_t>& known, double h,
                                               const std::string& who) {
  ScalarGrid exact = res.grid;
  redistance_from_signs(exact);
  const std::size_t n = exact.values.size();
  struct Deviation {
    double max = 0;
    std::size_t over = 0, compared = 0;
  };
  const Deviation d = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, n, 1 << 16), Deviation{},
      [&](const tbb::blocked_range<std::size_t>& r, Deviation acc) {
        for (std::size_t v = r.begin(); v != r.end(); ++v) {
          if (!known.empty() && !known[v]) continue;
          const double e = std::abs(double(res.grid.values[v]) - double(exact.values[v])) / h;
          acc.max = std::max(acc.max, e);
          acc.over += e > kDistanceToleranceVoxels;
          ++acc.compared;
        }
        return acc;
      },
      [](Deviation a, const Deviation& b) {
        a.max = std::max(a.max, b.max);
        a.over += b.over;
        a.compared += b.compared;
        return a;
      });
  res.max_distance_error_voxels = d.max;
  if (d.over == 0) return;
  std::ostringstream s;
  s << who << ": values are the distance to the zero level set only near it (" << d.over << " of " << d.compared
    << " vertices are more than " << kDistanceToleranceVoxels << " voxel off, up to " << d.max
    << " voxels: a min/max (CSG) field?); recomputed as the exact distance (--keep-values uses them as given)";
  res.warnings.push_back(s.str());
  res.source = "vdb level set (redistanced: not a distance far from the surface)";
  res.grid.values = std::move(exact.values);
}

}  // namespace

// Replaces the values of a dense grid by the signed distance to the zero level set its signs define.
// Every vertex with an axis neighbour of the other sign becomes a site whose surface point is one Newton
// step onto the level set (x - phi grad/|grad|^2, central differences), or the nearest crossing along its
// axis edges where that step is unreliable (flat gradient, or a step longer than 1.5 voxels); the exact
// feature transform of levelset_edt.cpp then gives every vertex the distance to the best of these
// points. First order near the surface and exact to the sampled points far from it, unlike fast
// sweeping, whose first-order error accumulates with the distance; and ~5x faster (tangle cube 257^3).
void redistance_from_signs(ScalarGrid& g, const std::vector<std::uint8_t>& known) {
  const int nx = g.dims[0], ny = g.dims[1];
  const float* f = g.values.data();
  const std::int64_t st[3] = {1, nx, std::int64_t(nx) * ny};
  const std::vector<detail::Site> sites = detail::collect_sites(g, [&](int i, int j, int k, std::int64_t v, detail::Site& site) {
    const int ijk[3] = {i, j, k};
    int best_axis, best_dir;
    double best_t;
    if (!detail::nearest_edge_crossing(g, v, ijk, best_axis, best_dir, best_t)) return false;
    const float fv = f[v];
    double grad[3];
    for (int a = 0; a < 3; ++a) {
      const bool has_lo = ijk[a] > 0, has_hi = ijk[a] < g.dims[a] - 1;
      const float lo = has_lo ? f[v - st[a]] : fv, hi = has_hi ? f[v + st[a]] : fv;
      grad[a] = double(hi - lo) / double(std::max(1, int(has_lo) + int(has_hi)));  // central, one-sided at the border
    }
    const double g2 = grad[0] * grad[0] + grad[1] * grad[1] + grad[2] * grad[2];
    double p[3] = {double(i), double(j), double(k)};
    bool newton = g2 > 0;
    if (newton) {
      const double step = double(fv) / g2;
      const double len2 = step * step * g2;
      newton = len2 <= 1.5 * 1.5;
      if (newton)
        for (int a = 0; a < 3; ++a) p[a] -= step * grad[a];
    }
    if (!newton) p[best_axis] += best_t * best_dir;
    site = {v, {float(p[0]), float(p[1]), float(p[2])}};
    return true;
  });
  detail::complete_by_feature_transform(g, known, sites);
}

LevelSetResult levelset_from_vdb(openvdb::FloatGrid::ConstPtr input, const LevelSetOptions& o, const std::string& name) {
  ensure_openvdb_initialized();
  const auto t0 = Clock::now();
  const std::string who = "'" + name + "'";
  LevelSetResult res;
  if (o.voxel_size > 0 || o.resolution != 256)
    res.warnings.push_back(who + ": .vdb input keeps its own voxel size; --resolution/--voxel-size ignored");
  // transform must be axis aligned + uniform (throws otherwise)
  (void)dense_from_grid;
  {
    const openvdb::math::Transform& xf = input->transform();
    const openvdb::Vec3d vs = xf.voxelSize();
    if (!xf.isLinear() || std::abs(vs[0] - vs[1]) > 1e-6 * vs[0] || std::abs(vs[0] - vs[2]) > 1e-6 * vs[0])
      throw Error(who + ": transform must be a uniform scale plus translation; resample the grid first");
  }
  const double h = input->voxelSize()[0];

  // classify: level set or fog
  float vmin = std::numeric_limits<float>::max(), vmax = -vmin;
  for (auto it = input->tree().cbeginValueOn(); it; ++it) {
    vmin = std::min(vmin, *it);
    vmax = std::max(vmax, *it);
    if (!std::isfinite(*it)) throw Error(who + ": grid holds non-finite values");
  }
  bool fog = input->getGridClass() == openvdb::GRID_FOG_VOLUME;
  if (input->getGridClass() == openvdb::GRID_UNKNOWN) fog = !(vmin < 0 && vmax > 0);
  // What the box's values come from: fogToSdf's band, or the input itself (read only).
  openvdb::FloatGrid::ConstPtr sdf;
  bool redistance = false;  // the input's values are not distances: only their signs are used
  if (fog) {
    if (!(vmin < o.iso && vmax > o.iso)) {
      std::ostringstream s;
      s << who << ": fog volume values lie in [" << vmin << ", " << vmax << "], the iso value " << o.iso
        << " is not crossed (use --iso)";
      throw Error(s.str());
    }
    // Unset voxels hold the background: one denser than the iso value would put all space outside the active
    // region inside the surface, and OpenVDB's fogToSdf throws from its sweeping on it.
    if (!(input->background() < o.iso)) {
      std::ostringstream s;
      s << who << ": fog volume's background value " << input->background() << " (the value of every voxel not stored)"
        << " is not below the iso value " << o.iso << ", so the inside would fill all space (use --iso above it)";
      throw Error(s.str());
    }
    try {
      sdf = openvdb::tools::fogToSdf(*input, float(o.iso));
    } catch (const openvdb::Exception& e) {
      throw Error(who + ": OpenVDB could not turn the fog volume into a signed distance at the iso value (" +
                  e.what() + ")");
    }
    res.source = "vdb fog";
  } else {
    if (!(vmin < 0 && vmax > 0)) throw Error(who + ": level set has no zero crossing (all values of one sign)");
    std::size_t sampled = 0;
    const double frac = eikonal_fraction(*input, &sampled);
    if (sampled >= 10 && frac >= 0.8) {
      sdf = input;
      res.source = "vdb level set";
    } else {
      redistance = true;
      sdf = input;
      res.source = "vdb level set (renormalised)";
      std::ostringstream s;
      s << who << ": values are not a true distance (" << int(frac * 100) << "% of " << sampled
        << " sampled voxels have |grad| within 15% of 1); recomputed as the distance to their zero level set";
      res.warnings.push_back(s.str());
    }
  }
  if (!sdf || sdf->activeVoxelCount() == 0) throw Error(who + ": conversion to a signed distance produced an empty grid");
  const openvdb::CoordBBox sb = redistance ? crossing_bbox(*sdf) : surface_bbox(*sdf);
  if (sb.empty()) throw Error(who + ": no surface (zero crossing) found in the grid");
  const double longest = double(std::max({sb.dim()[0], sb.dim()[1], sb.dim()[2]})) * h;
  const double margin = o.margin >= 0 ? o.margin : default_margin(longest, h);
  res.margin = margin;
  const int pad = int(std::ceil(margin / h));
  openvdb::CoordBBox box(sb.min() - openvdb::Coord(pad), sb.max() + openvdb::Coord(pad));
  const openvdb::CoordBBox active = input->evalActiveVoxelBoundingBox();
  const bool dense_input = input->activeVoxelCount() == active.volume();
  if (o.margin < 0 && dense_input && active.isInside(sb)) {
    box = active;  // a dense grid (e.g. written by `chokeloops levelset`) keeps its own box
    res.margin = double(std::min({sb.min()[0] - active.min()[0], sb.min()[1] - active.min()[1],
                                  sb.min()[2] - active.min()[2], active.max()[0] - sb.max()[0],
                                  active.max()[1] - sb.max()[1], active.max()[2] - sb.max()[2]})) * h;
  } else if (o.margin < 0) {
    box.expand(active);
  }
  check_memory(box, o, h, longest, who);
  // Voxels where sdf holds a distance (a narrow band, fogToSdf's band, a dense distance grid) keep it; the
  // rest of the box, all of it when the values are not distances, gets the exact feature transform's
  // distance to the zero crossings (OpenVDB's fast sweeping, used before, was 1.2 voxels off on a sphere's
  // far field; this is under 0.5: LevelSetVdbInput tests).
  res.grid = dense_from_grid(*sdf, box, who);
  std::vector<std::uint8_t> known;
  std::size_t known_count = 0;
  if (!redistance) {
    known.assign(res.grid.values.size(), 0);
    const openvdb::Coord b0 = box.min();
    for (auto it = sdf->tree().cbeginValueOn(); it; ++it) {
      openvdb::CoordBBox bb = it.getBoundingBox();
      bb.intersect(box);
      if (bb.empty()) continue;
      for (int k = bb.min()[2]; k <= bb.max()[2]; ++k)
        for (int j = bb.min()[1]; j <= bb.max()[1]; ++j)
          for (int i = bb.min()[0]; i <= bb.max()[0]; ++i) {
            std::uint8_t& kn = known[std::size_t(res.grid.index(i - b0[0], j - b0[1], k - b0[2]))];
            known_count += kn == 0;
            kn = 1;
          }
    }
  }
  if (known_count < res.grid.values.size()) redistance_from_signs(res.grid, known);
  if (!redistance && !fog && !o.keep_values) replace_values_that_are_not_the_distance(res, known, h, who);
  if (o.keep_vdb) {
    res.vdb = grid_from_dense(res.grid, true);
    res.vdb->setName(input->getName().empty() ? "sdf" : input->getName());
  }
  count_sides(res);
  res.seconds = since(t0);
  emit_warnings(res, o);
  return res;
}

}  // namespace chokeloops

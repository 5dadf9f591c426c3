// Sliding a shortened loop along its tube to the narrowest section nearby (slide.h).
#include "slide.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>

#include "chokeloops/loops/membranes.h"
#include "chokeloops/surface/topology.h"

namespace chokeloops::detail {

namespace {

// Trilinear interpolation of the grid at a world point (clamped to the box).
double phi_at(const ScalarGrid& grid, const std::array<double, 3>& p) {
  std::array<int, 3> i0;
  std::array<double, 3> t;
  for (int a = 0; a < 3; ++a) {
    double u = (p[a] - grid.origin[a]) / grid.h(a);
    u = std::min(std::max(u, 0.0), double(grid.dims[a] - 1) - 1e-9);
    i0[a] = std::min(int(u), grid.dims[a] - 2);
    t[a] = u - i0[a];
  }
  double v = 0;
  for (int c = 0; c < 8; ++c) {
    double w = 1;
    std::array<int, 3> q;
    for (int a = 0; a < 3; ++a) {
      int bit = c >> a & 1;
      q[a] = i0[a] + bit;
      w *= bit ? t[a] : 1 - t[a];
    }
    v += w * grid.values[grid.index(q[0], q[1], q[2])];
  }
  return v;
}

// What a move gains at a neck, of the length (the funnel's noise, seen up to 1e-5).
constexpr double kSlideNoise = 1e-5;

}  // namespace

void slide_to_narrowest(const ScalarGrid& grid, const SurfaceMesh& surface, const MeshAdjacency& adjacency, ShortenResult& best,
                        const ShortenOptions& so, double reach, bool debug) {
  // Probes only compare lengths: a narrower band and no sampling along its cut (a few times cheaper);
  // the loop where the slide stops is then shortened with the full options once.
  ShortenOptions probe_options = so;
  probe_options.max_rings = std::min(so.max_rings, 6);
  probe_options.cut_samples = 0;
  Loop probe;
  probe.points = best.points;
  bool moved = false;
  // Small steps from the current best, repeated while they help, follow a tube that bends.
  double travelled = 0;
  const double length_at_start = best.length;
  for (int round = 0; round < 6 && travelled < reach; ++round) {
    describe_loop(probe);
    const auto n = probe.normal;
    const Polyline3 start = best.points;
    const double length_before = best.length;
    double moved_by = 0;
    // The probes are independent: run them in parallel (a long slide is often the last loop left), then
    // pick in a fixed order, so the result is the sequential one. The first round asks only the near
    // probes: most loops sit at their neck already, and a neck farther away shows in them too.
    const std::array<double, 4> steps{-0.25 * reach, 0.25 * reach, -0.5 * reach, 0.5 * reach};
    const int count = round == 0 ? 2 : 4;
    std::array<ShortenResult, 4> probes;
    std::array<char, 4> ok{0, 0, 0, 0};
    tbb::parallel_for(0, count, [&](int i) {
      Polyline3 moved_points = start;
      for (auto& p : moved_points)
        for (int a = 0; a < 3; ++a) p[a] += steps[i] * n[a];
      // Only a loop on a tube slides along it: every moved point must stay on the surface (|phi|
      // small); otherwise snapping could change its homotopy class.
      double off = 0;
      for (auto& p : moved_points) off = std::max(off, std::abs(phi_at(grid, p)));
      if (off > 2 * grid.voxel_size) return;
      try {
        probes[i] = shorten_polyline(surface, adjacency, moved_points, probe_options);
        ok[i] = 1;
      } catch (const Error&) {
        // the moved loop left the surface (e.g. past the end of the tube)
      }
    });
    // A probe counts when it is shorter by more than the funnel's noise: on a tube of even radius (a
    // hole's wall) probes gained 1e-16 of the length, moved the loop a quarter of the reach for nothing
    // and cost a full shortening more (12 of the 20 slides that moved on the pierced block).
    for (int i = 0; i < count; ++i) {
      ShortenResult& r = probes[i];
      if (ok[i] && r.rings > 0 && r.points.size() >= 3 && loop_is_simple(r.edge_path) &&
          r.length < best.length * (1 - kSlideNoise)) {
        best = std::move(r);
        moved_by = std::abs(steps[i]);
      }
    }
    if (best.length >= length_before) break;
    moved = true;
    // A loop near its neck gains little from a move: slide on only while a round shortens it by a
    // thousandth or more.
    if (best.length > length_before * (1 - 1e-3)) break;
    travelled += moved_by;
    probe.points = best.points;
  }
  if (debug) std::fprintf(stderr, "slide: moved %d travelled %g reach %g length %g gain %g\n", int(moved), travelled, reach, best.length, 1 - best.length / length_at_start);
  if (!moved) return;
  try {
    ShortenResult full = shorten_loop(surface, adjacency, best.edge_path, so);
    if (full.rings > 0 && full.points.size() >= 3 && loop_is_simple(full.edge_path) && full.length <= best.length)
      best = std::move(full);
  } catch (const Error&) {
    // keep the probe's loop
  }
}

}  // namespace chokeloops::detail

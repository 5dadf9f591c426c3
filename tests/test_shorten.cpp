// Loop shortening on extracted surfaces: wiggly meridians become geodesic meridians, loops slide to the
// thinnest section of a varying torus when allowed and stay put when not; the class is kept.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <queue>
#include <random>
#include <unordered_map>

#include "analytic_fields.h"
#include "chokeloops/surface/mesh_adjacency.h"
#include "chokeloops/loops/shorten.h"
#include "chokeloops/surface/surface.h"
#include "chokeloops/surface/topology.h"
#include "loops/flat_int_map.h"
#include "loops/shortener.h"

using namespace chokeloops;

namespace {
// Meridian of a torus (axis z through c, major radius R) at angle phi, wiggled by `amp` in phi.
Polyline3 wiggly_meridian(std::array<double, 3> c, double R, double r, double phi, double amp, int waves, int n = 400) {
  Polyline3 p;
  for (int i = 0; i < n; ++i) {
    double s = 2 * M_PI * i / n;
    double ph = phi + amp * std::sin(waves * s);
    double rho = R + r * std::cos(s);
    p.push_back({c[0] + rho * std::cos(ph), c[1] + rho * std::sin(ph), c[2] + r * std::sin(s)});
  }
  return p;
}
double mean_angle(const Polyline3& p, std::array<double, 3> c) {
  double sx = 0, sy = 0;
  for (auto& q : p) sx += q[0] - c[0], sy += q[1] - c[1];
  return std::atan2(sy, sx);
}
// Every point on a face of the mesh (on an edge of the strip, so within a tiny distance of a face plane).
double max_distance_to_vertices_edges(const SurfaceMesh& m, const Polyline3& p) {
  double worst = 0;
  std::array<double, 3> lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
  for (auto& q : p)
    for (int d = 0; d < 3; ++d) lo[d] = std::min(lo[d], q[d] - 0.02), hi[d] = std::max(hi[d], q[d] + 0.02);
  std::vector<std::array<int, 3>> near;
  for (auto& t : m.faces) {
    auto& a = m.vertices[t[0]];
    bool in = true;
    for (int d = 0; d < 3; ++d) in = in && a[d] >= lo[d] && a[d] <= hi[d];
    if (in) near.push_back(t);
  }
  for (auto& q : p) {
    double best = 1e300;
    for (auto& t : near)
      for (int k = 0; k < 3; ++k) {
        auto& a = m.vertices[t[k]];
        auto& b = m.vertices[t[(k + 1) % 3]];
        double ab[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, aq[3] = {q[0] - a[0], q[1] - a[1], q[2] - a[2]};
        double L = ab[0] * ab[0] + ab[1] * ab[1] + ab[2] * ab[2];
        double s = std::clamp((ab[0] * aq[0] + ab[1] * aq[1] + ab[2] * aq[2]) / L, 0.0, 1.0);
        double d = std::hypot(aq[0] - s * ab[0], aq[1] - s * ab[1], aq[2] - s * ab[2]);
        best = std::min(best, d);
      }
    worst = std::max(worst, best);
  }
  return worst;
}
// The vertices within max_k edge rings of the loop, with their ring and nearness (2 on the loop, 1 next to it),
// as shorten_loop gathers them for the band.
struct LoopRegion {
  detail::DenseIntMap rid;
  std::vector<int> region, ring;
  std::vector<char> near;
};
LoopRegion loop_region(const SurfaceMesh& m, const MeshAdjacency& adj, const std::vector<int>& loop, int max_k) {
  LoopRegion r;
  r.rid = detail::DenseIntMap(m.vertices.size());
  std::vector<int> around;
  for (int v : loop)
    if (r.rid.emplace(v, int(r.region.size()))) r.region.push_back(v), r.ring.push_back(0);
  for (std::size_t i = 0; i < r.region.size(); ++i) {
    if (r.ring[i] >= max_k) continue;
    adj.neighbours(m, r.region[i], around);
    for (int w : around)
      if (r.rid.emplace(w, int(r.region.size()))) r.region.push_back(w), r.ring.push_back(r.ring[i] + 1);
  }
  r.near.resize(r.region.size());
  for (std::size_t i = 0; i < r.region.size(); ++i) r.near[i] = r.ring[i] == 0 ? 2 : r.ring[i] == 1 ? 1 : 0;
  return r;
}

// A wiggly meridian of a thin torus (R 0.3, r 0.1) sampled at n^3, snapped to the surface's edges, with its
// region of max_k rings: the band tests' loop.
struct MeridianOnTorus {
  SurfaceMesh m;
  MeshAdjacency adj;
  std::vector<int> loop;
  LoopRegion region;
};
MeridianOnTorus wiggly_meridian_on_torus(int n, int max_k) {
  MeridianOnTorus t;
  t.m = extract_zero_surface(sample_field({n, n, n}, analytic::torus(0.3, 0.1)));
  t.adj = build_adjacency(t.m);
  t.loop = snap_polyline_to_edge_path(t.m, t.adj, wiggly_meridian({0.5, 0.5, 0.5}, 0.3, 0.1, 0.4, 0.1, 3));
  t.region = loop_region(t.m, t.adj, t.loop, max_k);
  return t;
}
// That meridian's band of `rings` rings with its arcs, ready for searches (`built`: the band is an annulus).
struct MeridianBand {
  MeridianOnTorus torus;
  shorten_detail::Shortener sh;
  bool built = false;
  MeridianBand(int n, int rings) : torus(wiggly_meridian_on_torus(n, rings)), sh(torus.m, torus.adj) {
    const auto& [rid, region, ring, near] = torus.region;
    const auto candidates = shorten_detail::band_candidates(torus.m, torus.adj, region, rid, ring, near, rings);
    built = sh.build_band(candidates, rings, torus.loop);
    if (built) sh.build_arcs();
  }
};
}  // namespace

TEST(Shorten, WigglyMeridianBecomesGeodesicMeridian) {
  const double R = 0.3, r = 0.12;
  auto m = extract_zero_surface(sample_field({128, 128, 128}, analytic::torus(R, r)));
  auto adj = build_adjacency(m);
  auto wiggly = wiggly_meridian({0.5, 0.5, 0.5}, R, r, 0.3, 0.12, 5);
  auto loop = snap_polyline_to_edge_path(m, wiggly);
  auto t0 = std::chrono::steady_clock::now();
  ShortenResult res = shorten_loop(m, adj, loop, ShortenOptions{0, 12, 5000});
  std::printf("shorten: %.3f s\n", std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  const double target = 2 * M_PI * r;
  std::printf("meridian: input %.4f edge path %.4f final %.4f (target %.4f) rings %d swaps %d points %zu\n",
              res.input_length, res.edge_path_length, res.length, target, res.rings, res.swaps, res.points.size());
  EXPECT_GT(res.rings, 0);
  EXPECT_LT(res.length, res.edge_path_length);
  EXPECT_NEAR(res.length, target, 0.03 * target);
  EXPECT_NEAR(closed_length(res.points), res.length, 1e-9);
  EXPECT_LT(max_distance_to_vertices_edges(m, res.points), 1e-9);  // points lie on mesh edges
  // Same class: the edge path is still an essential, non-separating loop.
  SurfaceTopology topo(m);
  EXPECT_FALSE(topo.contractible(res.edge_path));
  EXPECT_FALSE(topo.separates(res.edge_path));
  auto snapped_back = snap_polyline_to_edge_path(m, res.points);
  EXPECT_FALSE(topo.contractible(snapped_back));
  // A meridian lies in a plane through the axis: every point at distance r from the tube's core circle.
  for (auto& q : res.points) {
    double rho = std::hypot(q[0] - 0.5, q[1] - 0.5);
    EXPECT_NEAR(std::hypot(rho - R, q[2] - 0.5), r, 0.01);
  }
}

TEST(Shorten, LongitudeTightensToInnerEquator) {
  // The shortest loop homotopic to the outer equator (length 2*pi*(R+r)) is the inner equator 2*pi*(R-r).
  const double R = 0.3, r = 0.12;
  auto m = extract_zero_surface(sample_field({96, 96, 96}, analytic::torus(R, r)));
  auto adj = build_adjacency(m);
  Polyline3 top;  // the top circle (z = r), halfway to the inner equator
  for (int i = 0; i < 300; ++i) {
    double t = 2 * M_PI * i / 300;
    top.push_back({0.5 + R * std::cos(t), 0.5 + R * std::sin(t), 0.5 + r});
  }
  auto res = shorten_polyline(m, adj, top, ShortenOptions{0, 40, 400});
  std::printf("longitude: input %.4f edge %.4f final %.4f target %.4f rings %d swaps %d\n", res.input_length,
              res.edge_path_length, res.length, 2 * M_PI * (R - r), res.rings, res.swaps);
  EXPECT_NEAR(res.length, 2 * M_PI * (R - r), 0.03 * 2 * M_PI * (R - r));
}

TEST(Shorten, VaryingTorusLoopSlidesToThinnestSectionWhenAllowed) {
  // r(t) = 0.15 + 0.06 cos t around R = 0.5: thinnest (0.09) at t = pi.
  const int n = 128;
  auto g = sample_field({n, n, n}, analytic::varying_torus(), {-0.3, -0.3, -0.3}, {1.3, 1.3, 1.3});
  auto m = extract_zero_surface(g);
  auto adj = build_adjacency(m);
  const double t0 = M_PI - 0.5;
  const double r0 = 0.15 + 0.06 * std::cos(t0);
  auto start = snap_polyline_to_edge_path(m, wiggly_meridian({0.5, 0.5, 0.5}, 0.5, r0, t0, 0.0, 1));
  auto far = shorten_loop(m, adj, start, ShortenOptions{0, 60, 400});
  double ang = mean_angle(far.points, {0.5, 0.5, 0.5});
  if (ang < 0) ang += 2 * M_PI;
  std::printf("varying torus: start angle %.3f len %.4f -> angle %.3f len %.4f (thinnest %.4f) rings %d swaps %d\n", t0,
              far.input_length, ang, far.length, 2 * M_PI * 0.09, far.rings, far.swaps);
  EXPECT_GT(far.rings, 0);
  EXPECT_NEAR(ang, M_PI, 2 * g.voxel_size / 0.5);  // within ~2 voxels along the core circle
  EXPECT_NEAR(far.length, 2 * M_PI * 0.09, 0.05 * 2 * M_PI * 0.09);
  // With a short leash the loop shortens but stays near its start.
  const double leash = 0.05;
  auto near = shorten_loop(m, adj, start, ShortenOptions{leash, 60, 400});
  double ang2 = mean_angle(near.points, {0.5, 0.5, 0.5});
  if (ang2 < 0) ang2 += 2 * M_PI;
  std::printf("leashed: angle %.3f len %.4f rings %d\n", ang2, near.length, near.rings);
  EXPECT_LT(near.length, near.input_length);
  EXPECT_GT(near.length, far.length);
  EXPECT_LT(std::fabs(ang2 - t0) * 0.5, leash + 2 * g.voxel_size);
  const auto start_pts = loop_points(m, start);
  auto farthest_from_start = [&](const Polyline3& points) {  // the farthest any point lies from the start loop
    double farthest = 0;
    for (auto& q : points) {
      double best = 1e300;
      for (auto& p : start_pts) best = std::min(best, std::hypot(q[0] - p[0], q[1] - p[1], q[2] - p[2]));
      farthest = std::max(farthest, best);
    }
    return farthest;
  };
  EXPECT_LE(farthest_from_start(near.points), leash + g.voxel_size);  // no point moved farther than the leash (plus one edge)
  // The region's surface distances are computed only when some vertex's path from the loop is longer than
  // the leash: a leash longer than any such path must give the loop of no leash at all, and every leash
  // must hold its loop.
  auto loose = shorten_loop(m, adj, start, ShortenOptions{100.0, 60, 400});
  EXPECT_EQ(loose.points, far.points);
  EXPECT_EQ(loose.at_band_edge, far.at_band_edge);
  for (double l : {0.03, 0.1, 0.2}) {
    auto held = shorten_loop(m, adj, start, ShortenOptions{l, 60, 400});
    EXPECT_LE(farthest_from_start(held.points), l + g.voxel_size) << "leash " << l;
    EXPECT_LE(held.length, held.input_length) << "leash " << l;
  }
  // The loop tracer slides a loop on only when it stopped at its band's edge: the unleashed loop found the
  // thinnest section inside its band, the leashed one was held back by the leash.
  EXPECT_FALSE(far.at_band_edge);
  EXPECT_TRUE(near.at_band_edge);
  // A loop starting at the thinnest section stays clear of its leash.
  auto at_neck = snap_polyline_to_edge_path(m, wiggly_meridian({0.5, 0.5, 0.5}, 0.5, 0.09, M_PI, 0.0, 1));
  auto settled = shorten_loop(m, adj, at_neck, ShortenOptions{leash, 60, 400});
  EXPECT_GT(settled.rings, 0);
  EXPECT_FALSE(settled.at_band_edge);
  EXPECT_NEAR(settled.length, 2 * M_PI * 0.09, 0.05 * 2 * M_PI * 0.09);
}

// A narrow band first: a loop that settles inside it is returned from it; one that runs to its edge (the
// neck lies farther off) is shortened again in the full band, from the input loop, as without it.
TEST(Shorten, NarrowBandFirstWidensOnlyAtItsEdge) {
  const int n = 128;
  auto g = sample_field({n, n, n}, analytic::varying_torus(), {-0.3, -0.3, -0.3}, {1.3, 1.3, 1.3});
  auto m = extract_zero_surface(g);
  auto adj = build_adjacency(m);
  auto start = snap_polyline_to_edge_path(m, wiggly_meridian({0.5, 0.5, 0.5}, 0.5, 0.15 + 0.06 * std::cos(M_PI - 0.5), M_PI - 0.5, 0.0, 1));
  ShortenOptions full{0, 60, 400}, narrow_first = full;
  narrow_first.first_rings = 4;
  const auto far = shorten_loop(m, adj, start, full);
  const auto widened = shorten_loop(m, adj, start, narrow_first);
  EXPECT_GT(far.rings, 4);
  EXPECT_EQ(widened.rings, far.rings);
  EXPECT_EQ(widened.points, far.points);
  // Alone, the narrow band stops the loop at its edge, well short of the neck.
  ShortenOptions narrow_only = full;
  narrow_only.max_rings = 4;
  const auto held = shorten_loop(m, adj, start, narrow_only);
  EXPECT_TRUE(held.at_band_edge);
  EXPECT_GT(held.length, far.length * 1.05);
  // At the neck the narrow band's loop is the answer.
  auto at_neck = snap_polyline_to_edge_path(m, wiggly_meridian({0.5, 0.5, 0.5}, 0.5, 0.09, M_PI, 0.0, 1));
  const auto settled = shorten_loop(m, adj, at_neck, narrow_first);
  EXPECT_EQ(settled.rings, 4);
  EXPECT_FALSE(settled.at_band_edge);
  EXPECT_NEAR(settled.length, 2 * M_PI * 0.09, 0.05 * 2 * M_PI * 0.09);
}

// Where the bands wider than the narrow one wrap round the tube, the full band comes out the narrow band, and
// its loop is the narrow band's loop, taken again without its searches: the same result, point for point, as
// the full band alone.
TEST(Shorten, AWidenedBandThatIsTheNarrowOneGivesItsLoop) {
  const double R = 0.3, r = 0.02;
  auto m = extract_zero_surface(sample_field({96, 96, 96}, analytic::torus(R, r)));
  auto adj = build_adjacency(m);
  Polyline3 wavy;  // round the hole on the tube's top, waving up and down its side
  for (int i = 0; i < 300; ++i) {
    const double t = 2 * M_PI * i / 300, v = 0.5 * M_PI + 0.6 * std::sin(5 * t);
    wavy.push_back({0.5 + (R + r * std::cos(v)) * std::cos(t), 0.5 + (R + r * std::cos(v)) * std::sin(t), 0.5 + r * std::sin(v)});
  }
  const auto loop = snap_polyline_to_edge_path(m, adj, wavy);
  ShortenOptions full{0, 12, 400}, narrow_first = full;
  narrow_first.first_rings = 8;
  const auto alone = shorten_loop(m, adj, loop, full);
  const auto widened = shorten_loop(m, adj, loop, narrow_first);
  ASSERT_GT(alone.rings, 0);
  EXPECT_LE(alone.rings, 8);        // wider bands wrap round the tube
  EXPECT_TRUE(alone.at_band_edge);  // so the narrow band's loop, at its edge too, was widened
  EXPECT_EQ(widened.rings, alone.rings);
  EXPECT_EQ(widened.edge_path, alone.edge_path);
  EXPECT_EQ(widened.points, alone.points);
  EXPECT_EQ(widened.length, alone.length);
  EXPECT_EQ(widened.at_band_edge, alone.at_band_edge);
  EXPECT_NEAR(alone.length, 2 * M_PI * (R - r), 0.05 * 2 * M_PI * (R - r));
}

// Step 3 starts from the band's shortest plane section near the edge loop's plane: the edge loop that step 2
// finds a few edges from a tube's neck reaches it in a few swap rounds instead of one vertex row per round.
TEST(Shorten, PlaneSectionsStartTheSwapsAtTheNeck) {
  const int n = 128;
  auto g = sample_field({n, n, n}, analytic::varying_torus(), {-0.3, -0.3, -0.3}, {1.3, 1.3, 1.3});
  auto m = extract_zero_surface(g);
  auto adj = build_adjacency(m);
  const double t0 = M_PI - 0.12;  // 0.06 from the neck along the core circle: inside a 12-ring band
  auto start = snap_polyline_to_edge_path(m, wiggly_meridian({0.5, 0.5, 0.5}, 0.5, 0.15 + 0.06 * std::cos(t0), t0, 0.0, 1));
  ShortenOptions o{0, 12, 5000};
  o.cut_samples = 0;  // as the loop tracer runs it: the edge loop stays near its start
  const ShortenResult with = shorten_loop(m, adj, start, o);
  o.plane_sections = false;
  const ShortenResult without = shorten_loop(m, adj, start, o);
  auto angle = [](const Polyline3& p) {
    const double a = mean_angle(p, {0.5, 0.5, 0.5});
    return a < 0 ? a + 2 * M_PI : a;
  };
  std::printf("neck from %.3f: with sections %.6f at %.4f (%d swaps), without %.6f at %.4f (%d swaps)\n", t0, with.length,
              angle(with.points), with.swaps, without.length, angle(without.points), without.swaps);
  ASSERT_GT(with.rings, 0);
  EXPECT_EQ(with.edge_path, without.edge_path);  // steps 1 and 2 are the same
  EXPECT_NEAR(angle(with.points), M_PI, 2 * g.voxel_size / 0.5);
  EXPECT_NEAR(angle(without.points), M_PI, 2 * g.voxel_size / 0.5);
  EXPECT_LE(with.length, without.length * (1 + 1e-5));
  EXPECT_LT(2 * with.swaps, without.swaps);
  EXPECT_NEAR(closed_length(with.points), with.length, 1e-9);
  EXPECT_LT(max_distance_to_vertices_edges(m, with.points), 1e-9);
  SurfaceTopology topo(m);
  EXPECT_FALSE(topo.contractible(snap_polyline_to_edge_path(m, adj, with.points)));
}

// The band's sections: the meridian plane of the wiggly meridian's band cuts it in one closed section round
// the tube that winds like the loop (and like the strip of the loop's own edges); a plane square to it
// cuts the band only across, in arcs that leave it.
TEST(Shorten, PlaneSectionOfTheBandWindsLikeTheLoop) {
  MeridianBand b(96, 12);
  ASSERT_TRUE(b.built);
  auto& sh = b.sh;
  std::vector<int> edge_strip;
  ASSERT_TRUE(sh.strip_from_edge_loop(b.torus.loop, edge_strip));
  EXPECT_EQ(sh.strip_winding(edge_strip), sh.band.winding);
  std::vector<int> reversed(edge_strip.rbegin(), edge_strip.rend());
  EXPECT_EQ(sh.strip_winding(reversed), -sh.band.winding);
  const double phi = 0.4;  // the meridian's plane, through the torus's axis
  std::vector<int> S;
  const double length = sh.shortest_plane_section({0.5, 0.5, 0.5}, {-std::sin(phi), std::cos(phi), 0}, S);
  std::printf("meridian plane section: %.6f (2 pi r %.6f), %zu faces\n", length, 2 * M_PI * 0.1, S.size());
  ASSERT_FALSE(S.empty());
  EXPECT_NEAR(length, 2 * M_PI * 0.1, 0.01 * 2 * M_PI * 0.1);
  EXPECT_TRUE(sh.portals_ok(S));
  EXPECT_EQ(sh.strip_winding(S), sh.band.winding);
  for (int f : S) EXPECT_TRUE(sh.face_in(f));
  std::vector<int> S2;
  EXPECT_FALSE(std::isfinite(sh.shortest_plane_section({0.5 + 0.3 * std::cos(phi), 0.5 + 0.3 * std::sin(phi), 0.5},
                                                        {std::cos(phi), std::sin(phi), 0}, S2)));
  EXPECT_TRUE(S2.empty());
  // Far from the band no plane cuts it at all.
  EXPECT_FALSE(std::isfinite(sh.shortest_plane_section({0.5, 0.5, 0.5}, {-std::sin(phi + 1.5), std::cos(phi + 1.5), 0}, S2)));
  // Any plane near the meridian's: no strip, or a whole strip of band faces winding like the loop whose section is as long as
  // returned (measured here from the strip's own portals).
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  int strips = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const std::array<double, 3> at{0.5 + 0.3 * std::cos(phi) + 0.05 * u(rng), 0.5 + 0.3 * std::sin(phi) + 0.05 * u(rng), 0.5 + 0.05 * u(rng)};
    // Tilted from the meridian plane by up to ~20 degrees, so that many of them close round the tube.
    std::array<double, 3> n{-std::sin(phi) + 0.35 * u(rng), std::cos(phi) + 0.35 * u(rng), 0.35 * u(rng)};
    const double norm = std::hypot(n[0], n[1], n[2]);
    for (double& c : n) c /= norm;
    std::vector<int> T;
    const double l = sh.shortest_plane_section(at, n, T);
    if (T.empty()) {
      EXPECT_FALSE(std::isfinite(l));
      continue;
    }
    ++strips;
    EXPECT_TRUE(sh.portals_ok(T));
    EXPECT_EQ(sh.strip_winding(T), sh.band.winding);
    double along = 0;
    std::vector<std::array<double, 3>> cross;
    for (std::size_t j = 0; j < T.size(); ++j) {
      const int h = sh.portal_of(T[j], T[(j + 1) % T.size()]);
      const auto& a = b.torus.m.vertices[std::size_t(sh.vert(h))];
      const auto& c = b.torus.m.vertices[std::size_t(sh.vert_to(h))];
      const double ha = (a[0] - at[0]) * n[0] + (a[1] - at[1]) * n[1] + (a[2] - at[2]) * n[2];
      const double hc = (c[0] - at[0]) * n[0] + (c[1] - at[1]) * n[1] + (c[2] - at[2]) * n[2];
      const double t = ha / (ha - hc);
      cross.push_back({a[0] + t * (c[0] - a[0]), a[1] + t * (c[1] - a[1]), a[2] + t * (c[2] - a[2])});
    }
    for (std::size_t j = 0; j < cross.size(); ++j) {
      const auto& p = cross[j];
      const auto& q = cross[(j + 1) % cross.size()];
      along += std::hypot(q[0] - p[0], q[1] - p[1], q[2] - p[2]);
    }
    EXPECT_NEAR(along, l, 1e-9);
  }
  std::printf("random planes: %d of 300 cut the band in a section winding like the loop\n", strips);
  EXPECT_GT(strips, 30);
}

TEST(Shorten, DoubleTorusHandleMeridianStaysEssential) {
  auto m = extract_zero_surface(sample_field({128, 128, 128}, analytic::double_torus()));
  auto adj = build_adjacency(m);
  // Left torus (centre x = 0.33, R = 0.17, r = 0.07): a tilted, wiggly loop around its far-side tube.
  auto wig = wiggly_meridian({0.33, 0.5, 0.5}, 0.17, 0.07, M_PI, 0.2, 3);
  auto res = shorten_polyline(m, adj, wig, ShortenOptions{0, 10, 5000});
  std::printf("double torus: input %.4f final %.4f target %.4f rings %d swaps %d\n", res.input_length, res.length,
              2 * M_PI * 0.07, res.rings, res.swaps);
  EXPECT_NEAR(res.length, 2 * M_PI * 0.07, 0.03 * 2 * M_PI * 0.07);
  SurfaceTopology topo(m);
  EXPECT_FALSE(topo.contractible(res.edge_path));
  EXPECT_FALSE(topo.contractible(snap_polyline_to_edge_path(m, adj, res.points)));
  EXPECT_FALSE(topo.separates(res.edge_path));
}

TEST(Shorten, CostFollowsTheLoopNotTheMesh) {
  // 256^3 torus (about a million faces): shortening one meridian touches a band around it, not the mesh.
  // (Its time is measured in bench/, not asserted here.)
  const double R = 0.3, r = 0.12;
  auto m = extract_zero_surface(sample_field({256, 256, 256}, analytic::torus(R, r)));
  auto adj = build_adjacency(m);
  auto loop = snap_polyline_to_edge_path(m, adj, wiggly_meridian({0.5, 0.5, 0.5}, R, r, 1.0, 0.05, 4));
  auto t0 = std::chrono::steady_clock::now();
  auto res = shorten_loop(m, adj, loop, ShortenOptions{0, 8, 5000});
  double sec = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("256^3 meridian (%zu faces): %.4f -> %.4f (target %.4f) in %.3f s, swaps %d\n", m.faces.size(),
              res.input_length, res.length, 2 * M_PI * r, sec, res.swaps);
  EXPECT_NEAR(res.length, 2 * M_PI * r, 0.01 * 2 * M_PI * r);
  EXPECT_LE(res.rings, 8);
  EXPECT_LT(res.strip_faces.size(), m.faces.size() / 200);
}

TEST(Shorten, DumbbellNeckLoopIsKeptAroundTheNeck) {
  // A contractible but separating loop around a neck stays around the neck (the band is an annulus).
  auto m = extract_zero_surface(sample_field({96, 96, 96}, analytic::dumbbell()));
  auto adj = build_adjacency(m);
  Polyline3 ring;
  for (int i = 0; i < 200; ++i) {
    double t = 2 * M_PI * i / 200;
    ring.push_back({0.5 + 0.02 * std::sin(3 * t), 0.5 + 0.12 * std::cos(t), 0.5 + 0.12 * std::sin(t)});
  }
  auto res = shorten_polyline(m, adj, ring, ShortenOptions{0, 8, 200});
  std::printf("neck: input %.4f final %.4f target %.4f rings %d\n", res.input_length, res.length, 2 * M_PI * 0.12, res.rings);
  EXPECT_GT(res.rings, 0);
  EXPECT_NEAR(res.length, 2 * M_PI * 0.12, 0.03 * 2 * M_PI * 0.12);
  EXPECT_TRUE(loop_separates_surface(m, res.edge_path));
}

TEST(Shorten, RejectsBrokenLoops) {
  auto m = extract_zero_surface(sample_field({24, 24, 24}, analytic::ball(0.3)));
  EXPECT_THROW(shorten_loop(m, std::vector<int>{}), Error);
  EXPECT_THROW(shorten_loop(m, std::vector<int>{0, 5, 77, 300}), Error);
}

// The shortener's band map against std::unordered_map: clustered and scattered keys, through several growths.
TEST(Shorten, FlatIntMapAgreesWithUnorderedMap) {
  detail::FlatIntMap flat;
  std::unordered_map<int, int> reference;
  std::mt19937 rng(7);
  for (int i = 0; i < 20000; ++i) {
    const int key = i % 3 == 0 ? int(rng() % 1000) : int(rng() % 50000000);
    const int value = int(rng() % 100) - 50;
    const bool inserted = reference.emplace(key, value).second;
    EXPECT_EQ(flat.emplace(key, value), inserted);
    if (i % 5 == 0) flat[key] += 3, reference[key] += 3;
  }
  EXPECT_EQ(flat.size(), reference.size());
  for (auto& [k, v] : reference) {
    ASSERT_NE(flat.find(k), nullptr);
    EXPECT_EQ(*flat.find(k), v);
    EXPECT_EQ(flat.at(k), v);
  }
  for (int k = 50000000; k < 50001000; ++k) EXPECT_FALSE(flat.contains(k));
  EXPECT_EQ(flat.find(-1), nullptr);
  EXPECT_THROW(flat.emplace(-1, 0), std::invalid_argument);
  EXPECT_THROW(flat.at(50000001), std::out_of_range);
  EXPECT_EQ(flat[123456789], 0);  // inserted as 0, as std::unordered_map's operator[]
  EXPECT_EQ(flat.size(), reference.size() + 1);
}

// The band's dense maps against std::unordered_map, and their pooled arrays: a map made after others went
// back to the pool (some on a bigger id range) holds none of their keys.
TEST(Shorten, DenseIntMapAgreesWithUnorderedMapAndStartsEmptyFromThePool) {
  std::mt19937 rng(11);
  for (int round = 0; round < 4; ++round) {
    const int keys = round % 2 ? 300000 : 90000;
    std::vector<detail::DenseIntMap> alive;  // several at once: several arrays in the pool
    for (int m = 0; m < 3; ++m) {
      detail::DenseIntMap dense{std::size_t(keys)};
      std::unordered_map<int, int> reference;
      EXPECT_EQ(dense.size(), 0u);
      for (int i = 0; i < 20000; ++i) {
        const int key = i % 3 == 0 ? int(rng() % 1000) : int(rng() % std::uint32_t(keys));
        ASSERT_EQ(dense.contains(key), reference.count(key) == 1) << "round " << round << " key " << key;
        const int value = int(rng() % 100) - 50;
        const bool inserted = reference.emplace(key, value).second;
        EXPECT_EQ(dense.emplace(key, value), inserted);
        if (i % 5 == 0) dense[key] += 3, reference[key] += 3;
      }
      EXPECT_EQ(dense.size(), reference.size());
      for (auto& [k, v] : reference) {
        ASSERT_NE(dense.find(k), nullptr);
        EXPECT_EQ(dense.at(k), v);
      }
      EXPECT_EQ(dense.find(-1), nullptr);
      EXPECT_EQ(dense.find(keys + 5000000), nullptr);
      EXPECT_THROW(dense.emplace(-1, 0), std::out_of_range);
      EXPECT_THROW(dense.emplace(keys + 5000000, 0), std::out_of_range);
      int absent = keys - 1;
      while (reference.count(absent)) --absent;
      EXPECT_THROW(dense.at(absent), std::out_of_range);
      alive.push_back(std::move(dense));
    }
  }
  detail::DenseIntMap empty;
  EXPECT_FALSE(empty.contains(0));
  EXPECT_THROW(empty[0], std::out_of_range);
}

// The ring region's surface distances (the Dijkstra over the arcs its BFS kept, and over the mesh for the
// last ring) against a plain Dijkstra over the mesh's neighbours through the same vertices; its rings against
// a plain BFS, its upper bounds above the distances. Both neighbour paths of the adjacency (closed and
// oriented, and the general one); the arcs kept, not kept, and dropped halfway for want of room.
TEST(Shorten, RingRegionDistancesAreThoseOfADijkstraOverTheMesh) {
  const int rings = 8;
  MeridianOnTorus t = wiggly_meridian_on_torus(64, rings);
  struct Case { bool closed_oriented, keep_arcs; std::size_t max_arcs; };
  for (const Case& k : {Case{true, true, std::size_t(1) << 22}, Case{false, true, std::size_t(1) << 22},
                        Case{true, false, std::size_t(1) << 22}, Case{true, true, 1000}}) {
    MeshAdjacency adj = t.adj;
    ASSERT_TRUE(t.adj.closed_oriented);
    adj.closed_oriented = k.closed_oriented;
    const shorten_detail::RingRegion rr(t.m, adj, t.loop, rings, k.keep_arcs, k.max_arcs);
    EXPECT_EQ(rr.kept_arcs(), k.keep_arcs && k.max_arcs > 1000);
    ASSERT_EQ(rr.vertices.size(), t.region.region.size());
    for (std::size_t i = 0; i < rr.vertices.size(); ++i)
      ASSERT_EQ(rr.ring[i], t.region.ring[std::size_t(t.region.rid.at(rr.vertices[i]))]) << "vertex " << rr.vertices[i];
    // The reference: every arc between two region vertices, from the sorted neighbour lists.
    const std::size_t n = rr.vertices.size();
    std::vector<double> reference(n, std::numeric_limits<double>::infinity());
    using QE = std::pair<double, int>;
    std::priority_queue<QE, std::vector<QE>, std::greater<QE>> q;
    for (int v : t.loop) reference[std::size_t(rr.index.at(v))] = 0, q.push({0.0, rr.index.at(v)});
    std::vector<int> around;
    while (!q.empty()) {
      const auto [d, i] = q.top();
      q.pop();
      if (d > reference[std::size_t(i)]) continue;
      const int v = rr.vertices[std::size_t(i)];
      adj.neighbours(t.m, v, around);
      for (int w : around) {
        const int* wi = rr.index.find(w);
        if (!wi) continue;
        const double nd = d + shorten_detail::dist3(t.m.vertices[std::size_t(v)], t.m.vertices[std::size_t(w)]);
        if (nd < reference[std::size_t(*wi)]) reference[std::size_t(*wi)] = nd, q.push({nd, *wi});
      }
    }
    const double farthest = *std::max_element(reference.begin(), reference.end());
    ASSERT_TRUE(std::isfinite(farthest));
    for (std::size_t i = 0; i < n; ++i) ASSERT_GE(rr.upper[i], reference[i] * (1 - 1e-12)) << "vertex " << rr.vertices[i];
    EXPECT_GT(rr.upper_max, 0.25 * farthest);
    for (double max_move : {0.25 * farthest, 0.6 * farthest, 2 * farthest}) {
      std::vector<double> dist;
      rr.surface_distances(max_move, dist);
      ASSERT_EQ(dist.size(), n);
      int within = 0;
      for (std::size_t i = 0; i < n; ++i) {
        if (reference[i] <= max_move) {
          ++within;
          ASSERT_DOUBLE_EQ(dist[i], reference[i]) << "vertex " << rr.vertices[i] << " max_move " << max_move;
        } else {
          ASSERT_GT(dist[i], max_move) << "vertex " << rr.vertices[i];
        }
      }
      EXPECT_GT(within, int(t.loop.size()));
      if (max_move > farthest) EXPECT_EQ(within, int(n));
    }
  }
}

// The band's candidate faces and the Euler characteristics that refuse a ring count unbuilt: for every ring
// count, the faces are those the band's rule takes (each vertex allowed, or next to the loop for a face that
// touches it and has an allowed vertex), and the characteristic is that of the band built from them. A
// meridian of a thin torus whose band wraps round the tube as it widens, with and without vertices barred
// (holes in the band, and faces that enter only because they touch the loop).
TEST(Shorten, BandCandidatesAndEulerCharacteristicForEveryRingCount) {
  const int max_k = 40;
  const MeridianOnTorus torus = wiggly_meridian_on_torus(40, max_k);
  const auto& [m, adj, loop, lr] = torus;
  // Named, not bound: the lambdas below capture rid and near (C++17).
  const auto& rid = lr.rid;
  const auto& near = lr.near;
  const auto &region = lr.region, &ring = lr.ring;
  int annuli = 0, not_annuli = 0, touching_only = 0;
  for (int barred_every : {0, 7}) {
    std::vector<int> entry = ring;
    if (barred_every)
      for (std::size_t i = 0; i < region.size(); i += std::size_t(barred_every)) entry[i] = max_k + 1;
    const auto c = shorten_detail::band_candidates(m, adj, region, rid, entry, near, max_k);
    ASSERT_EQ(c.euler.size(), std::size_t(max_k) + 1);
    ASSERT_TRUE(std::is_sorted(c.faces.begin(), c.faces.end()));
    shorten_detail::Shortener sh(m, adj);
    for (int k = 1; k <= max_k; ++k) {
      auto allowed = [&](int v) { const int* i = rid.find(v); return i && entry[std::size_t(*i)] <= k; };
      auto near_of = [&](int v) { const int* i = rid.find(v); return i ? int(near[std::size_t(*i)]) : 0; };
      std::vector<int> expected;
      for (std::size_t f = 0; f < m.faces.size(); ++f) {
        const auto& t = m.faces[f];
        int n_allowed = 0, n_ok = 0;
        bool touches = false;
        for (int j = 0; j < 3; ++j) {
          n_allowed += allowed(t[j]);
          n_ok += allowed(t[j]) || near_of(t[j]) > 0;
          touches |= near_of(t[j]) == 2;
        }
        if (n_allowed == 3 || (n_allowed > 0 && n_ok == 3 && touches)) expected.push_back(int(f));
        touching_only += n_allowed > 0 && n_allowed < 3 && n_ok == 3 && touches;
      }
      std::vector<int> got;
      for (std::size_t i = 0; i < c.faces.size(); ++i)
        if (c.entry[i] <= k) got.push_back(c.faces[i]);
      ASSERT_EQ(got, expected) << "k " << k << ", barred every " << barred_every;
      const bool annulus = sh.build_band(c, k, loop);
      long V = long(sh.band.global.size()), F = long(sh.band.faces.size()), E = 0;
      for (int f : sh.band.faces)
        for (int j = 0; j < 3; ++j) {
          const int h = 3 * f + j, t = adj.twin[std::size_t(h)];
          E += !(t >= 0 && sh.band.in_face.contains(t / 3)) || h < t;
        }
      EXPECT_EQ(F, long(expected.size()));
      EXPECT_EQ(c.euler[std::size_t(k)], V - E + F) << "k " << k << ", barred every " << barred_every;
      if (annulus) EXPECT_EQ(c.euler[std::size_t(k)], 0);
      (c.euler[std::size_t(k)] == 0 ? annuli : not_annuli) += 1;
    }
  }
  EXPECT_GT(annuli, 0);
  EXPECT_GT(not_annuli, 0);
  EXPECT_GT(touching_only, 0);
}

// Step 3's rounds redo the funnel only in windows around the swaps (Shortener::refunnel), or once round the
// strip held at an apex the swaps left (Shortener::funnel_through_apex): after every round, either must give
// the loop a funnel over the whole strip gives (relax), on a torus whose strip unfolds without overlapping
// itself. A very wiggly meridian's own edge loop makes many rounds with swaps far apart. Held at a vertex
// the shortest loop does not pass through, the funnel through it must see so and still give that loop.
TEST(Shorten, FunnelRedoneInWindowsOrThroughAnApexEqualsTheFunnelOverTheWholeStrip) {
  const double R = 0.3, r = 0.12;
  auto m = extract_zero_surface(sample_field({128, 128, 128}, analytic::torus(R, r)));
  auto adj = build_adjacency(m);
  auto loop = snap_polyline_to_edge_path(m, adj, wiggly_meridian({0.5, 0.5, 0.5}, R, r, 0.3, 0.15, 7));
  const int max_k = 12;
  const LoopRegion lr = loop_region(m, adj, loop, max_k);
  const auto candidates = shorten_detail::band_candidates(m, adj, lr.region, lr.rid, lr.ring, lr.near, max_k);
  shorten_detail::Shortener sh(m, adj);
  ASSERT_TRUE(sh.build_band(candidates, max_k, loop));
  std::vector<int> S;
  ASSERT_TRUE(sh.strip_from_edge_loop(loop, S));
  std::vector<double> s(S.size(), 0.5);
  std::vector<shorten_detail::Shortener::Apex> apexes;
  double L = sh.relax(S, 0, s, apexes);
  const double first = L;
  int rounds = 0;
  for (; rounds < 400; ++rounds) {
    std::vector<int> S2 = S;
    std::vector<double> s2 = s;
    std::vector<shorten_detail::Shortener::Apex> kept, whole_apexes;
    std::vector<std::array<int, 2>> dirty;
    if (!sh.swap_batch(S2, s2, apexes, 1 << 30, kept, dirty)) break;
    // swap_batch checks only the portals of its new runs: the strip must still be whole.
    ASSERT_TRUE(sh.portals_ok(S2)) << "round " << rounds;
    std::vector<double> whole = s2, through_apex = s2;
    std::vector<shorten_detail::Shortener::Apex> apex_kept = kept;
    const double L_whole = sh.relax(S2, 0, whole, whole_apexes);
    const double L_apex = sh.funnel_through_apex(S2, through_apex, apex_kept, dirty);
    const double L_windows = sh.refunnel(S2, s2, kept, dirty);
    ASSERT_NEAR(L_windows, L_whole, 1e-9 * L_whole) << "round " << rounds;
    ASSERT_NEAR(L_apex, L_whole, 1e-9 * L_whole) << "round " << rounds;
    if (!(L_windows < L + 1e-9 * L)) break;
    S.swap(S2), s.swap(s2), apexes.swap(kept), L = L_windows;
  }
  std::printf("wiggly meridian: edge loop relaxed %.6f -> %.6f after %d rounds (%d windows, %d whole-strip funnels; "
              "%d funnels through an apex, %d of those calls relaxed), 2 pi r %.6f\n",
              first, L, rounds, sh.refunnel_windows, sh.refunnel_fallbacks, sh.apex_funnels, sh.apex_funnels_relaxed, 2 * M_PI * r);
  EXPECT_GT(rounds, 10);
  EXPECT_GT(sh.refunnel_windows, 20);
  EXPECT_GE(sh.apex_funnels, rounds);
  EXPECT_LT(sh.apex_funnels_relaxed, rounds / 4);
  // Held at the far end of a portal the loop crosses inside (not at an apex): the loop pulls off it.
  int wrong_vertices = 0;
  for (int p = 0; p < int(S.size()); p += 7) {
    if (s[std::size_t(p)] < 0.05 || s[std::size_t(p)] > 0.95) continue;
    const int h = sh.portal_of(S[std::size_t(p)], S[std::size_t(p + 1) % S.size()]);
    const int far_end = s[std::size_t(p)] < 0.5 ? sh.vert_to(h) : sh.vert(h);  // s = 0 is vert(h)
    std::vector<double> held = s;
    std::vector<shorten_detail::Shortener::Apex> one{{p, far_end}};
    const int funnels_before = sh.apex_funnels;
    const double L_held = sh.funnel_through_apex(S, held, one, {});
    ASSERT_NEAR(L_held, L, 1e-9 * L) << "portal " << p;
    EXPECT_GE(sh.apex_funnels - funnels_before, 2) << "portal " << p;  // the first cut cannot be kept
    ++wrong_vertices;
  }
  EXPECT_GT(wrong_vertices, 10);
  EXPECT_LT(L, first);
  EXPECT_NEAR(L, 2 * M_PI * r, 0.03 * 2 * M_PI * r);
}

// The search for the shortest edge loop through a vertex runs either way round the band (the caller picks
// the way that takes fewer nodes): both give a loop of the same length, through the vertex and starting
// there, joined by mesh edges, winding as the input loop does across the cut; and the choice follows where
// the cut lies on the loop. A wiggly meridian of a torus, from every twentieth vertex of its band.
TEST(Shorten, SearchEitherWayRoundGivesTheSameLoopLength) {
  MeridianBand band(48, 6);
  ASSERT_TRUE(band.built);
  const auto& [m, adj, loop, lr] = band.torus;
  auto& sh = band.sh;
  int searched = 0, near_ahead = 0;
  for (std::size_t v = 0; v < sh.band.global.size(); v += 20) {
    double forward_length = 0, backward_length = 0;
    const auto forward = sh.shortest_loop_through(int(v), forward_length, false);
    const auto backward = sh.shortest_loop_through(int(v), backward_length, true);
    ASSERT_FALSE(forward.empty());
    ASSERT_FALSE(backward.empty());
    EXPECT_NEAR(backward_length, forward_length, 1e-12 * forward_length) << "band vertex " << v;
    for (const auto* path : {&forward, &backward}) {
      ASSERT_EQ(path->front(), sh.band.global[v]);
      int winding = 0;
      double length = 0;
      for (std::size_t i = 0; i < path->size(); ++i) {
        const int a = (*path)[i], b = (*path)[(i + 1) % path->size()];
        ASSERT_TRUE(adj.has_edge(m, a, b));
        winding += sh.signed_edge_sign(a, b);
        length += shorten_detail::dist3(m.vertices[std::size_t(a)], m.vertices[std::size_t(b)]);
      }
      EXPECT_EQ(winding, sh.band.winding);
      EXPECT_NEAR(length, forward_length, 1e-9);
    }
    // Walking the loop on from v, the first edge that crosses the cut starts before half its length, or
    // after; the first crossing the reversed loop meets is the last one of the loop read forward.
    double along = 0, first = -1, last = -1;
    for (std::size_t i = 0; i < forward.size(); ++i) {
      const int a = forward[i], b = forward[(i + 1) % forward.size()];
      const double e = shorten_detail::dist3(m.vertices[std::size_t(a)], m.vertices[std::size_t(b)]);
      if (sh.signed_edge_sign(a, b) != 0) {
        if (first < 0) first = along;
        last = along + e;  // where the reversed loop, walked from v, reaches this edge's start
      }
      along += e;
    }
    ASSERT_GE(first, 0);
    const bool ahead = sh.cut_is_near_ahead(forward, int(v));
    EXPECT_EQ(ahead, first < along / 2) << "band vertex " << v;
    std::vector<int> reversed(forward.rbegin(), forward.rend());
    EXPECT_EQ(sh.cut_is_near_ahead(reversed, int(v)), along - last < along / 2) << "band vertex " << v;
    near_ahead += ahead;
    ++searched;
  }
  EXPECT_GT(searched, 20);
  EXPECT_GT(near_ahead, 0);
  EXPECT_LT(near_ahead, searched);
}

// A descent asks a search only for a loop shorter than its best: asked below a loop's own length the search
// finds nothing, asked a hair above it finds the same loop; and the nodes it leaves out must not leave their
// straight-line bound to the next search (aimed elsewhere), which must take the nodes a fresh one takes.
TEST(Shorten, SearchForAShorterLoopOnlyFindsTheSameOneOrNone) {
  MeridianBand band(48, 6);
  ASSERT_TRUE(band.built);
  auto& sh = band.sh;
  std::vector<std::vector<int>> fresh;
  std::vector<double> fresh_length;
  for (std::size_t v = 0; v < sh.band.global.size(); v += 25) {
    double length = 0;
    fresh.push_back(sh.shortest_loop_through(int(v), length));
    fresh_length.push_back(length);
    ASSERT_FALSE(fresh.back().empty());
  }
  std::size_t k = 0;
  for (std::size_t v = 0; v < sh.band.global.size(); v += 25, ++k) {
    double length = 0;
    EXPECT_TRUE(sh.shortest_loop_through(int(v), length, false, fresh_length[k]).empty());
    EXPECT_TRUE(std::isinf(length));
    // A search from a neighbour u that leaves out every node but u (v among them): then v's own search must
    // take the same nodes as a fresh one, which a bound of v's kept from u's search would change.
    const int u = sh.arcs[std::size_t(sh.arc_start[v])].to;
    EXPECT_TRUE(sh.shortest_loop_through(u, length, false, 1e-9).empty());
    const long before = sh.search_nodes.load();
    EXPECT_EQ(sh.shortest_loop_through(int(v), length, false, fresh_length[k] * (1 + 1e-9)), fresh[k]) << "band vertex " << v;
    EXPECT_EQ(length, fresh_length[k]);
    const long taken = sh.search_nodes.load() - before;
    sh.shortest_loop_through(int(v), length);  // the unbounded search takes at least as many
    EXPECT_GE(sh.search_nodes.load() - before - taken, taken) << "band vertex " << v;
  }
  EXPECT_GT(k, 20u);
}

// A descent searches near the best loop so far (ShortenOptions::descent_rings): its search takes only the
// marked vertices. Marking every vertex changes nothing; marking the rings around a loop finds that loop
// again for fewer nodes; a mask that leaves out part of the loop sends the search round it.
TEST(Shorten, SearchWithinMarkedVerticesKeepsToThem) {
  MeridianBand band(48, 6);
  ASSERT_TRUE(band.built);
  auto& sh = band.sh;
  const std::size_t nv = sh.band.global.size();
  int checked = 0, went_round = 0;
  for (std::size_t v = 0; v < nv; v += 97) {
    double full_length = 0;
    long before = sh.search_nodes.load();
    const std::vector<int> full = sh.shortest_loop_through(int(v), full_length);
    const long full_nodes = sh.search_nodes.load() - before;
    ASSERT_FALSE(full.empty());

    const std::vector<char> all(nv, 1);
    double length = 0;
    before = sh.search_nodes.load();
    EXPECT_EQ(sh.shortest_loop_through(int(v), length, false, std::numeric_limits<double>::infinity(), &all), full);
    EXPECT_EQ(length, full_length);
    EXPECT_EQ(sh.search_nodes.load() - before, full_nodes);

    // The rings around the loop: every vertex of the loop marked, and a vertex marked only next to a marked one.
    std::vector<char> near;
    sh.mark_near(full, 2, near);
    for (int m : full) EXPECT_TRUE(near[std::size_t(sh.local_of(m))]);
    std::size_t marked = 0;
    for (std::size_t u = 0; u < nv; ++u) marked += near[u] != 0;
    EXPECT_LT(marked, nv);
    before = sh.search_nodes.load();
    EXPECT_EQ(sh.shortest_loop_through(int(v), length, false, std::numeric_limits<double>::infinity(), &near), full);
    EXPECT_EQ(length, full_length);
    EXPECT_LT(sh.search_nodes.load() - before, full_nodes);

    // Without the loop's vertices but v's, the loop found runs through marked vertices only, and is longer.
    std::vector<char> without = near;
    for (int m : full)
      if (sh.local_of(m) != int(v)) without[std::size_t(sh.local_of(m))] = 0;
    const std::vector<int> around = sh.shortest_loop_through(int(v), length, false, std::numeric_limits<double>::infinity(), &without);
    if (!around.empty()) {
      for (int m : around) EXPECT_TRUE(without[std::size_t(sh.local_of(m))]) << "band vertex " << v;
      EXPECT_GT(length, full_length);
      ++went_round;
    }
    ++checked;
  }
  EXPECT_GT(checked, 5);
  EXPECT_GT(went_round, 0);
}

// On a closed, consistently oriented surface the neighbours come from each face's next vertex alone, each
// once; a flipped face or a hole turns that off, and either way a vertex's neighbours are its faces' corners.
TEST(Shorten, NeighboursOfAClosedOrientedSurfaceAndOfOneThatIsNot) {
  SurfaceMesh closed = extract_zero_surface(sample_field({32, 32, 32}, analytic::torus(0.3, 0.1)));
  SurfaceMesh flipped = closed, holed = closed;
  std::swap(flipped.faces[100][1], flipped.faces[100][2]);
  holed.faces.erase(holed.faces.begin() + 100);
  const SurfaceMesh* meshes[] = {&closed, &flipped, &holed};
  for (int which = 0; which < 3; ++which) {
    const SurfaceMesh& m = *meshes[which];
    const MeshAdjacency adj = build_adjacency(m);
    EXPECT_EQ(adj.closed_oriented, which == 0) << "mesh " << which;
    std::vector<std::vector<int>> expected(m.vertices.size());  // the other two corners of each face at v
    for (const auto& f : m.faces)
      for (int k = 0; k < 3; ++k)
        for (int j = 1; j < 3; ++j) expected[std::size_t(f[std::size_t(k)])].push_back(f[std::size_t((k + j) % 3)]);
    for (std::size_t v = 0; v < m.vertices.size(); ++v) {
      std::vector<int> got;
      adj.for_each_neighbour(m, int(v), [&](int w) { got.push_back(w); });
      std::sort(got.begin(), got.end());
      // Once each on the closed oriented surface; elsewhere one may come twice (as the header says).
      if (which == 0) ASSERT_EQ(std::adjacent_find(got.begin(), got.end()), got.end()) << "vertex " << v << " twice";
      got.erase(std::unique(got.begin(), got.end()), got.end());
      auto& want = expected[v];
      std::sort(want.begin(), want.end());
      want.erase(std::unique(want.begin(), want.end()), want.end());
      ASSERT_EQ(got, want) << "mesh " << which << " vertex " << v;
    }
  }
}

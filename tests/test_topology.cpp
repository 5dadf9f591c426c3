// Topological checks of loops on extracted surfaces: CGAL contractibility, separation, polyline snapping.
#include <gtest/gtest.h>

#include <cmath>

#include "analytic_fields.h"
#include "chokeloops/mesh_adjacency.h"
#include "chokeloops/surface.h"
#include "chokeloops/topology.h"

using namespace chokeloops;

namespace {
SurfaceMesh cube_surface(int n, const Sdf& sdf) { return extract_zero_surface(sample_field({n, n, n}, sdf)); }
Polyline3 circle(std::array<double, 3> c, std::array<double, 3> u, std::array<double, 3> v, double r, int n = 200) {
  Polyline3 p;
  for (int i = 0; i < n; ++i) {
    double t = 2 * M_PI * i / n;
    p.push_back({c[0] + r * (std::cos(t) * u[0] + std::sin(t) * v[0]), c[1] + r * (std::cos(t) * u[1] + std::sin(t) * v[1]),
                 c[2] + r * (std::cos(t) * u[2] + std::sin(t) * v[2])});
  }
  return p;
}
void expect_edge_loop(const SurfaceMesh& m, const std::vector<int>& loop) {
  auto A = build_adjacency(m);
  ASSERT_GE(loop.size(), 3u);
  for (size_t i = 0; i < loop.size(); ++i) ASSERT_TRUE(A.has_edge(loop[i], loop[(i + 1) % loop.size()]));
}
}  // namespace

TEST(Topology, TorusMeridianAndLongitudeAreEssentialAndNonSeparating) {
  const double R = 0.3, r = 0.12;
  auto m = cube_surface(64, analytic::torus(R, r));
  SurfaceTopology topo(m);
  auto meridian = snap_polyline_to_edge_path(m, circle({0.5 + R, 0.5, 0.5}, {1, 0, 0}, {0, 0, 1}, r));
  expect_edge_loop(m, meridian);
  EXPECT_TRUE(loop_is_simple(meridian));
  EXPECT_NEAR(loop_length(m, meridian), 2 * M_PI * r, 0.25 * 2 * M_PI * r);  // edge paths zigzag
  EXPECT_FALSE(topo.contractible(meridian));
  EXPECT_FALSE(topo.separates(meridian));
  auto longitude = snap_polyline_to_edge_path(m, circle({0.5, 0.5, 0.5}, {1, 0, 0}, {0, 1, 0}, R + r));
  expect_edge_loop(m, longitude);
  EXPECT_TRUE(loop_is_simple(longitude));
  EXPECT_FALSE(topo.contractible(longitude));
  EXPECT_FALSE(topo.separates(longitude));
  // The inner equator is homotopic to the outer one, both essential.
  auto inner = snap_polyline_to_edge_path(m, circle({0.5, 0.5, 0.5}, {1, 0, 0}, {0, 1, 0}, R - r));
  EXPECT_FALSE(topo.contractible(inner));
  // A small circle around a point on the outer equator: contractible and separating.
  auto small = snap_polyline_to_edge_path(m, circle({0.5 + R + r, 0.5, 0.5}, {0, 1, 0}, {0, 0, 1}, 0.05));
  expect_edge_loop(m, small);
  EXPECT_TRUE(topo.contractible(small));
  EXPECT_TRUE(topo.separates(small));
  // The free functions agree.
  EXPECT_FALSE(loop_is_contractible(m, meridian));
  EXPECT_TRUE(loop_separates_surface(m, small));
}

TEST(Topology, SphereEquatorContractibleAndSeparating) {
  auto m = cube_surface(48, analytic::ball(0.3));
  auto eq = snap_polyline_to_edge_path(m, circle({0.5, 0.5, 0.5}, {1, 0, 0}, {0, 1, 0}, 0.3));
  expect_edge_loop(m, eq);
  EXPECT_TRUE(loop_is_simple(eq));
  EXPECT_TRUE(loop_is_contractible(m, eq));
  EXPECT_TRUE(loop_separates_surface(m, eq));
}

TEST(Topology, DoubleTorusHandleMeridiansAndLoopsOnTheInnerSphereOfAHollowBall) {
  auto dt = analytic::double_torus();  // tori centred at 0.5 -/+ 0.17 in x, R = 0.17, r = 0.07
  auto m = cube_surface(96, dt);
  SurfaceTopology topo(m);
  // Meridian of the left torus on its far side (x = 0.33 - 0.17).
  auto mer = snap_polyline_to_edge_path(m, circle({0.33 - 0.17, 0.5, 0.5}, {1, 0, 0}, {0, 0, 1}, 0.07));
  expect_edge_loop(m, mer);
  EXPECT_FALSE(topo.contractible(mer));
  EXPECT_FALSE(topo.separates(mer));
  auto hollow = [](double x, double y, double z) {
    double r = std::sqrt((x - .5) * (x - .5) + (y - .5) * (y - .5) + (z - .5) * (z - .5));
    return std::max(r - 0.4, 0.25 - r);
  };
  auto h = cube_surface(48, hollow);
  SurfaceTopology th(h);
  auto inner = snap_polyline_to_edge_path(h, circle({0.5, 0.5, 0.5}, {1, 0, 0}, {0, 1, 0}, 0.25));
  auto outer = snap_polyline_to_edge_path(h, circle({0.5, 0.5, 0.5}, {1, 0, 0}, {0, 1, 0}, 0.4));
  EXPECT_NE(th.component_of_vertex(inner[0]), th.component_of_vertex(outer[0]));
  EXPECT_TRUE(th.contractible(inner));
  EXPECT_TRUE(th.separates(inner));  // separates its own component (the inner sphere)
  EXPECT_TRUE(th.separates(outer));
}

TEST(Topology, RejectsBrokenLoops) {
  auto m = cube_surface(24, analytic::ball(0.3));
  SurfaceTopology topo(m);
  EXPECT_THROW(topo.contractible({}), Error);
  EXPECT_THROW(topo.contractible({0, int(m.vertices.size())}), Error);
  EXPECT_THROW(topo.separates({0, 1, 2, 3, 4, 5, 6, 7, 8, 9}), Error);  // not consecutive along edges
}

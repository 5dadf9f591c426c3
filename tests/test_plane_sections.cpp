// Plane sections found from a ray (SurfaceSections with an adjacency) against the whole plane's cut
// (section_of over every face the plane crosses): the same curve, point for point, on a block pierced by
// holes and on a tangle cube, for planes of every direction through points inside and outside the solid,
// with radii from a few voxels to the whole surface. And the curves are what a plane section must be: on the
// torus, the section square to the tube around a point on its core circle is a circle of the tube's radius.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "chokeloops/field/analytic.h"
#include "chokeloops/loops/plane_sections.h"
#include "chokeloops/surface/mesh_adjacency.h"
#include "chokeloops/surface/surface.h"
#include "loops/plane_sections.h"

using namespace chokeloops;

namespace {

struct Counts {
  int planes = 0, sections = 0;
};

Counts compare_ray_with_plane(const Sdf& sdf, int n, std::uint64_t seed) {
  const ScalarGrid grid = sample_field({n, n, n}, sdf);
  const SurfaceMesh surface = extract_zero_surface(grid);
  const MeshAdjacency adjacency = build_adjacency(surface);
  const SurfaceSections sections(surface, &adjacency);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> in_box(0.12, 0.88), unit(-1, 1);
  Counts counts;
  for (int k = 0; k < 150; ++k) {
    const std::array<double, 3> p{in_box(rng), in_box(rng), in_box(rng)};
    std::array<double, 3> normal{unit(rng), unit(rng), unit(rng)};
    if (k % 10 == 0) normal = {0, 0, 1};  // axis-aligned planes through grid vertices: the ties
    for (double radius : {0.03, 0.12, 2.0}) {
      const Polyline3 by_ray = sections.around(p, normal, radius, true);
      const Polyline3 by_plane = sections.around(p, normal, radius, false);
      ++counts.planes;
      counts.sections += !by_plane.empty();
      EXPECT_EQ(by_ray, by_plane) << "plane " << k << " radius " << radius << ": " << by_ray.size() << " vs "
                                  << by_plane.size() << " points";
    }
  }
  return counts;
}

}  // namespace

TEST(PlaneSections, FromARayEqualsTheWholePlanesCutOnAPiercedBlock) {
  const Counts c = compare_ray_with_plane(analytic::pierced_block(40, 7), 96, 1);
  EXPECT_EQ(c.planes, 450);
  EXPECT_GT(c.sections, 90);  // a point inside the block has the block's outline around it (112 of 450)
}

TEST(PlaneSections, FromARayEqualsTheWholePlanesCutOnATangleCube) {
  const Counts c = compare_ray_with_plane(analytic::tangle_cube(), 64, 2);
  EXPECT_GT(c.sections, 40);  // 53 of 450
}

// The faces near a segment, against every face's first vertex: none within reach of it is left out, for
// segments inside, across and beyond the surface's box, along the axes and slanted.
TEST(PlaneSections, FacesNearASegmentMissNoneWithinReach) {
  const ScalarGrid grid = sample_field({64, 64, 64}, analytic::tangle_cube());
  const SurfaceMesh surface = extract_zero_surface(grid);
  const double cell = 1.0 / 50;
  const detail::FaceCells cells(surface, cell);
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> coord(-0.2, 1.2);
  auto distance_to_segment = [](const std::array<double, 3>& x, const std::array<double, 3>& a, const std::array<double, 3>& b) {
    double dd = 0, t = 0;
    for (int k = 0; k < 3; ++k) dd += (b[k] - a[k]) * (b[k] - a[k]), t += (x[k] - a[k]) * (b[k] - a[k]);
    t = dd > 0 ? std::clamp(t / dd, 0.0, 1.0) : 0;
    double d2 = 0;
    for (int k = 0; k < 3; ++k) d2 += std::pow(x[k] - (a[k] + t * (b[k] - a[k])), 2);
    return std::sqrt(d2);
  };
  int near_total = 0;
  for (int k = 0; k < 60; ++k) {
    std::array<double, 3> a{coord(rng), coord(rng), coord(rng)}, b{coord(rng), coord(rng), coord(rng)};
    if (k % 6 == 0) b = {a[0], a[1], 1.1};  // along an axis
    if (k % 6 == 1) b = a;                  // a point
    const double reach = k % 2 ? cell : 1.7 * cell;
    std::vector<int> near;
    cells.near_segment(a, b, reach, near);
    std::sort(near.begin(), near.end());
    for (std::size_t f = 0; f < surface.faces.size(); ++f) {
      if (distance_to_segment(surface.vertices[std::size_t(surface.faces[f][0])], a, b) > reach) continue;
      ++near_total;
      EXPECT_TRUE(std::binary_search(near.begin(), near.end(), int(f))) << "segment " << k << " face " << f;
    }
  }
  EXPECT_GT(near_total, 1000);
}

TEST(PlaneSections, SquareToATorusTubeIsACircleOfTheTubesRadius) {
  const double R = 0.3, r = 0.1;
  const ScalarGrid grid = sample_field({97, 97, 97}, analytic::torus(R, r));
  const SurfaceMesh surface = extract_zero_surface(grid);
  const MeshAdjacency adjacency = build_adjacency(surface);
  const SurfaceSections sections(surface, &adjacency);
  for (int k = 0; k < 8; ++k) {
    const double t = 2 * M_PI * k / 8;
    const std::array<double, 3> core{0.5 + R * std::cos(t), 0.5 + R * std::sin(t), 0.5};
    const std::array<double, 3> tangent{-std::sin(t), std::cos(t), 0};
    const Polyline3 section = sections.around(core, tangent, 2.0);
    ASSERT_GE(section.size(), 20u) << k;
    double length = 0;
    for (std::size_t i = 0; i < section.size(); ++i) {
      const auto &a = section[i], &b = section[(i + 1) % section.size()];
      length += std::hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]);
      const double rho = std::hypot(std::hypot(a[0] - 0.5, a[1] - 0.5) - R, a[2] - 0.5);
      EXPECT_NEAR(rho, r, 0.01) << k;
    }
    EXPECT_NEAR(length, 2 * M_PI * r, 0.02) << k;
  }
}

// Plane sections found from a ray (SurfaceSections with an adjacency) against the whole plane's cut
// (section_of over every face the plane crosses): the same curve, point for point (and the ray's faces those
// of its segments), on a block pierced by
// holes and on a tangle cube, for planes of every direction through points inside and outside the solid,
// with radii from a few voxels to the whole surface. And the curves are what a plane section must be: on the
// torus, the section square to the tube around a point on its core circle is a circle of the tube's radius.
// A segment is found clear of the surface only when no face meets it, and the planes the generator sections
// skip (their sections cannot link the cycle once) are skipped only where every section links it evenly.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "chokeloops/field/analytic.h"
#include "chokeloops/loops/plane_sections.h"
#include "chokeloops/surface/mesh_adjacency.h"
#include "chokeloops/surface/surface.h"
#include "chokeloops/loops/linking.h"
#include "loops/generator_class.h"
#include "loops/plane_sections.h"

using namespace chokeloops;

namespace {

struct Counts {
  int planes = 0, sections = 0;
};

// The faces a section lists are those of its segments in turn: face k holds points k and k + 1, which lie on
// the edges it shares with the faces before and after it.
void expect_faces_of_curve(const SurfaceMesh& surface, const MeshAdjacency& adjacency, const Polyline3& curve,
                           const std::vector<int>& faces) {
  ASSERT_EQ(faces.size(), curve.size());
  const std::size_t n = faces.size();
  for (std::size_t k = 0; k < n; ++k) {
    const int f = faces[k], g = faces[(k + 1) % n];
    int shared = -1;
    for (int e = 0; e < 3; ++e) {
      const int t = adjacency.twin[std::size_t(3 * g + e)];
      if (t >= 0 && MeshAdjacency::face(t) == f) shared = 3 * g + e;
    }
    ASSERT_GE(shared, 0) << "faces " << k << " and " << k + 1 << " share no edge";
    const auto& a = surface.vertices[std::size_t(surface.faces[std::size_t(g)][std::size_t(shared % 3)])];
    const auto& b = surface.vertices[std::size_t(surface.faces[std::size_t(g)][std::size_t((shared % 3 + 1) % 3)])];
    const auto& q = curve[(k + 1) % n];
    double ab[3], aq[3], len2 = 0, along = 0;
    for (int d = 0; d < 3; ++d) ab[d] = b[std::size_t(d)] - a[std::size_t(d)], aq[d] = q[std::size_t(d)] - a[std::size_t(d)];
    for (int d = 0; d < 3; ++d) len2 += ab[d] * ab[d], along += ab[d] * aq[d];
    const double t = std::clamp(along / len2, 0.0, 1.0);
    double off = 0;
    for (int d = 0; d < 3; ++d) off += (aq[d] - t * ab[d]) * (aq[d] - t * ab[d]);
    EXPECT_LT(std::sqrt(off), 1e-12) << "point " << (k + 1) % n << " is not on the edge its faces share";
  }
}

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
      std::vector<int> faces;
      const Polyline3 by_ray = sections.around(p, normal, radius, true, &faces);
      const Polyline3 by_plane = sections.around(p, normal, radius, false);
      if (!faces.empty()) expect_faces_of_curve(surface, adjacency, by_ray, faces);
      ++counts.planes;
      counts.sections += !by_plane.empty();
      EXPECT_EQ(by_ray, by_plane) << "plane " << k << " radius " << radius << ": " << by_ray.size() << " vs "
                                  << by_plane.size() << " points";
    }
  }
  return counts;
}

// A torus of radii R and r round the unit cube's centre, sampled at 97^3, and its plane sections (built in
// place: the sections keep a reference to the surface).
struct TorusSections {
  TorusSections(double R, double r)
      : surface(extract_zero_surface(sample_field({97, 97, 97}, analytic::torus(R, r)))),
        adjacency(build_adjacency(surface)),
        sections(surface, &adjacency) {}
  const SurfaceMesh surface;
  const MeshAdjacency adjacency;
  const SurfaceSections sections;
};

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
  const TorusSections torus(R, r);
  const SurfaceSections& sections = torus.sections;
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

namespace {

// Whether the segment a-b meets triangle (p, q, r), plain Moller-Trumbore: the oracle segment_clear must agree with.
bool segment_meets_triangle(const std::array<double, 3>& a, const std::array<double, 3>& b, const std::array<double, 3>& p,
                            const std::array<double, 3>& q, const std::array<double, 3>& r) {
  auto sub = [](const std::array<double, 3>& u, const std::array<double, 3>& v) {
    return std::array<double, 3>{u[0] - v[0], u[1] - v[1], u[2] - v[2]};
  };
  auto cross = [](const std::array<double, 3>& u, const std::array<double, 3>& v) {
    return std::array<double, 3>{u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
  };
  auto dot = [](const std::array<double, 3>& u, const std::array<double, 3>& v) { return u[0] * v[0] + u[1] * v[1] + u[2] * v[2]; };
  const auto d = sub(b, a), e1 = sub(q, p), e2 = sub(r, p);
  const auto h = cross(d, e2);
  const double det = dot(e1, h);
  if (det == 0) return false;
  const auto s = sub(a, p);
  const double u = dot(s, h) / det;
  if (u < 0 || u > 1) return false;
  const auto qv = cross(s, e1);
  const double v = dot(d, qv) / det;
  if (v < 0 || u + v > 1) return false;
  const double t = dot(e2, qv) / det;
  return t >= 0 && t <= 1;
}

Polyline3 circle(const std::array<double, 3>& centre, const std::array<double, 3>& u, const std::array<double, 3>& v,
                 double radius, int n) {
  Polyline3 out;
  for (int k = 0; k < n; ++k) {
    const double t = 2 * M_PI * (k + 0.5) / n;
    out.push_back({centre[0] + radius * (std::cos(t) * u[0] + std::sin(t) * v[0]),
                   centre[1] + radius * (std::cos(t) * u[1] + std::sin(t) * v[1]),
                   centre[2] + radius * (std::cos(t) * u[2] + std::sin(t) * v[2])});
  }
  return out;
}

}  // namespace

// A segment is clear of the surface only if no face meets it (every face checked), and most segments that meet
// none are found clear: short and long ones, inside, across and beyond a tangle cube.
TEST(PlaneSections, ASegmentIsClearOnlyWhenNoFaceMeetsIt) {
  const ScalarGrid grid = sample_field({64, 64, 64}, analytic::tangle_cube());
  const SurfaceMesh surface = extract_zero_surface(grid);
  const SurfaceSections sections(surface);
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> coord(-0.1, 1.1), step(-0.06, 0.06);
  int met = 0, clear = 0, missed_and_clear = 0;
  for (int k = 0; k < 400; ++k) {
    const std::array<double, 3> a{coord(rng), coord(rng), coord(rng)};
    std::array<double, 3> b{coord(rng), coord(rng), coord(rng)};
    if (k % 2) b = {a[0] + step(rng), a[1] + step(rng), a[2] + step(rng)};  // short: a few voxels
    bool meets = false;
    for (const auto& f : surface.faces)
      if (segment_meets_triangle(a, b, surface.vertices[std::size_t(f[0])], surface.vertices[std::size_t(f[1])],
                                 surface.vertices[std::size_t(f[2])])) {
        meets = true;
        break;
      }
    const bool is_clear = sections.segment_clear(a, b);
    met += meets;
    clear += is_clear;
    missed_and_clear += !meets && is_clear;
    EXPECT_FALSE(meets && is_clear) << "segment " << k << " meets a face but was found clear";
  }
  EXPECT_GT(met, 80);     // 105 of 400
  EXPECT_GT(clear, 250);  // 295: every segment that meets no face
  EXPECT_EQ(clear, missed_and_clear);
  EXPECT_GE(clear, 400 - met - 2);  // a doubt (a touch within rounding) is rare
}

// The planes a generator's plane sections may skip: on a torus, planes through the core circle's points. A
// plane through the axis crosses the core once on each side of the hole, in two pieces of the solid, and its
// section round the point (the tube's circle) links the core once: never skipped. A plane across the tube
// beside the hole (x = const, cutting the core twice in one piece of the solid) is skipped, and every section
// of a skipped plane links the core an even number of times; the same for a tunnel cycle round the tube.
TEST(PlaneSections, PlanesWhoseSectionsCannotLinkACycleOnceOnATorus) {
  const double R = 0.3, r = 0.1;
  const TorusSections torus(R, r);
  const SurfaceSections& sections = torus.sections;
  const std::array<double, 3> centre{0.5, 0.5, 0.5};
  const Polyline3 core = circle(centre, {1, 0, 0}, {0, 1, 0}, R, 240);
  const Polyline3 round_tube = circle({0.5 + R, 0.5, 0.5}, {1, 0, 0}, {0, 0, 1}, 0.2, 240);  // in the outside
  for (int k = 0; k < 8; ++k) {
    const double t = 2 * M_PI * k / 8;
    const std::array<double, 3> point{0.5 + R * std::cos(t), 0.5 + R * std::sin(t), 0.5};
    const std::array<double, 3> tangent{-std::sin(t), std::cos(t), 0};
    EXPECT_FALSE(detail::section_cannot_link_odd(sections, core, point, tangent)) << k;
    const auto lk = linking_number(sections.around(point, tangent, 2.0), core);
    ASSERT_TRUE(lk.has_value()) << k;
    EXPECT_EQ(std::abs(*lk), 1) << k;
  }
  const std::array<double, 3> beside{0.5 + R - 0.3 * r, 0.5, 0.5}, across{1, 0, 0};
  EXPECT_TRUE(detail::section_cannot_link_odd(sections, core, beside, across));
  // Random planes through points of each cycle: a skipped plane's sections round any point of it link the
  // cycle evenly.
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> unit(-1, 1), along(-0.25, 0.25);
  for (const Polyline3* cycle : {&core, &round_tube}) {
    int skipped = 0, kept = 0, sections_checked = 0;
    for (int k = 0; k < 120; ++k) {
      const auto& p = (*cycle)[std::size_t(k * 2) % cycle->size()];
      const std::array<double, 3> n{unit(rng), unit(rng), unit(rng)};
      if (!detail::section_cannot_link_odd(sections, *cycle, p, n)) {
        ++kept;
        continue;
      }
      ++skipped;
      // Points of the plane round p: sections that wind round them, each checked.
      std::array<double, 3> u{n[1], -n[0], 0};
      if (std::hypot(u[0], u[1]) < 1e-6) u = {1, 0, 0};
      const std::array<double, 3> v{n[1] * u[2] - n[2] * u[1], n[2] * u[0] - n[0] * u[2], n[0] * u[1] - n[1] * u[0]};
      const double nu = std::hypot(u[0], u[1], u[2]), nv = std::hypot(v[0], v[1], v[2]);
      for (int j = 0; j < 6; ++j) {
        const double su = along(rng), sv = along(rng);
        const std::array<double, 3> q{p[0] + su * u[0] / nu + sv * v[0] / nv, p[1] + su * u[1] / nu + sv * v[1] / nv,
                                      p[2] + su * u[2] / nu + sv * v[2] / nv};
        const Polyline3 section = sections.around(q, n, 2.0);
        if (section.size() < 3) continue;
        ++sections_checked;
        const auto lk = linking_number(section, *cycle);
        if (lk) EXPECT_EQ(*lk % 2, 0) << "plane " << k << " point " << j;
      }
    }
    EXPECT_GT(skipped, 40);  // 71 and 73 of 120
    EXPECT_GT(kept, 30);
    EXPECT_GT(sections_checked, 20);
  }
}

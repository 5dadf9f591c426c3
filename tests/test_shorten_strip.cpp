// Shortening a loop from the strip of faces it crosses (shorten_strip_loop): a plane section of a torus's tube
// turned a little from the meridian plane tightens to its meridian (2 pi r), one turned far is reported still
// moving after its rounds; a long plane section of a pierced block ends where the band
// search from its edges ends; a loop that moves farther than max_move is reported at its band's edge; the
// strip's side is an edge loop of its class; faces that are no strip are refused.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "analytic_fields.h"
#include "chokeloops/field/analytic.h"
#include "chokeloops/loops/linking.h"
#include "chokeloops/loops/plane_sections.h"
#include "chokeloops/loops/shorten.h"
#include "chokeloops/surface/mesh_adjacency.h"
#include "chokeloops/surface/surface.h"
#include "chokeloops/surface/topology.h"

using namespace chokeloops;

namespace {

constexpr double kR = 0.3, kr = 0.12;  // the torus's radii, round the unit cube's centre

struct Torus {
  SurfaceMesh surface = extract_zero_surface(sample_field({128, 128, 128}, analytic::torus(kR, kr)));
  MeshAdjacency adjacency = build_adjacency(surface);
  SurfaceSections sections{surface, &adjacency};
  // The section of the tube by the plane through the core circle's point at angle 0, turned by `tilt` from
  // the meridian plane about the core circle's radius there; `faces` its strip.
  Polyline3 tilted_section(double tilt, std::vector<int>& faces) const {
    const std::array<double, 3> point{0.5 + kR, 0.5, 0.5}, normal{0, std::cos(tilt), std::sin(tilt)};
    return sections.around(point, normal, 0.3, true, &faces);
  }
};

const Torus& torus() {
  static const Torus t;
  return t;
}

// Every vertex of `loop` joined to the next by a mesh edge, and none visited twice.
void expect_simple_edge_loop(const SurfaceMesh& surface, const MeshAdjacency& adjacency, const std::vector<int>& loop) {
  ASSERT_GE(loop.size(), 3u);
  for (std::size_t i = 0; i < loop.size(); ++i)
    EXPECT_TRUE(adjacency.has_edge(surface, loop[i], loop[(i + 1) % loop.size()])) << i;
  std::vector<int> sorted = loop;
  std::sort(sorted.begin(), sorted.end());
  EXPECT_TRUE(std::adjacent_find(sorted.begin(), sorted.end()) == sorted.end());
}

}  // namespace

TEST(ShortenStrip, NearlyMeridianPlaneSectionOfATorusTightensToItsMeridian) {
  const Torus& t = torus();
  const double meridian = 2 * M_PI * kr;
  double first = 0;
  for (double tilt : {0.0, 0.01, 0.02}) {
    std::vector<int> faces;
    const Polyline3 section = t.tilted_section(tilt, faces);
    ASSERT_GE(faces.size(), 100u) << tilt;
    const ShortenResult r = shorten_strip_loop(t.surface, t.adjacency, faces);
    std::printf("tilt %.2f: section %.6f (%zu faces), funnel %.6f, loop %.6f after %d swaps, meridian %.6f%s\n", tilt,
                closed_length(section), faces.size(), r.input_length, r.length, r.swaps, meridian,
                r.at_band_edge ? ", still moving" : "");
    EXPECT_EQ(r.rings, 1);
    EXPECT_FALSE(r.at_band_edge) << tilt;
    EXPECT_LE(r.input_length, closed_length(section) * (1 + 1e-12));  // the funnel through the section's faces
    EXPECT_LE(r.length, r.input_length * (1 + 1e-12));
    EXPECT_NEAR(r.length, meridian, 5e-4 * meridian) << tilt;
    if (tilt == 0.0) first = r.length;
    EXPECT_NEAR(r.length, first, 1e-6 * first) << tilt;  // the tilted ones turn to the meridian plane's loop
    EXPECT_NEAR(closed_length(r.points), r.length, 1e-12);
    // A meridian: every point at distance r from the core circle, in the plane through the axis at angle 0.
    for (const auto& q : r.points) {
      EXPECT_NEAR(std::hypot(std::hypot(q[0] - 0.5, q[1] - 0.5) - kR, q[2] - 0.5), kr, 0.005);
      EXPECT_NEAR(q[1], 0.5, 0.005);
    }
    expect_simple_edge_loop(t.surface, t.adjacency, r.edge_path);
    SurfaceTopology topology(t.surface);
    EXPECT_FALSE(topology.contractible(r.edge_path));
    EXPECT_FALSE(topology.separates(r.edge_path));
  }
}

TEST(ShortenStrip, ASectionFarFromItsGeodesicIsStillMovingAfterItsRounds) {
  // Turned 0.3 rad from the meridian plane, the section is 2.4% longer than the meridian; the swaps turn it a
  // vertex row a round, and after their rounds it is shorter but not there: the loop tracer then takes the
  // band search, which finds the meridian at once.
  const Torus& t = torus();
  std::vector<int> faces;
  const Polyline3 section = t.tilted_section(0.3, faces);
  const ShortenResult r = shorten_strip_loop(t.surface, t.adjacency, faces);
  EXPECT_TRUE(r.at_band_edge);
  EXPECT_LT(r.length, r.input_length * (1 - 1e-3));
  EXPECT_GT(r.length, 2 * M_PI * kr);
  EXPECT_LE(r.swaps, 5000);
}

TEST(ShortenStrip, ALoopMovedFartherThanMaxMoveIsAtItsBandsEdge) {
  const Torus& t = torus();
  std::vector<int> faces;
  t.tilted_section(0.02, faces);
  ShortenOptions near;
  near.max_move = 0.0005;  // the section's ends turn by r tan(0.02) = 0.0024 to the meridian
  const ShortenResult held = shorten_strip_loop(t.surface, t.adjacency, faces, near);
  EXPECT_TRUE(held.at_band_edge);
  ShortenOptions far;
  far.max_move = 0.1;
  const ShortenResult free = shorten_strip_loop(t.surface, t.adjacency, faces, far);
  EXPECT_FALSE(free.at_band_edge);
  EXPECT_DOUBLE_EQ(free.length, held.length);  // the same loop, only judged otherwise
}

TEST(ShortenStrip, SideOfASectionsStripIsAnEdgeLoopOfItsClass) {
  const Torus& t = torus();
  std::vector<int> faces;
  const Polyline3 section = t.tilted_section(0.15, faces);
  const std::vector<int> side = strip_side_loop(t.surface, t.adjacency, faces);
  expect_simple_edge_loop(t.surface, t.adjacency, side);
  // Its vertices are corners of the strip's faces, all on one side of the plane.
  std::vector<char> corner(t.surface.vertices.size(), 0);
  for (int f : faces)
    for (int v : t.surface.faces[std::size_t(f)]) corner[std::size_t(v)] = 1;
  const std::array<double, 3> normal{0, std::cos(0.15), std::sin(0.15)};
  int above = 0;
  for (int v : side) {
    EXPECT_TRUE(corner[std::size_t(v)]);
    const auto& p = t.surface.vertices[std::size_t(v)];
    above += (p[1] - 0.5) * normal[1] + (p[2] - 0.5) * normal[2] > 0;
  }
  EXPECT_TRUE(above == 0 || above == int(side.size()));
  SurfaceTopology topology(t.surface);
  EXPECT_FALSE(topology.contractible(side));
  // Of the section's class: it goes once round the tube, linking the core circle once.
  Polyline3 core, points;
  for (int i = 0; i < 256; ++i)
    core.push_back({0.5 + kR * std::cos(2 * M_PI * i / 256), 0.5 + kR * std::sin(2 * M_PI * i / 256), 0.5});
  for (int v : side) points.push_back(t.surface.vertices[std::size_t(v)]);
  const auto side_links = linking_number(points, core), section_links = linking_number(section, core);
  ASSERT_TRUE(side_links && section_links);
  EXPECT_EQ(std::abs(*side_links), 1);
  EXPECT_EQ(std::abs(*section_links), 1);
}

TEST(ShortenStrip, LongPlaneSectionOfAPiercedBlockEndsWhereTheBandSearchDoes) {
  // A block with holes at 256: planes across it between the holes cut sections round the whole block of
  // 2,500 faces and more (the pierced block benchmark's handle loops). Where the swaps from a section's own
  // faces finish, they end in a loop as long as the band search's from an edge loop of those faces; where
  // they are still moving (the plane at x = 0.31 runs near a hole's rim), the loop tracer takes the band
  // search, and the loop so far is at least shorter than its section.
  const SurfaceMesh surface = extract_zero_surface(sample_field({256, 256, 256}, analytic::pierced_block(6, 7)));
  const MeshAdjacency adjacency = build_adjacency(surface);
  const SurfaceSections sections(surface, &adjacency);
  int finished = 0;
  for (double x : {0.31, 0.5, 0.69}) {
    std::vector<int> faces;
    const Polyline3 section = sections.around({x, 0.5, 0.5}, {1, 0.004, 0.003}, 2.0, true, &faces);
    ASSERT_GE(faces.size(), 1000u) << x;
    ShortenOptions options;
    options.max_move = 0.05;
    const ShortenResult from_strip = shorten_strip_loop(surface, adjacency, faces, options);
    options.cut_samples = 0;
    options.first_rings = 8;
    const ShortenResult from_band = shorten_loop(surface, adjacency, strip_side_loop(surface, adjacency, faces), options);
    std::printf("x %.2f: section %.6f (%zu faces), from its strip %.6f (%d swaps%s), band search %.6f\n", x,
                closed_length(section), faces.size(), from_strip.length, from_strip.swaps,
                from_strip.at_band_edge ? ", still moving" : "", from_band.length);
    EXPECT_LT(from_strip.length, closed_length(section)) << x;
    if (from_strip.at_band_edge) continue;
    ++finished;
    EXPECT_NEAR(from_strip.length, from_band.length, 2e-5 * from_band.length) << x;
  }
  EXPECT_GE(finished, 2);
}

TEST(ShortenStrip, RejectsFacesThatAreNoStrip) {
  const Torus& t = torus();
  EXPECT_THROW(shorten_strip_loop(t.surface, t.adjacency, {}), Error);
  EXPECT_THROW(shorten_strip_loop(t.surface, t.adjacency, {0, 1}), Error);
  EXPECT_THROW(shorten_strip_loop(t.surface, t.adjacency, {0, 1, int(t.surface.faces.size())}), Error);
  std::vector<int> faces;
  t.tilted_section(0.0, faces);
  std::vector<int> broken = faces;
  broken.erase(broken.begin() + long(broken.size() / 2));  // two faces in turn that share no edge
  EXPECT_THROW(shorten_strip_loop(t.surface, t.adjacency, broken), Error);
  EXPECT_TRUE(strip_side_loop(t.surface, t.adjacency, broken).empty());
}

// Meaning test of the signed lower-star filtration (DESIGN section 2): on sampled signed distance
// fields of shapes with known topology, the pairs fall into the classes of the table with the expected
// counts, and their values sit where the geometry says (within one voxel: a grid vertex is at most
// sqrt(3)/2 voxel from any point, and the fields are 1-Lipschitz).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <sstream>

#include "analytic_fields.h"
#include "chokeloops/topology/persistence.h"

using namespace chokeloops;

namespace {

struct Classes {
  std::vector<PersistencePair> genus;   // dim 1, b < 0 < d
  std::vector<PersistencePair> necks;   // dim 0, b < d < 0, persistence > 2 voxels
  std::vector<PersistencePair> mouths;  // dim 2, 0 < b < d, persistence > 2 voxels
  std::vector<PersistencePair> gaps;    // dim 0, b < 0 <= d
  std::vector<PersistencePair> sealed;  // dim 2, b < 0
  std::vector<PersistencePair> same_side_loops;  // dim 1, same sign, persistence > 2 voxels
};

Classes classify(const PersistenceDiagram& D, double voxel) {
  Classes c;
  const double noise = 2 * voxel;
  for (auto& p : D.pairs) {
    if (p.dim == 1 && p.birth < 0 && p.death > 0) c.genus.push_back(p);
    if (p.dim == 0 && p.birth < p.death && p.death < 0 && p.persistence() > noise) c.necks.push_back(p);
    if (p.dim == 2 && 0 < p.birth && p.birth < p.death && p.persistence() > noise) c.mouths.push_back(p);
    if (p.dim == 0 && p.birth < 0 && p.death >= 0) c.gaps.push_back(p);
    if (p.dim == 2 && p.birth < 0) c.sealed.push_back(p);
    if (p.dim == 1 && !(p.birth < 0 && p.death > 0) && p.persistence() > noise) c.same_side_loops.push_back(p);
  }
  return c;
}

std::string describe(const PersistenceDiagram& D, double voxel) {
  std::ostringstream s;
  s << "voxel " << voxel << "; pairs per dim " << D.count(0) << "/" << D.count(1) << "/" << D.count(2)
    << "; pairs with persistence > 1 voxel:\n";
  for (auto& p : D.pairs)
    if (p.persistence() > voxel) s << "  dim " << p.dim << " [" << p.birth << ", " << p.death << ")\n";
  return s.str();
}

// The single essential class is of dimension 0 and born at the global minimum (value, then index).
void expect_essential_is_global_minimum(const ScalarGrid& g, const PersistenceDiagram& D) {
  ASSERT_EQ(D.essential.size(), 1u);
  const auto& e = D.essential[0];
  EXPECT_EQ(e.dim, 0);
  Id vmin = 0;
  for (Id v = 1; v < g.vertex_count(); ++v)
    if (vertex_less(g.values.data(), v, vmin)) vmin = v;
  EXPECT_EQ(e.birth_simplex, vmin);
  EXPECT_EQ(e.birth_vertex, vmin);
  EXPECT_EQ(e.birth, g.values[size_t(vmin)]);
  EXPECT_TRUE(std::isinf(e.death) && e.death > 0);
  EXPECT_EQ(e.death_simplex, -1);
}

TEST(PersistenceMeaning, TorusHasOneHandleTunnelPair) {
  const double R = 0.3, r = 0.12;
  auto g = sample_field({56, 56, 56}, analytic::torus(R, r));
  auto D = lower_star_persistence(g);
  const double h = g.voxel_size;
  auto c = classify(D, h);
  ASSERT_EQ(c.genus.size(), 1u) << describe(D, h);
  // Born at the thinnest point of the handle (depth r), killed when the hole closes (distance R - r).
  EXPECT_NEAR(c.genus[0].birth, -r, h);
  EXPECT_NEAR(c.genus[0].death, R - r, h);
  EXPECT_EQ(c.necks.size(), 0u) << describe(D, h);
  EXPECT_EQ(c.mouths.size(), 0u) << describe(D, h);
  EXPECT_EQ(c.gaps.size(), 0u) << describe(D, h);
  EXPECT_EQ(c.sealed.size(), 0u) << describe(D, h);
  EXPECT_EQ(c.same_side_loops.size(), 0u) << describe(D, h);
  expect_essential_is_global_minimum(g, D);
}

TEST(PersistenceMeaning, DoubleTorusHasTwoHandleTunnelPairs) {
  const double R = 0.17, r = 0.07;
  auto g = sample_field({64, 64, 64}, analytic::double_torus(R, r, 0.34));
  auto D = lower_star_persistence(g);
  const double h = g.voxel_size;
  auto c = classify(D, h);
  ASSERT_EQ(c.genus.size(), 2u) << describe(D, h);
  for (auto& p : c.genus) {
    EXPECT_LT(p.birth, -r + 1.5 * h);  // the tubes are r deep, deeper where they overlap
    EXPECT_NEAR(p.death, R - r, h);    // each hole closes at its own axis
  }
  EXPECT_EQ(c.mouths.size(), 0u) << describe(D, h);
  EXPECT_EQ(c.gaps.size(), 0u) << describe(D, h);
  EXPECT_EQ(c.sealed.size(), 0u) << describe(D, h);
  expect_essential_is_global_minimum(g, D);
}

TEST(PersistenceMeaning, DumbbellHasOneNeckPair) {
  const double ball_r = 0.2, neck_r = 0.12;
  auto g = sample_field({64, 64, 64}, analytic::dumbbell(ball_r, neck_r, 0.23));
  auto D = lower_star_persistence(g);
  const double h = g.voxel_size;
  auto c = classify(D, h);
  EXPECT_EQ(c.genus.size(), 0u) << describe(D, h);
  ASSERT_EQ(c.necks.size(), 1u) << describe(D, h);
  // The second ball's centre is born at depth ball_r and merges with the first at the neck.
  EXPECT_NEAR(c.necks[0].birth, -ball_r, h);
  EXPECT_NEAR(c.necks[0].death, -neck_r, h);
  EXPECT_EQ(c.mouths.size(), 0u) << describe(D, h);
  EXPECT_EQ(c.gaps.size(), 0u) << describe(D, h);
  EXPECT_EQ(c.sealed.size(), 0u) << describe(D, h);
  expect_essential_is_global_minimum(g, D);
}

TEST(PersistenceMeaning, PiercedHollowBallHasOneCavityMouthPair) {
  const double outer = 0.4, inner = 0.25, hole_r = 0.06;
  auto g = sample_field({64, 64, 64}, analytic::pierced_hollow_ball(outer, inner, hole_r));
  auto D = lower_star_persistence(g);
  const double h = g.voxel_size;
  auto c = classify(D, h);
  EXPECT_EQ(c.genus.size(), 0u) << describe(D, h);  // genus 0
  ASSERT_EQ(c.mouths.size(), 1u) << describe(D, h);
  // The mouth closes at the hole's radius; the cavity then fills up at its centre.
  EXPECT_NEAR(c.mouths[0].birth, hole_r, h);
  EXPECT_NEAR(c.mouths[0].death, inner, h);
  EXPECT_EQ(c.gaps.size(), 0u) << describe(D, h);
  EXPECT_EQ(c.sealed.size(), 0u) << describe(D, h);
  expect_essential_is_global_minimum(g, D);
}

TEST(PersistenceMeaning, TwoSeparateBallsHaveOneGapPair) {
  Sdf a = analytic::ball(0.2, {0.27, 0.5, 0.5}), b = analytic::ball(0.2, {0.73, 0.5, 0.5});
  auto g = sample_field({48, 48, 48}, [&](double x, double y, double z) { return std::min(a(x, y, z), b(x, y, z)); });
  auto D = lower_star_persistence(g);
  const double h = g.voxel_size;
  auto c = classify(D, h);
  ASSERT_EQ(c.gaps.size(), 1u) << describe(D, h);
  EXPECT_NEAR(c.gaps[0].birth, -0.2, h);
  EXPECT_NEAR(c.gaps[0].death, 0.03, h);  // the balls are 0.06 apart: they meet at distance 0.03
  EXPECT_EQ(c.necks.size(), 0u) << describe(D, h);
  EXPECT_EQ(c.genus.size(), 0u) << describe(D, h);
  expect_essential_is_global_minimum(g, D);
}

TEST(PersistenceMeaning, ClosedHollowBallHasOneSealedCavity) {
  // A closed thick shell (radii 0.25..0.4): its cavity is a void of the solid, a dim-2 class born when
  // the shell's core closes around it (at the depth of the shell's mid-sphere, -0.075) and killed
  // when the cavity fills up at its centre (+0.25): the "sealed cavity" row, b < 0.
  Sdf ball_o = analytic::ball(0.4), ball_i = analytic::ball(0.25);
  auto g = sample_field({48, 48, 48}, [&](double x, double y, double z) {
    return std::max(ball_o(x, y, z), -ball_i(x, y, z));
  });
  auto D = lower_star_persistence(g);
  const double h = g.voxel_size;
  auto c = classify(D, h);
  EXPECT_EQ(c.genus.size(), 0u) << describe(D, h);
  EXPECT_EQ(c.mouths.size(), 0u) << describe(D, h);
  ASSERT_EQ(c.sealed.size(), 1u) << describe(D, h);
  EXPECT_NEAR(c.sealed[0].birth, -0.075, h);
  EXPECT_NEAR(c.sealed[0].death, 0.25, h);
  expect_essential_is_global_minimum(g, D);
}

}  // namespace

// A grid value that is not finite is refused with the index of the first one, whichever block of the
// parallel check meets one first.
TEST(PersistenceMeaning, NamesTheFirstValueThatIsNotFinite) {
  ScalarGrid g;
  g.dims = {100, 100, 100};
  g.voxel_size = 1;
  g.values.assign(1000000, 1.0f);
  g.values[700001] = std::numeric_limits<float>::infinity();
  g.values[300007] = std::nanf("");
  g.values[999999] = -std::numeric_limits<float>::infinity();
  auto message = [&] {
    try {
      lower_star_persistence(g);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message().find("vertex 300007 "), std::string::npos) << message();
  g.values[300007] = 0.5f;
  EXPECT_NE(message().find("vertex 700001 "), std::string::npos) << message();
  g.values[700001] = 0.5f;
  EXPECT_NE(message().find("vertex 999999 "), std::string::npos) << message();
  g.values[999999] = 0.5f;
  EXPECT_EQ(message(), "no error");
}

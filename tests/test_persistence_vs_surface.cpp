// Cross-check of two independent stages on the same complex: the persistence pairs alive at t = 0 give
// the Betti numbers of the solid subcomplex {v : value(v) <= 0}, and the marching-tetrahedra zero surface
// (surface.h) bounds a regular neighbourhood of that solid. For a solid off the grid's border:
//   total genus of the surface            = beta1(solid) = #{dim-1 classes with b <= 0 < d}
//   number of surface components          = beta0 + beta2 (one outer boundary per component, one per cavity)
// Checked on smooth shapes and on noisy ones, whose solids have many tiny handles, bubbles and islands.
#include <gtest/gtest.h>

#include <sstream>

#include "analytic_fields.h"
#include "chokeloops/topology/persistence.h"
#include "chokeloops/surface/surface.h"

using namespace chokeloops;

namespace {

struct Alive {
  int b[3] = {0, 0, 0};
};

Alive alive_at_zero(const PersistenceDiagram& D) {
  Alive a;
  for (auto& p : D.pairs)
    if (p.birth <= 0 && 0 < p.death) a.b[p.dim]++;
  for (auto& p : D.essential)
    if (p.birth <= 0) a.b[p.dim]++;
  return a;
}

void check(const std::string& name, const ScalarGrid& g, int expected_genus = -1) {
  SCOPED_TRACE(name);
  auto D = lower_star_persistence(g);
  auto a = alive_at_zero(D);
  auto s = surface_stats(extract_zero_surface(g));
  ASSERT_TRUE(s.closed_manifold) << "the solid must stay off the grid's border for this check";
  EXPECT_EQ(s.genus, a.b[1]) << "surface genus vs dim-1 classes alive at 0";
  EXPECT_EQ(s.components, a.b[0] + a.b[2]) << "surface components vs beta0 + beta2 (" << a.b[0] << " + " << a.b[2]
                                           << ")";
  if (expected_genus >= 0) EXPECT_EQ(a.b[1], expected_genus);
}

TEST(PersistenceVsSurface, BettiNumbersAtZeroMatchTheZeroSurface) {
  check("torus48", sample_field({48, 48, 48}, analytic::torus(0.3, 0.12)), 1);
  check("double_torus48", sample_field({48, 48, 48}, analytic::double_torus()), 2);
  check("pierced48", sample_field({48, 48, 48}, analytic::pierced_hollow_ball()), 0);
  check("varying_torus48", sample_field({48, 48, 48}, analytic::varying_torus(), {-0.3, -0.3, -0.3}, {1.3, 1.3, 1.3}), 1);
  check("tangle48", sample_field({48, 48, 48}, analytic::tangle_cube()));
  for (std::uint64_t seed : {1, 2, 3}) {
    auto g = sample_field({48, 48, 48}, analytic::torus(0.3, 0.12));
    add_uniform_noise(g, 0.02, seed);
    check("torus_noise48_s" + std::to_string(seed), g);
  }
  // A random smooth field cut by a ball (max): islands, handles and cavities of all kinds, off the border.
  for (std::uint64_t seed : {4, 5}) {
    Sdf r = analytic::random_gaussians(40, seed), b = analytic::ball(0.42);
    auto g = sample_field({40, 40, 40}, [&](double x, double y, double z) {
      return std::max(0.3 - r(x, y, z), b(x, y, z));
    });
    check("gaussians_in_ball40_s" + std::to_string(seed), g);
    add_uniform_noise(g, 0.05, seed);
    check("gaussians_in_ball_noise40_s" + std::to_string(seed), g);
  }
}

TEST(PersistenceMeaning, VaryingTorusHandleIsBornAtItsThinnestSection) {
  // Tube radius 0.15 + 0.06 cos t: the handle's core closes into a loop at the thinnest section (depth 0.09).
  auto g = sample_field({64, 64, 64}, analytic::varying_torus(0.5, 0.15, 0.06), {-0.3, -0.3, -0.3}, {1.3, 1.3, 1.3});
  auto D = lower_star_persistence(g);
  std::vector<PersistencePair> genus;
  for (auto& p : D.pairs)
    if (p.dim == 1 && p.birth < 0 && p.death > 0) genus.push_back(p);
  ASSERT_EQ(genus.size(), 1u);
  EXPECT_NEAR(genus[0].birth, -0.09, g.voxel_size);
  // The birth edge is on the thin side (x < centre).
  FreudenthalComplex K(g.dims);
  auto c = K.coords(genus[0].birth_vertex);
  EXPECT_LT(g.world(c)[0], 0.5 - 0.3);
  EXPECT_GT(genus[0].death, 0.25);  // the hole (radius >= 0.29) closes late
}

}  // namespace

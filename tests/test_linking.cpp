// Linking numbers of polylines against known links, and the cycles generator chokes close: on a torus the
// solid's core and the cycle through the hole link once, each loop links the cycle of its own side once and
// the other side's not at all, in a box with room around the torus and in one so tight that the outside's
// cycle must leave the grid (round the outside of the box, as the persistence joins it there).
#include <gtest/gtest.h>

#include <cmath>

#include "chokeloops/analyze.h"
#include "chokeloops/field/analytic.h"
#include "chokeloops/loops/linking.h"

using namespace chokeloops;

namespace {

constexpr double kPi = 3.14159265358979323846;

Polyline3 circle(std::array<double, 3> centre, std::array<double, 3> u, std::array<double, 3> v, double r, int n = 64) {
  Polyline3 out;
  for (int i = 0; i < n; ++i) {
    const double t = 2 * kPi * i / n;
    out.push_back({centre[0] + r * (std::cos(t) * u[0] + std::sin(t) * v[0]), centre[1] + r * (std::cos(t) * u[1] + std::sin(t) * v[1]),
                   centre[2] + r * (std::cos(t) * u[2] + std::sin(t) * v[2])});
  }
  return out;
}

// A (p, q) torus knot-like curve on the torus of radii R, r (p turns around the axis, q around the tube),
// starting at angle `phase` around the tube.
Polyline3 torus_curve(int p, int q, double R, double r, double phase, int n = 400) {
  Polyline3 out;
  for (int i = 0; i < n; ++i) {
    const double t = 2 * kPi * i / n, a = p * t, b = q * t + phase;
    out.push_back({(R + r * std::cos(b)) * std::cos(a), (R + r * std::cos(b)) * std::sin(a), r * std::sin(b)});
  }
  return out;
}

}  // namespace

TEST(Linking, HopfLinkUnlinkAndTorusLink) {
  const Polyline3 a = circle({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, 1);
  const Polyline3 hopf = circle({1, 0, 0}, {1, 0, 0}, {0, 0, 1}, 1);
  const Polyline3 apart = circle({3, 0, 0}, {1, 0, 0}, {0, 0, 1}, 1);
  const Polyline3 coaxial = circle({0, 0, 0.5}, {1, 0, 0}, {0, 1, 0}, 2);  // a bigger circle above: not linked
  ASSERT_TRUE(linking_number(a, hopf).has_value());
  EXPECT_EQ(std::abs(*linking_number(a, hopf)), 1);
  EXPECT_EQ(linking_number(a, apart), std::optional<int>(0));
  EXPECT_EQ(linking_number(a, coaxial), std::optional<int>(0));
  // Symmetric, and reversing one curve flips the sign.
  EXPECT_EQ(linking_number(hopf, a), linking_number(a, hopf));
  Polyline3 reversed(hopf.rbegin(), hopf.rend());
  EXPECT_EQ(*linking_number(a, reversed), -*linking_number(a, hopf));
  // Two (1, 2) curves on one torus, half a turn apart around the tube: they link twice.
  const Polyline3 c1 = torus_curve(1, 2, 2, 0.7, 0), c2 = torus_curve(1, 2, 2, 0.7, kPi);
  ASSERT_TRUE(linking_number(c1, c2).has_value());
  EXPECT_EQ(std::abs(*linking_number(c1, c2)), 2);
  // The core circle of that torus links a meridian once and a curve on the far side not at all.
  const Polyline3 core = circle({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, 2, 200);
  const Polyline3 meridian = circle({2, 0, 0}, {1, 0, 0}, {0, 0, 1}, 0.7);
  EXPECT_EQ(std::abs(*linking_number(core, meridian)), 1);
  EXPECT_EQ(std::abs(*linking_number(core, c1)), 2);  // c1 turns twice around the tube
}

TEST(Linking, CurvesThatMeetHaveNoLinkingNumber) {
  const Polyline3 a = circle({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, 1);
  const Polyline3 through = {{1, 0, -1}, {1, 0, 1}, {2, 0, 0}};  // passes through a's point (1, 0, 0)
  EXPECT_FALSE(linking_number(a, through).has_value());
}

namespace {
void expect_torus_cycles(std::array<int, 3> n, const std::array<double, 3>& lo, const std::array<double, 3>& hi, bool must_leave_grid) {
  AnalyzeOptions o;
  const AnalyzeResult r = analyze_grid(sample_field(n, analytic::torus(0.3, 0.1), lo, hi), o);
  ASSERT_EQ(r.surface_stats.genus, 1);
  const Loop *handle = nullptr, *tunnel = nullptr;
  for (const Loop& l : r.loops)
    if (l.choke.kind == Kind::Generator) (l.choke.side == Side::Handle ? handle : tunnel) = &l;
  ASSERT_TRUE(handle && tunnel);
  ASSERT_TRUE(handle->found && tunnel->found);
  const Polyline3 core = generator_cycle(r.grid, handle->choke), through = generator_cycle(r.grid, tunnel->choke);
  ASSERT_GE(core.size(), 3u);
  ASSERT_GE(through.size(), 3u);
  // Every vertex of the core cycle is inside the solid, every grid vertex of the other one outside.
  for (const auto& p : core) EXPECT_LT(std::hypot(std::hypot(p[0] - 0.5, p[1] - 0.5) - 0.3, p[2] - 0.5), 0.1);
  bool outside_grid = false;
  for (const auto& p : through)
    for (int a = 0; a < 3; ++a) outside_grid |= p[a] < lo[a] - 1e-9 || p[a] > hi[a] + 1e-9;
  if (must_leave_grid) EXPECT_TRUE(outside_grid);
  EXPECT_EQ(std::abs(*linking_number(core, through)), 1);
  EXPECT_EQ(std::abs(*linking_number(handle->points, core)), 1);  // the meridian goes round the core
  EXPECT_EQ(linking_number(handle->points, through), std::optional<int>(0));
  EXPECT_EQ(std::abs(*linking_number(tunnel->points, through)), 1);
  EXPECT_EQ(linking_number(tunnel->points, core), std::optional<int>(0));
}
}  // namespace

TEST(Linking, TorusGeneratorCyclesLinkOnceAndEachLoopBoundsOnItsSide) {
  expect_torus_cycles({73, 73, 73}, {0, 0, 0}, {1, 1, 1}, false);
}

TEST(Linking, TorusCycleThroughTheHoleLeavesATightGrid) {
  // The torus reaches 0.1..0.9 across and 0.4..0.6 in height: a box 0.05 wider holds no outside path
  // around the tube that stays farther from the surface than the hole's radius 0.2.
  expect_torus_cycles({73, 73, 33}, {0.05, 0.05, 0.3}, {0.95, 0.95, 0.7}, true);
}

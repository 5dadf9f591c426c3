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

namespace {
// Twice the linking number from every pair of segments, no cells: the count LinkingCurve's grid must give.
// Along the first direction LinkingCurve tries; nullopt at a degenerate crossing.
std::optional<long> all_pairs_crossing_sum(const Polyline3& a, const Polyline3& b) {
  const double d0[3] = {0.5712, 0.4233, 0.7033};
  const double dn = std::sqrt(d0[0] * d0[0] + d0[1] * d0[1] + d0[2] * d0[2]);
  const double d[3] = {d0[0] / dn, d0[1] / dn, d0[2] / dn};
  double u[3] = {d[1], -d[0], 0};
  const double un = std::hypot(u[0], u[1]);
  u[0] /= un, u[1] /= un;
  const double w[3] = {d[1] * u[2] - d[2] * u[1], d[2] * u[0] - d[0] * u[2], d[0] * u[1] - d[1] * u[0]};
  auto project = [&](const std::array<double, 3>& p) {
    return std::array<double, 3>{p[0] * u[0] + p[1] * u[1] + p[2] * u[2], p[0] * w[0] + p[1] * w[1] + p[2] * w[2],
                                 p[0] * d[0] + p[1] * d[1] + p[2] * d[2]};
  };
  long sum = 0;
  for (std::size_t i = 0; i < a.size(); ++i)
    for (std::size_t j = 0; j < b.size(); ++j) {
      const auto p = project(a[i]), p2 = project(a[(i + 1) % a.size()]);
      const auto q = project(b[j]), q2 = project(b[(j + 1) % b.size()]);
      const double rx = p2[0] - p[0], ry = p2[1] - p[1], sx = q2[0] - q[0], sy = q2[1] - q[1];
      const double denom = rx * sy - ry * sx;
      if (std::abs(denom) < 1e-12) continue;
      const double wx = q[0] - p[0], wy = q[1] - p[1];
      const double t = (wx * sy - wy * sx) / denom, s = (wx * ry - wy * rx) / denom;
      if (t < 0 || t > 1 || s < 0 || s > 1) continue;
      if (t < 1e-9 || t > 1 - 1e-9 || s < 1e-9 || s > 1 - 1e-9) return std::nullopt;
      const double ha = p[2] + t * (p2[2] - p[2]), hb = q[2] + s * (q2[2] - q[2]);
      sum += (ha > hb ? 1 : -1) * (denom > 0 ? 1 : -1);
    }
  return sum;
}
}  // namespace

// One curve prepared once and asked against many: the same numbers as a count over every pair of segments,
// for a long wavy curve (many cells, segments spanning several) against circles and torus curves that link it
// 0, 1 or 2 times, cross its cells in every way, or lie apart from it.
TEST(Linking, PreparedCurveCountsEveryCrossingOnce) {
  // A (1, 2) torus curve of 2000 points, wobbling: long against the cells, like a generator's loop.
  Polyline3 long_curve = torus_curve(1, 2, 2, 0.7, 0, 2000);
  for (std::size_t i = 0; i < long_curve.size(); ++i) long_curve[i][2] += 0.05 * std::sin(37.0 * 2 * kPi * double(i) / 2000);
  const LinkingCurve prepared(long_curve);
  std::vector<Polyline3> others;
  others.push_back(circle({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, 2, 300));        // the core: links twice
  others.push_back(circle({2, 0, 0}, {1, 0, 0}, {0, 0, 1}, 1.2, 50));       // a wide meridian: links once
  others.push_back(circle({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, 0.5, 7));        // in the hole, coarse: not linked
  others.push_back(circle({6, 0, 0}, {0, 1, 0}, {0, 0, 1}, 1, 64));         // apart
  others.push_back(circle({0, 0, 2}, {1, 0, 0}, {0, 1, 0}, 4, 9));          // above, long segments over many cells
  others.push_back(torus_curve(1, 2, 2, 0.7, kPi, 333));                    // the same torus, half a turn on: twice
  others.push_back(torus_curve(1, 1, 2, 1.3, 0.3, 41));                     // a coarse wider torus curve
  int linked = 0;
  for (const Polyline3& b : others) {
    const auto expected = all_pairs_crossing_sum(long_curve, b);
    ASSERT_TRUE(expected.has_value());
    ASSERT_EQ(*expected % 2, 0);
    const auto got = prepared.with(b);
    ASSERT_TRUE(got.has_value());
    EXPECT_EQ(*got, *expected / 2);
    EXPECT_EQ(got, linking_number(long_curve, b));
    EXPECT_EQ(got, linking_number(b, long_curve));
    linked += *got != 0;
  }
  EXPECT_EQ(std::abs(*prepared.with(others[0])), 2);
  EXPECT_EQ(std::abs(*prepared.with(others[1])), 1);
  EXPECT_EQ(*prepared.with(others[3]), 0);
  EXPECT_GE(linked, 3);
  // Coarse curves on both sides: a pair of long segments shares several cells and is still counted once.
  const Polyline3 coarse_core = circle({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, 2, 9);
  const LinkingCurve coarse(coarse_core);
  for (const Polyline3& b : {circle({1.9, 0.3, 0}, {1, 0, 0}, {0, 0, 1}, 1.0, 5), circle({-1.9, 0.2, 0}, {0, 1, 0}, {0, 0.3, 1}, 1.1, 6),
                             torus_curve(1, 3, 2, 0.8, 0.2, 31), circle({0.1, 0, 0.4}, {1, 0, 0}, {0, 1, 0}, 3, 11)}) {
    const auto expected = all_pairs_crossing_sum(coarse_core, b);
    ASSERT_TRUE(expected.has_value());
    ASSERT_EQ(*expected % 2, 0);
    EXPECT_EQ(coarse.with(b), std::optional<int>(int(*expected / 2)));
  }
  EXPECT_EQ(std::abs(*coarse.with(torus_curve(1, 3, 2, 0.8, 0.2, 31))), 3);
}

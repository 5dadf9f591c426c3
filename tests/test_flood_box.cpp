// The membrane flood's box: it grows by the sides where the membrane runs out of it, and a handle
// generator whose membrane is a sheet across a thick block still gets the block's shortest section.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "chokeloops/analyze.h"
#include "chokeloops/field/analytic.h"
#include "loops/two_lobe_flood.h"

using namespace chokeloops;
using detail::BoxExtent;

namespace {

RegionBounds bounds_of(std::array<int, 3> lo, std::array<int, 3> hi) {
  RegionBounds b;
  b.lo = lo, b.hi = hi;
  return b;
}

}  // namespace

TEST(FloodBox, GrowsOnlyTheOpenSidesThatCanGrow) {
  const RegionBounds bounds = bounds_of({0, 0, 0}, {99, 99, 99});
  const std::array<int, 3> saddle{50, 50, 50};
  BoxExtent box = BoxExtent::cube(10);
  // Open toward +z and -x: those two sides grow by 1.8, the others stay.
  detail::grow_box(box, {1, 0, 0, 0, 0, 1}, saddle, bounds, 100);
  EXPECT_EQ(box.below, (std::array<int, 3>{18, 10, 10}));
  EXPECT_EQ(box.above, (std::array<int, 3>{10, 10, 18}));
  EXPECT_FALSE(detail::box_covers(box, saddle, bounds));
  // A side past half of the grid's size goes to the whole size at once.
  box = BoxExtent::cube(30);
  detail::grow_box(box, {0, 0, 0, 0, 0, 1}, saddle, bounds, 100);
  EXPECT_EQ(box.above[2], 100);
  EXPECT_EQ(box.below[2], 30);
  // A side that already reaches the region's bound cannot grow: with nothing else marked, all six grow.
  box = {{10, 10, 10}, {10, 10, 60}};
  detail::grow_box(box, {0, 0, 0, 0, 0, 1}, saddle, bounds, 100);
  EXPECT_EQ(box.below, (std::array<int, 3>{18, 18, 18}));
  EXPECT_EQ(box.above, (std::array<int, 3>{18, 18, 100}));
  // Nothing marked: the cube grows as a whole, the old way.
  box = BoxExtent::cube(12);
  detail::grow_box(box, {}, saddle, bounds, 100);
  EXPECT_EQ(box.below, (std::array<int, 3>{22, 22, 22}));
  EXPECT_EQ(box.above, (std::array<int, 3>{22, 22, 22}));
}

TEST(FloodBox, CoversTheRegionOnlyWhenEverySideReachesItsBound) {
  const RegionBounds bounds = bounds_of({5, 0, 10}, {60, 99, 40});
  const std::array<int, 3> saddle{30, 50, 20};
  EXPECT_TRUE(detail::box_covers({{25, 50, 10}, {30, 49, 20}}, saddle, bounds));
  EXPECT_FALSE(detail::box_covers({{25, 50, 10}, {30, 48, 20}}, saddle, bounds));
  EXPECT_FALSE(detail::box_covers({{24, 50, 10}, {30, 49, 20}}, saddle, bounds));
}

TEST(FloodBox, ThickBlockWithOneHoleGetsItsShortestSectionAsHandleLoop) {
  // A block 0.6 x 0.6 x 0.7 with one hole of radius 0.06 along z at (0.4, 0.5): the thinnest material round
  // the hole is the 0.14 between it and the face x = 0.2, and its section is a 0.14 x 0.7 rectangle. The
  // membrane there is a sheet across the block's whole height, 5 times the choke's depth, which the box
  // reaches by growing along z only. The handle loop is that rectangle's rim, 2 (0.14 + 0.7) = 1.68 (less a
  // little where the marching surface rounds the block's edges).
  const double hole_x = 0.4, hole_y = 0.5, hole_r = 0.06;
  const Sdf block = [=](double x, double y, double z) {
    const double p[3] = {x, y, z}, lo[3] = {0.2, 0.2, 0.15}, hi[3] = {0.8, 0.8, 0.85};
    double inside = -1e300, outside = 0;
    for (int a = 0; a < 3; ++a) {
      const double d = std::max(lo[a] - p[a], p[a] - hi[a]);
      inside = std::max(inside, d);
      outside += std::max(d, 0.0) * std::max(d, 0.0);
    }
    const double f = inside > 0 ? std::sqrt(outside) : inside;
    return std::max(f, hole_r - std::hypot(x - hole_x, y - hole_y));
  };
  AnalyzeResult r = analyze_grid(sample_field({128, 128, 128}, block), AnalyzeOptions{});
  ASSERT_EQ(r.surface_stats.genus, 1);
  const Loop* handle = nullptr;
  for (const Loop& l : r.loops)
    if (l.choke.kind == Kind::Generator && l.choke.side == Side::Handle) handle = &l;
  ASSERT_NE(handle, nullptr);
  ASSERT_TRUE(handle->found) << handle->note;
  EXPECT_NEAR(handle->length, 1.68, 0.02 * 1.68);
  // It runs down the hole's wall on the side of the thin material (x < hole_x) and across the face x = 0.2.
  double min_x = 1, max_x = 0;
  for (const auto& p : handle->points) min_x = std::min(min_x, p[0]), max_x = std::max(max_x, p[0]);
  EXPECT_NEAR(min_x, 0.2, 0.01);
  EXPECT_NEAR(max_x, hole_x - hole_r, 0.01);
}

// The filter's check of a batch of side changes: judged from a group's surroundings where they settle it, the
// verdict must be the one the labels of the whole grid give.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "chokeloops/field/analytic.h"
#include "chokeloops/topology/complex.h"
#include "filter/batch_check.h"

using namespace chokeloops;
using namespace chokeloops::detail;

namespace {

struct Tally {
  int decided = 0, undecided = 0, kept_components = 0, split = 0, kept_cavities = 0, sealed = 0;
};

// Flips the side of every `stride`-th vertex within a voxel of the surface (each a group of its own: the
// stride keeps them apart), judges every group both ways and compares where the local check decided.
Tally judge_both_ways(ScalarGrid grid, int stride) {
  const FreudenthalComplex cx(grid.dims);
  const float h = float(grid.voxel_size);
  SideChanges changes;
  std::vector<Id> flipped;
  const SideLabels before = label_sides(grid);
  for (int k = 2; k < grid.dims[2] - 2; k += stride)
    for (int j = 2; j < grid.dims[1] - 2; j += stride)
      for (int i = 2; i < grid.dims[0] - 2; i += stride) {
        const Id v = cx.vertex(i, j, k);
        float& f = grid.values[std::size_t(v)];
        if (std::abs(f) > h) continue;
        changes.emplace(v, f <= 0);
        flipped.push_back(v);
        f = f <= 0 ? 0.5f * h : -0.5f * h;
      }
  const SideLabels after = label_sides(grid);
  Tally t;
  for (Id v : flipped) {
    const std::vector<Id> group{v};
    const GroupVerdict whole = judge_group(grid, cx, group, changes, before, after);
    const LocalVerdict local = judge_group_locally(grid, cx, group, changes);
    EXPECT_EQ(local.verdict.euler_change, whole.euler_change);
    EXPECT_EQ(local.verdict.on_border, whole.on_border);
    if (!local.decided) {
      ++t.undecided;
      continue;
    }
    ++t.decided;
    EXPECT_EQ(local.verdict.keeps_components, whole.keeps_components) << "vertex " << v;
    EXPECT_EQ(local.verdict.keeps_cavities, whole.keeps_cavities) << "vertex " << v;
    (whole.keeps_components ? t.kept_components : t.split)++;
    (whole.keeps_cavities ? t.kept_cavities : t.sealed)++;
  }
  return t;
}

}  // namespace

TEST(BatchCheck, LocalVerdictsOnNoiseEqualTheWholeGridsLabels) {
  // Noise of 0.4 voxel on the tangle cube: flipped vertices near the surface split off specks and seal tiny
  // cavities as well as keeping both sides whole, so both answers are compared.
  ScalarGrid g = sample_field({48, 48, 48}, analytic::tangle_cube());
  add_uniform_noise(g, 0.4 * g.voxel_size, 11);
  const Tally t = judge_both_ways(g, 3);
  EXPECT_GT(t.decided, 200);
  EXPECT_GT(t.kept_components, 0);
  EXPECT_GT(t.split, 0);
  EXPECT_GT(t.kept_cavities, 0);
  EXPECT_GT(t.sealed, 0);
}

TEST(BatchCheck, ACutAcrossALongHandleIsLeftToTheLabels) {
  // A torus whose tube (radius 3 voxels) runs ~400 voxels round: cutting a disc across it keeps the solid in
  // one piece only through the far side of the ring, beyond any box near the cut, so the local check must not
  // decide, and the labels must say the solid stayed whole.
  ScalarGrid g = sample_field({160, 160, 24}, analytic::torus(0.4, 3.0 / 159), {0, 0, 0.5 - 12.0 / 159}, {1, 1, 0.5 + 11.0 / 159});
  const FreudenthalComplex cx(g.dims);
  const SideLabels before = label_sides(g);
  SideChanges changes;
  std::vector<Id> group;
  // The plane x = centre, on the tube's side y > centre: every inside vertex there leaves the solid.
  const int i = g.dims[0] / 2;
  for (int k = 0; k < g.dims[2]; ++k)
    for (int j = g.dims[1] / 2; j < g.dims[1]; ++j)
      for (int di = 0; di < 2; ++di) {
        const Id v = cx.vertex(i + di, j, k);
        float& f = g.values[std::size_t(v)];
        if (f > 0) continue;
        changes.emplace(v, true);
        group.push_back(v);
        f = float(0.5 * g.voxel_size);
      }
  ASSERT_GT(group.size(), 20u);
  std::sort(group.begin(), group.end());
  const SideLabels after = label_sides(g);
  const LocalVerdict local = judge_group_locally(g, cx, group, changes);
  EXPECT_FALSE(local.decided);
  const GroupVerdict whole = judge_group(g, cx, group, changes, before, after);
  EXPECT_TRUE(whole.keeps_components);
  EXPECT_TRUE(whole.keeps_cavities);
  EXPECT_EQ(whole.euler_change, 1);
}

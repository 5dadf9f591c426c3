// A .vdb level set built by min/max of exact distances (CSG, the usual way implicits are made) is a distance
// only near its surface. Its far values must not be trusted: the level-set stage compares them with the exact
// distance to their own zero level set over the whole box and recomputes them when they are off, which
// changes the answer (the depth of a neck); a true distance field is kept bit for bit.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "analytic_fields.h"
#include "chokeloops/analyze.h"
#include "chokeloops/io/vdb_io.h"

using namespace chokeloops;
namespace fs = std::filesystem;

namespace {

// Two balls of radius r whose centres lie 2a apart on x, joined by min(): exact outside, but inside it
// underestimates the depth near the neck. The true inscribed radius at the neck's centre is the radius
// of the circle where the spheres meet, sqrt(r^2 - a^2); min() says r - a there.
constexpr double kR = 0.2, kA = 0.15;
double csg_two_balls(double x, double y, double z) {
  const double d1 = std::sqrt((x - 0.5 + kA) * (x - 0.5 + kA) + (y - 0.5) * (y - 0.5) + (z - 0.5) * (z - 0.5)) - kR;
  const double d2 = std::sqrt((x - 0.5 - kA) * (x - 0.5 - kA) + (y - 0.5) * (y - 0.5) + (z - 0.5) * (z - 0.5)) - kR;
  return std::min(d1, d2);
}

fs::path write_field(const ScalarGrid& g, const std::string& name) {
  fs::path p = fs::temp_directory_path() / ("chokeloops_csg_" + name + "_" + std::to_string(::getpid()) + ".vdb");
  write_vdb(g, p.string());
  return p;
}

const Loop* deepest_handle_choke(const AnalyzeResult& r) {
  const Loop* best = nullptr;
  for (auto& l : r.loops)
    if (l.choke.side == Side::Handle && l.choke.kind == Kind::Choke && (!best || l.choke.depth > best->choke.depth))
      best = &l;
  return best;
}

}  // namespace

TEST(LevelSetCsg, MinOfTwoBallsIsRedistancedAndTheNeckGetsItsTrueDepth) {
  const ScalarGrid field = sample_field({96, 96, 96}, csg_two_balls);
  const double h = field.voxel_size;
  const fs::path path = write_field(field, "balls");
  AnalyzeOptions o;
  o.levelset.quiet = true;
  o.chokes.d_max = Threshold::parse("100%");  // the neck (0.13) is deeper than half the balls' radius
  AnalyzeResult r = analyze(path.string(), o);
  EXPECT_GT(r.levelset_info.max_distance_error_voxels, 3.0);  // min() is ~8 voxels off at the neck
  bool warned = false;
  for (auto& w : r.warnings) warned |= w.find("recomputed as the exact distance") != std::string::npos;
  EXPECT_TRUE(warned);
  const Loop* neck = deepest_handle_choke(r);
  ASSERT_NE(neck, nullptr);
  const double true_depth = std::sqrt(kR * kR - kA * kA);  // 0.1323
  EXPECT_NEAR(neck->choke.depth, true_depth, 1.5 * h);
  EXPECT_NEAR(neck->length, 2 * M_PI * true_depth, 0.05 * 2 * M_PI * true_depth);

  // Trusting the values (as before, and as --keep-values asks) reports min()'s depth, r - a.
  o.levelset.keep_values = true;
  AnalyzeResult kept = analyze(path.string(), o);
  EXPECT_LT(kept.levelset_info.max_distance_error_voxels, 0);  // not checked
  const Loop* kept_neck = deepest_handle_choke(kept);
  ASSERT_NE(kept_neck, nullptr);
  EXPECT_NEAR(kept_neck->choke.depth, kR - kA, 1.5 * h);
  fs::remove(path);
}

TEST(LevelSetCsg, AnExactDistanceFieldIsKeptBitForBit) {
  const ScalarGrid field = sample_field({80, 80, 80}, analytic::torus(0.3, 0.12));
  const fs::path path = write_field(field, "torus");
  LevelSetOptions o;
  o.quiet = true;
  LevelSetResult r = make_levelset(path.string(), o);
  EXPECT_GE(r.max_distance_error_voxels, 0);
  EXPECT_LE(r.max_distance_error_voxels, 1.0);
  EXPECT_TRUE(r.warnings.empty()) << r.warnings.front();
  ASSERT_EQ(r.grid.values.size(), field.values.size());
  EXPECT_TRUE(r.grid.values == field.values);
  fs::remove(path);
}

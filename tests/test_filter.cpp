// The filter on analytic shapes whose pairs are known: what goes, what stays, and that nothing else moves.
#include <gtest/gtest.h>

#include <cmath>

#include <tbb/global_control.h>

#include "analytic_fields.h"
#include "chokeloops/analyze.h"
#include "chokeloops/filter/filter.h"
#include "chokeloops/loops/membrane_voxels.h"
#include "chokeloops/surface/surface.h"

using namespace chokeloops;

namespace {

// A torus (R 0.25, tube 0.08) with a bar of radius 0.02 across its hole, along x: genus 2.
Sdf torus_with_bar(double bar_r = 0.02) {
  Sdf t = analytic::torus(0.25, 0.08);
  return [t, bar_r](double x, double y, double z) {
    const double dy = y - 0.5, dz = z - 0.5, dx = std::abs(x - 0.5);
    const double radial = std::hypot(dy, dz) - bar_r;
    const double along = dx - 0.26;  // the bar ends inside the tube
    const double bar = along > 0 ? std::hypot(std::max(radial, 0.0), along) : radial;
    return std::min(t(x, y, z), bar);
  };
}

// A ball (r 0.3) drilled along z by a hole of radius r: genus 1.
Sdf drilled_ball(double hole_r) {
  Sdf b = analytic::ball(0.3);
  return [b, hole_r](double x, double y, double z) {
    return std::max(b(x, y, z), hole_r - std::hypot(x - 0.5, y - 0.5));
  };
}

// Filters `base` again on one thread: the same edits and the same field, bit for bit, as `all_threads` gave.
void expect_the_same_on_one_thread(const ScalarGrid& base, const FilterOptions& o, const FilterReport& all_threads,
                                   const ScalarGrid& filtered) {
  ScalarGrid one = base;
  FilterReport r1;
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    r1 = filter_grid(one, o);
  }
  ASSERT_EQ(r1.edits.size(), all_threads.edits.size());
  for (std::size_t i = 0; i < r1.edits.size(); ++i) EXPECT_EQ(r1.edits[i].voxels, all_threads.edits[i].voxels) << "edit " << i;
  EXPECT_TRUE(one.values == filtered.values);
}

std::string notes_of(const FilterReport& r) {
  std::string s;
  for (const auto& n : r.notes) s += "\n  " + n;
  return s;
}

int surface_genus(const ScalarGrid& g) { return surface_stats(extract_zero_surface(g)).genus; }

FilterOptions by_depth(double d) {
  FilterOptions o;
  o.has_max_depth = true;
  o.max_depth = Threshold{d, false};
  return o;
}

}  // namespace

TEST(Filter, CutsTheThinBarOfATorusAndKeepsTheTorusHandle) {
  ScalarGrid g = sample_field({128, 128, 128}, torus_with_bar());
  const ScalarGrid before = g;
  ASSERT_EQ(topology_summary(g).genus, 2);
  const FilterReport r = filter_grid(g, by_depth(0.03));
  EXPECT_EQ(r.before.genus, 2);
  EXPECT_EQ(r.after.genus, 1);
  EXPECT_EQ(r.after.components, 1);
  EXPECT_EQ(r.after.cavities, 0);
  EXPECT_EQ(surface_genus(g), 1);
  ASSERT_EQ(r.edits.size(), 1u);
  EXPECT_EQ(r.edits[0].side, Side::Handle);  // the bar is cut, its hole not filled
  EXPECT_NEAR(r.edits[0].depth, 0.02, g.voxel_size);
  EXPECT_TRUE(r.notes.empty());
  // The handle left is the torus's own: its narrowest section is the tube's radius.
  ChokeParameters p;
  const ChokeSet left = find_chokes(g, lower_star_persistence(g), p);
  ASSERT_EQ(left.handle_generators, 1);
  for (const Choke& c : left.chokes)
    if (c.kind == Kind::Generator && c.side == Side::Handle) EXPECT_NEAR(c.depth, 0.08, g.voxel_size);
  // A disc across the bar: about pi r^2 / h^2 voxels, one layer; everything beyond the bar's neighbourhood
  // is bit-identical.
  EXPECT_EQ(r.voxels_changed, r.edits[0].voxels.size());
  EXPECT_GT(r.voxels_changed, 5u);
  EXPECT_LT(r.voxels_changed, 80u);
  const double reach = 0.02 + 3 * g.voxel_size;
  for (int k = 0; k < g.dims[2]; ++k)
    for (int j = 0; j < g.dims[1]; ++j)
      for (int i = 0; i < g.dims[0]; ++i) {
        const auto p3 = g.world({i, j, k});
        if (std::hypot(p3[1] - 0.5, p3[2] - 0.5) > reach + 0.03) {
          const Id v = g.index(i, j, k);
          ASSERT_EQ(g.values[v], before.values[v]) << "at " << p3[0] << " " << p3[1] << " " << p3[2];
        }
      }
}

TEST(Filter, FillsAThinHoleThroughABall) {
  ScalarGrid g = sample_field({96, 96, 96}, drilled_ball(0.025));
  FilterOptions o;
  o.keep_genus = 0;
  const FilterReport r = filter_grid(g, o);
  EXPECT_EQ(r.before.genus, 1);
  EXPECT_EQ(r.after.genus, 0);
  EXPECT_EQ(r.after.components, 1);
  EXPECT_EQ(r.after.cavities, 0);
  EXPECT_EQ(surface_genus(g), 0);
  ASSERT_EQ(r.edits.size(), 1u);
  EXPECT_EQ(r.edits[0].side, Side::Tunnel);  // the hole is filled, the ball is not cut through
  EXPECT_NEAR(r.edits[0].depth, 0.025, g.voxel_size);
  EXPECT_LT(r.voxels_changed, 60u);
}

// The thinning to a pinch (the filter's last resort) on shapes with one pair to remove: flipping what it returns
// lowers the genus by one and changes nothing else, and it flips nothing deeper than the choke.
void expect_thinning_removes_one_pair(const ScalarGrid& grid, Side side, double depth) {
  const FilterSummary before = topology_summary(grid);
  const ChokeSet chokes = find_chokes(grid, lower_star_persistence(grid), ChokeParameters{});
  const Choke* generator = nullptr;
  for (const Choke& c : chokes.chokes)
    if (c.kind == Kind::Generator && c.side == side && std::abs(c.depth - depth) < 2 * grid.voxel_size) generator = &c;
  ASSERT_NE(generator, nullptr);
  const MembraneVoxels m = thinned_pinch_voxels(grid, *generator);
  ASSERT_TRUE(m.found) << m.note;
  ScalarGrid edited = grid;
  const float moved = float(side == Side::Handle ? 0.5 : -0.5) * float(grid.voxel_size);
  for (Id v : m.shore) {
    EXPECT_LE(std::abs(grid.values[std::size_t(v)]), generator->depth + 0.5 * grid.voxel_size);
    EXPECT_EQ(grid.values[std::size_t(v)] <= 0, side == Side::Handle);
    edited.values[std::size_t(v)] = moved;
  }
  const FilterSummary after = topology_summary(edited);
  EXPECT_EQ(after.genus, before.genus - 1);
  EXPECT_EQ(after.components, before.components);
  EXPECT_EQ(after.cavities, before.cavities);
  // Only what the pinch needs is left: about the section of the handle (or of the hole), not the ball around it
  // (measured 16 and 30 voxels, against sections of 39 and 36).
  const double section = 3.14159 * std::pow(depth / grid.voxel_size + 1, 2);
  EXPECT_LT(double(m.shore.size()), 1.2 * section) << m.shore.size() << " voxels";
}

TEST(Filter, ThinningToAPinchCutsTheBarOfATorus) {
  expect_thinning_removes_one_pair(sample_field({128, 128, 128}, torus_with_bar()), Side::Handle, 0.02);
}

TEST(Filter, ThinningToAPinchFillsTheHoleThroughABall) {
  expect_thinning_removes_one_pair(sample_field({96, 96, 96}, drilled_ball(0.025)), Side::Tunnel, 0.025);
}

TEST(Filter, CutModeCutsTheBallInsteadAndFillModeFillsTheBarsHole) {
  {
    ScalarGrid g = sample_field({96, 96, 96}, drilled_ball(0.025));
    FilterOptions o;
    o.keep_genus = 0;
    o.mode = FilterMode::Cut;
    const FilterReport r = filter_grid(g, o);
    EXPECT_EQ(r.after.genus, 0) << notes_of(r);
    EXPECT_EQ(r.after.components, 1);
    ASSERT_EQ(r.edits.size(), 1u);
    EXPECT_EQ(r.edits[0].side, Side::Handle);
    EXPECT_GT(r.voxels_changed, 200u);  // a slab across the ball's wall
  }
  {
    ScalarGrid g = sample_field({96, 96, 96}, torus_with_bar());
    FilterOptions o;
    o.keep_genus = 1;
    o.mode = FilterMode::Fill;
    const FilterReport r = filter_grid(g, o);
    EXPECT_EQ(r.after.genus, 1) << notes_of(r);
    EXPECT_EQ(r.after.cavities, 0);
    ASSERT_EQ(r.edits.size(), 1u);
    EXPECT_EQ(r.edits[0].side, Side::Tunnel);
  }
}

TEST(Filter, NoisyTangleCubeKeepsItsFiveMostPersistentPairs) {
  ScalarGrid g = sample_field({96, 96, 96}, analytic::tangle_cube());
  add_uniform_noise(g, 0.25 * g.voxel_size, 7);  // genus 51, 3 components, 4 cavities
  const FilterSummary noisy = topology_summary(g);
  ASSERT_GT(noisy.genus, 40);
  FilterOptions o;
  o.keep_genus = 5;
  const FilterReport r = filter_grid(g, o);
  EXPECT_EQ(r.before.genus, noisy.genus);
  EXPECT_EQ(r.after.genus, 5);
  EXPECT_EQ(r.after.components, noisy.components);
  EXPECT_EQ(r.after.cavities, noisy.cavities);
  // Noise pairs are thinner than a voxel: their edits are a voxel or a few each.
  EXPECT_GE(r.edits.size(), 10u);
  EXPECT_LT(r.voxels_changed, 20 * r.edits.size());
  EXPECT_TRUE(r.notes.empty()) << notes_of(r);
  EXPECT_EQ(topology_summary(g).genus, 5);
}

// Noise of 0.4 voxel: many pairs whose saddle alone does not remove them (the vertices around it close the
// handle again, or it was a speck's only bridge). They are tried again within the round (the other side's
// saddle, each side's piece within a voxel, then a disc), so one persistence run after the first round finds
// only the few left; the edits, judged in parallel, are the same on one thread as on all.
TEST(Filter, NoisePairsWhoseSaddleFailsAreRemovedInTheSameRound) {
  ScalarGrid base = sample_field({128, 128, 128}, analytic::tangle_cube());
  add_uniform_noise(base, 0.4 * base.voxel_size, 7);
  const FilterSummary noisy = topology_summary(base);
  ASSERT_GT(noisy.genus, 400);
  FilterOptions o;
  o.keep_genus = 5;
  ScalarGrid all = base;
  const FilterReport r = filter_grid(all, o);
  EXPECT_EQ(r.after.genus, 5);
  EXPECT_EQ(r.after.components, noisy.components);
  EXPECT_EQ(r.after.cavities, noisy.cavities);
  EXPECT_TRUE(r.notes.empty()) << notes_of(r);
  EXPECT_LE(r.rounds, 2);
  EXPECT_LT(r.voxels_changed, 10 * r.edits.size());
  EXPECT_EQ(topology_summary(all).genus, 5);
  expect_the_same_on_one_thread(base, o, r, all);
}

// The same edits and the same field bit for bit on one thread as on all of them (membranes in parallel,
// labels by slabs).
TEST(Filter, ResultDoesNotDependOnTheThreadCount) {
  ScalarGrid base = sample_field({80, 80, 80}, analytic::tangle_cube());
  add_uniform_noise(base, 0.25 * base.voxel_size, 11);
  FilterOptions o;
  o.keep_genus = 5;
  ScalarGrid all = base;
  const FilterReport r = filter_grid(all, o);
  EXPECT_EQ(r.after.genus, 5);
  expect_the_same_on_one_thread(base, o, r, all);
}

TEST(Filter, ImpossibleRequestsAreRefused) {
  ScalarGrid g = sample_field({48, 48, 48}, analytic::torus(0.25, 0.08));
  FilterOptions none;
  EXPECT_THROW(filter_grid(g, none), Error);
  FilterOptions too_many;
  too_many.keep_genus = 2;
  try {
    filter_grid(g, too_many);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("more than the genus"), std::string::npos) << e.what();
  }
  // Nothing small enough: no edit, the field untouched, and the report says so by its counts.
  const ScalarGrid before = g;
  const FilterReport r = filter_grid(g, by_depth(0.001));
  EXPECT_EQ(r.selected, 0);
  EXPECT_TRUE(r.edits.empty());
  EXPECT_EQ(r.after.genus, 1);
  EXPECT_EQ(g.values, before.values);
}

namespace {
// Clean shapes and a noisy one whose membranes take specks along (add_debris).
std::vector<ScalarGrid> membrane_test_grids() {
  std::vector<ScalarGrid> grids{sample_field({96, 96, 96}, torus_with_bar()), sample_field({96, 96, 96}, drilled_ball(0.05)),
                                sample_field({80, 80, 80}, analytic::tangle_cube())};
  add_uniform_noise(grids[2], 0.25 * grids[2].voxel_size, 7);
  return grids;
}
}  // namespace

// The label volumes clip each membrane's flood to its side's region (region_bounds): the same membranes,
// shore for shore, as the flood over the whole box, on clean shapes and on a noisy one whose membranes take
// specks along (add_debris).
TEST(MembraneVoxels, ClippedToTheRegionTheyAreTheSame) {
  const std::vector<ScalarGrid> grids = membrane_test_grids();
  int compared = 0, with_more_than_a_voxel = 0;
  for (const ScalarGrid& g : grids) {
    const auto bounds = region_bounds(g);
    ChokeParameters p;
    const ChokeSet set = find_chokes(g, lower_star_persistence(g), p);
    ASSERT_FALSE(set.chokes.empty());
    for (const Choke& c : set.chokes)
      for (MembraneShape shape : {MembraneShape::Sheet, MembraneShape::Plane}) {
        const MembraneVoxels whole = membrane_voxels(g, c, {}, shape);
        const MembraneVoxels clipped = membrane_voxels(g, c, {}, shape, &bounds);
        EXPECT_EQ(whole.found, clipped.found);
        EXPECT_EQ(whole.shore, clipped.shore);
        EXPECT_EQ(whole.box_radius, clipped.box_radius);
        EXPECT_EQ(whole.note, clipped.note);
        ++compared;
        with_more_than_a_voxel += whole.found && whole.shore.size() > 1;
      }
  }
  EXPECT_GE(compared, 20);
  EXPECT_GE(with_more_than_a_voxel, 4);
}

// closing_membrane_voxels reads the sheet and the plane from one sequence of floods: what it gives is what each
// shape gives alone, the first shape when it closes and else the other, note for note.
TEST(MembraneVoxels, TheShapesFloodedTogetherAreTheShapesAlone) {
  const std::vector<ScalarGrid> grids = membrane_test_grids();
  int compared = 0, first_open = 0;
  for (const ScalarGrid& g : grids) {
    const auto bounds = region_bounds(g);
    const ChokeSet set = find_chokes(g, lower_star_persistence(g), ChokeParameters{});
    for (const Choke& c : set.chokes)
      for (MembraneShape first : {MembraneShape::Sheet, MembraneShape::Plane}) {
        const MembraneShape other = first == MembraneShape::Sheet ? MembraneShape::Plane : MembraneShape::Sheet;
        MembraneVoxels alone = membrane_voxels(g, c, {}, first, &bounds);
        if (!alone.found) alone = membrane_voxels(g, c, {}, other, &bounds), ++first_open;
        const MembraneVoxels together = closing_membrane_voxels(g, c, {}, first, false, &bounds);
        EXPECT_EQ(together.found, alone.found);
        EXPECT_EQ(together.shore, alone.shore);
        EXPECT_EQ(together.box_radius, alone.box_radius);
        EXPECT_EQ(together.note, alone.note);
        ++compared;
      }
  }
  EXPECT_GE(compared, 20);
  EXPECT_GE(first_open, 1);  // the other shape's part of the shared floods is checked too
}

// The loop stage records where its floods leave each loop's label-volume membrane (AnalyzeOptions::
// record_membranes): going on from there gives the membrane the whole sequence gives, note for note; many
// records hold the closed membrane already, and one that does is taken as it is, with no flood.
TEST(MembraneVoxels, GoingOnFromTheLoopStagesFloodsGivesTheSameMembranes) {
  // With the plane start (LoopOptions::plane_start) a generator two voxels deep or more may take its loop
  // without a flood: its record is then the sequence before its first box, which resumes to the same membrane.
  for (const bool plane_start : {false, true}) {
  int compared = 0, recorded = 0, closed_in_loop_stage = 0, unflooded_generators = 0;
  for (const ScalarGrid& g : membrane_test_grids()) {
    AnalyzeOptions o;
    o.record_membranes = true;
    o.loops.plane_start = plane_start;
    const AnalyzeResult r = analyze_grid(g, o);
    ASSERT_EQ(r.membranes.size(), r.loops.size());
    const auto bounds = region_bounds(r.grid);
    for (std::size_t i = 0; i < r.loops.size(); ++i) {
      const Choke& c = r.loops[i].choke;
      const LoopOptions lo = label_membrane_options(r.grid, c);
      const MembraneVoxels fresh = closing_membrane_voxels(r.grid, c, lo, MembraneShape::Sheet, true, &bounds);
      const MembraneVoxels resumed = closing_membrane_voxels(r.grid, c, lo, MembraneShape::Sheet, true, &bounds, &r.membranes[i]);
      EXPECT_EQ(resumed.found, fresh.found);
      EXPECT_EQ(resumed.shore, fresh.shore);
      EXPECT_EQ(resumed.box_radius, fresh.box_radius);
      EXPECT_EQ(resumed.note, fresh.note);
      // Another choke's record is not this one's.
      const MembraneProgress& other = r.membranes[(i + 1) % r.membranes.size()];
      if (other.saddle != c.saddle)
        EXPECT_EQ(closing_membrane_voxels(r.grid, c, lo, MembraneShape::Sheet, true, &bounds, &other).shore, fresh.shore);
      ++compared;
      // Every found loop whose membrane floods has its record (but a generator started from its plane
      // section); one thinner than half a voxel takes its saddle alone, before any flood, and has none.
      const bool floods = !thinner_than_half_a_voxel(r.grid, c);
      if (r.loops[i].found && floods && r.membranes[i].attempts == 0) {
        EXPECT_TRUE(plane_start && c.kind == Kind::Generator && c.depth >= 2 * r.grid.voxel_size) << i;
        ++unflooded_generators;
      }
      if (!floods) EXPECT_EQ(r.membranes[i].saddle, -1);
      recorded += r.membranes[i].attempts > 0;
      if (r.membranes[i].done && r.membranes[i].membrane[0].found && floods) {
        ++closed_in_loop_stage;
        MembraneProgress marked = r.membranes[i];
        marked.membrane[0].shore = {-7};
        EXPECT_EQ(closing_membrane_voxels(r.grid, c, lo, MembraneShape::Sheet, true, &bounds, &marked).shore, std::vector<Id>{-7});
      }
    }
  }
  EXPECT_GE(compared, 20);
  EXPECT_GE(recorded, plane_start ? 10 : 16);
  EXPECT_GE(closed_in_loop_stage, 5);
  if (plane_start) EXPECT_GE(unflooded_generators, 3);
  }
}

// Each side's bounds hold every vertex of its region and its neighbours, and nothing more.
TEST(MembraneVoxels, RegionBoundsAreTheRegionsBoxAndOneVoxel) {
  const ScalarGrid g = sample_field({64, 64, 64}, drilled_ball(0.05));
  const auto b = region_bounds(g);
  for (int side = 0; side < 2; ++side) {
    std::array<int, 3> lo{g.dims[0], g.dims[1], g.dims[2]}, hi{-1, -1, -1};
    for (int k = 0; k < g.dims[2]; ++k)
      for (int j = 0; j < g.dims[1]; ++j)
        for (int i = 0; i < g.dims[0]; ++i)
          if ((g.values[std::size_t(g.index(i, j, k))] <= 0) == (side == 0)) {
            const std::array<int, 3> q{i, j, k};
            for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], q[a]), hi[a] = std::max(hi[a], q[a]);
          }
    for (int a = 0; a < 3; ++a) {
      EXPECT_EQ(b[side].lo[a], std::max(0, lo[a] - 1)) << side << " " << a;
      EXPECT_EQ(b[side].hi[a], std::min(g.dims[a] - 1, hi[a] + 1)) << side << " " << a;
    }
  }
  EXPECT_GT(b[0].lo[0], 0);  // the ball's box lies inside the grid: the clip is not the grid
}

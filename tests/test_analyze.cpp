// End-to-end loops on analytic shapes whose answer is known: counts, positions and lengths of
// the loops, and their topology on the output surface checked with CGAL's Surface_mesh_topology.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <unordered_map>
#include <nlohmann/json.hpp>

#include "analytic_fields.h"
#include "chokeloops/analyze.h"
#include "chokeloops/loops/cut_mesh.h"
#include "chokeloops/loops/linking.h"
#include "chokeloops/surface/mesh_adjacency.h"
#include "chokeloops/surface/topology.h"

using namespace chokeloops;

namespace {

constexpr double kPi = 3.14159265358979323846;

AnalyzeResult run(const Sdf& sdf, int n, std::array<double, 3> lo, std::array<double, 3> hi,
                  const std::string& d_max = "50%", const std::string& min_persistence = "10%") {
  AnalyzeOptions o;
  o.chokes.d_max = Threshold::parse(d_max);
  o.chokes.min_persistence = Threshold::parse(min_persistence);
  return analyze_grid(sample_field({n, n, n}, sdf, lo, hi), o);
}

std::vector<const Loop*> loops_of(const AnalyzeResult& r, Side side, Kind kind) {
  std::vector<const Loop*> out;
  for (auto& l : r.loops)
    if (l.choke.side == side && l.choke.kind == kind) out.push_back(&l);
  return out;
}

double point_triangle_distance(const std::array<double, 3>& p, const std::array<double, 3>& a,
                               const std::array<double, 3>& b, const std::array<double, 3>& c) {
  // Ericson, Real-Time Collision Detection, 5.1.5.
  auto sub = [](auto x, auto y) { return std::array<double, 3>{x[0] - y[0], x[1] - y[1], x[2] - y[2]}; };
  auto dot = [](auto x, auto y) { return x[0] * y[0] + x[1] * y[1] + x[2] * y[2]; };
  auto ab = sub(b, a), ac = sub(c, a), ap = sub(p, a);
  double d1 = dot(ab, ap), d2 = dot(ac, ap);
  std::array<double, 3> q;
  auto at = [&](double v, double w) { return std::array<double, 3>{a[0] + v * ab[0] + w * ac[0], a[1] + v * ab[1] + w * ac[1], a[2] + v * ab[2] + w * ac[2]}; };
  auto bp = sub(p, b);
  double d3 = dot(ab, bp), d4 = dot(ac, bp);
  auto cp = sub(p, c);
  double d5 = dot(ab, cp), d6 = dot(ac, cp);
  double vc = d1 * d4 - d3 * d2, vb = d5 * d2 - d1 * d6, va = d3 * d6 - d5 * d4;
  if (d1 <= 0 && d2 <= 0) q = a;
  else if (d3 >= 0 && d4 <= d3) q = b;
  else if (vc <= 0 && d1 >= 0 && d3 <= 0) q = at(d1 / (d1 - d3), 0);
  else if (d6 >= 0 && d5 <= d6) q = c;
  else if (vb <= 0 && d2 >= 0 && d6 <= 0) q = at(0, d2 / (d2 - d6));
  else if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    q = {b[0] + w * (c[0] - b[0]), b[1] + w * (c[1] - b[1]), b[2] + w * (c[2] - b[2])};
  } else {
    double den = 1 / (va + vb + vc);
    q = at(vb * den, vc * den);
  }
  auto d = sub(p, q);
  return std::sqrt(dot(d, d));
}

// Faces of a surface bucketed by the grid cells their bounding boxes touch.
struct FaceHash {
  double cell;
  std::unordered_map<std::int64_t, std::vector<int>> buckets;
  std::int64_t key(std::int64_t i, std::int64_t j, std::int64_t k) const { return (i * 73856093) ^ (j * 19349663) ^ (k * 83492791); }
  FaceHash(const SurfaceMesh& m, double voxel) : cell(voxel) {
    for (int f = 0; f < int(m.faces.size()); ++f) {
      std::array<std::int64_t, 3> lo, hi;
      for (int a = 0; a < 3; ++a) {
        double mn = 1e300, mx = -1e300;
        for (int q = 0; q < 3; ++q) { mn = std::min(mn, m.vertices[m.faces[f][q]][a]); mx = std::max(mx, m.vertices[m.faces[f][q]][a]); }
        lo[a] = std::int64_t(std::floor(mn / cell)) - 1;
        hi[a] = std::int64_t(std::floor(mx / cell)) + 1;
      }
      for (auto i = lo[0]; i <= hi[0]; ++i)
        for (auto j = lo[1]; j <= hi[1]; ++j)
          for (auto k = lo[2]; k <= hi[2]; ++k) buckets[key(i, j, k)].push_back(f);
    }
  }
  const std::vector<int>& near(const std::array<double, 3>& p) const {
    static const std::vector<int> none;
    auto it = buckets.find(key(std::int64_t(std::floor(p[0] / cell)), std::int64_t(std::floor(p[1] / cell)), std::int64_t(std::floor(p[2] / cell))));
    return it == buckets.end() ? none : it->second;
  }
};

// Every loop found, closed, simple, on the surface; generators non-contractible, chokes separating.
// `chokes_separate`: false when an additional loop may be homologous to a generator (a cavity with two
// mouths: one mouth is the tunnel generator, the other the choke; neither separates the surface).
void expect_valid_loops(const AnalyzeResult& r, bool chokes_separate = true) {
  SurfaceTopology topo(r.surface);
  FaceHash hash(r.surface, r.grid.voxel_size);
  for (const Loop& l : r.loops) {
    SCOPED_TRACE(std::string(to_string(l.choke.side)) + " " + to_string(l.choke.kind) + " depth " + std::to_string(l.choke.depth));
    ASSERT_TRUE(l.found) << l.note;
    ASSERT_GE(l.points.size(), 3u);
    ASSERT_TRUE(loop_is_simple(l.edge_path));
    // On the surface: each point within 1e-6 voxel of some face (faces hashed by their bounding boxes).
    double worst = 0;
    for (auto& p : l.points) {
      double best = 1e300;
      for (int f : hash.near(p)) {
        auto& F = r.surface.faces[f];
        best = std::min(best, point_triangle_distance(p, r.surface.vertices[F[0]], r.surface.vertices[F[1]], r.surface.vertices[F[2]]));
      }
      worst = std::max(worst, best);
    }
    EXPECT_LT(worst, 1e-6 * r.grid.voxel_size + 1e-12);
    // An additional loop passes near its choke point: within its depth (the membrane's radius) plus the
    // slide toward the narrowest section (at most depth + 2 voxels) plus discretisation. Generators are
    // exempt: their saddle may lie anywhere on a flat core (a tube's ridge, a shell's mid-surface); they
    // are checked by non-contractibility and, per shape, by where they must be.
    double near = 1e300;
    for (auto& p : l.points)
      near = std::min(near, std::hypot(p[0] - l.choke.point[0], p[1] - l.choke.point[1], p[2] - l.choke.point[2]));
    if (l.choke.kind == Kind::Choke) EXPECT_LE(near, 2 * l.choke.depth + 4 * r.grid.voxel_size);
    if (l.choke.kind == Kind::Generator) EXPECT_FALSE(topo.contractible(l.edge_path));
    else if (chokes_separate) EXPECT_TRUE(topo.separates(l.edge_path));
  }
  // A handle loop bounds in the solid, a tunnel loop in the outside: it links no cycle of the other side
  // (the cycles the other side's generator chokes close span that side's homology).
  for (const Loop& l : r.loops) {
    if (l.choke.kind != Kind::Generator) continue;
    for (const Choke& c : r.chokes.chokes) {
      if (c.kind != Kind::Generator || c.side == l.choke.side) continue;
      const Polyline3 cycle = generator_cycle(r.grid, c);
      ASSERT_GE(cycle.size(), 3u) << "no cycle for the " << to_string(c.side) << " generator at depth " << c.depth;
      EXPECT_EQ(linking_number(l.points, cycle), std::optional<int>(0))
          << to_string(l.choke.side) << " loop at depth " << l.choke.depth << " links the " << to_string(c.side)
          << " cycle at depth " << c.depth;
    }
  }
}

}  // namespace

TEST(AnalyzeAnalytic, VaryingTorusHandleAtThinnestSection) {
  // Tube radius 0.15 + 0.06 cos t around R = 0.5: thinnest (0.09) at t = pi, i.e. on the -x side.
  const int n = 192;
  AnalyzeResult r = run(analytic::varying_torus(), n, {-0.25, -0.25, -0.25}, {1.25, 1.25, 1.25});
  EXPECT_EQ(r.surface_stats.genus, 1);
  auto handles = loops_of(r, Side::Handle, Kind::Generator);
  auto tunnels = loops_of(r, Side::Tunnel, Kind::Generator);
  ASSERT_EQ(handles.size(), 1u);
  ASSERT_EQ(tunnels.size(), 1u);
  const Loop& h = *handles[0];
  ASSERT_TRUE(h.found) << h.note;
  const double voxel = r.grid.voxel_size;
  // The thinnest section is the half-plane y = 0.5, x < 0.5: every loop point within 2 voxels of it.
  double off = 0;
  for (auto& p : h.points) off = std::max(off, std::abs(p[1] - 0.5));
  EXPECT_LE(off, 2 * voxel);
  EXPECT_LT(h.centroid[0], 0.5 - 0.3);
  EXPECT_NEAR(h.length, 2 * kPi * 0.09, 0.05 * 2 * kPi * 0.09);
  expect_valid_loops(r);
}

TEST(AnalyzeAnalytic, DumbbellHasOneNeckLoop) {
  // Two balls (r 0.2) joined by a neck of radius 0.12: the neck's depth is 60% of R_in, so d_max 75%.
  AnalyzeResult r = run(analytic::dumbbell(), 128, {0, 0, 0}, {1, 1, 1}, "75%", "10%");
  EXPECT_EQ(r.chokes.handle_generators, 0);
  EXPECT_EQ(r.chokes.tunnel_generators, 0);
  auto necks = loops_of(r, Side::Handle, Kind::Choke);
  ASSERT_EQ(necks.size(), 1u);
  EXPECT_TRUE(loops_of(r, Side::Tunnel, Kind::Choke).empty());
  const Loop& neck = *necks[0];
  EXPECT_NEAR(neck.length, 2 * kPi * 0.12, 0.05 * 2 * kPi * 0.12);
  EXPECT_NEAR(std::abs(neck.normal[0]), 1.0, 0.02);  // the neck loop goes around the x axis
  expect_valid_loops(r);
}

TEST(AnalyzeAnalytic, ANeckBelowMinPersistenceIsReportedAsTheStrongestFiltered) {
  // The neck (depth 0.12, balls 0.2) lives ~40% of R_in: kept at 30%; filtered at 50% but then named as
  // the strongest filtered candidate, with the kept choke's depth and persistence.
  ScalarGrid grid = sample_field({96, 96, 96}, analytic::dumbbell(), {0, 0, 0}, {1, 1, 1});
  PersistenceDiagram diagram = lower_star_persistence(grid);
  ChokeParameters kept, filtered;
  kept.d_max = filtered.d_max = Threshold::parse("75%");
  kept.min_persistence = Threshold::parse("30%");
  filtered.min_persistence = Threshold::parse("50%");
  ChokeSet with = find_chokes(grid, diagram, kept), without = find_chokes(grid, diagram, filtered);
  ASSERT_EQ(with.chokes.size(), 1u);
  EXPECT_NEAR(with.chokes[0].depth, 0.12, 2 * grid.voxel_size);
  EXPECT_TRUE(without.chokes.empty());
  EXPECT_DOUBLE_EQ(without.strongest_filtered_handle[0], with.chokes[0].depth);
  EXPECT_DOUBLE_EQ(without.strongest_filtered_handle[1], with.chokes[0].persistence);
  // With the neck kept, what is filtered is sampling noise, far weaker than the neck.
  EXPECT_GT(with.strongest_filtered_handle[1], 0.0);
  EXPECT_LT(with.strongest_filtered_handle[1], 0.25 * with.chokes[0].persistence);
  EXPECT_LT(without.strongest_filtered_tunnel[1], 0.1 * without.R_out);  // no pocket outside the dumbbell
}

TEST(AnalyzeAnalytic, DoubleTorusHasTwoPlusTwoGenerators) {
  AnalyzeResult r = run(analytic::double_torus(), 128, {0, 0, 0}, {1, 1, 1});
  EXPECT_EQ(r.surface_stats.genus, 2);
  auto handles = loops_of(r, Side::Handle, Kind::Generator);
  auto tunnels = loops_of(r, Side::Tunnel, Kind::Generator);
  ASSERT_EQ(handles.size(), 2u);
  ASSERT_EQ(tunnels.size(), 2u);
  for (auto* l : handles) EXPECT_NEAR(l->length, 2 * kPi * 0.07, 0.05 * 2 * kPi * 0.07);
  for (auto* l : tunnels) EXPECT_NEAR(l->length, 2 * kPi * 0.10, 0.05 * 2 * kPi * 0.10);
  expect_valid_loops(r);
}

TEST(AnalyzeAnalytic, HollowBallWithThroughHoleHasTheCavityMouth) {
  // Shell 0.25..0.4 drilled through along x (hole radius 0.06): genus 1, and the cavity, open at two
  // mouths, is one more tunnel choke whose loop is a mouth of the hole.
  AnalyzeResult r = run(analytic::hollow_ball_through_hole(), 128, {0, 0, 0}, {1, 1, 1});
  EXPECT_EQ(r.surface_stats.genus, 1);
  EXPECT_EQ(loops_of(r, Side::Handle, Kind::Generator).size(), 1u);
  EXPECT_EQ(loops_of(r, Side::Tunnel, Kind::Generator).size(), 1u);
  auto mouths = loops_of(r, Side::Tunnel, Kind::Choke);
  ASSERT_EQ(mouths.size(), 1u);
  EXPECT_NEAR(mouths[0]->choke.depth, 0.06, 2 * r.grid.voxel_size);
  EXPECT_NEAR(mouths[0]->length, 2 * kPi * 0.06, 0.08 * 2 * kPi * 0.06);
  expect_valid_loops(r, false);
  SurfaceTopology topo(r.surface);
  EXPECT_FALSE(topo.contractible(mouths[0]->edge_path));  // homologous to the other mouth (the generator)
}

namespace {
// loops.json (without timings) and surface.ply of an analysis run on `threads` threads.
std::string report_with_threads(const ScalarGrid& field, int threads) {
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
  AnalyzeOptions o;
  AnalyzeResult r = analyze_grid(field, o);
  auto dir = std::filesystem::temp_directory_path() / ("chokeloops_threads_" + std::to_string(threads) + "_" +
                                                       std::to_string(field.values.size()));
  write_report(r, o, dir.string());
  nlohmann::json j = nlohmann::json::parse(std::ifstream(dir / "loops.json"));
  j.erase("timings_ms");
  std::ifstream ply(dir / "surface.ply", std::ios::binary);
  std::string surface((std::istreambuf_iterator<char>(ply)), std::istreambuf_iterator<char>());
  std::filesystem::remove_all(dir);
  return j.dump() + surface;
}
}  // namespace

TEST(AnalyzeAnalytic, SameReportWithOneAndTwoThreads) {
  const ScalarGrid field = sample_field({96, 96, 96}, analytic::double_torus());
  std::string one = report_with_threads(field, 1), two = report_with_threads(field, 2);
  EXPECT_GT(one.size(), 1000u);
  EXPECT_TRUE(one == two);
}

TEST(AnalyzeAnalytic, PiercedBlockHandleLoopsCutItToOneSphere) {
  // A block pierced by 6 holes of several radii: each handle loop bounds in the solid, so cutting the surface
  // along all of them leaves one sphere. Non-contractibility alone let two of them be curves around a hole
  // (the rims of membranes spread along a thin wall): the cut then left genus 2 in two pieces.
  AnalyzeResult r = analyze_grid(sample_field({128, 128, 128}, analytic::pierced_block(6, 7)), AnalyzeOptions{});
  ASSERT_EQ(r.surface_stats.genus, 6);
  expect_valid_loops(r);
  std::vector<std::vector<int>> handles;
  for (const Loop& l : r.loops)
    if (l.choke.kind == Kind::Generator && l.choke.side == Side::Handle) handles.push_back(l.edge_path);
  ASSERT_EQ(handles.size(), 6u);
  const CutResult c = cut_along_loops(TriangleMesh{r.surface.vertices, r.surface.faces}, handles);
  EXPECT_EQ(c.loops_cut, 6);
  EXPECT_TRUE(c.notes.empty());
  EXPECT_EQ(c.after.genus, 0);
  EXPECT_EQ(c.after.components, 1u);
}

TEST(AnalyzeAnalytic, PiercedBlockHandleLoopsAreIndependent) {
  // 30 holes at 128: some handle generators' loops, each bounding in the solid, fall in the class of others
  // (cutting along all of them split the block in two). Those are reported missing with a note, so cutting
  // along the rest keeps one piece and lowers the genus by exactly their number.
  AnalyzeResult r = analyze_grid(sample_field({128, 128, 128}, analytic::pierced_block(30, 7)), AnalyzeOptions{});
  ASSERT_EQ(r.surface_stats.genus, 30);
  std::vector<std::vector<int>> handles;
  int dependent = 0;
  for (const Loop& l : r.loops) {
    if (l.choke.kind != Kind::Generator || l.choke.side != Side::Handle) continue;
    if (l.found) handles.push_back(l.edge_path);
    else dependent += l.note.find("class of more persistent") != std::string::npos;
  }
  EXPECT_GE(handles.size(), 20u);
  EXPECT_GE(dependent, 1);
  const CutResult c = cut_along_loops(TriangleMesh{r.surface.vertices, r.surface.faces}, handles);
  EXPECT_EQ(c.after.components, 1u);
  EXPECT_EQ(c.after.genus, 30 - c.loops_cut);
}

TEST(AnalyzeAnalytic, PlaneStartGivesTheMembranesGeneratorLoops) {
  // A generator two voxels deep or more starts from the section by the plane square to its cycle instead of
  // its membrane (LoopOptions::plane_start): after shortening, the same loops within a small fraction of
  // their length, on the pierced block (bars between holes, long loops) and the cage (sticks); and those
  // loops did not flood (no record of a box for their label volume).
  struct Case { ScalarGrid field; int plane_started_at_least; bool chokes_separate; };
  std::vector<Case> cases;
  cases.push_back({sample_field({128, 128, 128}, analytic::pierced_block(6, 7)), 3, true});
  cases.push_back({sample_field({80, 80, 80}, analytic::ball_and_stick_cage({3, 2, 2})), 10, false});  // see the cage's test below
  for (const Case& k : cases) {
    AnalyzeOptions with, without;
    with.record_membranes = without.record_membranes = true;
    without.loops.plane_start = false;
    const AnalyzeResult a = analyze_grid(k.field, without), b = analyze_grid(k.field, with);
    ASSERT_EQ(a.loops.size(), b.loops.size());
    expect_valid_loops(b, k.chokes_separate);
    int plane_started = 0, compared = 0;
    double worst = 0;
    for (std::size_t i = 0; i < a.loops.size(); ++i) {
      const Loop &x = a.loops[i], &y = b.loops[i];
      if (x.choke.kind != Kind::Generator) {
        EXPECT_TRUE(x.points == y.points) << i;  // chokes never start from a plane
        continue;
      }
      plane_started += y.found && b.membranes[i].attempts == 0 && a.membranes[i].attempts > 0;
      if (!x.found || !y.found) continue;
      ++compared;
      worst = std::max(worst, std::abs(y.length / x.length - 1));
    }
    EXPECT_GE(plane_started, k.plane_started_at_least);
    EXPECT_GE(compared, 10);
    EXPECT_LT(worst, 2e-3);
  }
}

TEST(AnalyzeAnalytic, LongPlaneStartsShortenedFromTheirStripEndAtTheBandSearchsLoops) {
  // On the pierced block at 256 the sections round the block of its handle generators cross 2,000-2,700
  // faces, past LoopOptions::strip_start_faces (five of them): one of their loops finishes inside those faces
  // and ends within 1e-4 of the band search's loop from the same section; every other loop, the four still
  // moving after their rounds included, is the band search's point for point (a strip start that does not
  // finish leaves no trace).
  const ScalarGrid field = sample_field({256, 256, 256}, analytic::pierced_block(6, 7));
  AnalyzeOptions with, without;
  without.loops.strip_start_faces = std::numeric_limits<std::size_t>::max();
  const AnalyzeResult a = analyze_grid(field, without), b = analyze_grid(field, with);
  ASSERT_EQ(a.loops.size(), b.loops.size());
  expect_valid_loops(b);
  int from_strip = 0;
  for (std::size_t i = 0; i < a.loops.size(); ++i) {
    const Loop &x = a.loops[i], &y = b.loops[i];
    EXPECT_FALSE(x.from_strip) << i;
    EXPECT_EQ(x.found, y.found) << i;
    if (!y.from_strip) {
      EXPECT_TRUE(x.points == y.points) << i;
      continue;
    }
    ++from_strip;
    EXPECT_EQ(y.choke.kind, Kind::Generator) << i;
    EXPECT_NEAR(y.length, x.length, 1e-4 * x.length) << i;
  }
  EXPECT_GE(from_strip, 1);
}

TEST(AnalyzeAnalytic, CageHasALoopPerHandleAndNeckTheSameWithOneAndTwoThreads) {
  // 3x2x2 balls, 20 sticks: genus 20 - 12 + 1 = 9, a neck on every stick; many loops traced at once, so
  // the per-thread scratch of the loop stage is exercised by concurrent loops.
  const ScalarGrid field = sample_field({80, 80, 80}, analytic::ball_and_stick_cage({3, 2, 2}));
  AnalyzeResult r = analyze_grid(field, AnalyzeOptions{});
  EXPECT_EQ(r.surface_stats.genus, 9);
  EXPECT_EQ(r.chokes.handle_generators, 9);
  EXPECT_EQ(r.chokes.tunnel_generators, 9);
  EXPECT_GE(loops_of(r, Side::Handle, Kind::Choke).size(), 1u);
  expect_valid_loops(r, false);
  std::string one = report_with_threads(field, 1), two = report_with_threads(field, 2);
  EXPECT_TRUE(one == two);
}

TEST(AnalyzeAnalytic, LoopStageReportsEachLoopAndStopsBetweenLoopsWhenAsked) {
  // The loop stage tells the caller (its thread only) how far it is as loops finish, and a caller that asks
  // to stop is heard at the next loop, not at the stage's end; the loops do not depend on being watched.
  const ScalarGrid field = sample_field({64, 64, 64}, analytic::ball_and_stick_cage({3, 2, 2}));
  const AnalyzeResult unwatched = analyze_grid(field, AnalyzeOptions{});
  ASSERT_GE(unwatched.loops.size(), 10u);
  for (int threads : {1, 2}) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, std::size_t(threads));
    std::vector<double> fractions;
    const AnalyzeResult watched = analyze_grid(field, AnalyzeOptions{}, [&](const char* stage, double f) {
      if (std::string(stage) == "loops") fractions.push_back(f);
      return true;
    });
    ASSERT_EQ(watched.loops.size(), unwatched.loops.size());
    for (std::size_t i = 0; i < watched.loops.size(); ++i) {
      EXPECT_EQ(watched.loops[i].found, unwatched.loops[i].found) << i;
      EXPECT_TRUE(watched.loops[i].points == unwatched.loops[i].points) << i;
    }
    // The stage's start, then one report per loop the calling thread finished (all of them with one thread),
    // then the end.
    ASSERT_GE(fractions.size(), 3u) << threads;
    EXPECT_EQ(fractions.front(), 0.0);
    EXPECT_EQ(fractions.back(), 1.0);
    EXPECT_TRUE(std::is_sorted(fractions.begin(), fractions.end()));
    if (threads == 1) {
      EXPECT_EQ(fractions.size(), unwatched.loops.size() + 2);
      EXPECT_DOUBLE_EQ(fractions[1], 1.0 / double(unwatched.loops.size()));
    }

    // Stopped at the first loop done: no other loop report comes, and the run throws "interrupted".
    int reports_after_stop = 0;
    double stopped_at = -1;
    bool stopped = false;
    try {
      analyze_grid(field, AnalyzeOptions{}, [&](const char* stage, double f) {
        if (std::string(stage) != "loops" || f == 0) return true;
        if (stopped) ++reports_after_stop;
        if (!stopped) stopped = true, stopped_at = f;
        return false;
      });
      ADD_FAILURE() << "not interrupted";
    } catch (const Error& e) {
      EXPECT_STREQ(e.what(), "interrupted");
    }
    EXPECT_TRUE(stopped);
    EXPECT_EQ(reports_after_stop, 0);
    // A hook that throws instead: its own exception comes out.
    struct HookThrew {};
    EXPECT_THROW(analyze_grid(field, AnalyzeOptions{}, [](const char* stage, double f) {
                   if (std::string(stage) == "loops" && f > 0) throw HookThrew{};
                   return true;
                 }),
                 HookThrew);
    EXPECT_LT(stopped_at, 1.0);
    if (threads == 1) EXPECT_DOUBLE_EQ(stopped_at, 1.0 / double(unwatched.loops.size()));
  }
}

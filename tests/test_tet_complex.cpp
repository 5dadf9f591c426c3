// The TetGen reference path (src/tet): lower-star persistence on an explicit tetrahedral complex by PHAT, checked
// against the grid engine on the grid's own Freudenthal triangulation, then on TetGen's complex of meshes whose
// genus and handle depth are known.
#ifdef CHOKELOOPS_HAS_TETGEN
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>
#include <tuple>

#include <tbb/global_control.h>

#include "chokeloops/analyze.h"
#include "chokeloops/field/analytic.h"
#include "chokeloops/field/levelset.h"
#include "chokeloops/io/mesh_io.h"
#include "chokeloops/surface/mesh_adjacency.h"
#include "chokeloops/surface/surface.h"
#include "chokeloops/surface/topology.h"
#include "chokeloops/tet/analyze_tet.h"
#include "chokeloops/tet/tet_field.h"
#include "chokeloops/tet/tet_persistence.h"
#include "chokeloops/topology/persistence.h"

using chokeloops::Sdf;

using namespace chokeloops;

namespace {

// The six tets of each cube of the grid along its (0,0,0)-(1,1,1) diagonal: the grid engine's triangulation.
std::vector<std::array<std::int32_t, 4>> freudenthal_tets(const std::array<int, 3>& n) {
  std::vector<std::array<std::int32_t, 4>> tets;
  auto id = [&](int i, int j, int k) { return std::int32_t(i + n[0] * (j + n[1] * k)); };
  static constexpr int kPerm[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  for (int k = 0; k + 1 < n[2]; ++k)
    for (int j = 0; j + 1 < n[1]; ++j)
      for (int i = 0; i + 1 < n[0]; ++i)
        for (const auto& p : kPerm) {
          std::array<int, 3> c{i, j, k};
          std::array<std::int32_t, 4> t;
          t[0] = id(c[0], c[1], c[2]);
          for (int s = 0; s < 3; ++s) {
            ++c[std::size_t(p[s])];
            t[std::size_t(s) + 1] = id(c[0], c[1], c[2]);
          }
          tets.push_back(t);
        }
  return tets;
}

// The dim-1 pairs of the genus: born inside (birth <= 0), dying outside (death > 0).
std::vector<TetPersistencePair> genus_pairs(const TetDiagram& d) {
  std::vector<TetPersistencePair> out;
  for (const auto& p : d.pairs)
    if (p.dim == 1 && p.birth <= 0 && p.death > 0) out.push_back(p);
  return out;
}

TriangleMesh mesh_of(const SurfaceMesh& s) { return TriangleMesh{s.vertices, s.faces}; }

// The mesh is refused as bad input (exit 2) with a message containing `why`.
void expect_refused(const TriangleMesh& m, const std::string& why) {
  try {
    tetrahedralize_with_distance(m);
    FAIL() << "a mesh that should fail with '" << why << "' was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.exit_code, 2);
    EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
  }
}

constexpr double kPi = 3.14159265358979323846;

// Every loop of a tet analysis: found; its edge path a closed path of the input's own edges, and each of its
// points on the input vertex or edge it names; a generator's loop non-contractible on the input (CGAL's
// Surface_mesh_topology, asked directly).
void expect_loops_on_input_edges(const TetAnalysis& a) {
  const MeshAdjacency adj = build_adjacency(a.input);
  ASSERT_EQ(a.loops.size(), a.chokes.chokes.size());
  for (std::size_t i = 0; i < a.loops.size(); ++i) {
    const InputLoop& l = a.loops[i];
    SCOPED_TRACE("loop " + std::to_string(i) + " " + to_string(l.loop.choke.side) + " " + to_string(l.loop.choke.kind));
    ASSERT_TRUE(l.loop.found) << l.loop.note;
    EXPECT_TRUE(l.verified);
    const auto& p = l.loop.edge_path;
    ASSERT_GE(p.size(), 3u);
    for (std::size_t k = 0; k < p.size(); ++k) EXPECT_TRUE(adj.has_edge(a.input, p[k], p[(k + 1) % p.size()]));
    if (l.loop.choke.kind == Kind::Generator) EXPECT_FALSE(loop_is_contractible(a.input, p));
    ASSERT_EQ(l.where.size(), l.loop.points.size());
    for (std::size_t k = 0; k < l.where.size(); ++k) {
      const InputPoint& w = l.where[k];
      const auto& x = l.loop.points[k];
      std::array<double, 3> on{};
      if (w.vertex >= 0) {
        on = a.input.vertices[std::size_t(w.vertex)];
      } else {
        ASSERT_TRUE(adj.has_edge(a.input, w.edge[0], w.edge[1]));
        const auto &u = a.input.vertices[std::size_t(w.edge[0])], &v = a.input.vertices[std::size_t(w.edge[1])];
        for (int c = 0; c < 3; ++c) on[std::size_t(c)] = u[std::size_t(c)] + w.t * (v[std::size_t(c)] - u[std::size_t(c)]);
      }
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(x[std::size_t(c)], on[std::size_t(c)], 1e-9);
    }
  }
}

std::vector<const InputLoop*> loops_of(const TetAnalysis& a, Side side, Kind kind) {
  std::vector<const InputLoop*> out;
  for (const InputLoop& l : a.loops)
    if (l.loop.choke.side == side && l.loop.choke.kind == kind) out.push_back(&l);
  return out;
}

}  // namespace

TEST(TetPersistence, EqualsTheGridEngineOnItsOwnTriangulationOfARoughField) {
  const std::array<int, 3> n{14, 12, 10};
  ScalarGrid g = sample_field(n, analytic::torus(0.3, 0.12), {0, 0, 0}, {1, 11.0 / 13, 9.0 / 13});
  add_uniform_noise(g, 0.3, 7);
  const PersistenceDiagram grid = lower_star_persistence(g);
  std::vector<double> values(g.values.begin(), g.values.end());
  const TetDiagram tet = tet_lower_star_persistence(std::int32_t(values.size()), freudenthal_tets(n), values);
  std::multiset<std::tuple<int, Id, Id>> expected, got;
  for (const auto& p : grid.pairs) expected.insert({p.dim, p.birth_vertex, p.death_vertex});
  for (const auto& p : tet.pairs) got.insert({p.dim, p.birth_vertex, p.death_vertex});
  ASSERT_GT(expected.size(), 100u);  // rough: many pairs in every dimension
  EXPECT_EQ(got, expected);
  ASSERT_EQ(tet.essential.size(), 1u);
  EXPECT_EQ(tet.essential[0].dim, 0);
  EXPECT_EQ(tet.simplices[3], std::int64_t(13 * 11 * 9 * 6));
}

TEST(TetComplex, MeshesHaveAsManyGenusPairsAsTheGridPathWithTheDeepestHandleWithinTwoVoxels) {
  const std::string data = std::string(CHOKELOOPS_DATA) + "/meshes/";
  for (const auto& [file, genus] : {std::pair<std::string, int>{"genus3_directional.off", 3}, {"kitten_euclid.off", 1}}) {
    SCOPED_TRACE(file);
    const TriangleMesh mesh = read_mesh(data + file);
    LevelSetOptions lo;
    lo.resolution = 128;
    lo.quiet = true;
    const LevelSetResult grid = mesh_to_levelset(mesh, lo, file);
    double grid_deepest = 0;
    int grid_pairs = 0;
    for (const auto& p : lower_star_persistence(grid.grid).pairs)
      if (p.dim == 1 && p.birth <= 0 && p.death > 0) ++grid_pairs, grid_deepest = std::max(grid_deepest, double(-p.birth));
    const TetField field = tetrahedralize_with_distance(mesh);
    const auto pairs = genus_pairs(tet_lower_star_persistence(std::int32_t(field.vertices.size()), field.tets, field.values, &field.inside_tets));
    EXPECT_EQ(grid_pairs, genus);
    EXPECT_EQ(int(pairs.size()), genus);
    double deepest = 0;
    for (const auto& p : pairs) deepest = std::max(deepest, -p.birth);
    EXPECT_NEAR(deepest, grid_deepest, 2 * grid.grid.voxel_size);
  }
}

TEST(TetComplex, TorusDepthsAreItsRadiiWithinTwoVoxelsOfTheGridRun) {
  // Tube radius 0.1 (the handle's depth), hole radius 0.2 (the tunnel's); the grid run at 96^3.
  const Sdf torus = analytic::torus(0.3, 0.1);
  const ScalarGrid fine = sample_field({96, 96, 96}, torus);
  std::vector<PersistencePair> grid;
  for (const auto& p : lower_star_persistence(fine).pairs)
    if (p.dim == 1 && p.birth <= 0 && p.death > 0) grid.push_back(p);
  ASSERT_EQ(grid.size(), 1u);
  // Both samplings: the default graded one (fine near the surface and across the tube's core and the hole's
  // middle, coarse elsewhere) with far fewer tets than the uniform lattice of the same spacing.
  const TriangleMesh mesh = mesh_of(extract_zero_surface(sample_field({40, 40, 40}, torus)));
  std::size_t tets[2] = {0, 0};
  for (const double grading : {0.0, TetOptions{}.grading}) {
    SCOPED_TRACE("grading " + std::to_string(grading));
    TetOptions o;
    o.grading = grading;
    const TetField field = tetrahedralize_with_distance(mesh, o);
    tets[grading > 0] = field.tets.size();
    const auto pairs = genus_pairs(tet_lower_star_persistence(std::int32_t(field.vertices.size()), field.tets, field.values, &field.inside_tets));
    ASSERT_EQ(pairs.size(), 1u);
    EXPECT_NEAR(-pairs[0].birth, -grid[0].birth, 2 * fine.voxel_size);
    EXPECT_NEAR(pairs[0].death, grid[0].death, 2 * fine.voxel_size);
    EXPECT_NEAR(-pairs[0].birth, 0.1, 0.02);
    EXPECT_NEAR(pairs[0].death, 0.2, 0.02);
  }
  EXPECT_LT(tets[1], tets[0] * 2 / 3);
}

TEST(TetComplex, DoubleTorusHasTwoGenusPairsAsTheGridPath) {
  const Sdf shape = analytic::double_torus();
  const ScalarGrid fine = sample_field({96, 96, 96}, shape);
  int grid_pairs = 0;
  for (const auto& p : lower_star_persistence(fine).pairs) grid_pairs += p.dim == 1 && p.birth <= 0 && p.death > 0;
  const TetField field = tetrahedralize_with_distance(mesh_of(extract_zero_surface(sample_field({40, 40, 40}, shape))));
  const auto pairs = genus_pairs(tet_lower_star_persistence(std::int32_t(field.vertices.size()), field.tets, field.values, &field.inside_tets));
  EXPECT_EQ(grid_pairs, 2);
  EXPECT_EQ(pairs.size(), 2u);
}

TEST(TetComplex, SimplicesOutsideWithEveryVertexOnTheSurfaceEnterAfterLevelZero) {
  // No interior points: most tets have all their vertices on the surface. Taken at 0 with the solid, those
  // outside it close and open loops that the solid does not have.
  TetOptions o;
  o.spacing = 1e9;
  const TetField field = tetrahedralize_with_distance(read_mesh(std::string(CHOKELOOPS_DATA) + "/meshes/kitten_euclid.off"), o);
  const std::int32_t n = std::int32_t(field.vertices.size());
  EXPECT_EQ(genus_pairs(tet_lower_star_persistence(n, field.tets, field.values, &field.inside_tets)).size(), 1u);
  EXPECT_NE(genus_pairs(tet_lower_star_persistence(n, field.tets, field.values)).size(), 1u);
  // Its tunnel dies at 0+: the chokes table, which holds floats, must still count it.
  const TetAnalysis a = analyze_tet_complex(read_mesh(std::string(CHOKELOOPS_DATA) + "/meshes/kitten_euclid.off"), o, {});
  EXPECT_EQ(a.chokes.handle_generators, 1);
  EXPECT_EQ(a.chokes.tunnel_generators, 1);
}

TEST(TetLoops, TorusMeridianAndInnerEquatorLieOnTheInputsEdgesWithTheirLengths) {
  // Tube radius 0.1: the handle's loop is a meridian, 2 pi 0.1 long; hole radius 0.2: the tunnel's is the inner
  // equator, 2 pi 0.2 long (the marching-cubes mesh at 40^3 is within a few percent of the analytic torus).
  const TriangleMesh mesh = mesh_of(extract_zero_surface(sample_field({40, 40, 40}, analytic::torus(0.3, 0.1))));
  const TetAnalysis a = analyze_tet_complex(mesh, {}, {});
  expect_loops_on_input_edges(a);
  const auto handles = loops_of(a, Side::Handle, Kind::Generator), tunnels = loops_of(a, Side::Tunnel, Kind::Generator);
  ASSERT_EQ(handles.size(), 1u);
  ASSERT_EQ(tunnels.size(), 1u);
  EXPECT_NEAR(handles[0]->loop.length, 2 * kPi * 0.1, 0.05 * 2 * kPi * 0.1);
  EXPECT_NEAR(tunnels[0]->loop.length, 2 * kPi * 0.2, 0.05 * 2 * kPi * 0.2);
  // The meridian circles the tube near its choke point, the equator circles the axis (normal z).
  EXPECT_LT(std::hypot(handles[0]->loop.centroid[0] - handles[0]->loop.choke.point[0],
                       handles[0]->loop.centroid[1] - handles[0]->loop.choke.point[1]), 0.05);
  EXPECT_NEAR(std::abs(tunnels[0]->loop.normal[2]), 1.0, 0.02);
}

TEST(TetLoops, GenusMeshesHaveEveryGeneratorLoopNonContractibleOnTheirOwnEdges) {
  const std::string data = std::string(CHOKELOOPS_DATA) + "/meshes/";
  std::vector<std::pair<std::string, TriangleMesh>> meshes;
  meshes.push_back({"double torus", mesh_of(extract_zero_surface(sample_field({40, 40, 40}, analytic::double_torus())))});
  meshes.push_back({"genus3", read_mesh(data + "genus3_directional.off")});
  meshes.push_back({"kitten", read_mesh(data + "kitten_euclid.off")});
  for (const auto& [name, mesh] : meshes) {
    SCOPED_TRACE(name);
    const int genus = mesh_topology(mesh).genus;
    const TetAnalysis a = analyze_tet_complex(mesh, {}, {});
    EXPECT_EQ(a.chokes.handle_generators, genus);
    EXPECT_EQ(a.chokes.tunnel_generators, genus);
    EXPECT_EQ(int(loops_of(a, Side::Handle, Kind::Generator).size()), genus);
    EXPECT_EQ(int(loops_of(a, Side::Tunnel, Kind::Generator).size()), genus);
    expect_loops_on_input_edges(a);
  }
}

TEST(TetLoops, DumbbellNeckLoopCirclesTheNeck) {
  // Balls of radius 0.2 joined by a neck of radius 0.12 along x: one handle choke, its loop 2 pi 0.12 long
  // around the x axis.
  const TriangleMesh mesh = mesh_of(extract_zero_surface(sample_field({48, 48, 48}, analytic::dumbbell())));
  ChokeParameters p;
  p.d_max = Threshold::parse("75%");
  const TetAnalysis a = analyze_tet_complex(mesh, {}, p);
  expect_loops_on_input_edges(a);
  const auto necks = loops_of(a, Side::Handle, Kind::Choke);
  ASSERT_EQ(necks.size(), 1u);
  EXPECT_NEAR(necks[0]->loop.choke.depth, 0.12, 0.02);
  EXPECT_NEAR(necks[0]->loop.length, 2 * kPi * 0.12, 0.05 * 2 * kPi * 0.12);
  EXPECT_NEAR(std::abs(necks[0]->loop.normal[0]), 1.0, 0.02);
  EXPECT_TRUE(necks[0]->separating);
}

TEST(TetLoops, KittensLoopsAreTheGridPathsLoopsCarriedToTheSameMesh) {
  // Two complexes, one answer: each loop traced on TetGen's complex has the length of the grid path's loop of the
  // same side and kind carried onto the input mesh (input_loops.h), within 1%.
  const std::string file = std::string(CHOKELOOPS_DATA) + "/meshes/kitten_euclid.off";
  AnalyzeOptions options;
  options.levelset.quiet = true;
  const AnalyzeResult grid = analyze(file, options);
  const TetAnalysis tet = analyze_tet_complex(read_mesh(file), {}, options.chokes);
  ASSERT_TRUE(grid.has_input_loops);
  for (Side side : {Side::Handle, Side::Tunnel})
    for (Kind kind : {Kind::Generator, Kind::Choke}) {
      SCOPED_TRACE(std::string(to_string(side)) + " " + to_string(kind));
      std::vector<double> on_grid, on_tets;
      for (const InputLoop& l : grid.input_loops)
        if (l.loop.found && l.loop.choke.side == side && l.loop.choke.kind == kind) on_grid.push_back(l.loop.length);
      for (const InputLoop* l : loops_of(tet, side, kind))
        if (l->loop.found) on_tets.push_back(l->loop.length);
      std::sort(on_grid.begin(), on_grid.end());
      std::sort(on_tets.begin(), on_tets.end());
      ASSERT_EQ(on_tets.size(), on_grid.size());
      for (std::size_t i = 0; i < on_tets.size(); ++i) EXPECT_NEAR(on_tets[i], on_grid[i], 0.01 * on_grid[i]);
    }
  EXPECT_EQ(tet.loops.size(), 3u);
}

TEST(TetLoops, LoopsAreTheSameForOneAndTwoThreads) {
  const TriangleMesh mesh = mesh_of(extract_zero_surface(sample_field({40, 40, 40}, analytic::double_torus())));
  std::vector<std::vector<int>> paths[2];
  for (int threads : {1, 2}) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, std::size_t(threads));
    const TetAnalysis a = analyze_tet_complex(mesh, {}, {});
    for (const InputLoop& l : a.loops) paths[threads - 1].push_back(l.loop.edge_path);
  }
  ASSERT_GE(paths[0].size(), 4u);
  EXPECT_EQ(paths[0], paths[1]);
}

TEST(TetComplex, OpenMeshIsRefusedWithTheEdgeAtFault) {
  TriangleMesh m{{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}}, {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}}};
  expect_refused(m, "closed, manifold");
}

TEST(TetComplex, SamplesBeyondTheMemoryLimitAreRefusedBeforeTetGenRuns) {
  // 6 KB a vertex: 2 MB holds the torus's ~3K input vertices but not its samples at the default spacing.
  const TriangleMesh mesh = mesh_of(extract_zero_surface(sample_field({40, 40, 40}, analytic::torus(0.3, 0.1))));
  TetOptions o;
  o.max_memory = std::size_t(2) << 20;
  for (const double grading : {0.0, 2.0}) {
    o.grading = grading;
    try {
      tetrahedralize_with_distance(mesh, o);
      FAIL() << "grading " << grading << ": 2 MB was enough";
    } catch (const Error& e) {
      EXPECT_EQ(e.exit_code, 3);
      EXPECT_NE(std::string(e.what()).find("--max-memory"), std::string::npos) << e.what();
    }
  }
  o.max_memory = std::size_t(1) << 30;
  EXPECT_GT(tetrahedralize_with_distance(mesh, o).tets.size(), 0u);
}

TEST(TetComplex, SelfIntersectingMeshIsRefusedBeforeTetGenSeesIt) {
  // Two closed tetrahedra, the second's apex through the first's base.
  TriangleMesh m{{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0.2, 0.2, -0.5}, {1.2, 0.2, -0.5}, {0.2, 1.2, -0.5}, {0.2, 0.2, 0.5}},
                 {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}, {4, 6, 5}, {4, 5, 7}, {4, 7, 6}, {5, 6, 7}}};
  expect_refused(m, "intersects itself");
}
#endif

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

#include "chokeloops/field/analytic.h"
#include "chokeloops/field/levelset.h"
#include "chokeloops/io/mesh_io.h"
#include "chokeloops/surface/surface.h"
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
  const TetField field = tetrahedralize_with_distance(mesh_of(extract_zero_surface(sample_field({40, 40, 40}, torus))));
  const auto pairs = genus_pairs(tet_lower_star_persistence(std::int32_t(field.vertices.size()), field.tets, field.values, &field.inside_tets));
  ASSERT_EQ(pairs.size(), 1u);
  EXPECT_NEAR(-pairs[0].birth, -grid[0].birth, 2 * fine.voxel_size);
  EXPECT_NEAR(pairs[0].death, grid[0].death, 2 * fine.voxel_size);
  EXPECT_NEAR(-pairs[0].birth, 0.1, 0.02);
  EXPECT_NEAR(pairs[0].death, 0.2, 0.02);
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

TEST(TetComplex, OpenMeshIsRefusedWithTheEdgeAtFault) {
  TriangleMesh m{{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}}, {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}}};
  expect_refused(m, "closed, manifold");
}

TEST(TetComplex, SelfIntersectingMeshIsRefusedBeforeTetGenSeesIt) {
  // Two closed tetrahedra, the second's apex through the first's base.
  TriangleMesh m{{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0.2, 0.2, -0.5}, {1.2, 0.2, -0.5}, {0.2, 1.2, -0.5}, {0.2, 0.2, 0.5}},
                 {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}, {4, 6, 5}, {4, 5, 7}, {4, 7, 6}, {5, 6, 7}}};
  expect_refused(m, "intersects itself");
}
#endif

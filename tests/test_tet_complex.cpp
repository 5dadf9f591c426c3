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
#include "chokeloops/tet/tet_field.h"
#include "chokeloops/tet/tet_persistence.h"
#include "chokeloops/topology/persistence.h"

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

// Depths are not compared yet: with TetGen's default quality the interior has few vertices, so births are
// shallower than the grid's (genus3's deepest handle: -0.041 against -0.060 at 128^3; some handles are born at 0).
TEST(TetComplex, MeshesHaveAsManyGenusPairsAsTheGridPath) {
  const std::string data = std::string(CHOKELOOPS_DATA) + "/meshes/";
  for (const auto& [file, genus] : {std::pair<std::string, int>{"genus3_directional.off", 3}, {"kitten_euclid.off", 1}}) {
    SCOPED_TRACE(file);
    const TriangleMesh mesh = read_mesh(data + file);
    LevelSetOptions lo;
    lo.resolution = 128;
    lo.quiet = true;
    const LevelSetResult grid = mesh_to_levelset(mesh, lo, file);
    int grid_pairs = 0;
    for (const auto& p : lower_star_persistence(grid.grid).pairs) grid_pairs += p.dim == 1 && p.birth <= 0 && p.death > 0;
    const TetField field = tetrahedralize_with_distance(mesh);
    const auto pairs = genus_pairs(tet_lower_star_persistence(std::int32_t(field.vertices.size()), field.tets, field.values, &field.inside_tets));
    EXPECT_EQ(grid_pairs, genus);
    EXPECT_EQ(int(pairs.size()), genus);
    for (const auto& p : pairs) EXPECT_LE(p.birth, 0);  // 0: a handle with no tet vertex inside it deeper than the surface
    // Without the solid's tets marked, simplices outside it with every vertex on the surface join level 0.
    const auto unmarked = genus_pairs(tet_lower_star_persistence(std::int32_t(field.vertices.size()), field.tets, field.values));
    EXPECT_GT(int(unmarked.size()), genus);
  }
}

TEST(TetComplex, OpenMeshIsRefusedWithTheEdgeAtFault) {
  TriangleMesh m{{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}}, {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}}};
  try {
    tetrahedralize_with_distance(m);
    FAIL() << "an open mesh was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.exit_code, 2);
    EXPECT_NE(std::string(e.what()).find("closed, manifold"), std::string::npos) << e.what();
  }
}
#endif

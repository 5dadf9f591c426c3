// Real meshes: every closed mesh of data/MANIFEST.tsv gets exactly g handle and g tunnel
// generators and a surface of genus g; the bunny's neck; and a grid too coarse for a genus says so.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <cmath>
#include <map>
#include <set>
#include <sstream>

#include "chokeloops/analyze.h"
#include "chokeloops/surface/mesh_adjacency.h"
#include "chokeloops/surface/topology.h"

using namespace chokeloops;

namespace {

struct ManifestMesh { std::string file; int genus; };
// Names the parameter in ctest output (instead of its bytes).
void PrintTo(const ManifestMesh& m, std::ostream* os) { *os << m.file << " (genus " << m.genus << ")"; }

std::vector<ManifestMesh> closed_manifest_meshes() {
  std::vector<ManifestMesh> out;
  std::ifstream in(std::string(CHOKELOOPS_DATA) + "/MANIFEST.tsv");
  std::string line;
  std::getline(in, line);
  while (std::getline(in, line)) {
    std::vector<std::string> col;
    std::stringstream ss(line);
    for (std::string c; std::getline(ss, c, '\t');) col.push_back(c);
    if (col.size() < 10 || col[0].rfind("meshes/", 0) != 0 || col[5] != "yes") continue;
    try {
      out.push_back({col[0], std::stoi(col[9])});
    } catch (...) {
    }
  }
  return out;
}

// Models whose genus needs a finer grid than the test's 256, with the grid that keeps it (named, not dropped).
const std::map<std::string, int> kFinerGrid = {
    {"meshes/neptune_vmas.off", 472},  // parts closer than a voxel at 256 merge (surface genus 5 for 3)
};
// Models whose genus no grid that fits here keeps: tested below for saying so.
const std::map<std::string, std::string> kGenusOutOfReach = {
    {"meshes/seahorse2_100K_directional.off", "handles of a few triangles, thinner than a voxel even at 921 "
                                              "(surface genus 2 for 8): see SeahorseSaysItsGenusIsOutOfReach"},
};

}  // namespace

class ManifestMeshes : public ::testing::TestWithParam<ManifestMesh> {};

TEST_P(ManifestMeshes, GeneratorsMatchTheGenus) {
  const ManifestMesh& m = GetParam();
  auto skip = kGenusOutOfReach.find(m.file);
  if (skip != kGenusOutOfReach.end()) GTEST_SKIP() << m.file << ": " << skip->second;
  AnalyzeOptions o;
  auto finer = kFinerGrid.find(m.file);
  o.levelset.resolution = finer != kFinerGrid.end() ? finer->second : 256;
  AnalyzeResult r = analyze(std::string(CHOKELOOPS_DATA) + "/" + m.file, o);
  EXPECT_EQ(r.input_genus, m.genus);
  EXPECT_EQ(r.surface_stats.genus, m.genus);
  EXPECT_TRUE(r.surface_stats.closed_manifold);
  EXPECT_EQ(r.chokes.handle_generators, m.genus);
  EXPECT_EQ(r.chokes.tunnel_generators, m.genus);
  // Every generator found and non-contractible, by CGAL's Surface_mesh_topology (independent of the fast
  // check the loop stage uses to choose and verify its curves).
  SurfaceTopology topo(r.surface);
  int generators = 0;
  for (const Loop& l : r.loops) {
    SCOPED_TRACE(std::string(to_string(l.choke.side)) + " " + to_string(l.choke.kind) + " depth " + std::to_string(l.choke.depth));
    ASSERT_TRUE(l.found) << l.note;
    EXPECT_TRUE(loop_is_simple(l.edge_path));
    if (l.choke.kind == Kind::Generator) {
      ++generators;
      EXPECT_FALSE(topo.contractible(l.edge_path));
    }
  }
  EXPECT_EQ(generators, 2 * m.genus);
  // Every generator also carried onto the input mesh and still non-contractible there (CGAL).
  ASSERT_TRUE(r.has_input_loops);
  ASSERT_EQ(r.input_loops.size(), r.loops.size());
  SurfaceTopology input_topo(r.input_mesh.mesh);
  for (const InputLoop& l : r.input_loops) {
    if (l.loop.choke.kind != Kind::Generator) continue;
    SCOPED_TRACE(std::string("input mesh: ") + to_string(l.loop.choke.side) + " generator");
    ASSERT_TRUE(l.loop.found) << l.loop.note;
    EXPECT_TRUE(l.verified);
    EXPECT_FALSE(input_topo.contractible(l.loop.edge_path));
  }
}

GTEST_ALLOW_UNINSTANTIATED_PARAMETERIZED_TEST(ManifestMeshes);  // ManifestHasClosedMeshes reports missing data
INSTANTIATE_TEST_SUITE_P(Manifest, ManifestMeshes, ::testing::ValuesIn(closed_manifest_meshes()),
                         [](const ::testing::TestParamInfo<ManifestMesh>& info) {
                           std::string n = std::filesystem::path(info.param.file).stem().string();
                           for (char& c : n)
                             if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                           return n;
                         });

TEST(AnalyzeMeshes, ManifestHasClosedMeshes) { EXPECT_GE(closed_manifest_meshes().size(), 12u); }

namespace {

// The loop cuts the head (with the ears: the highest point) from the body (the lowest point), and the
// head side holds between 10% and 50% of the surface.
void expect_cuts_head_from_body(const AnalyzeResult& r, const Loop& neck) {
  ASSERT_EQ(neck.choke.side, Side::Handle);
  ASSERT_EQ(neck.choke.kind, Kind::Choke);
  ASSERT_TRUE(neck.found);
  EXPECT_TRUE(SurfaceTopology(r.surface).separates(neck.edge_path));
  const SurfaceMesh& S = r.surface;
  MeshAdjacency adj = build_adjacency(S);
  std::set<std::pair<int, int>> cut;
  for (std::size_t i = 0; i < neck.edge_path.size(); ++i) {
    int a = neck.edge_path[i], b = neck.edge_path[(i + 1) % neck.edge_path.size()];
    cut.insert({std::min(a, b), std::max(a, b)});
  }
  int top = 0, bottom = 0;
  for (int v = 0; v < int(S.vertices.size()); ++v) {
    if (S.vertices[v][1] > S.vertices[top][1]) top = v;
    if (S.vertices[v][1] < S.vertices[bottom][1]) bottom = v;
  }
  std::vector<char> seen(S.faces.size(), 0);
  std::vector<int> stack{adj.vf[adj.vf_start[top]]};
  seen[stack[0]] = 1;
  double head_area = 0, total_area = 0;
  auto area = [&](int f) {
    auto& A = S.vertices[S.faces[f][0]]; auto& B = S.vertices[S.faces[f][1]]; auto& C = S.vertices[S.faces[f][2]];
    double u[3] = {B[0] - A[0], B[1] - A[1], B[2] - A[2]}, w[3] = {C[0] - A[0], C[1] - A[1], C[2] - A[2]};
    return 0.5 * std::sqrt(std::pow(u[1] * w[2] - u[2] * w[1], 2) + std::pow(u[2] * w[0] - u[0] * w[2], 2) + std::pow(u[0] * w[1] - u[1] * w[0], 2));
  };
  for (int f = 0; f < int(S.faces.size()); ++f) total_area += area(f);
  while (!stack.empty()) {
    int f = stack.back();
    stack.pop_back();
    head_area += area(f);
    for (int k = 0; k < 3; ++k) {
      int a = S.faces[f][k], b = S.faces[f][(k + 1) % 3];
      if (cut.count({std::min(a, b), std::max(a, b)})) continue;
      int t = adj.twin[3 * f + k];
      if (t >= 0 && !seen[t / 3]) { seen[t / 3] = 1; stack.push_back(t / 3); }
    }
  }
  bool bottom_reached = false;
  for (int q = adj.vf_start[bottom]; q < adj.vf_start[bottom + 1]; ++q) bottom_reached |= seen[adj.vf[q]] != 0;
  EXPECT_FALSE(bottom_reached);
  EXPECT_GT(head_area / total_area, 0.10);
  EXPECT_LT(head_area / total_area, 0.50);
}

AnalyzeResult analyze_bunny(int resolution, const char* min_persistence) {
  AnalyzeOptions o;
  o.levelset.resolution = resolution;
  o.chokes.d_max = Threshold::parse("75%");
  o.chokes.min_persistence = Threshold::parse(min_persistence);
  return analyze(std::string(CHOKELOOPS_DATA) + "/meshes/bunny_libigl.off", o);
}

}  // namespace

TEST(AnalyzeMeshes, BunnyNeckWithThePapersParametersAtThePapersDensity) {
  // The paper's bunny (d_max 75%, delta_min 2.5%, k = 1) was a tetrahedral mesh with 72K interior
  // vertices; grids of 96-128 have 177K-419K inside. There the paper's parameters give its one loop, the
  // neck (head/body pair at 2.9-3.2% of R_in).
  for (int resolution : {96, 112, 128}) {
    SCOPED_TRACE("resolution " + std::to_string(resolution));
    AnalyzeResult r = analyze_bunny(resolution, "2.5%");
    ASSERT_EQ(r.loops.size(), 1u);
    expect_cuts_head_from_body(r, r.loops[0]);
  }
}

TEST(AnalyzeMeshes, BunnyNeckLoopOnAFineGrid) {
  // Sampled finer, the head/body pair converges below the paper's 2.5% (2.44%, 2.40%, 2.29%, 2.16% of
  // R_in at 192, 256, 384, 512; 2.05% on the Stanford scan): the neck shows from 2%, and at 2.5% the run
  // names it as the strongest filtered candidate.
  AnalyzeResult r = analyze_bunny(256, "2%");
  ASSERT_EQ(r.loops.size(), 1u);
  const Loop& neck = r.loops[0];
  EXPECT_GE(neck.choke.persistence / r.chokes.R_in, 0.020);
  EXPECT_LT(neck.choke.persistence / r.chokes.R_in, 0.025);
  expect_cuts_head_from_body(r, neck);
  ChokeParameters papers;
  papers.d_max = Threshold::parse("75%");
  papers.min_persistence = Threshold::parse("2.5%");
  ChokeSet at_papers = find_chokes(r.grid, r.diagram, papers);
  EXPECT_TRUE(at_papers.chokes.empty());
  EXPECT_DOUBLE_EQ(at_papers.strongest_filtered_handle[1], neck.choke.persistence);
}

TEST(AnalyzeMeshes, CoarseGridSaysSoAndNamesAResolution) {
  AnalyzeOptions o;
  o.levelset.resolution = 20;
  AnalyzeResult r = analyze(std::string(CHOKELOOPS_DATA) + "/meshes/genus3_directional.off", o);
  ASSERT_EQ(r.input_genus, 3);
  ASSERT_NE(r.surface_stats.genus, 3);
  bool said = false;
  for (auto& w : r.warnings) said |= w.find("too coarse") != std::string::npos && w.find("--resolution") != std::string::npos;
  EXPECT_TRUE(said);
  // The resolution it names keeps the genus.
  std::string hint;
  for (auto& w : r.warnings) {
    auto at = w.find("--resolution ");
    if (at != std::string::npos) hint = w.substr(at + 13);
  }
  ASSERT_FALSE(hint.empty());
  if (hint != "auto") {
    o.levelset.resolution = std::stoi(hint);
    EXPECT_EQ(analyze(std::string(CHOKELOOPS_DATA) + "/meshes/genus3_directional.off", o).surface_stats.genus, 3);
  }
}

TEST(AnalyzeMeshes, ResolutionAutoKeepsGenusAndComponents) {
  // The coarsest grid (64, x1.25 steps) whose surface has the input's genus and components, and no coarser.
  const std::string file = std::string(CHOKELOOPS_DATA) + "/meshes/genus3_directional.off";
  AnalyzeOptions o;
  o.resolution_auto = true;
  AnalyzeResult r = analyze(file, o);
  ASSERT_EQ(r.input_genus, 3);
  EXPECT_EQ(r.surface_stats.genus, 3);
  EXPECT_EQ(r.surface_stats.components, 1);
  EXPECT_GE(r.resolution, 64);
  EXPECT_LE(r.resolution, 256);
  EXPECT_EQ(r.chokes.handle_generators, 3);
  if (r.resolution > 64) {
    AnalyzeOptions coarser;
    coarser.levelset.resolution = int(r.resolution / 1.25);
    AnalyzeResult c = analyze(file, coarser);
    EXPECT_TRUE(c.surface_stats.genus != 3 || c.surface_stats.components != 1) << "resolution " << coarser.levelset.resolution;
  }
  // The grid the search kept is the one a run at that resolution makes.
  AnalyzeOptions direct;
  direct.levelset.resolution = r.resolution;
  AnalyzeResult d = analyze(file, direct);
  EXPECT_EQ(d.grid.dims, r.grid.dims);
  EXPECT_EQ(d.grid.values, r.grid.values);
  EXPECT_EQ(d.surface.vertices.size(), r.surface.vertices.size());
  ASSERT_EQ(d.loops.size(), r.loops.size());
  for (std::size_t i = 0; i < d.loops.size(); ++i) EXPECT_EQ(d.loops[i].edge_path, r.loops[i].edge_path);
}

namespace {
bool warned(const AnalyzeResult& r, const std::string& a, const std::string& b = "") {
  for (auto& w : r.warnings)
    if (w.find(a) != std::string::npos && w.find(b) != std::string::npos) return true;
  return false;
}
}  // namespace

TEST(AnalyzeMeshes, SeahorseSaysItsGenusIsOutOfReach) {
  // The seahorse mesh has genus 8, but its handles are a few triangles across and no grid up to 921 keeps
  // more than 2 of them. The run must say so, and what it reports must be consistent with the surface it
  // has: never a silently smaller genus.
  const std::string file = std::string(CHOKELOOPS_DATA) + "/meshes/seahorse2_100K_directional.off";
  ASSERT_TRUE(std::filesystem::exists(file)) << "bundled data missing: " << file;
  AnalyzeOptions o;
  o.levelset.resolution = 192;
  AnalyzeResult r = analyze(file, o);
  ASSERT_EQ(r.input_genus, 8);
  EXPECT_LT(r.surface_stats.genus, 8);
  EXPECT_EQ(r.chokes.handle_generators, r.surface_stats.genus);
  EXPECT_EQ(r.chokes.tunnel_generators, r.surface_stats.genus);
  EXPECT_TRUE(warned(r, "too coarse", "genus 8"));
  // The mesh also intersects itself (39 face pairs), which the warning names.
  EXPECT_TRUE(warned(r, "too coarse", "intersects itself"));

  // --resolution auto within a memory budget that stops the search at about 300 voxels: it says that no
  // grid it could afford keeps the genus, names the voxel size, and does not suggest itself again.
  AnalyzeOptions a;
  a.resolution_auto = true;
  a.levelset.max_memory = std::size_t(200) << 20;
  AnalyzeResult ra = analyze(file, a);
  EXPECT_GE(ra.resolution, 243);
  EXPECT_LE(ra.resolution, 320);
  EXPECT_EQ(ra.chokes.handle_generators, ra.surface_stats.genus);
  EXPECT_TRUE(warned(ra, "--resolution auto: no grid up to " + std::to_string(ra.resolution), "fits in memory"));
  EXPECT_TRUE(warned(ra, "thinner than"));
  EXPECT_FALSE(warned(ra, "or --resolution auto"));
}

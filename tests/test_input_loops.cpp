// Loops on the input mesh and `chokeloops cut`: on a polyhedral torus the carried loops keep their class and
// their length, the named vertices and edges hold the points; on real models every generator is carried and
// verified by CGAL, and cutting all handle generators leaves one sphere (Euler characteristic 2).
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <tbb/global_control.h>

#include "chokeloops/analyze.h"
#include "chokeloops/loops/cut_mesh.h"
#include "chokeloops/surface/topology.h"
#include "mesh_shapes.h"
#include "temp_dir.h"

using namespace chokeloops;
using test::polyhedral_torus;

namespace {

// Every point is where input_points (InputPoint) says, and the named edges and faces exist.
void expect_points_located(const InputMesh& in, const InputLoop& l) {
  ASSERT_EQ(l.where.size(), l.loop.points.size());
  for (std::size_t i = 0; i < l.where.size(); ++i) {
    const InputPoint& w = l.where[i];
    std::array<double, 3> q;
    ASSERT_GE(w.face, 0);
    const auto& f = in.mesh.faces[std::size_t(w.face)];
    auto in_face = [&](int v) { return f[0] == v || f[1] == v || f[2] == v; };
    if (w.vertex >= 0) {
      q = in.mesh.vertices[std::size_t(w.vertex)];
      EXPECT_TRUE(in_face(w.vertex));
    } else {
      EXPECT_TRUE(in_face(w.edge[0]) && in_face(w.edge[1]));
      const auto &a = in.mesh.vertices[std::size_t(w.edge[0])], &b = in.mesh.vertices[std::size_t(w.edge[1])];
      for (int k = 0; k < 3; ++k) q[k] = a[k] + w.t * (b[k] - a[k]);
    }
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(q[k], l.loop.points[i][k], 1e-9);
  }
}

// The mesh cut along `cut` of its `generators` handle generators: genus generators - cut, one component,
// Euler characteristic V - E + F = 2 - 2 genus; the input's faces first, each on the same points.
void expect_cut(const TriangleMesh& input, const CutResult& c, int generators, int cut) {
  EXPECT_EQ(c.before.genus, generators);
  EXPECT_EQ(c.loops_cut, cut);
  EXPECT_EQ(int(c.notes.size()), generators - cut);
  EXPECT_EQ(c.caps, 2 * cut);
  EXPECT_TRUE(c.after.closed);
  EXPECT_EQ(c.after.components, 1u);
  EXPECT_EQ(c.after.genus, generators - cut);
  const long V = long(c.mesh.vertices.size()), F = long(c.mesh.faces.size());
  EXPECT_EQ(F % 2, 0);  // closed triangle mesh: 3F = 2E
  EXPECT_EQ(V - 3 * F / 2 + F, 2 - 2 * (generators - cut));
  ASSERT_EQ(c.mesh.faces.size(), input.faces.size() + std::size_t(c.cap_faces));
  for (std::size_t f = 0; f < input.faces.size(); ++f)
    for (int k = 0; k < 3; ++k)
      ASSERT_EQ(c.mesh.vertices[std::size_t(c.mesh.faces[f][k])], input.vertices[std::size_t(input.faces[f][k])]) << "face " << f;
}

std::vector<std::vector<int>> handle_generator_paths(const AnalyzeResult& r) {
  std::vector<std::vector<int>> paths;
  for (const InputLoop& l : r.input_loops)
    if (l.loop.found && l.loop.choke.side == Side::Handle && l.loop.choke.kind == Kind::Generator) paths.push_back(l.loop.edge_path);
  return paths;
}

// Writes `mesh` to `path` and analyzes it at resolution 96, input loops included.
AnalyzeResult analyze_written(const TriangleMesh& mesh, const std::string& path, AnalyzeOptions& o) {
  write_mesh(mesh, path);
  o.levelset.resolution = 96;
  AnalyzeResult r = analyze(path, o);
  EXPECT_TRUE(r.has_input_loops);
  EXPECT_EQ(r.input_loops.size(), r.loops.size());
  return r;
}

}  // namespace

TEST(InputLoops, TorusLoopsKeepClassAndLength) {
  const double R = 1, r = 0.35;
  const int n = 96, m = 40;
  const TriangleMesh torus = polyhedral_torus(R, r, n, m);
  const auto dir = test::temp_dir("input_loops_torus");
  const std::string path = (dir / "torus.off").string();
  AnalyzeOptions o;
  AnalyzeResult res = analyze_written(torus, path, o);
  EXPECT_FALSE(res.input_mesh.repaired);
  ASSERT_EQ(res.input_loops.size(), res.loops.size());
  // The polygons' perimeters: the meridian (m sides of the tube) and the inner equator (n sides).
  const double meridian = 2 * m * r * std::sin(M_PI / m), inner = 2 * n * (R - r) * std::sin(M_PI / n);
  int generators = 0;
  SurfaceTopology topology(res.input_mesh.mesh);
  for (const InputLoop& l : res.input_loops) {
    if (l.loop.choke.kind != Kind::Generator) continue;
    ++generators;
    ASSERT_TRUE(l.loop.found) << l.loop.note;
    EXPECT_TRUE(l.verified);
    EXPECT_FALSE(topology.contractible(l.loop.edge_path));
    const double expected = l.loop.choke.side == Side::Handle ? meridian : inner;
    EXPECT_NEAR(l.loop.length, expected, 0.02 * expected) << to_string(l.loop.choke.side);
    EXPECT_LE(l.loop.length, l.loop.raw_length + 1e-12);
    expect_points_located(res.input_mesh, l);
  }
  EXPECT_EQ(generators, 2);
  {  // the same loops, to the bit, on one thread
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    const auto again = transfer_loops(res.input_mesh, res.surface, res.loops);
    for (std::size_t i = 0; i < again.size(); ++i) {
      EXPECT_EQ(again[i].loop.points, res.input_loops[i].loop.points);
      EXPECT_EQ(again[i].loop.edge_path, res.input_loops[i].loop.edge_path);
    }
  }

  write_report(res, o, (dir / "out").string());
  std::ifstream in(dir / "out" / "input_loops.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_EQ(j["loops"].size(), res.loops.size());
  EXPECT_TRUE(j["loops"][0].contains("input_points"));
  EXPECT_TRUE(std::filesystem::exists(dir / "out" / "input_loops.ply"));

  for (bool handles : {true, false}) {
    SCOPED_TRACE(handles ? "cut the handle" : "cut the tunnel");
    CutSelection sel;
    sel.handles = handles;
    const std::string cut = (dir / "cut.off").string();
    const CutResult c = cut_mesh_file(path, (dir / "out").string(), cut, sel);
    expect_cut(torus, c, 1, 1);
    EXPECT_EQ(mesh_topology(read_mesh(cut)).genus, 0);
  }
  // The command line: the same cut by id, and an id with no loop refused with exit 2.
  const std::string cli = std::string("'") + CHOKELOOPS_CLI + "' cut '" + path + "' '" + (dir / "out").string() + "' -o '";
  EXPECT_EQ(std::system((cli + (dir / "cli.ply").string() + "' --ids 0 --quiet").c_str()), 0);
  EXPECT_EQ(mesh_topology(read_mesh((dir / "cli.ply").string())).genus, 0);
  const int refused = std::system((cli + (dir / "cli.ply").string() + "' --ids 99 --quiet 2>/dev/null").c_str());
  EXPECT_TRUE(WIFEXITED(refused) && WEXITSTATUS(refused) == 2);
  std::filesystem::remove_all(dir);
}

TEST(InputLoops, AnOpenMeshIsRepairedAndTheLoopsSayWhereTheyCrossAFilledHole) {
  // A hole across the inner equator (3 x 2 quads): the repair fills it; the tunnel loop, which runs along the
  // inner equator, goes through the patch and says so.
  const int n = 96, m = 40;
  TriangleMesh torus = polyhedral_torus(1, 0.35, n, m);
  std::vector<std::array<int, 3>> kept;
  for (std::size_t f = 0; f < torus.faces.size(); ++f) {
    const int quad = int(f / 2), i = quad / m, j = quad % m;
    if (!(i < 3 && (j == 19 || j == 20))) kept.push_back(torus.faces[f]);
  }
  torus.faces = kept;
  const auto dir = test::temp_dir("input_loops_open");
  AnalyzeOptions o;
  AnalyzeResult res = analyze_written(torus, (dir / "open_torus.off").string(), o);
  EXPECT_TRUE(res.input_mesh.repaired);
  int added = 0;
  for (char a : res.input_mesh.added_face) added += a;
  EXPECT_GT(added, 0);
  bool warned = false;
  for (auto& w : res.warnings) warned |= w.find("repaired mesh") != std::string::npos;
  EXPECT_TRUE(warned);
  bool through_patch = false;
  for (const InputLoop& l : res.input_loops) {
    if (l.loop.choke.kind != Kind::Generator) continue;
    ASSERT_TRUE(l.loop.found) << l.loop.note;
    EXPECT_TRUE(l.verified);
    if (l.loop.choke.side == Side::Tunnel) through_patch = l.loop.note.find("repair added") != std::string::npos;
  }
  EXPECT_TRUE(through_patch);
  std::filesystem::remove_all(dir);
}

TEST(InputLoops, CutRefusesLoopsThatAreNotSimpleEdgePaths) {
  const TriangleMesh torus = polyhedral_torus(1, 0.3, 12, 8);
  EXPECT_THROW(cut_along_loops(torus, {{0, 1}}), Error);
  try {  // named by its id in input_loops.json when given
    cut_along_loops(torus, {{0, 1}}, {7});
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("loop 7"), std::string::npos) << e.what();
  }
  EXPECT_THROW(cut_along_loops(torus, {{0, 8, 0, 8}}), Error);
  EXPECT_THROW(cut_along_loops(torus, {{0, 17, 40}}), Error);  // not joined by edges
  // A meridian of the polyhedral torus is an edge loop: the cut gives a sphere.
  const CutResult c = cut_along_loops(torus, {{0, 1, 2, 3, 4, 5, 6, 7}});
  expect_cut(torus, c, 1, 1);
}

namespace {
// The cup is the case of a handle born where a wide thin wall closes last: its membrane's interface curves
// go around the tunnel beside it, and its loop is the ring's section that cuts its own cycle (membranes.cpp).
struct Model { const char* file; int genus; int resolution; };
void PrintTo(const Model& m, std::ostream* os) { *os << m.file; }
}  // namespace

class InputLoopModels : public ::testing::TestWithParam<Model> {};

TEST_P(InputLoopModels, GeneratorsVerifiedAndCutToGenusZero) {
  const Model& m = GetParam();
  const std::string path = std::string(CHOKELOOPS_DATA) + "/meshes/" + m.file;
  AnalyzeOptions o;
  o.levelset.resolution = m.resolution;
  AnalyzeResult r = analyze(path, o);
  ASSERT_EQ(r.surface_stats.genus, m.genus) << "the grid lost the genus";
  ASSERT_TRUE(r.has_input_loops);
  int generators = 0;
  for (std::size_t i = 0; i < r.loops.size(); ++i) {
    const InputLoop& l = r.input_loops[i];
    if (l.loop.choke.kind != Kind::Generator) continue;
    SCOPED_TRACE("loop " + std::to_string(i) + " " + to_string(l.loop.choke.side));
    ++generators;
    ASSERT_TRUE(l.loop.found) << l.loop.note;
    EXPECT_TRUE(l.verified);
    // Shortened on the input's own triangles: within a factor of the marching surface's length.
    EXPECT_GT(l.loop.length, 0.6 * r.loops[i].length);
    EXPECT_LT(l.loop.length, 1.3 * r.loops[i].length);
    expect_points_located(r.input_mesh, l);
  }
  EXPECT_EQ(generators, 2 * m.genus);
  const auto paths = handle_generator_paths(r);
  ASSERT_EQ(int(paths.size()), m.genus);
  const TriangleMesh input{r.input_mesh.mesh.vertices, r.input_mesh.mesh.faces};
  const CutResult c = cut_along_loops(input, paths);
  expect_cut(input, c, m.genus, m.genus);
}

INSTANTIATE_TEST_SUITE_P(Models, InputLoopModels,
                         ::testing::Values(Model{"kitten_euclid.off", 1, 128}, Model{"fertility_libigl.off", 4, 128},
                                           Model{"3holes_libigl.off", 3, 128}, Model{"genus3_directional.off", 3, 128},
                                           Model{"cup_directional.off", 2, 128}),
                         [](const ::testing::TestParamInfo<Model>& info) {
                           std::string n = std::filesystem::path(info.param.file).stem().string();
                           for (char& c : n)
                             if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                           return n;
                         });

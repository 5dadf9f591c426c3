// Every mesh of data/MANIFEST.tsv loads and converts at a modest resolution; closed ones
// report the genus listed there; open/messy ones give a warning and a usable grid.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "chokeloops/field/levelset.h"
#include "chokeloops/io/vdb_io.h"

using namespace chokeloops;
namespace fs = std::filesystem;

namespace {

struct Row {
  std::string file, closed, genus;
};

std::vector<Row> manifest_meshes() {
  std::vector<Row> rows;
  std::ifstream in(std::string(CHOKELOOPS_DATA) + "/MANIFEST.tsv");
  std::string line;
  std::getline(in, line);  // header
  while (std::getline(in, line)) {
    std::vector<std::string> c;
    std::stringstream ss(line);
    std::string cell;
    while (std::getline(ss, cell, '\t')) c.push_back(cell);
    if (c.size() < 10 || c[0].rfind("meshes/", 0) != 0) continue;
    rows.push_back({c[0], c[5], c[9]});
  }
  return rows;
}

// The grid is usable: finite, both signs, the box padded (all faces of the box outside).
void expect_usable(const ScalarGrid& g, const std::string& who) {
  ASSERT_GT(g.vertex_count(), 0) << who;
  std::size_t neg = 0;
  for (float v : g.values) {
    ASSERT_TRUE(std::isfinite(v)) << who;
    neg += v < 0;
  }
  EXPECT_GT(neg, 0u) << who;
  EXPECT_LT(neg, g.values.size()) << who;
  for (int k : {0, g.dims[2] - 1})
    for (int j = 0; j < g.dims[1]; j += 3)
      for (int i = 0; i < g.dims[0]; i += 3) EXPECT_GT(g.values[g.index(i, j, k)], 0.f) << who << " box face";
}

}  // namespace

TEST(LevelSetManifest, EveryMeshConvertsAndClosedOnesHaveTheListedGenus) {
  auto rows = manifest_meshes();
  ASSERT_GE(rows.size(), 10u);
  for (auto& r : rows) {
    SCOPED_TRACE(r.file);
    LevelSetOptions o;
    o.resolution = 64;
    o.quiet = true;
    LevelSetResult res = make_levelset(std::string(CHOKELOOPS_DATA) + "/" + r.file, o);
    expect_usable(res.grid, r.file);
    EXPECT_GE(res.grid.dims[0], 64 / 2);
    std::printf("%-40s %3dx%3dx%3d closed=%d boundary=%zu nonmanifold=%zu comps=%zu genus=%d warnings=%zu %.2fs\n",
                r.file.c_str(), res.grid.dims[0], res.grid.dims[1], res.grid.dims[2], int(res.report.closed),
                res.report.boundary_edges, res.report.nonmanifold_edges, res.report.components, res.report.genus,
                res.warnings.size(), res.seconds);
    if (r.closed == "yes") {
      EXPECT_TRUE(res.report.closed);
      EXPECT_EQ(res.report.boundary_edges, 0u);
      EXPECT_EQ(std::to_string(res.report.genus), r.genus);
      EXPECT_TRUE(res.warnings.empty()) << res.warnings.front();
    } else {
      EXPECT_FALSE(res.warnings.empty());
    }
  }
}

TEST(LevelSetManifest, OpenScanWarnsAndGivesAUsableGrid) {
  LevelSetOptions o;
  o.resolution = 96;
  o.quiet = true;
  LevelSetResult res = make_levelset(std::string(CHOKELOOPS_DATA) + "/meshes/stanford-bunny_scan_ajc.obj", o);
  EXPECT_FALSE(res.report.closed);
  EXPECT_EQ(res.report.boundary_edges, 223u);
  EXPECT_EQ(res.report.holes, 5u);
  ASSERT_FALSE(res.warnings.empty());
  bool named = false;
  for (auto& w : res.warnings)
    named |= w.find("open") != std::string::npos && w.find("223 boundary edges") != std::string::npos;
  EXPECT_TRUE(named) << res.warnings.front();
  expect_usable(res.grid, "scan");
  // the scan and the closed libigl bunny are the same shape: inside volumes agree within 5%
  LevelSetResult ref = make_levelset(std::string(CHOKELOOPS_DATA) + "/meshes/bunny_libigl.off", o);
  const double h3s = std::pow(res.grid.voxel_size, 3), h3r = std::pow(ref.grid.voxel_size, 3);
  EXPECT_NEAR(res.inside_voxels * h3s / (ref.inside_voxels * h3r), 1.0, 0.05);
}

TEST(LevelSetManifest, DragonWithDuplicatedFaceWarns) {
  LevelSetOptions o;
  o.resolution = 64;
  o.quiet = true;
  LevelSetResult res = make_levelset(std::string(CHOKELOOPS_DATA) + "/meshes/dragon_euclid.ply", o);
  ASSERT_FALSE(res.warnings.empty());
  EXPECT_EQ(res.report.nonmanifold_edges + res.report.removed_faces > 0, true);
  expect_usable(res.grid, "dragon");
}

TEST(LevelSetManifest, CliWritesAReadableGrid) {
  auto dir = fs::temp_directory_path() / ("chokeloops_ls_cli_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string out = (dir / "kitten.vdb").string();
  const std::string cmd = std::string(CHOKELOOPS_CLI) + " levelset '" + CHOKELOOPS_SOURCE_DIR +
                          "/data/meshes/kitten_euclid.off' -o '" + out + "' --resolution 48 > '" + (dir / "log").string() + "'";
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  std::ifstream log(dir / "log");
  std::string text((std::istreambuf_iterator<char>(log)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("genus 1"), std::string::npos) << text;
  EXPECT_NE(text.find("inside:"), std::string::npos) << text;
  ScalarGrid g = read_vdb_dense(out);
  LevelSetOptions o;
  o.resolution = 48;
  o.quiet = true;
  LevelSetResult res = make_levelset(std::string(CHOKELOOPS_SOURCE_DIR) + "/data/meshes/kitten_euclid.off", o);
  ASSERT_EQ(g.dims, res.grid.dims);
  for (int a = 0; a < 3; ++a) EXPECT_NEAR(g.origin[a], res.grid.origin[a], 1e-9);
  EXPECT_EQ(g.values, res.grid.values);
  // the written grid read back as .vdb input is used as is (a true distance) and keeps its box
  LevelSetResult again = make_levelset(out, o);
  EXPECT_EQ(again.source, "vdb level set");
  EXPECT_EQ(again.grid.dims, g.dims);
  EXPECT_EQ(again.grid.values, g.values);
  fs::remove_all(dir);
}

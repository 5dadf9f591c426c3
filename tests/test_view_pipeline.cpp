// The viewer on a surface made by the library itself (marching tetrahedra on a sampled double torus, written
// by write_ply), with loops placed where a double torus has them: the page and the picture must show them.
#include <gtest/gtest.h>
#include <stdlib.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "chokeloops/field/analytic.h"
#include "chokeloops/output/mesh_write.h"
#include "chokeloops/surface/surface.h"
#include "chokeloops/output/view.h"

namespace fs = std::filesystem;
using namespace chokeloops;

namespace {

std::string run_out(const std::string& cmd, int& code) {
  std::string out;
  FILE* p = popen((cmd + " 2>&1").c_str(), "r");
  if (!p) { code = -1; return out; }
  char buf[4096];
  size_t n;
  while ((n = fread(buf, 1, sizeof buf, p)) > 0) out.append(buf, n);
  int st = pclose(p);
  code = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  return out;
}

nlohmann::json circle_loop(int id, const char* side, const char* kind, std::array<double, 3> c, double radius,
                           int plane /* 0: xy, 1: xz */, double depth, double persistence) {
  nlohmann::json pts = nlohmann::json::array();
  const int n = 120;
  for (int k = 0; k < n; ++k) {
    double t = 2 * M_PI * k / n;
    std::array<double, 3> p = c;
    p[0] += radius * std::cos(t);
    p[plane == 0 ? 1 : 2] += radius * std::sin(t);
    pts.push_back(p);
  }
  return {{"id", id}, {"side", side}, {"kind", kind}, {"depth", depth}, {"persistence", persistence},
          {"birth", -depth}, {"death", -depth + persistence}, {"length", 2 * M_PI * radius},
          {"choke_point", pts[0]}, {"centroid", c}, {"points", pts}};
}

}  // namespace

TEST(ViewPipeline, MarchingTetsSurfaceWithLoopsRendersEveryColour) {
  const fs::path viewer = fs::path(CHOKELOOPS_SOURCE_DIR) / "viewer";
  if (find_chromium().empty() || !fs::exists(viewer / "node_modules/pngjs")) {
    if (std::getenv("CHOKELOOPS_ALLOW_NO_BROWSER")) GTEST_SKIP() << "no chromium or viewer/node_modules";
    FAIL() << "needs chromium (scripts/install-deps.sh) and viewer/node_modules (scripts/build-viewer.sh)";
  }
  std::string t = (fs::temp_directory_path() / "chokeloops-view-pipeline-XXXXXX").string();
  ASSERT_NE(mkdtemp(t.data()), nullptr);
  fs::path out(t);

  const double R = 0.17, r = 0.07, sep = 0.34;
  ScalarGrid grid = sample_field({97, 97, 97}, analytic::double_torus(R, r, sep));
  SurfaceMesh mesh = extract_zero_surface(grid);
  ASSERT_GT(mesh.faces.size(), 1000u);
  write_ply(mesh, (out / "surface.ply").string());

  const double cx0 = 0.5 - sep / 2, cx1 = 0.5 + sep / 2, z = 0.5, g = 1.03;
  nlohmann::json loops = nlohmann::json::array();
  // Handles: meridians around the tube on the far sides; tunnels: circles around each hole.
  loops.push_back(circle_loop(0, "handle", "generator", {cx0 - R, 0.5, z}, r * g, 1, r, 0.06));
  loops.push_back(circle_loop(1, "handle", "choke", {cx1 + R, 0.5, z}, r * g, 1, r, 0.06));
  loops.push_back(circle_loop(2, "tunnel", "generator", {cx0, 0.5, z + r * g}, R, 0, R - r, 0.08));
  loops.push_back(circle_loop(3, "tunnel", "choke", {cx1, 0.5, z}, (R - r) / g, 0, R - r, 0.08));
  nlohmann::json report = {
      {"input", "double_torus (sampled, 97^3)"}, {"units", "input"}, {"voxel_size", grid.voxel_size},
      {"grid", {{"dims", grid.dims}, {"origin", grid.origin}}},
      {"surface", {{"vertices", mesh.vertices.size()}, {"faces", mesh.faces.size()}, {"components", 1}, {"genus", 2}}},
      {"parameters", {{"d_max", "50%"}, {"min_persistence", "10%"}, {"d_max_abs", 0.2},
                      {"min_persistence_abs_handle", 0.01}, {"min_persistence_abs_tunnel", 0.01}}},
      {"loops", loops},
      {"diagram", {{"handle", {{r, 0.06}, {r, 0.06}, {0.01, 0.002}}}, {"tunnel", {{R - r, 0.08}, {R - r, 0.08}}}}}};
  std::ofstream(out / "loops.json") << report.dump(1);

  write_view_html(out.string());
  int code = 0;
  std::string page = run_out("node '" + (viewer / "tests/check-view.mjs").string() + "' '" + out.string() + "'", code);
  EXPECT_EQ(code, 0) << page;

  render_png(out.string(), (out / "picture.png").string(), 1000, 750);
  std::string counts = run_out("node '" + (viewer / "tests/check-png.mjs").string() + "' '" + (out / "picture.png").string() + "'", code);
  ASSERT_EQ(code, 0) << counts;
  auto j = nlohmann::json::parse(counts);
  for (auto& [colour, n] : j["counts"].items()) EXPECT_GT(n.get<int>(), 300) << colour << ": " << counts;
  EXPECT_GT(j["surface"].get<int>(), 1000 * 750 / 20) << counts;
  if (!std::getenv("CHOKELOOPS_KEEP_TEST_OUTPUT")) fs::remove_all(out);
}

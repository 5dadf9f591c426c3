// `chokeloops analyze MODEL -o OUTDIR --png FILE` on a real model: view.html is written, and the picture
// shows the surface and every kind of loop the analysis drew (counted by colour), and no colour of a kind
// it did not draw; the page switches to the input mesh and the loops carried onto it.
#include <gtest/gtest.h>
#include <stdlib.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "chokeloops/output/view.h"

namespace fs = std::filesystem;

namespace {
std::string run_cmd(const std::string& cmd, int& code) {
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
}  // namespace

TEST(ViewAnalyze, PngOfAModelShowsEachKindOfLoopItFound) {
  const fs::path viewer = fs::path(CHOKELOOPS_SOURCE_DIR) / "viewer";
  const fs::path model = fs::path(CHOKELOOPS_DATA) / "meshes/kitten_euclid.off";  // genus 1
  if (!fs::exists(model)) GTEST_SKIP() << model << " not found";
  if (chokeloops::find_chromium().empty() || !fs::exists(viewer / "node_modules/pngjs")) {
    if (std::getenv("CHOKELOOPS_ALLOW_NO_BROWSER")) GTEST_SKIP() << "no chromium or viewer/node_modules";
    FAIL() << "needs chromium (scripts/install-deps.sh) and viewer/node_modules (scripts/build-viewer.sh)";
  }
  std::string t = (fs::temp_directory_path() / "chokeloops-view-analyze-XXXXXX").string();
  ASSERT_NE(mkdtemp(t.data()), nullptr);
  fs::path out(t);
  int code = 0;
  std::string log = run_cmd(std::string(CHOKELOOPS_CLI) + " analyze '" + model.string() + "' -o '" + (out / "r").string() +
                                "' --resolution 128 --png '" + (out / "kitten.png").string() + "' --quiet",
                            code);
  if (log.find("unknown command 'analyze'") != std::string::npos) GTEST_SKIP() << "no analyze command yet";
  ASSERT_EQ(code, 0) << log;
  ASSERT_TRUE(fs::exists(out / "r/view.html"));
  ASSERT_TRUE(fs::exists(out / "kitten.png"));

  nlohmann::json report;
  std::ifstream(out / "r/loops.json") >> report;
  std::map<std::string, int> drawn;
  for (const auto& l : report["loops"])
    if (l["points"].size() >= 2) drawn[l["side"].get<std::string>() + " " + l["kind"].get<std::string>()]++;
  ASSERT_FALSE(drawn.empty()) << "the analysis drew no loop on a genus-1 model";

  std::string counts = run_cmd("node '" + (viewer / "tests/check-png.mjs").string() + "' '" + (out / "kitten.png").string() + "'", code);
  ASSERT_EQ(code, 0) << counts;
  auto j = nlohmann::json::parse(counts);
  for (auto& [kind, n] : j["counts"].items()) {
    if (drawn.count(kind)) EXPECT_GT(n.get<int>(), 200) << kind << " loops barely visible: " << counts;
    else EXPECT_LT(n.get<int>(), 50) << "colour of " << kind << " loops, but there are none: " << counts;
  }
  EXPECT_GT(j["surface"].get<int>(), 1200 * 900 / 20) << counts;

  // The same page shows the input mesh with the loops carried onto it (input_mesh.ply, input_loops.json).
  ASSERT_TRUE(fs::exists(out / "r/input_mesh.ply"));
  std::string page = run_cmd("node '" + (viewer / "tests/check-input-view.mjs").string() + "' '" + (out / "r").string() + "'", code);
  EXPECT_EQ(code, 0) << page;
  if (!std::getenv("CHOKELOOPS_KEEP_TEST_OUTPUT")) fs::remove_all(out);
}

// view.html and the PNG (include/chokeloops/output/view.h): the page is opened in headless Chromium by the Node
// scripts in viewer/tests/ (playwright-core, installed by scripts/build-viewer.sh), the PNG is checked by
// counting pixels of each loop colour.
#include <gtest/gtest.h>
#include <stdlib.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <functional>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "chokeloops/grid.h"
#include "chokeloops/output/view.h"

namespace fs = std::filesystem;
using namespace chokeloops;

namespace {

const fs::path kSource = CHOKELOOPS_SOURCE_DIR;
const fs::path kViewer = kSource / "viewer";
const fs::path kTorus = kSource / "tests/fixtures/view/torus";

struct TempDir {
  fs::path path;
  TempDir() {
    std::string t = (fs::temp_directory_path() / "chokeloops-view-test-XXXXXX").string();
    if (!mkdtemp(t.data())) throw std::runtime_error("mkdtemp failed");
    path = t;
  }
  ~TempDir() {
    std::error_code ec;
    if (!std::getenv("CHOKELOOPS_KEEP_TEST_OUTPUT")) fs::remove_all(path, ec);
  }
};

struct Run {
  int code;
  std::string out;
};
Run run(const std::string& cmd) {
  Run r{-1, {}};
  FILE* p = popen((cmd + " 2>&1").c_str(), "r");
  if (!p) return r;
  char buf[4096];
  size_t n;
  while ((n = fread(buf, 1, sizeof buf, p)) > 0) r.out.append(buf, n);
  int st = pclose(p);
  r.code = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  return r;
}
std::string q(const fs::path& p) { return "'" + p.string() + "'"; }

fs::path copy_torus(const TempDir& t) {
  fs::path out = t.path / "out";
  fs::create_directories(out);
  fs::copy_file(kTorus / "surface.ply", out / "surface.ply");
  fs::copy_file(kTorus / "loops.json", out / "loops.json");
  return out;
}

// The browser tests need Node with viewer/node_modules (scripts/build-viewer.sh) and Chromium.
bool browser_ready(std::string& why) {
  if (run("node --version").code != 0) why = "node not found";
  else if (!fs::exists(kViewer / "node_modules/playwright-core")) why = "viewer/node_modules missing: run scripts/build-viewer.sh";
  else if (find_chromium().empty()) why = "chromium not found: run scripts/install-deps.sh";
  return why.empty();
}
#define REQUIRE_BROWSER()                                                                   \
  do {                                                                                      \
    std::string why;                                                                        \
    if (!browser_ready(why)) {                                                              \
      if (std::getenv("CHOKELOOPS_ALLOW_NO_BROWSER")) GTEST_SKIP() << why;                  \
      FAIL() << why << " (set CHOKELOOPS_ALLOW_NO_BROWSER=1 to skip the browser tests)";    \
    }                                                                                       \
  } while (0)

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// The JSON the page embeds (loops.json as "report", display mesh facts as "mesh").
nlohmann::json page_data(const std::string& html) {
  const std::string open = "<script type=\"application/json\" id=\"chokeloops-data\">";
  auto a = html.find(open);
  if (a == std::string::npos) return {};
  auto b = html.find("</script>", a);
  return nlohmann::json::parse(html.substr(a + open.size(), b - a - open.size()));
}

int error_code_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.exit_code;
  }
  return 0;
}

}  // namespace

TEST(View, WritesOneSelfContainedPage) {
  TempDir t;
  fs::path out = copy_torus(t);
  write_view_html(out.string());
  std::string html = slurp(out / "view.html");
  ASSERT_GT(html.size(), 300000u) << "the three.js bundle should be inlined";
  EXPECT_EQ(html.find("<script src"), std::string::npos);
  EXPECT_EQ(html.find("<link"), std::string::npos);
  EXPECT_EQ(html.find("{{"), std::string::npos) << "unfilled template placeholder";
  EXPECT_NE(html.find("<title>chokeloops: thin-torus.obj</title>"), std::string::npos);
  auto data = page_data(html);
  ASSERT_TRUE(data.is_object());
  EXPECT_EQ(data["report"]["loops"].size(), 4u);
  EXPECT_EQ(data["mesh"]["source_faces"], 2304);
  EXPECT_EQ(data["mesh"]["display_faces"], 2304);
  EXPECT_FALSE(data["mesh"]["decimated"].get<bool>());
  EXPECT_FALSE(fs::exists(out / "view.html.tmp"));
}

TEST(View, ScriptBreakingTextInLoopsJsonIsEscaped) {
  TempDir t;
  fs::path out = copy_torus(t);
  auto report = nlohmann::json::parse(slurp(out / "loops.json"));
  report["input"] = "</script><script>alert(1)</script>.obj";
  std::ofstream(out / "loops.json") << report.dump();
  write_view_html(out.string());
  std::string html = slurp(out / "view.html");
  EXPECT_EQ(html.find("<script>alert(1)"), std::string::npos);
}

TEST(View, MissingOrBadInputsAreBadInput) {
  TempDir t;
  EXPECT_EQ(error_code_of([&] { write_view_html((t.path / "nope").string()); }), 2);
  EXPECT_EQ(error_code_of([&] { write_view_html(t.path.string()); }), 2);
  fs::path out = copy_torus(t);
  std::ofstream(out / "loops.json") << "{\"loops\": [";
  EXPECT_EQ(error_code_of([&] { write_view_html(out.string()); }), 2);
  std::ofstream(out / "loops.json") << "{\"loops\": [{\"id\": 0}]}";
  EXPECT_EQ(error_code_of([&] { write_view_html(out.string()); }), 2);
  fs::copy_file(kTorus / "loops.json", out / "loops.json", fs::copy_options::overwrite_existing);
  std::ofstream(out / "surface.ply") << "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nend_header\n";
  EXPECT_EQ(error_code_of([&] { write_view_html(out.string()); }), 2);
  fs::remove(out / "surface.ply");
  EXPECT_EQ(error_code_of([&] { write_view_html(out.string()); }), 2);
  EXPECT_EQ(error_code_of([&] { render_png(out.string(), (t.path / "x.png").string()); }), 2);
}

TEST(View, ReadsBinaryPlyOfEitherEndiannessWithExtraProperties) {
  TempDir t;
  for (bool big : {false, true}) {
    fs::path p = t.path / (big ? "be.ply" : "le.ply");
    std::ofstream f(p, std::ios::binary);
    f << "ply\nformat " << (big ? "binary_big_endian" : "binary_little_endian") << " 1.0\ncomment x\n"
      << "element vertex 4\nproperty double x\nproperty double y\nproperty double z\nproperty uchar red\n"
      << "element face 1\nproperty list uchar uint vertex_indices\nproperty float quality\n"
      << "element extra 1\nproperty list ushort short stuff\nend_header\n";
    auto put = [&](const void* v, size_t n) {
      std::string b(static_cast<const char*>(v), n);
      if (big) std::reverse(b.begin(), b.end());
      f.write(b.data(), std::streamsize(n));
    };
    double xyz[4][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0.5}};
    for (auto& v : xyz) {
      for (double c : v) put(&c, 8);
      unsigned char red = 7;
      put(&red, 1);
    }
    unsigned char four = 4;
    put(&four, 1);
    for (std::uint32_t i : {0u, 1u, 2u, 3u}) put(&i, 4);
    float qual = 1;
    put(&qual, 4);
    std::uint16_t two = 2;
    std::int16_t s = -1;
    put(&two, 2);
    put(&s, 2);
    put(&s, 2);
    f.close();
    auto m = view_detail::read_ply(p.string());
    ASSERT_EQ(m.vertices.size(), 4u);
    ASSERT_EQ(m.faces.size(), 2u) << "a quad is fanned into two triangles";
    EXPECT_FLOAT_EQ(m.vertices[3][2], 0.5f);
    EXPECT_EQ(m.faces[1], (std::array<std::uint32_t, 3>{0, 2, 3}));
  }
  auto ascii = view_detail::read_ply((kTorus / "surface.ply").string());
  EXPECT_EQ(ascii.vertices.size(), 1152u);
  EXPECT_EQ(ascii.faces.size(), 2304u);
}

TEST(View, DecimatesAboveTheFaceBudget) {
  // A sphere of about 400K faces.
  view_detail::TriMesh m;
  const int nu = 500, nv = 400;
  for (int j = 0; j <= nv; ++j)
    for (int i = 0; i < nu; ++i) {
      double th = M_PI * j / nv, ph = 2 * M_PI * i / nu;
      m.vertices.push_back({float(std::sin(th) * std::cos(ph)), float(std::sin(th) * std::sin(ph)), float(std::cos(th))});
    }
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      std::uint32_t a = j * nu + i, b = j * nu + (i + 1) % nu, c = a + nu, d = b + nu;
      m.faces.push_back({a, b, d});
      m.faces.push_back({a, d, c});
    }
  auto before = m.faces.size();
  EXPECT_EQ(view_detail::decimate(m, before), 0.0);
  double cell = view_detail::decimate(m, 50000);
  EXPECT_GT(cell, 0.0);
  EXPECT_LE(m.faces.size(), 50000u);
  EXPECT_GT(m.faces.size(), 20000u) << "should use most of the budget";
  for (const auto& v : m.vertices) {
    double r = std::sqrt(double(v[0]) * v[0] + double(v[1]) * v[1] + double(v[2]) * v[2]);
    ASSERT_NEAR(r, 1.0, 2 * cell);
  }
  for (const auto& f : m.faces)
    for (auto i : f) ASSERT_LT(i, m.vertices.size());
}

TEST(ViewBrowser, PageShowsEveryLoopAndClickingARowSelectsIt) {
  REQUIRE_BROWSER();
  TempDir t;
  fs::path out = copy_torus(t);
  write_view_html(out.string());
  auto r = run("node " + q(kViewer / "tests/check-view.mjs") + " " + q(out) + " --screenshot " + q(t.path / "page.png"));
  EXPECT_EQ(r.code, 0) << r.out;
  auto j = nlohmann::json::parse(r.out.substr(r.out.find('{')));
  EXPECT_EQ(j["shownLoops"], 4);
  EXPECT_EQ(j["selectedAfterRowClick"], j["clickedRow"]);
  EXPECT_GT(j["viewport"]["variance"].get<double>(), 40);
}

TEST(ViewBrowser, LargeSurfaceIsDecimatedAndStaysInteractive) {
  REQUIRE_BROWSER();
  TempDir t;
  fs::path out = t.path / "large";
  auto g = run("node " + q(kViewer / "tests/make-fixture.mjs") + " large " + q(out));
  ASSERT_EQ(g.code, 0) << g.out;
  write_view_html(out.string());
  EXPECT_LT(fs::file_size(out / "view.html"), 20u << 20);
  auto r = run("node " + q(kViewer / "tests/check-view.mjs") + " " + q(out) + " --expect-decimated");
  EXPECT_EQ(r.code, 0) << r.out;
  auto j = nlohmann::json::parse(r.out.substr(r.out.find('{')));
  EXPECT_EQ(j["shownLoops"], 12);
  EXPECT_EQ(j["state"]["sourceFaces"], 720000);
  EXPECT_LE(j["state"]["displayFaces"].get<int>(), 300000);
}

TEST(RenderPng, PictureShowsTheSurfaceAndEachLoopColour) {
  REQUIRE_BROWSER();
  TempDir t;
  fs::path out = copy_torus(t);
  fs::path png = t.path / "loops.png";
  auto r = run(std::string(CHOKELOOPS_CLI) + " render " + q(out) + " -o " + q(png));
  ASSERT_EQ(r.code, 0) << r.out;
  ASSERT_TRUE(fs::exists(out / "view.html")) << "render writes view.html when missing";
  auto c = run("node " + q(kViewer / "tests/check-png.mjs") + " " + q(png));
  ASSERT_EQ(c.code, 0) << c.out;
  auto j = nlohmann::json::parse(c.out);
  EXPECT_EQ(j["width"], 1200);
  EXPECT_EQ(j["height"], 900);
  for (auto& [colour, n] : j["counts"].items()) EXPECT_GT(n.get<int>(), 400) << colour << " loops are barely visible: " << c.out;
  EXPECT_GT(j["surface"].get<int>(), 1200 * 900 / 20) << "surface barely visible: " << c.out;
  EXPECT_GT(j["background"].get<int>(), 1200 * 900 / 10) << c.out;
  EXPECT_GT(j["variance"].get<double>(), 100) << c.out;
}

TEST(RenderPng, CliErrors) {
  TempDir t;
  auto r = run(std::string(CHOKELOOPS_CLI) + " render " + q(t.path / "missing") + " -o " + q(t.path / "x.png"));
  EXPECT_EQ(r.code, 2) << r.out;
  r = run(std::string(CHOKELOOPS_CLI) + " view " + q(t.path));
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("loops.json"), std::string::npos) << r.out;
  fs::path out = copy_torus(t);
  r = run("CHOKELOOPS_CHROMIUM=/nonexistent/chromium " + std::string(CHOKELOOPS_CLI) + " render " + q(out) + " -o " + q(t.path / "x.png"));
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("needs Chromium"), std::string::npos) << r.out;
  r = run(std::string(CHOKELOOPS_CLI) + " view " + q(out));
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_TRUE(fs::exists(out / "view.html"));
}

TEST(RenderPng, RewritesAPageOlderThanItsInputs) {
  REQUIRE_BROWSER();
  TempDir t;
  fs::path out = copy_torus(t);
  write_view_html(out.string());
  auto report = nlohmann::json::parse(slurp(out / "loops.json"));
  report["loops"].erase(report["loops"].begin());
  std::ofstream(out / "loops.json") << report.dump();
  fs::last_write_time(out / "view.html", fs::last_write_time(out / "loops.json") - std::chrono::hours(1));
  render_png(out.string(), (t.path / "x.png").string(), 400, 300);
  EXPECT_EQ(page_data(slurp(out / "view.html"))["report"]["loops"].size(), 3u) << "the page was not rewritten";
  EXPECT_TRUE(fs::exists(t.path / "x.png"));
}

TEST(ViewBrowser, PageWithoutLoopsDiagramOrThresholdsStillWorks) {
  REQUIRE_BROWSER();
  TempDir t;
  fs::path out = copy_torus(t);
  auto report = nlohmann::json::parse(slurp(out / "loops.json"));
  report["loops"] = nlohmann::json::array();
  report.erase("diagram");
  report.erase("parameters");
  std::ofstream(out / "loops.json") << report.dump();
  write_view_html(out.string());
  auto r = run("node " + q(kViewer / "tests/check-view.mjs") + " " + q(out));
  EXPECT_EQ(r.code, 0) << r.out;
  auto j = nlohmann::json::parse(r.out.substr(r.out.find('{')));
  EXPECT_EQ(j["shownLoops"], 0);
}

// A molecule run: loops.json carries each traced tunnel's radius profile (profiles.csv's rows), the page embeds
// it, and selecting the tunnel draws it.
TEST(ViewBrowser, MoleculePageDrawsTheSelectedTunnelsRadiusProfile) {
  TempDir t;
  fs::path out = t.path / "gramicidin";
  auto a = run(std::string(CHOKELOOPS_CLI) + " analyze " + q(fs::path(CHOKELOOPS_DATA) / "molecules/1grm_single_hole2.pdb") +
               " --radii amber --voxel-size 0.25 --quiet -o " + q(out));
  ASSERT_EQ(a.code, 0) << a.out;
  const nlohmann::json loops = page_data(slurp(out / "view.html"))["report"]["loops"];
  int widest = -1;
  double rb = 0;
  nlohmann::json profile;
  for (const auto& l : loops)
    if (l.contains("channel") && l["channel"]["bottleneck_radius"].get<double>() > rb)
      rb = l["channel"]["bottleneck_radius"], widest = l["id"], profile = l["channel"]["profile"];
  ASSERT_GE(widest, 0);
  EXPECT_NEAR(rb, 1.2, 0.15);  // gramicidin's pore
  std::vector<std::pair<double, double>> csv;
  {
    std::ifstream in(out / "profiles.csv");
    std::string line;
    std::getline(in, line);
    while (std::getline(in, line)) {
      std::istringstream ls(line);
      std::string f[6];
      for (auto& x : f) std::getline(ls, x, ',');
      if (std::stoi(f[0]) == widest) csv.push_back({std::stod(f[1]), std::stod(f[5])});
    }
  }
  ASSERT_GT(csv.size(), 10u);
  ASSERT_EQ(profile["s"].size(), csv.size());
  ASSERT_EQ(profile["radius"].size(), csv.size());
  std::size_t at_bottleneck = 0;
  for (std::size_t k = 0; k < csv.size(); ++k) {
    EXPECT_NEAR(profile["s"][k].get<double>(), csv[k].first, 1e-3);
    EXPECT_NEAR(profile["radius"][k].get<double>(), csv[k].second, 1e-4);
    if (std::abs(csv[k].first) < std::abs(csv[at_bottleneck].first)) at_bottleneck = k;
  }
  EXPECT_EQ(csv[at_bottleneck].first, 0.0);  // s = 0 at the bottleneck, with its exact radius
  EXPECT_NEAR(profile["radius"][at_bottleneck].get<double>(), rb, 1e-4);

  REQUIRE_BROWSER();
  auto r = run("node " + q(kViewer / "tests/check-profile.mjs") + " " + q(out) + " " + std::to_string(widest));
  EXPECT_EQ(r.code, 0) << r.out;
  auto j = nlohmann::json::parse(r.out.substr(r.out.find('{')));
  EXPECT_EQ(j["plotLoop"], widest);
  EXPECT_EQ(j["plotPoints"].get<std::size_t>(), csv.size());
}

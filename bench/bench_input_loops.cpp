// Loops on the input mesh: per model, the time to carry every loop onto the input mesh (transfer_loops: closest
// points, edge paths, shortening, CGAL check) and to cut along every handle generator and cap the cuts
// (cut_along_loops), medians of --runs; then each generator's length on the input mesh next to its length on
// the marching surface (the README's table).
//
//   bench_input_loops [--runs 3] [--resolution 256] [--only NAME] [--data data]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "chokeloops/huge_pages.h"
#include "chokeloops/analyze.h"
#include "chokeloops/loops/cut_mesh.h"

using namespace chokeloops;

namespace {
using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); }
double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0 : v[v.size() / 2];
}
}  // namespace

int main(int argc, char** argv) {
  chokeloops::restart_with_huge_pages(argv);
  int runs = 3, resolution = 256;
  std::string only, data = CHOKELOOPS_SOURCE_DIR "/data";
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--runs")) runs = std::max(1, std::atoi(argv[i + 1]));
    else if (!std::strcmp(argv[i], "--resolution")) resolution = std::atoi(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--only")) only = argv[i + 1];
    else if (!std::strcmp(argv[i], "--data")) data = argv[i + 1];
  }
  const char* models[] = {"kitten_euclid.off", "fertility_libigl.off", "3holes_libigl.off", "genus3_directional.off",
                          "cup_directional.off"};
  std::vector<std::string> lengths;
  std::printf("resolution %d, %d run(s), medians\n\n", resolution, runs);
  std::printf("| model | input faces | genus | loops carried | transfer ms | cut ms | genus after cut | components |\n");
  std::printf("|---|---|---|---|---|---|---|---|\n");
  for (const char* name : models) {
    if (!only.empty() && std::string(name).find(only) == std::string::npos) continue;
    AnalyzeOptions o;
    o.levelset.resolution = resolution;
    o.input_loops = false;
    const AnalyzeResult r = analyze(data + "/meshes/" + name, o);
    const InputMesh input = load_input_mesh(data + "/meshes/" + name);
    std::vector<double> t_transfer, t_cut;
    std::vector<InputLoop> carried;
    CutResult cut;
    for (int k = 0; k < runs; ++k) {
      auto t = Clock::now();
      carried = transfer_loops(input, r.surface, r.loops);
      t_transfer.push_back(ms_since(t));
      std::vector<std::vector<int>> paths;
      for (const InputLoop& l : carried)
        if (l.loop.found && l.loop.choke.side == Side::Handle && l.loop.choke.kind == Kind::Generator)
          paths.push_back(l.loop.edge_path);
      t = Clock::now();
      cut = cut_along_loops(TriangleMesh{input.mesh.vertices, input.mesh.faces}, paths);
      t_cut.push_back(ms_since(t));
    }
    int found = 0;
    for (std::size_t i = 0; i < carried.size(); ++i) {
      found += carried[i].loop.found;
      if (r.loops[i].choke.kind != Kind::Generator) continue;
      char line[256];
      std::snprintf(line, sizeof line, "| %s | %zu | %s | %.4g | %.4g | %.3f |", name, i, to_string(r.loops[i].choke.side),
                    r.loops[i].length, carried[i].loop.found ? carried[i].loop.length : 0.0,
                    carried[i].loop.found ? carried[i].loop.length / r.loops[i].length : 0.0);
      lengths.push_back(line);
    }
    std::printf("| %s | %zu | %d | %d / %zu | %.0f | %.0f | %d | %zu |\n", name, input.mesh.faces.size(), input.report.genus,
                found, carried.size(), median(t_transfer), median(t_cut), cut.after.genus, cut.after.components);
    std::fflush(stdout);
  }
  std::printf("\n| model | loop | side | marching surface length | input mesh length | ratio |\n|---|---|---|---|---|---|\n");
  for (auto& l : lengths) std::printf("%s\n", l.c_str());
  return 0;
}

// The paper's pipeline (TetGen's complex of the input surface, signed distance at its vertices, persistence on
// the tets) beside the grid engine's (level set on a grid, persistence on its implicit Freudenthal complex),
// on the paper's Table 1 models found in data: sizes, time per stage, genus pairs and the deepest handle's
// depth, the loop stage (loops traced and found, time per loop), peak RSS. Each path runs in its own child
// process per run (peak RSS per path); medians over --runs.
//
//   bench_tetgen [--runs 3] [--data data] [--only NAME] [--cells C] [--grading G] [--resolution 256]
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <string>
#include <vector>

#include "chokeloops/analyze.h"
#include "chokeloops/field/levelset.h"
#include "chokeloops/io/mesh_io.h"
#include "chokeloops/tet/analyze_tet.h"
#include "chokeloops/tet/tet_field.h"

using namespace chokeloops;
using Figures = std::map<std::string, double>;

namespace {

double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// One path on one model, in this (child) process.
Figures run_path(const std::string& file, bool tet, double cells, double grading, int resolution) {
  Figures f;
  auto t = std::chrono::steady_clock::now();
  const TriangleMesh mesh = read_mesh(file);
  f["read"] = ms_since(t);
  f["input vertices"] = double(mesh.vertices.size());
  int genus_pairs = 0;
  double deepest = 0;
  if (tet) {
    TetOptions o;
    o.default_cells = cells;
    o.grading = grading;
    const TetAnalysis a = analyze_tet_complex(mesh, o, {});
    for (const char* stage : {"tetgen", "distance", "persistence", "chokes"}) f[stage] = a.timings_ms.at(stage);
    f["tets"] = double(a.tets);
    f["vertices"] = double(a.vertices);
    genus_pairs = a.chokes.handle_generators;
    for (const Choke& c : a.chokes.chokes)
      if (c.side == Side::Handle && c.kind == Kind::Generator) deepest = std::max(deepest, c.depth);
    int found = 0;
    for (const InputLoop& l : a.loops) found += l.loop.found && l.verified;
    f["loops"] = double(a.loops.size());
    f["loops found"] = found;
    f["loops ms"] = a.timings_ms.at("loops");
  } else {
    LevelSetOptions o;
    o.resolution = resolution;
    o.quiet = true;
    t = std::chrono::steady_clock::now();
    LevelSetResult ls = mesh_to_levelset(mesh, o, file);
    f["levelset"] = ms_since(t);
    f["vertices"] = double(ls.grid.vertex_count());
    f["voxel"] = ls.grid.voxel_size;
    AnalyzeOptions ao;
    ao.input_loops = false;
    const AnalyzeResult r = analyze_grid(std::move(ls.grid), ao);
    for (const char* stage : {"persistence", "chokes", "surface"}) f[stage] = r.timings_ms.at(stage);
    f["loops ms"] = r.timings_ms.at("loops");
    genus_pairs = r.chokes.handle_generators;
    for (const Choke& c : r.chokes.chokes)
      if (c.side == Side::Handle && c.kind == Kind::Generator) deepest = std::max(deepest, c.depth);
    int found = 0;
    for (const Loop& l : r.loops) found += l.found;
    f["loops"] = double(r.loops.size());
    f["loops found"] = found;
  }
  f["genus pairs"] = genus_pairs;
  f["deepest handle"] = deepest;
  return f;
}

// run_path in a forked child; its figures come back through a pipe, its peak RSS from wait4.
Figures run_in_child(const std::string& file, bool tet, double cells, double grading, int resolution, std::string& error) {
  int fd[2];
  if (pipe(fd) != 0) return error = "pipe failed", Figures{};
  const pid_t pid = fork();
  if (pid == 0) {
    close(fd[0]);
    FILE* out = fdopen(fd[1], "w");
    try {
      for (const auto& [k, v] : run_path(file, tet, cells, grading, resolution)) std::fprintf(out, "%s\t%.9g\n", k.c_str(), v);
    } catch (const std::exception& e) {
      std::fprintf(out, "error\t%s\n", e.what());
    }
    std::fclose(out);
    _exit(0);
  }
  close(fd[1]);
  FILE* in = fdopen(fd[0], "r");
  Figures f;
  char line[4096];
  while (std::fgets(line, sizeof line, in)) {
    char* tab = std::strchr(line, '\t');
    if (!tab) continue;
    *tab = 0;
    if (std::strcmp(line, "error") == 0) error = tab + 1;
    else f[line] = std::atof(tab + 1);
  }
  std::fclose(in);
  int status = 0;
  struct rusage ru {};
  wait4(pid, &status, 0, &ru);
  f["peak MB"] = ru.ru_maxrss / 1024.0;
  return f;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0 : v[v.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  int runs = 3, resolution = 256;
  double cells = 64, grading = 2;
  std::string data = CHOKELOOPS_SOURCE_DIR "/data", only;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--runs" && i + 1 < argc) runs = std::atoi(argv[++i]);
    else if (a == "--data" && i + 1 < argc) data = argv[++i];
    else if (a == "--only" && i + 1 < argc) only = argv[++i];
    else if (a == "--cells" && i + 1 < argc) cells = std::atof(argv[++i]);
    else if (a == "--grading" && i + 1 < argc) grading = std::atof(argv[++i]);
    else if (a == "--resolution" && i + 1 < argc) resolution = std::atoi(argv[++i]);
    else {
      std::fprintf(stderr, "usage: bench_tetgen [--runs 3] [--data data] [--only NAME] [--cells C] [--grading G] [--resolution 256]\n");
      return 2;
    }
  }
  const std::vector<std::pair<std::string, std::string>> models = {
      {"armadillo", "armadillo_libigl.obj"}, {"bunny", "bunny_libigl.off"},     {"david", "david_booleans.obj"},
      {"fertility", "fertility_libigl.off"}, {"fertility (vmas)", "fertility_vmas.off"},   {"kitten", "kitten_niagara.obj"}, {"neptune", "neptune_vmas.off"},
      {"genus3", "genus3_directional.off"}};
  std::printf("samples: finest spacing box diagonal / %g, grading %g; grid: %d voxels along the longest side; medians of %d, ms\n", cells,
              grading, resolution, runs);
  for (const auto& [name, file] : models) {
    if (!only.empty() && name != only) continue;
    for (const bool tet : {true, false}) {
      std::map<std::string, std::vector<double>> all;
      std::string error;
      for (int r = 0; r < runs && error.empty(); ++r)
        for (const auto& [k, v] : run_in_child(data + "/meshes/" + file, tet, cells, grading, resolution, error)) all[k].push_back(v);
      std::printf("%-10s %-5s", name.c_str(), tet ? "tet" : "grid");
      if (!error.empty()) {
        std::printf(" error: %s", error.c_str());
        if (error.back() != '\n') std::printf("\n");
        continue;
      }
      for (const auto& [k, v] : all) std::printf(" | %s %.6g", k.c_str(), median(v));
      std::printf("\n");
      std::fflush(stdout);
    }
  }
}

// Table 1 of the paper, on this engine: for each of the paper's models found in ../shared/data (and the
// tangle cube made from its implicit equation), the median over --runs runs of every stage of
// `analyze`, with surface size, grid size, genus g, additional loops k, d_max, delta_min and peak RSS.
// Each model runs in its own child process so that peak RSS is per model.
//
//   bench_analyze [--runs 5] [--resolution 256] [--data ../shared/data] [--only NAME]
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "chokeloops/analytic.h"
#include "chokeloops/analyze.h"
#include "chokeloops/vdb_io.h"

using namespace chokeloops;

struct Model { std::string name, file, d_max, min_persistence; };

static double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0 : v[v.size() / 2];
}

static void run_model(const Model& m, int runs, int resolution) {
  AnalyzeOptions o;
  o.levelset.resolution = resolution;
  o.chokes.d_max = Threshold::parse(m.d_max);
  o.chokes.min_persistence = Threshold::parse(m.min_persistence);
  std::map<std::string, std::vector<double>> t;
  AnalyzeResult last;
  for (int r = 0; r < runs; ++r) {
    last = analyze(m.file, o);
    for (auto& kv : last.timings_ms) t[kv.first].push_back(kv.second);
  }
  int k = 0, g = last.chokes.handle_generators;
  for (auto& l : last.loops) k += l.choke.kind == Kind::Choke;
  struct rusage ru;
  getrusage(RUSAGE_SELF, &ru);
  std::printf("| %-10s | %9lld | %4dx%4dx%4d | %7.0f | %7.0f | %6.0f | %6.0f | %6.0f | %7.0f | %2d | %2d | %5s | %5s | %6.0f |\n",
              m.name.c_str(), (long long)last.surface_stats.vertices, last.grid.dims[0], last.grid.dims[1],
              last.grid.dims[2], median(t["levelset"]), median(t["persistence"]), median(t["chokes"]),
              median(t["surface"]), median(t["loops"]), median(t["total"]), g, k, m.d_max.c_str(),
              m.min_persistence.c_str(), ru.ru_maxrss / 1024.0);
  std::fflush(stdout);
}

int main(int argc, char** argv) {
  int runs = 5, resolution = 256;
  std::string data = std::string(CHOKELOOPS_SOURCE_DIR) + "/../shared/data", only;
  for (int i = 1; i < argc; ++i) {
    std::string a = argv[i];
    if (a == "--runs" && i + 1 < argc) runs = std::atoi(argv[++i]);
    else if (a == "--resolution" && i + 1 < argc) resolution = std::atoi(argv[++i]);
    else if (a == "--data" && i + 1 < argc) data = argv[++i];
    else if (a == "--only" && i + 1 < argc) only = argv[++i];
    else { std::fprintf(stderr, "usage: bench_analyze [--runs N] [--resolution R] [--data DIR] [--only NAME]\n"); return 2; }
  }
  // The tangle cube: the paper's implicit surface, sampled and written as a .vdb that analyze renormalises.
  std::string tangle = (std::filesystem::temp_directory_path() / "chokeloops_tangle.vdb").string();
  {
    ScalarGrid g = sample_field({resolution + 1, resolution + 1, resolution + 1}, analytic::tangle_cube());
    write_vdb(g, tangle, "tangle", true);  // a level set (not a distance): analyze renormalises it
  }
  // d_max and delta_min as in the paper's Table 1.
  std::vector<Model> models = {
      {"armadillo", data + "/meshes/armadillo_libigl.obj", "50%", "6%"},
      {"bunny", data + "/meshes/bunny_libigl.off", "75%", "2.5%"},
      {"david", data + "/meshes/david_booleans.obj", "50%", "10%"},
      {"fertility", data + "/meshes/fertility_vmas.off", "50%", "10%"},
      {"kitten", data + "/meshes/kitten_niagara.obj", "50%", "15%"},
      {"neptune", data + "/meshes/neptune_vmas.off", "50%", "10%"},
      {"tangle", tangle, "50%", "10%"},
  };
  std::printf("resolution %d, median of %d runs, times in ms, peak RSS in MB (own process per model)\n\n", resolution, runs);
  std::printf("| model      | surf #v   | grid           | levelset | persist | chokes | surface | loops | total   | g  | k  | d_max | d_min | RSS MB |\n");
  std::printf("|------------|-----------|----------------|---------|---------|--------|--------|--------|---------|----|----|-------|-------|--------|\n");
  std::fflush(stdout);
  for (const Model& m : models) {
    if (!only.empty() && m.name != only) continue;
    if (!std::filesystem::exists(m.file)) { std::printf("| %-10s | missing %s |\n", m.name.c_str(), m.file.c_str()); continue; }
    pid_t pid = fork();
    if (pid == 0) {
      try { run_model(m, runs, resolution); } catch (const std::exception& e) { std::printf("| %-10s | error: %s |\n", m.name.c_str(), e.what()); }
      std::fflush(stdout);
      _exit(0);
    }
    int status = 0;
    waitpid(pid, &status, 0);
  }
  std::filesystem::remove(tangle);
  return 0;
}

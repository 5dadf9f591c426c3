// Benchmark of the levelset stage: mesh → dense signed distance grid, wall time (median of N runs)
// and peak RSS, for bunny, armadillo, fertility and neptune at --resolution 256.
// Then, per model, each sub-stage's median time and peak RSS within it (VmHWM reset per stage).
// usage: bench_levelset [runs=3] [resolution=256] [mesh paths...]
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

#include "chokeloops/huge_pages.h"
#include "chokeloops/field/levelset.h"

using namespace chokeloops;

int main(int argc, char** argv) {
  chokeloops::restart_with_huge_pages(argv);
  const int runs = argc > 1 ? std::max(1, std::atoi(argv[1])) : 3;
  const int res = argc > 2 ? std::atoi(argv[2]) : 256;
  std::vector<std::string> files;
  for (int i = 3; i < argc; ++i) files.push_back(argv[i]);
  if (files.empty()) {
    const std::string d = std::string(CHOKELOOPS_SOURCE_DIR) + "/data/meshes/";
    files = {d + "bunny_libigl.off", d + "armadillo_libigl.obj", d + "fertility_libigl.off", d + "neptune_vmas.off"};
  }
  std::printf("%-24s %9s %16s %10s %10s %12s %10s %10s\n", "mesh", "triangles", "grid", "median s", "min s",
              "median CPU s", "read s", "peakRSS MB");
  auto cpu_now = [] {
    struct rusage u;
    getrusage(RUSAGE_SELF, &u);
    return u.ru_utime.tv_sec + u.ru_stime.tv_sec + 1e-6 * (u.ru_utime.tv_usec + u.ru_stime.tv_usec);
  };
  for (auto& f : files) {
    std::vector<double> times, cpu;
    LevelSetResult r;
    double prep = 0;
    std::vector<std::string> stage_order;
    std::map<std::string, std::vector<double>> stage_s, stage_cpu;
    std::map<std::string, std::size_t> stage_rss;
    for (int k = 0; k < runs; ++k) {
      LevelSetOptions o;
      o.resolution = res;
      o.quiet = true;
      o.stage_memory = true;
      const double c0 = cpu_now();
      auto t0 = std::chrono::steady_clock::now();
      r = LevelSetResult();  // the previous run's grid must not count in this run's peak
      r = make_levelset(f, o);
      auto t2 = std::chrono::steady_clock::now();
      times.push_back(std::chrono::duration<double>(t2 - t0).count());
      cpu.push_back(cpu_now() - c0);
      for (auto& s : r.stages) {
        if (!stage_s.count(s.name)) stage_order.push_back(s.name);
        stage_s[s.name].push_back(s.seconds);
        stage_cpu[s.name].push_back(s.cpu_seconds);
        stage_rss[s.name] = std::max(stage_rss[s.name], s.peak_rss);
        if (s.name == "read") prep = s.seconds;
      }
    }
    std::sort(times.begin(), times.end());
    std::sort(cpu.begin(), cpu.end());
    std::size_t peak = 0;
    for (auto& [n, b] : stage_rss) peak = std::max(peak, b);
    char grid[64];
    std::snprintf(grid, sizeof grid, "%dx%dx%d", r.grid.dims[0], r.grid.dims[1], r.grid.dims[2]);
    std::string name = f.substr(f.find_last_of('/') + 1);
    std::printf("%-24s %9zu %16s %10.3f %10.3f %12.3f %10.3f %10.0f\n", name.c_str(), r.report.input_faces, grid,
                times[times.size() / 2], times.front(), cpu[cpu.size() / 2], prep, peak / 1048576.0);
    for (auto& n : stage_order) {
      auto& v = stage_s[n];
      auto& c = stage_cpu[n];
      std::sort(v.begin(), v.end());
      std::sort(c.begin(), c.end());
      std::printf("    %-32s %8.3f s %8.3f s CPU %8.0f MB peak\n", n.c_str(), v[v.size() / 2], c[c.size() / 2],
                  stage_rss[n] / 1048576.0);
    }
    std::fflush(stdout);
  }
  std::printf("(wall times include mesh reading; CPU = user+sys over all threads, useful when the machine is\n"
              " shared; peak RSS: max over runs and stages of the process's peak within a stage, the VmHWM\n"
              " being reset at each stage start, so earlier models do not count)\n");
  return 0;
}

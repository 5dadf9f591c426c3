// The loop stage at scale: models with many loops, and the loop stage's time as a ratio of the level-set
// stage's time in the same run (robust to the shared machine's speed swings), with the time per loop.
//   pierced block  a block with 100 round through holes of four sizes (analytic::pierced_block), as a mesh
//   cage           a 4x3x3 ball-and-stick cage with a neck on every stick (analytic::ball_and_stick_cage)
//   fertility, neptune   the manifest meshes (Table 1 parameters)
// The analytic models are sampled and their marching surface written as a PLY mesh first, so that every
// model goes through `analyze` as a user's mesh does. Each run is a child process (analyze_child.h).
//
//   bench_loops [--runs 3] [--threads N] [--only NAME] [--data data] [--no-plane-start]
// --no-plane-start: every generator's loop from its membrane (LoopOptions::plane_start off), to compare.
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "analyze_child.h"
#include "chokeloops/huge_pages.h"
#include "chokeloops/field/analytic.h"
#include "chokeloops/output/mesh_write.h"
#include "chokeloops/surface/surface.h"

using namespace chokeloops;

namespace {

struct Model {
  std::string name, file;
  int resolution;
  std::string d_max, min_persistence;  // empty: the CLI's defaults
  bool aimed = false;                   // one of the aim's two models (the pierced block, the cage)
};

// The aim on the pierced block and the cage: the loop stage within 1.5x the level set, the median loop 5 ms.
constexpr double kAimRatio = 1.5, kAimMedianMs = bench::kLoopAimMs;
struct AimLine { std::string name; double ratio, median_ms; int within, loops; };
std::vector<AimLine> aim_lines;

// Samples `sdf` on the unit cube at n^3 and writes its zero surface as a mesh, in a child process (TBB's
// workers do not survive fork(): a parent that had started them would give every later child one thread).
void write_model_mesh(const Sdf& sdf, int n, const std::string& path) {
  if (pid_t pid = fork(); pid == 0) {
    write_ply(extract_zero_surface(sample_field({n, n, n}, sdf)), path);
    _exit(0);
  } else {
    int status = 0;
    waitpid(pid, &status, 0);
  }
}

void run_model(const Model& m, int runs, int threads, bool plane_start) {
  AnalyzeOptions o;
  o.loops.plane_start = plane_start;
  o.levelset.resolution = m.resolution;
  if (!m.d_max.empty()) o.chokes.d_max = Threshold::parse(m.d_max);
  if (!m.min_persistence.empty()) o.chokes.min_persistence = Threshold::parse(m.min_persistence);
  std::map<std::string, std::vector<double>> t;
  std::vector<double> ratio, per_loop, loop_median, handle_median, tunnel_median, p90, within_aim;
  bench::ChildRun last;
  double peak = 0;
  for (int r = 0; r < runs; ++r) {
    last = bench::analyze_in_child(m.file, o, threads);
    if (!last.error.empty()) {
      std::printf("| %-13s | %s |\n", m.name.c_str(), last.error.c_str());
      return;
    }
    for (auto& kv : last.timings_ms) t[kv.first].push_back(kv.second);
    ratio.push_back(last.timings_ms["loops"] / last.timings_ms["levelset"]);
    per_loop.push_back(last.loops ? last.timings_ms["loops"] / last.loops : 0);
    loop_median.push_back(last.loop_median_ms);
    handle_median.push_back(last.handle_median_ms);
    tunnel_median.push_back(last.tunnel_median_ms);
    p90.push_back(last.loop_p90_ms);
    within_aim.push_back(last.loops_within_aim);
    peak = std::max(peak, last.peak_mb);
  }
  std::printf("| %-13s | %4d | %9lld | %3d | %3d | %4d/%-4d | %8.0f | %8.0f | %7.0f | %5.2f | %7.2f | %7.2f | %7.2f | %7.2f | %7.1f | %6.0f |\n",
              m.name.c_str(), m.resolution, last.surface_vertices, last.g, last.k, last.loops_found, last.loops,
              bench::median(t["levelset"]), bench::median(t["loops"]), bench::median(t["check"]),
              bench::median(ratio), bench::median(per_loop), bench::median(loop_median), bench::median(handle_median),
              bench::median(tunnel_median), bench::median(p90), peak);
  std::fflush(stdout);
  if (m.aimed) aim_lines.push_back({m.name, bench::median(ratio), bench::median(loop_median), int(bench::median(within_aim)), last.loops});
}

}  // namespace

int main(int argc, char** argv) {
  chokeloops::restart_with_huge_pages(argv);
  int runs = 3, threads = 0;
  bool plane_start = true;
  std::string data = std::string(CHOKELOOPS_SOURCE_DIR) + "/data", only;
  for (int i = 1; i < argc; ++i) {
    std::string a = argv[i];
    if (a == "--runs" && i + 1 < argc) runs = std::atoi(argv[++i]);
    else if (a == "--threads" && i + 1 < argc) threads = std::atoi(argv[++i]);
    else if (a == "--data" && i + 1 < argc) data = argv[++i];
    else if (a == "--only" && i + 1 < argc) only = argv[++i];
    else if (a == "--no-plane-start") plane_start = false;
    else { std::fprintf(stderr, "usage: bench_loops [--runs N] [--threads N] [--only NAME] [--data DIR] [--no-plane-start]\n"); return 2; }
  }
  const auto tmp = std::filesystem::temp_directory_path();
  const std::string block = (tmp / "chokeloops_pierced_block.ply").string();
  const std::string cage = (tmp / "chokeloops_cage.ply").string();
  if (only.empty() || only == "pierced-block") write_model_mesh(analytic::pierced_block(100, 7), 256, block);
  if (only.empty() || only == "cage") write_model_mesh(analytic::ball_and_stick_cage({4, 3, 3}), 128, cage);
  std::vector<Model> models = {
      {"pierced-block", block, 256, "", "", true},
      {"cage", cage, 160, "", "", true},
      {"fertility", data + "/meshes/fertility_vmas.off", 256, "50%", "10%"},
      {"neptune", data + "/meshes/neptune_vmas.off", 472, "50%", "10%"},
  };
  if (!plane_start) std::printf("every generator's loop from its membrane (--no-plane-start)\n");
  std::printf("median of %d runs, %s threads; times in ms; ratio = loop stage / level-set stage of the same run;\n"
              "ms/loop = loop stage / loops traced; loop med = median over the loops of each one's own wall time (loops\n"
              "run in parallel), also over the handle loops (H med) and the tunnel loops (T med), and its 90th percentile\n"
              "(p90); check = the contractibility check of the generators after the loop stage\n\n",
              runs, threads > 0 ? std::to_string(threads).c_str() : "all");
  std::printf("| model         | res  | surf #v   | g   | k   | loops     | levelset | loops    | check   | ratio | ms/loop | loop med | H med   | T med   | p90     | RSS MB |\n");
  std::printf("|---------------|------|-----------|-----|-----|-----------|----------|----------|---------|-------|---------|----------|---------|---------|---------|--------|\n");
  std::fflush(stdout);
  for (const Model& m : models) {
    if (!only.empty() && m.name != only) continue;
    if (!std::filesystem::exists(m.file)) { std::printf("| %-13s | missing %s |\n", m.name.c_str(), m.file.c_str()); continue; }
    run_model(m, runs, threads, plane_start);
  }
  if (!aim_lines.empty()) std::printf("\naim: loop stage <= %.1fx the level set, median loop <= %.0f ms (medians of the runs)\n", kAimRatio, kAimMedianMs);
  // The median is the loop at place loops / 2 (from 0) in time order: loops / 2 + 1 of them within the aim meet it.
  for (const AimLine& a : aim_lines)
    std::printf("  %-13s ratio %.2f %s, median loop %.2f ms %s (%d of %d loops within %.0f ms, %d needed)\n", a.name.c_str(), a.ratio,
                a.ratio <= kAimRatio ? "met" : "NOT met", a.median_ms, a.median_ms <= kAimMedianMs ? "met" : "NOT met", a.within, a.loops,
                kAimMedianMs, a.loops / 2 + 1);
  if (!std::getenv("CHOKELOOPS_KEEP_MODELS")) {  // set it to profile `chokeloops analyze` on them
    std::filesystem::remove(block);
    std::filesystem::remove(cage);
  }
  return 0;
}

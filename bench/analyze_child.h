#pragma once
// One `analyze` per child process, as a user runs the CLI once per model: repeated runs in one process pay
// for re-faulting memory the allocator gave back (~20% slower), and each child's peak RSS is its own.
// Shared by the benchmarks that time the whole pipeline.
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <tbb/global_control.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "chokeloops/analyze.h"

namespace chokeloops::bench {

// The time a loop's median should stay within (bench_loops' aim); ChildRun counts the loops that do.
constexpr double kLoopAimMs = 5.0;

struct ChildRun {
  std::map<std::string, double> timings_ms;  // per stage, as AnalyzeResult::timings_ms
  long long surface_vertices = 0;
  int dims[3] = {0, 0, 0};
  int g = 0, k = 0, loops = 0, loops_found = 0;
  double loop_median_ms = 0;  // median over the loops of each one's own wall time (Loop::trace_ms)
  // The same over the handle loops and over the tunnel loops (where a model's median sits), and the 90th
  // percentile over all loops (its long tail)
  double handle_median_ms = 0, tunnel_median_ms = 0, loop_p90_ms = 0;
  int loops_within_aim = 0;  // loops whose own wall time is kLoopAimMs or less (how far the median is from it)
  double peak_mb = 0;
  std::string error;
};

inline double percentile(std::vector<double> v, double p) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0 : v[std::min(v.size() - 1, std::size_t(p * double(v.size())))];
}

inline double median(const std::vector<double>& v) { return percentile(v, 0.5); }

// Runs analyze(file, options) in a forked child (with `threads` TBB threads when > 0) and reads its
// figures back through a pipe.
inline ChildRun analyze_in_child(const std::string& file, const AnalyzeOptions& options, int threads = 0) {
  int fd[2];
  ChildRun res;
  if (pipe(fd) != 0) { res.error = "pipe failed"; return res; }
  pid_t pid = fork();
  if (pid == 0) {
    close(fd[0]);
    FILE* out = fdopen(fd[1], "w");
    try {
      std::unique_ptr<tbb::global_control> limit;
      if (threads > 0) limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, threads);
      AnalyzeResult r = analyze(file, options);
      int k = 0, found = 0, within_aim = 0;
      std::vector<double> per_loop, per_side[2];
      for (auto& l : r.loops) {
        k += l.choke.kind == Kind::Choke, found += l.found, per_loop.push_back(l.trace_ms), within_aim += l.trace_ms <= kLoopAimMs;
        per_side[l.choke.side == Side::Handle ? 0 : 1].push_back(l.trace_ms);
      }
      struct rusage ru;
      getrusage(RUSAGE_SELF, &ru);
      std::fprintf(out, "ok %lld %d %d %d %d %d %d %d %.1f %.3f %.3f %.3f %.3f %d\n", (long long)r.surface_stats.vertices,
                   r.grid.dims[0], r.grid.dims[1], r.grid.dims[2], r.chokes.handle_generators, k, int(r.loops.size()), found,
                   ru.ru_maxrss / 1024.0, median(per_loop), median(per_side[0]), median(per_side[1]), percentile(per_loop, 0.9),
                   within_aim);
      for (auto& kv : r.timings_ms) std::fprintf(out, "%s\t%.3f\n", kv.first.c_str(), kv.second);
    } catch (const std::exception& e) {
      std::fprintf(out, "error %s\n", e.what());
    }
    std::fclose(out);
    _exit(0);
  }
  close(fd[1]);
  FILE* in = fdopen(fd[0], "r");
  char line[4096];
  if (std::fgets(line, sizeof line, in)) {
    if (std::strncmp(line, "ok ", 3) == 0) {
      std::sscanf(line + 3, "%lld %d %d %d %d %d %d %d %lf %lf %lf %lf %lf %d", &res.surface_vertices, &res.dims[0], &res.dims[1],
                  &res.dims[2], &res.g, &res.k, &res.loops, &res.loops_found, &res.peak_mb, &res.loop_median_ms,
                  &res.handle_median_ms, &res.tunnel_median_ms, &res.loop_p90_ms, &res.loops_within_aim);
      while (std::fgets(line, sizeof line, in)) {
        char* tab = std::strchr(line, '\t');
        if (!tab) continue;
        *tab = 0;
        res.timings_ms[line] = std::atof(tab + 1);
      }
    } else {
      res.error = line;
      if (!res.error.empty() && res.error.back() == '\n') res.error.pop_back();
    }
  } else {
    res.error = "child produced no result";
  }
  std::fclose(in);
  int status = 0;
  waitpid(pid, &status, 0);
  return res;
}

}  // namespace chokeloops::bench

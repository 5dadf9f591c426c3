#pragma once
// What the benchmarks need to run a peer built from its own sources: a child process timed with its peak RSS,
// and fields as raw float32 mirrored along x, where TTK's triangulation of the grid is chokeloops'.
#include <sys/resource.h>
#include <sys/wait.h>
#include <fcntl.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "chokeloops/grid.h"

namespace chokeloops::bench {

// Runs argv as a child process; wall seconds and its peak RSS (MB) from wait4. False if it failed.
inline bool run_peer(const std::vector<std::string>& argv, double& seconds, double& peak_mb, std::string& error) {
  std::vector<char*> args;
  for (auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  std::fflush(stdout);
  auto t = std::chrono::steady_clock::now();
  pid_t pid = fork();
  if (pid < 0) { error = "fork failed"; return false; }
  if (pid == 0) {
    int null = open("/dev/null", O_WRONLY);
    dup2(null, 1);
    execv(args[0], args.data());
    _exit(127);
  }
  int status = 0;
  struct rusage ru;
  wait4(pid, &status, 0, &ru);
  seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
  peak_mb = double(ru.ru_maxrss) / 1024.0;
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    error = argv[0] + (WIFSIGNALED(status) ? " killed by signal " + std::to_string(WTERMSIG(status))
                                           : " exited with " + std::to_string(WEXITSTATUS(status)));
    return false;
  }
  return true;
}

// The field as raw float32, x fastest, mirrored along x: TTK splits each cube of the grid along its
// (1,0,0)-(0,1,1) diagonal and chokeloops along (0,0,0)-(1,1,1), so TTK's triangulation of the mirrored field is
// chokeloops' triangulation of the field.
inline void write_raw_mirrored_x(const ScalarGrid& g, const std::string& path) {
  std::ofstream out(path, std::ios::binary);
  const std::size_t nx = std::size_t(g.dims[0]);
  std::vector<float> row(nx);
  for (std::size_t r = 0; r < g.values.size() / nx; ++r) {
    for (std::size_t i = 0; i < nx; ++i) row[i] = g.values[r * nx + (nx - 1 - i)];
    out.write(reinterpret_cast<const char*>(row.data()), std::streamsize(nx * sizeof(float)));
  }
  if (!out) throw std::runtime_error("cannot write " + path);
}

// Reads back into `g` (its dims already set) what write_raw_mirrored_x wrote, or a peer's output in that frame.
inline void read_raw_mirrored_x(ScalarGrid& g, const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  const std::size_t nx = std::size_t(g.dims[0]);
  std::vector<float> row(nx);
  for (std::size_t r = 0; r < g.values.size() / nx; ++r) {
    in.read(reinterpret_cast<char*>(row.data()), std::streamsize(nx * sizeof(float)));
    for (std::size_t i = 0; i < nx; ++i) g.values[r * nx + (nx - 1 - i)] = row[i];
  }
  if (!in) throw std::runtime_error("cannot read " + path);
}

}  // namespace chokeloops::bench

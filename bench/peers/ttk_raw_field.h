#pragma once
// What both TTK drivers do first: read a raw float32 field and give TTK its vertex order, on TTK's implicit
// triangulation of the grid.
#include <OrderDisambiguation.h>
#include <Timer.h>
#include <Triangulation.h>

#include <cstdio>
#include <string>
#include <vector>

struct TtkField {
  std::vector<float> values;
  std::vector<ttk::SimplexId> order;
  double order_seconds = 0;
};

// NX*NY*NZ little-endian float32 from `path` (x fastest) and TTK's order of its vertices, with `threads`; false
// with a message on stderr when the file is short or missing.
inline bool read_ttk_field(const char* program, const char* path, int nx, int ny, int nz, int threads, TtkField& f) {
  const std::size_t n = std::size_t(nx) * ny * nz;
  f.values.resize(n);
  std::FILE* in = std::fopen(path, "rb");
  const bool ok = in && std::fread(f.values.data(), sizeof(float), n, in) == n;
  if (in) std::fclose(in);
  if (!ok) {
    std::fprintf(stderr, "%s: cannot read %zu floats from %s\n", program, n, path);
    return false;
  }
  ttk::globalThreadNumber_ = threads;
  ttk::globalDebugLevel_ = 0;
  ttk::Timer order_timer;
  f.order.resize(n);
  ttk::preconditionOrderArray(n, f.values.data(), f.order.data(), threads);
  f.order_seconds = order_timer.getElapsedTime();
  return true;
}

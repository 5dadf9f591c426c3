// The TTK peer of bench_filter: TTK's localized topological simplification (Lukasczyk, Garth, Maciejewski,
// Tierny, TVCG 2021) of a float32 field on a regular grid, through TTK's own base layer on its implicit
// triangulation: every minimum-saddle and maximum-saddle pair of persistence below THRESHOLD is removed by
// changing values. Built apart from the project, against a TTK built from its public sources (bench/README.md).
//
// usage: ttk_lts FIELD.raw NX NY NZ THREADS THRESHOLD OUT.raw
//   FIELD.raw, OUT.raw  NX*NY*NZ little-endian float32, x fastest
// Prints the seconds of the vertex order, of the triangulation's preconditioning and of the simplification.
#include <LocalizedTopologicalSimplification.h>
#include <Timer.h>
#include <Triangulation.h>

#include "ttk_raw_field.h"

#include <cstdio>
#include <cstdlib>
#include <vector>

int main(int argc, char** argv) {
  if (argc != 8) {
    std::fprintf(stderr, "usage: ttk_lts FIELD.raw NX NY NZ THREADS THRESHOLD OUT.raw\n");
    return 2;
  }
  const int nx = std::atoi(argv[2]), ny = std::atoi(argv[3]), nz = std::atoi(argv[4]), threads = std::atoi(argv[5]);
  const float threshold = float(std::atof(argv[6]));
  TtkField f;
  if (!read_ttk_field("ttk_lts", argv[1], nx, ny, nz, threads, f)) return 2;

  ttk::Timer precondition_timer;
  ttk::Triangulation triangulation;
  triangulation.setInputGrid(0, 0, 0, 1, 1, 1, nx, ny, nz);
  ttk::lts::LocalizedTopologicalSimplification lts;
  lts.setThreadNumber(threads);
  lts.setDebugLevel(0);
  lts.preconditionTriangulation(&triangulation);
  const double precondition_s = precondition_timer.getElapsedTime();

  ttk::Timer simplify_timer;
  int status = 0;
  ttkTemplateMacro(triangulation.getType(),
                   status = (lts.removeNonPersistentExtrema<float, ttk::SimplexId, TTK_TT>(
                       f.values.data(), f.order.data(), static_cast<const TTK_TT*>(triangulation.getData()), threshold, true)));
  const double simplify_s = simplify_timer.getElapsedTime();
  if (status != 0) {
    std::fprintf(stderr, "ttk_lts: TTK failed (%d)\n", status);
    return 1;
  }
  std::printf("order %.3f s, precondition %.3f s, simplification %.3f s\n", f.order_seconds, precondition_s, simplify_s);
  std::FILE* out = std::fopen(argv[7], "wb");
  if (!out || std::fwrite(f.values.data(), sizeof(float), f.values.size(), out) != f.values.size() || std::fclose(out) != 0) {
    std::fprintf(stderr, "ttk_lts: cannot write %s\n", argv[7]);
    return 2;
  }
  return 0;
}

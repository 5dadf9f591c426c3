// The TTK peer of bench_persistence: TTK's persistence diagram (DiscreteMorseSandwich backend, Guillou, Vidal,
// Tierny, TVCG 2023) of a float32 field on a regular grid, through TTK's own base layer on its implicit
// triangulation. Built apart from the project, against a TTK built from its public sources (bench/README.md):
// TTK is not packaged for Debian, and the tests never need it.
//
// usage: ttk_persistence FIELD.raw NX NY NZ THREADS [PAIRS.csv]
//   FIELD.raw  NX*NY*NZ little-endian float32, x fastest
//   PAIRS.csv  the finite pairs as "dim,birth,death" (%.9g), for bench_persistence to compare with its own
// Prints the seconds of the vertex order, of the triangulation's preconditioning and of the diagram.
#include <PersistenceDiagram.h>
#include <Timer.h>
#include <Triangulation.h>

#include "ttk_raw_field.h"

#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

int main(int argc, char** argv) {
  if (argc < 6) {
    std::fprintf(stderr, "usage: ttk_persistence FIELD.raw NX NY NZ THREADS [PAIRS.csv]\n");
    return 2;
  }
  const int nx = std::atoi(argv[2]), ny = std::atoi(argv[3]), nz = std::atoi(argv[4]), threads = std::atoi(argv[5]);
  TtkField f;
  if (!read_ttk_field("ttk_persistence", argv[1], nx, ny, nz, threads, f)) return 2;

  ttk::Timer precondition_timer;
  ttk::Triangulation triangulation;
  triangulation.setInputGrid(0, 0, 0, 1, 1, 1, nx, ny, nz);
  ttk::PersistenceDiagram diagram;
  diagram.setThreadNumber(threads);
  diagram.setDebugLevel(0);
  diagram.setBackend(ttk::PersistenceDiagram::BACKEND::DISCRETE_MORSE_SANDWICH);
  diagram.preconditionTriangulation(&triangulation);
  const double precondition_s = precondition_timer.getElapsedTime();

  ttk::Timer diagram_timer;
  std::vector<ttk::PersistencePair> pairs;
  int status = 0;
  ttkTemplateMacro(triangulation.getType(),
                   status = diagram.execute(pairs, f.values.data(), 0, f.order.data(),
                                            static_cast<const TTK_TT*>(triangulation.getData())));
  const double diagram_s = diagram_timer.getElapsedTime();
  if (status != 0) {
    std::fprintf(stderr, "ttk_persistence: TTK failed (%d)\n", status);
    return 1;
  }
  long long count[3] = {0, 0, 0};
  for (const auto& p : pairs)
    if (p.isFinite && p.dim >= 0 && p.dim < 3) ++count[p.dim];
  std::printf("order %.3f s, precondition %.3f s, diagram %.3f s; finite pairs %lld %lld %lld\n", f.order_seconds,
              precondition_s, diagram_s, count[0], count[1], count[2]);
  if (argc > 6) {
    std::FILE* out = std::fopen(argv[6], "w");
    if (!out) {
      std::fprintf(stderr, "ttk_persistence: cannot write %s\n", argv[6]);
      return 2;
    }
    for (const auto& p : pairs)
      if (p.isFinite) std::fprintf(out, "%d,%.9g,%.9g\n", int(p.dim), p.birth.sfValue, p.death.sfValue);
    if (std::fclose(out) != 0) return 2;
  }
  return 0;
}

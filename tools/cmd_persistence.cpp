// `chokeloops persistence FIELD.vdb -o pairs.csv`: lower-star persistence pairs of a scalar field.
#include <chrono>
#include <iomanip>
#include <iostream>
#include <memory>

#include "chokeloops/field/memory_budget.h"
#include "chokeloops/grid.h"
#include "chokeloops/topology/persistence.h"
#include "chokeloops/io/vdb_io.h"
#include "args.h"
#include "command.h"

namespace {

const char* kUsage =
    "usage: chokeloops persistence FIELD.vdb -o PAIRS.csv [options]\n"
    "\n"
    "Persistence pairs (dimensions 0, 1, 2; Z/2) of the lower-star filtration of a scalar field on the\n"
    "Freudenthal triangulation of its grid. The field is the first float grid of the .vdb file (or\n"
    "--grid NAME), densified over its active bounding box. Writes one 'dim,birth,death' row per pair\n"
    "(GUDHI style; the essential class has death 'inf'), and a summary on stderr.\n"
    "\n"
    "options:\n"
    "  -o, --output FILE   output .csv (required)\n"
    "  --grid NAME         which grid of the .vdb file (default: the first float grid)\n"
    "  --threads N         use at most N threads (default: all cores)\n"
    "  --max-memory BYTES  refuse fields whose pairs need more (e.g. 8G; default 80% of RAM)\n"
    "  -q, --quiet         no summary\n"
    "  -h, --help          this help\n"
    "\n"
    "exit codes: 0 ok, 2 bad input or arguments (missing file, no float grid, empty grid, non-finite\n"
    "values), 3 not enough memory\n";

int run(std::vector<std::string> args) {
  using namespace chokeloops;
  std::string input, output, grid_name;
  int threads = 0;
  std::size_t max_memory = 0;
  bool quiet = false;
  cli::Args in("persistence", std::move(args));
  while (in.next()) {
    if (in.is("-h", "--help")) {
      std::cout << kUsage;
      return 0;
    } else if (in.is("-o", "--output")) {
      output = in.value();
    } else if (in.is("--grid")) {
      grid_name = in.value();
    } else if (in.is("--threads")) {
      threads = in.threads();
    } else if (in.is("--max-memory")) {
      max_memory = parse_bytes(in.value());
    } else if (in.is("-q", "--quiet")) {
      quiet = true;
    } else {
      in.positional(input, "input file");
    }
  }
  if (input.empty()) throw Error("no input .vdb file given (see --help)");
  if (output.empty()) throw Error("no output file given: use -o PAIRS.csv (see --help)");

  auto limit = cli::limit_threads(threads);

  auto t0 = std::chrono::steady_clock::now();
  ScalarGrid grid = read_vdb_dense(input, grid_name);
  auto t1 = std::chrono::steady_clock::now();
  PersistenceDiagram d = lower_star_persistence(grid, {}, max_memory);
  auto t2 = std::chrono::steady_clock::now();
  write_pairs_csv(d, output);

  if (!quiet) {
    auto secs = [](auto a, auto b) { return std::chrono::duration<double>(b - a).count(); };
    std::cerr << std::fixed << std::setprecision(3) << "persistence: " << grid.dims[0] << "x" << grid.dims[1] << "x"
              << grid.dims[2] << " vertices; pairs dim0 " << d.count(0) << ", dim1 " << d.count(1) << ", dim2 "
              << d.count(2) << ", essential " << d.essential.size() << "; read " << secs(t0, t1) << " s, persistence "
              << secs(t1, t2) << " s; wrote " << output << "\n";
  }
  return 0;
}

chokeloops::cli::Register reg("persistence", "persistence pairs of a scalar field (.vdb) as CSV", run);

}  // namespace

// `chokeloops batch INPUT... -o OUTDIR [--jobs N]`: one output directory per input and OUTDIR/summary.csv;
// resumable, and a failing input never stops the others (a thin layer over run_batch, batch.h).
#include <cstdio>
#include <fstream>
#include <iostream>

#include "chokeloops/batch.h"
#include "args.h"
#include "command.h"

using namespace chokeloops;

namespace {

const char* kUsage = R"(usage: chokeloops batch INPUT... -o OUTDIR [options]

Analyses every INPUT (mesh or .vdb) into OUTDIR/<name>/ (the files of chokeloops analyze, plus status.json)
and writes OUTDIR/summary.csv: input, status (ok/failed), genus, loop counts, deepest and most persistent
loop, time, error. Inputs that finished earlier with the same options are skipped (resume); failed ones are
analysed again. A failing input never stops the others.
  -o, --output DIR          output directory
  --list FILE               also read inputs from FILE, one path per line (# comments)
  -j, --jobs N              inputs analysed at once, each in its own process (default 1)
  --threads N               threads per input (default: all cores / jobs)
  --force                   analyse every input again (no resume)
  --resolution N|auto, --voxel-size H, --margin M, --dmax X, --min-persistence Y, --side handle|tunnel|both,
  --max-memory BYTES, --no-view, --no-shorten, --no-slide, --no-plane-start, --no-check
                            as for chokeloops analyze (--max-memory is per input)
  --quiet                   no line per finished input on stderr
Exit codes: 0 every input ok, 1 some input failed (see summary.csv), 2 bad arguments.
)";

int run(std::vector<std::string> args) {
  BatchOptions options;
  AnalyzeOptions& ao = options.analyze;
  std::vector<std::string> inputs;
  std::string outdir;
  bool quiet = false;
  cli::Args in("batch", std::move(args));
  while (in.next()) {
    if (in.is("-h", "--help")) { std::cout << kUsage; return 0; }
    else if (in.is("-o", "--output")) outdir = in.value();
    else if (in.is("--list")) {
      std::string path = in.value();
      std::ifstream list(path);
      if (!list) throw Error("cannot read input list '" + path + "'");
      for (std::string line; std::getline(list, line);) {
        while (!line.empty() && (line.back() == '\r' || line.back() == ' ' || line.back() == '\t')) line.pop_back();
        if (!line.empty() && line[0] != '#') inputs.push_back(line);
      }
    } else if (in.is("-j", "--jobs")) options.jobs = int(in.integer(1, 1024));
    else if (in.is("--threads")) options.threads = in.threads();
    else if (in.is("--force")) options.resume = false;
    else if (in.is("--resolution")) {
      if (in.peek() == "auto") ao.resolution_auto = in.value() == "auto";
      else ao.levelset.resolution = int(in.integer(8, 4096));
    } else if (in.is("--voxel-size")) {
      ao.levelset.voxel_size = in.number();
      if (!(ao.levelset.voxel_size > 0)) throw Error("--voxel-size must be positive");
    } else if (in.is("--margin")) ao.levelset.margin = in.number();
    else if (in.is("--dmax")) ao.chokes.d_max = Threshold::parse(in.value());
    else if (in.is("--min-persistence")) ao.chokes.min_persistence = Threshold::parse(in.value());
    else if (in.is("--side")) {
      std::string v = in.value();
      if (v != "handle" && v != "tunnel" && v != "both") throw Error("--side must be handle, tunnel or both");
      ao.chokes.handles = v != "tunnel";
      ao.chokes.tunnels = v != "handle";
    } else if (in.is("--max-memory")) ao.levelset.max_memory = parse_bytes(in.value());
    else if (in.is("--no-view")) options.view = false;
    else if (in.is("--no-shorten")) ao.loops.shorten = false;
    else if (in.is("--no-slide")) ao.loops.slide = false;
    else if (in.is("--no-plane-start")) ao.loops.plane_start = false;
    else if (in.is("--no-check")) ao.check_generators = false;
    else if (in.is("-q", "--quiet")) quiet = true;
    else {
      std::string input;
      in.positional(input, "input");
      inputs.push_back(input);
    }
  }
  if (inputs.empty()) throw Error("no input given (usage: chokeloops batch INPUT... -o OUTDIR)");
  if (outdir.empty()) throw Error("no output directory given (-o OUTDIR)");

  auto items = run_batch(inputs, outdir, options, [&](const BatchItem& it, std::size_t done, std::size_t total) {
    if (quiet) return;
    if (it.status == "ok")
      std::fprintf(stderr, "[%zu/%zu] %s: ok%s, genus %d, %d+%d handle, %d+%d tunnel loops, %.1f s\n", done, total,
                   it.input.c_str(), it.resumed ? " (done earlier)" : "", it.genus, it.handle_generators,
                   it.handle_chokes, it.tunnel_generators, it.tunnel_chokes, it.seconds);
    else
      std::fprintf(stderr, "[%zu/%zu] %s: failed: %s\n", done, total, it.input.c_str(), it.error.c_str());
  });
  std::size_t ok = 0, resumed = 0;
  for (auto& it : items) {
    ok += it.status == "ok";
    resumed += it.resumed;
  }
  std::printf("%zu input(s): %zu ok (%zu done earlier), %zu failed; wrote %s/summary.csv\n", items.size(), ok,
              resumed, items.size() - ok, outdir.c_str());
  return ok == items.size() ? 0 : 1;
}

chokeloops::cli::Register reg("batch", "analyse many inputs into one directory each, with a summary CSV", run);

}  // namespace

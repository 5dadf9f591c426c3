// Benchmark of `filter`: time and peak memory per stage, each case in a forked child.
//   noisy:N[:A]  the tangle cube (genus 5) sampled at N^3 with uniform noise of A voxels (default 0.25), which
//             adds pairs thinner than a voxel (at 256: genus 360 at 0.25, 987 at 0.32); filtered with --keep-genus 5
//   gm        the MNI ICBM 2009a grey-matter map (data/volumes) at --iso 128 (p = 0.5), --keep-genus 0, through
//             the file path (read, field, filter, write, read back and check)
// usage: bench_filter [--runs R] [--peer-lts BIN [--lts-threshold V]] [case...]
//   (default: noisy:256 noisy:256:0.32 gm; medians of R runs, default 3)
//   --peer-lts  TTK's localized topological simplification (bench/peers/ttk_lts.cpp, built from TTK's sources,
//               bench/README.md) on each noisy case's field too, in its own process, mirrored along x (where its
//               triangulation is ours), removing every extremum-saddle pair of persistence below V voxels
//               (default 1); its output's genus, components and cavities by chokeloops' persistence, and how
//               many voxels changed side and value, on a second line.
// The figure that does not depend on the machine's speed: filter time / persistence time of the same run.
// Columns: persist = the first persistence; edits = applying edits and checking them, of which labels (the
// components of both sides after each batch) and recheck (one persistence after each round's kept batch).
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include <tbb/info.h>

#include "analyze_child.h"
#include "peer_process.h"
#include "chokeloops/huge_pages.h"
#include "chokeloops/field/analytic.h"
#include "chokeloops/filter/filter_file.h"

using namespace chokeloops;

namespace {

struct Figures {
  double persistence_ms = 0, membranes_ms = 0, edits_ms = 0, labels_ms = 0, rechecks_ms = 0, total_ms = 0, peak_mb = 0,
         changed_pct = 0;
  int genus_before = 0, genus_after = 0, components_before = 0, components_after = 0, edits = 0, notes = 0, rounds = 0;
  bool ok = false;
  // the peer (--peer-lts) on the same field
  bool lts_ok = false;
  double lts_ms = 0, lts_peak_mb = 0, lts_sides_pct = 0, lts_values_pct = 0;
  int lts_genus = 0, lts_components = 0, lts_cavities = 0, cavities_before = 0;
  char lts_error[160] = "";
};

std::string peer_lts;          // --peer-lts
double lts_threshold = 1.0;    // --lts-threshold, voxels

// TTK's LTS on the field, in its own process; its output read back and analysed here.
void run_lts(const ScalarGrid& g, Figures& f) {
  char dir[] = "/tmp/bench_filter_XXXXXX";
  if (!mkdtemp(dir)) return;
  const std::string raw = std::string(dir) + "/field.raw", out = std::string(dir) + "/simplified.raw";
  bench::write_raw_mirrored_x(g, raw);
  std::string error;
  double seconds = 0;
  char threshold[32];
  std::snprintf(threshold, sizeof threshold, "%.9g", lts_threshold * g.voxel_size);
  if (bench::run_peer({peer_lts, raw, std::to_string(g.dims[0]), std::to_string(g.dims[1]), std::to_string(g.dims[2]),
                       std::to_string(tbb::info::default_concurrency()), threshold, out},
                      seconds, f.lts_peak_mb, error)) {
    ScalarGrid s = g;
    bench::read_raw_mirrored_x(s, out);
    const FilterSummary after = topology_summary(s);
    std::size_t sides = 0, values = 0;
    for (std::size_t v = 0; v < g.values.size(); ++v) {
      sides += (s.values[v] <= 0) != (g.values[v] <= 0);
      values += s.values[v] != g.values[v];
    }
    f.lts_ok = true;
    f.lts_ms = 1000 * seconds;
    f.lts_genus = after.genus, f.lts_components = after.components, f.lts_cavities = after.cavities;
    f.lts_sides_pct = 100.0 * double(sides) / double(g.values.size());
    f.lts_values_pct = 100.0 * double(values) / double(g.values.size());
  } else {
    std::snprintf(f.lts_error, sizeof f.lts_error, "%s", error.c_str());
  }
  std::remove(raw.c_str());
  std::remove(out.c_str());
  rmdir(dir);
}

void take_report(const FilterReport& r, Figures& f) {
  f.persistence_ms = r.timings_ms.at("persistence");
  f.membranes_ms = r.timings_ms.at("membranes");
  f.edits_ms = r.timings_ms.at("edits and checks");
  f.labels_ms = r.timings_ms.at("labels");
  f.rechecks_ms = r.timings_ms.at("persistence after edits");
  f.total_ms = r.timings_ms.at("total");
  f.genus_before = r.before.genus, f.genus_after = r.after.genus;
  f.components_before = r.before.components, f.components_after = r.after.components;
  f.edits = int(r.edits.size()), f.notes = int(r.notes.size()), f.rounds = r.rounds;
}

Figures run_case(const std::string& name) {
  Figures f;
  if (name.rfind("noisy:", 0) == 0) {
    const int n = std::atoi(name.c_str() + 6);
    const std::size_t colon = name.find(':', 6);
    const double amplitude = colon == std::string::npos ? 0.25 : std::atof(name.c_str() + colon + 1);
    ScalarGrid g = sample_field({n, n, n}, analytic::tangle_cube());
    add_uniform_noise(g, amplitude * g.voxel_size, 7);
    if (!peer_lts.empty()) run_lts(g, f);  // first, untimed by the filter's own clock
    FilterOptions o;
    o.keep_genus = 5;
    const FilterReport r = filter_grid(g, o);
    take_report(r, f);
    f.cavities_before = r.before.cavities;
    const FilterSummary check = topology_summary(g);  // not timed: the filtered field, by persistence
    if (check.genus != r.after.genus || check.components != r.after.components || check.cavities != r.after.cavities)
      throw InternalError("bench: the filtered field's persistence disagrees with the filter's report");
    f.changed_pct = 100.0 * double(r.voxels_changed) / double(g.values.size());
  } else if (name == "gm") {
    const std::string in = std::string(CHOKELOOPS_SOURCE_DIR) + "/data/volumes/mni_icbm152_gm_tal_nlin_sym_09a_converted.nii.gz";
    const std::string out = (std::filesystem::temp_directory_path() / ("bench_filter_gm_" + std::to_string(::getpid()) + ".nii.gz")).string();
    FilterFileOptions o;
    o.field.has_iso = true;
    o.field.iso = 128;
    o.filter.keep_genus = 0;
    const auto t0 = std::chrono::steady_clock::now();
    const FilterFileResult r = filter_file(in, out, o);
    std::filesystem::remove(out);
    take_report(r.report, f);
    f.total_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    f.changed_pct = 100.0 * double(r.report.voxels_changed) / double(r.grid_vertices);
  } else {
    throw Error("unknown case " + name);
  }
  struct rusage ru;
  getrusage(RUSAGE_SELF, &ru);
  f.peak_mb = ru.ru_maxrss / 1024.0;
  f.ok = true;
  return f;
}

// In a child, as a user runs the CLI once per input; the figures come back through a pipe.
Figures in_child(const std::string& name) {
  int fd[2];
  Figures f;
  if (pipe(fd) != 0) return f;
  std::fflush(stdout);  // else the child's own flushes (the peer's) print the parent's buffer again
  const pid_t pid = fork();
  if (pid == 0) {
    close(fd[0]);
    Figures r;
    try {
      r = run_case(name);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "%s: %s\n", name.c_str(), e.what());
    }
    if (write(fd[1], &r, sizeof r) != ssize_t(sizeof r)) _exit(1);
    _exit(0);
  }
  close(fd[1]);
  if (read(fd[0], &f, sizeof f) != ssize_t(sizeof f)) f.ok = false;
  close(fd[0]);
  int status = 0;
  waitpid(pid, &status, 0);
  return f;
}

}  // namespace

int main(int argc, char** argv) {
  chokeloops::restart_with_huge_pages(argv);
  int runs = 3;
  std::vector<std::string> cases;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--runs") && i + 1 < argc) runs = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--peer-lts") && i + 1 < argc) peer_lts = argv[++i];
    else if (!std::strcmp(argv[i], "--lts-threshold") && i + 1 < argc) lts_threshold = std::atof(argv[++i]);
    else cases.push_back(argv[i]);
  }
  if (cases.empty()) cases = {"noisy:256", "noisy:256:0.32", "gm"};
  std::printf("%-14s %6s %6s %6s %6s %5s %5s %6s %9s %9s %9s %9s %9s %9s %7s %8s %8s\n", "case", "genus", "after", "comp", "after",
              "edits", "notes", "rounds", "persist", "membrane", "edits", "labels", "recheck", "total", "ratio", "changed", "peak");
  for (const std::string& name : cases) {
    std::vector<double> p, m, e, l, c, t, mem, lts;
    Figures last;
    for (int r = 0; r < runs; ++r) {
      last = in_child(name);
      if (!last.ok) break;
      p.push_back(last.persistence_ms), m.push_back(last.membranes_ms), e.push_back(last.edits_ms), t.push_back(last.total_ms);
      l.push_back(last.labels_ms), c.push_back(last.rechecks_ms);
      mem.push_back(last.peak_mb);
      if (last.lts_ok) lts.push_back(last.lts_ms);
    }
    if (!last.ok) {
      std::printf("%-14s failed\n", name.c_str());
      continue;
    }
    const double pm = bench::median(p), tm = bench::median(t);
    std::printf("%-14s %6d %6d %6d %6d %5d %5d %6d %7.0fms %7.0fms %7.0fms %7.0fms %7.0fms %7.0fms %6.1fx %7.4f%% %6.0fMB\n",
                name.c_str(), last.genus_before, last.genus_after, last.components_before, last.components_after, last.edits,
                last.notes, last.rounds, pm, bench::median(m), bench::median(e), bench::median(l), bench::median(c), tm, tm / pm,
                last.changed_pct, bench::median(mem));
    if (!peer_lts.empty() && name.rfind("noisy:", 0) == 0) {
      if (!last.lts_ok)
        std::printf("  TTK LTS failed: %s\n", last.lts_error);
      else
        std::printf("  TTK LTS (extremum-saddle pairs below %.2g voxel): %.0fms (%.1fx the filter's total), peak %.0fMB; genus %d -> %d, "
                    "components %d -> %d, cavities %d -> %d; %.4f%% of the voxels changed side, %.2f%% changed value\n",
                    lts_threshold, bench::median(lts), bench::median(lts) / tm, last.lts_peak_mb, last.genus_before, last.lts_genus,
                    last.components_before, last.lts_components, last.cavities_before, last.lts_cavities, last.lts_sides_pct,
                    last.lts_values_pct);
    }
  }
  return 0;
}

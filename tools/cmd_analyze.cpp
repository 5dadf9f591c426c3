// `chokeloops analyze INPUT -o OUTDIR`: every stage, the report files, the viewer page and a summary.
#include <unistd.h>

#include <array>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <memory>

#include "chokeloops/analyze.h"
#include "chokeloops/output/view.h"
#include "analyze_volume_cli.h"
#include "args.h"
#include "command.h"

using namespace chokeloops;

namespace {

const char* kUsage = R"(usage: chokeloops analyze INPUT -o OUTDIR [options]

INPUT is a mesh (.obj .ply .off .stl), a .vdb level set / density grid, or a medical volume (.nii .nii.gz
.hdr .nrrd .nhdr) with one of --iso, --label, --labels all.
  -o, --output DIR          output directory (surface.ply, loops.ply, loops.obj, loops.json, view.html)
  --resolution N|auto       voxels along the longest side (default 256); auto: the coarsest grid that keeps
                            a closed input mesh's genus and components (up to 1024 or --max-memory)
  --voxel-size H            voxel size in input units (instead of --resolution)
  --margin M                padding around the object, input units (default: 10% of its longest side)
  --dmax X                  how deep/far to look for additional loops: percentage of R_in (handles) /
                            R_out (tunnels), e.g. 50%, or a length in input units (default 50%)
  --min-persistence Y       minimum persistence of additional loops, same units (default 10%)
  --side handle|tunnel|both which loops to report (default both)
  --threads N               worker threads (default: all cores); results do not depend on it
  --max-memory BYTES        refuse grids needing more (e.g. 8G; default 80% of RAM)
  --png FILE                also render a picture of the surface and its loops (needs chromium)
  --no-view                 do not write view.html
  --no-shorten              keep the raw membrane loops (no geodesic shortening)
  --no-slide                shorten only; do not slide loops along tubes to the narrowest section
  --no-check                skip verifying that generator loops are non-contractible (CGAL; costs
                            seconds on large surfaces of positive genus)
  --quiet                   no progress on stderr
  --max-loops N|all         trace loops for the N most persistent chokes only (default 20 for volumes,
                            all otherwise); the rest are counted
Volumes (positions in the image's world mm, RAS for NIfTI, the file's space for NRRD; distances in mm with
the image's own spacing; writes loops.nii.gz / membranes.nii.gz (.nrrd for NRRD) on the input's grid too):
  --iso T                   scalar image: inside where the stored value is >= T
  --inside above|below      below: inside where the value is < T
  --label N                 label map: the voxels equal to N (boundary halfway between voxels)
  --labels all              one analysis per non-zero label into OUTDIR/label_N/, index in OUTDIR/labels.json
  --volume K                the K-th volume (from 0) of a 4D image
  --expect-genus G          list handle generators beyond the G most persistent as topology defects
Exit codes: 0 success, 2 bad input, 3 out of resources.
)";

// Stage names and a bar on stderr, shown once the run has taken more than a second.
class Progress {
 public:
  explicit Progress(bool quiet) : quiet_(quiet), start_(std::chrono::steady_clock::now()), tty_(isatty(2)) {}
  bool operator()(const char* stage, double fraction) {
    if (quiet_) return true;
    double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    if (t < 1.0) return true;
    std::string name = stage;
    int pct = int(fraction * 100);
    if (tty_) {
      int filled = pct / 5;
      std::fprintf(stderr, "\r%-12s [%s%s] %3d%%  %6.1fs", stage, std::string(filled, '#').c_str(),
                   std::string(20 - filled, '.').c_str(), pct, t);
      if (name == "done") std::fprintf(stderr, "\n");
    } else if (name != last_) {
      std::fprintf(stderr, "[%6.1fs] %s\n", t, stage);
    }
    last_ = name;
    return true;
  }

 private:
  bool quiet_;
  std::chrono::steady_clock::time_point start_;
  bool tty_;
  std::string last_;
};

int run(std::vector<std::string> args) {
  AnalyzeOptions options;
  std::string input, outdir, png;
  bool quiet = false, view = true;
  int threads = 0;
  cli::VolumeCliOptions vo;
  bool max_loops_given = false;
  cli::Args in("analyze", std::move(args));
  while (in.next()) {
    if (in.is("-h", "--help")) { std::cout << kUsage; return 0; }
    else if (in.is("-o", "--output")) outdir = in.value();
    else if (in.is("--resolution")) {
      if (in.peek() == "auto") options.resolution_auto = in.value() == "auto";
      else options.levelset.resolution = int(in.integer(8, 4096));
    } else if (in.is("--voxel-size")) {
      options.levelset.voxel_size = in.number();
      if (!(options.levelset.voxel_size > 0)) throw Error("--voxel-size must be positive");
    } else if (in.is("--margin")) options.levelset.margin = in.number();
    else if (in.is("--dmax")) options.chokes.d_max = Threshold::parse(in.value());
    else if (in.is("--min-persistence")) options.chokes.min_persistence = Threshold::parse(in.value());
    else if (in.is("--side")) {
      std::string v = in.value();
      if (v != "handle" && v != "tunnel" && v != "both") throw Error("--side must be handle, tunnel or both");
      options.chokes.handles = v != "tunnel";
      options.chokes.tunnels = v != "handle";
    } else if (in.is("--threads")) threads = in.threads();
    else if (in.is("--max-memory")) options.levelset.max_memory = parse_bytes(in.value());
    else if (in.is("--png")) png = in.value();
    else if (in.is("--no-view")) view = false;
    else if (in.is("--no-shorten")) options.loops.shorten = false;
    else if (in.is("--no-slide")) options.loops.slide = false;
    else if (in.is("--no-check")) options.check_generators = false;
    else if (in.is("-q", "--quiet")) quiet = true;
    else if (in.is("--iso")) { vo.field.has_iso = true; vo.field.iso = in.number(); }
    else if (in.is("--inside")) {
      std::string v = in.value();
      if (v != "above" && v != "below") throw Error("--inside must be above or below");
      vo.field.inside_below = v == "below";
    } else if (in.is("--label")) { vo.field.has_label = true; vo.field.label = double(in.integer(-2147483647L, 2147483647L)); }
    else if (in.is("--labels")) {
      if (in.value() != "all") throw Error("--labels takes 'all' (or use --label N)");
      vo.all_labels = true;
    } else if (in.is("--volume")) vo.volume = int(in.integer(0, 1 << 20));
    else if (in.is("--expect-genus")) vo.expect_genus = int(in.integer(0, 1 << 30));
    else if (in.is("--max-loops")) {
      max_loops_given = true;
      if (in.peek() == "all") { in.value(); options.max_loops = -1; }
      else options.max_loops = int(in.integer(0, 1 << 30));
    }
    else in.positional(input, "input");
  }
  if (input.empty()) throw Error("no input given (usage: chokeloops analyze INPUT -o OUTDIR)");
  if (outdir.empty()) throw Error("no output directory given (-o OUTDIR)");
  auto limit = cli::limit_threads(threads);

  Progress progress(quiet);
  const bool volume_input = is_volume_path(input);
  const bool volume_options = vo.field.has_iso || vo.field.has_label || vo.all_labels || vo.volume >= 0 ||
                              vo.expect_genus >= 0 || vo.field.inside_below;
  if (volume_input) {
    if (vo.all_labels && (vo.field.has_label || vo.field.has_iso))
      throw Error("--labels all analyses every label: give it without --label / --iso");
    if (!vo.all_labels && vo.field.has_label == vo.field.has_iso)
      throw Error("a volume needs exactly one of --iso T (scalar image), --label N or --labels all (label map)");
    if (options.levelset.voxel_size > 0 || options.resolution_auto)
      throw Error("--voxel-size / --resolution auto: volumes are analysed on their own voxel grid (no resampling)");
    if (!max_loops_given) options.max_loops = 20;
    vo.field.margin = options.levelset.margin;
    vo.view = view;
    return cli::run_volume(input, outdir, options, vo, std::ref(progress));
  }
  if (volume_options)
    throw Error("--iso, --inside, --label, --labels, --volume and --expect-genus apply to volumes (.nii, .nii.gz, .nrrd, .nhdr) only");
  AnalyzeResult r = analyze(input, options, std::ref(progress));
  auto t = std::chrono::steady_clock::now();
  write_report(r, options, outdir);
  if (view) write_view_html(outdir);
  if (!png.empty()) render_png(outdir, png);
  double report_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();

  for (auto& w : r.warnings) std::cerr << "chokeloops analyze: warning: " << w << "\n";
  int counts[2][2] = {{0, 0}, {0, 0}};
  for (auto& l : r.loops) counts[l.choke.side == Side::Tunnel][l.choke.kind == Kind::Choke] += 1;
  std::printf("%s: grid %dx%dx%d (voxel %.4g), surface %lld vertices, genus %d, %d component(s)\n",
              input.c_str(), r.grid.dims[0], r.grid.dims[1], r.grid.dims[2], r.grid.voxel_size,
              (long long)r.surface_stats.vertices, r.surface_stats.genus, r.surface_stats.components);
  std::printf("handle loops: %d generator(s), %d choke(s)   tunnel loops: %d generator(s), %d choke(s)\n",
              counts[0][0], counts[0][1], counts[1][0], counts[1][1]);
  std::printf("d_max %s (handles %.4g, tunnels %.4g), min persistence %s (handles %.4g, tunnels %.4g)\n",
              options.chokes.d_max.text().c_str(), r.chokes.d_max_handle, r.chokes.d_max_tunnel,
              options.chokes.min_persistence.text().c_str(), r.chokes.min_persistence_handle,
              r.chokes.min_persistence_tunnel);
  // Persistence is sampled: a loop just under the threshold may appear on another grid. Say how close it is.
  auto filtered = [](const char* side, const std::array<double, 2>& c, double scale, const char* scale_name) {
    if (c[1] <= 0) return std::string();
    char buf[160];
    std::snprintf(buf, sizeof buf, "%s %.4g (%.3g%% of %s) at depth %.4g", side, c[1], 100 * c[1] / scale, scale_name, c[0]);
    return std::string(buf);
  };
  std::string fh = filtered("handle", r.chokes.strongest_filtered_handle, r.chokes.R_in, "R_in");
  std::string ft = filtered("tunnel", r.chokes.strongest_filtered_tunnel, r.chokes.R_out, "R_out");
  if (!fh.empty() || !ft.empty())
    std::printf("strongest below min persistence: %s%s%s\n", fh.c_str(), !fh.empty() && !ft.empty() ? ", " : "", ft.c_str());
  std::printf("time: levelset %.0f ms, persistence %.0f ms, surface %.0f ms, loops %.0f ms, check %.0f ms, report %.0f ms, total %.0f ms\n",
              r.timings_ms["levelset"], r.timings_ms["persistence"], r.timings_ms["surface"], r.timings_ms["loops"],
              r.timings_ms["check"], report_ms, r.timings_ms["total"] + report_ms);
  std::printf("wrote %s/{surface.ply,loops.ply,loops.obj,loops.json%s}%s%s\n", outdir.c_str(), view ? ",view.html" : "",
              png.empty() ? "" : " and ", png.c_str());
  return 0;
}

chokeloops::cli::Register reg("analyze", "find the handle and tunnel choking loops of a mesh or level set", run);

}  // namespace

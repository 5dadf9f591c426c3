// `chokeloops analyze INPUT -o OUTDIR`: every stage, the report files, the viewer page and a summary.
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <array>
#include <chrono>
#include <cctype>
#include <filesystem>
#include <cstdio>
#include <iostream>
#include <memory>

#include "chokeloops/analyze.h"
#include "chokeloops/analyze_molecule.h"
#include "chokeloops/huge_pages.h"
#include "chokeloops/output/view.h"
#include "chokeloops/tet/tet_field.h"  // options only: the path itself is built with CHOKELOOPS_TETGEN
#ifdef CHOKELOOPS_HAS_TETGEN
#include "chokeloops/tet/analyze_tet.h"
#endif
#include "analyze_volume_cli.h"
#include "args.h"
#include "command.h"

using namespace chokeloops;

namespace {

const char* kUsage = R"(usage: chokeloops analyze INPUT -o OUTDIR [options]

INPUT is a mesh (.obj .ply .off .stl), a .vdb level set / density grid, a molecule (.pdb .cif .ent .mmcif,
optionally .gz; lengths in Å, default --voxel-size 0.25), or a medical volume (.nii .nii.gz .hdr .nrrd .nhdr
.mha .mhd) with one of --iso, --label, --labels all.
  -o, --output DIR          output directory (surface.ply, loops.ply, loops.obj, loops.json, view.html)
  --resolution N|auto       voxels along the longest side (default 256); auto: the coarsest grid that keeps
                            a closed input mesh's genus and components (up to 1024 or --max-memory)
  --voxel-size H            voxel size in input units (instead of --resolution)
  --margin M                padding around the object, input units (default: 10% of its longest side)
  --keep-values             .vdb level set: use its values as given, even where they are not the distance
                            to its zero level set (default: such values, e.g. of CSG fields, are recomputed)
  --dmax X                  how deep/far to look for additional loops: percentage of R_in (handles) /
                            R_out (tunnels), e.g. 50%, or a length in input units (default 50%)
  --min-persistence Y       minimum persistence of additional loops, same units (default 10%)
  --side handle|tunnel|both which loops to report (default both)
  --complex grid|tetgen     grid (default): the engine's implicit complex; tetgen: a closed, manifold mesh's
                            TetGen tetrahedralization (the paper's pipeline, a reference): the loops lie
                            on the input's own edges; loops.json ("complex": "tetgen") and chokes.csv
  --tet-spacing H           tetgen: finest spacing of the sample points inside and outside, input units
                            (default: the box's diagonal / 64)
  --tet-grading G           tetgen: sample points graded, cells up to G times their distance to the surface
                            (default 2); 0: a uniform lattice of the spacing
  --tet-quality Q           tetgen: also refine to a radius-edge ratio Q > 1 (TetGen -q; slow with the surface
                            kept, and it may not end on a mesh of thin triangles)
  --tet-max-volume V        tetgen: also refine to tets of volume V at most, input units cubed (TetGen -a)
  --threads N               worker threads (default: all cores); results do not depend on it
  --max-memory BYTES        refuse grids needing more (e.g. 8G; default 80% of RAM)
  --png FILE                also render a picture of the surface and its loops (needs chromium)
  --no-view                 do not write view.html
  --no-shorten              keep the raw membrane loops (no geodesic shortening)
  --no-slide                shorten only; do not slide loops along tubes to the narrowest section
  --no-plane-start          every generator's loop from its membrane, none from the plane section
                            square to its cycle (the same loops within ~0.1%, slower)
  --no-check                skip verifying that generator loops are non-contractible (CGAL; costs
                            seconds on large surfaces of positive genus)
  --no-input-loops          meshes: do not carry the loops onto the input mesh (input_loops.json,
                            input_loops.ply, input_mesh.ply; see chokeloops cut)
  --quiet                   no progress on stderr
  --max-loops N|all         trace loops for the N most persistent chokes only (default 20 for volumes,
                            all otherwise); the rest are counted
Molecules (tunnels.csv, profiles.csv, lining.csv, channels.pdb, view.pml are written too):
  --model N                 model number (default 1)
  --chains A,B              keep only these chains (default all; with --assembly, the file's chains,
                            every copy kept)
  --assembly ID|none        build biological assembly ID from the file's REMARK 350 / _pdbx_struct_assembly
                            (copies of chain C named C1, C2, ...); default none: the coordinates as stored
  --ignore RES,...          residue names to drop (default waters and common ions; "" keeps all)
  --radii bondi|amber       van der Waals radii: Bondi 1964 (default) or HOLE's simple.rad (amber)
  --surface vdw|sas|ses     van der Waals, solvent-accessible or solvent-excluded surface (default vdw)
  --probe R                 probe radius for sas/ses, Å (default 1.4)
  --min-radius R            tunnels with a bottleneck narrower than R Å get the bottleneck and a note, no
                            profile or loop (default 0.9, CAVER's probe; 0 traces all)
  --sections-only           tunnels without a cross-section loop get a note, not a membrane loop (fast)
Volumes (positions in the image's world mm, RAS for NIfTI, the file's space for NRRD, LPS for MetaImage;
distances in mm with the image's own spacing; writes loops.nii.gz / membranes.nii.gz (.nrrd for NRRD, .mha
for MetaImage) on the input's grid too):
  --iso T                   scalar image: inside where the stored value is >= T
  --inside above|below      below: inside where the value is < T
  --label N                 label map: the voxels equal to N (boundary halfway between voxels)
  --labels all              one analysis per non-zero label into OUTDIR/label_N/, index in OUTDIR/labels.json
  --volume K                the K-th volume (from 0) of a 4D image (a MetaImage's channel K too)
  --expect-genus G          list handle generators beyond the G most persistent as topology defects
  --voxel-size MM           resample onto an isotropic lattice of MM along the image's axes (trilinear;
                            default: the image's own spacing, anisotropic allowed)
Exit codes: 0 success, 2 bad input, 3 out of resources, 4 internal error (a bug: please report it).
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

// --complex tetgen: the chokes from TetGen's complex of a closed mesh (analyze_tet.h).
int run_tetgen(const std::string& input, const std::string& outdir, const TetOptions& tet, const ChokeParameters& params, bool grid_flags,
               bool view) {
#ifdef CHOKELOOPS_HAS_TETGEN
  if (grid_flags) throw Error("--resolution applies to the grid complex; --complex tetgen takes --tet-spacing");
  const std::size_t dot = input.rfind('.');
  std::string ext = dot == std::string::npos ? "" : input.substr(dot);
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  const auto& meshes = mesh_extensions();
  if (std::find(meshes.begin(), meshes.end(), ext) == meshes.end())
    throw Error("--complex tetgen takes a mesh (.obj .ply .off .stl): " + input);
  const auto t0 = std::chrono::steady_clock::now();
  const TriangleMesh mesh = read_mesh(input);
  const TetAnalysis a = analyze_tet_complex(mesh, tet, params);
  write_tet_report(a, params, input, outdir);
  if (view) write_view_html(outdir);
  const ChokeSet& c = a.chokes;
  int chokes[2] = {0, 0}, found[2] = {0, 0};
  for (std::size_t i = 0; i < c.chokes.size(); ++i) {
    chokes[c.chokes[i].side == Side::Tunnel] += c.chokes[i].kind == Kind::Choke;
    found[c.chokes[i].side == Side::Tunnel] += a.loops[i].loop.found;
  }
  std::printf("%s: complex tetgen, %lld vertices, %lld tets (%zu input vertices), genus %d, %d component(s)\n", input.c_str(),
              (long long)a.vertices, (long long)a.tets, mesh.vertices.size(), c.handle_generators, c.components);
  std::printf("handle loops: %d generator(s), %d choke(s)   tunnel loops: %d generator(s), %d choke(s)   (traced on the input's edges: %d and %d)\n",
              c.handle_generators, chokes[0], c.tunnel_generators, chokes[1], found[0], found[1]);
  for (std::size_t i = 0; i < c.chokes.size(); ++i) {
    const Choke& k = c.chokes[i];
    const InputLoop& l = a.loops[i];
    std::printf("  %s %s: depth %.5g, persistence %.4g at (%.4g, %.4g, %.4g)", to_string(k.side), to_string(k.kind), k.depth,
                k.persistence, k.point[0], k.point[1], k.point[2]);
    if (l.loop.found) std::printf(", loop length %.5g%s\n", l.loop.length, l.verified ? "" : " (not verified)");
    else std::printf(", no loop: %s\n", l.loop.note.c_str());
  }
  const double total = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  std::printf("time: tetgen %.0f ms, distance %.0f ms, persistence %.0f ms, chokes %.0f ms, loops %.0f ms, total %.0f ms\n",
              a.timings_ms.at("tetgen"), a.timings_ms.at("distance"), a.timings_ms.at("persistence"), a.timings_ms.at("chokes"),
              a.timings_ms.at("loops"), total);
  std::printf("wrote %s/{surface.ply,loops.ply,loops.obj,loops.json,chokes.csv%s}\n", outdir.c_str(), view ? ",view.html" : "");
  return 0;
#else
  (void)input, (void)outdir, (void)tet, (void)params, (void)grid_flags, (void)view;
  throw Error("--complex tetgen: this build leaves TetGen out (CHOKELOOPS_TETGEN=OFF)");
#endif
}

int run(std::vector<std::string> args) {
  AnalyzeOptions options;
  MoleculeOptions molecule;
  std::vector<std::string> molecule_flags, grid_flags;
  std::string input, outdir, png;
  bool quiet = false, view = true;
  int threads = 0;
  cli::VolumeCliOptions vo;
  bool max_loops_given = false;
  bool tetgen = false;
  double tet_spacing = 0, tet_quality = 0, tet_max_volume = 0, tet_grading = -1;
  cli::Args in("analyze", std::move(args));
  while (in.next()) {
    if (in.is("-h", "--help")) { std::cout << kUsage; return 0; }
    else if (in.is("-o", "--output")) outdir = in.value();
    else if (in.is("--model")) molecule.read.model = int(in.integer(1, 1000000)), molecule_flags.push_back("--model");
    else if (in.is("--chains")) molecule.read.chains = cli::split_list(in.value()), molecule_flags.push_back("--chains");
    else if (in.is("--assembly")) molecule.read.assembly = in.value(), molecule_flags.push_back("--assembly");
    else if (in.is("--ignore")) {
      molecule.read.ignore = cli::split_list(in.value());
      molecule.read.ignore_set = true;
      molecule_flags.push_back("--ignore");
    } else if (in.is("--radii")) {
      std::string v = in.value();
      if (v != "bondi" && v != "amber") throw Error("--radii must be bondi or amber (" + in.see_help() + ")");
      molecule.read.radii = v == "amber" ? RadiusSet::Amber : RadiusSet::Bondi;
      molecule_flags.push_back("--radii");
    } else if (in.is("--surface")) {
      std::string v = in.value();
      if (v != "vdw" && v != "sas" && v != "ses") throw Error("--surface must be vdw, sas or ses (" + in.see_help() + ")");
      molecule.field.surface = v == "sas" ? MolecularSurface::Sas : v == "ses" ? MolecularSurface::Ses : MolecularSurface::Vdw;
      molecule_flags.push_back("--surface");
    } else if (in.is("--probe")) {
      molecule.field.probe = in.number();
      if (!(molecule.field.probe > 0)) throw Error("--probe must be positive (" + in.see_help() + ")");
      molecule_flags.push_back("--probe");
    } else if (in.is("--min-radius")) {
      molecule.channels.min_radius = in.number();
      if (!(molecule.channels.min_radius >= 0)) throw Error("--min-radius must be 0 or more (" + in.see_help() + ")");
      molecule_flags.push_back("--min-radius");
    } else if (in.is("--sections-only")) {
      molecule.channels.trace_unsectioned = false;
      molecule_flags.push_back("--sections-only");
    } else if (in.is("--resolution")) {
      grid_flags.push_back("--resolution");
      if (in.peek() == "auto") options.resolution_auto = in.value() == "auto";
      else options.levelset.resolution = int(in.integer(8, 4096));
    } else if (in.is("--voxel-size")) {
      options.levelset.voxel_size = in.number();
      if (!(options.levelset.voxel_size > 0)) throw Error("--voxel-size must be positive");
    } else if (in.is("--margin")) options.levelset.margin = in.number();
    else if (in.is("--keep-values")) options.levelset.keep_values = true;
    else if (in.is("--dmax")) options.chokes.d_max = Threshold::parse(in.value());
    else if (in.is("--min-persistence")) options.chokes.min_persistence = Threshold::parse(in.value());
    else if (in.is("--side")) {
      std::string v = in.value();
      if (v != "handle" && v != "tunnel" && v != "both") throw Error("--side must be handle, tunnel or both");
      options.chokes.handles = v != "tunnel";
      options.chokes.tunnels = v != "handle";
    } else if (in.is("--complex")) {
      const std::string v = in.value();
      if (v != "grid" && v != "tetgen") throw Error("--complex must be grid or tetgen (" + in.see_help() + ")");
      tetgen = v == "tetgen";
    } else if (in.is("--tet-grading")) {
      tet_grading = in.number();
      if (!(tet_grading >= 0) || !std::isfinite(tet_grading)) throw Error("--tet-grading must be 0 or positive (" + in.see_help() + ")");
    } else if (in.is("--tet-spacing")) {
      tet_spacing = in.number();
      if (!(tet_spacing > 0)) throw Error("--tet-spacing must be positive (" + in.see_help() + ")");
    } else if (in.is("--tet-quality")) {
      tet_quality = in.number();
      if (!(tet_quality > 1)) throw Error("--tet-quality must be above 1 (TetGen's radius-edge ratio; " + in.see_help() + ")");
    } else if (in.is("--tet-max-volume")) {
      tet_max_volume = in.number();
      if (!(tet_max_volume > 0)) throw Error("--tet-max-volume must be positive (" + in.see_help() + ")");
    } else if (in.is("--threads")) threads = in.threads();
    else if (in.is("--max-memory")) options.levelset.max_memory = parse_bytes(in.value());
    else if (in.is("--png")) png = in.value();
    else if (in.is("--no-view")) view = false;
    else if (in.is("--no-shorten")) options.loops.shorten = false;
    else if (in.is("--no-slide")) options.loops.slide = false;
    else if (in.is("--no-plane-start")) options.loops.plane_start = false;
    else if (in.is("--no-check")) options.check_generators = false;
    else if (in.is("--no-input-loops")) options.input_loops = false;
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
  if (tetgen) {
    TetOptions tet;
    tet.spacing = tet_spacing;
    if (tet_grading >= 0) tet.grading = tet_grading;
    tet.max_memory = options.levelset.max_memory;
    tet.radius_edge = tet_quality;
    tet.max_volume = tet_max_volume;
    return run_tetgen(input, outdir, tet, options.chokes, !grid_flags.empty() || options.resolution_auto, view);
  }
  if (tet_spacing > 0 || tet_quality > 0 || tet_max_volume > 0 || tet_grading >= 0)
    throw Error("--tet-spacing, --tet-grading, --tet-quality and --tet-max-volume apply to --complex tetgen only");
  if (is_molecule_path(input)) {
    if (!grid_flags.empty() || options.resolution_auto)
      throw Error("--resolution does not apply to molecules; use --voxel-size in Å (" + std::string("see chokeloops analyze --help") + ")");
    keep_freed_memory();
    MoleculeAnalysis m = analyze_molecule(input, options, molecule, std::ref(progress));
    auto t = std::chrono::steady_clock::now();
    write_report(m.result, options, outdir);
    write_molecule_report(m, molecule, outdir);
    if (view) write_view_html(outdir);
    if (!png.empty()) render_png(outdir, png);
    double report_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
    for (auto& w : m.result.warnings) std::cerr << "chokeloops analyze: warning: " << w << "\n";
    AnalyzeResult& r = m.result;
    int counts[2][2] = {{0, 0}, {0, 0}};
    for (auto& l : r.loops) counts[l.choke.side == Side::Tunnel][l.choke.kind == Kind::Choke] += 1;
    std::printf("%s: %zu atoms, %s surface, grid %dx%dx%d (voxel %.4g A), surface %lld vertices, genus %d, %d component(s)\n",
                input.c_str(), m.molecule.atoms.size(), to_string(molecule.field.surface), r.grid.dims[0], r.grid.dims[1],
                r.grid.dims[2], r.grid.voxel_size, (long long)r.surface_stats.vertices, r.surface_stats.genus,
                r.surface_stats.components);
    std::printf("handle loops: %d generator(s), %d choke(s)   tunnel loops: %d generator(s), %d choke(s)\n", counts[0][0],
                counts[0][1], counts[1][0], counts[1][1]);
    // the widest tunnels first: what a HOLE user looks for
    std::vector<const Channel*> order;
    for (auto& c : m.channels) order.push_back(&c);
    std::stable_sort(order.begin(), order.end(), [&](const Channel* a, const Channel* b) {
      return r.loops[std::size_t(a->loop)].choke.persistence > r.loops[std::size_t(b->loop)].choke.persistence;
    });
    for (std::size_t i = 0; i < order.size() && i < 5; ++i) {
      const Channel& c = *order[i];
      const Loop& l = r.loops[std::size_t(c.loop)];
      std::printf("  tunnel %d (%s, persistence %.3g): bottleneck %.3f A at (%.2f, %.2f, %.2f), path %.1f A, %d open end(s), loop %.2f A\n",
                  c.loop, to_string(l.choke.kind), l.choke.persistence, c.bottleneck_radius, c.bottleneck[0],
                  c.bottleneck[1], c.bottleneck[2], c.length, int(c.open[0]) + int(c.open[1]), l.found ? l.length : 0.0);
    }
    std::printf("time: read %.0f ms, field %.0f ms, persistence %.0f ms, surface %.0f ms, loops %.0f ms, channels %.0f ms, report %.0f ms, total %.0f ms\n",
                r.timings_ms["read"], r.timings_ms["levelset"], r.timings_ms["persistence"], r.timings_ms["surface"],
                r.timings_ms["loops"], r.timings_ms["channels"], report_ms, r.timings_ms["total"] + report_ms);
    std::printf("wrote %s/{surface.ply,loops.*,tunnels.csv,profiles.csv,lining.csv,channels.pdb,view.pml%s}\n", outdir.c_str(),
                view ? ",view.html" : "");
    return 0;
  }
  if (!molecule_flags.empty())
    throw Error(molecule_flags.front() + " applies to molecules only (.pdb/.cif input; see chokeloops analyze --help)");
  const bool volume_input = is_volume_path(input);
  const bool volume_options = vo.field.has_iso || vo.field.has_label || vo.all_labels || vo.volume >= 0 ||
                              vo.expect_genus >= 0 || vo.field.inside_below;
  if (volume_input) {
    if (vo.all_labels && (vo.field.has_label || vo.field.has_iso))
      throw Error("--labels all analyses every label: give it without --label / --iso");
    if (!vo.all_labels && vo.field.has_label == vo.field.has_iso)
      throw Error("a volume needs exactly one of --iso T (scalar image), --label N or --labels all (label map)");
    if (!grid_flags.empty() || options.resolution_auto)
      throw Error("--resolution: a volume is analysed on its own voxel grid; --voxel-size MM resamples it");
    vo.field.voxel_size = options.levelset.voxel_size;
    if (!max_loops_given) options.max_loops = 20;
    vo.field.margin = options.levelset.margin;
    vo.view = view;
    return cli::run_volume(input, outdir, options, vo, std::ref(progress));
  }
  if (volume_options)
    throw Error("--iso, --inside, --label, --labels, --volume and --expect-genus apply to volumes (.nii, .nii.gz, .nrrd, .nhdr, .mha, .mhd) only");
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
  if (r.has_input_loops) {
    int carried = 0;
    for (auto& l : r.input_loops) carried += l.loop.found;
    std::printf("input mesh: %d of %zu loop(s) carried and checked (%.0f ms)\n", carried, r.input_loops.size(),
                r.timings_ms["input_loops"]);
  }
  std::printf("wrote %s/{surface.ply,loops.ply,loops.obj,loops.json%s%s}%s%s\n", outdir.c_str(),
              r.has_input_loops ? ",input_loops.json,input_loops.ply,input_mesh.ply" : "", view ? ",view.html" : "",
              png.empty() ? "" : " and ", png.c_str());
  return 0;
}

chokeloops::cli::Register reg("analyze", "find the handle and tunnel choking loops of a mesh or level set", run);

}  // namespace

// `chokeloops filter INPUT -o OUTPUT`: removes small handles and tunnels (filter_file.h); a thin layer.
#include <cstdio>
#include <fstream>
#include <iostream>

#include "chokeloops/filter/filter_file.h"
#include "args.h"
#include "command.h"

using namespace chokeloops;

namespace {

const char* kUsage = R"(usage: chokeloops filter INPUT -o OUTPUT [options]

Removes handle/tunnel pairs of the genus: a handle is cut (its membrane's voxels leave the solid), a tunnel
filled (they join it). Values away from the edits stay bit-identical; the output is read back and its genus,
components and cavities checked.
INPUT and OUTPUT: a .vdb level set -> .vdb; a mesh (.obj .ply .off .stl) -> the filtered surface as .ply (the
marching surface of the grid: every triangle is new, not only those near the edits); a volume (.nii .nii.gz
.nrrd .mha .mhd, with --iso or --label) -> the same format, header and datatype, only the edited voxels changed
(a MetaImage as .mha, or as .mhd with its .raw/.zraw beside it, whichever OUTPUT names).
Selection (at least one):
  --max-depth D             edits whose depth is at most D: percentage of R_in (cuts) / R_out (fills), e.g. 5%,
                            or a length in input units
  --max-persistence P       pairs whose persistence (death - birth) is at most P: % of R_in + R_out, or a length
  --keep-genus G            keep the G most persistent pairs, remove the others
  --mode auto|cut|fill      auto (default): per pair the edit that changes fewer voxels
  --report FILE.json        every edit (kind, side, location, depth, persistence, voxels, volume), genus and
                            components before and after, the Hausdorff distance between the two surfaces
Input: --resolution N, --voxel-size H, --margin M, --keep-values, --max-memory BYTES (as for analyze);
  --iso T, --inside above|below, --label N, --volume K (volumes); --threads N; --quiet
Exit codes: 0 success, 2 bad input or impossible request, 3 out of resources, 4 internal error (a bug).
)";

int run(std::vector<std::string> args) {
  cli::Args in("filter", std::move(args));
  FilterFileOptions o;
  std::string input, output, report;
  int threads = 0;
  bool quiet = false, grid_given = false;
  while (in.next()) {
    if (in.is("-h", "--help")) {
      std::fputs(kUsage, stdout);
      return 0;
    } else if (in.is("-o", "--output")) output = in.value();
    else if (in.is("--max-depth")) o.filter.has_max_depth = true, o.filter.max_depth = Threshold::parse(in.value());
    else if (in.is("--max-persistence")) o.filter.has_max_persistence = true, o.filter.max_persistence = Threshold::parse(in.value());
    else if (in.is("--keep-genus")) o.filter.keep_genus = int(in.integer(0, 1 << 30));
    else if (in.is("--mode")) {
      const std::string m = in.value();
      if (m == "auto") o.filter.mode = FilterMode::Auto;
      else if (m == "cut") o.filter.mode = FilterMode::Cut;
      else if (m == "fill") o.filter.mode = FilterMode::Fill;
      else throw Error("--mode must be auto, cut or fill (" + in.see_help() + ")");
    } else if (in.is("--report")) report = in.value();
    else if (in.is("--resolution")) o.levelset.resolution = int(in.integer(8, 4096)), grid_given = true;
    else if (in.is("--voxel-size")) {
      grid_given = true;
      o.levelset.voxel_size = in.number();
      if (!(o.levelset.voxel_size > 0)) throw Error("--voxel-size must be positive");
    } else if (in.is("--margin")) o.levelset.margin = o.field.margin = in.number();
    else if (in.is("--keep-values")) o.levelset.keep_values = true;
    else if (in.is("--max-memory")) o.levelset.max_memory = parse_bytes(in.value());
    else if (in.is("--iso")) o.field.has_iso = true, o.field.iso = in.number();
    else if (in.is("--inside")) {
      const std::string v = in.value();
      if (v != "above" && v != "below") throw Error("--inside must be above or below (" + in.see_help() + ")");
      o.field.inside_below = v == "below";
    } else if (in.is("--label")) o.field.has_label = true, o.field.label = in.number();
    else if (in.is("--volume")) o.volume = int(in.integer(0, 1 << 20));
    else if (in.is("--threads")) threads = in.threads();
    else if (in.is("--quiet")) quiet = true;
    else in.positional(input, "input");
  }
  if (input.empty()) throw Error("no input given (usage: chokeloops filter INPUT -o OUTPUT)");
  if (output.empty()) throw Error("no output given (-o OUTPUT)");
  if (is_volume_path(input) && o.field.has_iso == o.field.has_label)
    throw Error("a volume needs exactly one of --iso T or --label N (" + in.see_help() + ")");
  if (is_volume_path(input) && grid_given)
    throw Error("--resolution / --voxel-size: a volume is filtered on its own voxels (the output keeps its grid)");
  auto limit = cli::limit_threads(threads);
  const FilterFileResult r = filter_file(input, output, o);
  if (!report.empty()) {
    std::ofstream out(report);
    out << filter_report_json(r) << "\n";
    if (!out) throw Error("cannot write " + report, 3);
  }
  const FilterReport& f = r.report;
  if (!quiet) {
    int cuts = 0, fills = 0;
    for (const FilterEdit& e : f.edits) (e.side == Side::Handle ? cuts : fills) += 1;
    std::printf("%s: genus %d -> %d, components %d -> %d, cavities %d -> %d\n", input.c_str(), f.before.genus, f.after.genus,
                f.before.components, f.after.components, f.before.cavities, f.after.cavities);
    std::printf("pairs selected %d, removed %d: %d cut(s), %d fill(s) in %d round(s); %zu voxels changed (%.4f%%), largest edit depth %.4g, Hausdorff %.4g\n",
                f.selected, f.before.genus - f.after.genus, cuts, fills, f.rounds, f.voxels_changed,
                r.grid_vertices ? 100.0 * double(f.voxels_changed) / double(r.grid_vertices) : 0.0, f.max_edit_depth, r.hausdorff);
    for (const auto& n : f.notes) std::printf("note: %s\n", n.c_str());
    std::printf("time: %.0f ms; wrote %s%s\n", f.timings_ms.count("total") ? f.timings_ms.at("total") : 0.0, output.c_str(),
                report.empty() ? "" : (" and " + report).c_str());
  }
  if (f.selected == 0) std::fprintf(stderr, "chokeloops filter: nothing selected: no pair meets the criteria (the output is the input's field)\n");
  return 0;
}

cli::Register reg("filter", "remove small handles and tunnels by cutting or filling along their membranes", run);

}  // namespace

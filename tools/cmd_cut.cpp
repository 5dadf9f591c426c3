// `chokeloops cut INPUT OUTDIR -o OUTPUT`: cuts the input mesh along its loops and caps the cuts (cut_mesh.h);
// a thin layer.
#include <cstdio>

#include "chokeloops/grid.h"
#include "chokeloops/loops/cut_mesh.h"
#include "args.h"
#include "command.h"

using namespace chokeloops;

namespace {

const char* kUsage = R"(usage: chokeloops cut INPUT OUTDIR -o OUTPUT [--ids 1,4 | --side handle|tunnel]

Cuts the mesh INPUT along loops that `chokeloops analyze INPUT -o OUTDIR` carried onto it (OUTDIR/input_loops.json)
and closes each cut with a cap (CGAL's hole filling): a cut along a generator lowers the genus by one. The
input's triangles are written unchanged and in their order (corners on a cut refer to new copies of their
vertices), the caps after them. The cut follows each loop's edge_path (the input's edges next to the loop).
  -o, --output FILE   the cut mesh (.off .ply .obj .stl)
  --ids LIST          the loops to cut, by id (comma-separated)
  --side S            otherwise: every generator of side S carried onto the input (default handle)
  --quiet             no summary on stdout
Exit codes: 0 success, 2 bad input or impossible request, 3 out of resources, 4 internal error (a bug).
)";

std::vector<int> parse_ids(const std::string& text) {
  std::vector<int> ids;
  for (const std::string& item : cli::split_list(text)) {
    std::size_t used = 0;
    long v = -1;
    try {
      v = std::stol(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != item.size() || v < 0 || v > (1L << 30)) throw Error("--ids: '" + item + "' is not a loop id");
    ids.push_back(int(v));
  }
  if (ids.empty()) throw Error("--ids needs at least one loop id");
  return ids;
}

int run(std::vector<std::string> args) {
  cli::Args in("cut", std::move(args));
  std::string input, outdir, output;
  CutSelection selection;
  bool side_given = false, quiet = false;
  while (in.next()) {
    if (in.is("-h", "--help")) {
      std::fputs(kUsage, stdout);
      return 0;
    } else if (in.is("-o", "--output")) output = in.value();
    else if (in.is("--ids")) selection.ids = parse_ids(in.value());
    else if (in.is("--side")) {
      const std::string s = in.value();
      if (s != "handle" && s != "tunnel") throw Error("--side must be handle or tunnel (" + in.see_help() + ")");
      selection.handles = s == "handle";
      side_given = true;
    } else if (in.is("--quiet")) quiet = true;
    else if (input.empty()) in.positional(input, "input");
    else in.positional(outdir, "output directory");
  }
  if (input.empty() || outdir.empty()) throw Error("usage: chokeloops cut INPUT OUTDIR -o OUTPUT (" + in.see_help() + ")");
  if (output.empty()) throw Error("no output given (-o OUTPUT)");
  if (side_given && !selection.ids.empty()) throw Error("give --ids or --side, not both");
  std::vector<int> ids;
  const CutResult r = cut_mesh_file(input, outdir, output, selection, &ids);
  if (!quiet) {
    std::string list;
    for (int id : ids) list += (list.empty() ? "" : ",") + std::to_string(id);
    std::printf("%s: cut along loop(s) %s, %d cap(s) of %d triangles; genus %d -> %d, components %zu -> %zu, Euler %d -> %d\n",
                input.c_str(), list.c_str(), r.caps, r.cap_faces, r.before.genus, r.after.genus, r.before.components,
                r.after.components, r.before.euler, r.after.euler);
    for (const auto& n : r.notes) std::printf("note: %s\n", n.c_str());
    std::printf("wrote %s\n", output.c_str());
  }
  return 0;
}

cli::Register reg("cut", "cut a mesh along its loops (from analyze's input_loops.json) and cap the cuts", run);

}  // namespace

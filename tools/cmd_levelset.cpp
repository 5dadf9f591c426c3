// `chokeloops levelset INPUT -o OUT.vdb`: mesh or .vdb → signed distance grid (stage levelset).
#include <chrono>
#include <iomanip>
#include <iostream>
#include <sstream>

#include "chokeloops/grid.h"
#include "chokeloops/field/levelset.h"
#include "chokeloops/io/vdb_io.h"
#include "args.h"
#include "command.h"

namespace {

const char* kUsage =
    "usage: chokeloops levelset INPUT -o OUT.vdb [options]\n"
    "\n"
    "Makes the signed distance grid (negative inside) the analysis uses, over a box padded around the\n"
    "object, and writes it as an OpenVDB level set (every box vertex stored as an active voxel).\n"
    "INPUT: a mesh (.obj .ply .off .stl; repaired with CGAL, polygons triangulated) or a .vdb file\n"
    "(first float grid: a level set is kept if it is a true distance, else renormalised; a fog/density\n"
    "grid becomes the signed distance to {density = --iso}).\n"
    "\n"
    "options:\n"
    "  -o, --output FILE     output .vdb (required)\n"
    "  --resolution N        voxels along the longest side of the object (default 256)\n"
    "  --voxel-size H        voxel size in input units (overrides --resolution)\n"
    "  --margin M            padding around the object in input units\n"
    "                        (default: max(10% of the longest side, 4 voxels))\n"
    "  --iso V               iso value for fog/density .vdb input (default 0.5)\n"
    "  --grid NAME           which grid of a .vdb input (default: the first float grid)\n"
    "  --keep-values         .vdb level set: keep its values even where they are not its distance (CSG)\n"
    "  --max-memory BYTES    refuse grids needing more (e.g. 8G, 512M; default 80% of physical memory)\n"
    "  --no-fill-holes       do not close holes of open meshes (sign then from the winding number)\n"
    "  -q, --quiet           print only warnings and errors\n"
    "  -h, --help            this help\n"
    "\n"
    "exit codes: 0 ok, 2 bad input or arguments, 3 not enough memory (the message names a --resolution that fits)\n";

int run(std::vector<std::string> args) {
  using namespace chokeloops;
  LevelSetOptions o;
  std::string input, output;
  bool quiet = false;
  cli::Args in("levelset", std::move(args));
  while (in.next()) {
    if (in.is("-h", "--help")) {
      std::cout << kUsage;
      return 0;
    } else if (in.is("-o", "--output")) {
      output = in.value();
    } else if (in.is("--resolution")) {
      o.resolution = int(in.integer(2, 100000));
    } else if (in.is("--voxel-size")) {
      o.voxel_size = in.number();
      if (!(o.voxel_size > 0)) throw Error("--voxel-size must be positive");
    } else if (in.is("--margin")) {
      o.margin = in.number();
      if (o.margin < 0) throw Error("--margin must be >= 0");
    } else if (in.is("--iso")) {
      o.iso = in.number();
    } else if (in.is("--grid")) {
      o.grid_name = in.value();
    } else if (in.is("--keep-values")) {
      o.keep_values = true;
    } else if (in.is("--max-memory")) {
      o.max_memory = parse_bytes(in.value());
    } else if (in.is("--no-fill-holes")) {
      o.fill_holes = false;
    } else if (in.is("-q", "--quiet")) {
      quiet = true;
    } else {
      in.positional(input, "input file");
    }
  }
  if (input.empty()) throw Error("no INPUT given\n" + std::string(kUsage).substr(0, std::string(kUsage).find('\n')));
  if (output.empty()) throw Error("no output given: use -o OUT.vdb");

  LevelSetResult r = make_levelset(input, o);
  const auto t0 = std::chrono::steady_clock::now();
  write_vdb(r.grid, output, "sdf", true);
  const double wsec = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (!quiet) {
    const auto& g = r.grid;
    std::ostringstream s;
    s << std::setprecision(6);
    s << "input:        " << input << " (" << r.source << ")\n";
    if (r.source == "mesh") {
      const auto& m = r.report;
      s << "mesh:         " << m.input_vertices << " vertices, " << m.input_faces << " triangles in; " << m.vertices
        << " vertices, " << m.faces << " triangles after repair\n";
      s << "topology:     " << (m.closed ? "closed" : "open") << ", " << m.boundary_edges << " boundary edges";
      if (!m.closed) s << " (" << m.holes << " holes, " << m.holes_filled << " filled)";
      s << ", " << m.nonmanifold_edges << " non-manifold edges, " << m.components << " component"
        << (m.components == 1 ? "" : "s");
      if (m.genus >= 0) s << ", genus " << m.genus;
      s << "\n";
    }
    s << "grid:         " << g.dims[0] << " x " << g.dims[1] << " x " << g.dims[2] << " vertices ("
      << g.vertex_count() << ")\n";
    s << "voxel size:   " << g.voxel_size << "  (margin " << r.margin << ")\n";
    s << "origin:       " << g.origin[0] << " " << g.origin[1] << " " << g.origin[2] << "\n";
    s << "inside:       " << r.inside_voxels << " vertices (phi < 0)\n";
    s << "outside:      " << r.outside_voxels << " vertices (phi >= 0)\n";
    s << std::fixed << std::setprecision(3);
    s << "time:         " << r.seconds << " s (levelset) + " << wsec << " s (write)\n";
    s << "output:       " << output << "\n";
    std::cout << s.str();
  }
  return 0;
}

chokeloops::cli::Register reg("levelset", "mesh or .vdb -> signed distance grid (.vdb)", run);

}  // namespace

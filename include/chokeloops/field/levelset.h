#pragma once
// Stage `levelset` (DESIGN.md §4): meshes and .vdb files become signed distance grids (negative inside),
// both as an openvdb::FloatGrid and as the dense chokeloops::ScalarGrid over a padded box.
#include <cstddef>
#include <string>
#include <vector>

#include <openvdb/openvdb.h>

#include "chokeloops/field/memory_budget.h"
#include "chokeloops/grid.h"
#include "chokeloops/io/mesh_io.h"

namespace chokeloops {

struct LevelSetOptions {
  int resolution = 256;         // voxels along the longest side of the object (used when voxel_size <= 0)
  double voxel_size = 0;        // > 0: voxel size in input units (overrides resolution)
  double margin = -1;           // padding of the box around the object, input units; < 0: default_margin()
  double iso = 0.5;             // fog/density .vdb input: the surface is {density = iso}, inside = denser
  std::size_t max_memory = 0;   // bytes; 0: 80% of physical memory (default_max_memory())
  bool quiet = false;           // library: do not print warnings to stderr (they are in the result anyway)
  std::string grid_name;        // .vdb input: which grid ("" = first float grid)
  bool fill_holes = true;       // close holes of open meshes with CGAL (triangulate_hole) before taking the sign
  bool keep_values = false;     // .vdb level set: use its values as given, even where they are not the distance
                                // to its zero level set (by default such values are recomputed: CSG fields)
  bool keep_vdb = false;        // also build result.vdb (FloatGrid of the whole box; same as grid_from_dense(grid))
  bool stage_memory = false;    // record each stage's peak RSS (resets the process's VmHWM: benchmarks only)
};

// Wall time and (when LevelSetOptions::stage_memory) peak resident memory of one sub-stage.
struct LevelSetStage {
  std::string name;            // "read", "repair", "band", "sign", "far field", ...
  double seconds = 0;
  double cpu_seconds = 0;      // user + system over all threads (comparable on a loaded machine)
  std::size_t peak_rss = 0;    // bytes, process peak during this stage; 0 when not measured
};

struct LevelSetResult {
  ScalarGrid grid;                      // dense signed distance over the padded box, negative inside
  openvdb::FloatGrid::Ptr vdb;          // the same field as an OpenVDB level set (when keep_vdb)
  MeshReport report;                    // mesh input only
  std::vector<std::string> warnings;    // one line each
  std::string source;                   // "mesh", "vdb level set", "vdb level set (renormalised)", "vdb fog"
  std::size_t inside_voxels = 0;        // vertices with phi < 0
  std::size_t outside_voxels = 0;       // vertices with phi >= 0
  double margin = 0;                    // padding used, input units
  double max_distance_error_voxels = -1;  // .vdb level set: largest |value - exact distance| found (-1: not checked)
  double seconds = 0;                   // wall time of make_levelset
  std::vector<LevelSetStage> stages;    // in order; CHOKELOOPS_LEVELSET_TIMING=1 also prints them
};

// Dispatches on the extension: .vdb → levelset_from_vdb, .obj/.ply/.off/.stl → read_mesh + mesh_to_levelset.
// Throws Error (exit 2 bad input, exit 3 not enough memory: the message names a --resolution that fits).
LevelSetResult make_levelset(const std::string& input_path, const LevelSetOptions& options = {});

// Repairs the mesh (repair_mesh) and converts it: OpenVDB mesh-to-volume gives an exact band of closest
// points (and the sign, or the winding number where holes remain); an exact feature transform from those
// closest points gives every other vertex of the padded box its distance.
LevelSetResult mesh_to_levelset(const TriangleMesh& mesh, const LevelSetOptions& options = {},
                                const std::string& name = "mesh");

// A FloatGrid from a .vdb: a level set is used as is when its values are the distance to its own zero
// level set over the whole box (within a voxel of the exact distance; LevelSetOptions::keep_values skips the
// check), otherwise redistanced from its zero crossings: min/max (CSG) fields are exact only near the surface; a fog volume becomes a signed distance at options.iso (fogToSdf).
// What the input does not cover of the padded box gets the exact feature transform's distance to the
// zero crossings.
LevelSetResult levelset_from_vdb(openvdb::FloatGrid::ConstPtr grid, const LevelSetOptions& options = {},
                                 const std::string& name = "grid");

// Replaces every value by the signed distance to the zero level set the grid's signs define (the crossings
// along grid edges, refined by a Newton step), exact to those points far from the surface. Vertices with
// known[v] != 0 keep their values (empty: none do).
void redistance_from_signs(ScalarGrid& grid, const std::vector<std::uint8_t>& known = {});

// Default padding: max(10% of the longest side of the object, 4 voxels). Enough for the outside to
// stay connected around the object and for tunnel/pocket mouths at the bbox to close inside the box.
double default_margin(double longest_side, double voxel_size);

// Memory model used by the guard: bytes needed to build a dense grid of `box_voxels` vertices.
std::size_t estimate_levelset_bytes(std::size_t box_voxels);

}  // namespace chokeloops

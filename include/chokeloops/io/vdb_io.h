#pragma once
// OpenVDB file IO and conversions between openvdb::FloatGrid and the project's dense ScalarGrid.
//
// Conventions: a ScalarGrid vertex (i,j,k) is the OpenVDB voxel (i,j,k) + index offset of the grid's
// active bounding box, i.e. ScalarGrid::origin is the world position of that box's minimum voxel centre.
// Only axis-aligned uniform-scale transforms (scale + translation) can be densified.
#include <memory>
#include <string>
#include <vector>

#include <openvdb/openvdb.h>

#include "chokeloops/grid.h"

namespace chokeloops {

// Calls openvdb::initialize() exactly once (thread-safe). Every function below calls it itself.
void ensure_openvdb_initialized();

// Reads the first FloatGrid of a .vdb file (or the grid named `grid_name`), densified over its
// active-voxel bounding box. Inactive voxels inside that box carry the value the grid's accessor
// returns (for a level set: +/- background with the correct sign). Voxel size from the transform
// (uniform scale, no rotation, else Error); origin = world position of the bounding box minimum.
// Throws Error (exit code 2) with a one-line message naming the file for: missing file, not a VDB,
// no float grid (lists the grids it has), empty grid, non-uniform transform, non-finite values;
// Error with exit code 3 when the dense box cannot fit in memory.
ScalarGrid read_vdb_dense(const std::string& path, const std::string& grid_name = "");

// Writes `grid` to a .vdb file as a FloatGrid named `grid_name`, every vertex stored as an active
// voxel (so read_vdb_dense gives back exactly the same dims/origin/values). With level_set = true
// the grid class is GRID_LEVEL_SET and the background is larger than every |value|.
// Throws Error for an invalid grid (exit 2) or when the file cannot be written (exit 2).
void write_vdb(const ScalarGrid& grid, const std::string& path, const std::string& grid_name = "sdf",
               bool level_set = true);

// Lower-level pieces (also used by the levelset stage).

// Name and value type of every grid stored in a .vdb file (throws Error like read_vdb_dense).
struct VdbGridInfo {
  std::string name;
  std::string type;        // e.g. "float", "double", "vec3s", "bool"
  std::string grid_class;  // "level set", "fog volume", "unknown", ...
};
std::vector<VdbGridInfo> list_vdb_grids(const std::string& path);

// Reads the FloatGrid (first one, or the one named) from a .vdb file, with the same checks and
// messages as read_vdb_dense (except the dense-size and finiteness checks).
openvdb::FloatGrid::Ptr read_vdb_float_grid(const std::string& path, const std::string& grid_name = "");

// Densifies `grid` over the index box `bbox` (inclusive), using the value accessor, in parallel.
// The transform must be axis-aligned uniform scale + translation (else Error naming `what`).
ScalarGrid dense_from_grid(const openvdb::FloatGrid& grid, const openvdb::CoordBBox& bbox,
                           const std::string& what = "grid");

// Builds a FloatGrid holding every vertex of `grid` as an active voxel with index (i,j,k) at
// world position origin + voxel_size*(i,j,k). Background is `background` when > 0, otherwise
// max|value| + voxel_size. Grid class level set when level_set.
openvdb::FloatGrid::Ptr grid_from_dense(const ScalarGrid& grid, bool level_set = true, float background = 0.f);

}  // namespace chokeloops

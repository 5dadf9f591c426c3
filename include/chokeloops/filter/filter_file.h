#pragma once
// `chokeloops filter` on a file: input -> signed distance -> filter_grid -> output in the input's kind
// (a .vdb level set, a mesh of the filtered surface, or the input volume with only the edited voxels
// changed), then the output is read back and its topology checked against the report.
#include <string>

#include "chokeloops/field/levelset.h"
#include "chokeloops/field/volume_field.h"
#include "chokeloops/filter/filter.h"

namespace chokeloops {

struct FilterFileOptions {
  FilterOptions filter;
  LevelSetOptions levelset;   // meshes and .vdb
  VolumeFieldOptions field;   // volumes: --iso / --label
  int volume = -1;            // 4D volumes: which one
};

struct FilterFileResult {
  FilterReport report;
  std::string input, output, kind;  // kind: "vdb", "mesh", "volume"
  double voxel_size = 0;
  std::size_t grid_vertices = 0;
  double hausdorff = 0;            // between the surfaces before and after (voxel-accurate)
  FilterSummary output_check;      // topology of the output as read back
};

// Throws Error (2 bad input or impossible request, 3 resources), InternalError when the output read back
// does not have the topology the report claims.
FilterFileResult filter_file(const std::string& input, const std::string& output, const FilterFileOptions& options,
                             const ProgressFn& progress = {});

// The report as JSON (what --report writes).
std::string filter_report_json(const FilterFileResult& result);

}  // namespace chokeloops

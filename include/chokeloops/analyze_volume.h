#pragma once
// `analyze` for medical volumes (DESIGN §6 "Volumes"): image -> signed distance on its own lattice ->
// the usual stages -> the usual report with positions in the image's world mm, plus label volumes on
// the image's grid (loops, membranes).
#include <string>
#include <vector>

#include "chokeloops/analyze.h"
#include "chokeloops/field/volume_field.h"
#include "chokeloops/io/volume_io.h"

namespace chokeloops {

struct VolumeAnalysis {
  AnalyzeResult result;           // positions in the grid frame; result.frame maps them to world
  std::array<int, 3> pad{0, 0, 0};
  std::string what;               // "iso 128", "label 3"
};

// One analysis of one mask of the image. Throws Error (2 bad input, 3 resources).
VolumeAnalysis analyze_volume(const VolumeImage& image, const VolumeFieldOptions& field, const AnalyzeOptions& options,
                              const ProgressFn& progress = {});

// The distinct non-zero labels of a label map, ascending. Throws Error when the image is not integer-valued.
std::vector<long long> image_labels(const VolumeImage& image);

// Handle generators past the `expected_genus` most persistent (death - birth) ones: the loop indices of
// topology defects (handles a segmentation should not have). Traced loops only.
std::vector<int> topology_defects(const AnalyzeResult& r, int expected_genus);

// loops.nii.gz / loops.nrrd (each loop's voxels carry its id + 1) and membranes.* (the voxels whose flip
// removes the loop's handle or tunnel, loops/membrane_voxels.h, carry its id + 1) on the input's grid and
// header, into outdir.
struct LoopVolumes {
  std::vector<std::string> files;          // names within outdir: loops, membranes
  std::vector<std::string> warnings;       // traced loops whose membrane did not close, and why
};
// `progress`: as trace_loops's, with ("label volumes", the fraction of the loops whose membrane is done) on
// the calling thread; returning false stops before the files are written (Error "interrupted").
LoopVolumes write_loop_volumes(const VolumeAnalysis& a, const VolumeImage& image, const std::string& outdir,
                               const ProgressFn& progress = {});

}  // namespace chokeloops

#pragma once
// `chokeloops analyze` on a medical volume (.nii, .nii.gz, .nrrd, .nhdr, .mha, .mhd): see cmd_analyze_volume.cpp.
#include <functional>
#include <string>

#include "chokeloops/analyze_volume.h"

namespace chokeloops::cli {

struct VolumeCliOptions {
  VolumeFieldOptions field;
  bool all_labels = false;
  int volume = -1;
  int expect_genus = -1;
  bool view = true;
  bool quiet = false;
};

int run_volume(const std::string& input, const std::string& outdir, const AnalyzeOptions& options,
               const VolumeCliOptions& vo, const ProgressFn& progress);

}  // namespace chokeloops::cli

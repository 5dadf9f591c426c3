#pragma once
// The whole job for a molecule (DESIGN §6): atoms → molecular distance field → the engine's stages →
// exact bottlenecks, profiles and lining of the tunnels. `chokeloops analyze FILE.pdb` is a thin layer over it.
#include <string>
#include <vector>

#include "chokeloops/analyze.h"
#include "chokeloops/field/molecular_field.h"
#include "chokeloops/io/molecule_io.h"
#include "chokeloops/loops/channels.h"

namespace chokeloops {

struct MoleculeOptions {
  MoleculeReadOptions read;
  MolecularFieldOptions field;
  ChannelOptions channels;
};

struct MoleculeAnalysis {
  AnalyzeResult result;           // grid, chokes, surface and loops as for any input (lengths in Å)
  Molecule molecule;
  std::vector<Channel> channels;  // one per tunnel loop
};

// Throws Error (2 bad input, 3 resources). analyze.levelset's voxel size, margin and max memory override
// options.field's when set.
MoleculeAnalysis analyze_molecule(const std::string& path, const AnalyzeOptions& analyze, const MoleculeOptions& options,
                                  const ProgressFn& progress = {});

// tunnels.csv, profiles.csv, lining.csv, channels.pdb (path spheres, radius in the B-factor column, as
// HOLE's .sph files) and view.pml (PyMOL: structure, loops, paths) in outdir, and a "molecule" section with
// each tunnel loop's channel added to loops.json (written by write_report first).
void write_molecule_report(const MoleculeAnalysis& m, const MoleculeOptions& options, const std::string& outdir);

}  // namespace chokeloops

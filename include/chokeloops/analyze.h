#pragma once
// The whole job: input → level set → persistence → chokes → surface → loops → report (DESIGN §4).
// The library entry points know nothing of the command line; `chokeloops analyze` is a thin layer over them.
#include <map>
#include <string>
#include <vector>

#include "chokeloops/topology/chokes.h"
#include "chokeloops/field/levelset.h"
#include "chokeloops/field/volume_field.h"
#include "chokeloops/loops/input_loops.h"
#include "chokeloops/loops/membrane_voxels.h"
#include "chokeloops/loops/membranes.h"
#include "chokeloops/topology/persistence.h"
#include "chokeloops/surface/surface.h"

namespace chokeloops {

struct AnalyzeOptions {
  LevelSetOptions levelset;
  bool resolution_auto = false;  // find the coarsest resolution whose surface keeps a closed input's genus
  ChokeParameters chokes;
  LoopOptions loops;
  bool check_generators = true;  // verify each generator loop is non-contractible (CGAL); drop it if not
  // Loops are traced for at most this many chokes (-1: all). Past it, the chokes are ranked by their
  // pair's persistence (death - birth, most persistent first) and the rest are counted, not traced.
  int max_loops = -1;
  // Mesh inputs: every loop also carried onto the input mesh and checked there (input_loops.h), written as
  // input_loops.json and input_loops.ply.
  bool input_loops = true;
  // Keep where the loop stage's floods leave each choke's membrane (AnalyzeResult::membranes), for the label
  // volumes of a volume input.
  bool record_membranes = false;
};

struct AnalyzeResult {
  std::string input;
  ScalarGrid grid;
  LevelSetResult levelset_info;  // its grid moved to `grid`
  PersistenceDiagram diagram;
  ChokeSet chokes;
  SurfaceMesh surface;
  SurfaceStats surface_stats;
  std::vector<Loop> loops;
  std::vector<MembraneProgress> membranes;  // one per loop with AnalyzeOptions::record_membranes, else empty
  int input_genus = -1;                   // genus of a closed input mesh, -1 when unknown
  int resolution = 0;                     // voxels along the longest side actually used (0: voxel size given)
  std::vector<std::string> warnings;
  std::map<std::string, double> timings_ms;  // per stage, and "total"
  int loops_omitted = 0;                  // chokes past AnalyzeOptions::max_loops (not traced)
  WorldFrame frame;                       // volumes: grid frame -> image world (applied when writing)
  std::string extra_json;                 // a JSON object whose fields are added to loops.json
  bool has_input_loops = false;           // input_mesh and input_loops are set (mesh inputs)
  InputMesh input_mesh;
  std::vector<InputLoop> input_loops;     // one per loop, same order
};

// Runs every stage on a file (mesh or .vdb). Throws Error (2 bad input, 3 resources).
// `progress` hears each stage start ("levelset", "persistence", "chokes", "surface", "loops", "done") and the
// persistence's and loop stage's fractions (the loop stage's on the calling thread, at each loop done); false
// stops the run with Error "interrupted" (in the loop stage, once the loops under way finish).
AnalyzeResult analyze(const std::string& input, const AnalyzeOptions& options, const ProgressFn& progress = {});

// Runs every stage after the level set on a given signed distance grid (negative inside).
AnalyzeResult analyze_grid(ScalarGrid grid, const AnalyzeOptions& options, const ProgressFn& progress = {},
                           const std::string& name = "grid");

// Writes surface.ply, loops.ply, loops.obj and loops.json (DESIGN §5) into outdir (created if missing).
void write_report(const AnalyzeResult& result, const AnalyzeOptions& options, const std::string& outdir);

// The text of loops.json (what write_report writes there), for callers that keep results in memory.
std::string report_json(const AnalyzeResult& result, const AnalyzeOptions& options);

// The text of input_loops.json (written beside loops.json when result.has_input_loops): the loops on the input
// mesh with loops.json's fields, plus where each point lies on the input (vertex, or edge and face ids).
std::string input_loops_json(const AnalyzeResult& result);

// Carries result.loops onto the input mesh `input` (input_loops.h) and checks them there; sets
// has_input_loops, input_mesh and input_loops, warns about loops that could not be carried, times it as
// "input_loops". A mesh the carrying cannot use is a warning, not an error (loops.json stays valid).
void add_input_loops(AnalyzeResult& result, const std::string& input);

}  // namespace chokeloops

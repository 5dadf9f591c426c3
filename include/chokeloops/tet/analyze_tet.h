#pragma once
// `analyze MESH --complex tetgen`: the chokes of a closed mesh read from the persistence of its signed distance
// on TetGen's complex (tet_field.h) instead of the grid, by the same table (chokes.h), and their loops traced on
// the input mesh, a subcomplex of it (tet_loops.h).
#include <map>
#include <string>

#include "chokeloops/io/mesh_io.h"
#include "chokeloops/tet/tet_field.h"
#include "chokeloops/tet/tet_loops.h"
#include "chokeloops/tet/tet_persistence.h"
#include "chokeloops/topology/chokes.h"

namespace chokeloops {

struct TetAnalysis {
  std::int64_t vertices = 0, tets = 0;
  std::array<std::int64_t, 4> simplices{0, 0, 0, 0};
  ChokeSet chokes;
  std::vector<std::array<std::int32_t, 4>> pair_simplices;  // the pairs' simplices (vertex ids, -1 padded): Choke::simplex indexes it
  SurfaceMesh input;                   // the input mesh, whose vertex ids the loops' edge paths use
  MeshReport input_report;
  std::vector<InputLoop> loops;        // one per choke (empty when loops were not asked for)
  std::map<std::string, double> timings_ms;  // tetgen, distance, persistence, chokes, loops
};

// trace_loops = false stops after the chokes table.
TetAnalysis analyze_tet_complex(const TriangleMesh& mesh, const TetOptions& tet, const ChokeParameters& params,
                                bool trace_loops = true, const TetLoopOptions& loops = {});

// Writes into outdir (created if missing) what the grid path writes for a mesh, with the input mesh as the
// surface: surface.ply, loops.ply, loops.obj, loops.json ("complex": "tetgen"; each loop with its edge path and
// input points, as in input_loops.json) and chokes.csv.
void write_tet_report(const TetAnalysis& analysis, const ChokeParameters& params, const std::string& input,
                      const std::string& outdir);

// chokes.csv: side,kind,depth,persistence,birth,death,x,y,z (one row per choke, the table's order).
void write_chokes_csv(const ChokeSet& chokes, const std::string& path);

}  // namespace chokeloops

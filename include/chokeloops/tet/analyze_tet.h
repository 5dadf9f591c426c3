#pragma once
// `analyze MESH --complex tetgen`: the chokes of a closed mesh read from the persistence of its signed distance
// on TetGen's complex (tet_field.h) instead of the grid, by the same table (chokes.h). Loops are not traced on
// this complex yet: it reports the generators and chokes, their depths, persistence and points.
#include <map>
#include <string>

#include "chokeloops/io/mesh_io.h"
#include "chokeloops/tet/tet_field.h"
#include "chokeloops/tet/tet_persistence.h"
#include "chokeloops/topology/chokes.h"

namespace chokeloops {

struct TetAnalysis {
  std::int64_t vertices = 0, tets = 0;
  std::array<std::int64_t, 4> simplices{0, 0, 0, 0};
  ChokeSet chokes;
  std::map<std::string, double> timings_ms;  // tetgen, distance, persistence, chokes
};

TetAnalysis analyze_tet_complex(const TriangleMesh& mesh, const TetOptions& tet, const ChokeParameters& params);

// chokes.csv: side,kind,depth,persistence,birth,death,x,y,z (one row per choke, the table's order).
void write_chokes_csv(const ChokeSet& chokes, const std::string& path);

}  // namespace chokeloops

#pragma once
// Loops on TetGen's complex (`--complex tetgen`). The input surface is a subcomplex of it, so a choke's membrane
// ends on the input's own edges: a two-lobe priority flood over the complex's vertices (along the inside tets'
// edges for handles, the outside tets' for tunnels, in filtration order) labels each input vertex by the lobe
// that reaches it first; the loop is a curve between the two labelled face sets, shortened on the input mesh in
// its class (shorten_loop) and checked there with CGAL's Surface_mesh_topology.
#include <array>
#include <cstdint>
#include <vector>

#include "chokeloops/loops/input_loops.h"
#include "chokeloops/tet/tet_field.h"
#include "chokeloops/topology/chokes.h"

namespace chokeloops {

struct TetLoopOptions {
  bool shorten = true;
  int max_rings = 12;       // band of the shortening on the input mesh (ShortenOptions::max_rings)
  // The flood stays in a ball around the choke: box_factor * depth + box_margin * the lattice spacing at
  // first, grown by half again until the membrane closes on the surface.
  double box_factor = 1.5;
  double box_margin = 3;
};

// One loop per choke, in the same order (loop.edge_path: input vertex ids; where: each point's vertex or edge).
// `choke_simplices[c.simplex]` holds the vertex ids of choke c's simplex, -1 padded: an edge for handles, a
// triangle for tunnels. A generator's loop must be non-contractible on the input; a loop that cannot be found
// or fails its check is returned with found = false and a note saying why. Loops are traced in parallel; the
// result does not depend on the thread count.
std::vector<InputLoop> trace_tet_loops(const TetField& field, const SurfaceMesh& input, const std::vector<Choke>& chokes,
                                       const std::vector<std::array<std::int32_t, 4>>& choke_simplices,
                                       const TetLoopOptions& options = {});

}  // namespace chokeloops

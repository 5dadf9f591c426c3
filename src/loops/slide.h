#pragma once
// Private to src/loops: on a tube whose radius barely changes, the grid saddle lands anywhere along a flat
// ridge and local shortening cannot feel the narrowing. Translating the loop along its own normal and
// shortening again samples the nearby cross-sections; the shortest valid one is kept (it moves at most `reach`).
#include "chokeloops/grid.h"
#include "chokeloops/loops/shorten.h"
#include "chokeloops/surface/mesh_adjacency.h"
#include "chokeloops/surface/surface.h"

namespace chokeloops::detail {

// Slides `best` (shortened with `so`) toward the narrowest section within `reach`; debug: one line on stderr.
void slide_to_narrowest(const ScalarGrid& grid, const SurfaceMesh& surface, const MeshAdjacency& adjacency, ShortenResult& best,
                        const ShortenOptions& so, double reach, bool debug);

}  // namespace chokeloops::detail

#pragma once
// Linking numbers of closed polylines, and the cycle a generator's choke closes: together they check that a
// generator's loop cuts its own handle (tunnel), which non-contractibility on the surface alone does not say.
//
// A handle generator's choke is the edge where a cycle of the solid closes; its loop bounds a membrane across
// that cycle, so the two link an odd number of times. A curve of the surface in another class (e.g. the rim
// of a flat membrane along a thin wall, which goes around the tunnel instead of across the handle) is also
// non-contractible on the surface but links the cycle an even number of times.
#include <optional>

#include "chokeloops/grid.h"
#include "chokeloops/surface/surface.h"
#include "chokeloops/topology/chokes.h"

namespace chokeloops {

// Linking number of two disjoint closed polylines (each closed by its last-to-first segment), counted from
// the crossings of their projection along a fixed generic direction. nullopt: the projection is degenerate
// at a crossing for every direction tried (a curve meets the other, or nearly).
std::optional<int> linking_number(const Polyline3& a, const Polyline3& b);

// The cycle a generator's choke closes, as grid vertices in world coordinates: the saddle, one lobe, a
// shortest path (in steps of the Freudenthal grid) to the other lobe through the vertices beyond the saddle
// in its side's filtration (the solid below it for a handle, the outside above it for a tunnel), back to the
// saddle. Every vertex has the side's strict sign, so the cycle does not meet the marching surface. Empty
// when there is no such cycle: not a generator, a lobe outside the grid, a choke of depth 0, or lobes the
// region does not join (which a generator's pairing rules out).
Polyline3 generator_cycle(const ScalarGrid& grid, const Choke& choke);

}  // namespace chokeloops

#pragma once
// Private to src/loops: where the two zones of a flooded box (two_lobe_flood.h) meet on the surface. The
// surface vertices on the region's edges out of the zones' contact take the zone of their end in the region;
// the faces whose corners carry both zones hold the interface's segments, chained here into curves. The loop
// tracer asks the closed curves near the choke in turn; the open ones tell it which sides of the box to grow.
#include <array>
#include <cstdint>
#include <vector>

#include "chokeloops/surface/surface.h"
#include "chokeloops/topology/complex.h"
#include "two_lobe_flood.h"

namespace chokeloops::detail {

// Per-vertex (or per-face) marks over the whole surface that a thread reuses from one flood to the next:
// cleared by bumping a stamp, so that a small membrane on a surface of millions of vertices pays for the
// vertices it labels, not for the surface.
template <class T>
struct StampedMarks {
  std::vector<T> value;
  std::vector<std::uint32_t> stamp;
  std::uint32_t now = 0;
  void reset(std::size_t n) {
    if (stamp.size() < n) stamp.assign(n, 0), value.assign(n, T{});
    if (++now == 0) std::fill(stamp.begin(), stamp.end(), 0), now = 1;
  }
  bool has(std::size_t i) const { return stamp[i] == now; }
  T get(std::size_t i) const { return has(i) ? value[i] : T{}; }
  void set(std::size_t i, T v) { stamp[i] = now, value[i] = v; }
};

struct InterfaceCurve {
  Polyline3 points;                 // the midpoints of the surface edges it crosses, in turn round the curve
  std::vector<std::int64_t> edges;  // those edges (edge_key), in the same order
};

struct SurfaceInterface {
  InterfaceSegments segments;          // one per face holding the interface, in the order of the faces
  SegmentsAtEdge at;                   // the segments at each crossed edge
  std::vector<InterfaceCurve> closed;  // the closed curves of 3 points or more, by their first segment
};

// The zones' interface on the surface after `box` was flooded through the solid (`handle`) or the outside.
// `label` (reset here; the thread's, reused by its next call) ends with each labelled vertex's zone, 1 or 2.
void surface_interface(const ScalarGrid& grid, const FreudenthalComplex& cx, const SurfaceMesh& surface,
                       const MeshAdjacency& adjacency, const FloodBox& box, bool handle, StampedMarks<std::int8_t>& label,
                       SurfaceInterface& out);

// The edge paths along the two sides of an interface curve that crosses the surface edges `edges` (in order
// round the curve), the shorter first (a side collapsed to fewer than 3 vertices last): of each edge, its end
// in that side's zone. Two edges crossed in turn share a face and the corner whose label differs from the
// other two: the ends on one side are that corner twice, or the face's other two corners, joined by its third
// edge; so the ends make an edge path without a search, in the faces the curve crosses (the curve's homotopy
// class, unless the side touches itself).
std::array<std::vector<int>, 2> label_side_paths(const SurfaceMesh& surface, const std::vector<std::int64_t>& edges,
                                                 const StampedMarks<std::int8_t>& label);

}  // namespace chokeloops::detail

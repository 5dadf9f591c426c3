#pragma once
// The half-edges of a triangle mesh grouped by undirected edge, for the adjacency and the surface statistics.
// A counting sort over each edge's smaller vertex: linear in the mesh, the same order as a full sort.
#include <cstdint>
#include <vector>

#include "chokeloops/surface/surface.h"

namespace chokeloops {

struct EdgeHalfedge {
  std::uint64_t key;  // (smaller vertex << 32) | larger vertex
  int h;              // half-edge 3*f + k, from faces[f][k] to faces[f][(k+1)%3]
};

// Sorted by (key, h): the half-edges of one edge are consecutive, in face order.
std::vector<EdgeHalfedge> halfedges_by_edge(const SurfaceMesh& mesh);

}  // namespace chokeloops

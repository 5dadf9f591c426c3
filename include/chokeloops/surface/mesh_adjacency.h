#pragma once
// Half-edge style adjacency of a SurfaceMesh, built once and shared by the topology checks and the loop
// shortening. Half-edge h = 3*f + k runs from faces[f][k] to faces[f][(k+1)%3]; twin[h] is the opposite
// half-edge in the neighbouring face, or -1 on a boundary (or at a non-manifold edge).
#include <vector>

#include "chokeloops/surface/surface.h"

namespace chokeloops {

struct MeshAdjacency {
  std::vector<int> twin;                 // size 3*faces
  std::vector<int> vf_start, vf;         // CSR: faces around each vertex (unordered)
  std::vector<int> vv_start, vv;         // CSR: neighbour vertices of each vertex (sorted)

  static int face(int h) { return h / 3; }
  static int next(int h) { return h - h % 3 + (h % 3 + 1) % 3; }
  static int prev(int h) { return h - h % 3 + (h % 3 + 2) % 3; }
  // Half-edge a -> b inside some face, or -1 when no face has it.
  int halfedge(const SurfaceMesh& m, int a, int b) const;
  bool has_edge(int a, int b) const;
};

MeshAdjacency build_adjacency(const SurfaceMesh& mesh);

}  // namespace chokeloops

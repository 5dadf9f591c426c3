#pragma once
// The edges of a triangle mesh seen from each vertex: at a vertex, the half-edges of its faces (the
// adjacency's vf lists) that touch it, grouped by the edge's other end. The adjacency and the surface
// statistics read every edge from its smaller end, in parallel over vertices: each vertex reads only its own
// few faces, where a global sort of all half-edges by edge scattered hundreds of MB (17.7M faces of a
// molecular surface: 2 x 2-4 s).
#include <vector>

#include "chokeloops/surface/surface.h"

namespace chokeloops {

struct HalfedgeAt {
  int other;  // the edge's other end
  int h;      // half-edge 3*f + k, from faces[f][k] to faces[f][(k+1)%3]
};

// The half-edges of the faces around v (vf[begin, end)) that start or end at v, sorted by (other, h): each
// edge at v is a run of equal `other`, one entry per face that has it. `out` is reused (cleared first).
void halfedges_at(const SurfaceMesh& mesh, const std::vector<int>& vf, int begin, int end, int v,
                  std::vector<HalfedgeAt>& out);

}  // namespace chokeloops

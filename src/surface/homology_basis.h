#pragma once
// Z/2 homology classes of edge cycles on the closed components of a surface, in time proportional to the
// cycle's length plus the component's genus, times a logarithm (not to the surface's size).
//
// Tree-cotree decomposition (Eppstein 2003): a spanning tree T of the vertices, a spanning tree C of the
// faces through edges not in T, and the 2g edges left over, whose fundamental cycles (edge + tree path) are
// a basis of H1(component; Z/2). A cycle's class is the sum of its non-tree edges' classes. A leftover edge
// is a basis vector. A cotree edge e, above the subtree S of faces that C hangs below it, has the class of
// the leftover edges with exactly one face in S (the boundary of the faces of S is null and crosses C only
// at e). With the faces of C numbered in depth-first order, "in S" is an interval test, and the parity of
// the intervals of a cycle's cotree edges holding a face is a binary search in their sorted ends.
#include <array>
#include <cstdint>
#include <vector>

#include "chokeloops/surface/mesh_adjacency.h"
#include "chokeloops/surface/surface.h"

namespace chokeloops {

class HomologyBasis {
 public:
  // `face_label`/`closed`: the components (face_components numbering) and which of them are closed; the
  // basis is built on the closed ones only.
  HomologyBasis(const SurfaceMesh& mesh, const MeshAdjacency& adj, const std::vector<int>& face_label,
                const std::vector<char>& closed);
  // Whether the closed edge path `loop` (cyclic vertex list, consecutive vertices joined by mesh edges, on
  // a closed component) is null in H1(component; Z/2).
  bool null_homologous(const std::vector<int>& loop) const;

 private:
  // Per half-edge, one byte: which part of the decomposition its edge is in, and for a cotree edge which of
  // its two faces hangs below it (a quarter of the int32 codes that stored the face itself).
  enum Part : std::uint8_t { kUnset, kTree, kLeftover, kCotreeBelowHere, kCotreeBelowTwin };
  int leftover_index(int lower_halfedge, int component) const;
  const SurfaceMesh& mesh_;
  const MeshAdjacency& adj_;
  const std::vector<int>& face_label_;
  std::vector<std::uint8_t> part_;
  // Per face: its subtree of C is [first, last] in DFS order. One pair a face, not two arrays: the DFS reads a
  // neighbour's first and later writes the face's last, and one cache line serves both.
  std::vector<std::array<std::int32_t, 2>> interval_;
  std::vector<std::int32_t> leftover_start_;  // per component: its leftover edges' indices (components + 1)
  std::vector<std::int32_t> leftover_edge_;   // per leftover edge: its lower half-edge, rising in each component
  std::vector<std::array<std::int32_t, 2>> leftover_faces_;  // per leftover edge: DFS numbers of its faces
};

}  // namespace chokeloops

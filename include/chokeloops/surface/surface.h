#pragma once
// The zero level set of a grid, extracted on exactly the Freudenthal tetrahedra of complex.h (marching
// tetrahedra), so that its topology is the topology of the solid subcomplex {v : value(v) <= 0}.
//
// Inside/outside: a vertex is inside when its value is <= 0 (a value of exactly 0 is inside), outside when
// > 0. Every grid edge with one inside and one outside end carries exactly one surface vertex (keyed by the
// edge id, shared by all tets around the edge), placed by linear interpolation and kept at least 1e-3 of the
// edge away from either end, so no surface edge has zero length. A tet with 1 or 3 inside vertices gives a
// triangle, with 2 a quad split along its shorter diagonal. Faces are oriented with normals pointing from the
// inside to the outside (counter-clockwise seen from outside).
//
// The result is a 2-manifold without boundary wherever the solid stays off the grid's border; it is the
// boundary of a regular neighbourhood of the solid subcomplex, so its total genus equals the solid's first
// Betti number and its Euler characteristic is 2·components − 2·genus.
//
// Order: vertices by increasing grid edge id, faces by increasing tet id (then the fixed order inside a tet).
// The output does not depend on the thread count.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "chokeloops/topology/complex.h"
#include "chokeloops/grid.h"

namespace chokeloops {

using Polyline3 = std::vector<std::array<double, 3>>;  // a closed polyline (last point != first)

struct SurfaceMesh {
  std::vector<std::array<double, 3>> vertices;  // world coordinates
  std::vector<std::array<int, 3>> faces;        // counter-clockwise seen from outside
  std::vector<Id> vertex_edge;                  // grid edge id (complex.h) each vertex lies on
};

SurfaceMesh extract_zero_surface(const ScalarGrid& grid);

// The surface vertex lying on grid edge `edge` (binary search in vertex_edge, which is sorted), or -1 when
// the edge does not cross the zero level.
int surface_vertex_on_edge(const SurfaceMesh& mesh, Id edge);

struct SurfaceStats {
  std::int64_t vertices = 0, faces = 0, edges = 0;
  std::int64_t boundary_edges = 0;         // edges with one face
  std::int64_t nonmanifold_edges = 0;      // edges with more than two faces
  std::int64_t nonmanifold_vertices = 0;   // vertices whose faces form more than one fan
  std::int64_t inconsistent_edges = 0;     // interior edges whose two faces do not use it in opposite directions
  int components = 0;                      // connected components (through shared edges or vertices)
  std::int64_t euler = 0;                  // V - E + F
  std::vector<int> component_genus;        // genus of each component (-1 when it is not a closed manifold)
  std::vector<std::int64_t> component_faces;
  int genus = 0;                           // sum of the genera of the closed manifold components
  bool closed_manifold = false;            // no boundary, no non-manifold edge/vertex, consistently oriented
  double enclosed_volume = 0;              // signed volume (divergence theorem); > 0 for outward normals
  double area = 0;
};

SurfaceStats surface_stats(const SurfaceMesh& mesh);

// Component label (0..components-1, numbered by first face) of every face; components joined via shared
// vertices. Returns the number of components.
int face_components(const SurfaceMesh& mesh, std::vector<int>& face_label);

}  // namespace chokeloops

#pragma once
// The paper's complex: a TetGen tetrahedralization of a padded box around a closed mesh, the mesh's triangles
// constrained facets kept as they are (-Y), so that the input surface is a subcomplex; the signed distance to
// the mesh at every vertex (negative inside, 0 on the input's own vertices). The reference path beside the
// grid engine (`--complex tetgen`): an independent triangulation, and the pipeline the paper timed.
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "chokeloops/io/mesh_io.h"

namespace chokeloops {

// Where the function is sampled decides the depths' accuracy, as the voxel does on the grid. TetGen's own
// refinement (-q, -a) keeping the input surface (-Y) is slow (24 s for 155K tets on a 12K-vertex torus) and with
// -q can run without end on a mesh of thin triangles, so the points inside and outside are chosen here: graded
// by default, or a uniform lattice.
struct TetOptions {
  double spacing = 0;          // finest spacing of the sample points, input units; 0: the box's diagonal / default_cells
  double default_cells = 64;
  // 0: a uniform lattice of `spacing`; > 0: graded, an octree's cells split while larger than `spacing` and than
  // grading times their distance to the surface (tet_field.cpp: sample_points).
  double grading = 2;
  double radius_edge = 0;      // TetGen -q: largest radius-edge ratio of a tet (> 1; 0: no -q)
  double max_volume = 0;       // TetGen -a: largest tet volume in input units cubed; 0: no -a
  double padding = 0.1;        // the box around the mesh, as a fraction of its bounding box's diagonal
  std::size_t max_memory = 0;  // bytes the path may use (checked before TetGen runs); 0: default_max_memory()
};

struct TetField {
  std::vector<std::array<double, 3>> vertices;  // the input's vertices first, in their order, then TetGen's
  std::vector<std::array<std::int32_t, 4>> tets;
  std::vector<double> values;                   // signed distance to the input surface, per vertex
  std::vector<char> inside_tets;                // per tet: inside the input surface (a walk across faces from the box)
  std::int32_t input_vertices = 0;
  double spacing = 0;                           // finest spacing of the sample points
  double seconds_tetgen = 0, seconds_distance = 0;
};

// Throws Error (exit 2) for a mesh that is not closed and manifold, or that TetGen refuses (self-intersecting
// or touching facets); exit 3 when the samples would need more than max_memory, or TetGen runs out of memory.
TetField tetrahedralize_with_distance(const TriangleMesh& mesh, const TetOptions& options = {});

}  // namespace chokeloops

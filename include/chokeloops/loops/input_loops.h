#pragma once
// The loops carried from the marching surface onto the user's own mesh: each grid loop is projected onto the
// input triangles (closest points, CGAL AABB tree), joined into a closed edge path by shortest paths along the
// input's edges, shortened there in its homotopy class (shorten_loop), then checked with CGAL on the input mesh.
#include <array>
#include <string>
#include <vector>

#include "chokeloops/io/mesh_io.h"
#include "chokeloops/loops/membranes.h"
#include "chokeloops/surface/surface.h"

namespace chokeloops {

// The mesh the input loops refer to: the file's own triangles when they form a closed manifold (ids are the
// file's), else the repaired mesh the level set was made from (repair_mesh with its default options, which a
// later `chokeloops cut` repeats, so that the ids stay meaningful).
struct InputMesh {
  SurfaceMesh mesh;  // vertex_edge is empty
  bool repaired = false;
  MeshReport report;  // of `mesh`
  // Repaired meshes: per face, 1 when no face of the file has its three corners (hole filling added it).
  std::vector<char> added_face;
};
InputMesh load_input_mesh(const std::string& path);
InputMesh input_mesh_from(const TriangleMesh& mesh, const std::string& name);

// Where one point of an input loop lies: on a vertex of the input mesh, or inside an edge (a, b) at
// a + t (b - a); `face` is a face that holds it.
struct InputPoint {
  int vertex = -1;
  std::array<int, 2> edge{-1, -1};
  double t = 0;
  int face = -1;
};

struct InputLoop {
  Loop loop;                     // on the input mesh (choke copied from the grid loop; edge_path: input vertices)
  double grid_length = 0;        // of the grid loop on the marching surface
  // Checked on the input mesh: a generator is non-contractible (CGAL); a choke separates the input exactly
  // when it separates the marching surface, and is non-contractible when it does not.
  bool verified = false;
  bool separating = false;       // the grid loop separates the marching surface (chokes only)
  std::vector<InputPoint> where;  // one per loop.points
  double transfer_ms = 0;        // wall time of this loop's transfer and check (a diagnostic)
};

struct ShortenResult;

// Where each point of a shortened loop lies on `mesh` (its vertex, or its edge and parameter), from the strip
// shorten_loop ran through (an unshortened result: its edge path's vertices).
std::vector<InputPoint> locate_loop_points(const SurfaceMesh& mesh, const MeshAdjacency& adj, const ShortenResult& shortened);

struct InputLoopOptions {
  bool shorten = true;
  int max_rings = 12;  // band of the shortening on the input mesh (ShortenOptions::max_rings)
};

// One input loop per grid loop of `grid_surface`, in the same order; a grid loop that is missing, cannot be
// carried over or fails the check gives a loop with found = false and a note saying why. Loops are carried in
// parallel; the result does not depend on the thread count.
std::vector<InputLoop> transfer_loops(const InputMesh& input, const SurfaceMesh& grid_surface,
                                      const std::vector<Loop>& grid_loops, const InputLoopOptions& options = {});

}  // namespace chokeloops

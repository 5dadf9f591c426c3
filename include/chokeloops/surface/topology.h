#pragma once
// Topological checks of loops on a SurfaceMesh, used by tests and by the loop stage's self-checks:
// contractibility (CGAL Surface_mesh_topology, on the connected component that holds the loop) and
// separation (does cutting along the loop split its component?). A loop is a cyclic sequence of surface
// vertex indices, consecutive ones (and the last and the first) joined by mesh edges; the first vertex is
// not repeated at the end.
#include <array>
#include <memory>
#include <vector>

#include "chokeloops/surface/mesh_adjacency.h"
#include "chokeloops/surface/surface.h"

namespace chokeloops {

// Builds the per-component structures once, for many queries on one mesh. Queries may run concurrently (the
// CGAL structure of a component is built lazily, under a lock, on its first CGAL query). Throws Error when a
// loop is empty, uses an index out of range, or two consecutive vertices are not joined by a mesh edge.
class SurfaceTopology {
 public:
  explicit SurfaceTopology(const SurfaceMesh& mesh);
  // Shares a prebuilt adjacency of `mesh` (kept by reference: it must outlive this object).
  SurfaceTopology(const SurfaceMesh& mesh, const MeshAdjacency& adjacency);
  // ... and the faces' components already found (face_components numbering, e.g. from surface_stats).
  SurfaceTopology(const SurfaceMesh& mesh, const MeshAdjacency& adjacency, std::vector<int> face_label, int components);
  ~SurfaceTopology();
  SurfaceTopology(const SurfaceTopology&) = delete;
  SurfaceTopology& operator=(const SurfaceTopology&) = delete;

  // Null-homotopic on the surface (CGAL::Surface_mesh_topology::Curves_on_surface_topology).
  bool contractible(const std::vector<int>& loop);
  // The same answer without CGAL's structure when it can. A loop that is not null in Z/2 homology is
  // essential (time proportional to the loop, see null_homologous). A simple loop that is null separates
  // its closed component, and is contractible exactly when one side has Euler characteristic 1: two face
  // floods, one from each side of the loop and advanced in turn, decide it in time proportional to the
  // smaller side. The rest (a loop that is not simple, any loop on a component with boundary) goes to
  // contractible().
  bool contractible_fast(const std::vector<int>& loop);
  // Null in H1(surface; Z/2), exact for any closed edge path (simple or not) on a closed component: a
  // tree-cotree basis of the surface's homology (built once, on the first query) reduces it to interval
  // tests, time proportional to the loop's length plus the component's genus, times a log. A loop that is not null is
  // non-contractible. On a component with boundary it answers contractible() instead (a sufficient
  // condition only).
  bool null_homologous(const std::vector<int>& loop);
  // Builds the tree-cotree basis that null_homologous() (and so contractible_fast() and separates()) use,
  // now rather than at the first query: a caller can overlap it with other work. Thread-safe, done once.
  void prepare_homology();
  // How many contractibility queries CGAL answered so far (the others were decided by face floods).
  int cgal_queries() const;
  // Removing the loop's edges splits the loop's component into more face-connected parts.
  bool separates(const std::vector<int>& loop);
  // Component (face_components numbering) that holds vertex v, -1 for an isolated vertex.
  int component_of_vertex(int v) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

bool loop_is_contractible(const SurfaceMesh& mesh, const std::vector<int>& loop);
bool loop_separates_surface(const SurfaceMesh& mesh, const std::vector<int>& loop);

// True when every vertex of the loop occurs once and the loop has at least 3 vertices.
bool loop_is_simple(const std::vector<int>& loop);

// Removes from a closed edge path (a cyclic vertex list) the repeated vertices and the back-and-forth spurs
// a b a, cyclically, until none is left; a figure-eight stays (callers check loop_is_simple).
void remove_repeats_and_spurs(std::vector<int>& path);

// Turns a closed polyline lying on (or very near) the surface into a closed edge path: the nearest mesh
// vertex of every point, joined by shortest edge paths (Dijkstra over the part of the mesh near the
// polyline), with repeated vertices and back-and-forth spurs removed. When `component` >= 0, only vertices
// of that component are used. The result is a cyclic vertex list (first vertex not repeated).
// Points with no vertex within a few edge lengths are skipped. Throws Error when nothing is left or the
// snapped vertices are not connected. The overload with a prebuilt adjacency avoids scanning the faces.
std::vector<int> snap_polyline_to_edge_path(const SurfaceMesh& mesh, const Polyline3& polyline, int component = -1);
std::vector<int> snap_polyline_to_edge_path(const SurfaceMesh& mesh, const MeshAdjacency& adj, const Polyline3& polyline,
                                            int component = -1);
std::vector<int> snap_polyline_to_edge_path(const SurfaceMesh& mesh, const MeshAdjacency* adj, const Polyline3& polyline,
                                            int component);

// Length of a closed polyline (including the closing segment) and of a closed vertex loop.
double closed_length(const Polyline3& polyline);
double loop_length(const SurfaceMesh& mesh, const std::vector<int>& loop);
Polyline3 loop_points(const SurfaceMesh& mesh, const std::vector<int>& loop);
// The plane closest to a polyline's points in the least-squares sense: their centroid, and the unit normal
// of least spread (either sign).
void best_fit_plane(const Polyline3& points, std::array<double, 3>& centroid, std::array<double, 3>& normal);

}  // namespace chokeloops

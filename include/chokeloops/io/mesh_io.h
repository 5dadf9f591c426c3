#pragma once
// Triangle mesh input (OBJ, PLY ascii/binary, OFF, STL ascii/binary via CGAL IO), validation and repair
// (CGAL Polygon Mesh Processing). Stage `levelset`, see DESIGN.md §4.
#include <array>
#include <cstddef>
#include <string>
#include <vector>

namespace chokeloops {

// Plain indexed triangle mesh, in the input's units.
struct TriangleMesh {
  std::vector<std::array<double, 3>> vertices;
  std::vector<std::array<int, 3>> faces;  // indices into vertices
};

// Reads OBJ / PLY / OFF / STL (extension decides, case-insensitive), triangulates polygons
// (fan / shorter quad diagonal) and validates. Throws chokeloops::Error (exit code 2) with a
// one-line message naming the file and the problem for: missing file, directory, empty file,
// unknown extension, truncated file (binary PLY/STL counts are checked against the header/size),
// unparsable content, NaN/inf or huge (|x| > 1e30) coordinates, faces referencing missing
// vertices, no faces.
TriangleMesh read_mesh(const std::string& path);

// The supported mesh extensions, lower case with the dot: {".obj", ".ply", ".off", ".stl"}.
const std::vector<std::string>& mesh_extensions();

// What the input looked like and what repair did.
struct MeshReport {
  std::size_t input_vertices = 0, input_faces = 0;   // triangles after triangulation
  std::size_t vertices = 0, faces = 0;               // after repair (and hole filling)
  std::size_t merged_vertices = 0;                   // duplicate points merged
  std::size_t removed_faces = 0;                     // degenerate / duplicate faces removed
  std::size_t nonmanifold_edges = 0;                 // edges with > 2 faces (after merging duplicates)
  std::size_t nonmanifold_vertices_split = 0;        // vertices duplicated to make the soup orientable
  std::size_t boundary_edges = 0;                    // border edges of the repaired input (before hole filling)
  std::size_t holes = 0;                             // boundary cycles (before hole filling)
  std::size_t holes_filled = 0;                      // boundary cycles closed by hole filling
  std::size_t boundary_edges_remaining = 0;          // border edges after hole filling
  bool closed = false;                               // input (after repair, before filling) has no border
  bool self_intersecting = false;  // checked when check_self_intersections, and before nesting several closed components
  std::size_t components = 0;
  int euler = 0;                                     // V - E + F of the repaired mesh
  int genus = -1;                                    // sum over components of (2 - chi)/2 when closed, else -1
  std::vector<int> component_genus;                  // per component (-1 for an open one)
};

struct MeshRepairOptions {
  bool fill_holes = true;                // close remaining boundary cycles with CGAL triangulate_hole
  std::size_t max_hole_edges = 20000;    // larger holes are left open
  bool check_self_intersections = false; // costly on big meshes
};

struct RepairedMesh {
  TriangleMesh mesh;   // closed and outward-oriented when the repair succeeded
  MeshReport report;
  std::vector<std::string> warnings;  // one line each, naming the problem
};

// Merges duplicate points, removes degenerate and duplicate faces, orients, stitches borders,
// removes geometrically degenerate faces, optionally fills holes, orients outward when closed, and
// reports topology. `name` is used in warnings (usually the file path).
RepairedMesh repair_mesh(const TriangleMesh& mesh, const std::string& name = "mesh",
                         const MeshRepairOptions& options = {});

// Topology of a triangle mesh as it is (no repair): boundary edges, non-manifold edges,
// components (sharing vertices), Euler characteristic and genus (if closed).
MeshReport mesh_topology(const TriangleMesh& mesh);

// Writes an OFF/OBJ/PLY/STL file (extension decides) — handy for tests and debugging.
void write_mesh(const TriangleMesh& mesh, const std::string& path);

}  // namespace chokeloops

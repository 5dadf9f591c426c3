#pragma once
// Writers for the surface and the loops: binary little-endian PLY (float xyz; int vertex_indices for faces,
// int vertex1/vertex2 edges for polylines) and OBJ polylines. Throw Error (exit code 3) when the file
// cannot be written.
#include <array>
#include <string>
#include <vector>

#include "chokeloops/surface/surface.h"

namespace chokeloops {

// element vertex (float x,y,z), element face (list uchar int vertex_indices).
void write_ply(const SurfaceMesh& mesh, const std::string& path);

// Closed polylines: element vertex (float x,y,z; int loop), element edge (int vertex1, int vertex2); loop i
// with n points gives n vertices and n edges (the last one closes it).
void write_loops_ply(const std::vector<Polyline3>& loops, const std::string& path);

// OBJ: one "o loop_<i>" per loop, its points as "v", then one "l" line through them, closed by repeating
// the first index.
void write_loops_obj(const std::vector<Polyline3>& loops, const std::string& path);

}  // namespace chokeloops

#pragma once
// Lower-star persistence (Z/2, dimensions 0-2) of a function on the vertices of an explicit tetrahedral
// complex, reduced by PHAT (twist reduction) over the whole boundary matrix: the reference beside the grid
// engine's implicit, matrix-free one. Same conventions: vertices ordered by (value, index), a simplex enters
// with its highest vertex, simplices with the same highest vertex ordered lexicographically by their vertex
// lists sorted high to low; pairs inside one lower star are not reported.
#include <array>
#include <cstdint>
#include <vector>

namespace chokeloops {

struct TetPersistencePair {
  int dim = 0;
  double birth = 0, death = 0;  // death = +inf for an essential class
  std::int32_t birth_vertex = -1, death_vertex = -1;
  std::array<std::int32_t, 4> birth_simplex{-1, -1, -1, -1}, death_simplex{-1, -1, -1, -1};  // vertex ids, -1 padded
};

struct TetDiagram {
  std::vector<TetPersistencePair> pairs;      // finite, by dim then birth
  std::vector<TetPersistencePair> essential;
  std::array<std::int64_t, 4> simplices{0, 0, 0, 0};  // vertices, edges, triangles, tets
  double seconds_build = 0, seconds_reduce = 0;
};

// inside_tets (optional, one flag per tet): the tets of the solid. A simplex outside it whose vertices all lie at
// or below 0 (on the surface) then enters at "0+" (denorm_min), not with the solid at 0.
TetDiagram tet_lower_star_persistence(std::int32_t vertex_count, const std::vector<std::array<std::int32_t, 4>>& tets,
                                      const std::vector<double>& values, const std::vector<char>* inside_tets = nullptr);

}  // namespace chokeloops

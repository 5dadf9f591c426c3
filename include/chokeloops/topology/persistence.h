#pragma once
// Lower-star persistence (dimensions 0, 1, 2; Z/2; elder rule) of a scalar field on the implicit
// Freudenthal complex of its grid, without a global boundary matrix.
//
// Filtration: vertices by (value, linear index); a simplex enters with its highest vertex, and simplices
// are ordered lexicographically by their vertex lists sorted high to low (complex.h, simplex_less).
// Only pairs whose two simplices have different highest vertices are reported: the pairs inside one lower
// star carry no topological change. The result is the same whatever the thread count.
#include <array>
#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "chokeloops/topology/complex.h"
#include "chokeloops/grid.h"

namespace chokeloops {

struct PersistencePair {
  int dim = 0;                 // homology dimension of the class
  float birth = 0, death = 0;  // filtration values; death = +inf for an essential class
  Id birth_simplex = -1;       // id of a dim-simplex (vertex / edge / triangle id, see complex.h)
  Id death_simplex = -1;       // id of a (dim+1)-simplex, or -1 for an essential class
  Id birth_vertex = -1;        // highest vertex of the birth simplex (linear grid index)
  Id death_vertex = -1;        // highest vertex of the death simplex, -1 if essential
  // The two sides a critical simplex joins, one vertex of each (linear index; -2 = outside the box):
  // at a join saddle two lower-link components (below it), at a split saddle two upper-link components.
  // These seed the membranes: the loop of a choke separates its two lobes.
  std::array<Id, 2> birth_lobes{-1, -1};  // set for dim 1 (join saddle) and dim 2 (split saddle) births
  std::array<Id, 2> death_lobes{-1, -1};  // set for dim 0 (join saddle) and dim 1 (split saddle) deaths
  float persistence() const { return death - birth; }
  bool essential() const { return death_simplex < 0; }
};

struct PersistenceStats {
  double seconds_classify = 0, seconds_dim0 = 0, seconds_dim2 = 0, seconds_dim1 = 0, seconds_total = 0;
  Id join_saddles = 0, split_saddles = 0, minima = 0, maxima = 0;
  std::size_t estimated_bytes = 0;  // the memory guard's estimate of the whole computation's peak
  // dim-1 columns that the parallel pass left partly reduced (smooth fields with sparse noise: long columns,
  // few additions; see persistence_dim1.cpp), 0 where every column was reduced in full (rough fields)
  Id dim1_lazy_columns = 0;
};

struct PersistenceDiagram {
  std::array<int, 3> dims{0, 0, 0};
  std::vector<PersistencePair> pairs;  // finite pairs grouped by dim, in a deterministic discovery order
  std::vector<PersistencePair> essential;  // the essential classes (one dim-0 class for a box)
  PersistenceStats stats;
  std::size_t count(int dim) const;
};

// Called with a stage name and a fraction in [0,1]; returning false interrupts (throws Error).
using ProgressFn = std::function<bool(const char* stage, double fraction)>;

// Computes the diagram of `grid` (validated first: non-finite values throw Error).
// max_memory: the bytes it may use (0: 80% of physical memory). Once the field is classified, the counts of
// critical points give what the pairs will need, which on a rough field is several times a smooth one's; over
// the budget, Error with exit code 3 is thrown before anything large is allocated.
PersistenceDiagram lower_star_persistence(const ScalarGrid& grid, const ProgressFn& progress = {},
                                          std::size_t max_memory = 0);

// Writes "dim,birth,death" rows (GUDHI style, essential deaths as inf), header included.
void write_pairs_csv(const PersistenceDiagram& diagram, const std::string& path);

}  // namespace chokeloops

#pragma once
// Oracle for the lower-star persistence engine: builds the EXPLICIT filtered Freudenthal complex of a
// small grid (every valid vertex, edge, triangle and tetrahedron, enumerated by id), orders it by the
// same total order as the engine (complex.h: sorted_descending + simplex_less), reduces the boundary
// matrix with PHAT (twist reduction, Z/2) and maps the pairs back to simplex ids and values.
//
// Like the engine, it keeps only the pairs whose two simplices have different highest vertices (pairs
// inside one lower star carry no topological change), plus every essential (unpaired) simplex.
// Memory is about 100 bytes per simplex (~40 simplices per vertex): meant for grids up to ~30^3.
#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include <phat/algorithms/twist_reduction.h>
#include <phat/boundary_matrix.h>
#include <phat/compute_persistence_pairs.h>
#include <phat/persistence_pairs.h>
#include <phat/representations/default_representations.h>

#include "chokeloops/topology/complex.h"
#include "chokeloops/grid.h"

namespace chokeloops::oracle {

// One pair (or essential class: death_simplex = -1, death = +inf, death_vertex = -1).
struct OraclePair {
  int dim = 0;
  Id birth_simplex = -1, death_simplex = -1;
  Id birth_vertex = -1, death_vertex = -1;
  float birth = 0, death = 0;
  auto key() const { return std::make_tuple(dim, birth_simplex, death_simplex); }
  bool operator<(const OraclePair& o) const { return key() < o.key(); }
  bool operator==(const OraclePair& o) const {
    // Values compared bitwise-equal as floats (inf == inf); they are copies of grid values.
    return key() == o.key() && birth_vertex == o.birth_vertex && death_vertex == o.death_vertex &&
           birth == o.birth && death == o.death;
  }
};

inline std::string to_string(const OraclePair& p, const FreudenthalComplex& K) {
  std::ostringstream s;
  auto c = [&](Id v) {
    if (v < 0) return std::string("-");
    auto x = K.coords(v);
    return "(" + std::to_string(x[0]) + "," + std::to_string(x[1]) + "," + std::to_string(x[2]) + ")";
  };
  s << "dim " << p.dim << "  birth " << p.birth << " @ simplex " << p.birth_simplex << " top v" << p.birth_vertex
    << c(p.birth_vertex) << "  death " << p.death << " @ simplex " << p.death_simplex << " top v" << p.death_vertex
    << c(p.death_vertex);
  return s.str();
}

struct OracleDiagram {
  std::vector<OraclePair> pairs;      // finite pairs with different highest vertices, sorted by key()
  std::vector<OraclePair> essential;  // unpaired simplices, sorted by key()
  std::array<Id, 4> simplex_counts{0, 0, 0, 0};
  Id total_pairs = 0;                 // all finite pairs, including those inside one lower star
};

namespace detail {
struct Simplex {
  int dim;
  Id id;
  std::array<Id, 4> desc;  // vertices, highest first (only dim+1 entries used)
};
inline bool less(const float* f, const Simplex& a, const Simplex& b) {
  int n = std::min(a.dim, b.dim) + 1;
  for (int i = 0; i < n; ++i) {
    if (a.desc[i] == b.desc[i]) continue;
    return vertex_less(f, a.desc[i], b.desc[i]);
  }
  return a.dim < b.dim;
}
}  // namespace detail

inline OracleDiagram phat_persistence(const ScalarGrid& grid) {
  using detail::Simplex;
  FreudenthalComplex K(grid.dims);
  const float* f = grid.values.data();
  std::vector<Simplex> all;
  OracleDiagram out;
  for (Id v = 0; v < K.vertex_count(); ++v) all.push_back({0, v, {v, -1, -1, -1}});
  for (Id e = 0; e < K.edge_id_bound(); ++e)
    if (K.edge_valid(e)) {
      auto d = sorted_descending(f, K.edge_vertices(e));
      all.push_back({1, e, {d[0], d[1], -1, -1}});
    }
  for (Id t = 0; t < K.triangle_id_bound(); ++t)
    if (K.triangle_valid(t)) {
      auto d = sorted_descending(f, K.triangle_vertices(t));
      all.push_back({2, t, {d[0], d[1], d[2], -1}});
    }
  for (Id T = 0; T < K.tet_id_bound(); ++T)
    if (K.tet_valid(T)) {
      auto d = sorted_descending(f, K.tet_vertices(T));
      all.push_back({3, T, {d[0], d[1], d[2], d[3]}});
    }
  for (auto& s : all) out.simplex_counts[size_t(s.dim)]++;
  std::sort(all.begin(), all.end(), [f](const Simplex& a, const Simplex& b) { return detail::less(f, a, b); });

  // Position of each simplex in the filtration, per dimension, indexed by id.
  std::array<std::vector<phat::index>, 4> pos{
      std::vector<phat::index>(size_t(K.vertex_count()), -1), std::vector<phat::index>(size_t(K.edge_id_bound()), -1),
      std::vector<phat::index>(size_t(K.triangle_id_bound()), -1), std::vector<phat::index>(size_t(K.tet_id_bound()), -1)};
  for (size_t i = 0; i < all.size(); ++i) pos[size_t(all[i].dim)][size_t(all[i].id)] = phat::index(i);

  phat::boundary_matrix<phat::vector_vector> M;
  M.set_num_cols(phat::index(all.size()));
  std::vector<phat::index> col;
  for (size_t i = 0; i < all.size(); ++i) {
    const Simplex& s = all[i];
    col.clear();
    if (s.dim == 1) {
      for (Id v : K.edge_vertices(s.id)) col.push_back(pos[0][size_t(v)]);
    } else if (s.dim == 2) {
      for (Id e : K.triangle_edges(s.id)) col.push_back(pos[1][size_t(e)]);
    } else if (s.dim == 3) {
      for (Id t : K.tet_triangles(s.id)) col.push_back(pos[2][size_t(t)]);
    }
    for (auto c : col)
      if (c < 0 || c >= phat::index(i)) throw std::logic_error("oracle: a face is missing or comes after its coface");
    std::sort(col.begin(), col.end());
    M.set_dim(phat::index(i), phat::dimension(s.dim));
    M.set_col(phat::index(i), col);
  }

  phat::persistence_pairs P;
  phat::compute_persistence_pairs<phat::twist_reduction>(P, M);
  std::vector<char> paired(all.size(), 0);
  out.total_pairs = P.get_num_pairs();
  for (phat::index k = 0; k < P.get_num_pairs(); ++k) {
    auto [b, d] = P.get_pair(k);
    paired[size_t(b)] = paired[size_t(d)] = 1;
    const Simplex& sb = all[size_t(b)];
    const Simplex& sd = all[size_t(d)];
    if (sb.desc[0] == sd.desc[0]) continue;  // inside one lower star
    OraclePair p;
    p.dim = sb.dim;
    p.birth_simplex = sb.id;
    p.death_simplex = sd.id;
    p.birth_vertex = sb.desc[0];
    p.death_vertex = sd.desc[0];
    p.birth = f[p.birth_vertex];
    p.death = f[p.death_vertex];
    out.pairs.push_back(p);
  }
  for (size_t i = 0; i < all.size(); ++i)
    if (!paired[i]) {
      OraclePair p;
      p.dim = all[i].dim;
      p.birth_simplex = all[i].id;
      p.birth_vertex = all[i].desc[0];
      p.birth = f[p.birth_vertex];
      p.death = std::numeric_limits<float>::infinity();
      out.essential.push_back(p);
    }
  std::sort(out.pairs.begin(), out.pairs.end());
  std::sort(out.essential.begin(), out.essential.end());
  return out;
}

// Describes the differences between two sorted lists: the first `max_lines` entries present in only
// one of them. Empty when they are equal.
inline std::string diff(const std::vector<OraclePair>& expected, const std::vector<OraclePair>& actual,
                        const FreudenthalComplex& K, size_t max_lines = 12) {
  std::ostringstream s;
  size_t i = 0, j = 0, shown = 0, missing = 0, extra = 0;
  while (i < expected.size() || j < actual.size()) {
    bool take_e = j >= actual.size() || (i < expected.size() && expected[i] < actual[j]);
    bool take_a = i >= expected.size() || (j < actual.size() && actual[j] < expected[i]);
    if (!take_e && !take_a) {  // same key
      if (!(expected[i] == actual[j])) {
        if (shown++ < max_lines)
          s << "  differs: PHAT   " << to_string(expected[i], K) << "\n           engine " << to_string(actual[j], K) << "\n";
        ++missing, ++extra;
      }
      ++i, ++j;
    } else if (take_e) {
      if (shown++ < max_lines) s << "  only in PHAT:   " << to_string(expected[i], K) << "\n";
      ++missing, ++i;
    } else {
      if (shown++ < max_lines) s << "  only in engine: " << to_string(actual[j], K) << "\n";
      ++extra, ++j;
    }
  }
  if (shown == 0) return "";
  std::ostringstream head;
  head << missing << " PHAT entries not matched, " << extra << " engine entries not matched (PHAT "
       << expected.size() << ", engine " << actual.size() << "):\n";
  return head.str() + s.str() + (shown > max_lines ? "  ...\n" : "");
}

}  // namespace chokeloops::oracle

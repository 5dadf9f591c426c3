#include "chokeloops/tet/tet_persistence.h"

#include <phat/algorithms/twist_reduction.h>
#include <phat/boundary_matrix.h>
#include <phat/compute_persistence_pairs.h>
#include <phat/representations/default_representations.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>

#include "chokeloops/grid.h"

namespace chokeloops {

namespace {

// A simplex as the ranks of its vertices, high to low, padded with -1: sorting these lexicographically gives the
// filtration (a face comes before its cofaces: it is a prefix, or is smaller at the first vertex it lacks).
using Key = std::array<std::int32_t, 4>;

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

TetDiagram tet_lower_star_persistence(std::int32_t vertex_count, const std::vector<std::array<std::int32_t, 4>>& tets,
                                      const std::vector<double>& values, const std::vector<char>* inside_tets) {
  if (inside_tets && inside_tets->size() != tets.size()) throw InternalError("tet persistence: one inside flag per tet expected");
  if (values.size() != std::size_t(vertex_count)) throw InternalError("tet persistence: one value per vertex expected");
  for (double v : values)
    if (!std::isfinite(v)) throw Error("tet persistence: a vertex value is not finite");
  const auto t0 = std::chrono::steady_clock::now();
  TetDiagram diagram;
  std::vector<std::int32_t> by_rank(static_cast<std::size_t>(vertex_count)), rank(static_cast<std::size_t>(vertex_count));
  std::iota(by_rank.begin(), by_rank.end(), 0);
  std::sort(by_rank.begin(), by_rank.end(), [&](std::int32_t a, std::int32_t b) {
    return values[std::size_t(a)] != values[std::size_t(b)] ? values[std::size_t(a)] < values[std::size_t(b)] : a < b;
  });
  for (std::int32_t r = 0; r < vertex_count; ++r) rank[std::size_t(by_rank[std::size_t(r)])] = r;

  // Each simplex with whether it is a face of an inside tet (in the closed solid).
  struct Entry {
    Key key;
    char in_solid;
    bool operator<(const Entry& o) const { return key < o.key; }
  };
  std::vector<Entry> entries;
  entries.reserve(std::size_t(vertex_count) + tets.size() * 15);
  for (std::int32_t r = 0; r < vertex_count; ++r) entries.push_back({{r, -1, -1, -1}, 0});
  for (std::size_t ti = 0; ti < tets.size(); ++ti) {
    const auto& t = tets[ti];
    const char in = inside_tets ? (*inside_tets)[ti] : 0;
    std::array<std::int32_t, 4> r{rank[std::size_t(t[0])], rank[std::size_t(t[1])], rank[std::size_t(t[2])], rank[std::size_t(t[3])]};
    std::sort(r.begin(), r.end(), std::greater<>());
    entries.push_back({{r[0], r[1], r[2], r[3]}, in});
    for (int a = 0; a < 4; ++a) {
      entries.push_back({{r[std::size_t(a)], -1, -1, -1}, in});
      for (int b = a + 1; b < 4; ++b) {
        entries.push_back({{r[std::size_t(a)], r[std::size_t(b)], -1, -1}, in});
        for (int c = b + 1; c < 4; ++c) entries.push_back({{r[std::size_t(a)], r[std::size_t(b)], r[std::size_t(c)], -1}, in});
      }
    }
  }
  tbb::parallel_sort(entries.begin(), entries.end());
  std::vector<Key> keys;
  std::vector<char> in_solid;
  for (const Entry& e : entries) {
    if (!keys.empty() && keys.back() == e.key) {
      in_solid.back() |= e.in_solid;
      continue;
    }
    keys.push_back(e.key);
    in_solid.push_back(e.in_solid);
  }
  std::vector<Entry>().swap(entries);
  // With the solid given, a simplex outside it whose vertices are all at or below 0 (all on the surface: a
  // simplex with a vertex strictly inside lies inside, the surface being a subcomplex) enters just after level
  // 0, at "0+": else it would join the solid's sublevel set. The filtration: by where a simplex enters (twice its
  // highest rank; 2 z - 1 for "0+", z the count of vertices at or below 0), then key: within one entry point the
  // keys' order is a filtration too (a "0+" simplex's faces are in the solid, earlier, or "0+" and smaller). The
  // keys being sorted, that order is a stable partition: those below z not at "0+", those at "0+", the rest.
  const std::int32_t z = std::int32_t(std::upper_bound(by_rank.begin(), by_rank.end(), 0.0, [&](double x, std::int32_t v) {
                                        return x < values[std::size_t(v)];
                                      }) - by_rank.begin());
  auto dim_of = [](const Key& k) { return k[3] >= 0 ? 3 : k[2] >= 0 ? 2 : k[1] >= 0 ? 1 : 0; };
  std::vector<char> at_zero_plus(keys.size(), 0);
  if (inside_tets)
    for (std::size_t i = 0; i < keys.size(); ++i) at_zero_plus[i] = !in_solid[i] && keys[i][0] < z;
  auto enters = [&](std::size_t i) { return at_zero_plus[i] ? 2 * std::int64_t(z) - 1 : 2 * std::int64_t(keys[i][0]); };
  std::vector<std::int64_t> order;  // filtration position -> key index
  order.reserve(keys.size());
  const std::size_t below_z = std::size_t(std::lower_bound(keys.begin(), keys.end(), Key{z, -1, -1, -1}) - keys.begin());
  for (std::size_t i = 0; i < below_z; ++i)
    if (!at_zero_plus[i]) order.push_back(std::int64_t(i));
  for (std::size_t i = 0; i < below_z; ++i)
    if (at_zero_plus[i]) order.push_back(std::int64_t(i));
  for (std::size_t i = below_z; i < keys.size(); ++i) order.push_back(std::int64_t(i));
  std::vector<phat::index> position(keys.size());
  for (std::size_t p = 0; p < order.size(); ++p) position[std::size_t(order[p])] = phat::index(p);
  // A face is searched among the keys of its highest vertex only (a contiguous range of the sorted keys).
  std::vector<std::int64_t> first_of(std::size_t(vertex_count) + 1, 0);
  for (std::size_t i = keys.size(); i-- > 0;) first_of[std::size_t(keys[i][0])] = std::int64_t(i);
  first_of[std::size_t(vertex_count)] = std::int64_t(keys.size());
  auto index_of = [&](const Key& k) {
    const auto lo = keys.begin() + first_of[std::size_t(k[0])], hi = keys.begin() + first_of[std::size_t(k[0]) + 1];
    const auto it = std::lower_bound(lo, hi, k);
    if (it == hi || *it != k) throw InternalError("tet persistence: a face of a simplex is missing");
    return position[std::size_t(it - keys.begin())];
  };
  // A column has at most 4 entries (a tet's faces): kept in fixed slots, computed in parallel, then handed to
  // PHAT one by one (a vector per column took the armadillo to 682 MB peak RSS, 557 MB so).
  std::vector<std::array<phat::index, 4>> columns(keys.size());
  std::vector<phat::dimension> dims(keys.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, order.size(), 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t p = r.begin(); p != r.end(); ++p) {
      const Key& k = keys[std::size_t(order[p])];
      const int d = dim_of(k);
      dims[p] = phat::dimension(d);
      std::array<phat::index, 4>& column = columns[p];
      for (int drop = 0; d > 0 && drop <= d; ++drop) {
        Key face{-1, -1, -1, -1};
        for (int j = 0, n = 0; j <= d; ++j)
          if (j != drop) face[std::size_t(n++)] = k[std::size_t(j)];
        column[std::size_t(drop)] = index_of(face);
      }
      std::sort(column.begin(), column.begin() + (d > 0 ? d + 1 : 0));
    }
  });
  phat::boundary_matrix<phat::bit_tree_pivot_column> matrix;
  matrix.set_num_cols(phat::index(keys.size()));
  std::vector<phat::index> column;
  for (std::size_t p = 0; p < order.size(); ++p) {
    const int d = dims[p];
    ++diagram.simplices[std::size_t(d)];
    matrix.set_dim(phat::index(p), dims[p]);
    column.assign(columns[p].begin(), columns[p].begin() + (d > 0 ? d + 1 : 0));
    matrix.set_col(phat::index(p), column);
  }
  std::vector<std::array<phat::index, 4>>().swap(columns);
  diagram.seconds_build = seconds_since(t0);
  const auto t1 = std::chrono::steady_clock::now();
  phat::persistence_pairs pairs;
  phat::compute_persistence_pairs<phat::twist_reduction>(pairs, matrix);
  diagram.seconds_reduce = seconds_since(t1);

  // The value a simplex enters at (position p in the filtration): its highest vertex's, or "0+".
  const double zero_plus = std::numeric_limits<double>::denorm_min();
  auto value_at = [&](phat::index p) {
    const std::size_t i = std::size_t(order[std::size_t(p)]);
    return at_zero_plus[i] ? zero_plus : values[std::size_t(by_rank[std::size_t(keys[i][0])])];
  };
  auto vertex_of = [&](phat::index p) { return by_rank[std::size_t(keys[std::size_t(order[std::size_t(p)])][0])]; };
  auto simplex_of = [&](phat::index p) {
    std::array<std::int32_t, 4> vs{-1, -1, -1, -1};
    const Key& k = keys[std::size_t(order[std::size_t(p)])];
    for (int j = 0; j < 4 && k[std::size_t(j)] >= 0; ++j) vs[std::size_t(j)] = by_rank[std::size_t(k[std::size_t(j)])];
    return vs;
  };
  std::vector<char> paired(keys.size(), 0);
  for (phat::index p = 0; p < pairs.get_num_pairs(); ++p) {
    const auto [b, d] = pairs.get_pair(p);
    paired[std::size_t(b)] = paired[std::size_t(d)] = 1;
    if (enters(std::size_t(order[std::size_t(b)])) == enters(std::size_t(order[std::size_t(d)]))) continue;  // one lower star
    TetPersistencePair q;
    q.dim = dim_of(keys[std::size_t(order[std::size_t(b)])]);
    q.birth_vertex = vertex_of(b);
    q.death_vertex = vertex_of(d);
    q.birth_simplex = simplex_of(b);
    q.death_simplex = simplex_of(d);
    q.birth = value_at(b);
    q.death = value_at(d);
    diagram.pairs.push_back(q);
  }
  for (std::size_t p = 0; p < keys.size(); ++p)
    if (!paired[p]) {
      TetPersistencePair q;
      q.dim = dim_of(keys[std::size_t(order[p])]);
      q.birth_vertex = vertex_of(phat::index(p));
      q.birth_simplex = simplex_of(phat::index(p));
      q.birth = value_at(phat::index(p));
      q.death = std::numeric_limits<double>::infinity();
      diagram.essential.push_back(q);
    }
  std::stable_sort(diagram.pairs.begin(), diagram.pairs.end(), [](const TetPersistencePair& a, const TetPersistencePair& b) {
    return a.dim != b.dim ? a.dim < b.dim : a.birth < b.birth;
  });
  return diagram;
}

}  // namespace chokeloops

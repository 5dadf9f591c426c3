// Euler tests of the persistence engine, independent of any other persistence code:
//  - V - E + F - T from the closed-form simplex counts equals the enumeration of valid ids, and is 1;
//  - the essential classes give beta0 - beta1 + beta2 = 1 (a box is contractible);
//  - for every threshold t, the Euler characteristic of the sublevel complex {simplices whose highest
//    vertex has value <= t}, counted directly, equals the alternating count of classes alive at t
//    (b <= t < d) implied by the pairs;
//  - the number of dim-0 classes alive at t equals the number of components of {f <= t} found by a
//    breadth-first search over the 14-neighbour graph.
// Plus the per-pair contract: values and highest vertices match the simplices, b <= d, grouped by dim.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <queue>
#include <random>

#include "analytic_fields.h"
#include "chokeloops/topology/persistence.h"

using namespace chokeloops;

namespace {

TEST(PersistenceEuler, SimplexCountsMatchEnumerationAndEulerIsOne) {
  for (auto dims : {std::array<int, 3>{2, 2, 2}, {2, 3, 4}, {5, 2, 3}, {4, 4, 4}, {7, 3, 5}, {2, 9, 2}}) {
    FreudenthalComplex K(dims);
    std::array<Id, 4> n{K.vertex_count(), 0, 0, 0};
    for (Id e = 0; e < K.edge_id_bound(); ++e) n[1] += K.edge_valid(e);
    for (Id t = 0; t < K.triangle_id_bound(); ++t) n[2] += K.triangle_valid(t);
    for (Id T = 0; T < K.tet_id_bound(); ++T) n[3] += K.tet_valid(T);
    auto c = K.simplex_counts();
    EXPECT_EQ(c, n) << dims[0] << "x" << dims[1] << "x" << dims[2];
    EXPECT_EQ(c[0] - c[1] + c[2] - c[3], 1);
  }
  // Large grid: closed forms only.
  FreudenthalComplex K({256, 256, 256});
  auto c = K.simplex_counts();
  EXPECT_EQ(c[0] - c[1] + c[2] - c[3], 1);
}

struct Field {
  std::string name;
  ScalarGrid grid;
};

std::vector<Field> fields() {
  std::vector<Field> f;
  f.push_back({"torus40", sample_field({40, 40, 40}, analytic::torus(0.3, 0.12))});
  f.push_back({"torus_noise40", sample_field({40, 40, 40}, analytic::torus(0.3, 0.12))});
  add_uniform_noise(f.back().grid, 0.02, 7);
  f.push_back({"double_torus40", sample_field({40, 40, 40}, analytic::double_torus())});
  f.push_back({"dumbbell40", sample_field({40, 40, 40}, analytic::dumbbell())});
  f.push_back({"pierced40", sample_field({40, 40, 40}, analytic::pierced_hollow_ball())});
  f.push_back({"tangle40", sample_field({40, 40, 40}, analytic::tangle_cube())});
  f.push_back({"gaussians_17x31x23", sample_field({17, 31, 23}, analytic::random_gaussians(30, 3), {0, 0, 0},
                                                 {1, 30.0 / 16, 22.0 / 16})});
  ScalarGrid plateau;
  plateau.dims = {30, 20, 25};
  std::mt19937 rng(5);
  for (Id i = 0; i < plateau.vertex_count(); ++i) plateau.values.push_back(float(rng() % 3) - 1.f);
  f.push_back({"plateau30x20x25", plateau});
  return f;
}

// Highest-vertex values of every valid simplex, per dimension, sorted.
std::array<std::vector<float>, 4> simplex_entry_values(const ScalarGrid& g) {
  FreudenthalComplex K(g.dims);
  const float* f = g.values.data();
  std::array<std::vector<float>, 4> out;
  out[0].assign(g.values.begin(), g.values.end());
  auto top = [f](auto vs) {
    float m = f[vs[0]];
    for (Id v : vs) m = std::max(m, f[v]);
    return m;
  };
  for (Id e = 0; e < K.edge_id_bound(); ++e)
    if (K.edge_valid(e)) out[1].push_back(top(K.edge_vertices(e)));
  for (Id t = 0; t < K.triangle_id_bound(); ++t)
    if (K.triangle_valid(t)) out[2].push_back(top(K.triangle_vertices(t)));
  for (Id T = 0; T < K.tet_id_bound(); ++T)
    if (K.tet_valid(T)) out[3].push_back(top(K.tet_vertices(T)));
  for (auto& v : out) std::sort(v.begin(), v.end());
  return out;
}

Id count_le(const std::vector<float>& sorted, float t) {
  return Id(std::upper_bound(sorted.begin(), sorted.end(), t) - sorted.begin());
}

// Components of {f <= t} over the 14-neighbour graph.
Id components_below(const ScalarGrid& g, float t) {
  FreudenthalComplex K(g.dims);
  std::vector<char> seen(g.values.size(), 0);
  Id comps = 0;
  std::vector<Id> stack;
  for (Id s = 0; s < g.vertex_count(); ++s) {
    if (seen[size_t(s)] || !(g.values[size_t(s)] <= t)) continue;
    ++comps;
    seen[size_t(s)] = 1;
    stack.push_back(s);
    while (!stack.empty()) {
      Id v = stack.back();
      stack.pop_back();
      auto c = K.coords(v);
      for (int n = 0; n < 14; ++n) {
        if (!K.neighbor_inside(c, n)) continue;
        Id w = v + K.neighbor_delta(n);
        if (!seen[size_t(w)] && g.values[size_t(w)] <= t) {
          seen[size_t(w)] = 1;
          stack.push_back(w);
        }
      }
    }
  }
  return comps;
}

TEST(PersistenceEuler, SublevelEulerCharacteristicsAndComponentsMatchThePairs) {
  for (auto& [name, g] : fields()) {
    SCOPED_TRACE(name);
    auto D = lower_star_persistence(g);
    // Essential classes of a contractible box.
    Id ess[3] = {0, 0, 0};
    for (auto& p : D.essential) {
      ASSERT_GE(p.dim, 0);
      ASSERT_LE(p.dim, 2);
      ess[p.dim]++;
    }
    EXPECT_EQ(ess[0] - ess[1] + ess[2], 1);
    EXPECT_EQ(ess[0], 1);

    auto entry = simplex_entry_values(g);
    std::vector<float> thresholds{0.f};
    std::vector<float> sorted = g.values;
    std::sort(sorted.begin(), sorted.end());
    for (int q = 0; q <= 10; ++q) thresholds.push_back(sorted[size_t(q * (sorted.size() - 1) / 10)]);
    for (float t : thresholds) {
      Id chi = count_le(entry[0], t) - count_le(entry[1], t) + count_le(entry[2], t) - count_le(entry[3], t);
      Id alive[3] = {0, 0, 0};
      for (auto& p : D.pairs)
        if (p.birth <= t && t < p.death) alive[p.dim]++;
      for (auto& p : D.essential)
        if (p.birth <= t) alive[p.dim]++;
      EXPECT_EQ(chi, alive[0] - alive[1] + alive[2]) << "threshold " << t;
      EXPECT_EQ(components_below(g, t), alive[0]) << "threshold " << t;
    }
  }
}

TEST(PersistenceEuler, PairsAreConsistentWithTheirSimplices) {
  for (auto& [name, g] : fields()) {
    SCOPED_TRACE(name);
    FreudenthalComplex K(g.dims);
    const float* f = g.values.data();
    auto D = lower_star_persistence(g);
    EXPECT_EQ(D.dims, g.dims);
    // Vertices of a simplex of dimension dim, highest first, or empty when the id is invalid.
    auto verts = [&](int dim, Id id) -> std::vector<Id> {
      std::vector<Id> v;
      if (dim == 0 && id >= 0 && id < K.vertex_count()) v = {id};
      if (dim == 1 && K.edge_valid(id)) { auto a = K.edge_vertices(id); v.assign(a.begin(), a.end()); }
      if (dim == 2 && K.triangle_valid(id)) { auto a = K.triangle_vertices(id); v.assign(a.begin(), a.end()); }
      if (dim == 3 && K.tet_valid(id)) { auto a = K.tet_vertices(id); v.assign(a.begin(), a.end()); }
      std::sort(v.begin(), v.end(), [f](Id a, Id b) { return vertex_less(f, b, a); });
      return v;
    };
    auto lex_less = [f](const std::vector<Id>& a, const std::vector<Id>& b) {
      for (size_t i = 0; i < std::min(a.size(), b.size()); ++i) {
        if (a[i] == b[i]) continue;
        return vertex_less(f, a[i], b[i]);
      }
      return a.size() < b.size();
    };
    size_t bad = 0;
    for (size_t i = 0; i < D.pairs.size() && bad < 5; ++i) {
      const auto& p = D.pairs[i];
      auto b = verts(p.dim, p.birth_simplex), d = verts(p.dim + 1, p.death_simplex);
      std::string why;
      if (b.empty() || d.empty()) why = "invalid simplex id";
      else if (b[0] != p.birth_vertex || d[0] != p.death_vertex) why = "highest vertex differs from the simplex's";
      else if (p.birth != f[p.birth_vertex] || p.death != f[p.death_vertex]) why = "value differs from the vertex's";
      else if (!(p.birth <= p.death) || !lex_less(b, d)) why = "death simplex does not come after the birth simplex";
      else if (b[0] == d[0]) why = "a pair inside one lower star is reported";
      else if (i > 0 && D.pairs[i - 1].dim > p.dim)  // persistence.h: "grouped by dim"
        why = "pairs are not grouped by dimension (after a pair of dim " + std::to_string(D.pairs[i - 1].dim) + ")";
      if (!why.empty()) {
        ++bad;
        ADD_FAILURE() << "pair " << i << ": dim " << p.dim << " birth " << p.birth << " @" << p.birth_simplex
                      << " (v" << p.birth_vertex << ") death " << p.death << " @" << p.death_simplex << " (v"
                      << p.death_vertex << "): " << why;
      }
    }
    size_t total = 0;
    for (int dim = 0; dim < 3; ++dim) total += D.count(dim);
    EXPECT_EQ(total, D.pairs.size());
  }
}

}  // namespace

// The coordinates of a vertex come from multiply-and-shift divisions: exact for every index below 2^31.
TEST(PersistenceEuler, DivisionByMultiplyAndShiftIsExact) {
  std::mt19937_64 rng(7);
  const std::uint64_t top = (std::uint64_t(1) << 31) - 1;
  for (std::uint64_t d : {std::uint64_t(1), std::uint64_t(2), std::uint64_t(3), std::uint64_t(7), std::uint64_t(255),
                          std::uint64_t(256), std::uint64_t(309), std::uint64_t(309 * 277), std::uint64_t(65537),
                          std::uint64_t(1) << 30, top}) {
    const DivideBy31 div(d);
    std::vector<std::uint64_t> ns = {0, 1, d - 1, d, d + 1, top, top - 1, top - d};
    for (std::uint64_t k = 1; k * d <= top && k < 1000; ++k) ns.insert(ns.end(), {k * d - 1, k * d});
    for (int i = 0; i < 20000; ++i) ns.push_back(rng() & top);
    for (std::uint64_t n : ns)
      if (n <= top) ASSERT_EQ(div(n), n / d) << n << " / " << d;
  }
  const FreudenthalComplex cx({309, 277, 245});
  for (Id v : {Id(0), Id(308), Id(309), Id(309 * 277 - 1), Id(309 * 277), cx.vertex_count() - 1}) {
    auto c = cx.coords(v);
    EXPECT_EQ(cx.vertex(c[0], c[1], c[2]), v);
    EXPECT_TRUE(cx.inside(c[0], c[1], c[2]));
  }
}

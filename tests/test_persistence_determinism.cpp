// The persistence diagram is the same, pair for pair and in the same order, whatever the thread count.
#include <gtest/gtest.h>

#include <random>

#include <tbb/global_control.h>

#include "analytic_fields.h"
#include "chokeloops/topology/persistence.h"

using namespace chokeloops;

namespace {

PersistenceDiagram run_with_threads(const ScalarGrid& g, int threads) {
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(threads));
  return lower_star_persistence(g);
}

bool same_pair(const PersistencePair& a, const PersistencePair& b) {
  return a.dim == b.dim && a.birth == b.birth && a.death == b.death && a.birth_simplex == b.birth_simplex &&
         a.death_simplex == b.death_simplex && a.birth_vertex == b.birth_vertex && a.death_vertex == b.death_vertex;
}

void expect_same(const PersistenceDiagram& a, const PersistenceDiagram& b) {
  EXPECT_EQ(a.dims, b.dims);
  ASSERT_EQ(a.pairs.size(), b.pairs.size());
  ASSERT_EQ(a.essential.size(), b.essential.size());
  size_t bad = 0;
  for (size_t i = 0; i < a.pairs.size() && bad < 5; ++i)
    if (!same_pair(a.pairs[i], b.pairs[i])) {
      ++bad;
      ADD_FAILURE() << "pair " << i << " differs: dim " << a.pairs[i].dim << " @" << a.pairs[i].birth_simplex << "->"
                    << a.pairs[i].death_simplex << " vs dim " << b.pairs[i].dim << " @" << b.pairs[i].birth_simplex
                    << "->" << b.pairs[i].death_simplex;
    }
  for (size_t i = 0; i < a.essential.size(); ++i) EXPECT_TRUE(same_pair(a.essential[i], b.essential[i]));
}

TEST(PersistenceDeterminism, OneAndManyThreadsGiveTheSameDiagram) {
  std::vector<std::pair<std::string, ScalarGrid>> fields;
  fields.push_back({"torus_noise64", sample_field({64, 64, 64}, analytic::torus(0.3, 0.12))});
  add_uniform_noise(fields.back().second, 0.02, 1);
  fields.push_back({"gaussians48", sample_field({48, 48, 48}, analytic::random_gaussians(30, 11))});
  ScalarGrid plateau;
  plateau.dims = {41, 37, 33};
  std::mt19937 rng(3);
  for (Id i = 0; i < plateau.vertex_count(); ++i) plateau.values.push_back(float(rng() % 3));
  fields.push_back({"plateau012_41x37x33", plateau});
  for (auto& [name, g] : fields) {
    SCOPED_TRACE(name);
    auto one = run_with_threads(g, 1);
    auto two = run_with_threads(g, 2);
    auto four = run_with_threads(g, 4);
    EXPECT_GT(one.pairs.size(), 0u);
    expect_same(one, two);
    expect_same(one, four);
  }
}

}  // namespace

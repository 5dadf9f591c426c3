// The memory guard of lower_star_persistence: its estimate comes from the classification's counts, so a
// rough field is refused (exit code 3, before the pairs are allocated) where a smooth one of the same size
// fits, and the estimate grows with the number of pairs, not with the grid alone.
#include <gtest/gtest.h>

#include <string>

#include "chokeloops/field/analytic.h"
#include "chokeloops/topology/persistence.h"

using namespace chokeloops;

TEST(PersistenceMemoryGuard, RoughFieldOverBudgetIsRefusedWhereASmoothOneFits) {
  const ScalarGrid smooth = sample_field({96, 96, 96}, analytic::torus(0.3, 0.12));
  ScalarGrid rough = smooth;
  add_uniform_noise(rough, 0.1, 7);
  const PersistenceDiagram ds = lower_star_persistence(smooth), dr = lower_star_persistence(rough);
  const std::size_t es = ds.stats.estimated_bytes, er = dr.stats.estimated_bytes;
  ASSERT_GT(dr.pairs.size(), 20000u);
  // at least the bytes of the diagram it returns, and more for the rough field by about that much
  EXPECT_GE(er, dr.pairs.size() * sizeof(PersistencePair));
  EXPECT_GT(er - es, dr.pairs.size() * sizeof(PersistencePair));
  const std::size_t budget = (es + er) / 2;
  EXPECT_NO_THROW(lower_star_persistence(smooth, {}, budget));
  try {
    lower_star_persistence(rough, {}, budget);
    FAIL() << "the rough field fitted a budget below its estimate";
  } catch (const Error& e) {
    EXPECT_EQ(e.exit_code, 3);
    const std::string m = e.what();
    EXPECT_NE(m.find("96x96x96"), std::string::npos) << m;
    EXPECT_NE(m.find("rough"), std::string::npos) << m;
    EXPECT_NE(m.find("--max-memory"), std::string::npos) << m;
  }
}

// Oracle test of the lower-star persistence engine: on many small random fields (random values, large
// plateaus, constant fields, smooth fields plus noise, anisotropic boxes) the engine's pairs must equal
// those of PHAT on the explicit filtered complex exactly: same dimension, same birth and death
// simplices, same values, same essential classes.
//
// Set CHOKELOOPS_ORACLE_FAILURES=/path/file to append every failing case (dims, values, diff) there.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <random>
#include <sstream>
#include <tuple>

#include "analytic_fields.h"
#include "chokeloops/topology/persistence.h"
#include "phat_oracle.h"

using namespace chokeloops;
using oracle::OraclePair;

namespace {

enum class Kind { Uniform, Plateau3, Plateau2, Constant, SmoothNoise, Quantized, Integers };
const char* kind_name(Kind k) {
  switch (k) {
    case Kind::Uniform: return "uniform";
    case Kind::Plateau3: return "plateau012";
    case Kind::Plateau2: return "plateau01";
    case Kind::Constant: return "constant";
    case Kind::SmoothNoise: return "smoothnoise";
    case Kind::Quantized: return "quantized";
    case Kind::Integers: return "int0to9";
  }
  return "?";
}

struct Case {
  std::array<int, 3> dims;
  Kind kind;
  unsigned seed;
};

double unit01(std::mt19937& rng) { return double(rng() >> 8) * (1.0 / 16777216.0); }

ScalarGrid make_field(const Case& c) {
  ScalarGrid g;
  g.dims = c.dims;
  g.values.resize(size_t(g.vertex_count()));
  std::mt19937 rng(c.seed);
  // Smooth part: a few random low-frequency modes over the box.
  double a[4][4];
  for (auto& m : a)
    for (auto& x : m) x = unit01(rng) * 2 - 1;
  auto smooth = [&](int i, int j, int k) {
    double x = double(i) / c.dims[0], y = double(j) / c.dims[1], z = double(k) / c.dims[2];
    double s = 0;
    for (int m = 0; m < 4; ++m)
      s += a[m][0] * std::sin(6.2831853 * ((m + 1) * a[m][1] * x + (m + 1) * a[m][2] * y + (m + 1) * a[m][3] * z) + m);
    return s;
  };
  const float constant = float(std::floor(unit01(rng) * 10) - 5) * 0.5f;
  for (int k = 0; k < c.dims[2]; ++k)
    for (int j = 0; j < c.dims[1]; ++j)
      for (int i = 0; i < c.dims[0]; ++i) {
        float v = 0;
        switch (c.kind) {
          case Kind::Uniform: v = float(unit01(rng) * 2 - 1); break;
          case Kind::Plateau3: v = float(rng() % 3); break;
          case Kind::Plateau2: v = float(unit01(rng) < 0.7 ? 0 : 1); break;
          case Kind::Constant: v = constant; break;
          case Kind::SmoothNoise: v = float(smooth(i, j, k) + 0.1 * (unit01(rng) * 2 - 1)); break;
          case Kind::Quantized: v = float(std::round(2 * smooth(i, j, k))); break;
          case Kind::Integers: v = float(rng() % 10); break;
        }
        g.values[size_t(g.index(i, j, k))] = v;
      }
  return g;
}

std::vector<Case> all_cases() {
  const std::array<int, 3> shapes[] = {{2, 2, 2},  {2, 3, 4},  {3, 3, 3},  {4, 3, 2},   {2, 2, 12}, {12, 2, 2},
                                       {2, 12, 3}, {5, 5, 5},  {3, 7, 2},  {6, 6, 6},   {8, 5, 3},  {7, 7, 7},
                                       {4, 9, 11}, {10, 10, 10}, {12, 12, 12}, {12, 4, 9}, {9, 12, 5}, {11, 6, 12}};
  const Kind kinds[] = {Kind::Uniform,     Kind::Plateau3,  Kind::Plateau2, Kind::Constant,
                        Kind::SmoothNoise, Kind::Quantized, Kind::Integers};
  std::vector<Case> cases;
  unsigned seed = 1;
  for (auto& s : shapes)
    for (Kind k : kinds) cases.push_back({s, k, 1000 + 7919 * seed++});
  // A few larger ones (beyond 12^3): longer dim-1 reduction chains.
  cases.push_back({{16, 16, 16}, Kind::Uniform, 5});
  cases.push_back({{20, 17, 13}, Kind::Plateau3, 6});
  cases.push_back({{24, 8, 16}, Kind::SmoothNoise, 7});
  cases.push_back({{18, 18, 18}, Kind::Quantized, 8});
  cases.push_back({{20, 20, 20}, Kind::Integers, 9});
  cases.push_back({{32, 6, 5}, Kind::Uniform, 10});
  return cases;
}

std::string case_name(const Case& c) {
  return "n" + std::to_string(c.dims[0]) + "x" + std::to_string(c.dims[1]) + "x" + std::to_string(c.dims[2]) + "_" +
         kind_name(c.kind) + "_s" + std::to_string(c.seed);
}
// Names the parameter in ctest output (instead of its bytes).
void PrintTo(const Case& c, std::ostream* os) { *os << case_name(c); }

std::vector<OraclePair> convert(const std::vector<PersistencePair>& v) {
  std::vector<OraclePair> out;
  for (auto& p : v) {
    OraclePair o;
    o.dim = p.dim;
    o.birth_simplex = p.birth_simplex;
    o.death_simplex = p.death_simplex;
    o.birth_vertex = p.birth_vertex;
    o.death_vertex = p.death_vertex;
    o.birth = p.birth;
    o.death = p.death;
    out.push_back(o);
  }
  std::sort(out.begin(), out.end());
  return out;
}

void record_failure(const std::string& name, const ScalarGrid& g, const std::string& diff) {
  const char* path = std::getenv("CHOKELOOPS_ORACLE_FAILURES");
  if (!path) return;
  std::ofstream out(path, std::ios::app);
  out << "case " << name << " dims " << g.dims[0] << "x" << g.dims[1] << "x" << g.dims[2] << "\nvalues (x fastest):";
  for (float v : g.values) out << " " << v;
  out << "\n" << diff << "\n";
}

// Compares the engine with PHAT on `g`; returns "" when they agree, else a description.
std::string compare_with_oracle(const ScalarGrid& g) {
  FreudenthalComplex K(g.dims);
  auto expected = oracle::phat_persistence(g);
  auto diagram = lower_star_persistence(g);
  std::string out;
  if (diagram.dims != g.dims) out += "diagram dims differ from the grid's\n";
  auto d = oracle::diff(expected.pairs, convert(diagram.pairs), K);
  if (!d.empty()) out += "finite pairs: " + d;
  auto e = oracle::diff(expected.essential, convert(diagram.essential), K);
  if (!e.empty()) out += "essential classes: " + e;
  for (auto& p : diagram.essential)
    if (!std::isinf(p.death) || p.death_simplex != -1 || p.death_vertex != -1)
      out += "an essential class lacks death = inf / death_simplex = -1\n";
  for (int dim = 0; dim < 3; ++dim) {
    size_t n = 0;
    for (auto& p : diagram.pairs) n += p.dim == dim;
    if (diagram.count(dim) != n) out += "count(" + std::to_string(dim) + ") disagrees with pairs\n";
  }
  return out;
}

class Oracle : public ::testing::TestWithParam<Case> {};

TEST_P(Oracle, EngineEqualsPhat) {
  const Case& c = GetParam();
  ScalarGrid g = make_field(c);
  std::string d = compare_with_oracle(g);
  if (!d.empty()) record_failure(case_name(c), g, d);
  EXPECT_TRUE(d.empty()) << case_name(c) << ":\n" << d;
}

INSTANTIATE_TEST_SUITE_P(RandomFields, Oracle, ::testing::ValuesIn(all_cases()),
                         [](const ::testing::TestParamInfo<Case>& info) { return case_name(info.param); });

// The oracle itself: on a box (contractible) exactly one essential class, of dimension 0, at the global
// minimum; the alternating count of simplices matches the closed-form counts.
TEST(OracleSelfCheck, BoxHasOneEssentialClassAtTheMinimum) {
  for (const Case& c : all_cases()) {
    if (c.dims[0] * c.dims[1] * c.dims[2] > 300) continue;
    ScalarGrid g = make_field(c);
    auto o = oracle::phat_persistence(g);
    ASSERT_EQ(o.essential.size(), 1u) << case_name(c);
    EXPECT_EQ(o.essential[0].dim, 0);
    Id vmin = 0;
    for (Id v = 1; v < g.vertex_count(); ++v)
      if (vertex_less(g.values.data(), v, vmin)) vmin = v;
    EXPECT_EQ(o.essential[0].birth_simplex, vmin);
    FreudenthalComplex K(g.dims);
    EXPECT_EQ(o.simplex_counts, K.simplex_counts()) << case_name(c);
    Id total = o.simplex_counts[0] + o.simplex_counts[1] + o.simplex_counts[2] + o.simplex_counts[3];
    EXPECT_EQ(2 * o.total_pairs + 1, total);
  }
}

// Sampled shapes (coarse, with and without noise): the pairs of meaning are found by the oracle too.
TEST(OracleShapes, SampledSdfsEqualPhat) {
  std::vector<std::pair<std::string, ScalarGrid>> f;
  f.push_back({"torus16", sample_field({16, 16, 16}, analytic::torus(0.3, 0.12))});
  f.push_back({"torus_noise18", sample_field({18, 18, 18}, analytic::torus(0.3, 0.12))});
  add_uniform_noise(f.back().second, 0.02, 5);
  f.push_back({"double_torus20", sample_field({20, 20, 20}, analytic::double_torus())});
  f.push_back({"dumbbell_21x11x11", sample_field({21, 11, 11}, analytic::dumbbell(), {0, 0.25, 0.25}, {1, 0.75, 0.75})});
  f.push_back({"pierced20", sample_field({20, 20, 20}, analytic::pierced_hollow_ball())});
  f.push_back({"tangle18", sample_field({18, 18, 18}, analytic::tangle_cube())});
  f.push_back({"gaussians_noise16", sample_field({16, 16, 16}, analytic::random_gaussians(30, 9))});
  add_uniform_noise(f.back().second, 0.05, 9);
  for (auto& [name, g] : f) {
    std::string d = compare_with_oracle(g);
    if (!d.empty()) record_failure(name, g, d);
    EXPECT_TRUE(d.empty()) << name << ":\n" << d;
  }
}

// A rough field as the bench's noise case is at 256^3 (noise of several voxels, the dimension-1 pairs in their
// thousands), large enough that many dim-1 columns need additions after their first reduction: each of the
// engine's two dim-1 phases is compared pair for pair.
TEST(OracleShapes, RoughTorusAt40CubedEqualsPhat) {
  ScalarGrid g = sample_field({40, 40, 40}, analytic::torus(0.3, 0.12));
  add_uniform_noise(g, 0.1, 2026);
  const PersistenceDiagram d = lower_star_persistence(g);
  EXPECT_GT(d.count(1), 3000u);
  EXPECT_EQ(d.stats.dim1_lazy_columns, 0);  // rough: every column reduced in full in the parallel pass
  std::string diff = compare_with_oracle(g);
  if (!diff.empty()) record_failure("torus_rough40", g, diff);
  EXPECT_TRUE(diff.empty()) << diff;
}

// A smooth field with sub-voxel noise (what filtering and segmentations give): long columns, few additions, so
// the parallel pass leaves most columns partly reduced and the sequential pass reduces them on a heap only as
// far as it must, adding lazy owners from their triangles.
TEST(OracleShapes, SmoothFieldWithSparseNoiseReducedLazilyEqualsPhat) {
  ScalarGrid g = sample_field({48, 48, 48}, analytic::tangle_cube());
  add_uniform_noise(g, 0.32 * g.voxel_size, 7);
  const PersistenceDiagram d = lower_star_persistence(g);
  EXPECT_GT(d.count(1), 100u);
  EXPECT_GT(d.stats.dim1_lazy_columns, 0);
  std::string diff = compare_with_oracle(g);
  if (!diff.empty()) record_failure("tangle_sparse_noise48", g, diff);
  EXPECT_TRUE(diff.empty()) << diff;
}

// -0.0 and +0.0 are equal values: the order between them is by linear index only (vertex_less).
TEST(OracleEdgeCases, SignedZerosAreEqualValues) {
  for (unsigned seed : {11u, 12u, 13u}) {
    ScalarGrid g;
    g.dims = {5, 4, 6};
    g.values.resize(size_t(g.vertex_count()));
    std::mt19937 rng(seed);
    for (auto& v : g.values) {
      unsigned r = rng() % 4;
      v = r == 0 ? -0.0f : r == 1 ? 0.0f : r == 2 ? 1.0f : -1.0f;
    }
    std::string d = compare_with_oracle(g);
    if (!d.empty()) record_failure("signed_zeros_s" + std::to_string(seed), g, d);
    EXPECT_TRUE(d.empty()) << "signed zeros, seed " << seed << ":\n" << d;
  }
}

// Extreme and tiny magnitudes (denormals, +-FLT_MAX) are ordinary finite values.
TEST(OracleEdgeCases, ExtremeMagnitudes) {
  ScalarGrid g;
  g.dims = {4, 5, 3};
  g.values.resize(size_t(g.vertex_count()));
  std::mt19937 rng(99);
  const float choices[] = {std::numeric_limits<float>::max(), -std::numeric_limits<float>::max(),
                           std::numeric_limits<float>::denorm_min(), -std::numeric_limits<float>::denorm_min(),
                           1e-30f, 0.0f, 3.0f};
  for (auto& v : g.values) v = choices[rng() % 7];
  std::string d = compare_with_oracle(g);
  if (!d.empty()) record_failure("extreme_magnitudes", g, d);
  EXPECT_TRUE(d.empty()) << d;
}

}  // namespace

// A second, independent oracle: TTK's DiscreteMorseSandwich (tests/fixtures/ttk/README.md). TTK ran on the
// field mirrored along x, where its triangulation is ours, so the pairs must be equal as values, exactly.
TEST(OracleTtk, RoughFieldEqualsTtkOnTheMirroredField) {
  const std::string dir = std::string(CHOKELOOPS_SOURCE_DIR) + "/tests/fixtures/ttk/";
  ScalarGrid g;
  g.dims = {28, 24, 20};
  g.values.resize(28 * 24 * 20);
  std::ifstream field(dir + "rough_torus_28x24x20.f32", std::ios::binary);
  field.read(reinterpret_cast<char*>(g.values.data()), std::streamsize(g.values.size() * sizeof(float)));
  ASSERT_TRUE(field.good());
  using Triple = std::tuple<int, float, float>;
  std::vector<Triple> ttk;
  std::ifstream csv(dir + "rough_torus_28x24x20.ttk_pairs.csv");
  int dim;
  float birth, death;
  char c1, c2;
  while (csv >> dim >> c1 >> birth >> c2 >> death) ttk.emplace_back(dim, birth, death);
  ASSERT_EQ(ttk.size(), 560u);
  auto diagram_of = [](const ScalarGrid& grid) {
    std::vector<Triple> out;
    for (auto& p : lower_star_persistence(grid).pairs) out.emplace_back(p.dim, p.birth, p.death);
    std::sort(out.begin(), out.end());
    return out;
  };
  std::sort(ttk.begin(), ttk.end());
  const std::vector<Triple> ours = diagram_of(g);
  EXPECT_EQ(std::count_if(ours.begin(), ours.end(), [](const Triple& t) { return std::get<0>(t) == 1; }), 466);
  EXPECT_EQ(ours, ttk);
  // The triangulation matters: on the field mirrored along x (TTK's input), chokeloops' diagram differs.
  ScalarGrid mirrored = g;
  for (int k = 0; k < 20; ++k)
    for (int j = 0; j < 24; ++j)
      for (int i = 0; i < 28; ++i)
        mirrored.values[std::size_t((k * 24 + j) * 28 + i)] = g.values[std::size_t((k * 24 + j) * 28 + 27 - i)];
  EXPECT_NE(diagram_of(mirrored), ttk);
}

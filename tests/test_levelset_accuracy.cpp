// Distance accuracy of mesh → signed distance on meshed spheres and tori of known radius.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>

#include <tbb/global_control.h>

#include "chokeloops/field/levelset.h"
#include "chokeloops/io/mesh_io.h"
#include "mesh_shapes.h"

using namespace chokeloops;

namespace {

// Icosphere: 20 * 4^sub triangles on the sphere of radius r centred at c.
TriangleMesh icosphere(double r, std::array<double, 3> c, int sub) {
  const double t = (1 + std::sqrt(5.0)) / 2;
  std::vector<std::array<double, 3>> v{{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                                       {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  std::vector<std::array<int, 3>> f{{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                    {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                    {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                    {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  auto norm = [](std::array<double, 3> p) {
    double l = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    return std::array<double, 3>{p[0] / l, p[1] / l, p[2] / l};
  };
  for (auto& p : v) p = norm(p);
  for (int s = 0; s < sub; ++s) {
    std::map<std::pair<int, int>, int> mid;
    auto midpoint = [&](int a, int b) {
      auto key = std::make_pair(std::min(a, b), std::max(a, b));
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      v.push_back(norm({(v[a][0] + v[b][0]) / 2, (v[a][1] + v[b][1]) / 2, (v[a][2] + v[b][2]) / 2}));
      return mid[key] = int(v.size()) - 1;
    };
    std::vector<std::array<int, 3>> nf;
    for (auto& tri : f) {
      int a = midpoint(tri[0], tri[1]), b = midpoint(tri[1], tri[2]), cc = midpoint(tri[2], tri[0]);
      nf.push_back({tri[0], a, cc});
      nf.push_back({tri[1], b, a});
      nf.push_back({tri[2], cc, b});
      nf.push_back({a, b, cc});
    }
    f.swap(nf);
  }
  TriangleMesh m;
  for (auto& p : v) m.vertices.push_back({c[0] + r * p[0], c[1] + r * p[1], c[2] + r * p[2]});
  m.faces = f;
  return m;
}

struct Errors {
  double near = 0, deep = 0, far_out = 0;
  std::size_t n_near = 0, n_deep = 0, n_out = 0, wrong_sign = 0;
};

template <class Exact>
Errors measure(const ScalarGrid& g, Exact exact) {
  Errors e;
  const double h = g.voxel_size;
  for (int k = 0; k < g.dims[2]; ++k)
    for (int j = 0; j < g.dims[1]; ++j)
      for (int i = 0; i < g.dims[0]; ++i) {
        auto x = g.world({i, j, k});
        const double d = exact(x);
        const double phi = g.values[g.index(i, j, k)];
        const double err = std::abs(phi - d);
        if (std::abs(d) > 0.5 * h && (phi < 0) != (d < 0)) ++e.wrong_sign;
        if (std::abs(d) <= 2 * h) {
          e.near = std::max(e.near, err);
          ++e.n_near;
        } else if (d < 0) {
          if (err > e.deep && std::getenv("CHOKELOOPS_TEST_VERBOSE"))
            std::printf("  deep max so far: (%d,%d,%d) d=%.3f phi=%.3f h\n", i, j, k, d / h, phi / h);
          e.deep = std::max(e.deep, err);
          ++e.n_deep;
        } else {
          if (err > e.far_out && std::getenv("CHOKELOOPS_TEST_VERBOSE"))
            std::printf("  out max so far: (%d,%d,%d) d=%.3f phi=%.3f h\n", i, j, k, d / h, phi / h);
          e.far_out = std::max(e.far_out, err);
          ++e.n_out;
        }
      }
  return e;
}

}  // namespace

TEST(LevelSetAccuracy, SphereAt128) {
  const double r = 1.0;
  TriangleMesh m = icosphere(r, {0.3, -0.2, 0.1}, 6);  // 81920 faces: sagitta ~1e-3 voxel
  LevelSetOptions o;
  o.resolution = 128;
  o.quiet = true;
  LevelSetResult res = mesh_to_levelset(m, o, "sphere");
  const ScalarGrid& g = res.grid;
  const double h = g.voxel_size;
  EXPECT_NEAR(h, 2.0 / 128, 1e-3);
  EXPECT_TRUE(res.report.closed);
  EXPECT_EQ(res.report.genus, 0);
  EXPECT_EQ(res.report.components, 1u);
  // padded box: margin = 10% of the diameter on each side
  EXPECT_GE(g.dims[0], 128 + 2 * 12);
  Errors e = measure(g, [&](std::array<double, 3> x) {
    double dx = x[0] - 0.3, dy = x[1] + 0.2, dz = x[2] - 0.1;
    return std::sqrt(dx * dx + dy * dy + dz * dz) - r;
  });
  std::printf("sphere 128: max error near %.3f voxel, deep inside %.3f voxel, outside %.3f voxel (%zu/%zu/%zu)\n",
              e.near / h, e.deep / h, e.far_out / h, e.n_near, e.n_deep, e.n_out);
  EXPECT_EQ(e.wrong_sign, 0u);
  EXPECT_LE(e.near, 0.5 * h);
  EXPECT_LE(e.deep, 1.0 * h);
  EXPECT_LE(e.far_out, 1.0 * h);
  EXPECT_GT(res.inside_voxels, 0u);
  EXPECT_EQ(res.inside_voxels + res.outside_voxels, std::size_t(g.vertex_count()));
}

TEST(LevelSetAccuracy, TorusAt128) {
  const double R = 1.0, a = 0.4;
  TriangleMesh m = test::polyhedral_torus(R, a, 720, 288);  // sagitta ~1e-3 voxel
  LevelSetOptions o;
  o.resolution = 128;
  o.quiet = true;
  LevelSetResult res = mesh_to_levelset(m, o, "torus");
  const ScalarGrid& g = res.grid;
  const double h = g.voxel_size;
  EXPECT_TRUE(res.report.closed);
  EXPECT_EQ(res.report.genus, 1);
  Errors e = measure(g, [&](std::array<double, 3> x) {
    double q = std::sqrt(x[0] * x[0] + x[1] * x[1]) - R;
    return std::sqrt(q * q + x[2] * x[2]) - a;
  });
  std::printf("torus 128: max error near %.3f voxel, deep inside %.3f voxel, outside %.3f voxel (%zu/%zu/%zu)\n",
              e.near / h, e.deep / h, e.far_out / h, e.n_near, e.n_deep, e.n_out);
  EXPECT_EQ(e.wrong_sign, 0u);
  EXPECT_LE(e.near, 0.5 * h);
  EXPECT_LE(e.deep, 1.0 * h);
  EXPECT_LE(e.far_out, 1.0 * h);
}

TEST(LevelSetAccuracy, VoxelSizeAndMarginOptions) {
  TriangleMesh m = icosphere(1.0, {0, 0, 0}, 3);
  LevelSetOptions o;
  o.voxel_size = 0.1;
  o.margin = 0.5;
  o.quiet = true;
  LevelSetResult res = mesh_to_levelset(m, o, "sphere");
  EXPECT_DOUBLE_EQ(res.grid.voxel_size, 0.1);
  // [-1.5, 1.5] / 0.1 → 31 vertices (the icosphere's extent is exactly ±1 on at least one axis)
  EXPECT_GE(res.grid.dims[0], 31);
  EXPECT_LE(res.grid.dims[0], 32);
  EXPECT_LE(res.grid.origin[0], -1.5 + 1e-9);
  EXPECT_NEAR(res.margin, 0.5, 1e-12);
}

TEST(LevelSetAccuracy, SameGridWhateverTheThreadCount) {
  // the feature transform and its relaxation run in parallel; the grid must not depend on the split
  TriangleMesh m = test::polyhedral_torus(1.0, 0.4, 180, 72);
  LevelSetOptions o;
  o.resolution = 96;
  o.quiet = true;
  LevelSetResult many = mesh_to_levelset(m, o, "torus");
  LevelSetResult one;
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    one = mesh_to_levelset(m, o, "torus");
  }
  ASSERT_EQ(one.grid.values.size(), many.grid.values.size());
  std::size_t differ = 0;
  for (std::size_t i = 0; i < one.grid.values.size(); ++i) differ += one.grid.values[i] != many.grid.values[i];
  EXPECT_EQ(differ, 0u);
  EXPECT_EQ(one.inside_voxels, many.inside_voxels);
  EXPECT_GT(one.inside_voxels, 0u);
}

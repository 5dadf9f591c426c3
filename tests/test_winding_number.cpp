// Generalised winding number (fast, Barill et al. style) and the sign it gives to meshes that stay open
// after repair.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <random>
#include <string>

#include "chokeloops/field/levelset.h"
#include "chokeloops/io/mesh_io.h"
#include "chokeloops/field/winding_number.h"

using namespace chokeloops;

namespace {

constexpr double kPi = 3.14159265358979323846;

// UV sphere of radius r at c, outward oriented; faces with every vertex above z = c + cap_z * r are left
// out (cap_z >= 1: closed).
TriangleMesh uv_sphere(double r, std::array<double, 3> c, int nu, int nv, double cap_z = 2) {
  TriangleMesh m;
  m.vertices.push_back({c[0], c[1], c[2] + r});  // north pole
  for (int i = 1; i < nv; ++i) {
    const double th = kPi * i / nv;
    for (int j = 0; j < nu; ++j) {
      const double ph = 2 * kPi * j / nu;
      m.vertices.push_back({c[0] + r * std::sin(th) * std::cos(ph), c[1] + r * std::sin(th) * std::sin(ph),
                            c[2] + r * std::cos(th)});
    }
  }
  m.vertices.push_back({c[0], c[1], c[2] - r});  // south pole
  const int south = int(m.vertices.size()) - 1;
  auto ring = [&](int i, int j) { return 1 + (i - 1) * nu + (j + nu) % nu; };
  std::vector<std::array<int, 3>> f;
  for (int j = 0; j < nu; ++j) f.push_back({0, ring(1, j), ring(1, j + 1)});
  for (int i = 1; i < nv - 1; ++i)
    for (int j = 0; j < nu; ++j) {
      f.push_back({ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)});
      f.push_back({ring(i, j), ring(i + 1, j + 1), ring(i, j + 1)});
    }
  for (int j = 0; j < nu; ++j) f.push_back({south, ring(nv - 1, j + 1), ring(nv - 1, j)});
  for (auto& t : f) {
    bool above = true;
    for (int k = 0; k < 3; ++k) above = above && m.vertices[std::size_t(t[k])][2] > c[2] + cap_z * r;
    if (!above) m.faces.push_back(t);
  }
  return m;
}

}  // namespace

TEST(WindingNumber, ClosedSphereInsideOneOutsideZeroTreeMatchesExact) {
  const TriangleMesh m = uv_sphere(1.0, {0.1, -0.2, 0.3}, 64, 32);
  const WindingNumber wn(m);
  EXPECT_NEAR(wn.exact({0.1, -0.2, 0.3}), 1.0, 1e-9);
  EXPECT_NEAR(wn({0.1, -0.2, 0.3}), 1.0, 2e-2);
  EXPECT_NEAR(wn.exact({2.5, 0, 0}), 0.0, 1e-9);
  EXPECT_NEAR(wn({2.5, 0, 0}), 0.0, 1e-2);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-2, 2);
  double worst = 0;
  int n = 0;
  for (int t = 0; t < 2000; ++t) {
    const std::array<double, 3> q{u(rng), u(rng), u(rng)};
    const double r = std::sqrt((q[0] - 0.1) * (q[0] - 0.1) + (q[1] + 0.2) * (q[1] + 0.2) + (q[2] - 0.3) * (q[2] - 0.3));
    if (std::abs(r - 1) < 0.05) continue;  // w jumps across the surface; compare off it
    const double exact = wn.exact(q);
    EXPECT_NEAR(exact, r < 1 ? 1.0 : 0.0, 0.02) << q[0] << " " << q[1] << " " << q[2];
    worst = std::max(worst, std::abs(wn(q) - exact));
    ++n;
  }
  std::printf("winding number, sphere: tree vs exact max difference %.2e over %d points\n", worst, n);
  EXPECT_GT(n, 1000);
  EXPECT_LT(worst, 2e-2);  // far below the 1/2 that decides the sign
  // reversed orientation: -1 inside
  TriangleMesh flipped = m;
  for (auto& f : flipped.faces) std::swap(f[1], f[2]);
  EXPECT_NEAR(WindingNumber(flipped)({0.1, -0.2, 0.3}), -1.0, 2e-2);
}

TEST(WindingNumber, OpenSphereKeepsItsInside) {
  // a sphere without its top cap (z > 0.8 r): OpenVDB's flood fill would run in through the hole
  LevelSetOptions o;
  o.resolution = 64;
  o.quiet = true;
  o.fill_holes = false;
  const LevelSetResult closed = mesh_to_levelset(uv_sphere(1.0, {0, 0, 0}, 96, 48), o, "closed sphere");
  const TriangleMesh open_mesh = uv_sphere(1.0, {0, 0, 0}, 96, 48, 0.8);
  const LevelSetResult open = mesh_to_levelset(open_mesh, o, "open sphere");
  ASSERT_GT(open.report.boundary_edges_remaining, 0u);
  bool named = false;
  for (auto& w : open.warnings)
    named = named || (w.find(std::to_string(open.report.boundary_edges_remaining) + " boundary edges") != std::string::npos &&
                      w.find("winding number") != std::string::npos);
  EXPECT_TRUE(named) << "no warning naming the open boundary edges and the winding number";
  const double ratio = double(open.inside_voxels) / double(closed.inside_voxels);
  std::printf("open sphere: %zu inside voxels, closed %zu (ratio %.4f)\n", open.inside_voxels, closed.inside_voxels,
              ratio);
  // the cap above z = 0.8 is 2.8% of the ball; the winding number closes the hole with a surface
  // between the flat disk and the cap
  EXPECT_GT(ratio, 0.96);
  EXPECT_LT(ratio, 1.01);
  // deep inside is inside, far outside is outside (centre of the box, a corner)
  const ScalarGrid& g = open.grid;
  EXPECT_LT(g.values[std::size_t(g.index(g.dims[0] / 2, g.dims[1] / 2, g.dims[2] / 2))], 0.f);
  EXPECT_GT(g.values[0], 0.f);
}

TEST(WindingNumber, OpenScanWithoutHoleFillingMatchesFilled) {
  const std::string path = std::string(CHOKELOOPS_DATA) + "/meshes/stanford-bunny_scan_ajc.obj";
  ASSERT_TRUE(std::filesystem::exists(path)) << "bundled data missing: " << path;
  LevelSetOptions o;
  o.resolution = 64;
  o.quiet = true;
  const LevelSetResult filled = make_levelset(path, o);
  o.fill_holes = false;
  const LevelSetResult open = make_levelset(path, o);
  ASSERT_GT(open.report.boundary_edges_remaining, 0u);
  EXPECT_EQ(filled.report.boundary_edges_remaining, 0u);
  const double ratio = double(open.inside_voxels) / double(filled.inside_voxels);
  std::printf("open bunny scan at 64: %zu inside voxels without hole filling, %zu with (ratio %.4f)\n",
              open.inside_voxels, filled.inside_voxels, ratio);
  EXPECT_NEAR(ratio, 1.0, 0.02);
}

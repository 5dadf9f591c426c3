#pragma once
// Checks shared by the volume tests (NIfTI/NRRD in test_volume.cpp, MetaImage in test_volume_metaimage.cpp):
// masks of known shapes and where their loops must land.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <utility>

#include "chokeloops/analyze_volume.h"

namespace chokeloops::test {

inline VolumeFieldOptions label(double n) {
  VolumeFieldOptions f;
  f.has_label = true;
  f.label = n;
  return f;
}

inline const Loop* find_loop(const AnalyzeResult& r, Side side, Kind kind) {
  for (auto& l : r.loops)
    if (l.choke.side == side && l.choke.kind == kind && l.found) return &l;
  return nullptr;
}

inline double dist(const std::array<double, 3>& a, const std::array<double, 3>& b) {
  return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

// 1 inside the torus of centre-circle radius R and tube radius r around c (axis along z), else 0.
inline float torus(double x, double y, double z, std::array<double, 3> c, double R, double r) {
  const double q = std::hypot(x - c[0], y - c[1]) - R;
  return std::hypot(q, z - c[2]) <= r ? 1.f : 0.f;
}

// The voxelised torus (radii R, rr; centre at `centre` in world mm) has one handle generator; its tunnel
// loop circles the centre and its handle loop lies on the centre circle, with metric lengths (mm) of the
// two circles (the voxelised tube is ~half a voxel fatter). Returns {handle loop, tunnel loop}, null if missing.
inline std::pair<const Loop*, const Loop*> expect_torus_generator_loops(const AnalyzeResult& r,
                                                                         const std::array<double, 3>& centre,
                                                                         double R, double rr) {
  EXPECT_EQ(r.chokes.handle_generators, 1);
  const Loop* hl = find_loop(r, Side::Handle, Kind::Generator);
  const Loop* tl = find_loop(r, Side::Tunnel, Kind::Generator);
  EXPECT_TRUE(hl && tl);
  if (!hl || !tl) return {hl, tl};
  EXPECT_NEAR(tl->length, 2 * M_PI * (R - rr), 0.1 * 2 * M_PI * (R - rr));
  EXPECT_NEAR(hl->length, 2 * M_PI * rr, 0.15 * 2 * M_PI * rr);
  EXPECT_LT(dist(r.frame.apply(tl->centroid), centre), 1.0);
  EXPECT_NEAR(dist(r.frame.apply(hl->centroid), centre), R, 1.5);
  return {hl, tl};
}

}  // namespace chokeloops::test

#pragma once
// Small volumes made in memory for the volume and filter tests.
#include <cmath>
#include <functional>
#include <string>

#include "chokeloops/io/volume_io.h"

namespace chokeloops::test {

// A volume whose voxel (i,j,k) is at affine * (i,j,k,1), filled by value(physical position in the image's
// axis-aligned frame: spacing * (i,j,k)).
inline VolumeImage make_image(std::array<int, 3> dims, std::array<double, 3> spacing, const std::string& datatype,
                       const std::function<float(double, double, double)>& value) {
  VolumeImage v;
  v.dims = dims;
  v.datatype = datatype;
  v.convention = "RAS";
  v.spacing = spacing;
  for (int r = 0; r < 3; ++r) v.affine[r][r] = spacing[r];
  v.values.resize(std::size_t(v.voxel_count()));
  for (int k = 0; k < dims[2]; ++k)
    for (int j = 0; j < dims[1]; ++j)
      for (int i = 0; i < dims[0]; ++i)
        v.values[std::size_t(i) + std::size_t(dims[0]) * (std::size_t(j) + std::size_t(dims[1]) * k)] =
            value(spacing[0] * i, spacing[1] * j, spacing[2] * k);
  return v;
}

// A ball of radius 10 voxels (label 1) with a wire loop on top: up from the ball, across, and down to a second
// strand; the two strands touch at one voxel when z_a == z_b (a one-voxel bridge: genus 1).
inline VolumeImage sphere_with_bridge(int z_a, int z_b) {
  auto img = make_image({48, 48, 48}, {1, 1, 1}, "uint8", [](double x, double y, double z) {
    return std::hypot(std::hypot(x - 24, y - 24), z - 24) <= 10 ? 1.f : 0.f;
  });
  auto set = [&](int i, int j, int k) { img.values[std::size_t(i) + 48 * (std::size_t(j) + 48 * std::size_t(k))] = 1.f; };
  for (int k = 34; k <= z_a; ++k) set(24, 24, k);
  for (int i = 24; i <= 28; ++i) set(i, 24, z_a);
  for (int i = 29; i <= 32; ++i) set(i, 24, z_b);
  for (int k = 30; k <= z_b; ++k) set(32, 24, k);
  return img;
}

}  // namespace chokeloops::test

// Decodes fuzz bytes into a small FloatGrid for levelset_from_vdb(): shared by fuzz_vdb_levelset.cpp and the
// regression tests that replay its findings. The byte layout is described in fuzz_vdb_levelset.cpp.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>

#include <openvdb/openvdb.h>

namespace chokeloops::fuzz {
constexpr int kVdbLevelsetSpan = 24;
constexpr std::size_t kVdbLevelsetMaxValues = 512;

inline float vdb_levelset_value(std::uint8_t lo, std::uint8_t hi, double h) {
  const auto v = static_cast<std::int16_t>(std::uint16_t(lo | (hi << 8)));
  if (v == 0x7fff) return std::numeric_limits<float>::quiet_NaN();
  if (v == 0x7ffe) return std::numeric_limits<float>::infinity();
  return float(double(v) / 64.0 * h);
}

/// The grid the bytes describe, or null when there are fewer than 5 or the voxel is below OpenVDB's smallest. OpenVDB must be initialised.
inline openvdb::FloatGrid::Ptr decode_vdb_levelset_grid(const std::uint8_t* data, std::size_t size) {
  if (size < 5) return nullptr;
  const int exponent = std::clamp(int(static_cast<std::int8_t>(data[1])), -24, 24);
  const double h = std::ldexp(1.0 + data[2] / 256.0, exponent);
  auto grid = openvdb::FloatGrid::create(std::abs(vdb_levelset_value(data[3], data[4], h)));
  const openvdb::GridClass classes[] = {openvdb::GRID_LEVEL_SET, openvdb::GRID_FOG_VOLUME, openvdb::GRID_UNKNOWN};
  grid->setGridClass(classes[data[0] % 3]);
  openvdb::math::Transform::Ptr xf;
  try {
    xf = openvdb::math::Transform::createLinearTransform(h);  // throws below OpenVDB's smallest voxel
  } catch (const openvdb::ArithmeticError&) {
    return nullptr;  // not a grid a file can hold: its transform's reading refuses it (the .vdb harness)
  }
  if (data[0] & 4) xf->preScale(openvdb::Vec3d(1, 2, 1));
  if (data[0] & 8) xf->postTranslate(openvdb::Vec3d(0.5 * h));
  grid->setTransform(xf);
  for (std::size_t pos = 5, n = 0; pos + 5 <= size && n < kVdbLevelsetMaxValues; pos += 5, ++n) {
    const openvdb::Coord c(data[pos] % kVdbLevelsetSpan, (data[pos + 1] & 0x7f) % kVdbLevelsetSpan,
                           data[pos + 2] % kVdbLevelsetSpan);
    const float v = vdb_levelset_value(data[pos + 3], data[pos + 4], h);
    if (data[pos + 1] & 0x80)
      grid->tree().addTile(1, c, v, true);
    else if (data[pos] & 0x80)
      grid->tree().setValueOff(c, v);
    else
      grid->tree().setValueOn(c, v);
  }
  return grid;
}
}  // namespace chokeloops::fuzz

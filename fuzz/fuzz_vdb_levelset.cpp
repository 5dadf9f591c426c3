// libFuzzer harness for what the levelset stage does with a float grid read from a .vdb file:
// levelset_from_vdb() (the transform check, level set or fog, the eikonal check and redistancing, fogToSdf, the
// memory guard, the feature transform). The reader is fuzzed by fuzz_vdb_reader.cpp; here the bytes are decoded
// straight into a small FloatGrid, so that mutations change the values, the topology and the transform:
//   byte 0      grid class (% 3: level set, fog volume, unknown); bit 2: a scale non-uniform along y;
//               bit 3: a translation of 0.5 voxel
//   byte 1      voxel size exponent (int8, clamped to [-24, 24]); byte 2 its mantissa: (1 + b/256) 2^e
//   bytes 3-4   the background (int16 / 64, in voxels)
//   then        5 bytes a value: x, y, z (% kSpan; the top bit of x makes it inactive, the top bit of y makes
//               it an active 8^3 tile instead of a voxel) and an int16 value / 64 in voxels (0x7fff: NaN,
//               0x7ffe: +inf), at most kMaxValues
// On one thread, with a memory guard of 64^3. The only acceptable failure is chokeloops::Error.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>

#include <tbb/global_control.h>

#include "chokeloops/field/levelset.h"
#include "chokeloops/grid.h"
#include "chokeloops/io/vdb_io.h"

namespace {
constexpr int kSpan = 24;
constexpr std::size_t kMaxValues = 512;

float value_of(std::uint8_t lo, std::uint8_t hi, double h) {
  const auto v = static_cast<std::int16_t>(std::uint16_t(lo | (hi << 8)));
  if (v == 0x7fff) return std::numeric_limits<float>::quiet_NaN();
  if (v == 0x7ffe) return std::numeric_limits<float>::infinity();
  return float(double(v) / 64.0 * h);
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
  if (size < 5) return 0;
  chokeloops::ensure_openvdb_initialized();
  const int exponent = std::clamp(int(static_cast<std::int8_t>(data[1])), -24, 24);
  const double h = std::ldexp(1.0 + data[2] / 256.0, exponent);
  auto grid = openvdb::FloatGrid::create(std::abs(value_of(data[3], data[4], h)));
  const openvdb::GridClass classes[] = {openvdb::GRID_LEVEL_SET, openvdb::GRID_FOG_VOLUME, openvdb::GRID_UNKNOWN};
  grid->setGridClass(classes[data[0] % 3]);
  auto xf = openvdb::math::Transform::createLinearTransform(h);
  if (data[0] & 4) xf->preScale(openvdb::Vec3d(1, 2, 1));
  if (data[0] & 8) xf->postTranslate(openvdb::Vec3d(0.5 * h));
  grid->setTransform(xf);
  for (std::size_t pos = 5, n = 0; pos + 5 <= size && n < kMaxValues; pos += 5, ++n) {
    const openvdb::Coord c(data[pos] % kSpan, (data[pos + 1] & 0x7f) % kSpan, data[pos + 2] % kSpan);
    const float v = value_of(data[pos + 3], data[pos + 4], h);
    if (data[pos + 1] & 0x80)
      grid->tree().addTile(1, c, v, true);
    else if (data[pos] & 0x80)
      grid->tree().setValueOff(c, v);
    else
      grid->tree().setValueOn(c, v);
  }
  try {
    chokeloops::LevelSetOptions o;
    o.quiet = true;
    o.max_memory = chokeloops::estimate_levelset_bytes(64 * 64 * 64);
    chokeloops::levelset_from_vdb(grid, o, "fuzz");
  } catch (const chokeloops::Error&) {
  }
  return 0;
}

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
//               0x7ffe: +inf), at most kVdbLevelsetMaxValues
// On one thread, with a memory guard of 64^3. The only acceptable failure is chokeloops::Error.
#include <cstddef>
#include <cstdint>

#include <tbb/global_control.h>

#include "chokeloops/field/levelset.h"
#include "chokeloops/grid.h"
#include "chokeloops/io/vdb_io.h"
#include "vdb_levelset_decode.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
  chokeloops::ensure_openvdb_initialized();
  const openvdb::FloatGrid::Ptr grid = chokeloops::fuzz::decode_vdb_levelset_grid(data, size);
  if (!grid) return 0;
  try {
    chokeloops::LevelSetOptions o;
    o.quiet = true;
    o.max_memory = chokeloops::estimate_levelset_bytes(64 * 64 * 64);
    chokeloops::levelset_from_vdb(grid, o, "fuzz");
  } catch (const chokeloops::Error&) {
  }
  return 0;
}

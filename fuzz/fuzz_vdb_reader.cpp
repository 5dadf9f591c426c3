// libFuzzer harness for the .vdb reader: the bytes become a file and read_vdb_float_grid() reads it (OpenVDB's
// file reader behind the guard of src/io/vdb_guard.cpp: value blocks, metadata, names, the root node and the
// topology), then every active value and the active bounding box are visited, as the levelset stage does first.
// What levelset_from_vdb() does with a grid is the separate harness fuzz_vdb_levelset.cpp, on small grids built
// from the bytes, so that this one spends its time in the reader. Only chokeloops::Error is an acceptable failure.
#include <unistd.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <fstream>
#include <string>

#include "chokeloops/grid.h"
#include "chokeloops/io/vdb_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string path = "/dev/shm/chokeloops_fuzz_" + std::to_string(::getpid()) + ".vdb";
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), std::streamsize(size));
  }
  try {
    const openvdb::FloatGrid::Ptr grid = chokeloops::read_vdb_float_grid(path, "");
    std::size_t finite = 0;
    for (auto it = grid->tree().cbeginValueOn(); it; ++it) finite += std::isfinite(*it) ? 1 : 0;
    const openvdb::CoordBBox box = grid->evalActiveVoxelBoundingBox();
    if (finite > 0 && box.empty()) __builtin_trap();  // active values but no active box
  } catch (const chokeloops::Error&) {
  }
  return 0;
}

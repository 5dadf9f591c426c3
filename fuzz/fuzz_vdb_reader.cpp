// libFuzzer harness for the .vdb input: the bytes become a file, read_vdb_float_grid() reads it and
// levelset_from_vdb() turns it into the dense signed distance under a 256 MB memory guard (a huge grid
// must be refused with exit code 3, not allocated). Only chokeloops::Error is an acceptable failure.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <fstream>
#include <string>

#include "chokeloops/field/levelset.h"
#include "chokeloops/grid.h"
#include "chokeloops/io/vdb_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string path = "/dev/shm/chokeloops_fuzz_" + std::to_string(::getpid()) + ".vdb";
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), std::streamsize(size));
  }
  try {
    auto grid = chokeloops::read_vdb_float_grid(path, "");
    chokeloops::LevelSetOptions o;
    o.quiet = true;
    o.max_memory = std::size_t(256) << 20;
    chokeloops::levelset_from_vdb(grid, o, "fuzz");
  } catch (const chokeloops::Error&) {
  }
  return 0;
}

// libFuzzer harness for the .vdb input: the bytes become a file, read_vdb_float_grid() reads it and
// levelset_from_vdb() turns it into the dense signed distance under a memory guard that allows only a tiny
// box (64^3 vertices: a larger grid must be refused with exit code 3, not allocated; the cap keeps each input
// cheap), on one thread. Only chokeloops::Error is an acceptable failure.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <fstream>
#include <string>

#include <tbb/global_control.h>

#include "chokeloops/field/levelset.h"
#include "chokeloops/grid.h"
#include "chokeloops/io/vdb_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
  static const std::string path = "/dev/shm/chokeloops_fuzz_" + std::to_string(::getpid()) + ".vdb";
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), std::streamsize(size));
  }
  try {
    auto grid = chokeloops::read_vdb_float_grid(path, "");
    chokeloops::LevelSetOptions o;
    o.quiet = true;
    o.max_memory = chokeloops::estimate_levelset_bytes(64 * 64 * 64);
    chokeloops::levelset_from_vdb(grid, o, "fuzz");
  } catch (const chokeloops::Error&) {
  }
  return 0;
}

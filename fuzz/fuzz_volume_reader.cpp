// libFuzzer harness for the volume reader (CHOKELOOPS_FUZZ_EXT: ".nii", ".nii.gz", ".nrrd", ".mha"): the bytes
// become a file and read_volume() (niftilib / teem / MetaIO) reads it, 4D inputs as their first volume.
// Headers announcing huge images must be refused, not allocated. Only chokeloops::Error is an acceptable
// failure.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <fstream>
#include <string>

#include "chokeloops/grid.h"
#include "chokeloops/io/volume_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string path = "/dev/shm/chokeloops_fuzz_" + std::to_string(::getpid()) + CHOKELOOPS_FUZZ_EXT;
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), std::streamsize(size));
  }
  try {
    chokeloops::read_volume(path, 0);
  } catch (const chokeloops::Error&) {
  }
  return 0;
}

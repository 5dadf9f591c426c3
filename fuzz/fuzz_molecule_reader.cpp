// libFuzzer harness for the molecule reader (CHOKELOOPS_FUZZ_EXT: ".pdb", ".cif", ".pdb.gz"): the bytes
// become a file and read_molecule() (gemmi) reads it with the default filters. Only chokeloops::Error is an
// acceptable failure: any other exception, a crash or a sanitizer report is a finding.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <fstream>
#include <string>

#include "chokeloops/grid.h"
#include "chokeloops/io/molecule_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string path = "/dev/shm/chokeloops_fuzz_" + std::to_string(::getpid()) + CHOKELOOPS_FUZZ_EXT;
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), std::streamsize(size));
  }
  try {
    chokeloops::read_molecule(path);
  } catch (const chokeloops::Error&) {
  }
  return 0;
}

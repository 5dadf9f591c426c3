// libFuzzer harness for one mesh reader (the extension is CHOKELOOPS_FUZZ_EXT: ".obj", ".ply", ".off",
// ".stl"). The bytes become a file, read_mesh() reads it and, when it yields a small mesh, repair_mesh()
// repairs it. The only acceptable failure is chokeloops::Error (a one-line message for bad input):
// any other exception, a crash or a sanitizer report is a finding.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <fstream>
#include <string>

#include "chokeloops/grid.h"
#include "chokeloops/io/mesh_io.h"

namespace {
const std::string& scratch_file() {
  static const std::string path = "/dev/shm/chokeloops_fuzz_" + std::to_string(::getpid()) + CHOKELOOPS_FUZZ_EXT;
  return path;
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  {
    std::ofstream out(scratch_file(), std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), std::streamsize(size));
  }
  try {
    chokeloops::TriangleMesh mesh = chokeloops::read_mesh(scratch_file());
    if (mesh.faces.size() <= 2000) chokeloops::repair_mesh(mesh, "fuzz");
  } catch (const chokeloops::Error&) {
  }
  return 0;
}

// libFuzzer harness for one mesh reader (the extension is CHOKELOOPS_FUZZ_EXT: ".obj", ".ply", ".off",
// ".stl"). The bytes become a file and read_mesh() reads it; a small mesh (at most kMaxFaces triangles) then
// goes through what the levelset stage does with it, mesh_to_levelset(): repair (CGAL), the checks on the
// repaired mesh (extent, index range, memory guard) and the conversion, on a tiny grid (kResolution voxels
// along the longest side, one thread) so that each input stays cheap and the parsing and validation code is
// what the fuzzer spends its time in. The only acceptable failure is chokeloops::Error (a one-line message for
// bad input, exit code 2, or a resource error, exit code 3): any other exception, a crash or a sanitizer
// report is a finding.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <fstream>
#include <string>

#include <tbb/global_control.h>

#include "chokeloops/field/levelset.h"
#include "chokeloops/grid.h"
#include "chokeloops/io/mesh_io.h"

namespace {
constexpr std::size_t kMaxFaces = 128;  // hole filling is cubic in the hole's length
constexpr int kResolution = 12;

const std::string& scratch_file() {
  static const std::string path = "/dev/shm/chokeloops_fuzz_" + std::to_string(::getpid()) + CHOKELOOPS_FUZZ_EXT;
  return path;
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
  {
    std::ofstream out(scratch_file(), std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), std::streamsize(size));
  }
  try {
    chokeloops::TriangleMesh mesh = chokeloops::read_mesh(scratch_file());
    if (mesh.faces.size() <= kMaxFaces) {
      chokeloops::LevelSetOptions o;
      o.quiet = true;
      o.resolution = kResolution;
      o.max_memory = chokeloops::estimate_levelset_bytes(64 * 64 * 64);
      chokeloops::mesh_to_levelset(mesh, o, "fuzz");
    }
  } catch (const chokeloops::Error&) {
  }
  return 0;
}

// libFuzzer harness for one mesh reader (the extension is CHOKELOOPS_FUZZ_EXT: ".obj", ".ply", ".off",
// ".stl"): parse and validate only. The bytes become a file, read_mesh() reads it (CGAL IO, triangulation of
// polygons and the reader's checks: counts against the file, finite and bounded coordinates, face indices in
// range, at least one face), and mesh_topology() takes what it returns (edges, components, Euler
// characteristic; no repair). What mesh_to_levelset() does with a parsed mesh (CGAL repair, the checks on the
// repaired mesh, the conversion) is the separate harness fuzz_mesh_levelset.cpp, on tiny meshes, so that this
// one spends its time in the parsers. The only acceptable failure is chokeloops::Error (a one-line message
// for bad input, exit code 2): any other exception, a crash or a sanitizer report is a finding.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <fstream>
#include <string>

#include "chokeloops/grid.h"
#include "chokeloops/io/mesh_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string path = "/dev/shm/chokeloops_fuzz_" + std::to_string(::getpid()) + CHOKELOOPS_FUZZ_EXT;
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), std::streamsize(size));
  }
  try {
    const chokeloops::TriangleMesh mesh = chokeloops::read_mesh(path);
    const chokeloops::MeshReport report = chokeloops::mesh_topology(mesh);
    if (report.components == 0) __builtin_trap();  // read_mesh() promises at least one face
  } catch (const chokeloops::Error&) {
  }
  return 0;
}

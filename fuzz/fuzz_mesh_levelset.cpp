// libFuzzer harness for what the levelset stage does with a parsed mesh: mesh_to_levelset() (CGAL repair,
// the checks on the repaired mesh: extent, voxel size, index range, memory guard; then OpenVDB's band and
// the exact feature transform), on tiny meshes so that each input stays cheap. The readers are fuzzed by
// fuzz_mesh_reader.cpp; here the bytes are decoded straight into a TriangleMesh, as read_mesh() would return
// it, so that mutations change the geometry and the connectivity rather than the syntax:
//   byte 0        number of vertices, 1 + (byte % kMeshLevelsetMaxVertices)
//   byte 1        binary exponent of the coordinates' unit, (int8) clamped to [-90, 90]: tiny and huge objects
//   then          3 int16 (little endian) per vertex, times that unit (missing bytes read as 0)
//   the rest      faces, 3 bytes each: vertex index % the number of vertices (at most kMeshLevelsetMaxFaces faces)
// The grid is kMeshLevelsetResolution voxels along the longest side, on one thread, with a memory guard of 64^3.
// The only acceptable failure is chokeloops::Error (bad input, exit code 2; resources, exit code 3).
#include <cstddef>
#include <cstdint>

#include <tbb/global_control.h>

#include "chokeloops/field/levelset.h"
#include "chokeloops/grid.h"
#include "mesh_levelset_decode.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
  const chokeloops::TriangleMesh mesh = chokeloops::fuzz::decode_mesh_levelset_mesh(data, size);
  if (mesh.faces.empty()) return 0;  // read_mesh() refuses a mesh without faces
  try {
    chokeloops::LevelSetOptions o;
    o.quiet = true;
    o.resolution = chokeloops::fuzz::kMeshLevelsetResolution;
    o.max_memory = chokeloops::estimate_levelset_bytes(64 * 64 * 64);
    chokeloops::mesh_to_levelset(mesh, o, "fuzz");
  } catch (const chokeloops::Error&) {
  }
  return 0;
}

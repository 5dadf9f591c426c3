// Decodes fuzz bytes into a tiny TriangleMesh for mesh_to_levelset(): shared by fuzz_mesh_levelset.cpp and the
// regression tests that replay its findings. The byte layout is described in fuzz_mesh_levelset.cpp.
#pragma once
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "chokeloops/io/mesh_io.h"

namespace chokeloops::fuzz {
constexpr std::size_t kMeshLevelsetMaxVertices = 24;
constexpr std::size_t kMeshLevelsetMaxFaces = 48;
constexpr int kMeshLevelsetResolution = 10;

/// The mesh the bytes describe; without faces when they hold none (read_mesh() refuses such a mesh).
inline TriangleMesh decode_mesh_levelset_mesh(const std::uint8_t* data, std::size_t size) {
  TriangleMesh mesh;
  if (size < 2) return mesh;
  const std::size_t nv = 1 + data[0] % kMeshLevelsetMaxVertices;
  const int exponent = std::clamp(int(static_cast<std::int8_t>(data[1])), -90, 90);
  const double unit = std::ldexp(1.0, exponent);
  std::size_t pos = 2;
  auto byte = [&]() -> std::uint8_t { return pos < size ? data[pos++] : 0; };
  mesh.vertices.resize(nv);
  for (auto& v : mesh.vertices)
    for (double& x : v) {
      const std::uint8_t lo = byte(), hi = byte();
      x = double(static_cast<std::int16_t>(std::uint16_t(lo | (hi << 8)))) * unit;
    }
  while (pos + 3 <= size && mesh.faces.size() < kMeshLevelsetMaxFaces) {
    std::array<int, 3> f{};
    for (int& i : f) i = int(data[pos++] % nv);
    mesh.faces.push_back(f);
  }
  return mesh;
}
}  // namespace chokeloops::fuzz

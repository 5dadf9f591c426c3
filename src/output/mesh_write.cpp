#include "chokeloops/output/mesh_write.h"

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>

#include "chokeloops/grid.h"

namespace chokeloops {

namespace {

// All supported targets are little-endian; memcpy keeps the byte layout.
template <typename T>
void put(std::string& buf, T v) {
  char b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));
  buf.append(b, sizeof(T));
}

void write_file(const std::string& path, const std::string& header, const std::string& body) {
  std::ofstream out(path, std::ios::binary);
  if (!out) throw Error("cannot open '" + path + "' for writing", 3);
  out.write(header.data(), std::streamsize(header.size()));
  out.write(body.data(), std::streamsize(body.size()));
  out.flush();
  if (!out) throw Error("cannot write '" + path + "' (disk full?)", 3);
}

}  // namespace

void write_ply(const SurfaceMesh& mesh, const std::string& path) {
  std::ostringstream h;
  h << "ply\nformat binary_little_endian 1.0\ncomment chokeloops zero level set\n"
    << "element vertex " << mesh.vertices.size() << "\nproperty float x\nproperty float y\nproperty float z\n"
    << "element face " << mesh.faces.size() << "\nproperty list uchar int vertex_indices\nend_header\n";
  std::string body;
  body.reserve(mesh.vertices.size() * 12 + mesh.faces.size() * 13);
  for (auto& p : mesh.vertices)
    for (int d = 0; d < 3; ++d) put(body, float(p[d]));
  for (auto& t : mesh.faces) {
    put(body, std::uint8_t(3));
    for (int d = 0; d < 3; ++d) put(body, std::int32_t(t[d]));
  }
  write_file(path, h.str(), body);
}

void write_loops_ply(const std::vector<Polyline3>& loops, const std::string& path) {
  size_t nv = 0, ne = 0;
  for (auto& l : loops) {
    nv += l.size();
    ne += l.size() >= 2 ? l.size() : 0;
  }
  std::ostringstream h;
  h << "ply\nformat binary_little_endian 1.0\ncomment chokeloops loops (closed polylines)\n"
    << "element vertex " << nv << "\nproperty float x\nproperty float y\nproperty float z\nproperty int loop\n"
    << "element edge " << ne << "\nproperty int vertex1\nproperty int vertex2\nend_header\n";
  std::string body;
  for (size_t i = 0; i < loops.size(); ++i)
    for (auto& p : loops[i]) {
      for (int d = 0; d < 3; ++d) put(body, float(p[d]));
      put(body, std::int32_t(i));
    }
  std::int32_t first = 0;
  for (auto& l : loops) {
    std::int32_t n = std::int32_t(l.size());
    if (n >= 2)
      for (std::int32_t k = 0; k < n; ++k) {
        put(body, first + k);
        put(body, first + (k + 1) % n);
      }
    first += n;
  }
  write_file(path, h.str(), body);
}

void write_loops_obj(const std::vector<Polyline3>& loops, const std::string& path) {
  std::string body;
  body += "# chokeloops loops: one object per closed polyline\n";
  char buf[128];
  size_t first = 1;
  for (size_t i = 0; i < loops.size(); ++i) {
    body += "o loop_" + std::to_string(i) + "\n";
    for (auto& p : loops[i]) {
      std::snprintf(buf, sizeof buf, "v %.9g %.9g %.9g\n", p[0], p[1], p[2]);
      body += buf;
    }
    if (!loops[i].empty()) {
      body += "l";
      for (size_t k = 0; k < loops[i].size(); ++k) body += " " + std::to_string(first + k);
      body += " " + std::to_string(first) + "\n";
    }
    first += loops[i].size();
  }
  write_file(path, "", body);
}

}  // namespace chokeloops

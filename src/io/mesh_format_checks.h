#pragma once
// Private to src/io: the checks mesh_io.cpp runs on OFF and PLY files before CGAL reads them (CGAL trusts the
// counts and lengths a file gives; fuzzing found each of these), and the diagnostics of ASCII files CGAL
// refused. Every failure is a chokeloops::Error naming the file and what is wrong, in one line.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace chokeloops::detail {

inline std::string quoted(const std::string& path) { return "'" + path + "'"; }

// A PLY header, to check CGAL's counts and binary sizes ourselves.
struct PlyHeader {
  bool ok = false;
  std::string format;  // ascii, binary_little_endian, binary_big_endian
  std::size_t header_bytes = 0;
  std::size_t vertex_count = 0, face_count = 0;
  bool has_vertex = false, has_face = false;
  std::size_t min_body_bytes = 0;  // lower bound on the binary body size
  struct Property {
    std::string type;        // a scalar's type, or a list's item type
    std::string count_type;  // a list's count type; empty for a scalar
  };
  struct Element {
    std::size_t count = 0;
    std::vector<Property> properties;
  };
  std::vector<Element> elements;  // in the file's order, as CGAL reads them
};

// Reads the header (throws Error for a malformed one).
PlyHeader read_ply_header(const std::string& path);
// Refuses a list longer than what the file has left, before CGAL sizes it.
void check_ply_lists(const std::string& path, const PlyHeader& header, std::uintmax_t size);
// Refuses OFF headers and bodies CGAL would misread or size from counts the file cannot hold. For an ASCII file
// with normals, colours or texture coordinates, returns the plain OFF text CGAL is to read instead (else empty).
std::string check_off_header(const std::string& path, std::uintmax_t size);
// After CGAL refused an ASCII file: names the first non-finite number, a face referencing a missing vertex, or
// the absence of faces (throws Error); returns when it finds none of these.
void diagnose_ascii(const std::string& path, const std::string& ext);
void diagnose_faces(const std::string& path, const std::string& ext);

}  // namespace chokeloops::detail

// Mesh input: OBJ, PLY (ascii/binary), OFF, STL (ascii/binary) through CGAL IO, with validation that
// names the file and the problem in one line (stage `levelset`, DESIGN.md §4).
#include "chokeloops/io/mesh_io.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/IO/OBJ.h>
#include <CGAL/IO/OFF.h>
#include <CGAL/IO/PLY.h>
#include <CGAL/IO/STL.h>
#include <CGAL/IO/polygon_soup_io.h>

#include "chokeloops/grid.h"
#include "mesh_format_checks.h"

namespace chokeloops {
namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = K::Point_3;
namespace fs = std::filesystem;

constexpr double kHuge = 1e30;

std::string q(const std::string& path) { return detail::quoted(path); }
using detail::check_off_header;
using detail::check_ply_lists;
using detail::diagnose_ascii;
using detail::PlyHeader;
using detail::read_ply_header;

std::string lower_ext(const std::string& path) {
  std::string e = fs::path(path).extension().string();
  for (auto& c : e) c = char(std::tolower(static_cast<unsigned char>(c)));
  return e;
}

std::uintmax_t file_size_checked(const std::string& path) {
  std::error_code ec;
  if (path.empty()) throw Error("empty input file name");
  if (!fs::exists(path, ec)) throw Error(q(path) + ": no such file");
  if (fs::is_directory(path, ec)) throw Error(q(path) + ": is a directory, not a mesh file");
  std::ifstream probe(path, std::ios::binary);
  if (!probe) throw Error(q(path) + ": cannot open for reading (permission denied?)");
  auto size = fs::file_size(path, ec);
  if (ec) throw Error(q(path) + ": cannot determine file size");
  if (size == 0) throw Error(q(path) + ": empty file");
  return size;
}

// Binary STL: 80-byte header, uint32 count, 50 bytes per triangle.
bool stl_is_binary(const std::string& path, std::uintmax_t size, std::uint32_t* count) {
  std::ifstream in(path, std::ios::binary);
  char head[84] = {0};
  in.read(head, 84);
  const std::streamsize got = in.gcount();
  bool starts_solid = got >= 5 && std::strncmp(head, "solid", 5) == 0;
  std::uint32_t n = 0;
  if (got == 84) std::memcpy(&n, head + 80, 4);  // little-endian host assumed (x86/arm)
  *count = n;
  if (got == 84 && 84 + 50 * std::uintmax_t(n) == size) return true;  // exact binary size
  if (starts_solid) {
    // ASCII STL must contain 'facet' or 'endsolid' as text; binary files named 'solid...' exist too
    std::ifstream t(path);
    std::string w;
    int words = 0;
    while (t >> w && words < 64) {
      ++words;
      if (w == "facet" || w == "endsolid") return false;
    }
    return got == 84;
  }
  return true;
}

void check_point(const std::string& path, const Point& p, std::size_t i) {
  for (int a = 0; a < 3; ++a) {
    const double x = p[a];
    if (!std::isfinite(x)) {
      std::ostringstream s;
      s << q(path) << ": vertex " << i << " has a non-finite coordinate (" << x << ")";
      throw Error(s.str());
    }
    if (std::abs(x) > kHuge) {
      std::ostringstream s;
      s << q(path) << ": vertex " << i << " has a huge coordinate (" << x << ", limit 1e30)";
      throw Error(s.str());
    }
  }
}

}  // namespace

const std::vector<std::string>& mesh_extensions() {
  static const std::vector<std::string> e{".obj", ".ply", ".off", ".stl"};
  return e;
}

TriangleMesh read_mesh(const std::string& path) {
  const std::uintmax_t size = file_size_checked(path);
  const std::string ext = lower_ext(path);
  auto& exts = mesh_extensions();
  if (std::find(exts.begin(), exts.end(), ext) == exts.end())
    throw Error(q(path) + ": unknown mesh extension '" + ext + "' (supported: .obj .ply .off .stl, and .vdb)");

  std::vector<Point> points;
  std::vector<std::vector<std::size_t>> polygons;
  bool ok = false;
  bool binary = false;
  PlyHeader ply;
  std::uint32_t stl_count = 0;
  std::string plain_off;  // an OFF file's coordinates and faces, when CGAL is not to read its other attributes
  std::string format = ext.substr(1);
  for (auto& c : format) c = char(std::toupper(static_cast<unsigned char>(c)));

  if (ext == ".ply") {
    ply = read_ply_header(path);
    if (!ply.has_vertex) throw Error(q(path) + ": PLY header declares no vertex element");
    if (!ply.has_face) throw Error(q(path) + ": PLY header declares no face element (a point cloud, not a mesh)");
    binary = ply.format.rfind("binary", 0) == 0;
    if (binary && size < ply.header_bytes + ply.min_body_bytes) {
      std::ostringstream s;
      s << q(path) << ": truncated binary PLY (" << size << " bytes, the header's " << ply.vertex_count
        << " vertices and " << ply.face_count << " faces need at least " << ply.header_bytes + ply.min_body_bytes
        << ")";
      throw Error(s.str());
    }
    check_ply_lists(path, ply, size);
  } else if (ext == ".off") {
    plain_off = check_off_header(path, size);
  } else if (ext == ".stl") {
    binary = stl_is_binary(path, size, &stl_count);
    if (binary) {
      if (size < 84) throw Error(q(path) + ": truncated binary STL (shorter than its 84-byte header)");
      if (84 + 50 * std::uintmax_t(stl_count) > size) {
        std::ostringstream s;
        s << q(path) << ": truncated binary STL (" << size << " bytes, header announces " << stl_count
          << " triangles = " << 84 + 50 * std::uintmax_t(stl_count) << " bytes)";
        throw Error(s.str());
      }
    }
  }

  try {
    if (ext == ".obj") ok = CGAL::IO::read_OBJ(path, points, polygons);
    else if (ext == ".off" && !plain_off.empty()) {
      std::istringstream plain(plain_off);
      ok = CGAL::IO::read_OFF(plain, points, polygons);
    } else if (ext == ".off") ok = CGAL::IO::read_OFF(path, points, polygons);
    else if (ext == ".ply") ok = CGAL::IO::read_PLY(path, points, polygons);
    else if (ext == ".stl") ok = CGAL::IO::read_STL(path, points, polygons, CGAL::parameters::use_binary_mode(binary));
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    std::string m = e.what();
    std::replace(m.begin(), m.end(), '\n', ' ');
    throw Error(q(path) + ": cannot parse as " + format + " (" + m + ")");
  }
  if (!ok) {
    if (!binary) diagnose_ascii(path, ext);
    throw Error(q(path) + ": cannot parse as " + (binary ? "binary " : "") + format + " (malformed or truncated file)");
  }
  if (ext == ".ply" && (points.size() != ply.vertex_count || polygons.size() != ply.face_count)) {
    std::ostringstream s;
    s << q(path) << ": truncated or malformed PLY (read " << points.size() << " of " << ply.vertex_count
      << " vertices and " << polygons.size() << " of " << ply.face_count << " faces)";
    throw Error(s.str());
  }
  if (ext == ".stl" && binary && polygons.size() != stl_count) {
    std::ostringstream s;
    s << q(path) << ": truncated or malformed binary STL (read " << polygons.size() << " of " << stl_count
      << " triangles)";
    throw Error(s.str());
  }
  if (points.empty()) throw Error(q(path) + ": no vertices");
  if (points.size() >= std::size_t(std::numeric_limits<int>::max()))
    throw Error(q(path) + ": too many vertices (" + std::to_string(points.size()) + ")");

  TriangleMesh mesh;
  mesh.vertices.resize(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    check_point(path, points[i], i);
    mesh.vertices[i] = {points[i].x(), points[i].y(), points[i].z()};
  }
  mesh.faces.reserve(polygons.size());
  for (std::size_t f = 0; f < polygons.size(); ++f) {
    const auto& poly = polygons[f];
    if (poly.size() < 3) {
      std::ostringstream s;
      s << q(path) << ": face " << f << " has " << poly.size() << " vertices (at least 3 needed)";
      throw Error(s.str());
    }
    for (std::size_t v : poly)
      if (v >= points.size()) {
        std::ostringstream s;
        s << q(path) << ": face " << f << " references vertex " << v << " but the file has only " << points.size()
          << " vertices (indices 0.." << points.size() - 1 << ")";
        throw Error(s.str());
      }
    auto P = [&](std::size_t v) { return points[poly[v]]; };
    if (poly.size() == 4) {
      // split along the shorter diagonal
      if (CGAL::squared_distance(P(0), P(2)) <= CGAL::squared_distance(P(1), P(3))) {
        mesh.faces.push_back({int(poly[0]), int(poly[1]), int(poly[2])});
        mesh.faces.push_back({int(poly[0]), int(poly[2]), int(poly[3])});
      } else {
        mesh.faces.push_back({int(poly[0]), int(poly[1]), int(poly[3])});
        mesh.faces.push_back({int(poly[1]), int(poly[2]), int(poly[3])});
      }
    } else {
      for (std::size_t k = 1; k + 1 < poly.size(); ++k)
        mesh.faces.push_back({int(poly[0]), int(poly[k]), int(poly[k + 1])});
    }
  }
  if (mesh.faces.empty()) throw Error(q(path) + ": no faces (" + std::to_string(points.size()) + " vertices, 0 faces)");
  return mesh;
}

void write_mesh(const TriangleMesh& mesh, const std::string& path) {
  std::vector<Point> points;
  points.reserve(mesh.vertices.size());
  for (auto& v : mesh.vertices) points.emplace_back(v[0], v[1], v[2]);
  std::vector<std::vector<std::size_t>> polys;
  polys.reserve(mesh.faces.size());
  for (auto& f : mesh.faces) polys.push_back({std::size_t(f[0]), std::size_t(f[1]), std::size_t(f[2])});
  if (!CGAL::IO::write_polygon_soup(path, points, polys, CGAL::parameters::stream_precision(17)))
    throw Error("cannot write mesh '" + path + "'");
}

}  // namespace chokeloops

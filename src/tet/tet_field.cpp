#include "chokeloops/tet/tet_field.h"

#define TETLIBRARY
#include <tetgen.h>

#include <sys/wait.h>
#include <unistd.h>

#include <tbb/parallel_for.h>

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <map>
#include <sstream>
#include <string>

#include "chokeloops/field/memory_budget.h"
#include "chokeloops/grid.h"

namespace chokeloops {

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Triangles = std::vector<K::Triangle_3>;
using Primitive = CGAL::AABB_triangle_primitive<K, Triangles::const_iterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<K, Primitive>>;

// TetGen needs a closed surface to tell its inside; every edge must be shared by exactly two triangles that
// run it in opposite directions (closed, manifold along edges and consistently oriented).
void require_closed_manifold(const TriangleMesh& mesh) {
  std::map<std::pair<int, int>, int> directed;  // (a, b) -> how many triangles run a -> b
  for (const auto& f : mesh.faces)
    for (int e = 0; e < 3; ++e) ++directed[{f[std::size_t(e)], f[std::size_t((e + 1) % 3)]}];
  for (const auto& [edge, n] : directed) {
    const auto opposite = directed.find({edge.second, edge.first});
    const int back = opposite == directed.end() ? 0 : opposite->second;
    if (n != 1 || back != 1) {
      std::ostringstream s;
      s << "--complex tetgen needs a closed, manifold, consistently oriented mesh: the edge between vertices "
        << edge.first << " and " << edge.second << " has " << n << " triangle(s) one way and " << back
        << " the other (repair the mesh, or use the default grid complex, which repairs it)";
      throw Error(s.str());
    }
  }
}

// CGAL finds the first pair of intersecting triangles; TetGen would fail on them (and see below).
void require_no_self_intersection(const TriangleMesh& mesh) {
  CGAL::Surface_mesh<K::Point_3> sm;
  for (const auto& p : mesh.vertices) sm.add_vertex(K::Point_3(p[0], p[1], p[2]));
  for (const auto& f : mesh.faces) {
    using VI = CGAL::Surface_mesh<K::Point_3>::Vertex_index;
    if (sm.add_face(VI(std::uint32_t(f[0])), VI(std::uint32_t(f[1])), VI(std::uint32_t(f[2]))) == sm.null_face())
      throw Error("--complex tetgen: the mesh is not manifold at a vertex (CGAL could not add a triangle); repair it, or use the default grid complex");
  }
  if (CGAL::Polygon_mesh_processing::does_self_intersect(sm))
    throw Error("--complex tetgen: the mesh intersects itself (CGAL); repair it, or use the default grid complex, which tolerates it");
}

// TetGen 1.5.0 frees its memory twice when it stops on an error (terminatetetgen, then ~tetgenmesh while the code
// it throws unwinds): the process crashes. So it runs in a child process, which hands back the vertices and tets
// through a pipe, or the error code, or dies alone.
struct TetgenResult {
  std::vector<double> points;       // x y z per vertex
  std::vector<std::int32_t> tets;   // 4 per tet
  std::vector<std::int32_t> neighbours;  // 4 per tet: the tet across the face opposite each corner, -1 none
};

void write_all(int fd, const void* data, std::size_t bytes) {
  const char* p = static_cast<const char*>(data);
  while (bytes > 0) {
    const ssize_t n = ::write(fd, p, bytes);
    if (n <= 0) _exit(5);
    p += n, bytes -= std::size_t(n);
  }
}

TetgenResult tetrahedralize_in_child(tetgenio& in, std::string switches) {
  int fd[2];
  if (pipe(fd) != 0) throw Error("--complex tetgen: could not open a pipe to TetGen's process", 3);
  const pid_t pid = fork();
  if (pid < 0) throw Error("--complex tetgen: could not start TetGen's process (fork)", 3);
  if (pid == 0) {
    close(fd[0]);
    std::int64_t header[3] = {0, 0, 0};  // error code, points, tets
    tetgenio out;
    try {
      tetgenbehavior behaviour;
      if (!behaviour.parse_commandline(switches.data())) header[0] = -1;
      else tetrahedralize(&behaviour, &in, &out);
    } catch (int code) {
      header[0] = code;
    } catch (...) {
      header[0] = 2;
    }
    if (header[0] == 0) header[1] = out.numberofpoints, header[2] = out.numberoftetrahedra;
    if (header[0] == 0 && (out.numberofcorners != 4 || !out.neighborlist)) header[0] = -2;
    write_all(fd[1], header, sizeof header);
    if (header[0] == 0) {
      write_all(fd[1], out.pointlist, sizeof(REAL) * 3 * std::size_t(header[1]));
      std::vector<std::int32_t> tets(out.tetrahedronlist, out.tetrahedronlist + 4 * header[2]);
      write_all(fd[1], tets.data(), sizeof(std::int32_t) * tets.size());
      tets.assign(out.neighborlist, out.neighborlist + 4 * header[2]);
      write_all(fd[1], tets.data(), sizeof(std::int32_t) * tets.size());
    }
    close(fd[1]);
    _exit(0);
  }
  close(fd[1]);
  std::vector<char> bytes;
  char buffer[1 << 16];
  for (ssize_t n; (n = ::read(fd[0], buffer, sizeof buffer)) != 0;) {
    if (n < 0) {
      if (errno == EINTR) continue;
      break;
    }
    bytes.insert(bytes.end(), buffer, buffer + n);
  }
  close(fd[0]);
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  std::int64_t header[3] = {0, 0, 0};
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0 || bytes.size() < sizeof header)
    throw Error("--complex tetgen: TetGen's process died (signal " + std::to_string(WIFSIGNALED(status) ? WTERMSIG(status) : 0) +
                "), as TetGen 1.5.0 does after an error on touching or nearly touching facets; repair the mesh, or use the "
                "default grid complex");
  std::memcpy(header, bytes.data(), sizeof header);
  const int code = int(header[0]);
  if (code == 1) throw Error("TetGen ran out of memory: use a coarser --tet-spacing", 3);
  if (code == 3 || code == 4 || code == 5)
    throw Error(std::string("TetGen refuses the mesh: ") +
                (code == 3 ? "it intersects itself" : code == 4 ? "a feature is too small for its precision" : "two facets are too close") +
                " (repair it, or use the default grid complex)");
  if (code == 10) throw Error("TetGen refuses the mesh as input (a degenerate or repeated triangle?)");
  if (code != 0) throw InternalError("TetGen failed with code " + std::to_string(code) + " (switches " + switches + ")");
  TetgenResult r;
  const std::size_t point_bytes = sizeof(double) * 3 * std::size_t(header[1]), tet_bytes = sizeof(std::int32_t) * 4 * std::size_t(header[2]);
  if (bytes.size() != sizeof header + point_bytes + 2 * tet_bytes) throw InternalError("TetGen's process returned a truncated mesh");
  r.points.resize(3 * std::size_t(header[1]));
  r.tets.resize(4 * std::size_t(header[2]));
  r.neighbours.resize(4 * std::size_t(header[2]));
  std::memcpy(r.points.data(), bytes.data() + sizeof header, point_bytes);
  std::memcpy(r.tets.data(), bytes.data() + sizeof header + point_bytes, tet_bytes);
  std::memcpy(r.neighbours.data(), bytes.data() + sizeof header + point_bytes + tet_bytes, tet_bytes);
  return r;
}

// Each tet's side, exactly: a walk from the box's corner (outside) across the tets' faces, changing side at
// each input triangle. Nested surfaces alternate; no winding number is needed.
std::vector<char> sides_of_tets(const std::vector<std::array<std::int32_t, 4>>& tets, const std::vector<std::int32_t>& neighbours,
                                const TriangleMesh& mesh, int nv) {
  std::vector<std::array<int, 3>> input(mesh.faces.begin(), mesh.faces.end());
  for (auto& f : input) std::sort(f.begin(), f.end());
  std::sort(input.begin(), input.end());
  auto on_surface = [&](std::array<int, 3> f) {
    if (f[0] >= nv || f[1] >= nv || f[2] >= nv) return false;
    std::sort(f.begin(), f.end());
    return std::binary_search(input.begin(), input.end(), f);
  };
  std::vector<signed char> side(tets.size(), -1);
  std::vector<std::size_t> queue;
  for (std::size_t t = 0; t < tets.size() && queue.empty(); ++t)
    for (std::int32_t v : tets[t])
      if (v == nv) side[t] = 0, queue.push_back(t);  // the box's first corner: outside
  if (queue.empty()) throw InternalError("TetGen's complex has no tet at the box's corner");
  for (std::size_t q = 0; q < queue.size(); ++q) {
    const std::size_t t = queue[q];
    for (int i = 0; i < 4; ++i) {
      const std::int32_t u = neighbours[4 * t + std::size_t(i)];
      if (u < 0) continue;
      std::array<int, 3> face;
      for (int j = 0, n = 0; j < 4; ++j)
        if (j != i) face[std::size_t(n++)] = tets[t][std::size_t(j)];
      const signed char s = on_surface(face) ? static_cast<signed char>(1 - side[t]) : side[t];
      if (side[std::size_t(u)] < 0) side[std::size_t(u)] = s, queue.push_back(std::size_t(u));
      else if (side[std::size_t(u)] != s) throw InternalError("TetGen's complex: a tet is both inside and outside the mesh");
    }
  }
  if (queue.size() != tets.size()) throw InternalError("TetGen's complex is not connected across its faces");
  return std::vector<char>(side.begin(), side.end());
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// The points inside and outside where the function is sampled, besides the input's vertices.
// grading = 0: a lattice of spacing h over the box. grading > 0: the centres of an octree's leaves, a cell being
// split while it is larger than h and either than `grading` times the distance from its centre to the surface,
// or than a quarter of it where the cell straddles the medial axis (or while it is not inside the box): samples
// as fine as the lattice's near the surface, and at the core of every part and the middle of every hole, where
// the depths are read; coarse elsewhere, deep inside thick parts and far outside, where the lattice spent most
// of its points. Either way points nearer the surface
// than half their spacing are left out: they would only make slivers. Deterministic, built in parallel.
std::vector<std::array<double, 3>> sample_points(const Tree& tree, const std::array<double, 3>& lo, const std::array<double, 3>& hi,
                                                 double h, double grading, double max_points,
                                                 const std::function<Error(double)>& too_many) {
  auto distance = [&](const std::array<double, 3>& p) { return std::sqrt(tree.squared_distance(K::Point_3(p[0], p[1], p[2]))); };
  if (grading <= 0) {
    std::array<int, 3> cells;
    double lattice_points = 1;
    for (int a = 0; a < 3; ++a) cells[std::size_t(a)] = std::max(1, int(std::floor((hi[std::size_t(a)] - lo[std::size_t(a)]) / h))),
                                lattice_points *= cells[std::size_t(a)] - 1;
    if (lattice_points > max_points) throw too_many(lattice_points);
    std::vector<std::array<double, 3>> extra;
    for (int k = 1; k < cells[2]; ++k)
      for (int j = 1; j < cells[1]; ++j)
        for (int i = 1; i < cells[0]; ++i) extra.push_back({lo[0] + i * h, lo[1] + j * h, lo[2] + k * h});
    std::vector<char> keep(extra.size());
    tbb::parallel_for(std::size_t(0), extra.size(), [&](std::size_t e) { keep[e] = distance(extra[e]) >= 0.5 * h; });
    std::size_t kept = 0;
    for (std::size_t e = 0; e < extra.size(); ++e)
      if (keep[e]) extra[kept++] = extra[e];
    extra.resize(kept);
    return extra;
  }
  // Top cells of h * 2^k, about a quarter of the box's longest side, tiling the box from its low corner.
  double side = 0;
  for (int a = 0; a < 3; ++a) side = std::max(side, hi[std::size_t(a)] - lo[std::size_t(a)]);
  double top = h;
  while (top * 2 <= side / 4) top *= 2;
  std::array<int, 3> n;
  for (int a = 0; a < 3; ++a) n[std::size_t(a)] = int(std::ceil((hi[std::size_t(a)] - lo[std::size_t(a)]) / top));
  const std::size_t tops = std::size_t(n[0]) * std::size_t(n[1]) * std::size_t(n[2]);
  std::vector<std::vector<std::array<double, 3>>> found(tops);
  std::atomic<std::int64_t> total{0};
  tbb::parallel_for(std::size_t(0), tops, [&](std::size_t c) {
    struct Cell { std::array<double, 3> low; double size; };
    std::vector<Cell> stack{{{lo[0] + top * double(c % std::size_t(n[0])), lo[1] + top * double(c / std::size_t(n[0]) % std::size_t(n[1])),
                              lo[2] + top * double(c / (std::size_t(n[0]) * std::size_t(n[1])))}, top}};
    auto& out = found[c];
    while (!stack.empty()) {
      const Cell cell = stack.back();
      stack.pop_back();
      const double half = cell.size / 2;
      const std::array<double, 3> centre{cell.low[0] + half, cell.low[1] + half, cell.low[2] + half};
      bool inside_box = true;
      for (int a = 0; a < 3; ++a)
        inside_box = inside_box && cell.low[std::size_t(a)] >= lo[std::size_t(a)] - 1e-12 * side &&
                     cell.low[std::size_t(a)] + cell.size <= hi[std::size_t(a)] + 1e-12 * side;
      const auto nearest = tree.closest_point(K::Point_3(centre[0], centre[1], centre[2]));
      const double d = std::sqrt(CGAL::squared_distance(nearest, K::Point_3(centre[0], centre[1], centre[2])));
      // Across the medial axis (the core of a part, the middle of a hole) the directions from the nearest surface
      // points turn by up to half a turn; there the depths are read, so those cells are split down to a quarter of
      // their distance.
      auto straddles_medial_axis = [&] {
        std::array<std::array<double, 3>, 9> u;
        for (int k = 0; k < 9; ++k) {
          const K::Point_3 p = k == 8 ? K::Point_3(centre[0], centre[1], centre[2])
                                      : K::Point_3(cell.low[0] + (k & 1) * cell.size, cell.low[1] + (k >> 1 & 1) * cell.size,
                                                   cell.low[2] + (k >> 2 & 1) * cell.size);
          const K::Point_3 q = k == 8 ? nearest : tree.closest_point(p);
          const double len = std::sqrt(CGAL::squared_distance(p, q));
          if (len <= 0) return true;
          u[std::size_t(k)] = {(p.x() - q.x()) / len, (p.y() - q.y()) / len, (p.z() - q.z()) / len};
        }
        for (int a = 0; a < 9; ++a)
          for (int b = a + 1; b < 9; ++b)
            if (u[std::size_t(a)][0] * u[std::size_t(b)][0] + u[std::size_t(a)][1] * u[std::size_t(b)][1] +
                    u[std::size_t(a)][2] * u[std::size_t(b)][2] < 0.5)
              return true;
        return false;
      };
      if (cell.size > 1.5 * h &&
          (!inside_box || cell.size > grading * d || (cell.size > d / 4 && straddles_medial_axis()))) {
        for (int k = 7; k >= 0; --k)  // popped in octant order 0..7
          stack.push_back({{cell.low[0] + (k & 1) * half, cell.low[1] + (k >> 1 & 1) * half, cell.low[2] + (k >> 2 & 1) * half}, half});
        continue;
      }
      if (!inside_box || d < half) continue;
      out.push_back(centre);
      if (double(++total) > max_points) throw too_many(double(total.load()));
    }
  });
  std::vector<std::array<double, 3>> extra;
  extra.reserve(std::size_t(total.load()));
  for (const auto& f : found) extra.insert(extra.end(), f.begin(), f.end());
  return extra;
}

}  // namespace

TetField tetrahedralize_with_distance(const TriangleMesh& mesh, const TetOptions& options) {
  if (mesh.faces.empty()) throw Error("--complex tetgen: the mesh has no triangles");
  if (options.radius_edge != 0 && !(options.radius_edge > 1.0))
    throw Error("--tet-quality must be above 1 (TetGen's radius-edge ratio), or 0 for none");
  if (options.spacing < 0 || !std::isfinite(options.spacing)) throw Error("--tet-spacing must be >= 0");
  if (options.max_volume < 0 || !std::isfinite(options.max_volume)) throw Error("--tet-max-volume must be >= 0");
  require_closed_manifold(mesh);
  require_no_self_intersection(mesh);
  const auto t0 = std::chrono::steady_clock::now();
  std::array<double, 3> lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
  for (const auto& p : mesh.vertices)
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], p[a]), hi[a] = std::max(hi[a], p[a]);
  const double diagonal = std::sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                                    (hi[2] - lo[2]) * (hi[2] - lo[2]));
  const double pad = options.padding * diagonal;
  for (int a = 0; a < 3; ++a) lo[a] -= pad, hi[a] += pad;

  const int nv = int(mesh.vertices.size()), nf = int(mesh.faces.size());
  Triangles triangles;
  triangles.reserve(std::size_t(nf));
  auto point = [&](int v) {
    const auto& p = mesh.vertices[std::size_t(v)];
    return K::Point_3(p[0], p[1], p[2]);
  };
  for (const auto& f : mesh.faces) triangles.emplace_back(point(f[0]), point(f[1]), point(f[2]));
  Tree tree(triangles.begin(), triangles.end());
  tree.accelerate_distance_queries();

  // Points inside and outside where the function is sampled (sample_points).
  const double h = options.spacing > 0 ? options.spacing : diagonal / options.default_cells;
  // Measured: the whole path peaks at 4-4.5 KB a vertex of the complex (TetGen's mesh, its copy through the pipe,
  // the simplices and PHAT's columns); the guard counts 6 KB.
  constexpr double kBytesPerVertex = 6144;
  const double limit = double(options.max_memory ? options.max_memory : default_max_memory());
  auto size = [](double bytes) {
    char text[32];
    std::snprintf(text, sizeof text, bytes < 1e9 ? "%.0f MB" : "%.1f GB", bytes < 1e9 ? bytes / 1e6 : bytes / 1e9);
    return std::string(text);
  };
  auto too_many = [&](double points) {
    char count[32];
    std::snprintf(count, sizeof count, "%.3g", points + nv);
    return Error("--complex tetgen would need more than " + size((points + nv) * kBytesPerVertex) + " for " + count +
                 " vertices (limit " + size(limit) + "): use a coarser --tet-spacing or a larger --tet-grading, or raise --max-memory", 3);
  };
  const double max_points = limit / kBytesPerVertex - nv;
  if (max_points < 0) throw too_many(0);
  const std::vector<std::array<double, 3>> extra = sample_points(tree, lo, hi, h, options.grading, max_points, too_many);

  // The input: the mesh's vertices, the box's 8 corners, the samples; its triangles, then the box's 6 quads.
  tetgenio in;
  in.firstnumber = 0;
  const int n_points = nv + 8 + int(extra.size());
  in.numberofpoints = n_points;
  in.pointlist = new REAL[std::size_t(3) * std::size_t(n_points)];
  for (int v = 0; v < nv; ++v)
    for (int a = 0; a < 3; ++a) in.pointlist[3 * v + a] = mesh.vertices[std::size_t(v)][std::size_t(a)];
  for (int c = 0; c < 8; ++c)
    for (int a = 0; a < 3; ++a) in.pointlist[3 * (nv + c) + a] = (c >> a) & 1 ? hi[std::size_t(a)] : lo[std::size_t(a)];
  for (std::size_t e = 0; e < extra.size(); ++e)
    for (int a = 0; a < 3; ++a) in.pointlist[3 * (std::size_t(nv) + 8 + e) + std::size_t(a)] = extra[e][std::size_t(a)];
  static constexpr int kBoxQuads[6][4] = {{0, 2, 6, 4}, {1, 5, 7, 3}, {0, 4, 5, 1}, {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 6, 7, 5}};
  in.numberoffacets = nf + 6;
  in.facetlist = new tetgenio::facet[std::size_t(nf + 6)];
  for (int f = 0; f < nf + 6; ++f) {
    tetgenio::facet& facet = in.facetlist[f];
    tetgenio::init(&facet);
    facet.numberofpolygons = 1;
    facet.polygonlist = new tetgenio::polygon[1];
    tetgenio::polygon& p = facet.polygonlist[0];
    tetgenio::init(&p);
    p.numberofvertices = f < nf ? 3 : 4;
    p.vertexlist = new int[std::size_t(p.numberofvertices)];
    for (int i = 0; i < p.numberofvertices; ++i)
      p.vertexlist[i] = f < nf ? mesh.faces[std::size_t(f)][std::size_t(i)] : nv + kBoxQuads[f - nf][i];
  }
  // p: a PLC; q: quality; a: volume; n: neighbours; Y: no Steiner point on the input's facets (the surface stays a subcomplex
  // with the input's own edges); z: indices from 0; Q: quiet.
  std::ostringstream sw;
  sw << "p";
  if (options.radius_edge > 0) sw << "q" << options.radius_edge;
  if (options.max_volume > 0) sw << "a" << options.max_volume;
  sw << "YnzQ";  // n: each tet's neighbours
  const TetgenResult out = tetrahedralize_in_child(in, sw.str());
  TetField field;
  field.input_vertices = nv;
  field.spacing = h;
  field.vertices.resize(out.points.size() / 3);
  for (std::size_t v = 0; v < field.vertices.size(); ++v)
    field.vertices[v] = {out.points[3 * v], out.points[3 * v + 1], out.points[3 * v + 2]};
  for (int v = 0; v < nv; ++v)  // -Y keeps the input's vertices first and where they were
    if (field.vertices[std::size_t(v)] != mesh.vertices[std::size_t(v)])
      throw InternalError("TetGen moved input vertex " + std::to_string(v));
  field.tets.resize(out.tets.size() / 4);
  for (std::size_t t = 0; t < field.tets.size(); ++t)
    for (int i = 0; i < 4; ++i) field.tets[t][std::size_t(i)] = out.tets[4 * t + std::size_t(i)];
  field.seconds_tetgen = seconds_since(t0);

  // Distance from CGAL's AABB tree; the sign from the side of the tets around the vertex.
  const auto t1 = std::chrono::steady_clock::now();
  field.inside_tets = sides_of_tets(field.tets, out.neighbours, mesh, nv);
  // A vertex off the surface lies strictly inside one side: that of any tet around it.
  std::vector<signed char> vertex_side(field.vertices.size(), -1);
  for (std::size_t t = 0; t < field.tets.size(); ++t)
    for (std::int32_t v : field.tets[t]) vertex_side[std::size_t(v)] = field.inside_tets[t];
  field.values.assign(field.vertices.size(), 0.0);
  tbb::parallel_for(std::size_t(nv), field.vertices.size(), [&](std::size_t v) {
    const auto& p = field.vertices[v];
    const double d = std::sqrt(tree.squared_distance(K::Point_3(p[0], p[1], p[2])));
    field.values[v] = vertex_side[v] == 1 ? -d : d;
  });
  field.seconds_distance = seconds_since(t1);
  return field;
}

}  // namespace chokeloops

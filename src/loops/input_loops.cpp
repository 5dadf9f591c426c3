// Loops on the input mesh (input_loops.h): closest points on the input's triangles, the nearest corner of each
// point's triangle, shortest edge paths between consecutive corners, shortening in the class, CGAL's check.
#include "chokeloops/loops/input_loops.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <set>

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <tbb/parallel_for.h>

#include "chokeloops/grid.h"
#include "chokeloops/loops/shorten.h"
#include "chokeloops/surface/mesh_adjacency.h"
#include "chokeloops/surface/topology.h"

namespace chokeloops {

namespace {
using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Triangles = std::vector<K::Triangle_3>;
using Primitive = CGAL::AABB_triangle_primitive<K, Triangles::const_iterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<K, Primitive>>;
using P3 = std::array<double, 3>;

double dist2(const P3& a, const P3& b) {
  return (a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]);
}

// The two corners faces f and g share (f's orientation), or {-1, -1}.
std::array<int, 2> shared_edge(const SurfaceMesh& m, int f, int g) {
  for (int k = 0; k < 3; ++k) {
    const int a = m.faces[f][k], b = m.faces[f][(k + 1) % 3];
    const auto& t = m.faces[g];
    const bool has_a = t[0] == a || t[1] == a || t[2] == a, has_b = t[0] == b || t[1] == b || t[2] == b;
    if (has_a && has_b) return {a, b};
  }
  return {-1, -1};
}

// Names the vertex or edge each point lies on. Shortened points are the crossings of the portals between
// consecutive strip faces, in strip order with repeats (at a vertex) dropped, so one walk along the strip
// finds them; unshortened points are the edge path's vertices.
std::vector<InputPoint> locate(const SurfaceMesh& m, const MeshAdjacency& adj, const Polyline3& points,
                               const std::vector<int>& strip, const std::vector<int>& path) {
  std::vector<InputPoint> where(points.size());
  if (strip.empty()) {
    for (std::size_t i = 0; i < points.size() && i < path.size(); ++i) {
      where[i].vertex = path[i];
      where[i].face = adj.vf[std::size_t(adj.vf_start[std::size_t(path[i])])];
    }
    return where;
  }
  const std::size_t n = strip.size();
  std::size_t next = 0;
  for (std::size_t j = 0; j < n && next < points.size(); ++j) {
    const auto e = shared_edge(m, strip[j], strip[(j + 1) % n]);
    if (e[0] < 0) continue;
    const P3 &a = m.vertices[std::size_t(e[0])], &b = m.vertices[std::size_t(e[1])], &p = points[next];
    const P3 ab{b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const double len2 = ab[0] * ab[0] + ab[1] * ab[1] + ab[2] * ab[2];
    if (len2 <= 0) continue;
    double t = ((p[0] - a[0]) * ab[0] + (p[1] - a[1]) * ab[1] + (p[2] - a[2]) * ab[2]) / len2;
    t = std::min(1.0, std::max(0.0, t));
    const P3 q{a[0] + t * ab[0], a[1] + t * ab[1], a[2] + t * ab[2]};
    if (dist2(p, q) > 1e-18 * len2) continue;  // a repeat dropped at a vertex: the point is further along
    InputPoint& w = where[next++];
    w.face = strip[j];
    if (t <= 1e-9) w.vertex = e[0];
    else if (t >= 1 - 1e-9) w.vertex = e[1];
    else w.edge = e, w.t = t;
  }
  if (next != points.size()) throw InternalError("input loop: a shortened point lies on no portal of its strip");
  return where;
}

// The corner nearest to each point's closest point on the input, consecutive repeats dropped.
Polyline3 project_to_corners(const SurfaceMesh& m, const Tree& tree, const Triangles& triangles, const Polyline3& grid) {
  Polyline3 out;
  int last = -1;
  for (const P3& p : grid) {
    const auto hit = tree.closest_point_and_primitive(K::Point_3(p[0], p[1], p[2]));
    const std::size_t f = std::size_t(hit.second - triangles.begin());
    const P3 c{hit.first.x(), hit.first.y(), hit.first.z()};
    int best = m.faces[f][0];
    for (int k = 1; k < 3; ++k)
      if (dist2(m.vertices[std::size_t(m.faces[f][k])], c) < dist2(m.vertices[std::size_t(best)], c)) best = m.faces[f][k];
    if (best != last) out.push_back(m.vertices[std::size_t(best)]);
    last = best;
  }
  while (out.size() > 1 && out.back() == out.front()) out.pop_back();
  return out;
}

bool mark_missing(const Loop& grid, InputLoop& out) {
  out.loop.choke = grid.choke;
  out.grid_length = grid.length;
  if (!grid.found) out.loop.note = "no loop on the marching surface" + (grid.note.empty() ? std::string() : ": " + grid.note);
  return !grid.found;
}

// Carries one grid loop; sets found/note on failure.
void carry(const SurfaceMesh& m, const std::vector<char>& added, const MeshAdjacency& adj, SurfaceTopology& topology,
           const Tree& tree, const Triangles& triangles, const Loop& grid, const InputLoopOptions& options, InputLoop& out) {
  if (mark_missing(grid, out)) return;
  const Polyline3 corners = project_to_corners(m, tree, triangles, grid.points);
  if (corners.size() < 3) {
    out.loop.note = "the loop's closest points on the input mesh gather on fewer than 3 vertices (its handle is "
                    "narrower than the input's triangles)";
    return;
  }
  std::vector<int> path;
  try {
    path = snap_polyline_to_edge_path(m, adj, corners);
  } catch (const Error& e) {
    out.loop.note = std::string("the loop's closest points on the input mesh could not be joined along its edges: ") + e.what();
    return;
  }
  if (path.size() < 3) {
    out.loop.note = "the loop's edge path on the input mesh collapses (fewer than 3 vertices)";
    return;
  }
  ShortenResult s;
  if (options.shorten) {
    ShortenOptions so;
    so.max_rings = options.max_rings;
    s = shorten_loop(m, adj, path, so);
  } else {
    s.edge_path = path;
    s.points = loop_points(m, path);
  }
  out.loop.raw_length = loop_length(m, path);
  // The check runs on the edge loop; the shortened polyline is homotopic to it inside the shortening's band.
  // A choke is compared with itself on the marching surface: some chokes are deeper copies of a generator,
  // not separating.
  const bool generator = grid.choke.kind == Kind::Generator;
  std::string lost;
  if (generator || !out.separating) {
    if (topology.contractible_fast(s.edge_path)) lost = "is contractible there";
  }
  if (!generator && lost.empty() && topology.separates(s.edge_path) != out.separating)
    lost = out.separating ? "does not separate it (it separates the marching surface)"
                          : "separates it (it does not separate the marching surface)";
  if (!lost.empty()) {
    out.loop.note = "carried to the input mesh, the loop " + lost + ": its class was lost, no loop";
    return;
  }
  out.verified = true;
  out.loop.found = true;
  out.loop.points = s.points;
  out.loop.edge_path = s.edge_path;
  out.where = locate_loop_points(m, adj, s);
  describe_loop(out.loop);
  if (options.shorten && s.rings == 0) out.loop.note = "left unshortened: no annulus band around it on the input mesh";
  if (!added.empty()) {
    std::set<int> faces(s.strip_faces.begin(), s.strip_faces.end());
    for (std::size_t k = 0; k < s.edge_path.size() && s.strip_faces.empty(); ++k) {
      const int h = adj.halfedge(m, s.edge_path[k], s.edge_path[(k + 1) % s.edge_path.size()]);
      if (h >= 0) faces.insert(MeshAdjacency::face(h));
    }
    int through = 0;
    for (int f : faces) through += added[std::size_t(f)];
    if (through) {
      if (!out.loop.note.empty()) out.loop.note += "; ";
      out.loop.note += "runs through " + std::to_string(through) +
                       " face(s) that the repair added to close holes: there it is not on the file's surface";
    }
  }
}
}  // namespace

std::vector<InputPoint> locate_loop_points(const SurfaceMesh& mesh, const MeshAdjacency& adj, const ShortenResult& s) {
  return locate(mesh, adj, s.points, s.strip_faces, s.edge_path);
}

InputMesh input_mesh_from(const TriangleMesh& mesh, const std::string& name) {
  InputMesh in;
  in.report = mesh_topology(mesh);
  const TriangleMesh* use = &mesh;
  RepairedMesh repaired;
  if (!in.report.closed || in.report.nonmanifold_edges > 0) {
    repaired = repair_mesh(mesh, name);
    use = &repaired.mesh;
    in.repaired = true;
    in.report = repaired.report;
  }
  in.mesh.vertices = use->vertices;
  in.mesh.faces = use->faces;
  if (in.repaired) {
    // The repair merges and renumbers vertices, so faces are matched by their corners' points.
    using Corners = std::array<P3, 3>;
    auto corners = [](const TriangleMesh& t, const std::array<int, 3>& f) {
      Corners c{t.vertices[std::size_t(f[0])], t.vertices[std::size_t(f[1])], t.vertices[std::size_t(f[2])]};
      std::sort(c.begin(), c.end());
      return c;
    };
    std::set<Corners> file_faces;
    for (const auto& f : mesh.faces) file_faces.insert(corners(mesh, f));
    in.added_face.resize(use->faces.size());
    for (std::size_t f = 0; f < use->faces.size(); ++f) in.added_face[f] = !file_faces.count(corners(*use, use->faces[f]));
  }
  return in;
}

InputMesh load_input_mesh(const std::string& path) { return input_mesh_from(read_mesh(path), path); }

std::vector<InputLoop> transfer_loops(const InputMesh& input, const SurfaceMesh& grid_surface,
                                      const std::vector<Loop>& grid_loops, const InputLoopOptions& options) {
  std::vector<InputLoop> out(grid_loops.size());
  bool any = false;
  for (const Loop& l : grid_loops) any |= l.found;
  if (!any) {
    for (std::size_t i = 0; i < out.size(); ++i) mark_missing(grid_loops[i], out[i]);
    return out;
  }
  bool any_choke = false;
  for (const Loop& l : grid_loops) any_choke |= l.found && l.choke.kind == Kind::Choke;
  if (any_choke) {
    SurfaceTopology grid_topology(grid_surface);
    tbb::parallel_for(std::size_t(0), grid_loops.size(), [&](std::size_t i) {
      const Loop& l = grid_loops[i];
      if (l.found && l.choke.kind == Kind::Choke) out[i].separating = grid_topology.separates(l.edge_path);
    });
  }
  const SurfaceMesh& m = input.mesh;
  const MeshAdjacency adj = build_adjacency(m);
  SurfaceTopology topology(m, adj);
  Triangles triangles;
  triangles.reserve(m.faces.size());
  auto point = [&](int v) {
    const P3& p = m.vertices[std::size_t(v)];
    return K::Point_3(p[0], p[1], p[2]);
  };
  for (const auto& f : m.faces) triangles.emplace_back(point(f[0]), point(f[1]), point(f[2]));
  Tree tree(triangles.begin(), triangles.end());
  tree.accelerate_distance_queries();
  tbb::parallel_for(std::size_t(0), grid_loops.size(), [&](std::size_t i) {
    const auto t0 = std::chrono::steady_clock::now();
    carry(m, input.added_face, adj, topology, tree, triangles, grid_loops[i], options, out[i]);
    out[i].transfer_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  });
  release_shortening_scratch();
  return out;
}

}  // namespace chokeloops

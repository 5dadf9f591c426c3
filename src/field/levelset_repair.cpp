// Mesh repair and topology report with CGAL Polygon Mesh Processing (stage `levelset`).
#include <algorithm>
#include <map>
#include <sstream>
#include <unordered_map>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/border.h>
#include <CGAL/Polygon_mesh_processing/connected_components.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/orientation.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/repair_degeneracies.h>
#include <CGAL/Polygon_mesh_processing/repair_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Polygon_mesh_processing/stitch_borders.h>
#include <CGAL/Polygon_mesh_processing/triangulate_hole.h>
#include <CGAL/Surface_mesh.h>

#include "chokeloops/grid.h"
#include "chokeloops/io/mesh_io.h"

namespace chokeloops {
namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = K::Point_3;
using SMesh = CGAL::Surface_mesh<Point>;
namespace PMP = CGAL::Polygon_mesh_processing;

// Whether some connected component's vertices all lie in one plane (exact predicates).
bool has_flat_component(SMesh& m) {
  auto component = m.add_property_map<SMesh::Face_index, std::size_t>("f:chokeloops_component", 0).first;
  const std::size_t n = PMP::connected_components(m, component);
  std::vector<std::vector<Point>> points(n);
  for (auto f : m.faces())
    for (auto v : CGAL::vertices_around_face(m.halfedge(f), m)) points[component[f]].push_back(m.point(v));
  m.remove_property_map(component);
  for (auto& pts : points) {
    if (pts.size() < 4) return true;
    std::size_t b = 1, c = 0;
    while (b < pts.size() && pts[b] == pts[0]) ++b;
    for (std::size_t i = b + 1; i < pts.size() && !c; ++i)
      if (!CGAL::collinear(pts[0], pts[b], pts[i])) c = i;
    if (b >= pts.size() || !c) return true;
    bool flat = true;
    for (std::size_t i = 1; i < pts.size() && flat; ++i)
      flat = CGAL::orientation(pts[0], pts[b], pts[c], pts[i]) == CGAL::COPLANAR;
    if (flat) return true;
  }
  return false;
}

std::size_t count_components(SMesh& m) {
  auto component = m.add_property_map<SMesh::Face_index, std::size_t>("f:chokeloops_count", 0).first;
  const std::size_t n = PMP::connected_components(m, component);
  m.remove_property_map(component);
  return n;
}

std::uint64_t edge_key(std::size_t a, std::size_t b) {
  if (a > b) std::swap(a, b);
  return (std::uint64_t(a) << 32) | std::uint64_t(b);
}

// Fills V, E, F, components, Euler characteristic and genus of a Surface_mesh.
void fill_topology(const SMesh& sm, MeshReport& r) {
  r.vertices = sm.number_of_vertices();
  r.faces = sm.number_of_faces();
  auto fcc = const_cast<SMesh&>(sm).add_property_map<SMesh::Face_index, std::size_t>("f:cl_cc", 0).first;
  std::size_t nc = PMP::connected_components(sm, fcc);
  std::vector<long long> V(nc, 0), E(nc, 0), F(nc, 0), B(nc, 0);
  for (auto f : sm.faces()) ++F[fcc[f]];
  for (auto e : sm.edges()) {
    auto h = sm.halfedge(e);
    auto f = sm.face(h);
    if (f == SMesh::null_face()) f = sm.face(sm.opposite(h));
    if (f == SMesh::null_face()) continue;
    ++E[fcc[f]];
    if (sm.is_border(e)) ++B[fcc[f]];
  }
  for (auto v : sm.vertices()) {
    auto h = sm.halfedge(v);
    if (h == SMesh::null_halfedge()) continue;
    // find any incident face
    SMesh::Face_index f = SMesh::null_face();
    for (auto hh : CGAL::halfedges_around_target(h, sm)) {
      if (sm.face(hh) != SMesh::null_face()) { f = sm.face(hh); break; }
    }
    if (f != SMesh::null_face()) ++V[fcc[f]];
  }
  const_cast<SMesh&>(sm).remove_property_map(fcc);
  r.components = nc;
  r.euler = 0;
  r.component_genus.assign(nc, -1);
  bool all_closed = true;
  int total = 0;
  for (std::size_t c = 0; c < nc; ++c) {
    long long chi = V[c] - E[c] + F[c];
    r.euler += int(chi);
    if (B[c] == 0 && (2 - chi) % 2 == 0 && chi <= 2) {
      r.component_genus[c] = int((2 - chi) / 2);
      total += r.component_genus[c];
    } else {
      all_closed = false;
    }
  }
  r.genus = all_closed ? total : -1;
}

TriangleMesh to_triangle_mesh(SMesh& sm) {
  sm.collect_garbage();
  TriangleMesh out;
  out.vertices.reserve(sm.number_of_vertices());
  for (auto v : sm.vertices()) {
    const Point& p = sm.point(v);
    out.vertices.push_back({p.x(), p.y(), p.z()});
  }
  out.faces.reserve(sm.number_of_faces());
  for (auto f : sm.faces()) {
    std::array<int, 3> t{0, 0, 0};
    int k = 0;
    for (auto v : CGAL::vertices_around_face(sm.halfedge(f), sm)) {
      if (k < 3) t[k] = int(v.idx());
      ++k;
    }
    if (k == 3) out.faces.push_back(t);
  }
  return out;
}

}  // namespace

MeshReport mesh_topology(const TriangleMesh& mesh) {
  MeshReport r;
  r.input_vertices = r.vertices = mesh.vertices.size();
  r.input_faces = r.faces = mesh.faces.size();
  std::unordered_map<std::uint64_t, int> edges;
  edges.reserve(mesh.faces.size() * 2);
  for (auto& f : mesh.faces)
    for (int k = 0; k < 3; ++k) ++edges[edge_key(std::size_t(f[k]), std::size_t(f[(k + 1) % 3]))];
  for (auto& [key, n] : edges) {
    if (n == 1) ++r.boundary_edges;
    if (n > 2) ++r.nonmanifold_edges;
  }
  r.closed = r.boundary_edges == 0;
  // components through shared vertices (union-find)
  std::vector<int> parent(mesh.vertices.size());
  for (std::size_t i = 0; i < parent.size(); ++i) parent[i] = int(i);
  auto find = [&](int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  std::vector<char> used(mesh.vertices.size(), 0);
  for (auto& f : mesh.faces) {
    for (int k = 0; k < 3; ++k) used[f[k]] = 1;
    int a = find(f[0]);
    for (int k = 1; k < 3; ++k) {
      int b = find(f[k]);
      if (a != b) parent[b] = a;
    }
  }
  std::map<int, int> comp;
  std::vector<long long> V, E, F;
  for (std::size_t i = 0; i < parent.size(); ++i)
    if (used[i]) {
      auto it = comp.emplace(find(int(i)), int(comp.size())).first;
      if (V.size() <= std::size_t(it->second)) V.resize(it->second + 1, 0);
      ++V[it->second];
    }
  E.assign(comp.size(), 0);
  F.assign(comp.size(), 0);
  for (auto& f : mesh.faces) ++F[comp[find(f[0])]];
  for (auto& [key, n] : edges) ++E[comp[find(int(key & 0xffffffffu))]];
  r.components = comp.size();
  r.component_genus.assign(comp.size(), -1);
  int total = 0;
  for (std::size_t c = 0; c < comp.size(); ++c) {
    long long chi = V[c] - E[c] + F[c];
    r.euler += int(chi);
    if (r.closed && r.nonmanifold_edges == 0 && chi <= 2 && (2 - chi) % 2 == 0) {
      r.component_genus[c] = int((2 - chi) / 2);
      total += r.component_genus[c];
    }
  }
  r.genus = (r.closed && r.nonmanifold_edges == 0) ? total : -1;
  return r;
}

RepairedMesh repair_mesh(const TriangleMesh& mesh, const std::string& name, const MeshRepairOptions& options) {
  RepairedMesh out;
  MeshReport& r = out.report;
  r.input_vertices = mesh.vertices.size();
  r.input_faces = mesh.faces.size();
  const std::string who = "'" + name + "'";

  // Fast path: a closed, consistently oriented, edge-manifold triangle mesh without repeated indices
  // needs no repair (OpenVDB's conversion does not depend on the orientation); skip CGAL entirely, unless
  // asked for self-intersections, which need CGAL's structure.
  if (!options.check_self_intersections) {
    bool clean = !mesh.faces.empty();
    std::unordered_map<std::uint64_t, int> directed;
    directed.reserve(mesh.faces.size() * 4);
    for (auto& f : mesh.faces) {
      if (f[0] == f[1] || f[1] == f[2] || f[0] == f[2]) { clean = false; break; }
      for (int k = 0; k < 3 && clean; ++k) {
        const std::uint64_t key = (std::uint64_t(std::uint32_t(f[k])) << 32) | std::uint32_t(f[(k + 1) % 3]);
        if (++directed[key] > 1) clean = false;
      }
      if (!clean) break;
    }
    if (clean)
      for (auto& [key, n] : directed) {
        const std::uint64_t rev = (key << 32) | (key >> 32);
        if (directed.find(rev) == directed.end()) { clean = false; break; }
      }
    if (clean) {
      MeshReport t = mesh_topology(mesh);
      if (t.closed && t.nonmanifold_edges == 0 && t.genus >= 0) {
        out.report = t;
        out.mesh = mesh;
        // drop unreferenced vertices from the counts only (they do not affect the distance)
        return out;
      }
    }
  }

  std::vector<Point> points;
  points.reserve(mesh.vertices.size());
  for (auto& v : mesh.vertices) points.emplace_back(v[0], v[1], v[2]);
  std::vector<std::array<std::size_t, 3>> tris;
  tris.reserve(mesh.faces.size());
  for (auto& f : mesh.faces) tris.push_back({std::size_t(f[0]), std::size_t(f[1]), std::size_t(f[2])});

  // 1. soup repair: merge duplicate points, drop degenerate/duplicate polygons and isolated points
  std::vector<std::vector<std::size_t>> polys(tris.size());
  for (std::size_t i = 0; i < tris.size(); ++i) polys[i].assign(tris[i].begin(), tris[i].end());
  const std::size_t np0 = points.size(), nf0 = polys.size();
  PMP::repair_polygon_soup(points, polys,
                           CGAL::parameters::erase_all_duplicates(false).require_same_orientation(false));
  r.merged_vertices = np0 > points.size() ? np0 - points.size() : 0;
  r.removed_faces = nf0 - polys.size();
  if (polys.empty()) throw Error(who + ": every face is degenerate (no area); nothing to convert");

  // non-manifold edges of the cleaned soup
  {
    std::unordered_map<std::uint64_t, int> edges;
    edges.reserve(polys.size() * 2);
    for (auto& p : polys)
      for (std::size_t k = 0; k < p.size(); ++k) ++edges[edge_key(p[k], p[(k + 1) % p.size()])];
    for (auto& [key, n] : edges)
      if (n > 2) ++r.nonmanifold_edges;
  }

  // 2. consistent orientation (duplicates points where the soup is not manifold)
  const std::size_t np1 = points.size();
  PMP::orient_polygon_soup(points, polys);
  r.nonmanifold_vertices_split = points.size() - np1;

  SMesh sm;
  PMP::polygon_soup_to_polygon_mesh(points, polys, sm);
  points.clear();
  polys.clear();

  // 3. stitch borders that are geometrically the same, remove geometrically degenerate faces
  PMP::stitch_borders(sm);
  try {
    const std::size_t f0 = sm.number_of_faces();
    PMP::remove_degenerate_faces(sm);
    sm.collect_garbage();
    r.removed_faces += f0 > sm.number_of_faces() ? f0 - sm.number_of_faces() : 0;
  } catch (const std::exception&) {
    // leave as is: OpenVDB's mesh conversion copes with degenerate faces
  }
  // Faces that are not degenerate as index triples can all be degenerate as geometry (collinear points).
  // Nothing is left then, and CGAL's outward orientation reads the orientation of a first component that does
  // not exist (found by fuzzing).
  if (sm.number_of_faces() == 0) throw Error(who + ": every face is degenerate (no area); nothing to convert");

  // 4. boundary
  std::vector<SMesh::Halfedge_index> cycles;
  PMP::extract_boundary_cycles(sm, std::back_inserter(cycles));
  for (auto e : sm.edges())
    if (sm.is_border(e)) ++r.boundary_edges;
  r.holes = cycles.size();
  r.closed = r.boundary_edges == 0;

  if (r.removed_faces > 0 || r.merged_vertices > 0) {
    std::ostringstream s;
    s << who << ": repaired the soup: merged " << r.merged_vertices << " duplicate vertices, removed " << r.removed_faces
      << " degenerate or duplicate faces";
    if (r.removed_faces > 0) out.warnings.push_back(s.str());
  }
  if (r.nonmanifold_edges > 0 || r.nonmanifold_vertices_split > 0) {
    std::ostringstream s;
    s << who << ": non-manifold input: " << r.nonmanifold_edges << " edges with more than two faces, "
      << r.nonmanifold_vertices_split << " vertices split to orient the surface consistently";
    out.warnings.push_back(s.str());
  }

  // 5. fill holes
  if (!r.closed && options.fill_holes) {
    for (auto h : cycles) {
      std::size_t len = 0;
      for (auto hh : CGAL::halfedges_around_face(h, sm)) { (void)hh; ++len; }
      if (len > options.max_hole_edges) continue;
      std::vector<SMesh::Face_index> patch;
      try {
        PMP::triangulate_hole(sm, h, std::back_inserter(patch));
      } catch (const std::exception&) {
        patch.clear();
      }
      if (!patch.empty()) ++r.holes_filled;
    }
  }
  for (auto e : sm.edges())
    if (sm.is_border(e)) ++r.boundary_edges_remaining;

  if (!r.closed) {
    std::ostringstream s;
    s << who << ": mesh is open: " << r.boundary_edges << " boundary edges in " << r.holes << " holes";
    if (r.holes_filled > 0)
      s << "; filled " << r.holes_filled << " of them (CGAL triangulate_hole), the sign comes from the filled surface";
    if (r.boundary_edges_remaining > 0)
      s << "; " << r.boundary_edges_remaining
        << " boundary edges remain open";
    out.warnings.push_back(s.str());
  }

  // 6. outward orientation of closed meshes (nested components alternate). CGAL's orientation looks at
  // the extreme vertex of each component and is undefined (an assertion, then a crash) on a component that
  // encloses no volume: all its points coplanar. Such a mesh is left as it is (found by fuzzing).
  // It also decides the nesting of several components by casting rays from a point of each through the others,
  // and retries random rays for as long as every ray is indeterminate: for ever when that point lies on another
  // component, as where components touch or cross (found by fuzzing: a hang). Such a mesh keeps its orientation.
  bool intersection_checked = false;
  if (r.boundary_edges_remaining == 0 && !has_flat_component(sm)) {
    bool nesting_defined = true;
    if (count_components(sm) > 1) {
      r.self_intersecting = PMP::does_self_intersect(sm);
      intersection_checked = true;
      nesting_defined = !r.self_intersecting;
    }
    if (nesting_defined) {
      try {
        PMP::orient_to_bound_a_volume(sm);
      } catch (const std::exception&) {
      }
    }
  }
  if (options.check_self_intersections && !intersection_checked) r.self_intersecting = PMP::does_self_intersect(sm);
  if (options.check_self_intersections && r.self_intersecting)
    out.warnings.push_back(who + ": the surface intersects itself");

  fill_topology(sm, r);
  out.mesh = to_triangle_mesh(sm);
  return out;
}

}  // namespace chokeloops

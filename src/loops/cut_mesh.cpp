// Cutting a mesh along closed edge loops and capping the cuts (cut_mesh.h), on a CGAL Surface_mesh: its
// indices are stable (nothing is removed), so the input's faces keep their numbers and the caps come after.
#include "chokeloops/loops/cut_mesh.h"

#include <algorithm>
#include <set>
#include <unordered_map>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/clip.h>
#include <CGAL/Polygon_mesh_processing/triangulate_hole.h>
#include <CGAL/Surface_mesh.h>

#include "chokeloops/grid.h"
#include "chokeloops/surface/topology.h"

namespace chokeloops {

namespace {
using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using SM = CGAL::Surface_mesh<K::Point_3>;
using V = SM::Vertex_index;
namespace PMP = CGAL::Polygon_mesh_processing;

// Records which vertex each copy made by the split came from.
struct CopyVisitor : PMP::Corefinement::Default_visitor<SM> {
  std::vector<std::pair<V, V>>* copies;
  void after_vertex_copy(V src, const SM&, V copy, const SM&) { copies->push_back({src, copy}); }
};

// The loop on the mesh as cut so far: each vertex an earlier cut split is replaced by the copy that keeps the
// loop's edges (a loop that only touches an earlier one stays on one side of it). Empty when no choice of
// copies does: the loop crosses an earlier cut.
std::vector<V> follow_copies(const SM& sm, const std::vector<int>& loop, const std::vector<std::vector<V>>& copies_of) {
  const std::size_t n = loop.size();
  auto options = [&](std::size_t k) {
    std::vector<V> c{V(loop[k])};
    const auto& more = copies_of[std::size_t(loop[k])];
    c.insert(c.end(), more.begin(), more.end());
    return c;
  };
  for (V start : options(0)) {
    std::vector<V> path{start};
    for (std::size_t k = 1; k <= n && path.size() == k; ++k) {
      const std::vector<V> next = k < n ? options(k) : std::vector<V>{start};
      for (V c : next)
        if (CGAL::halfedge(path.back(), c, sm).second) {
          if (k < n) path.push_back(c);
          else return path;
          break;
        }
    }
  }
  return {};
}
}  // namespace

CutResult cut_along_loops(const TriangleMesh& mesh, const std::vector<std::vector<int>>& loops, const std::vector<int>& ids) {
  CutResult r;
  auto name = [&](std::size_t i) { return "loop " + std::to_string(i < ids.size() ? ids[i] : int(i)); };
  r.before = mesh_topology(mesh);
  SM sm;
  for (const auto& v : mesh.vertices) sm.add_vertex(K::Point_3(v[0], v[1], v[2]));
  for (std::size_t f = 0; f < mesh.faces.size(); ++f) {
    const auto& t = mesh.faces[f];
    if (sm.add_face(V(t[0]), V(t[1]), V(t[2])) == SM::null_face())
      throw Error("cannot cut: face " + std::to_string(f) +
                  " makes the mesh non-manifold or inconsistently oriented (CGAL's Surface_mesh refuses it)");
  }
  const std::size_t nv = mesh.vertices.size();
  for (std::size_t i = 0; i < loops.size(); ++i) {
    const auto& loop = loops[i];
    if (!loop_is_simple(loop))
      throw Error("cannot cut along " + name(i) + ": it passes a vertex twice or has fewer than 3 vertices");
    for (std::size_t k = 0; k < loop.size(); ++k) {
      const int a = loop[k], b = loop[(k + 1) % loop.size()];
      if (a < 0 || b < 0 || std::size_t(a) >= nv || std::size_t(b) >= nv)
        throw Error("cannot cut along " + name(i) + ": vertex index out of range");
      if (!CGAL::halfedge(V(a), V(b), sm).second)
        throw Error("cannot cut along " + name(i) + ": vertices " + std::to_string(a) + " and " +
                    std::to_string(b) + " are not joined by an edge");
    }
  }
  std::set<SM::Halfedge_index> old_border;
  for (auto h : sm.halfedges())
    if (sm.is_border(h)) old_border.insert(h);
  // One loop at a time, each cut capped before the next: loops that touch (share a vertex) then still give
  // one cut each, where cutting all at once would merge their borders into one.
  std::vector<std::vector<V>> copies_of(nv);
  std::unordered_map<std::size_t, std::size_t> origin;  // copy -> input vertex
  std::vector<std::pair<V, V>> copies;
  CopyVisitor visitor;
  visitor.copies = &copies;
  auto cut = sm.add_property_map<SM::Edge_index, bool>("e:chokeloops_cut", false).first;
  for (std::size_t i = 0; i < loops.size(); ++i) {
    const std::vector<V> path = follow_copies(sm, loops[i], copies_of);
    if (path.empty()) {
      r.notes.push_back(name(i) + " crosses an earlier cut: not cut");
      continue;
    }
    for (auto e : sm.edges()) put(cut, e, false);
    for (std::size_t k = 0; k < path.size(); ++k)
      put(cut, sm.edge(CGAL::halfedge(path[k], path[(k + 1) % path.size()], sm).first), true);
    copies.clear();
    PMP::internal::split_along_edges(sm, cut, sm.points(), visitor);
    for (auto [src, copy] : copies) {  // a copy of a copy still stands for the input's vertex
      const std::size_t o = std::size_t(src) < nv ? std::size_t(src) : origin.at(std::size_t(src));
      origin[std::size_t(copy)] = o;
      copies_of[o].push_back(copy);
    }
    ++r.loops_cut;
    // One representative per border cycle the split opened (collected first: filling adds halfedges).
    std::vector<SM::Halfedge_index> holes;
    std::set<SM::Halfedge_index> seen;
    for (auto h : sm.halfedges()) {
      if (!sm.is_border(h) || old_border.count(h) || seen.count(h)) continue;
      holes.push_back(h);
      for (auto g = h; seen.insert(g).second; g = sm.next(g)) {
      }
    }
    for (auto h : holes) {
      std::vector<SM::Face_index> patch;
      PMP::triangulate_hole(sm, h, std::back_inserter(patch));
      if (patch.empty()) throw Error("cannot cap the cut along " + name(i) + ": CGAL's triangulate_hole found no triangulation");
      r.cap_faces += int(patch.size());
      ++r.caps;
    }
  }

  for (auto v : sm.vertices()) {
    const auto& p = sm.point(v);
    r.mesh.vertices.push_back({p.x(), p.y(), p.z()});
  }
  for (auto f : sm.faces()) {
    std::array<int, 3> t{};
    int k = 0;
    for (auto v : CGAL::vertices_around_face(sm.halfedge(f), sm)) {
      if (k == 3) throw InternalError("cut: a face with more than 3 corners");
      t[k++] = int(std::size_t(v));
    }
    if (std::size_t(f) < mesh.faces.size()) {
      // Same first corner as the input's face (a copy on the cut has the same point), so untouched faces are
      // written exactly as they were read.
      const auto& first = mesh.vertices[std::size_t(mesh.faces[std::size_t(f)][0])];
      for (int rot = 0; rot < 3 && r.mesh.vertices[std::size_t(t[0])] != first; ++rot) std::rotate(t.begin(), t.begin() + 1, t.end());
    }
    r.mesh.faces.push_back(t);
  }
  r.after = mesh_topology(r.mesh);
  return r;
}

}  // namespace chokeloops

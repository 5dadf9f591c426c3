#include "chokeloops/surface/topology.h"

#include <CGAL/Curves_on_surface_topology.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Path_on_surface.h>
#include <CGAL/Surface_mesh.h>
#include <tbb/blocked_range.h>
#include <tbb/combinable.h>
#include <tbb/parallel_for.h>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <mutex>
#include <queue>
#include <unordered_map>
#include <unordered_set>

#include "chokeloops/surface/mesh_adjacency.h"
#include "homology_basis.h"

namespace chokeloops {

namespace {
using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using SM = CGAL::Surface_mesh<K::Point_3>;
using CST = CGAL::Surface_mesh_topology::Curves_on_surface_topology<SM>;
using Path = CGAL::Surface_mesh_topology::Path_on_surface<SM>;

double dist(const std::array<double, 3>& a, const std::array<double, 3>& b) {
  return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}
}  // namespace

struct SurfaceTopology::Impl {
  const SurfaceMesh& mesh;
  MeshAdjacency own;
  const MeshAdjacency& adj;
  std::vector<int> face_label;
  std::vector<int> vertex_label;
  int components = 0;
  std::vector<std::int64_t> euler;  // per component: V - E + F
  std::vector<char> closed;         // per component: every edge has two faces
  std::mutex cgal_lock;
  int cgal_queries = 0;  // guarded by cgal_lock
  struct Component {
    std::unique_ptr<SM> sm;
    std::unique_ptr<CST> cst;
    std::unordered_map<int, SM::Vertex_index> local;
  };
  std::map<int, Component> comps;
  std::once_flag basis_once;
  std::unique_ptr<HomologyBasis> basis;  // built on the first homology query

  const HomologyBasis& homology() {
    std::call_once(basis_once, [&] { basis = std::make_unique<HomologyBasis>(mesh, adj, face_label, closed); });
    return *basis;
  }

  Impl(const SurfaceMesh& m, const MeshAdjacency* a, std::vector<int>* labels = nullptr, int n_components = 0)
      : mesh(m), own(a ? MeshAdjacency{} : build_adjacency(m)), adj(a ? *a : own) {
    if (labels) face_label = std::move(*labels), components = n_components;
    else components = face_components(m, face_label);
    // A vertex takes the component of its last face (the faces around it rise): on a surface of millions of
    // faces these passes run in parallel, each thread counting into its own per-component sums.
    const std::size_t V = m.vertices.size(), F = m.faces.size(), C = std::size_t(std::max(components, 0));
    vertex_label.resize(V);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, V, 1 << 14), [&](const tbb::blocked_range<std::size_t>& r) {
      for (std::size_t v = r.begin(); v != r.end(); ++v) {
        const int last = adj.vf_start[v + 1] - 1;
        vertex_label[v] = last >= adj.vf_start[v] ? face_label[std::size_t(adj.vf[std::size_t(last)])] : -1;
      }
    });
    struct Counts {
      std::vector<std::int64_t> vertices, edges, faces;
      std::vector<char> open;
    };
    tbb::combinable<Counts> counts([C] { return Counts{std::vector<std::int64_t>(C, 0), std::vector<std::int64_t>(C, 0),
                                                       std::vector<std::int64_t>(C, 0), std::vector<char>(C, 0)}; });
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, std::max(V, F), 1 << 14), [&](const tbb::blocked_range<std::size_t>& r) {
      Counts& c = counts.local();
      for (std::size_t i = r.begin(); i != r.end(); ++i) {
        if (i < V && vertex_label[i] >= 0) ++c.vertices[std::size_t(vertex_label[i])];
        if (i >= F) continue;
        const std::size_t label = std::size_t(face_label[i]);
        ++c.faces[label];
        for (int k = 0; k < 3; ++k) {
          const int h = int(3 * i) + k, t = adj.twin[std::size_t(h)];
          if (t < 0) c.open[label] = 1;
          if (t < 0 || h < t) ++c.edges[label];
        }
      }
    });
    euler.assign(C, 0);
    closed.assign(C, 1);
    counts.combine_each([&](const Counts& c) {
      for (std::size_t k = 0; k < C; ++k) {
        euler[k] += c.vertices[k] - c.edges[k] + c.faces[k];
        if (c.open[k]) closed[k] = 0;
      }
    });
  }

  void check(const std::vector<int>& loop) const {
    if (loop.empty()) throw Error("loop is empty");
    for (int v : loop)
      if (v < 0 || size_t(v) >= mesh.vertices.size()) throw Error("loop vertex index out of range");
    for (size_t i = 0; i < loop.size(); ++i) {
      int a = loop[i], b = loop[(i + 1) % loop.size()];
      if (!adj.has_edge(mesh, a, b)) throw Error("loop vertices " + std::to_string(a) + " and " + std::to_string(b) +
                                           " are not joined by a mesh edge");
    }
  }

  Component& component(int c) {
    auto it = comps.find(c);
    if (it != comps.end()) return it->second;
    Component& C = comps[c];
    C.sm = std::make_unique<SM>();
    for (size_t f = 0; f < mesh.faces.size(); ++f) {
      if (face_label[f] != c) continue;
      std::array<SM::Vertex_index, 3> vs;
      for (int k = 0; k < 3; ++k) {
        int v = mesh.faces[f][k];
        auto j = C.local.find(v);
        if (j == C.local.end()) {
          auto& p = mesh.vertices[v];
          j = C.local.emplace(v, C.sm->add_vertex(K::Point_3(p[0], p[1], p[2]))).first;
        }
        vs[k] = j->second;
      }
      if (C.sm->add_face(vs[0], vs[1], vs[2]) == SM::null_face())
        throw Error("surface component is not an oriented 2-manifold; cannot test contractibility");
    }
    C.cst = std::make_unique<CST>(*C.sm);
    return C;
  }
};

SurfaceTopology::SurfaceTopology(const SurfaceMesh& mesh) : impl_(std::make_unique<Impl>(mesh, nullptr)) {}
SurfaceTopology::SurfaceTopology(const SurfaceMesh& mesh, const MeshAdjacency& adjacency)
    : impl_(std::make_unique<Impl>(mesh, &adjacency)) {}
SurfaceTopology::SurfaceTopology(const SurfaceMesh& mesh, const MeshAdjacency& adjacency, std::vector<int> face_label,
                                 int components) {
  if (face_label.size() != mesh.faces.size()) throw Error("face labels do not match the surface's faces");
  impl_ = std::make_unique<Impl>(mesh, &adjacency, &face_label, components);
}
SurfaceTopology::~SurfaceTopology() = default;

int SurfaceTopology::cgal_queries() const {
  std::lock_guard<std::mutex> hold(impl_->cgal_lock);
  return impl_->cgal_queries;
}

int SurfaceTopology::component_of_vertex(int v) const { return impl_->vertex_label.at(size_t(v)); }

bool SurfaceTopology::contractible(const std::vector<int>& loop) {
  impl_->check(loop);
  if (loop.size() < 3) return true;  // a point or an edge traversed back and forth
  std::lock_guard<std::mutex> hold(impl_->cgal_lock);
  ++impl_->cgal_queries;
  auto& C = impl_->component(impl_->vertex_label[loop[0]]);
  Path p(*C.sm);
  for (size_t i = 0; i < loop.size(); ++i) {
    auto a = C.local.at(loop[i]), b = C.local.at(loop[(i + 1) % loop.size()]);
    auto h = CGAL::halfedge(a, b, *C.sm);
    if (!h.second) throw Error("loop edge missing from the component mesh");
    p.push_back(h.first, false, false);
  }
  p.update_is_closed();
  if (!p.is_closed()) throw Error("loop is not closed");
  return C.cst->is_contractible(p);
}

bool SurfaceTopology::contractible_fast(const std::vector<int>& loop) {
  impl_->check(loop);
  if (loop.size() < 3) return true;
  const auto& mesh = impl_->mesh;
  const auto& adj = impl_->adj;
  const int c = impl_->vertex_label[loop[0]];
  if (c < 0 || !impl_->closed[c]) return contractible(loop);
  // Not null in homology: essential, in time proportional to the loop (a generator's usual answer).
  if (!impl_->homology().null_homologous(loop)) return false;
  if (!loop_is_simple(loop)) return contractible(loop);
  auto key = [](int a, int b) { return (std::uint64_t(std::uint32_t(std::min(a, b))) << 32) | std::uint32_t(std::max(a, b)); };
  std::unordered_set<std::uint64_t> cut;
  std::vector<char> on_loop(mesh.vertices.size(), 0);  // spares most edges the hash look-up
  for (size_t i = 0; i < loop.size(); ++i) {
    cut.insert(key(loop[i], loop[(i + 1) % loop.size()]));
    on_loop[loop[i]] = 1;
  }
  int h0 = adj.halfedge(mesh, loop[0], loop[1]);
  if (h0 < 0) h0 = adj.halfedge(mesh, loop[1], loop[0]);  // the loop runs against the faces' orientation
  const int t0 = h0 < 0 ? -1 : adj.twin[h0];
  if (t0 < 0) return contractible(loop);
  // side[f]: 0 unseen, 1 or 2 the side of the loop whose flood reached f first.
  std::vector<char> side(mesh.faces.size(), 0);
  std::array<std::vector<int>, 2> queue{std::vector<int>{MeshAdjacency::face(h0)}, std::vector<int>{MeshAdjacency::face(t0)}};
  std::array<std::size_t, 2> head{0, 0};
  side[queue[0][0]] = 1;
  side[queue[1][0]] = 2;
  int done = -1;
  while (done < 0) {
    for (int s = 0; s < 2 && done < 0; ++s) {
      if (head[s] == queue[s].size()) { done = s; break; }
      int f = queue[s][head[s]++];
      for (int k = 0; k < 3; ++k) {
        int a = mesh.faces[f][k], b = mesh.faces[f][(k + 1) % 3];
        if (on_loop[a] && on_loop[b] && cut.count(key(a, b))) continue;
        int g = MeshAdjacency::face(adj.twin[3 * f + k]);
        if (side[g] == 0) { side[g] = char(s + 1); queue[s].push_back(g); }
        else if (side[g] != s + 1) return false;  // both sides are one: the loop does not separate
      }
    }
  }
  // The loop separates; side `done` is complete. Its Euler characteristic (the loop's edges and vertices
  // included once) decides whether it is a disk; the other side's is the component's minus it (the loop,
  // a circle, has characteristic 0).
  const auto& faces = queue[done];
  std::vector<char> seen(mesh.vertices.size(), 0);
  std::int64_t V = 0;
  for (int f : faces)
    for (int k = 0; k < 3; ++k)
      if (!seen[mesh.faces[f][k]]) seen[mesh.faces[f][k]] = 1, ++V;
  const std::int64_t F = std::int64_t(faces.size()), L = std::int64_t(loop.size());
  const std::int64_t E = (3 * F + L) / 2;  // interior edges are shared by two of its faces, loop edges not
  const std::int64_t chi = V - E + F;
  return chi == 1 || impl_->euler[c] - chi == 1;
}

void SurfaceTopology::prepare_homology() { impl_->homology(); }

bool SurfaceTopology::null_homologous(const std::vector<int>& loop) {
  impl_->check(loop);
  const int c = impl_->vertex_label[loop[0]];
  if (c < 0 || !impl_->closed[c]) return contractible(loop);
  return impl_->homology().null_homologous(loop);
}

bool SurfaceTopology::separates(const std::vector<int>& loop) {
  impl_->check(loop);
  const auto& mesh = impl_->mesh;
  const auto& adj = impl_->adj;
  int c = impl_->vertex_label[loop[0]];
  // A simple loop through vertices that each have one oriented disc of faces around them, on a closed
  // component, has two sides along its whole length, each connected: it separates exactly when they are
  // apart, which is when it bounds a set of faces, i.e. is null in Z/2 homology. That costs the loop's
  // length; the flood below costs the whole component.
  if (c >= 0 && impl_->closed[c] && loop_is_simple(loop) &&
      std::all_of(loop.begin(), loop.end(), [&](int v) { return turns_once_around(mesh, adj, v); }))
    return impl_->homology().null_homologous(loop);
  auto key = [](int a, int b) { return (std::uint64_t(std::uint32_t(std::min(a, b))) << 32) | std::uint32_t(std::max(a, b)); };
  std::unordered_set<std::uint64_t> cut;
  for (size_t i = 0; i < loop.size(); ++i) cut.insert(key(loop[i], loop[(i + 1) % loop.size()]));
  // Flood the component's faces from one face, never crossing a cut edge.
  int start = -1;
  size_t total = 0;
  for (size_t f = 0; f < mesh.faces.size(); ++f)
    if (impl_->face_label[f] == c) {
      if (start < 0) start = int(f);
      ++total;
    }
  std::vector<char> seen(mesh.faces.size(), 0);
  std::vector<int> stack{start};
  seen[start] = 1;
  size_t reached = 1;
  while (!stack.empty()) {
    int f = stack.back();
    stack.pop_back();
    for (int k = 0; k < 3; ++k) {
      int h = 3 * f + k, t = adj.twin[h];
      if (t < 0) continue;
      if (cut.count(key(mesh.faces[f][k], mesh.faces[f][(k + 1) % 3]))) continue;
      int g = MeshAdjacency::face(t);
      if (!seen[g]) {
        seen[g] = 1;
        ++reached;
        stack.push_back(g);
      }
    }
  }
  return reached < total;
}

bool loop_is_contractible(const SurfaceMesh& mesh, const std::vector<int>& loop) {
  SurfaceTopology t(mesh);
  return t.contractible(loop);
}
bool loop_separates_surface(const SurfaceMesh& mesh, const std::vector<int>& loop) {
  SurfaceTopology t(mesh);
  return t.separates(loop);
}

bool loop_is_simple(const std::vector<int>& loop) {
  if (loop.size() < 3) return false;
  std::vector<int> s(loop);
  std::sort(s.begin(), s.end());
  return std::adjacent_find(s.begin(), s.end()) == s.end();
}

double closed_length(const Polyline3& p) {
  double L = 0;
  for (size_t i = 0; i < p.size(); ++i) L += dist(p[i], p[(i + 1) % p.size()]);
  return L;
}
void best_fit_plane(const Polyline3& points, std::array<double, 3>& centroid, std::array<double, 3>& normal) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : points) mean += Eigen::Vector3d(p[0], p[1], p[2]);
  mean /= double(points.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto& p : points) {
    const Eigen::Vector3d d = Eigen::Vector3d(p[0], p[1], p[2]) - mean;
    cov += d * d.transpose();
  }
  const Eigen::Vector3d n = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(cov).eigenvectors().col(0);
  centroid = {mean[0], mean[1], mean[2]};
  normal = {n[0], n[1], n[2]};
}

Polyline3 loop_points(const SurfaceMesh& mesh, const std::vector<int>& loop) {
  Polyline3 p;
  for (int v : loop) p.push_back(mesh.vertices.at(size_t(v)));
  return p;
}
double loop_length(const SurfaceMesh& mesh, const std::vector<int>& loop) { return closed_length(loop_points(mesh, loop)); }

void remove_repeats_and_spurs(std::vector<int>& path) {
  // Spurs a b a -> a and repeats, cyclically, until stable.
  bool changed = true;
  while (changed && path.size() >= 3) {
    changed = false;
    std::vector<int> out;
    for (int v : path) {
      if (!out.empty() && out.back() == v) { changed = true; continue; }
      if (out.size() >= 2 && out[out.size() - 2] == v) { out.pop_back(); changed = true; continue; }
      out.push_back(v);
    }
    while (out.size() >= 2 && out.front() == out.back()) out.pop_back(), changed = true;
    while (out.size() >= 3 && out[out.size() - 2] == out.front()) out.pop_back(), changed = true;
    while (out.size() >= 3 && out[1] == out.back()) {  // spur through the start: b a b ... -> rotate away
      out.erase(out.begin());
      out.pop_back();
      changed = true;
    }
    path.swap(out);
  }
}

std::vector<int> snap_polyline_to_edge_path(const SurfaceMesh& mesh, const Polyline3& polyline, int component) {
  return snap_polyline_to_edge_path(mesh, nullptr, polyline, component);
}
std::vector<int> snap_polyline_to_edge_path(const SurfaceMesh& mesh, const MeshAdjacency& adj, const Polyline3& polyline,
                                            int component) {
  return snap_polyline_to_edge_path(mesh, &adj, polyline, component);
}

std::vector<int> snap_polyline_to_edge_path(const SurfaceMesh& mesh, const MeshAdjacency* adj, const Polyline3& polyline,
                                            int component) {
  if (polyline.empty()) throw Error("polyline is empty");
  if (mesh.faces.empty()) throw Error("surface is empty");
  MeshAdjacency own;
  if (!adj) own = build_adjacency(mesh);
  const MeshAdjacency& A = adj ? *adj : own;
  std::vector<int> vlabel;
  if (component >= 0) {
    std::vector<int> fl;
    face_components(mesh, fl);
    vlabel.assign(mesh.vertices.size(), -1);
    for (size_t f = 0; f < mesh.faces.size(); ++f)
      for (int k = 0; k < 3; ++k) vlabel[mesh.faces[f][k]] = fl[f];
  }
  auto accept = [&](int v) { return component < 0 || vlabel[v] == component; };
  // Everything below touches only vertices near the polyline (the adjacency's vertex cells, searches that
  // stop at the next point), so that snapping a loop costs what the loop's neighbourhood holds.
  const double edge = A.mean_edge;
  double seg = 0;
  for (size_t i = 0; i < polyline.size(); ++i) seg = std::max(seg, dist(polyline[i], polyline[(i + 1) % polyline.size()]));
  const double margin = 4 * std::max(edge, seg) + 4 * edge;
  std::vector<int> snapped;
  for (auto& p : polyline) {
    int v = A.nearest_vertex(mesh, p, margin, accept);
    if (v >= 0 && (snapped.empty() || snapped.back() != v)) snapped.push_back(v);
  }
  while (snapped.size() > 1 && snapped.back() == snapped.front()) snapped.pop_back();
  if (snapped.empty()) throw Error("no surface vertex near the polyline");
  if (snapped.size() < 2) return {snapped[0]};
  // Join consecutive vertices by shortest edge paths: a search that gives up past a few margins (the two
  // points are then not joined near the polyline).
  struct State { double d; int from; };
  std::unordered_map<int, State> state;
  std::vector<int> path, around;
  for (size_t i = 0; i < snapped.size(); ++i) {
    const int s = snapped[i], t = snapped[(i + 1) % snapped.size()];
    // Neighbours (most pairs of a dense polyline): their edge is the shortest path between them, a straight
    // segment; the search below would find it too, at a hash map and a heap's cost.
    if (A.has_edge(mesh, s, t)) {
      path.push_back(s);
      continue;
    }
    const double limit = 2 * dist(mesh.vertices[s], mesh.vertices[t]) + 4 * margin;
    state.clear();
    using QE = std::pair<double, int>;
    std::priority_queue<QE, std::vector<QE>, std::greater<QE>> q;
    state[s] = {0, -1};
    q.push({0, s});
    bool reached = false;
    while (!q.empty()) {
      auto [dv, v] = q.top();
      q.pop();
      if (dv > state[v].d) continue;
      if (v == t) { reached = true; break; }
      if (dv > limit) break;
      A.neighbours(mesh, v, around);
      for (const int w : around) {
        if (!accept(w)) continue;
        const double nd = dv + dist(mesh.vertices[v], mesh.vertices[w]);
        auto it = state.find(w);
        if (it == state.end()) state.emplace(w, State{nd, v}), q.push({nd, w});
        else if (nd < it->second.d) it->second = {nd, v}, q.push({nd, w});
      }
    }
    if (!reached) throw Error("polyline points are not connected on the surface");
    std::vector<int> seg_path;
    for (int v = t; v != s; v = state[v].from) seg_path.push_back(v);
    std::reverse(seg_path.begin(), seg_path.end());  // excludes s, ends with t
    path.push_back(s);
    for (size_t k = 0; k + 1 < seg_path.size(); ++k) path.push_back(seg_path[k]);
  }
  remove_repeats_and_spurs(path);
  // Cut out repeated vertices (figure-eights): keep the longest simple piece is not homotopy-safe, so
  // leave them; callers check loop_is_simple.
  return path;
}

}  // namespace chokeloops

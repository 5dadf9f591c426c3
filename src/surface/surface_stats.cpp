// Counts of a triangle mesh (edges, boundary and non-manifold elements, components, each component's genus),
// read from its adjacency: every vertex looks only at its own faces and their twins, in parallel, so that the
// statistics of a 17.7M-face molecular surface cost a pass over its vertices rather than a sort of its 53M
// half-edges.
#include "chokeloops/surface/mesh_adjacency.h"
#include "chokeloops/surface/surface.h"

#include "halfedge_groups.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>
#include <array>

namespace chokeloops {

namespace {

// Disjoint sets joined from many threads at once: a root is linked only by a compare-and-swap of its own
// parent, always under the smaller root, so each set's root is its smallest vertex whatever the order of
// the unions (the serial UnionFind's result). Path halving may race, but only ever points a vertex at one
// of its ancestors.
struct ConcurrentUnionFind {
  std::vector<int> p;
  explicit ConcurrentUnionFind(std::size_t n) : p(n) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1 << 16), [&](const tbb::blocked_range<std::size_t>& r) {
      for (std::size_t i = r.begin(); i < r.end(); ++i) p[i] = int(i);
    });
  }
  int parent(int x) const { return __atomic_load_n(&p[std::size_t(x)], __ATOMIC_RELAXED); }
  int find(int x) {
    for (int up = parent(x); up != x; up = parent(x)) {
      const int grand = parent(up);
      __atomic_compare_exchange_n(&p[std::size_t(x)], &up, grand, false, __ATOMIC_RELAXED, __ATOMIC_RELAXED);
      x = grand;
    }
    return x;
  }
  void unite(int a, int b) {
    for (;;) {
      a = find(a), b = find(b);
      if (a == b) return;
      if (a < b) std::swap(a, b);
      int expected = a;  // a is still a root: hang it under b
      if (__atomic_compare_exchange_n(&p[std::size_t(a)], &expected, b, false, __ATOMIC_ACQ_REL, __ATOMIC_RELAXED))
        return;
    }
  }
};

}  // namespace

int face_components(const SurfaceMesh& mesh, std::vector<int>& face_label) {
  ConcurrentUnionFind uf(mesh.vertices.size());
  const std::size_t nf = mesh.faces.size();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nf, 1 << 14), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t fi = r.begin(); fi < r.end(); ++fi) {
      const auto& t = mesh.faces[fi];
      uf.unite(t[0], t[1]);
      uf.unite(t[0], t[2]);
    }
  });
  // Each face's root in parallel; the labels then follow the faces' order, as before.
  face_label.resize(nf);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nf, 1 << 14), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t fi = r.begin(); fi < r.end(); ++fi) face_label[fi] = uf.find(mesh.faces[fi][0]);
  });
  std::vector<int> label(mesh.vertices.size(), -1);
  int n = 0;
  for (std::size_t fi = 0; fi < nf; ++fi) {
    int& l = label[std::size_t(face_label[fi])];
    if (l < 0) l = n++;
    face_label[fi] = l;
  }
  return n;
}

SurfaceStats surface_stats(const SurfaceMesh& mesh) { return surface_stats(mesh, build_adjacency(mesh)); }

namespace {

struct AtVertex {
  int edges = 0;           // edges whose smaller end this vertex is
  int bad_edges = 0;       // of them, those without two faces or whose two faces use them in one direction
  bool nonmanifold = false;  // its faces form more than one fan
};

// The edges at v and the fans of its faces: the faces around v joined across the manifold edges (those with
// a twin) at v. `fan` and `bad` are scratch space.
AtVertex count_at_vertex(const SurfaceMesh& mesh, const MeshAdjacency& A, int v, std::vector<int>& fan,
                         std::vector<int>& bad) {
  AtVertex out;
  const int b0 = A.vf_start[std::size_t(v)], b1 = A.vf_start[std::size_t(v) + 1];
  if (b0 == b1) return out;
  // The usual vertex: one disc of faces, each with one corner here, whose next vertices are its neighbours,
  // each once (a neighbour met twice would leave its edge four half-edges and no twins).
  auto disc_edges = [&]() -> int {
    int edges = 0;
    for (int i = b0; i < b1; ++i) {
      if (i > b0 && A.vf[std::size_t(i)] == A.vf[std::size_t(i - 1)]) return -1;  // two corners here
      const auto& t = mesh.faces[std::size_t(A.vf[std::size_t(i)])];
      const int k = t[0] == v ? 0 : t[1] == v ? 1 : 2;
      edges += t[(k + 1) % 3] > v;
    }
    return edges;
  };
  if (turns_once_around(mesh, A, v) && (out.edges = disc_edges()) >= 0) return out;
  A.neighbours(mesh, v, fan);
  out.edges = int(fan.end() - std::upper_bound(fan.begin(), fan.end(), v));
  const auto f0 = A.vf.begin() + b0, f1 = A.vf.begin() + b1;
  auto slot = [&](int f) { return int(std::lower_bound(f0, f1, f) - f0); };  // faces around v rise
  fan.resize(std::size_t(b1 - b0));
  for (std::size_t i = 0; i < fan.size(); ++i) fan[i] = int(i);
  auto root = [&](int i) {
    while (fan[std::size_t(i)] != i) i = fan[std::size_t(i)] = fan[std::size_t(fan[std::size_t(i)])];
    return i;
  };
  bad.clear();
  for (int i = b0; i < b1; ++i) {
    const int f = A.vf[std::size_t(i)];
    if (i > b0 && A.vf[std::size_t(i - 1)] == f) continue;
    const auto& t = mesh.faces[std::size_t(f)];
    for (int k = 0; k < 3; ++k) {
      const int a = t[k], b = t[(k + 1) % 3];
      if (a != v && b != v) continue;
      const int other = a == v ? b : a, h = 3 * f + k, tw = A.twin[std::size_t(h)];
      if (tw < 0) {
        if (other >= v) bad.push_back(other);
        continue;
      }
      const int x = root(slot(f)), y = root(slot(tw / 3));
      if (x != y) fan[std::size_t(std::max(x, y))] = std::min(x, y);
      // both faces of the edge are around v: count the pair once, from its smaller half-edge
      if (other >= v && h < tw && mesh.faces[std::size_t(tw / 3)][tw % 3] == a) ++out.bad_edges;
    }
  }
  std::sort(bad.begin(), bad.end());
  out.bad_edges += int(std::unique(bad.begin(), bad.end()) - bad.begin());
  int fans = 0;
  for (int i = 0; i < b1 - b0; ++i) fans += (i == 0 || f0[i] != f0[i - 1]) && root(i) == i;
  out.nonmanifold = fans > 1;
  return out;
}

}  // namespace

SurfaceStats surface_stats(const SurfaceMesh& mesh, const MeshAdjacency& A, std::vector<int>* face_label) {
  SurfaceStats s;
  const std::size_t nv = mesh.vertices.size();
  s.vertices = std::int64_t(nv);
  s.faces = std::int64_t(mesh.faces.size());
  std::vector<AtVertex> at_vertex(nv);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    std::vector<int> fan, bad;
    for (std::size_t v = r.begin(); v < r.end(); ++v) at_vertex[v] = count_at_vertex(mesh, A, int(v), fan, bad);
  });
  for (const AtVertex& a : at_vertex) {
    s.edges += a.edges;
    s.nonmanifold_vertices += a.nonmanifold;
  }
  // Which kind each bad edge is: read again only at the vertices that have one (none on a closed surface).
  std::vector<HalfedgeAt> at;
  for (std::size_t v = 0; v < nv; ++v) {
    if (!at_vertex[v].bad_edges) continue;
    halfedges_at(mesh, A.vf, A.vf_start[v], A.vf_start[v + 1], int(v), at);
    for (std::size_t i = 0; i < at.size();) {
      std::size_t j = i;
      while (j < at.size() && at[j].other == at[i].other) ++j;
      if (at[i].other >= int(v)) {
        const std::size_t n = j - i;
        if (n == 1) ++s.boundary_edges;
        else if (n > 2) ++s.nonmanifold_edges;
        else if (mesh.faces[std::size_t(at[i].h / 3)][at[i].h % 3] ==
                 mesh.faces[std::size_t(at[i + 1].h / 3)][at[i + 1].h % 3])
          ++s.inconsistent_edges;
      }
      i = j;
    }
  }
  s.euler = s.vertices - s.edges + s.faces;

  std::vector<int> label;
  s.components = face_components(mesh, label);
  std::vector<std::int64_t> cv(s.components, 0), ce(s.components, 0), cf(s.components, 0), cbad(s.components, 0);
  for (std::size_t fi = 0; fi < mesh.faces.size(); ++fi) ++cf[std::size_t(label[fi])];
  for (std::size_t v = 0; v < nv; ++v) {
    if (A.vf_start[v] == A.vf_start[v + 1]) continue;  // isolated: in no component
    const std::size_t c = std::size_t(label[std::size_t(A.vf[std::size_t(A.vf_start[v])])]);
    ++cv[c];
    ce[c] += at_vertex[v].edges;
    cbad[c] += at_vertex[v].bad_edges + at_vertex[v].nonmanifold;
  }
  s.component_genus.assign(s.components, -1);
  s.component_faces = cf;
  s.genus = 0;
  for (int c = 0; c < s.components; ++c) {
    std::int64_t chi = cv[c] - ce[c] + cf[c];
    if (cbad[c] == 0 && chi % 2 == 0 && chi <= 2) {
      s.component_genus[c] = int((2 - chi) / 2);
      s.genus += s.component_genus[c];
    }
  }
  if (face_label) *face_label = std::move(label);
  s.closed_manifold = s.boundary_edges == 0 && s.nonmanifold_edges == 0 && s.nonmanifold_vertices == 0 &&
                      s.inconsistent_edges == 0;
  // Fixed chunks summed in order: the same sums for any thread count.
  constexpr std::size_t kChunk = 1 << 16;
  const std::size_t nf = mesh.faces.size(), chunks = (nf + kChunk - 1) / kChunk;
  std::vector<std::array<double, 2>> part(chunks, {0.0, 0.0});
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, chunks, 1), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t ch = r.begin(); ch < r.end(); ++ch) {
      double vol = 0, area = 0;
      for (std::size_t fi = ch * kChunk; fi < std::min(nf, (ch + 1) * kChunk); ++fi) {
        const auto& t = mesh.faces[fi];
        const Eigen::Vector3d a(mesh.vertices[t[0]].data()), b(mesh.vertices[t[1]].data()),
            c(mesh.vertices[t[2]].data());
        vol += a.dot(b.cross(c)) / 6.0;
        area += 0.5 * (b - a).cross(c - a).norm();
      }
      part[ch] = {vol, area};
    }
  });
  double vol = 0, area = 0;
  for (const auto& pa : part) vol += pa[0], area += pa[1];
  s.enclosed_volume = vol;
  s.area = area;
  return s;
}

}  // namespace chokeloops

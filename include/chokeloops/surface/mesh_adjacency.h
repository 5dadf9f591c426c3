#pragma once
// Half-edge style adjacency of a SurfaceMesh, built once and shared by the topology checks and the loop
// shortening. Half-edge h = 3*f + k runs from faces[f][k] to faces[f][(k+1)%3]; twin[h] is the opposite
// half-edge in the neighbouring face, or -1 on a boundary (or at a non-manifold edge).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <vector>

#include "chokeloops/surface/surface.h"

namespace chokeloops {

struct MeshAdjacency {
  std::vector<int> twin;                 // size 3*faces
  std::vector<int> vf_start, vf;         // CSR: faces around each vertex (rising)
  // The vertices in a uniform grid of cells about twice the mean edge long (CSR over cells), so that a
  // point's nearest vertex costs a few cells, not a scan of the mesh.
  std::array<double, 3> cell_origin{0, 0, 0};
  double cell_size = 0;
  std::array<long, 3> cell_dims{0, 0, 0};
  std::vector<int> cell_start, cell_vertex;
  double mean_edge = 0;
  // Every edge has a twin running the other way (a closed, consistently oriented surface, as marching
  // cubes gives): then v's neighbours are the vertices after it in its faces, each once, and
  // for_each_neighbour reads no twins. build_adjacency sets it; false keeps the general path.
  bool closed_oriented = false;

  static int face(int h) { return h / 3; }
  static int next(int h) { return h - h % 3 + (h % 3 + 1) % 3; }
  static int prev(int h) { return h - h % 3 + (h % 3 + 2) % 3; }
  // Half-edge a -> b inside some face, or -1 when no face has it.
  int halfedge(const SurfaceMesh& m, int a, int b) const;
  bool has_edge(const SurfaceMesh& m, int a, int b) const;
  // The vertices joined to v by an edge, rising, read from v's faces: a neighbour list per vertex would be
  // another 4 bytes a half-edge to allocate and fill, and its readers are local searches.
  void neighbours(const SurfaceMesh& m, int v, std::vector<int>& out) const;
  // fn(w) for the same vertices, unsorted, for searches that cannot afford a sort per vertex: the vertex
  // after v in each of its faces, and the one before it where no face runs the other way along that edge
  // (a border, or faces whose orientations disagree). Each neighbour once on a closed, consistently
  // oriented surface; one across a non-manifold edge may come twice.
  template <class Fn>
  void for_each_neighbour(const SurfaceMesh& m, int v, Fn&& fn) const;
  // The vertex nearest to p among those within `radius` of it for which accept(v) is true, or -1.
  template <class Accept>
  int nearest_vertex(const SurfaceMesh& m, const std::array<double, 3>& p, double radius, Accept&& accept) const;
  int nearest_vertex(const SurfaceMesh& m, const std::array<double, 3>& p, double radius) const {
    return nearest_vertex(m, p, radius, [](int) { return true; });
  }
};

template <class Accept>
int MeshAdjacency::nearest_vertex(const SurfaceMesh& m, const std::array<double, 3>& p, double radius, Accept&& accept) const {
  if (cell_size <= 0) return -1;
  std::array<long, 3> lo, hi, c;
  for (int a = 0; a < 3; ++a) {
    lo[a] = std::max(0L, long((p[a] - radius - cell_origin[a]) / cell_size));
    hi[a] = std::min(cell_dims[a] - 1, long((p[a] + radius - cell_origin[a]) / cell_size));
    if (p[a] + radius < cell_origin[a] || hi[a] < lo[a]) return -1;
    c[a] = std::clamp(long(std::floor((p[a] - cell_origin[a]) / cell_size)), lo[a], hi[a]);
  }
  // The nearest accepted vertex (the lowest index on a tie) among the cells within `radius`, visited in
  // rings of cells around p's own: once the best is nearer than anything beyond the rings done, the rest
  // cannot change it. Callers pass a radius of several cells for the rare far point, and the nearest vertex
  // is nearly always in the first ring.
  int best = -1;
  double best_d2 = radius * radius;
  auto visit = [&](long x, long y, long z) {
    const long cell = x + cell_dims[0] * (y + cell_dims[1] * z);
    for (int i = cell_start[std::size_t(cell)]; i < cell_start[std::size_t(cell) + 1]; ++i) {
      const int v = cell_vertex[std::size_t(i)];
      const auto& q = m.vertices[std::size_t(v)];
      const double d2 = (q[0] - p[0]) * (q[0] - p[0]) + (q[1] - p[1]) * (q[1] - p[1]) + (q[2] - p[2]) * (q[2] - p[2]);
      if (d2 < best_d2 || (d2 == best_d2 && best >= 0 && v < best)) {
        if (!accept(v)) continue;
        best_d2 = d2, best = v;
      }
    }
  };
  for (long k = 0;; ++k) {
    for (long z = std::max(lo[2], c[2] - k); z <= std::min(hi[2], c[2] + k); ++z)
      for (long y = std::max(lo[1], c[1] - k); y <= std::min(hi[1], c[1] + k); ++y) {
        const bool shell = std::abs(z - c[2]) == k || std::abs(y - c[1]) == k;
        for (long x = std::max(lo[0], c[0] - k); x <= std::min(hi[0], c[0] + k); ++x)
          if (shell || std::abs(x - c[0]) == k) visit(x, y, z);
          else x = c[0] + k - 1;  // inside the shell: jump to its far wall
      }
    // The distance from p to the cells not visited yet (none left: done), less a hair for a vertex that
    // rounding put in the next cell.
    bool left = false;
    double gap = radius;
    for (int a = 0; a < 3; ++a) {
      if (c[a] - k > lo[a]) left = true, gap = std::min(gap, p[a] - (cell_origin[a] + double(c[a] - k) * cell_size));
      if (c[a] + k < hi[a]) left = true, gap = std::min(gap, cell_origin[a] + double(c[a] + k + 1) * cell_size - p[a]);
    }
    if (!left) break;
    gap -= 1e-6 * cell_size;
    if (gap > 0 && best >= 0 && best_d2 < gap * gap) break;
  }
  return best;
}

template <class Fn>
void MeshAdjacency::for_each_neighbour(const SurfaceMesh& m, int v, Fn&& fn) const {
  if (closed_oriented) {
    for (int j = vf_start[std::size_t(v)]; j < vf_start[std::size_t(v) + 1]; ++j) {
      const auto& t = m.faces[std::size_t(vf[std::size_t(j)])];
      fn(t[0] == v ? t[1] : t[1] == v ? t[2] : t[0]);
    }
    return;
  }
  for (int j = vf_start[std::size_t(v)]; j < vf_start[std::size_t(v) + 1]; ++j) {
    const int f = vf[std::size_t(j)];
    const auto& t = m.faces[std::size_t(f)];
    for (int k = 0; k < 3; ++k) {
      if (t[k] != v) continue;
      fn(t[(k + 1) % 3]);
      const int before = twin[std::size_t(prev(3 * f + k))];
      if (before < 0 || m.faces[std::size_t(before / 3)][before % 3] != v) fn(t[(k + 2) % 3]);
    }
  }
}

MeshAdjacency build_adjacency(const SurfaceMesh& mesh);

// Whether turning around vertex v from face to face through twins visits each of its faces once: its faces
// form one consistently oriented disc around it (no border, no pinch, no flipped face at v).
bool turns_once_around(const SurfaceMesh& mesh, const MeshAdjacency& adjacency, int v);

// surface_stats(mesh) from an adjacency already built for `mesh` (the same numbers, without building it).
// `face_label`, when given, receives each face's component as face_components numbers them.
SurfaceStats surface_stats(const SurfaceMesh& mesh, const MeshAdjacency& adjacency, std::vector<int>* face_label = nullptr);

}  // namespace chokeloops

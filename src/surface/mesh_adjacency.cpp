#include "chokeloops/surface/mesh_adjacency.h"

#include "halfedge_groups.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace chokeloops {

int MeshAdjacency::halfedge(const SurfaceMesh& m, int a, int b) const {
  for (int i = vf_start[a]; i < vf_start[a + 1]; ++i) {
    int f = vf[i];
    for (int k = 0; k < 3; ++k)
      if (m.faces[f][k] == a && m.faces[f][(k + 1) % 3] == b) return 3 * f + k;
  }
  return -1;
}

bool turns_once_around(const SurfaceMesh& mesh, const MeshAdjacency& A, int v) {
  const int b0 = A.vf_start[std::size_t(v)], b1 = A.vf_start[std::size_t(v) + 1];
  if (b0 == b1) return false;
  int start = -1;
  const int f = A.vf[std::size_t(b0)];
  for (int k = 0; k < 3; ++k)
    if (mesh.faces[std::size_t(f)][k] == v) start = 3 * f + k;
  int h = start, turns = 0;
  do {
    const int t = A.twin[std::size_t(MeshAdjacency::prev(h))];
    if (t < 0 || mesh.faces[std::size_t(t / 3)][t % 3] != v) return false;  // boundary, or orientations disagree
    h = t;
    ++turns;
  } while (h != start && turns <= b1 - b0);
  return h == start && turns == b1 - b0;
}

bool MeshAdjacency::has_edge(const SurfaceMesh& m, int a, int b) const {
  return halfedge(m, a, b) >= 0 || halfedge(m, b, a) >= 0;
}

void MeshAdjacency::neighbours(const SurfaceMesh& m, int v, std::vector<int>& out) const {
  out.clear();
  for_each_neighbour(m, v, [&](int w) { out.push_back(w); });
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
}

namespace {
double edge_length(const SurfaceMesh& m, int a, int b) {
  const auto &p = m.vertices[a], &q = m.vertices[b];
  return std::sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2]));
}

// Cells about twice the mean edge long (at most ~2 cells a vertex, so that a sparse mesh in a big box does
// not allocate a huge empty grid); vertices in order within each cell, so that ties resolve the same way.
void build_vertex_cells(const SurfaceMesh& mesh, MeshAdjacency& A) {
  const size_t nv = mesh.vertices.size(), nf = mesh.faces.size();
  if (nv == 0 || nf == 0) return;
  double sum = 0;
  const size_t stride = std::max<size_t>(1, nf / 4096);
  size_t sampled = 0;
  for (size_t f = 0; f < nf; f += stride, ++sampled) sum += edge_length(mesh, mesh.faces[f][0], mesh.faces[f][1]);
  A.mean_edge = sum / double(sampled);
  std::array<double, 3> lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
  for (const auto& p : mesh.vertices)
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], p[a]), hi[a] = std::max(hi[a], p[a]);
  double cell = std::max(2 * A.mean_edge, 1e-12);
  for (;;) {
    double cells = 1;
    for (int a = 0; a < 3; ++a) cells *= std::floor((hi[a] - lo[a]) / cell) + 1;
    if (cells <= 2.0 * double(nv) + 8) break;
    cell *= 1.5;
  }
  A.cell_origin = lo;
  A.cell_size = cell;
  for (int a = 0; a < 3; ++a) A.cell_dims[a] = long(std::floor((hi[a] - lo[a]) / cell)) + 1;
  const long ncells = A.cell_dims[0] * A.cell_dims[1] * A.cell_dims[2];
  std::vector<int> cell_of(nv);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, nv, 1 << 14), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t v = r.begin(); v < r.end(); ++v) {
      std::array<long, 3> c;
      for (int a = 0; a < 3; ++a)
        c[a] = std::min(A.cell_dims[a] - 1, long((mesh.vertices[v][a] - lo[a]) / cell));
      cell_of[v] = int(c[0] + A.cell_dims[0] * (c[1] + A.cell_dims[1] * c[2]));
    }
  });
  A.cell_start.assign(size_t(ncells) + 1, 0);
  for (size_t v = 0; v < nv; ++v) ++A.cell_start[size_t(cell_of[v]) + 1];
  for (long c = 0; c < ncells; ++c) A.cell_start[c + 1] += A.cell_start[c];
  A.cell_vertex.resize(nv);
  std::vector<int> fill(A.cell_start.begin(), A.cell_start.end() - 1);
  for (size_t v = 0; v < nv; ++v) A.cell_vertex[fill[cell_of[v]]++] = int(v);
}

// Faces around each vertex, in rising face order; a face is listed once per corner it has there.
void vertex_faces(const SurfaceMesh& mesh, std::vector<int>& start, std::vector<int>& faces) {
  const std::size_t nv = mesh.vertices.size(), nf = mesh.faces.size();
  start.assign(nv + 1, 0);
  for (auto& t : mesh.faces)
    for (int k = 0; k < 3; ++k) ++start[std::size_t(t[k]) + 1];
  for (std::size_t v = 0; v < nv; ++v) start[v + 1] += start[v];
  faces.resize(3 * nf);
  std::vector<int> fill(start.begin(), start.end() - 1);
  for (std::size_t f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) faces[std::size_t(fill[std::size_t(mesh.faces[f][k])]++)] = int(f);
}
}  // namespace

void halfedges_at(const SurfaceMesh& mesh, const std::vector<int>& vf, int begin, int end, int v,
                  std::vector<HalfedgeAt>& out) {
  out.clear();
  for (int i = begin; i < end; ++i) {
    const int f = vf[std::size_t(i)];
    if (i > begin && vf[std::size_t(i - 1)] == f) continue;  // a face with two corners at v: read it once
    const auto& t = mesh.faces[std::size_t(f)];
    for (int k = 0; k < 3; ++k) {
      const int a = t[k], b = t[(k + 1) % 3];
      if (a == v) out.push_back({b, 3 * f + k});
      else if (b == v) out.push_back({a, 3 * f + k});
    }
  }
  std::sort(out.begin(), out.end(), [](const HalfedgeAt& x, const HalfedgeAt& y) {
    return x.other != y.other ? x.other < y.other : x.h < y.h;
  });
}

MeshAdjacency build_adjacency(const SurfaceMesh& mesh) {
  MeshAdjacency A;
  const std::size_t nf = mesh.faces.size(), nv = mesh.vertices.size();
  vertex_faces(mesh, A.vf_start, A.vf);
  A.twin.assign(3 * nf, -1);
  // Each edge is read at its smaller end, so every twin is written once.
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    std::vector<HalfedgeAt> at;
    for (std::size_t v = r.begin(); v < r.end(); ++v) {
      halfedges_at(mesh, A.vf, A.vf_start[v], A.vf_start[v + 1], int(v), at);
      for (std::size_t i = 0; i < at.size();) {
        std::size_t j = i;
        while (j < at.size() && at[j].other == at[i].other) ++j;
        if (j - i == 2 && at[i].other >= int(v)) {
          A.twin[std::size_t(at[i].h)] = at[i + 1].h;
          A.twin[std::size_t(at[i + 1].h)] = at[i].h;
        }
        i = j;
      }
    }
  });
  A.closed_oriented = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, A.twin.size(), 1 << 16), true,
      [&](const tbb::blocked_range<std::size_t>& r, bool ok) {
        for (std::size_t h = r.begin(); ok && h < r.end(); ++h) {
          const int t = A.twin[h];
          const auto& f = mesh.faces[h / 3];
          if (t < 0 || f[0] == f[1] || f[1] == f[2] || f[2] == f[0]) { ok = false; break; }
          const auto& g = mesh.faces[std::size_t(t) / 3];
          const std::size_t k = h % 3, kt = std::size_t(t) % 3;
          ok = g[kt] == f[(k + 1) % 3] && g[(kt + 1) % 3] == f[k];  // the twin runs to -> from
        }
        return ok;
      },
      [](bool a, bool b) { return a && b; });
  build_vertex_cells(mesh, A);
  return A;
}

}  // namespace chokeloops

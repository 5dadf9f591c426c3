#include "chokeloops/surface/mesh_adjacency.h"

#include "halfedge_groups.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

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

bool MeshAdjacency::has_edge(int a, int b) const {
  return std::binary_search(vv.begin() + vv_start[a], vv.begin() + vv_start[a + 1], b);
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
  A.cell_start.assign(size_t(ncells) + 1, 0);
  for (size_t v = 0; v < nv; ++v) {
    std::array<long, 3> c;
    for (int a = 0; a < 3; ++a)
      c[a] = std::min(A.cell_dims[a] - 1, long((mesh.vertices[v][a] - lo[a]) / cell));
    cell_of[v] = int(c[0] + A.cell_dims[0] * (c[1] + A.cell_dims[1] * c[2]));
    ++A.cell_start[size_t(cell_of[v]) + 1];
  }
  for (long c = 0; c < ncells; ++c) A.cell_start[c + 1] += A.cell_start[c];
  A.cell_vertex.resize(nv);
  std::vector<int> fill(A.cell_start.begin(), A.cell_start.end() - 1);
  for (size_t v = 0; v < nv; ++v) A.cell_vertex[fill[cell_of[v]]++] = int(v);
}
}  // namespace

std::vector<EdgeHalfedge> halfedges_by_edge(const SurfaceMesh& mesh) {
  const std::size_t nf = mesh.faces.size(), nv = mesh.vertices.size();
  auto key_of = [&](std::size_t h) {
    const auto& t = mesh.faces[h / 3];
    const int a = t[h % 3], b = t[(h + 1) % 3];
    return (std::uint64_t(std::uint32_t(std::min(a, b))) << 32) | std::uint32_t(std::max(a, b));
  };
  std::vector<int> start(nv + 1, 0);
  for (std::size_t h = 0; h < 3 * nf; ++h) ++start[(key_of(h) >> 32) + 1];
  for (std::size_t v = 0; v < nv; ++v) start[v + 1] += start[v];
  std::vector<EdgeHalfedge> he(3 * nf);
  {
    std::vector<int> fill(start.begin(), start.end() - 1);
    for (std::size_t h = 0; h < 3 * nf; ++h) {
      const std::uint64_t key = key_of(h);
      he[std::size_t(fill[key >> 32]++)] = {key, int(h)};
    }
  }
  // Each bucket holds a vertex's few edges in rising h: a stable insertion sort by key finishes the order.
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t v = r.begin(); v < r.end(); ++v)
      for (int i = start[v] + 1; i < start[v + 1]; ++i) {
        const EdgeHalfedge x = he[std::size_t(i)];
        int j = i;
        for (; j > start[v] && he[std::size_t(j - 1)].key > x.key; --j) he[std::size_t(j)] = he[std::size_t(j - 1)];
        he[std::size_t(j)] = x;
      }
  });
  return he;
}

MeshAdjacency build_adjacency(const SurfaceMesh& mesh) {
  MeshAdjacency A;
  const size_t nf = mesh.faces.size(), nv = mesh.vertices.size();
  const std::vector<EdgeHalfedge> he = halfedges_by_edge(mesh);
  A.twin.assign(3 * nf, -1);
  A.vv_start.assign(nv + 1, 0);
  size_t nedges = 0;
  for (size_t i = 0; i < he.size();) {
    size_t j = i;
    while (j < he.size() && he[j].key == he[i].key) ++j;
    if (j - i == 2) {
      A.twin[he[i].h] = he[i + 1].h;
      A.twin[he[i + 1].h] = he[i].h;
    }
    ++A.vv_start[(he[i].key >> 32) + 1];
    ++A.vv_start[(he[i].key & 0xffffffffu) + 1];
    ++nedges;
    i = j;
  }
  for (size_t v = 0; v < nv; ++v) A.vv_start[v + 1] += A.vv_start[v];
  A.vv.resize(2 * nedges);
  {
    std::vector<int> fill(A.vv_start.begin(), A.vv_start.end() - 1);
    for (size_t i = 0; i < he.size();) {
      size_t j = i;
      while (j < he.size() && he[j].key == he[i].key) ++j;
      int a = int(he[i].key >> 32), b = int(he[i].key & 0xffffffffu);
      A.vv[fill[a]++] = b;
      A.vv[fill[b]++] = a;
      i = j;
    }
  }
  // Neighbours come out sorted for a (keys sorted by min then max) only partly; sort each list.
  tbb::parallel_for(size_t(0), nv, [&](size_t v) { std::sort(A.vv.begin() + A.vv_start[v], A.vv.begin() + A.vv_start[v + 1]); });
  A.vf_start.assign(nv + 1, 0);
  for (auto& t : mesh.faces)
    for (int k = 0; k < 3; ++k) ++A.vf_start[t[k] + 1];
  for (size_t v = 0; v < nv; ++v) A.vf_start[v + 1] += A.vf_start[v];
  A.vf.resize(3 * nf);
  {
    std::vector<int> fill(A.vf_start.begin(), A.vf_start.end() - 1);
    for (size_t f = 0; f < nf; ++f)
      for (int k = 0; k < 3; ++k) A.vf[fill[mesh.faces[f][k]]++] = int(f);
  }
  build_vertex_cells(mesh, A);
  return A;
}

}  // namespace chokeloops

#include "chokeloops/surface/surface.h"


#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace chokeloops {

namespace {

// The 19 Freudenthal edges inside a cube: corner ci -> corner cj with ci a proper subset of cj.
struct CubeEdge { int ci, m; };  // m = cj ^ ci

// Polygons (triangle or quad) of one cube configuration, as indices into the cube-edge list.
struct Polygon { int n; int e[4]; };
struct CubeCase { int count = 0; Polygon poly[12]; };

struct Tables {
  std::array<CubeEdge, 19> edges{};
  int edge_index[8][8];  // [ci][cj] -> cube edge, -1 if none
  std::array<CubeCase, 256> cases;
};

double dot3(const std::array<double, 3>& a, const std::array<double, 3>& b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
std::array<double, 3> sub3(const std::array<double, 3>& a, const std::array<double, 3>& b) {
  return {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
}
std::array<double, 3> cross3(const std::array<double, 3>& a, const std::array<double, 3>& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}

const Tables& tables() {
  static const Tables T = [] {
    Tables t{};
    int n = 0;
    for (int a = 0; a < 8; ++a)
      for (int b = 0; b < 8; ++b) t.edge_index[a][b] = -1;
    for (int cj = 0; cj < 8; ++cj)
      for (int ci = 0; ci < 8; ++ci)
        if (ci != cj && (ci & cj) == ci) {
          t.edges[n] = {ci, cj ^ ci};
          t.edge_index[ci][cj] = t.edge_index[cj][ci] = n;
          ++n;
        }
    auto corner = [](int c) { return std::array<double, 3>{double(c & 1), double(c >> 1 & 1), double(c >> 2 & 1)}; };
    auto mid = [&](int a, int b) {
      auto pa = corner(a), pb = corner(b);
      return std::array<double, 3>{(pa[0] + pb[0]) / 2, (pa[1] + pb[1]) / 2, (pa[2] + pb[2]) / 2};
    };
    for (int mask = 0; mask < 256; ++mask) {
      CubeCase& cc = t.cases[mask];
      for (int p = 0; p < 6; ++p) {
        auto ax = freudenthal::tet_axes(p);
        int cv[4] = {0, ax[0], ax[0] | ax[1], 7};
        std::vector<int> in, out;
        for (int c : cv) (mask >> c & 1 ? in : out).push_back(c);
        if (in.empty() || out.empty()) continue;
        std::array<double, 3> cin{0, 0, 0}, cout{0, 0, 0};
        for (int c : in) { auto q = corner(c); for (int d = 0; d < 3; ++d) cin[d] += q[d] / in.size(); }
        for (int c : out) { auto q = corner(c); for (int d = 0; d < 3; ++d) cout[d] += q[d] / out.size(); }
        auto dir = sub3(cout, cin);
        Polygon poly{};
        std::vector<std::pair<int, int>> ring;
        if (in.size() == 1 || out.size() == 1) {
          int apex = in.size() == 1 ? in[0] : out[0];
          auto& others = in.size() == 1 ? out : in;
          for (int o : others) ring.push_back({apex, o});
        } else {
          int a = in[0], b = in[1], c = out[0], d = out[1];
          ring = {{a, c}, {a, d}, {b, d}, {b, c}};
        }
        poly.n = int(ring.size());
        // Orient: normal of the (planar, midpoint) polygon must point along dir.
        auto p0 = mid(ring[0].first, ring[0].second), p1 = mid(ring[1].first, ring[1].second),
             p2 = mid(ring[2].first, ring[2].second);
        if (dot3(cross3(sub3(p1, p0), sub3(p2, p0)), dir) < 0) std::reverse(ring.begin(), ring.end());
        for (int k = 0; k < poly.n; ++k) poly.e[k] = t.edge_index[ring[k].first][ring[k].second];
        cc.poly[cc.count++] = poly;
      }
    }
    return t;
  }();
  return T;
}

}  // namespace

SurfaceMesh extract_zero_surface(const ScalarGrid& grid) {
  validate_grid(grid);
  const Tables& T = tables();
  const int nx = grid.dims[0], ny = grid.dims[1], nz = grid.dims[2];
  const Id sy = nx, sz = Id(nx) * ny;
  const float* f = grid.values.data();
  auto offset = [&](int m) -> Id { return (m & 1 ? 1 : 0) + (m & 2 ? sy : 0) + (m & 4 ? sz : 0); };
  Id off[8];
  for (int m = 0; m < 8; ++m) off[m] = offset(m);

  std::vector<std::uint8_t> cross(size_t(grid.vertex_count()), 0);
  std::vector<std::uint32_t> base(size_t(grid.vertex_count()), 0);
  std::vector<std::int64_t> layer_vertices(nz + 1, 0), layer_faces(nz + 1, 0);

  auto cube_mask = [&](Id v) {
    int mask = 0;
    for (int c = 0; c < 8; ++c) mask |= (f[v + off[c]] <= 0.f ? 1 : 0) << c;
    return mask;
  };
  auto faces_of = [&](int mask) {
    int n = 0;
    const CubeCase& cc = T.cases[mask];
    for (int q = 0; q < cc.count; ++q) n += cc.poly[q].n - 2;
    return n;
  };

  // Pass 1: crossing masks per vertex and counts per layer.
  tbb::parallel_for(tbb::blocked_range<int>(0, nz), [&](const tbb::blocked_range<int>& r) {
    for (int k = r.begin(); k < r.end(); ++k) {
      std::int64_t nv = 0, nf = 0;
      for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) {
          Id v = i + sy * j + sz * k;
          bool vin = f[v] <= 0.f;
          std::uint8_t cm = 0;
          for (int m = 1; m < 8; ++m) {
            if ((m & 1) && i + 1 >= nx) continue;
            if ((m & 2) && j + 1 >= ny) continue;
            if ((m & 4) && k + 1 >= nz) continue;
            if ((f[v + off[m]] <= 0.f) != vin) cm |= std::uint8_t(1u << (m - 1));
          }
          cross[v] = cm;
          nv += __builtin_popcount(cm);
          if (i + 1 < nx && j + 1 < ny && k + 1 < nz) {
            int mask = cube_mask(v);
            if (mask != 0 && mask != 255) nf += faces_of(mask);
          }
        }
      layer_vertices[k + 1] = nv;
      layer_faces[k + 1] = nf;
    }
  });
  for (int k = 0; k < nz; ++k) {
    layer_vertices[k + 1] += layer_vertices[k];
    layer_faces[k + 1] += layer_faces[k];
  }
  if (layer_vertices[nz] >= (std::int64_t(1) << 31) || layer_faces[nz] >= (std::int64_t(1) << 31))
    throw Error("surface has more than 2^31 vertices or faces; use a coarser resolution", 3);

  SurfaceMesh mesh;
  mesh.vertices.resize(size_t(layer_vertices[nz]));
  mesh.vertex_edge.resize(size_t(layer_vertices[nz]));
  mesh.faces.resize(size_t(layer_faces[nz]));
  const double hx = grid.h(0), hy = grid.h(1), hz = grid.h(2);
  const double eps = 1e-3;

  // Pass 2: vertex numbering and positions.
  tbb::parallel_for(tbb::blocked_range<int>(0, nz), [&](const tbb::blocked_range<int>& r) {
    for (int k = r.begin(); k < r.end(); ++k) {
      std::int64_t next = layer_vertices[k];
      for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) {
          Id v = i + sy * j + sz * k;
          base[v] = std::uint32_t(next);
          std::uint8_t cm = cross[v];
          if (!cm) continue;
          for (int m = 1; m < 8; ++m) {
            if (!(cm >> (m - 1) & 1)) continue;
            double fa = f[v], fb = f[v + off[m]];
            double t = fa / (fa - fb);
            t = std::min(std::max(t, eps), 1 - eps);
            mesh.vertices[size_t(next)] = {grid.origin[0] + hx * (i + t * (m & 1)),
                                           grid.origin[1] + hy * (j + t * (m >> 1 & 1)),
                                           grid.origin[2] + hz * (k + t * (m >> 2 & 1))};
            mesh.vertex_edge[size_t(next)] = 7 * v + (m - 1);
            ++next;
          }
        }
    }
  });

  // Pass 3: faces.
  tbb::parallel_for(tbb::blocked_range<int>(0, nz - 1), [&](const tbb::blocked_range<int>& r) {
    for (int k = r.begin(); k < r.end(); ++k) {
      std::int64_t next = layer_faces[k];
      for (int j = 0; j + 1 < ny; ++j)
        for (int i = 0; i + 1 < nx; ++i) {
          Id v = i + sy * j + sz * k;
          int mask = cube_mask(v);
          if (mask == 0 || mask == 255) continue;
          const CubeCase& cc = T.cases[mask];
          for (int q = 0; q < cc.count; ++q) {
            const Polygon& P = cc.poly[q];
            int idx[4];
            for (int a = 0; a < P.n; ++a) {
              const CubeEdge& e = T.edges[P.e[a]];
              Id u = v + off[e.ci];
              idx[a] = int(base[u] + __builtin_popcount(unsigned(cross[u]) & ((1u << (e.m - 1)) - 1u)));
            }
            if (P.n == 3) {
              mesh.faces[size_t(next++)] = {idx[0], idx[1], idx[2]};
            } else {
              auto d02 = sub3(mesh.vertices[idx[0]], mesh.vertices[idx[2]]);
              auto d13 = sub3(mesh.vertices[idx[1]], mesh.vertices[idx[3]]);
              if (dot3(d02, d02) <= dot3(d13, d13)) {
                mesh.faces[size_t(next++)] = {idx[0], idx[1], idx[2]};
                mesh.faces[size_t(next++)] = {idx[0], idx[2], idx[3]};
              } else {
                mesh.faces[size_t(next++)] = {idx[1], idx[2], idx[3]};
                mesh.faces[size_t(next++)] = {idx[1], idx[3], idx[0]};
              }
            }
          }
        }
    }
  });
  return mesh;
}

int surface_vertex_on_edge(const SurfaceMesh& mesh, Id edge) {
  auto it = std::lower_bound(mesh.vertex_edge.begin(), mesh.vertex_edge.end(), edge);
  return it != mesh.vertex_edge.end() && *it == edge ? int(it - mesh.vertex_edge.begin()) : -1;
}

}  // namespace chokeloops

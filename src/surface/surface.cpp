#include "chokeloops/surface/surface.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstring>

#include "common/grid_array.h"

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

  const std::size_t N = size_t(grid.vertex_count());
  // One byte per vertex, 1 inside: eight vertices of a row are then compared in one 64-bit word, and most
  // of a molecular or medical grid is far from the surface (maltoporin at 0.25 A: 53M vertices, 8.8M crossings).
  detail::GridArray<std::uint8_t> inside(N);  // every vertex written below
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, N, 1 << 16), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t v = r.begin(); v < r.end(); ++v) inside[v] = f[v] <= 0.f;
  });
  const std::uint8_t* in = inside.data();
  detail::GridArray<std::uint8_t> cross(N, 0);
  std::vector<std::int64_t> layer_vertices(nz + 1, 0), layer_faces(nz + 1, 0);

  auto cube_mask = [&](Id v) {
    int mask = 0;
    for (int c = 0; c < 8; ++c) mask |= in[v + off[c]] << c;
    return mask;
  };
  auto faces_of = [&](int mask) {
    int n = 0;
    const CubeCase& cc = T.cases[mask];
    for (int q = 0; q < cc.count; ++q) n += cc.poly[q].n - 2;
    return n;
  };
  // Bits set in a byte (crossing masks), without a libgcc call where the build does not assume POPCNT.
  static const std::array<std::uint8_t, 256> kBits = [] {
    std::array<std::uint8_t, 256> t{};
    for (int b = 1; b < 256; ++b) t[std::size_t(b)] = std::uint8_t(t[std::size_t(b >> 1)] + (b & 1));
    return t;
  }();
  auto word = [](const std::uint8_t* p) {
    std::uint64_t w;
    std::memcpy(&w, p, 8);
    return w;
  };
  constexpr std::uint64_t kAllInside = 0x0101010101010101ull;
  // The cubes at v .. v+7 of a row whose corners are all inside or all outside (j + 1 < ny, k + 1 < nz,
  // v + 8 still in the row).
  auto eight_uniform = [&](Id v) {
    const std::uint8_t* p = in + v;
    const std::uint64_t a = word(p), b = word(p + 1), c = word(p + sy), d = word(p + sy + 1), e = word(p + sz),
                        g = word(p + sz + 1), h = word(p + sy + sz), q = word(p + sy + sz + 1);
    const std::uint64_t any = a | b | c | d | e | g | h | q, all = a & b & c & d & e & g & h & q;
    return any == 0 || all == kAllInside;
  };
  // Eight vertices of a row with no crossing edge (v + 8 still in the row).
  auto eight_without_crossings = [&](Id v) { return word(cross.data() + v) == 0; };

  // Pass 1: crossing masks per vertex and counts per layer.
  tbb::parallel_for(tbb::blocked_range<int>(0, nz), [&](const tbb::blocked_range<int>& r) {
    for (int k = r.begin(); k < r.end(); ++k) {
      std::int64_t nv = 0, nf = 0;
      for (int j = 0; j < ny; ++j) {
        const bool inner_row = j + 1 < ny && k + 1 < nz;
        for (int i = 0; i < nx;) {
          Id v = i + sy * j + sz * k;
          if (inner_row && i + 8 < nx && eight_uniform(v)) {
            i += 8;  // cross[] stays 0 and no face
            continue;
          }
          const bool vin = in[v];
          std::uint8_t cm = 0;
          for (int m = 1; m < 8; ++m) {
            if ((m & 1) && i + 1 >= nx) continue;
            if ((m & 2) && j + 1 >= ny) continue;
            if ((m & 4) && k + 1 >= nz) continue;
            if (bool(in[v + off[m]]) != vin) cm |= std::uint8_t(1u << (m - 1));
          }
          cross[v] = cm;
          nv += kBits[cm];
          if (cm && i + 1 < nx && inner_row) nf += faces_of(cube_mask(v));
          ++i;
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

  // The mesh's arrays are zeroed on one thread (std::vector): allocated before the numbering, they take what
  // the stage before freed (in the molecule pipeline, the far field's arrays) rather than fresh pages, which
  // cost this machine ~2 GB/s to fault in. The numbering is touched only where written, in parallel.
  SurfaceMesh mesh;
  mesh.vertices.resize(size_t(layer_vertices[nz]));
  mesh.vertex_edge.resize(size_t(layer_vertices[nz]));
  mesh.faces.resize(size_t(layer_faces[nz]));
  detail::GridArray<std::uint32_t> base(N);  // written and read only where a vertex has a crossing
  const double hx = grid.h(0), hy = grid.h(1), hz = grid.h(2);
  const double eps = 1e-3;

  // Pass 2: vertex numbering and positions.
  tbb::parallel_for(tbb::blocked_range<int>(0, nz), [&](const tbb::blocked_range<int>& r) {
    for (int k = r.begin(); k < r.end(); ++k) {
      std::int64_t next = layer_vertices[k];
      for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) {
          Id v = i + sy * j + sz * k;
          if (i + 8 < nx && eight_without_crossings(v)) {
            i += 7;
            continue;
          }
          std::uint8_t cm = cross[v];
          if (!cm) continue;
          base[v] = std::uint32_t(next);  // read only where the vertex has a crossing
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
          // a cube whose corners differ has a crossing edge from its first corner
          if (i + 8 < nx && eight_without_crossings(v)) {
            i += 7;
            continue;
          }
          if (!cross[v]) continue;
          int mask = cube_mask(v);
          const CubeCase& cc = T.cases[mask];
          for (int q = 0; q < cc.count; ++q) {
            const Polygon& P = cc.poly[q];
            int idx[4];
            for (int a = 0; a < P.n; ++a) {
              const CubeEdge& e = T.edges[P.e[a]];
              Id u = v + off[e.ci];
              idx[a] = int(base[u] + kBits[cross[u] & ((1u << (e.m - 1)) - 1u)]);
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

// Dense far-field completion of a signed distance grid by an exact Euclidean feature transform
// (Felzenszwalb-Huttenlocher separable lower envelopes, carrying the nearest site), stage `levelset`.
//
// Sites are grid vertices near the surface whose closest surface point p(s) is known (exactly for
// meshes: closest point on the closest triangle from OpenVDB's polygon index grid). Every vertex that
// is not `known` gets sign * |x - p(F(x))|, F(x) = the site nearest to x. That is the distance to a
// real surface point, an upper bound of the true distance, and equal to it up to a small fraction of
// a voxel away from the surface (tests: sphere/torus at 128^3, max error well below one voxel).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/blocked_range2d.h>
#include <tbb/parallel_for.h>

#include "chokeloops/grid.h"

namespace chokeloops::detail {

struct Site {
  std::int64_t vertex;  // linear index of the site vertex
  float p[3];           // closest surface point, in grid index units (vertex (i,j,k) at (i,j,k))
};

namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

// One FH pass over a line of n samples: f (squared distance so far, kInf = none), feature id.
// Scratch: v (int n), z (double n+1). Writes results back into f / id.
void envelope_line(int n, float* f, std::int32_t* id, std::vector<int>& v, std::vector<double>& z,
                   std::vector<float>& fo, std::vector<std::int32_t>& io) {
  int k = -1;
  double s = 0;
  for (int q = 0; q < n; ++q) {
    if (!(f[q] < kInf)) continue;
    if (k < 0) {
      k = 0;
      v[0] = q;
      z[0] = -std::numeric_limits<double>::infinity();
      z[1] = std::numeric_limits<double>::infinity();
      continue;
    }
    while (true) {  // z[0] = -inf stops this at k = 0
      const int p = v[k];
      s = ((double(f[q]) + double(q) * q) - (double(f[p]) + double(p) * p)) / (2.0 * (q - p));
      if (s <= z[k]) {
        --k;
        continue;
      }
      break;
    }
    ++k;
    v[k] = q;
    z[k] = s;
    z[k + 1] = std::numeric_limits<double>::infinity();
  }
  if (k < 0) return;  // no site on this line
  int j = 0;
  for (int q = 0; q < n; ++q) {
    while (z[j + 1] < q) ++j;
    const int p = v[j];
    fo[q] = float(double(q - p) * (q - p) + f[p]);
    io[q] = id[p];
  }
  std::copy(fo.begin(), fo.begin() + n, f);
  std::copy(io.begin(), io.begin() + n, id);
}

}  // namespace

// grid.values: signed values (only the sign is used where not known); `known[i]` = keep as is
// (empty: recompute every vertex); sites: see above.
void complete_by_feature_transform(ScalarGrid& grid, const std::vector<std::uint8_t>& known,
                                   const std::vector<Site>& sites) {
  const int nx = grid.dims[0], ny = grid.dims[1], nz = grid.dims[2];
  const std::size_t N = std::size_t(grid.vertex_count());
  if (sites.empty()) return;
  std::vector<float> D(N, kInf);
  std::vector<std::int32_t> F(N, -1);
  for (std::size_t s = 0; s < sites.size(); ++s) {
    D[std::size_t(sites[s].vertex)] = 0.f;
    F[std::size_t(sites[s].vertex)] = std::int32_t(s);
  }
  // pass x: contiguous lines
  tbb::parallel_for(tbb::blocked_range<int>(0, ny * nz, 16), [&](const tbb::blocked_range<int>& r) {
    std::vector<int> v(nx + 1);
    std::vector<double> z(nx + 2);
    std::vector<float> fo(nx);
    std::vector<std::int32_t> io(nx);
    for (int line = r.begin(); line != r.end(); ++line) {
      const std::size_t base = std::size_t(line) * nx;
      envelope_line(nx, &D[base], &F[base], v, z, fo, io);
    }
  });
  // pass y and z: gather/scatter strided lines, a few at a time for cache
  auto strided = [&](int n, std::size_t stride, int lines_outer, int lines_inner, std::size_t outer_stride) {
    tbb::parallel_for(tbb::blocked_range<int>(0, lines_outer), [&](const tbb::blocked_range<int>& r) {
      std::vector<int> v(n + 1);
      std::vector<double> z(n + 2);
      std::vector<float> fo(n), fl(n);
      std::vector<std::int32_t> io(n), il(n);
      for (int o = r.begin(); o != r.end(); ++o)
        for (int i = 0; i < lines_inner; ++i) {
          const std::size_t base = std::size_t(o) * outer_stride + std::size_t(i);
          for (int q = 0; q < n; ++q) {
            fl[q] = D[base + q * stride];
            il[q] = F[base + q * stride];
          }
          envelope_line(n, fl.data(), il.data(), v, z, fo, io);
          for (int q = 0; q < n; ++q) {
            D[base + q * stride] = fl[q];
            F[base + q * stride] = il[q];
          }
        }
    });
  };
  // y lines: index = i + nx*(j + ny*k); for fixed k (outer) and i (inner), stride nx
  strided(ny, std::size_t(nx), nz, nx, std::size_t(nx) * ny);
  // z lines: for fixed j (outer, stride nx) and i (inner), stride nx*ny
  strided(nz, std::size_t(nx) * ny, ny, nx, std::size_t(nx));
  D.clear();
  D.shrink_to_fit();

  // Refinement: the nearest site (by vertex position) is not always the one with the nearest surface
  // point; let every vertex try its axial neighbours' choices, in both directions along each axis.
  auto d2 = [&](int i, int j, int k, std::int32_t s) {
    const float* p = sites[std::size_t(s)].p;
    const double dx = i - p[0], dy = j - p[1], dz = k - p[2];
    return dx * dx + dy * dy + dz * dz;
  };
  const std::size_t sx = 1, sy = std::size_t(nx), sz = std::size_t(nx) * ny;
  auto relax_axis = [&](int axis) {
    const int n = axis == 0 ? nx : axis == 1 ? ny : nz;
    const std::size_t stride = axis == 0 ? sx : axis == 1 ? sy : sz;
    const int na = axis == 0 ? ny : nx, nb = axis == 2 ? ny : nz;  // the two other axes
    tbb::parallel_for(tbb::blocked_range<int>(0, nb), [&](const tbb::blocked_range<int>& r) {
      for (int b = r.begin(); b != r.end(); ++b)
        for (int a = 0; a < na; ++a) {
          int ijk[3];
          auto set = [&](int q) {
            if (axis == 0) { ijk[0] = q; ijk[1] = a; ijk[2] = b; }
            else if (axis == 1) { ijk[0] = a; ijk[1] = q; ijk[2] = b; }
            else { ijk[0] = a; ijk[1] = b; ijk[2] = q; }
          };
          set(0);
          const std::size_t base = std::size_t(grid.index(ijk[0], ijk[1], ijk[2]));
          for (int dir = 0; dir < 2; ++dir) {
            std::int32_t carry = -1;
            for (int t = 0; t < n; ++t) {
              const int q = dir == 0 ? t : n - 1 - t;
              const std::size_t idx = base + std::size_t(q) * stride;
              std::int32_t cur = F[idx];
              if (carry >= 0 && carry != cur) {
                set(q);
                if (cur < 0 || d2(ijk[0], ijk[1], ijk[2], carry) < d2(ijk[0], ijk[1], ijk[2], cur)) {
                  F[idx] = carry;
                  cur = carry;
                }
              }
              carry = cur;
            }
          }
        }
    });
  };
  const int rounds = 2;  // measured: 0 rounds 0.73, 2 rounds 0.25, 4 rounds 0.18 voxel max error
  for (int round = 0; round < rounds; ++round)
    for (int axis = 0; axis < 3; ++axis) relax_axis(axis);

  const double h = grid.voxel_size;
  tbb::parallel_for(tbb::blocked_range<int>(0, nz), [&](const tbb::blocked_range<int>& r) {
    for (int k = r.begin(); k != r.end(); ++k)
      for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) {
          const std::size_t idx = std::size_t(grid.index(i, j, k));
          if (!known.empty() && known[idx]) continue;
          const std::int32_t s = F[idx];
          if (s < 0) continue;
          const float* p = sites[std::size_t(s)].p;
          const double dx = i - p[0], dy = j - p[1], dz = k - p[2];
          const double d = std::sqrt(dx * dx + dy * dy + dz * dz) * h;
          grid.values[idx] = float(grid.values[idx] < 0 ? -d : d);
        }
  });
}

}  // namespace chokeloops::detail

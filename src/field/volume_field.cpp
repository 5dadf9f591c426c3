#include "chokeloops/field/volume_field.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "chokeloops/field/levelset.h"
#include "feature_transform.h"

namespace chokeloops {

std::array<double, 3> WorldFrame::apply(const std::array<double, 3>& p) const {
  std::array<double, 3> x;
  for (int r = 0; r < 3; ++r) x[r] = linear[r][0] * p[0] + linear[r][1] * p[1] + linear[r][2] * p[2] + offset[r];
  return x;
}

std::array<double, 3> WorldFrame::rotate(const std::array<double, 3>& v) const {
  std::array<double, 3> x;
  for (int r = 0; r < 3; ++r) x[r] = linear[r][0] * v[0] + linear[r][1] * v[1] + linear[r][2] * v[2];
  double n = std::sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
  if (n > 0)
    for (auto& c : x) c /= n;
  return x;
}

namespace {

// The image's inside function (>= 0 inside) resampled trilinearly onto an isotropic lattice of spacing H
// along the image's axes; the result is a scalar image read at iso 0.
VolumeImage resample_inside_function(const VolumeImage& image, const std::function<float(float)>& g_of, double H,
                                     double margin_mm) {
  const std::array<double, 3>& h = image.spacing;
  VolumeImage out;
  out.path = image.path;
  out.format = image.format;
  out.datatype = "float32";
  out.convention = image.convention;
  out.transform_source = image.transform_source + ", resampled";
  out.warnings = image.warnings;
  double longest = 0;
  for (int a = 0; a < 3; ++a) longest = std::max(longest, h[a] * (image.dims[a] - 1));
  const double margin = margin_mm >= 0 ? margin_mm : default_margin(longest, H);
  std::int64_t padded = 1;
  for (int a = 0; a < 3; ++a) {
    const double extent = h[a] * (image.dims[a] - 1);
    const double n = std::floor(extent / H + 1e-9) + 1;
    if (n > double(1 << 20)) throw Error(image.path + ": --voxel-size " + std::to_string(H) + " mm is far too small for the image", 3);
    out.dims[a] = int(n);
    if (out.dims[a] < 2)
      throw Error(image.path + ": --voxel-size " + std::to_string(H) + " mm leaves fewer than 2 voxels along axis " +
                  std::to_string(a) + " (" + std::to_string(extent) + " mm)");
    padded *= out.dims[a] + 2 * std::max<std::int64_t>(1, std::int64_t(std::ceil(margin / H)));
    out.spacing[a] = H;
    for (int r = 0; r < 3; ++r) out.affine[r][a] = image.affine[r][a] / h[a] * H;
  }
  for (int r = 0; r < 3; ++r) out.affine[r][3] = image.affine[r][3];
  if (estimate_levelset_bytes(std::size_t(padded)) > default_max_memory())
    throw Error(image.path + ": resampled to " + std::to_string(H) + " mm the grid needs more memory than the budget (" +
                    std::to_string(default_max_memory() >> 20) + " MB); use a larger --voxel-size",
                3);
  const int nx = image.dims[0], ny = image.dims[1], nz = image.dims[2];
  auto g_at = [&](int i, int j, int k) {
    return g_of(image.values[std::size_t(i) + std::size_t(nx) * (std::size_t(j) + std::size_t(ny) * k)]);
  };
  out.values.resize(std::size_t(out.voxel_count()));
  tbb::parallel_for(0, out.dims[2], [&](int k) {
    auto cell = [&](int idx, int a, int& lo, double& t) {
      const double u = std::min(idx * H / h[a], double(image.dims[a] - 1));
      lo = std::min(int(u), image.dims[a] - 2);
      t = u - lo;
    };
    int k0, j0, i0;
    double tk, tj, ti;
    cell(k, 2, k0, tk);
    for (int j = 0; j < out.dims[1]; ++j) {
      cell(j, 1, j0, tj);
      for (int i = 0; i < out.dims[0]; ++i) {
        cell(i, 0, i0, ti);
        double v = 0;
        for (int c = 0; c < 8; ++c) {
          const int di = c & 1, dj = (c >> 1) & 1, dk = c >> 2;
          const double w = (di ? ti : 1 - ti) * (dj ? tj : 1 - tj) * (dk ? tk : 1 - tk);
          if (w != 0) v += w * g_at(i0 + di, j0 + dj, k0 + dk);
        }
        out.values[std::size_t(i) + std::size_t(out.dims[0]) * (std::size_t(j) + std::size_t(out.dims[1]) * k)] = float(v);
      }
    }
  });
  return out;
}

}  // namespace

VolumeField volume_to_levelset(const VolumeImage& image, const VolumeFieldOptions& o) {
  const std::string& path = image.path;
  if (o.has_iso == o.has_label)
    throw Error(path + ": give either --iso T (a scalar image: inside where the value is at or above T) or "
                       "--label N / --labels all (a label map)");
  if (o.has_iso && !std::isfinite(o.iso)) throw Error("--iso must be a finite number");
  const int nx = image.dims[0], ny = image.dims[1], nz = image.dims[2];
  const std::size_t n_img = std::size_t(image.voxel_count());
  if (image.values.size() != n_img)
    throw Error(path + ": the image holds " + std::to_string(image.values.size()) + " values for dims " +
                std::to_string(nx) + "x" + std::to_string(ny) + "x" + std::to_string(nz));

  // g >= 0 inside; the boundary is where the linear interpolation of g crosses 0.
  const float iso = float(o.has_iso ? o.iso : 0.5);
  auto g_of = [&](float value) -> float {
    if (o.has_label) return value == float(o.label) ? 0.5f : -0.5f;
    return o.inside_below ? iso - value : value - iso;
  };
  auto inside_of = [&](float value) {
    if (o.has_label) return value == float(o.label);
    return o.inside_below ? value < iso : value >= iso;
  };
  auto refuse_empty = [&] {
    if (o.has_label) throw Error(path + ": label " + std::to_string(o.label) + " has no voxel (empty label)");
    throw Error(path + ": no voxel is inside (" + (o.inside_below ? "below " : "at or above ") + "--iso " +
                std::to_string(o.iso) + "); the image's values do not reach it");
  };
  if (o.voxel_size > 0) {
    if (!std::isfinite(o.voxel_size)) throw Error("--voxel-size must be a finite number of mm");
    if (std::none_of(image.values.begin(), image.values.end(), inside_of)) refuse_empty();
    VolumeFieldOptions at_zero;
    at_zero.has_iso = true;
    at_zero.margin = o.margin;
    return volume_to_levelset(resample_inside_function(image, g_of, o.voxel_size, o.margin), at_zero);
  }

  VolumeField out;
  ScalarGrid& grid = out.grid;
  const std::array<double, 3> h = image.spacing;
  const double hmin = std::min({h[0], h[1], h[2]});
  double longest = 0;
  for (int a = 0; a < 3; ++a) longest = std::max(longest, h[a] * (image.dims[a] - 1));
  const double margin = o.margin >= 0 ? o.margin : default_margin(longest, hmin);
  for (int a = 0; a < 3; ++a) {
    out.pad[a] = std::max(1, int(std::ceil(margin / h[a] - 1e-9)));
    grid.dims[a] = image.dims[a] + 2 * out.pad[a];
    grid.origin[a] = -out.pad[a] * h[a];
  }
  grid.voxel_size = hmin;
  if (h[0] == h[1] && h[1] == h[2]) grid.voxel_size = h[0];
  else grid.spacing = h;
  const std::size_t N = std::size_t(grid.vertex_count());
  const std::size_t budget = default_max_memory();
  if (estimate_levelset_bytes(N) > budget)
    throw Error(path + ": the padded grid " + std::to_string(grid.dims[0]) + "x" + std::to_string(grid.dims[1]) + "x" +
                    std::to_string(grid.dims[2]) + " needs more memory than the budget; use a smaller --margin",
                3);

  // Sign: -1 inside, +1 outside (the padding is outside).
  grid.values.assign(N, 1.f);
  std::size_t inside = 0;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const std::size_t s = std::size_t(i) + std::size_t(nx) * (std::size_t(j) + std::size_t(ny) * k);
        if (inside_of(image.values[s])) {
          grid.values[std::size_t(grid.index(i + out.pad[0], j + out.pad[1], k + out.pad[2]))] = -1.f;
          ++inside;
        }
      }
  out.inside_voxels = inside;
  if (inside == 0) refuse_empty();

  // Boundary sites: every vertex with an axis neighbour of the other sign gets the nearest crossing point.
  auto g_at = [&](int i, int j, int k) -> float {  // grid coordinates; padding is far outside
    i -= out.pad[0], j -= out.pad[1], k -= out.pad[2];
    if (i < 0 || j < 0 || k < 0 || i >= nx || j >= ny || k >= nz) return o.has_label ? -0.5f : -1.f;
    const float v = image.values[std::size_t(i) + std::size_t(nx) * (std::size_t(j) + std::size_t(ny) * k)];
    return g_of(v);
  };
  const int gx = grid.dims[0], gy = grid.dims[1], gz = grid.dims[2];
  std::vector<std::vector<detail::Site>> slice_sites(static_cast<std::size_t>(gz));  // per z slice, joined in order
  tbb::parallel_for(0, gz, [&](int k) {
    std::vector<detail::Site>& sites = slice_sites[std::size_t(k)];
    for (int j = 0; j < gy; ++j)
      for (int i = 0; i < gx; ++i) {
        const std::size_t idx = std::size_t(grid.index(i, j, k));
        const bool in = grid.values[idx] < 0;
        double best = 1e300;
        float bp[3] = {0, 0, 0};
        for (int a = 0; a < 3; ++a)
          for (int dir = -1; dir <= 1; dir += 2) {
            int q[3] = {i, j, k};
            q[a] += dir;
            if (q[a] < 0 || q[a] >= grid.dims[a]) continue;
            const bool qin = grid.values[std::size_t(grid.index(q[0], q[1], q[2]))] < 0;
            if (qin == in) continue;
            auto in_image = [&](int a2, int c) { return c >= out.pad[a2] && c < out.pad[a2] + image.dims[a2]; };
            const bool both = in_image(0, i) && in_image(1, j) && in_image(2, k) && in_image(0, q[0]) &&
                              in_image(1, q[1]) && in_image(2, q[2]);
            // Against the padding (the image's border) the boundary is halfway, as for a mask.
            const double gv = g_at(i, j, k), gq = g_at(q[0], q[1], q[2]);
            double t = !both || gv == gq ? 0.5 : gv / (gv - gq);
            t = std::min(std::max(t, 0.0), 1.0);
            const double d = t * h[a];
            if (d < best) {
              best = d;
              bp[0] = float(i), bp[1] = float(j), bp[2] = float(k);
              bp[a] += float(dir * t);
            }
          }
        if (best < 1e300) sites.push_back({std::int64_t(idx), {bp[0], bp[1], bp[2]}});
      }
  });
  std::size_t total_sites = 0;
  for (auto& v : slice_sites) total_sites += v.size();
  std::vector<detail::Site> sites;
  sites.reserve(total_sites);
  for (auto& v : slice_sites) {
    sites.insert(sites.end(), v.begin(), v.end());
    std::vector<detail::Site>().swap(v);
  }
  out.boundary_sites = sites.size();
  if (sites.size() >= std::size_t(1u << 31))
    throw Error(path + ": more than 2^31 boundary voxels; not supported", 3);
  detail::complete_by_feature_transform(grid, {}, sites);
  // No exact zero: a vertex on the boundary (a voxel exactly at the iso value) keeps its side.
  const float eps = float(1e-3 * hmin);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, N, 1 << 16), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      float& v = grid.values[i];
      if (std::signbit(v)) {  // -0 is inside
        if (v > -eps) v = -eps;
      } else if (v < eps) {
        v = eps;
      }
    }
  });

  out.frame.set = true;
  out.frame.convention = image.convention;
  out.frame.source = image.transform_source;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) out.frame.linear[r][c] = image.affine[r][c] / h[c];
    out.frame.offset[r] = image.affine[r][3];
  }
  return out;
}

}  // namespace chokeloops

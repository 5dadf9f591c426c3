// Sampled analytic test shapes (see include/chokeloops/field/analytic.h).
#include "chokeloops/field/analytic.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace chokeloops {

namespace {

// splitmix64: a tiny, portable, seedable generator (std distributions differ between libraries).
std::uint64_t mix(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}
// Uniform in [0, 1) from 53 random bits.
double unit(std::uint64_t bits) { return double(bits >> 11) * (1.0 / 9007199254740992.0); }

struct Rng {
  std::uint64_t state;
  double next() { return unit(mix(state++)); }
  double uniform(double a, double b) { return a + (b - a) * next(); }
};

double length3(double x, double y, double z) { return std::sqrt(x * x + y * y + z * z); }

// Exact SDF of a cylinder of radius r around the x axis through (cy, cz), capped at x0 <= x <= x1.
double capped_cylinder_x(double x, double y, double z, double x0, double x1, double cy, double cz, double r) {
  double mid = 0.5 * (x0 + x1), h = 0.5 * (x1 - x0);
  double dr = std::hypot(y - cy, z - cz) - r, dx = std::abs(x - mid) - h;
  return std::min(std::max(dr, dx), 0.0) + std::hypot(std::max(dr, 0.0), std::max(dx, 0.0));
}

}  // namespace

ScalarGrid sample_field(std::array<int, 3> n, const Sdf& sdf, Vec3 lo, Vec3 hi) {
  for (int a = 0; a < 3; ++a)
    if (n[a] < 2) throw std::invalid_argument("sample_field: need at least 2 samples per axis");
  std::array<double, 3> h{};
  for (int a = 0; a < 3; ++a) h[a] = (hi[a] - lo[a]) / (n[a] - 1);
  for (int a = 1; a < 3; ++a)
    if (!(std::abs(h[a] - h[0]) <= 1e-6 * std::abs(h[0])) || !(h[0] > 0))
      throw std::invalid_argument("sample_field: the voxel must be a cube ((hi-lo)/(n-1) equal on all axes)");
  ScalarGrid g;
  g.dims = n;
  g.origin = lo;
  g.voxel_size = h[0];
  g.values.resize(size_t(g.vertex_count()));
  tbb::parallel_for(tbb::blocked_range<int>(0, n[2]), [&](const tbb::blocked_range<int>& r) {
    for (int k = r.begin(); k < r.end(); ++k)
      for (int j = 0; j < n[1]; ++j)
        for (int i = 0; i < n[0]; ++i)
          g.values[size_t(g.index(i, j, k))] =
              float(sdf(lo[0] + i * h[0], lo[1] + j * h[1], lo[2] + k * h[2]));
  });
  return g;
}

namespace analytic {

Sdf ball(double r, Vec3 c) {
  return [=](double x, double y, double z) { return length3(x - c[0], y - c[1], z - c[2]) - r; };
}

Sdf torus(double R, double r, Vec3 c) {
  return [=](double x, double y, double z) {
    double q = std::hypot(x - c[0], y - c[1]) - R;
    return std::hypot(q, z - c[2]) - r;
  };
}

Sdf double_torus(double R, double r, double separation, Vec3 c) {
  Sdf a = torus(R, r, {c[0] - separation / 2, c[1], c[2]});
  Sdf b = torus(R, r, {c[0] + separation / 2, c[1], c[2]});
  return [=](double x, double y, double z) { return std::min(a(x, y, z), b(x, y, z)); };
}

Sdf dumbbell(double ball_r, double neck_r, double half_length, Vec3 c) {
  Sdf a = ball(ball_r, {c[0] - half_length, c[1], c[2]});
  Sdf b = ball(ball_r, {c[0] + half_length, c[1], c[2]});
  return [=](double x, double y, double z) {
    double neck = capped_cylinder_x(x, y, z, c[0] - half_length, c[0] + half_length, c[1], c[2], neck_r);
    return std::min({a(x, y, z), b(x, y, z), neck});
  };
}

Sdf pierced_hollow_ball(double outer, double inner, double hole_r, Vec3 c) {
  return [=](double x, double y, double z) {
    double rho = length3(x - c[0], y - c[1], z - c[2]);
    double shell = std::max(rho - outer, inner - rho);
    // From the centre through the +x wall and well beyond it.
    double hole = capped_cylinder_x(x, y, z, c[0], c[0] + 2 * outer, c[1], c[2], hole_r);
    return std::max(shell, -hole);
  };
}

Sdf varying_torus(double R, double r0, double amp, Vec3 c) {
  return [=](double x, double y, double z) {
    double dx = x - c[0], dy = y - c[1];
    double t = std::atan2(dy, dx);
    double q = std::hypot(dx, dy) - R;
    return std::hypot(q, z - c[2]) - (r0 + amp * std::cos(t));
  };
}

Sdf tangle_cube(Vec3 c) {
  const double s = 6.0;
  return [=](double x, double y, double z) {
    double X = s * (x - c[0]), Y = s * (y - c[1]), Z = s * (z - c[2]);
    double X2 = X * X, Y2 = Y * Y, Z2 = Z * Z;
    double f = X2 * X2 - 5 * X2 + Y2 * Y2 - 5 * Y2 + Z2 * Z2 - 5 * Z2 + 11.8;
    return f / (s * 20.0);
  };
}

Sdf random_gaussians(int count, std::uint64_t seed) {
  struct Bump { double x, y, z, inv2w2, amp; };
  std::vector<Bump> bumps;
  Rng rng{mix(seed)};
  for (int i = 0; i < count; ++i) {
    Bump b;
    b.x = rng.next();
    b.y = rng.next();
    b.z = rng.next();
    double w = rng.uniform(0.05, 0.2);
    b.inv2w2 = 1.0 / (2 * w * w);
    b.amp = rng.uniform(0.5, 1.0) * (rng.next() < 0.5 ? -1 : 1);
    bumps.push_back(b);
  }
  return [bumps](double x, double y, double z) {
    double s = 0;
    for (auto& b : bumps) {
      double d2 = (x - b.x) * (x - b.x) + (y - b.y) * (y - b.y) + (z - b.z) * (z - b.z);
      s += b.amp * std::exp(-d2 * b.inv2w2);
    }
    return s;
  };
}

}  // namespace analytic

void add_uniform_noise(ScalarGrid& grid, double amplitude, std::uint64_t seed) {
  std::uint64_t base = mix(seed ^ 0x6a09e667f3bcc909ull);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, grid.values.size()), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i < r.end(); ++i)
      grid.values[i] = float(grid.values[i] + amplitude * (2 * unit(mix(base + i)) - 1));
  });
}

}  // namespace chokeloops

namespace chokeloops::analytic {

Sdf hollow_ball_through_hole(double outer, double inner, double hole_r, Vec3 c) {
  return [=](double x, double y, double z) {
    double rho = length3(x - c[0], y - c[1], z - c[2]);
    double shell = std::max(rho - outer, inner - rho);
    double hole = capped_cylinder_x(x, y, z, c[0] - 2 * outer, c[0] + 2 * outer, c[1], c[2], hole_r);
    return std::max(shell, -hole);
  };
}

}  // namespace chokeloops::analytic

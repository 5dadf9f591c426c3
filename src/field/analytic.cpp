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

namespace {
struct Hole { int axis; double u, v, r; };  // a line along `axis` through (u, v) in the other two coordinates

// Distance between the axes of two holes (parallel: in their common plane; crossing: along the third axis).
double axis_distance(const Hole& a, const Hole& b) {
  if (a.axis == b.axis) return std::hypot(a.u - b.u, a.v - b.v);
  // Coordinates (u, v) are the two axes other than `axis`, in increasing order; the third axis, not
  // along either hole, is where both lines have a fixed coordinate.
  const int third = 3 - a.axis - b.axis;
  auto coordinate = [](const Hole& h, int axis) { return axis == (h.axis == 0 ? 1 : 0) ? h.u : h.v; };
  return std::abs(coordinate(a, third) - coordinate(b, third));
}
}  // namespace

Sdf pierced_block(int holes, std::uint64_t seed, double r_min, double r_max) {
  const Vec3 lo{0.1, 0.15, 0.2}, hi{0.9, 0.85, 0.8};
  std::vector<Hole> placed;
  Rng rng{mix(seed)};
  // Four sizes, so that depths spread.
  for (int tries = 0; int(placed.size()) < holes && tries < 200000; ++tries) {
    Hole h;
    h.axis = int(rng.next() * 3) % 3;
    h.r = r_min + (r_max - r_min) * double(int(rng.next() * 4) % 4) / 3.0;
    const int ua = h.axis == 0 ? 1 : 0, va = h.axis == 2 ? 1 : 2;
    h.u = rng.uniform(lo[ua] + 2 * h.r, hi[ua] - 2 * h.r);
    h.v = rng.uniform(lo[va] + 2 * h.r, hi[va] - 2 * h.r);
    bool fits = true;
    for (const Hole& o : placed) fits &= axis_distance(h, o) > 1.5 * (h.r + o.r);
    if (fits) placed.push_back(h);
  }
  if (int(placed.size()) < holes) throw std::invalid_argument("pierced_block: holes do not fit in the block");
  return [=](double x, double y, double z) {
    const double p[3] = {x, y, z};
    double box_out = 0, box_in = -1e300;
    for (int a = 0; a < 3; ++a) {
      const double d = std::max(lo[a] - p[a], p[a] - hi[a]);
      box_in = std::max(box_in, d);
      box_out += std::max(d, 0.0) * std::max(d, 0.0);
    }
    double f = box_in > 0 ? std::sqrt(box_out) : box_in;
    for (const Hole& h : placed) {
      const int ua = h.axis == 0 ? 1 : 0, va = h.axis == 2 ? 1 : 2;
      f = std::max(f, h.r - std::hypot(p[ua] - h.u, p[va] - h.v));
    }
    return f;
  };
}

Sdf ball_and_stick_cage(std::array<int, 3> n, double ball_r, double neck_r) {
  const int longest = std::max({n[0], n[1], n[2]});
  if (std::min({n[0], n[1], n[2]}) < 1 || longest < 2) throw std::invalid_argument("ball_and_stick_cage: need 2 balls or more");
  const double step = 0.6 / (longest - 1);
  Vec3 first;
  for (int a = 0; a < 3; ++a) first[a] = 0.5 - 0.5 * step * (n[a] - 1);
  return [=](double x, double y, double z) {
    const double p[3] = {x, y, z};
    // Only the balls and sticks of the nearest lattice cell can be nearest (beyond it a ball covers the
    // end of every stick): clamp to that cell.
    std::array<int, 3> c;
    for (int a = 0; a < 3; ++a)
      c[a] = std::min(std::max(int(std::floor((p[a] - first[a]) / step)), 0), std::max(n[a] - 2, 0));
    double f = 1e300;
    for (int k = c[2]; k <= std::min(c[2] + 1, n[2] - 1); ++k)
      for (int j = c[1]; j <= std::min(c[1] + 1, n[1] - 1); ++j)
        for (int i = c[0]; i <= std::min(c[0] + 1, n[0] - 1); ++i) {
          const int at[3] = {i, j, k};
          double d0[3];
          for (int a = 0; a < 3; ++a) d0[a] = p[a] - (first[a] + step * at[a]);
          f = std::min(f, length3(d0[0], d0[1], d0[2]) - ball_r);
          // The stick toward +x, +y, +z from this ball: radius ball_r at its ends, neck_r at its middle.
          for (int a = 0; a < 3; ++a) {
            if (at[a] + 1 > n[a] - 1) continue;
            double d[3] = {d0[0], d0[1], d0[2]};
            const double t = std::min(std::max(d[a] / step, 0.0), 1.0);
            d[a] -= t * step;
            const double s = 2 * t - 1;
            f = std::min(f, length3(d[0], d[1], d[2]) - (neck_r + (ball_r - neck_r) * s * s));
          }
        }
    return f;
  };
}

}  // namespace chokeloops::analytic

#pragma once
// Sampled analytic test shapes: signed distance functions (negative inside) of shapes whose topology
// is known (torus, double torus, dumbbell, pierced hollow ball, ...), a sampler that turns any such
// function into a ScalarGrid, and seeded random fields. Used by the tests and the benchmarks; they are
// library code so that bench/ and tools can use them without the test tree.
//
// All shapes live in the unit cube by default, centred at (0.5, 0.5, 0.5). "Exact" below means the
// function is the true Euclidean signed distance; unions (min) and differences (max(a, -b)) are exact
// outside the union / only approximate elsewhere, which does not change the sign or the topology of
// the sublevel sets that the tests rely on.
#include <array>
#include <cstdint>
#include <functional>

#include "chokeloops/grid.h"

namespace chokeloops {

using Vec3 = std::array<double, 3>;
using Sdf = std::function<double(double, double, double)>;

// Samples `sdf` at the vertices x_i = lo + i*(hi-lo)/(n-1) (per axis). The spacing must be the same on
// all three axes (a cubic voxel; relative tolerance 1e-6), else std::invalid_argument. The result has
// origin = lo and voxel_size = that spacing. Sampling runs in parallel (deterministic).
ScalarGrid sample_field(std::array<int, 3> n, const Sdf& sdf, Vec3 lo = {0, 0, 0}, Vec3 hi = {1, 1, 1});

namespace analytic {

constexpr Vec3 kCentre{0.5, 0.5, 0.5};

// Ball of radius r. Exact.
Sdf ball(double r, Vec3 c = kCentre);

// Torus around the z axis through c: major radius R, tube radius r. Exact.
// Genus 1; the hole closes (outside) at distance R - r, the tube's core dies at depth r.
Sdf torus(double R, double r, Vec3 c = kCentre);

// Two tori (axis z, major radius R, tube r) with centres c -/+ (separation/2, 0, 0), joined by min.
// Their tubes overlap when separation < 2R + 2r; the defaults give a genus-2 solid whose holes are
// 6+ voxels wide at 64^3 and whose tubes overlap around x = 0.5.
Sdf double_torus(double R = 0.17, double r = 0.07, double separation = 0.34, Vec3 c = kCentre);

// Dumbbell: balls of radius `ball_r` at c -/+ (half_length, 0, 0) joined by a cylinder (axis x) of
// radius `neck_r` between the two ball centres; union by min. The inside has two deep minima (-ball_r)
// merging at the neck (about -neck_r): one dim-0 pair with persistence about ball_r - neck_r.
Sdf dumbbell(double ball_r = 0.2, double neck_r = 0.12, double half_length = 0.23, Vec3 c = kCentre);

// Hollow ball pierced by one hole: a thick spherical shell (outer radius `outer`, inner `inner`) with
// a cylinder of radius `hole_r` drilled from the centre along +x through ONE wall, so the cavity opens
// to the outside through a single tunnel (the cavity's "mouth"). Genus 0. In the signed filtration
// the mouth closes at about hole_r and the cavity then fills up at about `inner`: one dim-2 pair
// (b ~ hole_r, d ~ inner). Difference by max(shell, -cylinder): approximate near the hole's rim.
Sdf pierced_hollow_ball(double outer = 0.4, double inner = 0.25, double hole_r = 0.06, Vec3 c = kCentre);

// The same shell drilled straight through both walls along x: genus 1 (the hole is a handle/tunnel pair) and
// the cavity, open to the outside at two mouths, gives one additional tunnel choke.
Sdf hollow_ball_through_hole(double outer = 0.4, double inner = 0.25, double hole_r = 0.06, Vec3 c = kCentre);

// Torus (axis z, major radius R) whose tube radius varies with the angle t around the axis:
// r(t) = r0 + amp*cos(t) (thinnest at t = pi, i.e. on the -x side). Approximate SDF:
// sqrt((rho - R)^2 + z^2) - r(t), whose gradient norm is within 1 +- amp/(R - r0 - amp) of 1.
// With the defaults it extends to 0.71 from the centre: sample it on e.g. lo = -0.3, hi = 1.3.
Sdf varying_torus(double R = 0.5, double r0 = 0.15, double amp = 0.06, Vec3 c = kCentre);

// Tangle cube x^4 - 5x^2 + y^4 - 5y^2 + z^4 - 5z^2 + 11.8 (an implicit function, not a distance), with
// X = 6 (p - c) so that the shape (|X| <= 2.27 per axis) sits inside the unit cube, divided by 6*20 so
// that its gradient is of order 1 near the surface (|grad f| is 15-45 on the zero set in X units).
Sdf tangle_cube(Vec3 c = kCentre);

// A block pierced by `holes` straight round holes (cylinders along x, y or z, radii in [r_min, r_max],
// placed by a seeded rejection sampling: the gap between two holes is at least half their radii's sum, and
// every hole is at least its radius from the block's edges): genus `holes`, one handle and one tunnel
// generator per hole. The block spans [0.1, 0.9] x [0.15, 0.85] x [0.2, 0.8]; sample it on the unit cube.
// Exact outside the block, approximate (max of exact distances) inside it.
Sdf pierced_block(int holes, std::uint64_t seed, double r_min = 0.01, double r_max = 0.03);

// A ball-and-stick cage: balls of radius `ball_r` on an n[0] x n[1] x n[2] lattice (step 0.6 / (largest
// n - 1), centred in the unit cube), each pair of lattice neighbours joined by a stick whose radius narrows
// from `ball_r` at its ends to `neck_r` at its middle (a neck on every stick). Genus = sticks - balls + 1.
// Approximate SDF.
Sdf ball_and_stick_cage(std::array<int, 3> n = {3, 3, 3}, double ball_r = 0.07, double neck_r = 0.035);

// Smooth random field: sum of `count` Gaussian bumps of random sign, centre in the unit cube and width
// in [0.05, 0.2], amplitude in [0.5, 1], seeded (same seed -> same function on every platform).
Sdf random_gaussians(int count, std::uint64_t seed);

}  // namespace analytic

// Adds uniform noise in [-amplitude, amplitude] to every value (seeded, deterministic).
void add_uniform_noise(ScalarGrid& grid, double amplitude, std::uint64_t seed);

}  // namespace chokeloops

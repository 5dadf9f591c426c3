#pragma once
// Private to src/loops: the two-lobe priority flood of a choke (membranes.cpp says why this construction).
// The two pieces of {below the saddle} that the choke simplex joins seed zones 1 and 2; the flood grows them
// through the region (the solid for handles, the outside for tunnels) in filtration order inside a box
// around the saddle. Their contact is the membrane; where it meets the surface is the loop. The loop
// tracer reads the contact at the shore, the filter the whole contact sheet.
#include <algorithm>
#include <array>
#include <cstdint>
#include <string>
#include <unordered_map>
#include <vector>

#include "chokeloops/loops/membrane_voxels.h"
#include "chokeloops/topology/chokes.h"
#include "chokeloops/topology/complex.h"
#include "chokeloops/surface/surface.h"

namespace chokeloops::detail {

enum class FloodOutcome { Flooded, Grow, Shrink };  // Grow: a lobe is not in the box; Shrink: the seeds touch

// The box of one flood and its labels. The per-vertex arrays belong to the calling thread and are reused
// by its next flood: read what is needed before flooding again on the same thread.
struct FloodBox {
  static constexpr std::uint32_t kZone = 3, kOutside = 3, kBorder = 4;
  static constexpr int kLevelShift = 3;
  static constexpr int kLevelsPerVoxel = 64;  // the flood's levels are this fine (a bucket queue)
  std::array<int, 3> lo{}, hi{}, n{};  // grid coordinates of the box (inclusive) and its size
  Id base = 0;                         // grid id of local (0, 0, 0)
  Id gy = 0, gz = 0;                   // grid strides
  std::size_t ly = 0, lz = 0;          // local strides
  // per box vertex: zone (bits 0-1), border bit, level; in 16 bits when the levels fit, else in 32
  const std::vector<std::uint16_t>* cell16 = nullptr;
  const std::vector<std::uint32_t>* cell = nullptr;
  const std::vector<std::uint8_t>* contact = nullptr;  // 1: a neighbour carries the other zone
  std::vector<std::uint32_t> shore;    // labelled box vertices in contact, with a neighbour outside the region
  std::array<std::array<double, 3>, 2> seed_centroid{};  // of each seed piece, grid coordinates
  std::array<std::size_t, 2> seed_count{0, 0};

  std::uint32_t word(std::uint32_t li) const { return cell16 ? (*cell16)[li] : (*cell)[li]; }
  std::uint32_t zone(std::uint32_t li) const { return word(li) & kZone; }
  std::uint32_t level(std::uint32_t li) const { return word(li) >> kLevelShift; }  // 0: below the saddle
  bool on_border(std::uint32_t li) const { return word(li) & kBorder; }
  bool in_contact(std::uint32_t li) const { return (*contact)[li] != 0; }
  std::array<int, 3> local(std::uint32_t li) const {
    const int k = int(li / lz), rest = int(li % lz);
    return {rest % n[0], rest / n[0], k};
  }
  Id global(std::uint32_t li) const {
    const auto p = local(li);
    return base + p[0] + gy * p[1] + gz * p[2];
  }
  std::size_t size() const { return lz * std::size_t(n[2]); }
};

// RegionBounds and region_bounds are public (loops/membrane_voxels.h): the label volumes clip their floods too.
using chokeloops::RegionBounds;
using chokeloops::region_bounds;

// The half-sizes of a flood box on each side of the saddle, per axis: a box can grow toward the side where
// its membrane runs out (a sheet across a block's whole section is thin across its own plane).
struct BoxExtent {
  std::array<int, 3> below{}, above{};
  static BoxExtent cube(int r) { return {{r, r, r}, {r, r, r}}; }
  int largest() const { return std::max({below[0], below[1], below[2], above[0], above[1], above[2]}); }
  int smallest() const { return std::min({below[0], below[1], below[2], above[0], above[1], above[2]}); }
};

// The grid box (inclusive) that a flood of `extent` around `saddle` reads: clipped to the grid, and to
// `bounds` when given. Some hi[a] < lo[a] where the box holds none of the region.
inline void flood_box_range(const BoxExtent& extent, const std::array<int, 3>& saddle, const std::array<int, 3>& dims,
                            const RegionBounds* bounds, std::array<int, 3>& lo, std::array<int, 3>& hi) {
  for (int a = 0; a < 3; ++a) {
    lo[a] = std::max(0, saddle[a] - extent.below[a]);
    hi[a] = std::min(dims[a] - 1, saddle[a] + extent.above[a]);
    if (bounds) lo[a] = std::max(lo[a], bounds->lo[a]), hi[a] = std::min(hi[a], bounds->hi[a]);
  }
}

// Floods the box of half-size `r` around the choke's saddle, clipped to `bounds` when given (the choke's side's
// region_bounds); the seed pieces are looked for within `seed_radius` of it. by_distance: grow the zones by
// steps from the seeds (their bisector) instead of in filtration order. Throws Error when the choke is too
// deep for the level queue.
FloodOutcome flood_two_lobes(const ScalarGrid& grid, const FreudenthalComplex& cx, const Choke& c, int r, int seed_radius,
                             bool by_distance, FloodBox& box, const RegionBounds* bounds = nullptr);
// The same in a box of the given half-sizes on each side of the saddle.
FloodOutcome flood_two_lobes(const ScalarGrid& grid, const FreudenthalComplex& cx, const Choke& c, const BoxExtent& extent,
                             int seed_radius, bool by_distance, FloodBox& box, const RegionBounds* bounds = nullptr);

// True when the box around `saddle` (grid coordinates) holds all of `bounds`: its flood is the region's.
bool box_covers(const BoxExtent& extent, const std::array<int, 3>& saddle, const RegionBounds& bounds);

// Grows the sides of the box marked in `open_sides` (below x y z, above x y z) that can still grow within
// `bounds`, each by a factor 1.8 up to `full` voxels (a side past half of `full` goes to `full` at once: one
// more box nearly the grid's size would cost what the grid does); all six sides when none of them is marked.
void grow_box(BoxExtent& extent, const std::array<char, 6>& open_sides, const std::array<int, 3>& saddle,
              const RegionBounds& bounds, int full);

// Interface segments on surface faces, each between two surface edges (keys: the edges' two vertices, the
// smaller first, in 32 bits each), and the segments at each edge (the second -1 at a curve's open end).
using InterfaceSegments = std::vector<std::array<std::int64_t, 2>>;
using SegmentsAtEdge = std::unordered_map<std::int64_t, std::array<int, 2>>;

// The key of the surface edge between vertices a and b.
inline std::int64_t edge_key(int a, int b) {
  return a < b ? (std::int64_t(a) << 32) | b : (std::int64_t(b) << 32) | a;
}

// The midpoint of the surface edge with key `edge` (the interface crosses the edge there).
inline std::array<double, 3> edge_midpoint(const SurfaceMesh& surface, std::int64_t edge) {
  const auto& a = surface.vertices[std::size_t(edge >> 32)];
  const auto& b = surface.vertices[std::size_t(edge & 0xffffffff)];
  return {(a[0] + b[0]) / 2, (a[1] + b[1]) / 2, (a[2] + b[2]) / 2};
}

// Marks the sides of the flood box (below x y z, above x y z) where an interface curve that comes within
// `near` of `point` ends: such a curve ends where the box cuts its membrane, and the box grows there.
void mark_open_sides(const ScalarGrid& grid, const SurfaceMesh& surface, const InterfaceSegments& segments,
                     const SegmentsAtEdge& at, const FloodBox& box, const std::array<double, 3>& point, double near,
                     std::array<char, 6>& open_sides);

// The box sequence of closing_membrane_voxels for one choke: which box to flood next (cubes from
// LoopOptions::first_box_radius, x1.8 up to the options' cap, a smaller seed where the seeds touch) and what
// each flooded box gives its Sheet and Plane membranes. The label volumes run it; the loop tracer feeds it
// the floods of its own first boxes while they are the same boxes (MembraneProgress).
class MembraneSequence {
 public:
  MembraneSequence(const ScalarGrid& grid, const Choke& choke, const LoopOptions& options, std::array<bool, 2> open,
                   int stop_at);
  // Goes on from `from`, recorded for this choke with the same options and shapes.
  MembraneSequence(const ScalarGrid& grid, const Choke& choke, const LoopOptions& options, MembraneProgress from);
  bool done() const { return p_.done; }
  int radius() const { return p_.radius; }
  int seed_radius() const { return p_.seed_radius; }
  // The outcome of flooding the box radius() with seed_radius(); `box` is read when it was flooded.
  void take(FloodOutcome outcome, const FloodBox& box);
  // That flood threw: each open shape ends with `why` as its note.
  void fail(const std::string& why);
  MembraneProgress release() { return std::move(p_); }

 private:
  const ScalarGrid& grid_;
  std::array<int, 3> saddle_;  // grid coordinates
  int full_, cap_;
  MembraneProgress p_;
};

}  // namespace chokeloops::detail

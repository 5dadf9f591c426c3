#pragma once
// Stage `membranes` + `shorten`: from each choke simplex, the loop on the surface.
//
// Construction (DESIGN §3, chosen by measurement — see membranes.cpp): a two-lobe priority flood. The two
// pieces of the sublevel set (superlevel set, for tunnels) that the choke simplex joins seed two labels;
// the flood grows them through the solid (the outside, for tunnels) in filtration order inside a local box
// around the choke. The interface of the two zones is the membrane; where it meets the surface is the loop.
// The loop is then shortened toward a local geodesic without leaving the choke's neighbourhood.
#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

#include "chokeloops/topology/chokes.h"
#include "chokeloops/surface/mesh_adjacency.h"
#include "chokeloops/surface/surface.h"

namespace chokeloops {

struct LoopOptions {
  bool shorten = true;
  bool slide = true;         // after shortening, slide the loop along its normal to the narrowest section
  double box_factor = 1.5;   // local box half-size = box_factor * depth + box_margin voxels (grown on demand)
  int box_margin = 3;
  int max_box_radius = 0;    // voxels; 0: boxes grow up to the whole grid
  // A generator two voxels deep or more first tries the section by the plane through its choke square to its
  // cycle, kept when it bounds on its side and shortens to a loop that stays essential; else, and for thinner
  // ones, its membrane. (Across a handle the grid resolves, that plane cuts it where the membrane does, for a
  // fifth of the membrane's cost; a plane through a pinhole of a thin sheet cuts the sheet instead.)
  bool plane_start = true;
  // A plane start whose section crosses this many faces or more is first shortened inside those faces
  // (shorten_strip_loop), the band search only when that loop is still moving after its rounds or moved
  // farther than the choke's depth; SIZE_MAX: never. On shorter sections the band search costs little, and
  // from a section running obliquely over a hole's stepped wall the swaps stop in a loop 1% longer than the
  // band search's (43 of the pierced block's tunnel loops when every section was).
  std::size_t strip_start_faces = 1000;

  // The first box's half-size around a choke of this depth, and the radius its seed pieces are looked for
  // within, in voxels of size `voxel`: what the loop stage, the label volumes and the filter start from.
  int first_box_radius(double depth, double voxel) const { return int(std::ceil(box_factor * depth / voxel)) + box_margin; }
  int seed_radius(double depth, double voxel) const { return int(std::ceil(depth / voxel)) + box_margin; }
};

struct Loop {
  Choke choke;
  bool found = false;              // false: no closed interface curve was found (see note)
  std::string note;                // why a loop is missing or was left unshortened
  Polyline3 points;                // closed polyline on the surface (last point != first)
  std::vector<int> edge_path;      // the same loop snapped to surface vertices (cyclic; for topology checks)
  double length = 0;               // of `points`, closing segment included
  double raw_length = 0;           // of the flood interface before shortening
  std::array<double, 3> centroid{0, 0, 0};
  std::array<double, 3> normal{0, 0, 0};  // unit normal of the loop's best-fit plane
  double radius_min = 0, radius_mean = 0;  // distances of the points from the centroid
  int box_radius = 0;              // largest half-size in voxels of the box the membrane closed in
  double trace_ms = 0;             // wall time spent on this loop (a diagnostic for benchmarks; not reported)
  bool from_strip = false;         // shortened inside its plane section's own faces (a diagnostic; not reported)
};

// Length, centroid, best-fit plane normal (sign fixed: its largest component positive) and radii of
// loop.points; every loop stage describes its loops with it.
void describe_loop(Loop& loop);

class SurfaceTopology;
struct MembraneProgress;

// Loops of all chokes, computed in parallel; the result does not depend on the thread count. With a
// topology of `surface`, a generator's loop is chosen among its membrane's interface curves as the nearest
// one that is non-contractible on the surface and bounds on its side: it links no cycle of the other side's
// generators (loops/linking.h); else a plane section that does (the box grows until one appears); without,
// the nearest. `genus`: the surface's genus, when `chokes` hold every generator of the surface; the
// generator loops of each side are then also checked to be independent, and one that is not is reported
// missing with a note (the cycles of a side span its homology only when every generator is there).
// `membranes`: when given, one per choke, where the floods of each choke's loop leave the sequence of boxes
// its label-volume membrane grows in (closing_membrane_voxels with label_membrane_options), so that those
// boxes are not flooded twice: a choke's boxes are that sequence's up to the cap, a generator's as long as
// they grow as cubes.
// `progress`: called on the calling thread only (the hooks of the CLI and of Python are not made for others)
// with ("loops", the fraction of the chokes whose loop is done) each time it finishes one, and with 1 at the
// end. Returning false stops the stage: the loops under way finish, no other one starts, and Error
// "interrupted" is thrown. The loops do not depend on it.
std::vector<Loop> trace_loops(const ScalarGrid& grid, const SurfaceMesh& surface, const MeshAdjacency& adjacency,
                              const std::vector<Choke>& chokes, const LoopOptions& options = {},
                              SurfaceTopology* topology = nullptr, int genus = -1,
                              std::vector<MembraneProgress>* membranes = nullptr, const ProgressFn& progress = {});

}  // namespace chokeloops

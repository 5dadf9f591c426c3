#pragma once
// Tunnels of molecules (DESIGN §6): for each tunnel choke, the exact bottleneck against the atom spheres,
// the radius profile of the widest path through it, the atoms lining it, and the tunnel loop taken as the
// surface's cross-section at the bottleneck.
//
// Bottleneck. A tunnel choke is born or dies at a triangle of the grid: the sampled image of an index-2
// critical point of the distance to the spheres, f(x) = min_i |x - c_i| - R_i. Such a point is equidistant
// from three spheres, lies in the plane of their centres, and the directions from the three centres to it
// surround it (0 in their convex hull); f there is the radius of the largest ball that passes, and the normal
// of that plane is the channel's axis. It is found exactly (Apollonius' problem in the plane of each triple
// of nearby atoms) and the candidate nearest the grid's choke is taken. HOLE maximises f in planes normal to
// a given axis and minimises over the planes, which gives the same point when its axis is the channel's.
// Profile. From the bottleneck, a Dijkstra on the grid each way along the axis (the half-disc behind it
// blocked), with cost length / f^2 over vertices where f is at least half the choke's value, to the bulk
// (f >= bulk_radius or the box border) or, in a cavity, to its widest point; radii are exact f on the path.
#include <array>
#include <memory>
#include <string>
#include <vector>

#include "chokeloops/field/molecular_field.h"
#include "chokeloops/loops/membranes.h"
#include "chokeloops/loops/plane_sections.h"
#include "chokeloops/surface/mesh_adjacency.h"
#include "chokeloops/surface/surface.h"

namespace chokeloops {

struct ChannelOptions {
  double bulk_radius = 5.0;       // Å: the profile ends where f reaches max(this, 1.5 x bottleneck) (HOLE's endrad)
  double lining_margin = 0.5;     // Å: an atom lines the path where its surface is within radius + this
  double search_radius = 1.5;     // Å: how far from the grid's choke the exact bottleneck may lie
  bool trace_unsectioned = true;  // tunnel chokes without a valid cross-section get membrane loops (slow on
                                  // big proteins: thousands of generators); false: a note instead
  bool section_loops = true;      // tunnel loops are the surface's cross-section at the bottleneck where one is found
  // Å: a tunnel whose bottleneck is narrower keeps its bottleneck, axis and lining there but gets no profile
  // and no loop, only a note (as CAVER's probe radius: no probe passes such a constriction; 0 traces all).
  // analyze_molecule leaves the handles shallower than it untraced too (rings of atoms closed by a contact).
  double min_radius = 0.9;
};

struct ProfilePoint {
  double s = 0;                    // signed arc length from the bottleneck, Å
  std::array<double, 3> p{0, 0, 0};
  double radius = 0;               // exact f at p
};

struct LiningAtom {
  int atom = -1;                   // index into Molecule::atoms
  double distance = 0;             // closest |x - c| - r_vdw over the path (bottleneck: at the bottleneck)
};

struct Channel {
  int loop = -1;                   // index into the analysis' loops
  bool refined = false;            // exact bottleneck found (else the grid's choke is reported)
  double bottleneck_radius = 0;    // Å
  double grid_radius = 0;          // the grid's value (the choke's depth)
  std::array<double, 3> bottleneck{0, 0, 0};
  std::array<double, 3> axis{0, 0, 1};
  std::array<int, 3> atoms{-1, -1, -1};  // the three atoms the bottleneck touches
  std::vector<ProfilePoint> profile;
  double length = 0;               // of the profile path, Å
  bool open[2] = {false, false};   // each end reached the bulk (false: ends in a cavity)
  std::vector<LiningAtom> lining;             // along the path, by distance
  std::vector<LiningAtom> bottleneck_lining;  // at the bottleneck, by distance
  Polyline3 section;               // the surface's cross-section around the bottleneck (empty: none found)
  double section_length = 0;
  bool traced = true;              // false: narrower than ChannelOptions::min_radius (no profile, no loop)
  std::string note;
};

// One channel per tunnel choke, in the order of `chokes` (Channel::loop = the choke's index). `locator`
// holds the spheres the chosen surface's distance is measured against (vdW radii, + probe for SAS); `vdw`
// the van der Waals spheres (lining distances). Parallel; the result does not depend on the thread count.
std::vector<Channel> analyze_channels(const ScalarGrid& grid, const SurfaceMesh& surface, const AtomLocator& locator,
                                      const AtomLocator& vdw, const std::vector<Choke>& chokes,
                                      const ChannelOptions& options = {});

// A tunnel loop made of a cross-section (Channel::section), snapped to surface edges for the topology checks.
Loop section_loop(const Choke& choke, const Polyline3& section, const SurfaceMesh& surface, const MeshAdjacency& adjacency);

// The index-2 critical point of f nearest `x0` within `search_radius` (false if none).
bool refine_bottleneck(const AtomLocator& locator, const std::array<double, 3>& x0, double search_radius,
                       Channel& out);

}  // namespace chokeloops

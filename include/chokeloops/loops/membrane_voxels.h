#pragma once
// The grid vertices of a choke's membrane: one shore of the two-lobe flood's contact sheet (membranes.h),
// the disc across a handle (in the solid) or across a tunnel (in the outside). Flipping their sign cuts the
// handle or fills the tunnel; `chokeloops filter` does that, and label volumes draw the membrane with them.
#include <array>
#include <functional>
#include <string>
#include <vector>

#include "chokeloops/loops/membranes.h"
#include "chokeloops/topology/chokes.h"

namespace chokeloops {

struct MembraneVoxels {
  bool found = false;
  std::string note;      // why not found
  std::vector<Id> shore;  // grid vertices, ascending: the smaller shore of the sheet through the choke
  int box_radius = 0;    // half-size in voxels of the box the sheet closed in
  bool at_saddle = false;  // the saddle alone or its level piece (MembraneShape::Saddle, LevelPiece), not a disc
};

// Sheet: the flood's contact sheet through the choke's saddle (follows a bent handle). Plane: the piece
// through the saddle of a digital plane across the line between the two seed pieces, thick enough that no
// Freudenthal edge jumps it (a straight cut; on a flat core, where the filtration order spreads the two
// zones erratically and their contact can wrap around, it still crosses the handle once).
// Saddle: the choke's saddle vertex alone (for a tunnel, with its triangle's other vertices outside: the
// triangle is in the solid only with all three), for pairs thinner than a voxel (noise), where neither closes.
// LevelPiece: the saddle with the vertices joined to it between the surface and the pair's level (a handle's
// birth <= f <= 0, a tunnel's 0 < f <= death) within a voxel of it, for noise pairs whose saddle alone is not
// enough. NearbyPinch: the vertex of the generator's side within two voxels of the saddle, nearest the surface,
// whose flip alone lowers that side's genus (its link on that side is two pieces): where a noise pair is thin at
// level 0 when its saddle is not. Saddle, LevelPiece and NearbyPinch take along the specks (at most 8 vertices)
// that hung on them only.
enum class MembraneShape { Sheet, Plane, Saddle, LevelPiece, NearbyPinch };

// The grid box (inclusive) holding every vertex of one side's region and its neighbours. A membrane's flood
// never leaves it, so a flood box clipped to it floods the same vertices in the same order: the same
// membrane, at the cost of the region rather than of the grid's padding around the shape.
struct RegionBounds {
  std::array<int, 3> lo{0, 0, 0}, hi{-1, -1, -1};  // empty: no vertex in the region
};
// Of the solid ([0], f <= 0: handles) and of the outside ([1], f > 0: tunnels), in one pass over the grid.
std::array<RegionBounds, 2> region_bounds(const ScalarGrid& grid);

// The membrane of the choke, grown in boxes (LoopOptions::box_factor, box_margin) until it closes inside one.
// `bounds`: region_bounds(grid), when the caller made them for many membranes of one grid (it must not
// have changed since); the result is the same with them or without.
MembraneVoxels membrane_voxels(const ScalarGrid& grid, const Choke& choke, const LoopOptions& options = {},
                               MembraneShape shape = MembraneShape::Sheet,
                               const std::array<RegionBounds, 2>* bounds = nullptr);

// The Sheet and Plane membranes of a choke as far as the first boxes of closing_membrane_voxels's sequence
// took them, and the box it goes on with. The loop stage floods a choke's first boxes in that sequence too
// (trace_loops can record what they gave): the label volumes then go on from there instead of flooding
// those boxes again.
struct MembraneProgress {
  Id saddle = -1;                          // the choke's; -1: nothing recorded
  std::array<MembraneVoxels, 2> membrane;  // [Sheet, Plane], each closed or not yet
  std::array<bool, 2> wanted{true, true};  // the shapes the sequence is for
  std::array<bool, 2> open{true, true};    // of those, the ones still to be closed
  int stop_at = 0;                         // the shape whose closing ends the sequence
  int radius = 0, seed_radius = 0;         // the next box's half-size and seed radius, in voxels
  int attempts = 0;                        // boxes flooded so far (a seed that touched its twin counts)
  bool done = false;                       // the sequence has ended: `membrane` is final
};

// The options the label volumes grow a choke's membrane with: the defaults, capped at membrane_box_cap(wide).
LoopOptions label_membrane_options(const ScalarGrid& grid, const Choke& choke);

// A choke thinner than half a voxel (noise): closing_membrane_voxels takes its saddle alone, before any flood.
bool thinner_than_half_a_voxel(const ScalarGrid& grid, const Choke& choke);

// The first membrane that closes: `first` (Sheet or Plane), then the other of the two. A choke thinner than
// half a voxel tries its saddle alone before both (a flood around noise would grow to the whole grid) and
// only then (unless `saddle_alone` is false). A membrane that throws counts as not closing; the last note
// says why none did. `bounds` as for membrane_voxels. `from`: where the floods of this choke's sequence (same
// options, `first`) stand already (trace_loops); the result is the same with it or without.
MembraneVoxels closing_membrane_voxels(const ScalarGrid& grid, const Choke& choke, const LoopOptions& options = {},
                                       MembraneShape first = MembraneShape::Sheet, bool saddle_alone = true,
                                       const std::array<RegionBounds, 2>* bounds = nullptr,
                                       const MembraneProgress* from = nullptr);

// The largest box half-size (voxels) a membrane of `choke` grows to where it must stay near it: a few times
// the box its depth asks for (LoopOptions::box_factor, box_margin), at least 16 voxels; `wide`: 16 times
// that box, at least 64 voxels. A sheet that closes only beyond that is not this choke's edit: on the
// grey-matter map the membranes of sub-voxel tunnels that grew past it spread over the brain or never closed.
int membrane_box_cap(const ScalarGrid& grid, const Choke& choke, const LoopOptions& options, bool wide);

// Where no membrane removes the pair alone (it joins components, opens a cavity, or does not close): the
// generator's side near the saddle thinned by simple points (a flip that changes neither side's topology),
// nearest the surface first and no deeper than the choke (|f| <= depth + half a voxel), in a box of depth + 1
// voxels around the saddle grown x2 up to 64 voxels, until a vertex of that side pinches (its link there is two
// pieces that meet elsewhere in the grid); then the flips the pinch does not need are taken back. Flipping the
// result lowers that side's genus by one and changes nothing else. `can_change` (may be empty) limits the flips.
MembraneVoxels thinned_pinch_voxels(const ScalarGrid& grid, const Choke& choke,
                                    const std::function<bool(Id)>& can_change = {});

}  // namespace chokeloops

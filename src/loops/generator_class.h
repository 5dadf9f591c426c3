#pragma once
// Private to src/loops: whether a generator's candidate loop is in its side's class, and the plane sections
// tried when the membrane gives none. A handle loop bounds in the solid, a tunnel loop in the outside; the
// cycles the generator chokes of one side close span that side's homology (linking.h), so a curve bounds
// on its side exactly when it links none of the other side's cycles.
#include <array>
#include <cstddef>
#include <vector>

#include "chokeloops/grid.h"
#include "chokeloops/loops/membranes.h"
#include "chokeloops/loops/shorten.h"
#include "chokeloops/surface/mesh_adjacency.h"
#include "chokeloops/surface/surface.h"
#include "chokeloops/topology/chokes.h"

namespace chokeloops {
class SurfaceTopology;
class SurfaceSections;
}

namespace chokeloops::detail {

// The cycle a generator's choke closes, with its bounding box.
struct SideCycle {
  Polyline3 points;
  std::array<double, 3> lo{0, 0, 0}, hi{0, 0, 0};
};

// The cycles of every generator among `chokes`, made in parallel: by_side[0] the handles', [1] the
// tunnels'; own[i] is choke i's (null when it is not a generator or its cycle cannot be made).
struct GeneratorCycles {
  std::vector<SideCycle> storage;
  std::array<std::vector<const SideCycle*>, 2> by_side;
  std::vector<const SideCycle*> own;
};
void make_generator_cycles(const ScalarGrid& grid, const std::vector<Choke>& chokes, GeneratorCycles& out);

// Index in `cycles` of the first one `curve` links, or -1 (boxes apart are skipped: they cannot link).
int linked_cycle(const Polyline3& curve, const std::vector<const SideCycle*>& cycles);

// Whether no curve of the section by the plane (p, n) can link `cycle` an odd number of times. A closed curve of
// the plane links the cycle as often as the signed count of the cycle's crossings with the plane it winds
// around; two crossings joined by a segment that meets no face are wound around by the same curves (every
// curve lies on the surface). So when each group of crossings joined that way holds an even number of them,
// every curve winds around an even number: the plane's sections need not be made (on the grey-matter map at
// 128, half the planes that reach the whole-grid radius, whose sections cost 2 ms each).
bool section_cannot_link_odd(const SurfaceSections& sections, const Polyline3& cycle, const std::array<double, 3>& p,
                             const std::array<double, 3>& n);

// Independence: loops that each bound on their side still need not be independent (two may be in one
// class). Side by side, in order of persistence, a generator loop whose row of linking numbers (mod 2) with
// its own side's cycles adds nothing to the rows before it is dropped with a note (found = false): those
// numbers pair the loops bounding in the solid perfectly with the solid's homology, so the rows of a set of
// independent loops are independent. `max_loops` bounds the work (loops times cycles linking numbers): a side
// with more found generator loops is left unchecked and false is returned for it.
bool drop_dependent_generators(std::vector<Loop>& loops, const GeneratorCycles& cycles, std::size_t max_loops = 1000);

// Whether a plane section is a loop of a generator of its side: it links `own` (when given) an odd number of
// times and none of `other_side`, and is essential on the surface; `path` is then an edge loop of its class:
// the side of its strip of `faces` when given (SurfaceSections::around), else the section snapped to edges.
bool section_bounds_on_its_side(const SurfaceMesh& surface, const MeshAdjacency& adjacency, SurfaceTopology& topology,
                                const Polyline3& section, const std::vector<const SideCycle*>& other_side, const SideCycle* own,
                                std::vector<int>& path, const std::vector<int>* faces = nullptr);

// The start of generator `c`'s loop without a membrane: the section by the plane through the choke point square
// to the choke's own cycle (where the cycle passes nearest the choke), the innermost curve round the choke at
// any radius, when it passes section_bounds_on_its_side. Across a handle resolved by the grid that plane cuts
// it as its membrane does (the loop tracer asks it only for chokes two voxels deep or more). `out_faces` gets
// the faces the section crosses in turn (SurfaceSections::around), empty where it was not followed face by face.
bool generator_plane_start(const ScalarGrid& grid, const SurfaceMesh& surface, const MeshAdjacency& adjacency,
                           SurfaceTopology& topology, const SurfaceSections& sections, const Choke& c,
                           const std::vector<const SideCycle*>& other_side, const SideCycle& own, Polyline3& out,
                           std::vector<int>& out_path,
                           std::vector<int>& out_faces);

// shorten_strip_loop on a plane start's faces (its section's, in turn: generator_plane_start) when they are
// `min_faces` or more (LoopOptions::strip_start_faces); true when its loop finished within max_move of the
// section (`out` is then the loop), false for the band search.
bool shorten_plane_start(const SurfaceMesh& surface, const MeshAdjacency& adjacency, const std::vector<int>& faces,
                         std::size_t min_faces, double max_move, ShortenResult& out);

// The loop of generator `c` found as HOLE finds a pore: the surface's sections by planes through the choke
// point in 48 directions, and by planes square to the choke's own cycle at about 40 points along it,
// that wind around their point; the shortest that is essential on the surface, links none of
// `other_side` and links `own` (when given) an odd number of times. False when none does.
bool generator_section_loop(const ScalarGrid& grid, const SurfaceMesh& surface, const MeshAdjacency& adjacency,
                            SurfaceTopology& topology, const SurfaceSections& sections, const Choke& c,
                            const std::vector<const SideCycle*>& other_side, const SideCycle* own, Polyline3& out,
                            std::vector<int>& out_path, bool debug);

}  // namespace chokeloops::detail

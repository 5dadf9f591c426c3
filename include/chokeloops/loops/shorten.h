#pragma once
// Loop shortening on the surface: moves a closed loop toward a locally shortest (geodesic) loop of its
// homotopy class without leaving a neighbourhood of where it started (DESIGN §3, paper ref. [19]).
//
// Method.
//  1. Band: the faces whose three vertices lie within `max_rings` edge rings of the loop and (when
//     max_move > 0) within surface distance max_move of it (the faces touching the loop are always in).
//     The band must be an annulus (connected, manifold, Euler characteristic 0, two boundary curves) around
//     which the loop winds once; otherwise the ring count is lowered until it is (0 rings left: the loop is
//     returned unchanged, `rings` = 0). The Euler characteristic of every ring count's band comes from one
//     pass over the candidate faces, so that counts whose band is no annulus are refused without building it.
//  2. Shortest edge loop: the band is cut along a dual path from one boundary curve to the other; an A*
//     search (Dijkstra ordered by distance plus the straight line to the target) in two sheets of the
//     band's cyclic cover, from a vertex to its lift one sheet on, gives the shortest edge loop through
//     that vertex in the loop's class that crosses the cut no more backward than forward (a shortest
//     loop across a cut that runs straight over the band does); run from the loop's first vertex and
//     `cut_samples` vertices along the cut, then from the midpoint of the best result until it stops
//     improving.
//  3. String pulling: the triangle strip around that edge loop (at each vertex, the fan on the side of
//     smaller angle) is unfolded and the shortest path through it found by the funnel algorithm, closing
//     the loop by alternating the cut portal; then wherever the loop bends around a vertex whose angle on
//     the other side is below pi, the strip is moved to that side and the funnel rerun (iterative shortest
//     path in a triangle strip). After each round of swaps the funnel is rerun only between the apexes
//     around the swapped runs (widened until the apexes next to them stay apexes), and once over the whole
//     strip at the end. Every step is a homotopy inside the band, so the class is kept.
//     Before the swaps (with `plane_sections`), the band's plane sections parallel to the funnel loop's
//     best-fit plane are measured along its normal (a line search in half-edge steps) and the strip of the
//     shortest one that winds like the loop is taken instead when its funnel is shorter: the edge loop sits
//     where the edges run best round a tube, not at its neck, and the swaps move it one vertex at a time.
//     The funnel's lengths are checked against the polyline actually built from its portal crossings (the
//     unfolded strip can overlap itself near tiny faces), and a final Gauss-Seidel pass moves each crossing
//     to the best point of its portal (the length is convex in the crossing parameters).
// The result is a closed polyline whose points lie on mesh edges (or vertices) of the band, deterministic.
// Measured: wiggly meridian of a torus (R 0.3, r 0.12, 128^3) 1.298 -> 0.7538 (2*pi*r = 0.7540) in ~0.15 s;
// the same at 256^3 (826K faces) 0.7563 in ~0.1-0.25 s; varying torus: a loop 0.5 rad from the thinnest
// section slides there (angle 3.127 vs pi, length 0.5650 vs 0.5655). Thread-safe for concurrent calls on one
// mesh and adjacency (the only state they share is a locked pool of scratch arrays, one int per vertex or
// face, that the calls borrow and give back reset). Set CHOKELOOPS_DEBUG_SHORTEN=1 for a trace on stderr.
#include <vector>

#include "chokeloops/surface/mesh_adjacency.h"
#include "chokeloops/surface/surface.h"

namespace chokeloops {

struct ShortenOptions {
  double max_move = 0;     // > 0: no point may end farther than this (along mesh edges) from the input loop
  int max_rings = 12;      // band width in edge rings around the input loop
  int max_swaps = 5000;    // limit on strip side swaps in step 3
  // Step 2 also starts from this many vertices spread along the band's cut, then descends from the best
  // loop's midpoint: the samples find a narrower section elsewhere in a wide band (with none, the varying
  // torus test's loop misses its thinnest section 0.5 rad away). Against sixteen, four left no loop longer
  // by more than 2e-4 of its length on the cage, Neptune, two fertilities, the pierced block and maltoporin
  // (one of fertility's came out 0.6% shorter), for a third of the searches.
  int cut_samples = 4;
  // Step 3 starts from the shortest nearby plane section when that is shorter (see Method): on the cage's
  // 75 handle loops the swap rounds went from 43 to 4 at the median, the loops within 2e-6 of their length.
  bool plane_sections = true;
  // Step 2's descents (the searches through the midpoint of the best loop so far, which move it by a vertex
  // or two) take only the band's vertices within this many rings of that loop; 0: the whole band. Against
  // the whole band, 6 left the cage's 127 loops identical, the grey-matter map's 1861 but one (shorter), and
  // no loop of the pierced block, fertility or Neptune longer by more than 5e-5 of its length (three of
  // fertility's up to 1.7% shorter), for a third fewer search nodes on the cage, 28% on the block.
  int descent_rings = 6;
  // > 0 (and below max_rings): the loop is first shortened in a band of this many rings, and again in the
  // band of max_rings (from the input loop) only when it comes within an edge or two of the narrow band's
  // edge or no narrow band is an annulus; the shorter of the two is returned. Most loops settle well inside
  // a few rings, and a band's cost grows with its width.
  int first_rings = 0;
};

struct ShortenResult {
  Polyline3 points;               // the shortened closed loop (last point != first)
  std::vector<int> edge_path;     // step 2's shortest edge loop (cyclic vertex list), or the input loop
  std::vector<int> strip_faces;   // the triangle strip the final loop runs through (cyclic)
  double input_length = 0, edge_path_length = 0, length = 0;
  int rings = 0;                  // band width actually used; 0 when no annulus band was found
  int swaps = 0;                  // strip side swaps performed
  // Step 2's loop comes within an edge or two of the band's edge (its last ring, or max_move): a shorter
  // loop may lie beyond the band. When false, the loop is the band's own local minimum.
  bool at_band_edge = false;
};

// `loop`: cyclic sequence of surface vertices joined by mesh edges (first vertex not repeated).
// Throws Error when the loop is not such a sequence.
ShortenResult shorten_loop(const SurfaceMesh& mesh, const MeshAdjacency& adj, const std::vector<int>& loop,
                           const ShortenOptions& options = {});
ShortenResult shorten_loop(const SurfaceMesh& mesh, const std::vector<int>& loop, const ShortenOptions& options = {});

// Frees the scratch arrays that shorten_loop keeps between calls (an int per surface vertex or face, a
// few per thread): call it after a batch of loops, so that later stages do not carry them.
void release_shortening_scratch() noexcept;

// Gives the calling thread's next shortenings of loops on `mesh` their scratch arrays ahead (an int per
// vertex or face each, filled once when made): a worker that calls it before its loops spares its first
// loops that one-time cost (15-30 MB per array on the pierced block, 5-15 ms per loop that made one).
void prepare_shortening_scratch(const SurfaceMesh& mesh);

// A closed curve given by the faces it crosses in turn (each shares an edge with the next, the last with the
// first: a plane section's faces) shortened by step 3 alone: the funnel through those faces, then at most 32
// rounds of side swaps over any faces, and the polish. Without steps 1-2 its cost follows the strip, not a
// band round it (a 2,000-face plane section of the pierced block: 0.2 ms and 0.1 ms a round, against 10-15 ms
// for the band search); the loop is the local minimum the swaps reach from the curve, not a band's shortest.
// `at_band_edge` is set when the loop was still shortening after those rounds, or (max_move > 0) ended
// farther than max_move from the funnel's loop: shorten_loop from an edge path of the curve then searches a
// band at once. Only max_move and max_swaps apply; `rings` is 1, `input_length` the funnel's length, and
// `edge_path` the shorter simple side of the final strip (strip_side_loop). Throws Error when the faces are
// fewer than three, out of range, or not joined by shared edges in turn.
ShortenResult shorten_strip_loop(const SurfaceMesh& mesh, const MeshAdjacency& adj, const std::vector<int>& faces,
                                 const ShortenOptions& options = {});

// The shorter of the two edge loops along the sides of a closed strip of faces (as shorten_strip_loop takes):
// the ends of the edges it crosses on one side, in turn, an edge loop of the strip's class. Empty when neither
// visits each vertex once, or the faces do not form a strip.
std::vector<int> strip_side_loop(const SurfaceMesh& mesh, const MeshAdjacency& adj, const std::vector<int>& faces);

// A closed polyline on the surface is first snapped to an edge loop (snap_polyline_to_edge_path), then
// shortened; max_move is measured from the snapped loop.
ShortenResult shorten_polyline(const SurfaceMesh& mesh, const MeshAdjacency& adj, const Polyline3& polyline,
                               const ShortenOptions& options = {});

}  // namespace chokeloops

#pragma once
// Internals of shorten_loop and shorten_strip_loop shared by their files: the ring region around the loop
// (shorten_region.cpp), the annulus band in it, the Shortener that holds the band (steps 1-2 in
// shorten_band.cpp, step 3 in shorten_strip.cpp, shorten_swaps.cpp and shorten_section.cpp; the entry from a
// strip in shorten_from_strip.cpp) and the small 3D helpers and the heap they use.
#include <array>
#include <atomic>
#include <cmath>
#include <limits>
#include <memory>
#include <vector>

#include "chokeloops/surface/mesh_adjacency.h"
#include "chokeloops/surface/surface.h"
#include "dense_int_map.h"
#include "flat_int_map.h"

namespace chokeloops::shorten_detail {

using P3 = std::array<double, 3>;

inline double dist3(const P3& a, const P3& b) {
  return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}
inline double dist3_squared(const P3& a, const P3& b) {
  return (a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]);
}
inline P3 lerp3(const P3& a, const P3& b, double s) { return {a[0] + s * (b[0] - a[0]), a[1] + s * (b[1] - a[1]), a[2] + s * (b[2] - a[2])}; }
inline double angle3(const P3& v, const P3& a, const P3& b) {  // angle at v between v->a and v->b
  P3 u{a[0] - v[0], a[1] - v[1], a[2] - v[2]}, w{b[0] - v[0], b[1] - v[1], b[2] - v[2]};
  P3 c{u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
  double cn = std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
  return std::atan2(cn, u[0] * w[0] + u[1] * w[1] + u[2] * w[2]);
}
// x mod m for 0 <= x < 3m, without a division: the strip's loops take an index round the strip at every
// portal, and `% m` with m known only at run time is a division (the swap rounds ~7% faster without them).
inline int wrap(int x, int m) {
  if (x >= m) x -= m;
  if (x >= m) x -= m;
  return x;
}
// A 4-ary min-heap of (distance, node), popped in the order of that pair as std::priority_queue with
// std::greater pops it (so the search relaxes in the same order): shallower than a binary heap, and its
// storage is the caller's (the searches and the band's surface distances keep theirs per thread).
struct QueueEntry { double d; int node; };
inline bool pops_before(const QueueEntry& a, const QueueEntry& b) { return a.d < b.d || (a.d == b.d && a.node < b.node); }
inline void heap_push(std::vector<QueueEntry>& h, QueueEntry e) {
  std::size_t i = h.size();
  h.push_back(e);
  while (i > 0) {
    const std::size_t parent = (i - 1) / 4;
    if (!pops_before(e, h[parent])) break;
    h[i] = h[parent];
    i = parent;
  }
  h[i] = e;
}
inline QueueEntry heap_pop(std::vector<QueueEntry>& h) {
  const QueueEntry top = h[0], last = h.back();
  h.pop_back();
  const std::size_t n = h.size();
  if (n == 0) return top;
  std::size_t i = 0;
  for (;;) {
    const std::size_t first = 4 * i + 1;
    if (first >= n) break;
    std::size_t best = first;
    for (std::size_t c = first + 1; c < std::min(first + 4, n); ++c)
      if (pops_before(h[c], h[best])) best = c;
    if (!pops_before(h[best], last)) break;
    h[i] = h[best];
    i = best;
  }
  h[i] = last;
  return top;
}
// The index of v among face f's corners (2 when v is not the first or second).
inline int corner_of(const SurfaceMesh& mesh, int f, int v) {
  const auto& t = mesh.faces[std::size_t(f)];
  return t[0] == v ? 0 : t[1] == v ? 1 : 2;
}
// The angle of face f at its corner v.
inline double angle_at_corner(const SurfaceMesh& mesh, int f, int v) {
  const auto& t = mesh.faces[std::size_t(f)];
  const int k = corner_of(mesh, f, v);
  return angle3(mesh.vertices[std::size_t(v)], mesh.vertices[std::size_t(t[std::size_t((k + 1) % 3)])],
                mesh.vertices[std::size_t(t[std::size_t((k + 2) % 3)])]);
}

// Everything about the annulus band around the loop.
struct Band {
  detail::DenseIntMap in_face;      // mesh face -> its place in `faces`
  std::vector<int> faces;
  detail::DenseIntMap local;        // mesh vertex -> band vertex
  std::vector<int> global;          // band vertex -> mesh vertex
  detail::FlatIntMap sign;          // cut crossing sign per mesh half-edge (the cut's few edges)
  // Per band half-edge 3 * place + k (edge k -> k+1 of faces[place]): the band vertex at its source, the
  // mesh half-edge across it when that one's face is in the band (else -1), and its cut crossing sign.
  // Built once with the band, so that the band's own passes read small arrays, not mesh-sized maps.
  std::vector<int> corner, twin_in_band;
  std::vector<signed char> crossing_sign;
  int corner_to(std::size_t hl) const { return corner[std::size_t(MeshAdjacency::next(int(hl)))]; }  // its target
  int winding = 0;                  // of the input loop
  std::vector<int> cut_vertices;    // band vertices at one end of each crossed edge, along the cut
};

// The vertices within `max_rings` edge rings of a loop (mesh vertices), in BFS order from the loop's own: each
// one's ring, an upper bound of its surface distance from the loop (the BFS tree's path, shortened through
// every region neighbour met later, in one pass), and their exact surface distances on demand. It keeps
// references to the mesh, the adjacency and the loop; with keep_arcs it holds about 100 bytes per vertex,
// up to max_arcs arcs (16 bytes each), beyond which it drops them and the distances read the mesh.
struct RingRegion {
  RingRegion(const SurfaceMesh& mesh, const MeshAdjacency& adj, const std::vector<int>& loop, int max_rings,
             bool keep_arcs, std::size_t max_arcs = std::size_t(1) << 22);
  // dist[i]: the length of the shortest edge path from the loop to vertices[i] through the region, for every
  // vertex within max_move; farther vertices get a larger value or infinity (the same numbers with the arcs
  // kept or read from the mesh).
  void surface_distances(double max_move, std::vector<double>& dist) const;
  // Whether the arcs were kept (keep_arcs, and no more than max_arcs of them).
  bool kept_arcs() const { return !arcs_from_.empty(); }

  detail::DenseIntMap index;  // mesh vertex -> its place in `vertices`
  std::vector<int> vertices, ring;
  std::vector<double> upper;
  double upper_max = 0;

 private:
  const SurfaceMesh& mesh_;
  const MeshAdjacency& adj_;
  const std::vector<int>& loop_;
  int max_rings_;
  // The arcs the BFS read (region index and length) of each vertex it expanded, [arcs_from[i], arcs_from[i + 1]):
  // the distances walk them again without the mesh's scattered arrays (a second read of them was 8.6% of the
  // grey-matter map's run in perf, against 3.9% for the BFS).
  // Owned by the region, not a thread's: a region lives across the searches' parallel_for, where its thread
  // may take up another loop's shortening. Grown without clearing (a vector's resize wrote every arc twice).
  struct Arc { double len; int to; };
  std::unique_ptr<Arc[]> arcs_;
  std::size_t arcs_capacity_ = 0;
  std::vector<int> arcs_from_;
};

// The faces a band around the loop may take, each with the first ring count k at which it enters: all three
// vertices allowed, or (a face touching the loop) each vertex allowed or next to the loop and one of them
// allowed. A vertex region[i] is allowed from k = entry[i] on (above max_k: never); near[i] is 2 on the
// loop, 1 one ring away. `euler[k]` is V - E + F of the band of k rings, for every k in 0..max_k: a ring
// count whose band is not an annulus (not 0) is refused without building it.
struct BandCandidates {
  std::vector<int> faces;   // rising
  std::vector<int> entry;   // per face
  std::vector<long> euler;  // per ring count
};
BandCandidates band_candidates(const SurfaceMesh& mesh, const MeshAdjacency& adj, const std::vector<int>& region,
                               const detail::DenseIntMap& rid, const std::vector<int>& entry,
                               const std::vector<char>& near, int max_k);

struct Shortener {
  const SurfaceMesh& mesh;
  const MeshAdjacency& adj;
  Band band;

  Shortener(const SurfaceMesh& m, const MeshAdjacency& a) : mesh(m), adj(a) {}

  int vert(int h) const { return mesh.faces[h / 3][h % 3]; }          // source of half-edge h
  int vert_to(int h) const { return mesh.faces[h / 3][(h % 3 + 1) % 3]; }
  // Every face is in when there is no band (shorten_strip_loop's swaps).
  bool whole_mesh = false;
  bool face_in(int f) const { return f >= 0 && (whole_mesh || band.in_face.contains(f)); }
  int local_of(int v) const {
    const int* l = band.local.find(v);
    return l ? *l : -1;
  }
  int hsign(int h) const {
    const int* s = band.sign.find(h);
    return s ? *s : 0;
  }
  // Half-edge a->b in any face, or -1 - (half-edge b->a) when only the reverse exists.
  int signed_edge_sign(int a, int b) const {
    int h = adj.halfedge(mesh, a, b);
    if (h >= 0) return hsign(h);
    int r = adj.halfedge(mesh, b, a);
    return r >= 0 ? -hsign(r) : 0;
  }
  bool contains(int f, int v) const { auto& t = mesh.faces[f]; return t[0] == v || t[1] == v || t[2] == v; }

  // ---- Step 1: band (shorten_band.cpp) -----------------------------------------------------------
  // Builds the band of the candidates' faces that enter within `rings` rings and checks that it is an
  // annulus; sets the cut and the input loop's winding across it.
  bool build_band(const BandCandidates& candidates, int rings, const std::vector<int>& loop);

  // ---- Step 2: shortest edge loop in the band (shorten_band.cpp) ---------------------------------
  struct Arc { double len; int to; int sign; };  // 16 bytes: the search reads them in runs
  std::vector<int> arc_start;
  std::vector<Arc> arcs;
  std::vector<P3> position;  // per band vertex: the search's lower bound, the plane sections
  void build_arcs();
  // Shortest loop through band vertex s winding `band.winding` times; returns mesh vertices, in the
  // input loop's direction. `backward`: search the loop the other way round (the same loops; the search
  // takes fewer nodes when the cut lies a short way ahead of s, see cut_is_near_ahead).
  // `below`: only a loop shorter than this is wanted (none found: empty, length infinite); the search then
  // leaves out the nodes that cannot lie on one.
  // `within` (per band vertex, may be null): the search takes only the vertices marked there.
  std::vector<int> shortest_loop_through(int s, double& length, bool backward = false,
                                         double below = std::numeric_limits<double>::infinity(),
                                         const std::vector<char>* within = nullptr) const;
  // Marks (per band vertex) the vertices within `rings` arcs of the band vertices of `loop` (mesh vertices):
  // where a descent's search may go (ShortenOptions::descent_rings).
  void mark_near(const std::vector<int>& loop, int rings, std::vector<char>& marks) const;
  // Whether, walking `loop` (mesh vertices, through band vertex s) on from s in its own direction, the
  // first crossing of the cut comes before half the loop's length.
  bool cut_is_near_ahead(const std::vector<int>& loop, int s) const;
  // Nodes the searches took (CHOKELOOPS_DEBUG_SHORTEN prints them): the searches of one call run in
  // parallel, hence atomic.
  mutable std::atomic<long> search_nodes{0};

  // ---- Step 3: strip and funnel (shorten_strip.cpp) ----------------------------------------------
  // Fan of faces around path vertex p (from in-edge a->p to out-edge p->b), on the left or the right.
  bool fan(int a, int p, int b, bool left, std::vector<int>& out, double& angle) const;
  bool strip_from_edge_loop(const std::vector<int>& P, std::vector<int>& S) const;
  // Portal j: half-edge (in S[j+1]) whose twin lies in S[j]; left = its source, right = its target.
  // True when every consecutive pair of S (round the strip) shares a portal; with `ranges`, only the
  // portals j in each [first, last] (a strip known whole but for the runs a swap batch put in).
  bool portals_ok(const std::vector<int>& S, const std::vector<std::array<int, 2>>* ranges = nullptr) const;
  int portal_of(int f, int g) const;
  // The winding of the loop through strip S across the band's cut (0 when S is not a strip).
  int strip_winding(const std::vector<int>& S) const;
  // The strip of the band's faces that the plane through `point` square to `normal` cuts in its shortest
  // closed section winding once like the input loop, in the input loop's direction (shorten_section.cpp);
  // returns that section's length (infinite and S empty when there is none).
  double shortest_plane_section(const P3& point, const P3& normal, std::vector<int>& S) const;
  // The strip of the shortest of the band's plane sections parallel to the best-fit plane of `loop`, offset
  // along its normal by multiples of `step` (at most max_steps): false when none winds like the loop.
  bool strip_from_nearby_sections(const Polyline3& loop, double step, int max_steps, std::vector<int>& S) const;

  // Funnel through the strip cut at portal c with the loop crossing it at parameter s_c. Fills s (per
  // portal) and the apex list (portal index, mesh vertex), in order along the loop from c. Returns the length.
  struct Apex { int portal; int vertex; };
  double funnel(const std::vector<int>& S, int c, std::vector<double>& s, std::vector<Apex>& apexes);
  // The funnel from the crossing s_from of portal `from` to the crossing s_to of portal from + count
  // (cyclic) through the faces between them: sets s of the portals strictly between and appends their
  // apexes, in order. count = S.size() with s_to = s_from is the closed loop cut at `from`.
  // `end_angle`, when given, receives for a closed loop (s_from = s_to) the angle at the held crossing
  // between the loop's last and first segments, on the side of the portal's left end (its right end when
  // held at the left end): pi where the loop runs straight through; `plane_length` the length of the path
  // in the plane of the unfolding; `loop_length`, for the closed loop, that of the polyline through its
  // crossings (params_length).
  void funnel_segment(const std::vector<int>& S, int from, int count, double s_from, double s_to, std::vector<double>& s,
                      std::vector<Apex>& apexes, double* end_angle = nullptr, double* plane_length = nullptr,
                      double* loop_length = nullptr);
  // After swaps, the funnel again only where the strip changed: `dirty` lists portal ranges [first, last]
  // whose inner crossings are unknown; `apexes` (the old ones outside those ranges, in portal order)
  // anchor each range's funnel between the apexes around it, widened until the apexes next to the range
  // stay apexes (then the path outside is still the shortest, see shorten_strip.cpp). Falls back to
  // funnel_through_apex() when a window would cover the loop. Returns the length.
  double refunnel(const std::vector<int>& S, std::vector<double>& s, std::vector<Apex>& apexes,
                  const std::vector<std::array<int, 2>>& dirty);
  int refunnel_windows = 0, refunnel_fallbacks = 0;  // how refunnel went, for the tests

  P3 crossing(const std::vector<int>& S, const std::vector<double>& s, int j) const;
  double params_length(const std::vector<int>& S, const std::vector<double>& s) const;
  // Gauss-Seidel on the crossing parameters: each crossing moves to the point of its portal that is
  // closest to its neighbours (unfolding the two faces around the portal). The length is a convex
  // function of the parameters, so this only polishes what the funnel left.
  double polish(const std::vector<int>& S, std::vector<double>& s, int sweeps) const;
  Polyline3 strip_points(const std::vector<int>& S, const std::vector<double>& s) const;
  // Alternate the cut portal until the length stops decreasing.
  double relax(const std::vector<int>& S, int c, std::vector<double>& s, std::vector<Apex>& apexes);
  // The funnel round the whole strip held at the apex farthest from the `dirty` ranges (none left: at the
  // portal farthest from them, then at the apex that funnel found farthest from its cut), kept when the
  // loop does not pull off the held point and its polyline is as long as its path in the plane; else
  // relax(). Returns the length.
  double funnel_through_apex(const std::vector<int>& S, std::vector<double>& s, std::vector<Apex>& apexes,
                             const std::vector<std::array<int, 2>>& dirty);
  int apex_funnels = 0, apex_funnels_relaxed = 0;  // how funnel_through_apex went, for the trace and tests

  // ---- Step 3: side swaps (shorten_swaps.cpp) ----------------------------------------------------
  // Faces around v from f_a the other way round to f_b (f_a and f_b included, so at least two), appended to
  // `run`; false (and `run` as it was) when there is no such fan in the band.
  bool other_fan(int v, int fa, int fb, int fa_next, std::vector<int>& run) const;
  // The angle of band face f at its corner v; kept once computed, as total_angle is (the swap rounds measure
  // the same apexes' runs again and again, an arctangent each).
  double corner_angle(int f, int v) const;
  mutable std::vector<double> corner_angle_of;  // per band face corner, negative until asked; reset with the band
  // The sum of v's face angles; a band vertex's is kept (the swap rounds ask for the same apexes' sums
  // again and again, six arctangents each).
  double total_angle(int v) const;
  mutable std::vector<double> total_angle_of;  // per band vertex, negative until asked; reset with the band
  double sum_of_angles(int v) const;
  bool interior_vertex(int v) const;

  // Side swaps at every apex whose angle on the far side is below pi, for non-overlapping runs at once
  // (smallest far-side angle first). Returns the number of swaps made. Gives the apexes that the swaps left
  // in place, renumbered for the new strip and in portal order, and the portal ranges whose crossings the
  // swaps made unknown (for refunnel).
  int swap_batch(std::vector<int>& S, std::vector<double>& s, const std::vector<Apex>& apexes, int limit,
                 std::vector<Apex>& kept, std::vector<std::array<int, 2>>& dirty);
  // Rounds of swap_batch, each refunnelled where it changed, while the loop shortens (at most max_swaps swaps
  // in all), then one funnel over the whole strip when any swap was made. Takes the
  // relaxed strip and its length; returns the new length and adds to `swaps` and `rounds`.
  // `max_rounds`: a loop still shortening after that many rounds stops there and sets `unfinished`.
  double swap_rounds(std::vector<int>& S, std::vector<double>& s, std::vector<Apex>& apexes, double length, int max_swaps,
                     int& swaps, int& rounds, bool debug, int max_rounds = 400, bool* unfinished = nullptr);
};

}  // namespace chokeloops::shorten_detail

// Loop shortening on the surface (shorten.h): checks the input loop and drives the three steps, widest
// annulus band first, then the shortest edge loop, then the funnel with side swaps and polishing.
#include "chokeloops/loops/shorten.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <utility>

#include <tbb/parallel_for.h>

#include "chokeloops/surface/topology.h"
#include "shortener.h"

namespace chokeloops {

using shorten_detail::dist3;
using shorten_detail::Shortener;

namespace {
// The plane sections' line search goes at most this many steps from the edge loop's plane (64 half edges:
// well past a 12-ring band, where no section closes).
constexpr int kMaxSectionSteps = 64;

// With CHOKELOOPS_DEBUG_SHORTEN=1 each call that reaches the funnel also prints how long its steps took, so
// that where the shortening goes can be summed over a run (bands, searches, swaps, ...).
struct StepClock {
  enum Step { kRegion, kCandidates, kBands, kArcs, kSearches, kSwaps, kPolish, kSteps };
  bool on;
  std::chrono::steady_clock::time_point last = std::chrono::steady_clock::now();
  std::array<double, kSteps> ms{};
  explicit StepClock(bool enabled) : on(enabled) {}
  void lap(Step step) {
    if (!on) return;
    const auto now = std::chrono::steady_clock::now();
    ms[step] += std::chrono::duration<double, std::milli>(now - last).count();
    last = now;
  }
};

// A call's result with the band it came from: a later call on the same loop whose band is the same face
// for face would compute the same result from step 2 on.
struct BandResult {
  ShortenResult result;
  std::vector<int> band_faces;  // sorted; empty when no band was built
  bool searched = false;        // step 2 found an edge loop (else the result is the input loop)
};

// shorten_loop within a band of at most opt.max_rings rings. `earlier`: a call on the same loop with other
// options; where this call's band is its band, steps 2 and 3 are its, and only what depends on this call's
// rings and distances (whether the loop is at the band's edge) is computed again. `record`: where this call's
// band and whether it searched are kept, for a later call (its `result` is left to the caller).
ShortenResult shorten_in_band(const SurfaceMesh& mesh, const MeshAdjacency& adj, const std::vector<int>& loop,
                              const ShortenOptions& opt, const BandResult* earlier = nullptr, BandResult* record = nullptr) {
  ShortenResult R;
  if (loop.empty()) throw Error("loop is empty");
  for (size_t i = 0; i < loop.size(); ++i) {
    int a = loop[i], b = loop[(i + 1) % loop.size()];
    if (a < 0 || b < 0 || size_t(a) >= mesh.vertices.size() || size_t(b) >= mesh.vertices.size())
      throw Error("loop vertex index out of range");
    if (loop.size() > 1 && !adj.has_edge(mesh, a, b)) throw Error("loop vertices are not joined by a mesh edge");
  }
  R.edge_path = loop;
  R.points = loop_points(mesh, loop);
  R.input_length = R.edge_path_length = R.length = closed_length(R.points);
  if (loop.size() < 3) return R;

  const bool debug = std::getenv("CHOKELOOPS_DEBUG_SHORTEN") != nullptr;
  StepClock clock(debug);
  // Rings (BFS hops) and surface distance (Dijkstra along edges) from the loop, both bounded; all per-vertex
  // data lives on this region so that the cost follows the band, not the mesh.
  const int max_rings = std::max(1, opt.max_rings);
  const bool distances = opt.max_move > 0;
  shorten_detail::RingRegion rr(mesh, adj, loop, max_rings, distances);
  const detail::DenseIntMap& rid = rr.index;
  const std::vector<int>& region = rr.vertices;
  const std::vector<int>& ring = rr.ring;
  const std::vector<double>& upper = rr.upper;
  std::vector<double> dist;
  auto compute_distances = [&] { rr.surface_distances(opt.max_move, dist); };
  // When no vertex's upper bound exceeds max_move, the distances cannot limit the band and are not computed.
  if (distances && rr.upper_max > opt.max_move) compute_distances();
  std::vector<char> near_loop(region.size(), 0);
  for (size_t i = 0; i < region.size(); ++i)
    if (ring[i] <= 1) near_loop[i] = ring[i] == 0 ? 2 : 1;

  clock.lap(StepClock::kRegion);
  Shortener sh(mesh, adj);
  std::vector<int> entry(region.size());
  for (size_t i = 0; i < region.size(); ++i)
    entry[i] = dist.empty() || dist[i] <= opt.max_move ? ring[i] : max_rings + 1;
  // Most ring counts the search below tries on a bumpy surface give a band that wraps round or swallows a
  // handle; their Euler characteristic, known for every count at once, refuses them without building the
  // band, and every band is taken from the one list of candidate faces.
  const shorten_detail::BandCandidates candidates =
      shorten_detail::band_candidates(mesh, adj, region, rid, entry, near_loop, max_rings);
  clock.lap(StepClock::kCandidates);
  auto try_rings = [&](int k) {
    return candidates.euler[std::size_t(k)] == 0 && sh.build_band(candidates, k, loop);
  };
  // The widest annulus band: max_rings, else halve until one works, then bisect between that and the
  // last failure (wider bands stop being annuli when they wrap around or swallow a handle).
  int rings = 0;
  if (try_rings(max_rings)) {
    rings = max_rings;
  } else {
    int bad = max_rings, good = 0;
    for (int k = max_rings / 2; k >= 1; k /= 2) {
      if (try_rings(k)) { good = k; break; }
      bad = k;
    }
    if (good) {
      while (bad - good > 1) {
        int mid = (good + bad) / 2;
        if (try_rings(mid)) good = mid; else bad = mid;
      }
      if (!try_rings(good)) good = 0;  // leave the band of `good` rings built
    }
    rings = good;
  }
  R.rings = rings;
  if (!rings) return R;
  // The test above builds each band it tries; the last one built is the band of `rings` rings.
  if (record) record->band_faces.assign(sh.band.faces.begin(), sh.band.faces.end());
  // Step 2's loop is at the band's edge when a vertex of it lies in the band's last ring, or within two of
  // its edges of max_move from the input loop.
  const auto at_band_edge = [&](const std::vector<int>& path, double path_length) {
    const double edge = path_length / double(path.size());  // the loop's mean edge length
    double path_upper = 0;
    for (int v : path) path_upper = std::max(path_upper, upper[std::size_t(rid.at(v))]);
    if (distances && dist.empty() && path_upper > opt.max_move - 2 * edge) compute_distances();
    for (int v : path) {
      const std::size_t i = std::size_t(rid.at(v));
      if (ring[i] >= rings - 1 || (!dist.empty() && dist[i] > opt.max_move - 2 * edge)) return true;
    }
    return false;
  };
  if (earlier && earlier->result.rings == rings && earlier->band_faces == sh.band.faces) {
    // The widened band came out as the narrow one (on the grey-matter map 1,656 of 1,754 widenings: the
    // wider bands wrap round or swallow a handle): the same band gives the same loop.
    ShortenResult same = earlier->result;
    if (earlier->searched) same.at_band_edge = at_band_edge(same.edge_path, same.edge_path_length);
    if (debug) std::fprintf(stderr, "band of %d rings as before: its loop again\n", rings);
    return same;
  }

  // Step 2.
  clock.lap(StepClock::kBands);
  sh.build_arcs();
  clock.lap(StepClock::kArcs);
  // Every loop of the class crosses the cut, so loops through vertices sampled along the cut (which runs
  // across the band) find the best place in the band; then loops through the midpoint of the best one.
  std::vector<int> best;
  double best_len = std::numeric_limits<double>::infinity();
  int s = sh.local_of(loop[0]);
  {
    std::vector<int> starts{s};
    const auto& cv = sh.band.cut_vertices;
    const int samples = std::max(0, opt.cut_samples);
    for (int i = 0; i < samples && !cv.empty(); ++i) starts.push_back(cv[size_t(i) * cv.size() / samples]);
    std::sort(starts.begin() + 1, starts.end());
    starts.erase(std::unique(starts.begin() + 1, starts.end()), starts.end());
    // The searches are independent (they only read the band): run them in parallel, then pick in the
    // sequential order, so the choice does not depend on the thread count.
    std::vector<std::vector<int>> paths(starts.size());
    std::vector<double> lengths(starts.size(), std::numeric_limits<double>::infinity());
    tbb::parallel_for(std::size_t(0), starts.size(), [&](std::size_t i) {
      if (starts[i] < 0) return;
      const bool backward = i == 0 && sh.cut_is_near_ahead(loop, starts[i]);  // the cut samples lie on it
      paths[i] = sh.shortest_loop_through(starts[i], lengths[i], backward);
    });
    for (std::size_t i = 0; i < starts.size(); ++i)
      if (!paths[i].empty() && lengths[i] < best_len - 1e-12) best = paths[i], best_len = lengths[i], s = starts[i];
    if (!best.empty()) {
      double acc = 0;
      for (size_t i = 0; i + 1 < best.size(); ++i) {
        acc += dist3(mesh.vertices[best[i]], mesh.vertices[best[i + 1]]);
        if (acc >= best_len / 2) { s = sh.local_of(best[i + 1]); break; }
      }
    }
  }
  int descents = 0;
  // The first searches place the loop in the band; a descent moves it by a vertex or two, so it searches
  // only near the best loop so far (each took the whole band, two thirds of the searches' nodes on the cage).
  const int descent_rings = std::max(0, opt.descent_rings);
  std::vector<char> near_best;
  for (int it = 0; it < 16 && s >= 0; ++it) {
    double L;
    ++descents;
    const double wanted = best_len - 1e-12;  // a descent only takes a shorter loop; the search knows it
    const bool near_only = descent_rings > 0 && !best.empty();
    if (near_only) sh.mark_near(best, descent_rings, near_best);
    auto P = sh.shortest_loop_through(s, L, !best.empty() && sh.cut_is_near_ahead(best, s), wanted, near_only ? &near_best : nullptr);
    if (P.empty() || !(L < wanted)) break;
    best = P, best_len = L;
    double acc = 0;  // next start: the vertex at half the length
    int mid = best[0];
    for (size_t i = 0; i + 1 < best.size(); ++i) {
      acc += dist3(mesh.vertices[best[i]], mesh.vertices[best[i + 1]]);
      if (acc >= best_len / 2) { mid = best[i + 1]; break; }
    }
    s = sh.local_of(mid);
  }
  if (best.empty()) return R;
  if (record) record->searched = true;
  R.edge_path = best;
  R.edge_path_length = best_len;
  R.at_band_edge = at_band_edge(best, best_len);
  R.points = loop_points(mesh, best);
  R.length = closed_length(R.points);

  // Step 3.
  clock.lap(StepClock::kSearches);
  std::vector<int> S;
  if (!sh.strip_from_edge_loop(best, S)) {
    if (debug) std::fprintf(stderr, "no triangle strip around the edge loop\n");
    return R;
  }
  std::vector<double> sp(S.size(), 0.5);
  std::vector<Shortener::Apex> apexes;
  double L = sh.relax(S, 0, sp, apexes);
  if (opt.plane_sections) {
    // Steps of half the edge loop's mean edge: the sections' lengths vary smoothly at that scale (the
    // cage's necks lie 4 to 8 such steps from their edge loop's plane), coarser steps found the same loops.
    const double step = 0.5 * R.length / double(best.size());
    std::vector<int> S3;
    if (sh.strip_from_nearby_sections(sh.strip_points(S, sp), step, kMaxSectionSteps, S3)) {
      std::vector<double> s3(S3.size(), 0.5);
      std::vector<Shortener::Apex> a3;
      const double L3 = sh.relax(S3, 0, s3, a3);
      if (debug) std::fprintf(stderr, "plane section: strip %zu faces, relaxed %.9f (edge loop's strip %.9f)\n", S3.size(), L3, L);
      if (L3 < L) L = L3, S.swap(S3), sp.swap(s3), apexes.swap(a3);
    } else if (debug) {
      std::fprintf(stderr, "plane section: none winds like the loop\n");
    }
  }
  int rounds = 0;
  L = sh.swap_rounds(S, sp, apexes, L, opt.max_swaps, R.swaps, rounds, debug);
  clock.lap(StepClock::kSwaps);
  sh.polish(S, sp, 200);
  auto pts = sh.strip_points(S, sp);
  double Lp = closed_length(pts);
  clock.lap(StepClock::kPolish);
  if (debug) {
    std::fprintf(stderr, "edge loop %.9f (%zu vertices; input %.9f, %zu vertices%s), strip %zu faces, relaxed %.9f, polished %.9f; band %zu vertices, %d rings, %d descents\n", R.length,
                 best.size(), R.input_length, loop.size(), R.at_band_edge ? ", at band edge" : "", S.size(), L, Lp, sh.band.global.size(), rings, descents);
    const auto& t = clock.ms;
    std::fprintf(stderr,
                 "shorten steps ms: region %.3f candidates %.3f bands %.3f arcs %.3f searches %.3f swaps %.3f (%d rounds) "
                 "polish %.3f; %ld search nodes, %d refunnel windows, %d fallbacks, %d apex funnels (%d relaxed)\n",
                 t[0], t[1], t[2], t[3], t[4], t[5], rounds, t[6], sh.search_nodes.load(), sh.refunnel_windows,
                 sh.refunnel_fallbacks, sh.apex_funnels, sh.apex_funnels_relaxed);
  }
  if (pts.size() >= 3 && Lp <= R.length) {
    R.points = pts;
    R.length = Lp;
    R.strip_faces = S;
  }
  return R;
}

}  // namespace

ShortenResult shorten_loop(const SurfaceMesh& mesh, const MeshAdjacency& adj, const std::vector<int>& loop,
                           const ShortenOptions& opt) {
  if (opt.first_rings <= 0 || opt.first_rings >= opt.max_rings) return shorten_in_band(mesh, adj, loop, opt);
  ShortenOptions narrow = opt;
  narrow.max_rings = opt.first_rings;
  BandResult narrow_result;
  narrow_result.result = shorten_in_band(mesh, adj, loop, narrow, nullptr, &narrow_result);
  const ShortenResult& first = narrow_result.result;
  if (first.rings > 0 && !first.at_band_edge) return first;
  // The wide band starts from the input loop again, so that max_move keeps its meaning; of two loops
  // in the class, the shorter.
  ShortenResult wide = shorten_in_band(mesh, adj, loop, opt, first.rings > 0 ? &narrow_result : nullptr);
  if (std::getenv("CHOKELOOPS_DEBUG_SHORTEN"))
    std::fprintf(stderr, "widened band: %d rings %.9f (at its edge: %d), %d rings %.9f\n", first.rings, first.length,
                 int(first.at_band_edge), wide.rings, wide.length);
  if (first.rings > 0 && !(wide.rings > 0 && wide.length <= first.length)) return first;
  return wide;
}

void release_shortening_scratch() noexcept { detail::DenseIntMap::release_pool(); }

void prepare_shortening_scratch(const SurfaceMesh& mesh) {
  // A shortening holds four maps at most at once (the ring region's, the band candidates', the band's two),
  // over the faces or the vertices: four of the larger size, made and given back, wait in the pool for any.
  const std::size_t keys = std::max(mesh.faces.size(), mesh.vertices.size());
  detail::DenseIntMap a(keys), b(keys), c(keys), d(keys);
}

ShortenResult shorten_loop(const SurfaceMesh& mesh, const std::vector<int>& loop, const ShortenOptions& options) {
  auto adj = build_adjacency(mesh);
  return shorten_loop(mesh, adj, loop, options);
}

ShortenResult shorten_polyline(const SurfaceMesh& mesh, const MeshAdjacency& adj, const Polyline3& polyline,
                               const ShortenOptions& options) {
  auto loop = snap_polyline_to_edge_path(mesh, adj, polyline);
  return shorten_loop(mesh, adj, loop, options);
}

}  // namespace chokeloops

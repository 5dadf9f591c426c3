// Loop shortening on the surface (shorten.h): checks the input loop and drives the three steps, widest
// annulus band first, then the shortest edge loop, then the funnel with side swaps and polishing.
#include "chokeloops/loops/shorten.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <limits>
#include <queue>
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

// shorten_loop within a band of at most opt.max_rings rings.
ShortenResult shorten_in_band(const SurfaceMesh& mesh, const MeshAdjacency& adj, const std::vector<int>& loop,
                              const ShortenOptions& opt) {
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
  detail::DenseIntMap rid(mesh.vertices.size());
  std::vector<int> region, ring;
  // Each vertex's distance along some path from the loop bounds its surface distance from above: when no
  // bound exceeds max_move, the distances cannot limit the band and the Dijkstra is not run. The bound is
  // the BFS tree's path, shortened through every region neighbour met later (one pass, BFS order): with
  // the tree's path alone half the cage's handle loops ran the Dijkstra for the band and the rest for the
  // band-edge test, 7% of their time.
  std::vector<double> upper;
  // The arcs the BFS reads (region index and length, per vertex it expands, in region order): the surface
  // distances below walk them again, without the mesh's scattered arrays (the Dijkstra read them a second
  // time, 8.6% of the grey-matter map's run in perf against 3.9% for the BFS).
  const bool distances = opt.max_move > 0;
  struct RegionArc { double len; int to; };
  thread_local std::vector<RegionArc> region_arcs;
  thread_local std::vector<int> arcs_from;  // region_arcs of region[i]: [arcs_from[i], arcs_from[i + 1])
  arcs_from.clear();
  std::size_t arc_count = 0;  // region_arcs is only grown (written through a pointer: the BFS's inner loop)
  // A band of k rings round a loop of n vertices holds about (2k + 1) n of them: grown once, not a dozen times.
  const std::size_t expected = loop.size() * std::size_t(2 * max_rings + 2);
  region.reserve(expected), ring.reserve(expected), upper.reserve(expected);
  for (int v : loop)
    if (rid.emplace(v, int(region.size()))) region.push_back(v), ring.push_back(0), upper.push_back(0);
  for (size_t i = 0; i < region.size(); ++i) {
    const int v = region[i];
    if (distances) arcs_from.push_back(int(arc_count));
    if (ring[i] >= max_rings) continue;
    // At most two neighbours per corner of v (MeshAdjacency::for_each_neighbour), a corner per face.
    const std::size_t most = 6 * std::size_t(adj.vf_start[std::size_t(v) + 1] - adj.vf_start[std::size_t(v)]);
    if (distances && arc_count + most > region_arcs.size()) region_arcs.resize(std::max(2 * region_arcs.size(), arc_count + most + 1024));
    RegionArc* const arcs_out = region_arcs.data();
    // The BFS waits on the mesh's arrays (scattered over tens of megabytes): ask for what the vertices a few
    // places ahead will read, their face lists two stages before their faces.
    if (i + 8 < region.size()) {
      const int ahead = region[i + 8];
      __builtin_prefetch(&adj.vf_start[std::size_t(ahead)]);
      __builtin_prefetch(&mesh.vertices[std::size_t(ahead)]);
    }
    if (i + 4 < region.size()) {
      const int near = region[i + 4];
      const int first = adj.vf_start[std::size_t(near)], last = adj.vf_start[std::size_t(near) + 1];
      __builtin_prefetch(&adj.vf[std::size_t(first)]);
      for (int j = first; j < last; ++j) __builtin_prefetch(&mesh.faces[std::size_t(adj.vf[std::size_t(j)])]);
    }
    const auto& p = mesh.vertices[std::size_t(v)];
    // Unsorted (a sort per vertex was a fifth of this step).
    adj.for_each_neighbour(mesh, v, [&](int w) {
      const double length = dist3(p, mesh.vertices[std::size_t(w)]);
      const double through_v = upper[i] + length;
      int wi = int(region.size());
      if (rid.emplace(w, wi)) {
        region.push_back(w), ring.push_back(ring[i] + 1), upper.push_back(through_v);
      } else {
        wi = rid.at(w);
        double& bound = upper[std::size_t(wi)];
        bound = std::min(bound, through_v);
      }
      if (distances) arcs_out[arc_count++] = {length, wi};
    });
  }
  if (distances) arcs_from.push_back(int(arc_count));
  const double upper_max = upper.empty() ? 0.0 : *std::max_element(upper.begin(), upper.end());
  std::vector<double> dist;
  auto compute_distances = [&] {
    // Only the vertices within max_move are expanded, often a small part of the rings: their neighbours in
    // the region are read as they are (a neighbour met twice across a non-manifold edge costs a repeated
    // arc and nothing else). The BFS's arcs serve every vertex it expanded; those of the last ring, which it
    // did not, read the mesh. The same arcs and lengths as the mesh's: the same distances.
    dist.assign(region.size(), std::numeric_limits<double>::infinity());
    thread_local std::vector<shorten_detail::QueueEntry> q;
    q.clear();
    for (int v : loop) {
      const int i = rid.at(v);
      dist[std::size_t(i)] = 0, shorten_detail::heap_push(q, {0, i});
    }
    const RegionArc* const arc = region_arcs.data();
    while (!q.empty()) {
      const auto [d, i] = shorten_detail::heap_pop(q);
      if (d > dist[std::size_t(i)] || d > opt.max_move) continue;
      auto relax = [&](int wi, double length) {
        const double nd = d + length;
        if (nd < dist[std::size_t(wi)]) dist[std::size_t(wi)] = nd, shorten_detail::heap_push(q, {nd, wi});
      };
      if (ring[std::size_t(i)] < max_rings) {
        for (int k = arcs_from[std::size_t(i)], end = arcs_from[std::size_t(i) + 1]; k < end; ++k) relax(arc[k].to, arc[k].len);
        continue;
      }
      const auto& p = mesh.vertices[std::size_t(region[std::size_t(i)])];
      adj.for_each_neighbour(mesh, region[std::size_t(i)], [&](int w) {
        if (const int* wi = rid.find(w)) relax(*wi, dist3(p, mesh.vertices[std::size_t(w)]));
      });
    }
  };
  if (distances && upper_max > opt.max_move) compute_distances();
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
  R.edge_path = best;
  R.edge_path_length = best_len;
  {
    const double edge = best_len / double(best.size());  // the loop's mean edge length
    double best_upper = 0;
    for (int v : best) best_upper = std::max(best_upper, upper[std::size_t(rid.at(v))]);
    if (distances && dist.empty() && best_upper > opt.max_move - 2 * edge) compute_distances();
    for (int v : best) {
      const std::size_t i = std::size_t(rid.at(v));
      if (ring[i] >= rings - 1 || (!dist.empty() && dist[i] > opt.max_move - 2 * edge)) {
        R.at_band_edge = true;
        break;
      }
    }
  }
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
  int flat_rounds = 0, rounds = 0;
  // On a surface of revolution (a hole's wall, a tube of even radius) the loop drifts across a family of
  // nearly equal sections, each round of swaps gaining a millionth of its length: hundreds of rounds for
  // a loop already within 1e-4 of its final length. Stop when the last rounds together gain too little.
  constexpr int kProgressWindow = 8;
  constexpr double kMinProgress = 1e-5;  // of the length, over the window
  std::vector<double> round_length{L};
  // A round's trial strip lives in buffers kept across rounds (an accepted round swaps them with the strip's).
  std::vector<int> S2;
  std::vector<double> s2;
  std::vector<Shortener::Apex> ap2;
  std::vector<std::array<int, 2>> dirty;
  for (int it = 0; it < 400 && R.swaps < opt.max_swaps; ++it) {
    S2.assign(S.begin(), S.end());
    s2.assign(sp.begin(), sp.end());
    int n = sh.swap_batch(S2, s2, apexes, 1 << 30, ap2, dirty);
    if (!n) break;
    // Only the funnel between the apexes around each swap is run again (a round costs what it changes).
    double L2 = sh.refunnel(S2, s2, ap2, dirty);
    if (!(L2 < L - 1e-12 * L) && n > 1) {  // the batch did not help: the single best swap alone
      S2.assign(S.begin(), S.end());
      s2.assign(sp.begin(), sp.end());
      n = sh.swap_batch(S2, s2, apexes, 1, ap2, dirty);
      if (!n) break;
      L2 = sh.refunnel(S2, s2, ap2, dirty);
    }
    if (debug)
      std::fprintf(stderr, "swap round %d: %d swaps, %.9f -> %.9f (strip %zu)\n", it, n, L, L2, S2.size());
    if (!(L2 < L + 1e-9 * L)) break;  // a swap below pi shortens; allow relaxation noise only
    if (!(L2 < L - 1e-12 * L) && ++flat_rounds > 3) break;
    S.swap(S2), sp.swap(s2), apexes.swap(ap2), L = std::min(L, L2);
    R.swaps += n;
    ++rounds;
    round_length.push_back(L);
    if (rounds >= kProgressWindow &&
        round_length[std::size_t(rounds - kProgressWindow)] - L < kMinProgress * L)
      break;
  }
  // The windows kept every crossing but the one the first funnel was cut at; a funnel over the whole
  // strip settles that one too.
  if (R.swaps > 0) L = sh.funnel_through_apex(S, sp, apexes, {});
  clock.lap(StepClock::kSwaps);
  sh.polish(S, sp, 200);
  auto pts = sh.strip_points(S, sp);
  double Lp = closed_length(pts);
  clock.lap(StepClock::kPolish);
  if (debug) {
    std::fprintf(stderr, "edge loop %.9f (%zu vertices), strip %zu faces, relaxed %.9f, polished %.9f; band %zu vertices, %d rings, %d descents\n", R.length,
                 best.size(), S.size(), L, Lp, sh.band.global.size(), rings, descents);
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
  ShortenResult first = shorten_in_band(mesh, adj, loop, narrow);
  if (first.rings > 0 && !first.at_band_edge) return first;
  // The wide band starts from the input loop again, so that max_move keeps its meaning; of two loops
  // in the class, the shorter.
  ShortenResult wide = shorten_in_band(mesh, adj, loop, opt);
  if (std::getenv("CHOKELOOPS_DEBUG_SHORTEN"))
    std::fprintf(stderr, "widened band: %d rings %.9f (at its edge: %d), %d rings %.9f\n", first.rings, first.length,
                 int(first.at_band_edge), wide.rings, wide.length);
  if (first.rings > 0 && !(wide.rings > 0 && wide.length <= first.length)) return first;
  return wide;
}

void release_shortening_scratch() noexcept { detail::DenseIntMap::release_pool(); }

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

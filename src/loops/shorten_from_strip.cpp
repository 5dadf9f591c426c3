// The entry of loop shortening that starts from a strip of faces instead of an edge loop (shorten_strip_loop,
// shorten.h): a plane section is such a strip already, and where its loop is near its geodesic the swap
// rounds of step 3 find from it what the band search of steps 1-2 (most of a long loop's cost) would.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <utility>
#include <vector>

#include "chokeloops/loops/shorten.h"
#include "chokeloops/surface/topology.h"
#include "shortener.h"

namespace chokeloops {

namespace shorten_detail {

namespace {

// A loop still shortening after this many swap rounds is sliding a vertex row a round towards a loop some
// rows away, which the band search of steps 1-2 finds at once: it is reported at its band's edge. On the
// pierced block's 44 long sections 24, 32 and 48 rounds let 16, 18 and 23 of them finish, and 113, 114 and
// 110 of its 220 loops within 5 ms (one thread): past 32 the loops that finish take longer than 5 ms.
constexpr int kStripMaxRounds = 32;

// The strip's vertices on one side of the loop (each portal's left or right end), in turn: an edge loop in
// the strip, so of the loop's class. Empty when it visits a vertex twice.
std::vector<int> strip_side(const Shortener& sh, const std::vector<int>& S, bool left) {
  std::vector<int> side;
  const std::size_t m = S.size();
  for (std::size_t j = 0; j < m; ++j) {
    const int h = sh.portal_of(S[j], S[j + 1 == m ? 0 : j + 1]);
    if (h < 0) return {};
    const int v = left ? sh.vert(h) : sh.vert_to(h);
    if (side.empty() || side.back() != v) side.push_back(v);
  }
  while (side.size() > 1 && side.front() == side.back()) side.pop_back();
  std::vector<int> sorted = side;
  std::sort(sorted.begin(), sorted.end());
  if (side.size() < 3 || std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end()) return {};
  return side;
}

// Whether every point of `moved` lies within `reach` of some point of `start` (straight-line distances:
// a lower bound of the distance along the surface), by cells of that size.
bool within_reach(const Polyline3& start, const Polyline3& moved, double reach) {
  auto cell_of = [reach](const P3& p) {
    std::array<std::int64_t, 3> c;
    for (int a = 0; a < 3; ++a) c[std::size_t(a)] = std::int64_t(std::floor(p[std::size_t(a)] / reach));
    return c;
  };
  auto key = [](std::int64_t x, std::int64_t y, std::int64_t z) {
    constexpr std::int64_t kBias = std::int64_t(1) << 20;
    return std::uint64_t(x + kBias) << 42 | std::uint64_t(y + kBias) << 21 | std::uint64_t(z + kBias);
  };
  std::vector<std::pair<std::uint64_t, int>> cells;
  cells.reserve(start.size());
  for (std::size_t i = 0; i < start.size(); ++i) {
    const auto c = cell_of(start[i]);
    cells.push_back({key(c[0], c[1], c[2]), int(i)});
  }
  std::sort(cells.begin(), cells.end());
  const double reach2 = reach * reach;
  auto near_in = [&](const P3& p, std::uint64_t k) {
    for (auto it = std::lower_bound(cells.begin(), cells.end(), std::make_pair(k, -1)); it != cells.end() && it->first == k; ++it)
      if (dist3_squared(p, start[std::size_t(it->second)]) <= reach2) return true;
    return false;
  };
  for (const P3& p : moved) {
    const auto c = cell_of(p);
    // Its own cell first: a loop that moved less than `reach` mostly finds its old place there.
    bool near = near_in(p, key(c[0], c[1], c[2]));
    for (int d = 0; d < 27 && !near; ++d)
      if (d != 13) near = near_in(p, key(c[0] + d / 9 - 1, c[1] + d / 3 % 3 - 1, c[2] + d % 3 - 1));
    if (!near) return false;
  }
  return true;
}

double edge_loop_length(const SurfaceMesh& mesh, const std::vector<int>& loop) {
  double length = 0;
  for (std::size_t i = 0; i < loop.size(); ++i)
    length += shorten_detail::dist3(mesh.vertices[std::size_t(loop[i])], mesh.vertices[std::size_t(loop[(i + 1) % loop.size()])]);
  return length;
}

}  // namespace
}  // namespace shorten_detail

std::vector<int> strip_side_loop(const SurfaceMesh& mesh, const MeshAdjacency& adj, const std::vector<int>& faces) {
  shorten_detail::Shortener sh(mesh, adj);
  if (faces.size() < 3 || !sh.portals_ok(faces)) return {};
  const std::vector<int> left = shorten_detail::strip_side(sh, faces, true), right = shorten_detail::strip_side(sh, faces, false);
  if (left.empty() || right.empty()) return left.empty() ? right : left;
  return shorten_detail::edge_loop_length(mesh, left) <= shorten_detail::edge_loop_length(mesh, right) ? left : right;
}

ShortenResult shorten_strip_loop(const SurfaceMesh& mesh, const MeshAdjacency& adj, const std::vector<int>& faces,
                                 const ShortenOptions& opt) {
  using shorten_detail::Shortener;
  if (faces.size() < 3) throw Error("a strip loop needs at least three faces, got " + std::to_string(faces.size()));
  for (int f : faces)
    if (f < 0 || std::size_t(f) >= mesh.faces.size()) throw Error("strip face index out of range: " + std::to_string(f));
  Shortener sh(mesh, adj);
  if (!sh.portals_ok(faces)) throw Error("strip faces are not joined by shared edges in turn");
  const bool debug = std::getenv("CHOKELOOPS_DEBUG_SHORTEN") != nullptr;
  // No band: a swap is a homotopy across one vertex wherever it is, and the band's only other use here,
  // bounding how far the loop goes, is what the round cap and the distance check below do.
  sh.whole_mesh = true;

  ShortenResult R;
  R.rings = 1;
  std::vector<int> S = faces;
  std::vector<double> sp(S.size(), 0.5);
  std::vector<Shortener::Apex> apexes;
  double L = sh.funnel_through_apex(S, sp, apexes, {});
  R.input_length = L;
  const Polyline3 start = sh.strip_points(S, sp);
  int rounds = 0;
  bool unfinished = false;
  L = sh.swap_rounds(S, sp, apexes, L, opt.max_swaps, R.swaps, rounds, debug, shorten_detail::kStripMaxRounds, &unfinished);
  sh.polish(S, sp, 200);
  R.points = sh.strip_points(S, sp);
  R.length = closed_length(R.points);
  R.strip_faces = S;
  R.at_band_edge = unfinished;
  if (opt.max_move > 0 && !shorten_detail::within_reach(start, R.points, opt.max_move)) R.at_band_edge = true;
  // Of the strip's two sides, the shorter simple one; the polyline snapped to edges when neither is simple.
  R.edge_path = strip_side_loop(mesh, adj, S);
  if (R.edge_path.empty()) R.edge_path = snap_polyline_to_edge_path(mesh, adj, R.points);
  R.edge_path_length = shorten_detail::edge_loop_length(mesh, R.edge_path);
  if (debug)
    std::fprintf(stderr, "strip loop: %zu faces, funnel %.9f, after %d swaps in %d rounds %.9f, polished %.9f%s\n", faces.size(),
                 R.input_length, R.swaps, rounds, L, R.length, R.at_band_edge ? ", still moving or moved too far" : "");
  return R;
}

}  // namespace chokeloops

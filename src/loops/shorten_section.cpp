// A starting strip for step 3 from plane sections of the band (shortener.h).
//
// Why. The shortest edge loop of step 2 is taut along the mesh's edges, and where the edges run best
// round a tube is not where the tube is narrowest: on the cage's sticks that loop lies a few edges from the
// neck and is 0.4% longer than the geodesic there, and the side swaps of step 3 moved it past one vertex
// at a time, a few per round: ~40 rounds of a funnel over the whole strip. A tube's narrowest loop, and a
// loop round a block's flat wall, lie close to a plane; the planes parallel to the edge loop's own cut the
// band in sections whose lengths (a few microseconds each) find the neck, and the faces the shortest one
// crosses form a strip whose funnel leaves the swaps a few rounds.
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <vector>

#include "chokeloops/surface/topology.h"
#include "shortener.h"

namespace chokeloops::shorten_detail {

int Shortener::strip_winding(const std::vector<int>& S) const {
  // The strip's left side is an edge path homotopic to the loop through the strip (each face holds both):
  // its crossings of the cut give the loop's winding.
  const int m = int(S.size());
  if (m < 2) return 0;
  int w = 0, first = -1, prev = -1;
  for (int j = 0; j < m; ++j) {
    const int h = portal_of(S[std::size_t(j)], S[std::size_t((j + 1) % m)]);
    if (h < 0) return 0;
    const int left = vert(h);
    if (first < 0) first = left;
    else if (left != prev) w += signed_edge_sign(prev, left);
    prev = left;
  }
  if (prev != first) w += signed_edge_sign(prev, first);
  return w;
}

double Shortener::shortest_plane_section(const P3& point, const P3& normal, std::vector<int>& S) const {
  double best = std::numeric_limits<double>::infinity();
  S.clear();
  const std::size_t F = band.faces.size();
  thread_local std::vector<double> height;  // per band vertex, above the plane
  thread_local std::vector<char> visited;   // per band face
  thread_local std::vector<int> cycle;
  // The band's own copy of its points (build_arcs): the mesh's are scattered over megabytes, and a line
  // search measures several sections of one band.
  height.resize(band.global.size());
  for (std::size_t v = 0; v < band.global.size(); ++v) {
    const P3& p = position[v];
    height[v] = (p[0] - point[0]) * normal[0] + (p[1] - point[1]) * normal[1] + (p[2] - point[2]) * normal[2];
  }
  auto above = [&](int v) { return height[std::size_t(v)] >= 0; };
  visited.assign(F, 0);
  // The face's two local half-edges that the plane crosses; false when it does not cross the face.
  auto crossed = [&](std::size_t i, std::array<int, 2>& k) {
    int n = 0;
    for (int e = 0; e < 3; ++e)
      if (above(band.corner[3 * i + std::size_t(e)]) != above(band.corner[3 * i + std::size_t((e + 1) % 3)])) {
        if (n == 2) return false;
        k[std::size_t(n++)] = e;
      }
    return n == 2;
  };
  // Where the plane crosses local half-edge hl.
  auto crossing_point = [&](std::size_t hl) {
    const int a = band.corner[hl], b = band.corner[std::size_t(MeshAdjacency::next(int(hl)))];
    const double ha = height[std::size_t(a)], hb = height[std::size_t(b)];
    return lerp3(position[std::size_t(a)], position[std::size_t(b)], ha / (ha - hb));
  };
  for (std::size_t start = 0; start < F; ++start) {
    std::array<int, 2> k{};
    if (visited[start] || !crossed(start, k)) continue;
    cycle.clear();
    std::size_t i = start;
    int exit = k[0];
    bool closed = false;
    double length = 0;
    P3 entered = crossing_point(3 * start + std::size_t(k[1]));
    for (std::size_t steps = 0; steps <= F; ++steps) {
      visited[i] = 1;
      cycle.push_back(band.faces[i]);
      const P3 left = crossing_point(3 * i + std::size_t(exit));
      length += dist3(entered, left);
      entered = left;
      const int twin = band.twin_in_band[3 * i + std::size_t(exit)];
      if (twin < 0) break;  // the section leaves the band
      const int* place = band.in_face.find(twin / 3);
      if (!place) break;
      const std::size_t j = std::size_t(*place);
      if (j == start) { closed = true; break; }
      std::array<int, 2> kj{};
      if (visited[j] || !crossed(j, kj)) break;
      exit = kj[0] == twin % 3 ? kj[1] : kj[0];
      i = j;
    }
    if (!closed || cycle.size() < 3 || !(length < best)) continue;
    const int w = strip_winding(cycle);
    if (w != 1 && w != -1) continue;  // contractible in the band, or not a loop of its class
    if (w != band.winding) std::reverse(cycle.begin(), cycle.end());
    best = length;
    S = cycle;
  }
  return best;
}

bool Shortener::strip_from_nearby_sections(const Polyline3& loop, double step, int max_steps, std::vector<int>& S) const {
  S.clear();
  if (loop.size() < 3 || !(step > 0)) return false;
  P3 mean, n;
  best_fit_plane(loop, mean, n);
  std::map<int, double> length_at;  // offset (in steps) -> its shortest section's length
  std::vector<int> strip;           // the strip of the offset measured last, when it was measured anew
  auto length = [&](int offset) {
    if (auto it = length_at.find(offset); it != length_at.end()) return it->second;
    const double at = double(offset) * step;
    return length_at[offset] = shortest_plane_section({mean[0] + at * n[0], mean[1] + at * n[1], mean[2] + at * n[2]}, n, strip);
  };
  // A line search over the offsets: steps that double while the sections shorten, then halve. S keeps the
  // strip of the best offset so far.
  int best = 0;
  double best_length = length(0);
  S.swap(strip);
  const double up = length(1);
  std::vector<int> up_strip;
  up_strip.swap(strip);
  const double down = length(-1);
  const int direction = up < down ? 1 : -1;
  if (std::min(up, down) < best_length) {
    best = direction, best_length = std::min(up, down);
    S.swap(direction == 1 ? up_strip : strip);
  } else if (!std::isfinite(best_length)) {
    return false;
  }
  if (best != 0)
    for (int stride = 2; stride >= 1;) {
      const int next = best + direction * stride;
      if (std::abs(next) > max_steps) { stride /= 2; continue; }
      const double l = length(next);  // an offset measured before is no shorter than the best
      if (l < best_length) best = next, best_length = l, stride *= 2, S.swap(strip);
      else stride /= 2;
    }
  return std::isfinite(best_length) && !S.empty() && portals_ok(S);
}

}  // namespace chokeloops::shorten_detail

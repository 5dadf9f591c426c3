// Steps 1 and 2 of shorten_loop: the annulus band of faces around the loop with a cut across it, and the
// shortest edge loop in the band in the loop's class (an A* search in two sheets of the band's cyclic cover).
#include <algorithm>
#include <array>
#include <cstdint>
#include <functional>
#include <limits>
#include <numeric>
#include <queue>
#include <utility>

#include "shortener.h"

namespace chokeloops::shorten_detail {

// ---- Step 1: band --------------------------------------------------------------------------------

bool Shortener::build_band(const BandCandidates& candidates, int rings, const std::vector<int>& loop) {
  band = Band();  // its arrays back to the pool first: a call holds one band's at a time
  total_angle_of.clear();
  corner_angle_of.clear();
  Band B;
  B.in_face = detail::DenseIntMap(mesh.faces.size());
  B.local = detail::DenseIntMap(mesh.vertices.size());
  for (std::size_t i = 0; i < candidates.faces.size(); ++i)
    if (candidates.entry[i] <= rings) {
      B.in_face.emplace(candidates.faces[i], int(B.faces.size()));
      B.faces.push_back(candidates.faces[i]);
    }
  if (B.faces.empty()) return false;
  for (int f : B.faces)
    for (int k = 0; k < 3; ++k) {
      int v = mesh.faces[f][k];
      if (B.local.emplace(v, int(B.global.size()))) B.global.push_back(v);
    }
  band = std::move(B);
  Band& b = band;
  auto place = [&](int f) { const int* i = b.in_face.find(f); return i ? *i : -1; };
  const std::size_t nh = 3 * b.faces.size();
  b.corner.resize(nh);
  b.twin_in_band.resize(nh);
  b.crossing_sign.assign(nh, 0);
  // This step's tables are the thread's, kept between calls (a loop stage builds a band per loop).
  thread_local std::vector<int> across;  // the band place of the face across each band half-edge, or -1
  across.resize(nh);
  for (std::size_t i = 0; i < b.faces.size(); ++i) {
    const int f = b.faces[i];
    for (int k = 0; k < 3; ++k) {
      const std::size_t hl = 3 * i + std::size_t(k);
      const int t = adj.twin[std::size_t(3 * f + k)];
      b.corner[hl] = b.local.at(mesh.faces[std::size_t(f)][std::size_t(k)]);
      across[hl] = t >= 0 ? place(t / 3) : -1;
      b.twin_in_band[hl] = across[hl] >= 0 ? t : -1;
    }
  }
  // Euler characteristic, boundary, fans.
  std::int64_t V = std::int64_t(b.global.size()), F = std::int64_t(b.faces.size()), E = 0;
  thread_local std::vector<int> faces_at, interior_at, boundary_at, bparent;
  faces_at.assign(std::size_t(V), 0), interior_at.assign(std::size_t(V), 0), boundary_at.assign(std::size_t(V), 0);
  bparent.resize(std::size_t(V));
  std::iota(bparent.begin(), bparent.end(), 0);
  auto find = [&](int x) { while (bparent[x] != x) x = bparent[x] = bparent[bparent[x]]; return x; };
  for (std::size_t i = 0; i < b.faces.size(); ++i)
    for (int k = 0; k < 3; ++k) {
      const std::size_t hl = 3 * i + std::size_t(k);
      const int h = 3 * b.faces[i] + k, t = b.twin_in_band[hl];
      const int a = b.corner[hl], c = b.corner_to(hl);
      ++faces_at[a];
      if (t >= 0) {
        if (h < t) {
          ++E;
          ++interior_at[a], ++interior_at[c];
        }
      } else {
        ++E;
        ++boundary_at[a], ++boundary_at[c];
        bparent[find(a)] = find(c);
      }
    }
  if (V - E + F != 0) return false;
  int boundary_components = 0;
  for (int v = 0; v < V; ++v) {
    if (boundary_at[v] != 0 && boundary_at[v] != 2) return false;
    int fans = boundary_at[v] ? faces_at[v] - interior_at[v] : 1;
    if (fans != 1) return false;
    if (boundary_at[v] && find(v) == v) ++boundary_components;
  }
  if (boundary_components != 2) return false;
  // Connected (face flood over band places).
  {
    std::vector<int> stack{0};
    thread_local std::vector<char> seen;
    seen.assign(b.faces.size(), 0);
    seen[0] = 1;
    size_t reached = 1;
    while (!stack.empty()) {
      const int i = stack.back();
      stack.pop_back();
      for (int k = 0; k < 3; ++k) {
        const int j = across[3 * std::size_t(i) + std::size_t(k)];
        if (j >= 0 && !seen[std::size_t(j)]) seen[std::size_t(j)] = 1, ++reached, stack.push_back(j);
      }
    }
    if (reached != b.faces.size()) return false;
  }
  // Cut: BFS over band faces from faces on boundary curve A to a face on boundary curve B.
  int rootA = -1;
  for (int v = 0; v < V && rootA < 0; ++v)
    if (boundary_at[v]) rootA = find(v);
  // Boundary half-edge (mesh) of the face at band place i on the given curve, or -1.
  auto on_curve = [&](int i, bool curveA) {
    for (int k = 0; k < 3; ++k) {
      const std::size_t hl = 3 * std::size_t(i) + std::size_t(k);
      if (across[hl] >= 0) continue;
      const bool isA = find(b.corner[hl]) == rootA;
      if (isA == curveA) return 3 * b.faces[std::size_t(i)] + k;
    }
    return -1;
  };
  constexpr int kUnreached = -2;
  thread_local std::vector<int> parent_h;
  parent_h.assign(b.faces.size(), kUnreached);  // per band face: half-edge (in the parent face) crossed to reach it
  std::queue<int> q;
  for (std::size_t i = 0; i < b.faces.size(); ++i)
    if (on_curve(int(i), true) >= 0) parent_h[i] = -1, q.push(int(i));
  int target = -1;
  while (!q.empty() && target < 0) {
    const int i = q.front();
    q.pop();
    if (on_curve(i, false) >= 0) { target = i; break; }
    for (int k = 0; k < 3; ++k) {
      const int j = across[3 * std::size_t(i) + std::size_t(k)];
      if (j < 0 || parent_h[std::size_t(j)] != kUnreached) continue;
      parent_h[std::size_t(j)] = 3 * b.faces[std::size_t(i)] + k;
      q.push(j);
    }
  }
  if (target < 0) return false;
  // The cut runs from the midpoint of a boundary edge on curve A through the faces to the midpoint of
  // one on curve B; those two boundary edges count as crossed too (a loop along the boundary around
  // the cut's end would otherwise wind once).
  auto set_sign = [&](int h, int sg) {
    b.sign[h] = sg;
    b.crossing_sign[3 * std::size_t(place(h / 3)) + std::size_t(h % 3)] = static_cast<signed char>(sg);
    if (const int t = adj.twin[h]; t >= 0) {
      b.sign[t] = -sg;
      if (const int j = place(t / 3); j >= 0) b.crossing_sign[3 * std::size_t(j) + std::size_t(t % 3)] = static_cast<signed char>(-sg);
    }
  };
  set_sign(on_curve(target, false), +1);
  int i = target;
  b.cut_vertices.clear();
  for (; parent_h[std::size_t(i)] >= 0; i = place(parent_h[std::size_t(i)] / 3)) {
    const int h = parent_h[std::size_t(i)];
    set_sign(h, +1);
    b.cut_vertices.push_back(b.local.at(vert(h)));
  }
  set_sign(on_curve(i, true), -1);
  int w = 0;
  for (size_t i = 0; i < loop.size(); ++i) w += signed_edge_sign(loop[i], loop[(i + 1) % loop.size()]);
  b.winding = w;
  return w == 1 || w == -1;
}

BandCandidates band_candidates(const SurfaceMesh& mesh, const MeshAdjacency& adj, const std::vector<int>& region,
                               const detail::DenseIntMap& rid, const std::vector<int>& entry,
                               const std::vector<char>& near, int max_k) {
  const int never = max_k + 1;
  auto face_entry = [&](int f) {
    int a[3], n[3];
    bool touches = false;
    for (int j = 0; j < 3; ++j) {
      const int* i = rid.find(mesh.faces[f][j]);
      a[j] = i ? std::min(entry[std::size_t(*i)], never) : never;
      n[j] = i ? near[std::size_t(*i)] : 0;
      touches |= n[j] == 2;
    }
    int k = std::max({a[0], a[1], a[2]});
    if (touches) {
      int via_loop = std::min({a[0], a[1], a[2]});
      for (int j = 0; j < 3; ++j) via_loop = std::max(via_loop, n[j] ? 0 : a[j]);
      k = std::min(k, via_loop);
    }
    return k;
  };
  detail::DenseIntMap face_k(mesh.faces.size());
  std::vector<std::pair<int, int>> taken;  // (face, entry ring), sorted by face below
  for (std::size_t i = 0; i < region.size(); ++i)
    if (entry[i] <= max_k)
      for (int j = adj.vf_start[region[i]]; j < adj.vf_start[region[i] + 1]; ++j) {
        const int f = adj.vf[j];
        if (face_k.contains(f)) continue;
        const int k = face_entry(f);
        face_k.emplace(f, k);
        if (k <= max_k) taken.push_back({f, k});
      }
  // By face: a least-significant-digit radix sort on the face index, 11 bits a pass (std::sort of the few
  // thousand pairs was a sixth of this step); faces are unique, so the order is std::sort's.
  {
    std::vector<std::pair<int, int>> other(taken.size());
    const unsigned top = unsigned(std::max<std::size_t>(mesh.faces.size(), 1) - 1);
    for (unsigned shift = 0; shift < 32 && (top >> shift) != 0; shift += 11) {
      std::array<int, 2049> count{};
      for (const auto& x : taken) ++count[((unsigned(x.first) >> shift) & 2047u) + 1];
      for (std::size_t d = 1; d < count.size(); ++d) count[d] += count[d - 1];
      for (const auto& x : taken) other[std::size_t(count[(unsigned(x.first) >> shift) & 2047u]++)] = x;
      taken.swap(other);
    }
  }
  BandCandidates c;
  c.faces.reserve(taken.size());
  c.entry.reserve(taken.size());
  for (const auto& [f, k] : taken) c.faces.push_back(f), c.entry.push_back(k);
  std::vector<long> delta(std::size_t(max_k) + 2, 0);
  thread_local std::vector<int> vertex_k;  // kept by the thread, as the band's tables
  vertex_k.assign(region.size(), never);
  for (std::size_t i = 0; i < c.faces.size(); ++i) {
    const int f = c.faces[i], k = c.entry[i];
    ++delta[std::size_t(k)];
    for (int j = 0; j < 3; ++j) {
      const std::size_t v = std::size_t(rid.at(mesh.faces[f][j]));
      vertex_k[v] = std::min(vertex_k[v], k);
      const int h = 3 * f + j, t = adj.twin[std::size_t(h)];
      const int* tk = t >= 0 ? face_k.find(t / 3) : nullptr;
      const int kt = tk ? *tk : never;
      if (k < kt || (k == kt && h < t)) --delta[std::size_t(k)];  // the edge enters with the first of its faces
    }
  }
  for (int k : vertex_k)
    if (k <= max_k) ++delta[std::size_t(k)];
  c.euler.assign(std::size_t(max_k) + 1, 0);
  long sum = 0;
  for (int k = 0; k <= max_k; ++k) c.euler[std::size_t(k)] = sum += delta[std::size_t(k)];
  return c;
}

// ---- Step 2: shortest edge loop in the band ------------------------------------------------------

void Shortener::build_arcs() {
  // Both directions of every edge of the band (an inner edge once, from the half-edge of its pair that
  // comes first), bucketed by their source vertex, then each vertex's few arcs by (target, sign) with
  // repeats (edges of more than two faces) dropped: the arcs a sort of all of them gave, for a counting pass.
  struct Half { int from; Arc arc; };
  thread_local std::vector<Half> all;  // this step's tables are the thread's, kept between calls
  // Sized for every half-edge once and written through a pointer: push_back's capacity check and its
  // out-of-line growth path were half of this step's samples (perf, the cage's handle loops).
  if (all.size() < band.faces.size() * 6) all.resize(band.faces.size() * 6);  // never shrunk: no refill
  Half* out = all.data();
  const std::size_t nv = band.global.size();
  position.resize(nv);
  for (std::size_t v = 0; v < nv; ++v) position[v] = mesh.vertices[std::size_t(band.global[v])];
  for (std::size_t i = 0; i < band.faces.size(); ++i)
    for (int k = 0; k < 3; ++k) {
      const std::size_t hl = 3 * i + std::size_t(k);
      const int h = 3 * band.faces[i] + k, t = band.twin_in_band[hl];
      if (t >= 0 && t < h) continue;
      const int a = band.corner[hl], c = band.corner_to(hl);
      const double L = dist3(position[std::size_t(a)], position[std::size_t(c)]);
      const int sg = band.crossing_sign[hl];
      *out++ = {a, {L, c, sg}};
      *out++ = {c, {L, a, -sg}};
    }
  const Half* const first_half = all.data();
  const Half* const end_half = out;
  thread_local std::vector<int> fill;
  fill.assign(nv + 1, 0);
  for (const Half* x = first_half; x != end_half; ++x) ++fill[std::size_t(x->from) + 1];
  for (std::size_t v = 0; v < nv; ++v) fill[v + 1] += fill[v];
  thread_local std::vector<Arc> bucketed;
  const std::size_t halves = std::size_t(end_half - first_half);
  if (bucketed.size() < halves) bucketed.resize(halves);
  {
    thread_local std::vector<int> next;
    next.assign(fill.begin(), fill.end() - 1);
    for (const Half* x = first_half; x != end_half; ++x) bucketed[std::size_t(next[std::size_t(x->from)]++)] = x->arc;
  }
  auto before = [](const Arc& x, const Arc& y) { return x.to != y.to ? x.to < y.to : x.sign < y.sign; };
  arc_start.assign(nv + 1, 0);
  arcs.clear();
  arcs.reserve(halves);
  for (std::size_t v = 0; v < nv; ++v) {
    Arc* b = bucketed.data() + fill[v];
    Arc* e = bucketed.data() + fill[v + 1];
    for (Arc* i = b + 1; i < e; ++i)  // insertion sort: a vertex has a handful of arcs
      for (Arc* j = i; j > b && before(*j, *(j - 1)); --j) std::swap(*j, *(j - 1));
    for (Arc* i = b; i < e; ++i)
      if (i == b || before(*(i - 1), *i)) arcs.push_back(*i);
    arc_start[v + 1] = int(arcs.size());
  }
}


bool Shortener::cut_is_near_ahead(const std::vector<int>& loop, int s) const {
  const int n = int(loop.size());
  const int at = int(std::find(loop.begin(), loop.end(), band.global[std::size_t(s)]) - loop.begin());
  if (at == n) return false;
  double total = 0, ahead = -1;
  for (int i = 0; i < n; ++i) {
    const int a = loop[std::size_t((at + i) % n)], b = loop[std::size_t((at + i + 1) % n)];
    if (ahead < 0 && signed_edge_sign(a, b) != 0) ahead = total;
    total += dist3(mesh.vertices[std::size_t(a)], mesh.vertices[std::size_t(b)]);
  }
  return ahead >= 0 && ahead < total / 2;
}

void Shortener::mark_near(const std::vector<int>& loop, int rings, std::vector<char>& marks) const {
  marks.assign(band.global.size(), 0);
  std::vector<int> frontier, next;
  for (int v : loop) {
    const int l = local_of(v);
    if (l >= 0 && !marks[std::size_t(l)]) marks[std::size_t(l)] = 1, frontier.push_back(l);
  }
  for (int k = 0; k < rings && !frontier.empty(); ++k) {
    next.clear();
    for (int v : frontier)
      for (int i = arc_start[std::size_t(v)]; i < arc_start[std::size_t(v) + 1]; ++i) {
        const int w = arcs[std::size_t(i)].to;
        if (!marks[std::size_t(w)]) marks[std::size_t(w)] = 1, next.push_back(w);
      }
    frontier.swap(next);
  }
}

std::vector<int> Shortener::shortest_loop_through(int s, double& length, bool backward, double below,
                                                  const std::vector<char>* within) const {
  // Two sheets of the cover: the one the search starts on and the next one in the loop's winding
  // direction (sheet = crossings of the cut so far, times the winding). A path that dips into a third
  // sheet crosses the cut back and forth, which a cut that runs straight across the band (the fewest
  // faces from one border to the other) rarely lets a shortest loop do. Of the two ways round, the search
  // takes all of the start's sheet and the part of the next one from the cut on to the start: searching
  // backward when the cut lies a short way ahead of the start takes the shorter part (see the caller).
  // Nodes taken in a one-thread run on the pierced block: 22.1M with a Dijkstra over sheets -3..3 (the
  // sheet behind the start held about a quarter of them), 14.2M with these two and the A* below, 11.9M
  // with the way round chosen. The searches of one band reuse their arrays (one set per thread): only the
  // nodes a search touched are reset, so a search costs what it explores, not the band's size.
  constexpr int NL = 2;
  struct Scratch {
    std::vector<double> d, bound;  // per node; per band vertex (negative: not computed yet)
    std::vector<int> from, touched, bounded;  // nodes whose d was set; vertices whose bound was computed
    std::vector<QueueEntry> queue;
  };
  static thread_local Scratch scratch;
  const std::size_t nodes = band.global.size() * std::size_t(NL);
  auto& d = scratch.d;
  auto& from = scratch.from;
  auto& touched = scratch.touched;
  if (d.size() < nodes) {
    d.assign(nodes, std::numeric_limits<double>::infinity());
    from.assign(nodes, -1);
  }
  if (scratch.bound.size() < band.global.size()) scratch.bound.assign(band.global.size(), -1);
  touched.clear();
  scratch.bounded.clear();
  auto& q = scratch.queue;
  q.clear();
  const int winding = backward ? -band.winding : band.winding;  // band.winding: +1 or -1 (build_band)
  const int src = s * NL, dst = s * NL + 1;
  // A*: a node is taken in the order of its distance plus the straight line from it to s (the target's
  // point in space), a lower bound of what is left that never drops by more than an arc's length along
  // an arc; so the first time the target is taken its distance is the shortest, as in Dijkstra, and the
  // nodes whose distance plus that bound exceed the loop's length are never taken. The heap holds that
  // sum; an entry is current when its sum is the node's distance plus its bound, one addition of the same
  // two numbers (each vertex's bound is computed once a search), so the test is exact.
  const P3 target = position[std::size_t(s)];
  // The loop below reads the band and the scratch through plain pointers: through the vectors (a
  // thread_local's members) each read went back to the thread's block and the vector for its data pointer.
  double* const dist = d.data();
  int* const prev = from.data();
  double* const bounds = scratch.bound.data();
  const Arc* const arc = arcs.data();
  const int* const first_arc = arc_start.data();
  const P3* const at = position.data();
  std::vector<int>& bounded = scratch.bounded;
  const char* const allowed = within ? within->data() : nullptr;
  auto bound = [&](int v) {
    double b = bounds[v];
    if (b < 0) b = bounds[v] = dist3(at[v], target), bounded.push_back(v);
    return b;
  };
  dist[src] = 0;
  touched.push_back(src);
  heap_push(q, {0, src});
  long taken = 0;
  while (!q.empty()) {
    const auto [key, node] = heap_pop(q);
    const int v = node / NL, sheet = node % NL;
    const double dv = dist[node];
    if (key != dv + bound(v)) continue;
    ++taken;
    if (node == dst) break;
    for (int i = first_arc[v], end = first_arc[v + 1]; i < end; ++i) {
      const Arc& a = arc[i];
      if (allowed && !allowed[a.to]) continue;
      const int next_sheet = sheet + a.sign * winding;
      if (next_sheet < 0 || next_sheet >= NL) continue;
      const int w = a.to * NL + next_sheet;
      const double nd = dv + a.len;
      if (nd < dist[w]) {
        // A node whose key reaches `below` lies on no loop shorter than that (the key is a lower bound of
        // any loop through it): it is left out, and the nodes below it are taken in the same order.
        const double key_w = nd + bound(a.to);
        if (!(key_w < below)) continue;
        if (std::isinf(dist[w])) touched.push_back(w);
        dist[w] = nd, prev[w] = node;
        heap_push(q, {key_w, w});
      }
    }
  }
  search_nodes += taken;
  std::vector<int> path;
  if (std::isinf(d[dst])) {
    length = std::numeric_limits<double>::infinity();
  } else {
    length = d[dst];
    // s, then the vertices the search took back from s to its start: the loop in the input's direction
    // from s when the search went backward; else reversed and s brought to the front.
    for (int node = dst; node != src; node = from[node]) path.push_back(band.global[node / NL]);
    if (!backward) {
      std::reverse(path.begin(), path.end());  // starts after s, ends with s
      std::rotate(path.begin(), path.end() - 1, path.end());
    }
  }
  for (int w : touched) d[w] = std::numeric_limits<double>::infinity(), from[w] = -1;
  for (int v : scratch.bounded) scratch.bound[std::size_t(v)] = -1;
  return path;
}

}  // namespace chokeloops::shorten_detail

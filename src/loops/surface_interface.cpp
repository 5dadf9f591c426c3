// The zones' interface on the surface (surface_interface.h).
#include "surface_interface.h"

#include <algorithm>
#include <limits>

#include "chokeloops/surface/topology.h"

namespace chokeloops::detail {

void surface_interface(const ScalarGrid& grid, const FreudenthalComplex& cx, const SurfaceMesh& surface,
                       const MeshAdjacency& adjacency, const FloodBox& box, bool handle, StampedMarks<std::int8_t>& label,
                       SurfaceInterface& out) {
  const float* f = grid.values.data();
  auto region = [&](Id v) { return handle ? f[v] <= 0 : f[v] > 0; };
  // Label the surface vertices on the crossing edges by their region end.
  // Flat arrays over the whole surface rather than hash maps: a big box has a million shore vertices.
  label.reset(surface.vertices.size());
  std::vector<int> labelled;
  for (std::uint32_t xl : box.shore) {
    const auto p = box.local(xl);
    const std::array<int, 3> gp{box.lo[0] + p[0], box.lo[1] + p[1], box.lo[2] + p[2]};
    const Id x = box.global(xl);
    for (int nb = 0; nb < 14; ++nb) {
      if (!cx.neighbor_inside(gp, nb)) continue;
      Id u = x + cx.neighbor_delta(nb);
      if (region(u)) continue;
      int sv = surface_vertex_on_edge(surface, cx.edge_id(x, u));
      if (sv >= 0) {
        if (label.get(sv) == 0) labelled.push_back(sv);
        label.set(sv, std::int8_t(box.zone(xl)));
      }
    }
  }

  // Interface segments on faces whose vertices carry both labels; chain them into curves.
  // Only faces whose corners carry both labels hold interface segments: a big box labels a million
  // vertices, and sorting all their faces cost more than the flood.
  std::vector<int> sorted_faces;
  for (int v : labelled)
    for (int q = adjacency.vf_start[v]; q < adjacency.vf_start[v + 1]; ++q) {
      const auto& F = surface.faces[adjacency.vf[q]];
      const std::int8_t a = label.get(F[0]), b = label.get(F[1]), c = label.get(F[2]);
      if (a && b && c && !(a == b && b == c)) sorted_faces.push_back(adjacency.vf[q]);
    }
  std::sort(sorted_faces.begin(), sorted_faces.end());
  sorted_faces.erase(std::unique(sorted_faces.begin(), sorted_faces.end()), sorted_faces.end());
  InterfaceSegments& segments = out.segments;
  segments.clear();
  for (int fi : sorted_faces) {  // every corner labelled, both labels present (the filter above)
    const auto& F = surface.faces[fi];
    const std::array<std::int8_t, 3> l{label.get(F[0]), label.get(F[1]), label.get(F[2])};
    std::array<std::int64_t, 2> seg;
    int m = 0;
    for (int q = 0; q < 3; ++q)
      if (l[q] != l[(q + 1) % 3]) seg[m++] = edge_key(F[q], F[(q + 1) % 3]);
    segments.push_back(seg);
  }
  SegmentsAtEdge& at = out.at;
  at.clear();
  for (int i = 0; i < int(segments.size()); ++i)
    for (auto e : segments[i]) {
      auto it = at.find(e);
      if (it == at.end()) at[e] = {i, -1};
      else it->second[1] = i;
    }
  out.closed.clear();
  std::vector<char> used(segments.size(), 0);
  for (int start = 0; start < int(segments.size()); ++start) {
    if (used[start]) continue;
    InterfaceCurve curve;
    std::int64_t first = segments[start][0], e = segments[start][1];
    int seg = start;
    bool closed = false;
    curve.points.push_back(edge_midpoint(surface, first));
    curve.edges.push_back(first);
    used[seg] = 1;
    for (;;) {
      curve.points.push_back(edge_midpoint(surface, e));
      curve.edges.push_back(e);
      auto& pair = at[e];
      int next = pair[0] == seg ? pair[1] : pair[0];
      if (next < 0 || used[next]) break;
      used[next] = 1;
      seg = next;
      e = segments[seg][0] == e ? segments[seg][1] : segments[seg][0];
      if (e == first) { closed = true; break; }
    }
    if (closed && curve.points.size() >= 3) out.closed.push_back(std::move(curve));
  }
}

std::array<std::vector<int>, 2> label_side_paths(const SurfaceMesh& surface, const std::vector<std::int64_t>& edges,
                                                 const StampedMarks<std::int8_t>& label) {
  std::array<std::vector<int>, 2> paths;
  std::array<double, 2> length{};
  for (int side = 0; side < 2; ++side) {
    std::vector<int>& path = paths[std::size_t(side)];
    path.reserve(edges.size());
    for (std::int64_t e : edges) {
      const int a = int(e >> 32), b = int(e & 0xffffffff);
      const int v = label.get(a) == side + 1 ? a : b;
      if (path.empty() || path.back() != v) path.push_back(v);
    }
    remove_repeats_and_spurs(path);
    length[std::size_t(side)] = path.size() < 3 ? std::numeric_limits<double>::infinity() : loop_length(surface, path);
  }
  if (length[1] < length[0]) std::swap(paths[0], paths[1]);
  return paths;
}

}  // namespace chokeloops::detail

// Tree-cotree homology basis (homology_basis.h).
#include "homology_basis.h"

#include "union_find.h"

#include <algorithm>

namespace chokeloops {

HomologyBasis::HomologyBasis(const SurfaceMesh& mesh, const MeshAdjacency& adj, const std::vector<int>& face_label,
                             const std::vector<char>& closed)
    : mesh_(mesh), adj_(adj), face_label_(face_label) {
  const int F = int(mesh.faces.size()), V = int(mesh.vertices.size());
  const int components = int(closed.size());
  // Fresh pages are much of this constructor's cost on a 17.7M-face surface: one byte a half-edge, and the
  // DFS numbers double as the cotree's "reached" marks (-2 once a face is pushed).
  part_.assign(std::size_t(3) * F, kUnset);
  interval_.assign(F, {-1, 0});
  auto in_basis = [&](int f) {
    const int c = face_label[f];
    return c >= 0 && closed[c];
  };
  // Any spanning trees serve. The primal one is built by union-find over the edges in half-edge order, which
  // reads the mesh front to back; a breadth-first search jumps across it, and on surfaces of millions of
  // faces its cache misses were most of the time.
  {  // Primal tree over the vertices.
    UnionFind vertices{std::size_t(V)};
    for (int h = 0; h < 3 * F; ++h) {
      const int t = adj.twin[h];
      if (t < h || !in_basis(MeshAdjacency::face(h))) continue;
      const auto& tri = mesh.faces[MeshAdjacency::face(h)];
      if (vertices.unite(tri[h % 3], tri[(h + 1) % 3])) part_[h] = part_[t] = kTree;
    }
  }
  // Cotree over the faces, through the edges not in the tree, rooted at each component's first face and
  // numbered depth first as it grows: a face joins when it is first reached, so that the faces below it are
  // numbered right after it, and a marker (~f) pushed under its children closes its interval when they are
  // done. A cotree edge records which of its faces is the one below it.
  constexpr std::int32_t kReached = -2;
  std::vector<int> stack;
  std::int32_t counter = 0;
  for (int root = 0; root < F; ++root) {
    if (interval_[root][0] != -1 || !in_basis(root)) continue;
    interval_[root][0] = kReached;
    stack.assign(1, root);
    while (!stack.empty()) {
      const int f = stack.back();
      stack.pop_back();
      if (f < 0) {
        interval_[~f][1] = counter - 1;
        continue;
      }
      interval_[f][0] = counter++;
      stack.push_back(~f);
      for (int k = 0; k < 3; ++k) {
        const int h = 3 * f + k;
        if (part_[h] != kUnset) continue;
        const int t = adj.twin[h], g = MeshAdjacency::face(t);
        if (interval_[g][0] != -1) continue;
        interval_[g][0] = kReached;
        part_[h] = kCotreeBelowTwin;
        part_[t] = kCotreeBelowHere;
        stack.push_back(g);
      }
    }
  }
  // Leftover edges, numbered component by component.
  leftover_start_.assign(components + 1, 0);
  std::vector<std::vector<int>> per_component(components);
  for (int h = 0; h < 3 * F; ++h) {
    const int t = adj.twin[h];
    const int c = face_label[MeshAdjacency::face(h)];
    if (c < 0 || !closed[c] || part_[h] != kUnset || t < h) continue;
    per_component[c].push_back(h);
  }
  for (int c = 0; c < components; ++c) {
    leftover_start_[c + 1] = leftover_start_[c] + int(per_component[c].size());
    for (int h : per_component[c]) {
      const int t = adj.twin[h];
      part_[h] = part_[t] = kLeftover;
      leftover_edge_.push_back(h);
      leftover_faces_.push_back({interval_[MeshAdjacency::face(h)][0], interval_[MeshAdjacency::face(t)][0]});
    }
  }
}

int HomologyBasis::leftover_index(int lower_halfedge, int component) const {
  const auto begin = leftover_edge_.begin() + leftover_start_[component],
             end = leftover_edge_.begin() + leftover_start_[component + 1];
  return int(std::lower_bound(begin, end, lower_halfedge) - leftover_edge_.begin());
}

bool HomologyBasis::null_homologous(const std::vector<int>& loop) const {
  if (loop.size() < 3) return true;
  const int c = face_label_[adj_.vf[adj_.vf_start[loop[0]]]];  // vf holds faces
  const int begin = leftover_start_[c], end = leftover_start_[c + 1];
  if (begin == end) return true;  // a sphere: every cycle is null
  // Edges used an odd number of times, as the lower half-edge id of each.
  std::vector<int> edges;
  edges.reserve(loop.size());
  for (std::size_t i = 0; i < loop.size(); ++i) {
    int h = adj_.halfedge(mesh_, loop[i], loop[(i + 1) % loop.size()]);
    if (h < 0) h = adj_.halfedge(mesh_, loop[(i + 1) % loop.size()], loop[i]);
    if (h < 0) throw Error("loop vertices are not joined by a mesh edge");
    edges.push_back(std::min(h, adj_.twin[h]));
  }
  std::sort(edges.begin(), edges.end());
  std::vector<char> bits(std::size_t(end - begin), 0);
  // A cotree edge flips the leftover edges with exactly one face in its interval [lo, hi]. Summed over the
  // loop's cotree edges, a leftover edge's bit is the parity of the intervals holding its first face plus
  // those holding its second: with the intervals' ends sorted (lo, and hi + 1), that parity at x is the
  // parity of the ends <= x. Time (cotree edges + 2g) x log, instead of cotree edges x 2g.
  std::vector<std::int32_t> ends;
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i;
    while (j < edges.size() && edges[j] == edges[i]) ++j;
    const bool odd = (j - i) % 2 == 1;
    const int e = edges[i];
    i = j;
    if (!odd || part_[e] == kTree) continue;
    if (part_[e] == kLeftover) {
      bits[leftover_index(e, c) - begin] ^= 1;
      continue;
    }
    const int f = MeshAdjacency::face(part_[e] == kCotreeBelowHere ? e : adj_.twin[e]);  // the face below
    ends.push_back(interval_[f][0]);
    ends.push_back(interval_[f][1] + 1);
  }
  if (!ends.empty()) {
    std::sort(ends.begin(), ends.end());
    auto parity = [&](std::int32_t x) { return char((std::upper_bound(ends.begin(), ends.end(), x) - ends.begin()) & 1); };
    for (int l = begin; l < end; ++l) bits[l - begin] ^= char(parity(leftover_faces_[l][0]) ^ parity(leftover_faces_[l][1]));
  }
  return std::none_of(bits.begin(), bits.end(), [](char b) { return b != 0; });
}

}  // namespace chokeloops

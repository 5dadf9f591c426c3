// Tree-cotree homology basis (homology_basis.h).
#include "homology_basis.h"

#include <algorithm>

namespace chokeloops {

HomologyBasis::HomologyBasis(const SurfaceMesh& mesh, const MeshAdjacency& adj, const std::vector<int>& face_label,
                             const std::vector<char>& closed)
    : mesh_(mesh), adj_(adj), face_label_(face_label) {
  const int F = int(mesh.faces.size()), V = int(mesh.vertices.size());
  const int components = int(closed.size());
  code_.assign(std::size_t(3) * F, kUnset);
  first_.assign(F, -1);
  last_.assign(F, -1);
  // Primal tree: breadth first over the vertices, through the half-edges leaving each vertex.
  std::vector<char> seen_vertex(V, 0);
  std::vector<int> queue;
  auto leaving = [&](int v, auto&& fn) {
    for (int q = adj.vf_start[v]; q < adj.vf_start[v + 1]; ++q) {
      const int f = adj.vf[q];
      for (int k = 0; k < 3; ++k)
        if (mesh.faces[f][k] == v) fn(3 * f + k, mesh.faces[f][(k + 1) % 3]);
    }
  };
  std::vector<char> component_done(components, 0);
  std::vector<int> roots(components, -1);
  for (int f = 0; f < F; ++f) {
    const int c = face_label[f];
    if (c < 0 || !closed[c] || component_done[c]) continue;
    component_done[c] = 1;
    roots[c] = f;
    const int v0 = mesh.faces[f][0];
    seen_vertex[v0] = 1;
    queue.assign(1, v0);
    for (std::size_t i = 0; i < queue.size(); ++i)
      leaving(queue[i], [&](int h, int w) {
        if (seen_vertex[w]) return;
        seen_vertex[w] = 1;
        code_[h] = code_[adj.twin[h]] = kTree;
        queue.push_back(w);
      });
  }
  // Cotree: breadth first over the faces through non-tree edges; then depth-first numbering of it.
  std::vector<int> parent(F, -1);
  std::vector<char> seen_face(F, 0);
  for (int c = 0; c < components; ++c) {
    if (roots[c] < 0) continue;
    queue.assign(1, roots[c]);
    seen_face[roots[c]] = 1;
    for (std::size_t i = 0; i < queue.size(); ++i) {
      const int f = queue[i];
      for (int k = 0; k < 3; ++k) {
        const int h = 3 * f + k, t = adj.twin[h];
        if (code_[h] == kTree) continue;
        const int g = MeshAdjacency::face(t);
        if (seen_face[g]) continue;
        seen_face[g] = 1;
        parent[g] = f;
        code_[h] = code_[t] = 2 * g + 1;
        queue.push_back(g);
      }
    }
  }
  std::vector<int> child_start(F + 1, 0), children;
  for (int f = 0; f < F; ++f)
    if (parent[f] >= 0) ++child_start[parent[f] + 1];
  for (int f = 0; f < F; ++f) child_start[f + 1] += child_start[f];
  children.resize(child_start[F]);
  {
    std::vector<int> fill(child_start.begin(), child_start.end() - 1);
    for (int f = 0; f < F; ++f)
      if (parent[f] >= 0) children[fill[parent[f]]++] = f;
  }
  std::int32_t counter = 0;
  std::vector<int> order;  // preorder
  for (int c = 0; c < components; ++c) {
    if (roots[c] < 0) continue;
    std::vector<int> stack{roots[c]};
    while (!stack.empty()) {
      const int f = stack.back();
      stack.pop_back();
      first_[f] = counter++;
      order.push_back(f);
      for (int q = child_start[f]; q < child_start[f + 1]; ++q) stack.push_back(children[q]);
    }
  }
  // last_ = first_ + subtree size - 1: sizes gathered from the leaves up (reverse preorder).
  std::vector<std::int32_t> size(F, 1);
  for (auto it = order.rbegin(); it != order.rend(); ++it)
    if (parent[*it] >= 0) size[parent[*it]] += size[*it];
  for (int f : order) last_[f] = first_[f] + size[f] - 1;
  // Leftover edges, numbered component by component.
  leftover_start_.assign(components + 1, 0);
  std::vector<std::vector<int>> per_component(components);
  for (int h = 0; h < 3 * F; ++h) {
    const int t = adj.twin[h];
    const int c = face_label[MeshAdjacency::face(h)];
    if (c < 0 || !closed[c] || code_[h] != kUnset || t < h) continue;
    per_component[c].push_back(h);
  }
  for (int c = 0; c < components; ++c) {
    leftover_start_[c + 1] = leftover_start_[c] + int(per_component[c].size());
    for (int h : per_component[c]) {
      const int t = adj.twin[h];
      const int i = int(leftover_faces_.size());
      code_[h] = code_[t] = 2 * i;
      leftover_faces_.push_back({first_[MeshAdjacency::face(h)], first_[MeshAdjacency::face(t)]});
    }
  }
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
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i;
    while (j < edges.size() && edges[j] == edges[i]) ++j;
    const bool odd = (j - i) % 2 == 1;
    const std::int32_t code = code_[edges[i]];
    i = j;
    if (!odd || code == kTree) continue;
    if (code % 2 == 0) {
      bits[code / 2 - begin] ^= 1;
      continue;
    }
    const int f = code / 2;  // the cotree edge above face f
    const std::int32_t lo = first_[f], hi = last_[f];
    for (int l = begin; l < end; ++l) {
      const auto& fl = leftover_faces_[l];
      const bool a = fl[0] >= lo && fl[0] <= hi, b = fl[1] >= lo && fl[1] <= hi;
      bits[l - begin] ^= char(a != b);
    }
  }
  return std::none_of(bits.begin(), bits.end(), [](char b) { return b != 0; });
}

}  // namespace chokeloops

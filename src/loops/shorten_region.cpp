// Step 1 of shorten_loop, before the band: the ring region around the loop and its surface distances.
#include <algorithm>
#include <limits>

#include "shortener.h"

namespace chokeloops::shorten_detail {

RingRegion::RingRegion(const SurfaceMesh& mesh, const MeshAdjacency& adj, const std::vector<int>& loop, int max_rings,
                       bool keep_arcs, std::size_t max_arcs)
    : index(mesh.vertices.size()), mesh_(mesh), adj_(adj), loop_(loop), max_rings_(max_rings) {
  // Each vertex's distance along some path from the loop bounds its surface distance from above: when no
  // bound exceeds max_move, the distances cannot limit the band and need not be computed. The bound is
  // the BFS tree's path, shortened through every region neighbour met later (one pass, BFS order): with
  // the tree's path alone half the cage's handle loops ran the Dijkstra for the band and the rest for the
  // band-edge test, 7% of their time.
  // A band of k rings round a loop of n vertices holds about (2k + 1) n of them: grown once, not a dozen times.
  const std::size_t expected = loop.size() * std::size_t(2 * max_rings + 2);
  vertices.reserve(expected), ring.reserve(expected), upper.reserve(expected);
  if (keep_arcs) arcs_from_.reserve(expected + 1);
  std::size_t arc_count = 0;  // written through a pointer in the BFS's inner loop
  for (int v : loop)
    if (index.emplace(v, int(vertices.size()))) vertices.push_back(v), ring.push_back(0), upper.push_back(0);
  for (std::size_t i = 0; i < vertices.size(); ++i) {
    const int v = vertices[i];
    if (keep_arcs) arcs_from_.push_back(int(arc_count));
    if (ring[i] >= max_rings) continue;
    Arc* arcs_out = nullptr;
    if (keep_arcs) {
      // At most two neighbours per corner of v (MeshAdjacency::for_each_neighbour), a corner per face.
      const std::size_t most = 6 * std::size_t(adj.vf_start[std::size_t(v) + 1] - adj.vf_start[std::size_t(v)]);
      if (arc_count + most > max_arcs) {
        // A region this big (a loop of some hundred thousand vertices) reads the mesh again instead.
        keep_arcs = false;
        arcs_.reset(), arcs_capacity_ = 0;
        arcs_from_.clear(), arcs_from_.shrink_to_fit();
      } else if (arc_count + most > arcs_capacity_) {
        const std::size_t capacity = std::min(max_arcs, std::max(2 * arcs_capacity_, std::max(arc_count + most, 7 * expected)));
        std::unique_ptr<Arc[]> grown(new Arc[capacity]);
        std::copy(arcs_.get(), arcs_.get() + arc_count, grown.get());
        arcs_ = std::move(grown), arcs_capacity_ = capacity;
      }
      arcs_out = arcs_.get();
    }
    // The BFS waits on the mesh's arrays (scattered over tens of megabytes): ask for what the vertices a few
    // places ahead will read, their face lists two stages before their faces.
    if (i + 8 < vertices.size()) {
      const int ahead = vertices[i + 8];
      __builtin_prefetch(&adj.vf_start[std::size_t(ahead)]);
      __builtin_prefetch(&mesh.vertices[std::size_t(ahead)]);
    }
    if (i + 4 < vertices.size()) {
      const int near = vertices[i + 4];
      const int first = adj.vf_start[std::size_t(near)], last = adj.vf_start[std::size_t(near) + 1];
      __builtin_prefetch(&adj.vf[std::size_t(first)]);
      for (int j = first; j < last; ++j) __builtin_prefetch(&mesh.faces[std::size_t(adj.vf[std::size_t(j)])]);
    }
    const auto& p = mesh.vertices[std::size_t(v)];
    // Unsorted (a sort per vertex was a fifth of this step).
    adj.for_each_neighbour(mesh, v, [&](int w) {
      const double length = dist3(p, mesh.vertices[std::size_t(w)]);
      const double through_v = upper[i] + length;
      int wi = int(vertices.size());
      if (index.emplace(w, wi)) {
        vertices.push_back(w), ring.push_back(ring[i] + 1), upper.push_back(through_v);
      } else {
        wi = index.at(w);
        double& bound = upper[std::size_t(wi)];
        bound = std::min(bound, through_v);
      }
      if (arcs_out) arcs_out[arc_count++] = {length, wi};
    });
  }
  if (keep_arcs) arcs_from_.push_back(int(arc_count));
  upper_max = upper.empty() ? 0.0 : *std::max_element(upper.begin(), upper.end());
}

void RingRegion::surface_distances(double max_move, std::vector<double>& dist) const {
  // Only the vertices within max_move are expanded, often a small part of the rings: their neighbours in
  // the region are read as they are (a neighbour met twice across a non-manifold edge costs a repeated
  // arc and nothing else). The BFS's arcs serve every vertex it expanded; those of the last ring, which it
  // did not, read the mesh. The same arcs and lengths as the mesh's give the same distances.
  dist.assign(vertices.size(), std::numeric_limits<double>::infinity());
  thread_local std::vector<QueueEntry> q;  // the thread's, kept between calls
  q.clear();
  for (int v : loop_) {
    const int i = index.at(v);
    dist[std::size_t(i)] = 0, heap_push(q, {0, i});
  }
  const Arc* const arc = arcs_.get();
  while (!q.empty()) {
    // A named entry, not a structured binding: the lambda below captures its distance (C++17).
    const QueueEntry top = heap_pop(q);
    const double d = top.d;
    const int i = top.node;
    if (d > dist[std::size_t(i)] || d > max_move) continue;
    auto relax = [&](int wi, double length) {
      const double nd = d + length;
      if (nd < dist[std::size_t(wi)]) dist[std::size_t(wi)] = nd, heap_push(q, {nd, wi});
    };
    if (ring[std::size_t(i)] < max_rings_ && !arcs_from_.empty()) {
      for (int k = arcs_from_[std::size_t(i)], end = arcs_from_[std::size_t(i) + 1]; k < end; ++k) relax(arc[k].to, arc[k].len);
      continue;
    }
    const auto& p = mesh_.vertices[std::size_t(vertices[std::size_t(i)])];
    adj_.for_each_neighbour(mesh_, vertices[std::size_t(i)], [&](int w) {
      if (const int* wi = index.find(w)) relax(*wi, dist3(p, mesh_.vertices[std::size_t(w)]));
    });
  }
}

}  // namespace chokeloops::shorten_detail

// Loops on TetGen's complex (tet_loops.h).
//
// The grid's flood (loops/two_lobe_flood.h) carried over to an explicit complex: the seeds are the two pieces
// of {below the saddle} that the choke simplex joins, found near the saddle; the flood grows them through the
// side's edges in filtration order (above the saddle: by value; below it: breadth first) inside a ball around
// the saddle. On the grid the zones' contact crosses the marching surface between vertices; here the input's
// vertices are the complex's own, so each input face takes the zone of most of its corners and the loop is a
// boundary curve of the zone-1 faces that borders zone-2 faces only: a closed path of input edges. Where every
// such curve is contractible (a flat core: one zone wraps the other), the same ball is flooded by distance from
// the seeds instead (their bisector), as the grid does.
#include "chokeloops/tet/tet_loops.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <queue>
#include <tuple>

#include "chokeloops/loops/shorten.h"
#include "chokeloops/surface/mesh_adjacency.h"
#include "chokeloops/surface/topology.h"

namespace chokeloops {

namespace {

using P3 = std::array<double, 3>;

double dist(const P3& a, const P3& b) {
  return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

// Vertex neighbours along the edges of one side's tets (CSR, each list in increasing id).
struct Neighbours {
  std::vector<std::int64_t> start;
  std::vector<std::int32_t> to;
  template <class Fn>
  void each(std::int32_t v, Fn&& fn) const {
    for (std::int64_t k = start[std::size_t(v)]; k < start[std::size_t(v) + 1]; ++k) fn(to[std::size_t(k)]);
  }
};

Neighbours neighbours_on_side(const TetField& f, bool inside) {
  std::vector<std::uint64_t> keys;
  for (std::size_t t = 0; t < f.tets.size(); ++t) {
    if (bool(f.inside_tets[t]) != inside) continue;
    const auto& q = f.tets[t];
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b) {
        const std::uint32_t x = std::uint32_t(std::min(q[a], q[b])), y = std::uint32_t(std::max(q[a], q[b]));
        keys.push_back(std::uint64_t(x) << 32 | y);
      }
  }
  tbb::parallel_sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  Neighbours n;
  n.start.assign(f.vertices.size() + 1, 0);
  for (std::uint64_t k : keys) ++n.start[(k >> 32) + 1], ++n.start[(k & 0xffffffffu) + 1];
  for (std::size_t v = 0; v < f.vertices.size(); ++v) n.start[v + 1] += n.start[v];
  n.to.resize(2 * keys.size());
  std::vector<std::int64_t> fill(n.start.begin(), n.start.end() - 1);
  for (std::uint64_t k : keys) {
    const std::int32_t x = std::int32_t(k >> 32), y = std::int32_t(k & 0xffffffffu);
    n.to[std::size_t(fill[std::size_t(x)]++)] = y;
    n.to[std::size_t(fill[std::size_t(y)]++)] = x;
  }
  for (std::size_t v = 0; v < f.vertices.size(); ++v) std::sort(n.to.begin() + n.start[v], n.to.begin() + n.start[v + 1]);
  return n;
}

// Per-thread marks over the complex's vertices and the input's faces, reset through the lists of what was set.
struct Scratch {
  std::vector<std::uint8_t> zone;     // per vertex: 0 unreached, 1 or 2
  std::vector<std::int32_t> touched;
  std::vector<std::int8_t> face_zone;  // per input face: 0 unlabelled, 1 or 2
  std::vector<int> faces;
  void prepare(std::size_t vertices, std::size_t input_faces) {
    if (zone.size() != vertices) zone.assign(vertices, 0);
    if (face_zone.size() != input_faces) face_zone.assign(input_faces, 0);
  }
  void set(std::int32_t v, std::uint8_t z) {
    if (!zone[std::size_t(v)]) touched.push_back(v);
    zone[std::size_t(v)] = z;
  }
  void clear() {
    for (std::int32_t v : touched) zone[std::size_t(v)] = 0;
    touched.clear();
    for (int f : faces) face_zone[std::size_t(f)] = 0;
    faces.clear();
  }
};

struct Context {
  const TetField& field;
  const SurfaceMesh& mesh;
  const MeshAdjacency& adj;
  SurfaceTopology& topology;
  const Neighbours& inside;
  const Neighbours& outside;
  const std::vector<std::int64_t>& tet_start;  // tets around each vertex (CSR)
  const std::vector<std::int32_t>& tet_of;
  const TetLoopOptions& options;
  double unit = 0;    // the lattice's spacing, capped for meshes tetrahedralized without interior points
  double extent = 0;  // the box's diagonal: no ball needs to be larger
};

enum class Attempt { Found, NoCurve, Joined };

class ChokeTracer {
 public:
  ChokeTracer(const Context& cx, const Choke& c, const std::array<std::int32_t, 4>& simplex, Scratch& s)
      : cx_(cx), c_(c), simplex_(simplex), s_(s), handle_(c.side == Side::Handle), saddle_(std::int32_t(c.saddle)),
        adjacency_(handle_ ? cx.inside : cx.outside), centre_(cx.field.vertices[std::size_t(c.saddle)]) {}

  void trace(InputLoop& out) {
    out.loop.choke = c_;
    if (saddle_ < 0 || std::size_t(saddle_) >= cx_.field.vertices.size()) {
      out.loop.note = "the choke has no saddle vertex on the complex";
      return;
    }
    lobes_ = lobe_candidates();
    double seed_radius = c_.depth + cx_.options.box_margin * cx_.unit;
    double r = cx_.options.box_factor * c_.depth + cx_.options.box_margin * cx_.unit;
    std::string why = "the membrane did not close on the input surface in any ball up to the whole box";
    for (int step = 0; step < 64; ++step) {
      Attempt a = flood(r, seed_radius, false, out);
      if (a == Attempt::NoCurve) a = flood(r, seed_radius, true, out);
      if (a == Attempt::Found) return;
      if (a == Attempt::Joined) {
        if (seed_radius <= 0) {
          why = "the two sides of the choke simplex are one piece below it";
          break;
        }
        seed_radius = seed_radius < cx_.unit ? 0 : seed_radius / 2;
        continue;
      }
      if (r >= cx_.extent) break;
      r = std::min(cx_.extent, r * 1.5);
    }
    out.loop.found = false;
    out.loop.note = why;
  }

 private:
  bool below(std::int32_t v) const {
    const auto& f = cx_.field.values;
    const std::int32_t a = handle_ ? v : saddle_, b = handle_ ? saddle_ : v;
    return f[std::size_t(a)] < f[std::size_t(b)] || (f[std::size_t(a)] == f[std::size_t(b)] && a < b);
  }
  // Distance from the saddle in the flood's direction: 0 up to it, growing toward the surface.
  double level(std::int32_t v) const {
    const double d = cx_.field.values[std::size_t(v)] - cx_.field.values[std::size_t(saddle_)];
    return std::max(0.0, handle_ ? d : -d);
  }
  bool in_ball(std::int32_t v, double r) const { return dist(cx_.field.vertices[std::size_t(v)], centre_) <= r; }

  // The lobes, best first: for a handle's edge its other vertex, for a tunnel's triangle the far corners of
  // the two tets on it; then every neighbour of the saddle below it, in filtration order.
  std::vector<std::int32_t> lobe_candidates() const {
    std::vector<std::int32_t> out;
    if (handle_) {
      for (std::int32_t v : simplex_)
        if (v >= 0 && v != saddle_) out.push_back(v);
    } else {
      std::array<std::int32_t, 3> t{simplex_[0], simplex_[1], simplex_[2]};
      for (std::int64_t k = cx_.tet_start[std::size_t(saddle_)]; k < cx_.tet_start[std::size_t(saddle_) + 1]; ++k) {
        const auto& q = cx_.field.tets[std::size_t(cx_.tet_of[std::size_t(k)])];
        if (cx_.field.inside_tets[std::size_t(cx_.tet_of[std::size_t(k)])]) continue;
        int shared = 0;
        std::int32_t far = -1;
        for (std::int32_t v : q) {
          if (v == t[0] || v == t[1] || v == t[2]) ++shared;
          else far = v;
        }
        if (shared == 3) out.push_back(far);
      }
    }
    std::vector<std::int32_t> low;
    adjacency_.each(saddle_, [&](std::int32_t u) {
      if (below(u)) low.push_back(u);
    });
    std::sort(low.begin(), low.end(), [&](std::int32_t a, std::int32_t b) {
      const double fa = cx_.field.values[std::size_t(a)], fb = cx_.field.values[std::size_t(b)];
      return handle_ ? (fa < fb || (fa == fb && a < b)) : (fa > fb || (fa == fb && a > b));
    });
    out.insert(out.end(), low.begin(), low.end());
    return out;
  }

  // Labels the piece of {below the saddle} around `lobe` within `radius` of the saddle with `zone`; false when
  // it meets the other zone. The lobe itself is always in its piece.
  bool grow_piece(std::int32_t lobe, std::uint8_t zone, double radius, std::vector<std::int32_t>& piece) {
    s_.set(lobe, zone);
    std::size_t first = piece.size();
    piece.push_back(lobe);
    for (std::size_t q = first; q < piece.size(); ++q) {
      bool joined = false;
      adjacency_.each(piece[q], [&](std::int32_t u) {
        if (u == saddle_ || !below(u) || !in_ball(u, radius)) return;
        const std::uint8_t z = s_.zone[std::size_t(u)];
        if (z == 0) s_.set(u, zone), piece.push_back(u);
        else if (z != zone) joined = true;
      });
      if (joined) return false;
    }
    return true;
  }

  Attempt flood(double r, double seed_radius, bool by_distance, InputLoop& out) {
    s_.clear();
    s_.set(saddle_, 3);  // the saddle joins the pieces: neither seed grows through it
    std::vector<std::int32_t> seeds;
    int lobes = 0;
    for (std::int32_t v : lobes_) {
      if (lobes == 2) break;
      if (!below(v) || s_.zone[std::size_t(v)] != 0) continue;
      if (!grow_piece(v, std::uint8_t(lobes + 1), seed_radius, seeds)) {
        s_.clear();
        return Attempt::Joined;
      }
      ++lobes;
    }
    if (lobes < 2) {
      s_.clear();
      return Attempt::Joined;
    }
    s_.zone[std::size_t(saddle_)] = 0;  // the saddle is flooded like any vertex
    using Item = std::tuple<double, std::uint64_t, std::int32_t>;
    std::priority_queue<Item, std::vector<Item>, std::greater<Item>> queue;
    std::uint64_t order = 0;
    for (std::int32_t v : seeds) queue.emplace(0.0, order++, v);
    std::vector<std::int32_t> shore;  // labelled input vertices
    const auto& pos = cx_.field.vertices;
    while (!queue.empty()) {
      // Named copies, not structured bindings: a lambda may capture those only from C++20 (clang refuses).
      const double key = std::get<0>(queue.top());
      const std::int32_t x = std::get<2>(queue.top());
      queue.pop();
      const std::uint8_t z = s_.zone[std::size_t(x)];
      if (x < cx_.field.input_vertices) shore.push_back(x);
      adjacency_.each(x, [&](std::int32_t u) {
        if (s_.zone[std::size_t(u)] != 0 || !in_ball(u, r)) return;
        s_.set(u, z);
        const double k = by_distance ? key + dist(pos[std::size_t(x)], pos[std::size_t(u)]) : std::max(key, level(u));
        queue.emplace(k, order++, u);
      });
    }
    return loop_on_input(shore, out) ? Attempt::Found : Attempt::NoCurve;
  }

  // Each input face around the labelled input vertices takes the zone of most of its corners (none when a corner
  // is unlabelled); the loop is the nearest boundary curve of the zone-1 faces that borders zone-2 faces only.
  bool loop_on_input(const std::vector<std::int32_t>& shore, InputLoop& out) {
    const SurfaceMesh& m = cx_.mesh;
    const MeshAdjacency& adj = cx_.adj;
    for (std::int32_t v : shore)
      for (int k = adj.vf_start[std::size_t(v)]; k < adj.vf_start[std::size_t(v) + 1]; ++k) {
        const int f = adj.vf[std::size_t(k)];
        if (s_.face_zone[std::size_t(f)] != 0) continue;
        int ones = 0, twos = 0;
        for (int c : m.faces[std::size_t(f)]) {
          const std::uint8_t z = s_.zone[std::size_t(c)];
          ones += z == 1, twos += z == 2;
        }
        if (ones + twos < 3) continue;
        s_.face_zone[std::size_t(f)] = std::int8_t(ones > twos ? 1 : 2);
        s_.faces.push_back(f);
      }
    auto zone_of_face = [&](int h) { return h < 0 ? 0 : int(s_.face_zone[std::size_t(MeshAdjacency::face(h))]); };
    auto is_boundary = [&](int h) { return zone_of_face(adj.twin[std::size_t(h)]) != 1; };
    auto next_boundary = [&](int h) {
      int g = MeshAdjacency::next(h);
      for (int guard = 0; !is_boundary(g) && guard < 1 << 20; ++guard) g = MeshAdjacency::next(adj.twin[std::size_t(g)]);
      return g;
    };
    // Boundary curves of the zone-1 faces, split where they touch themselves into simple ones.
    std::vector<std::vector<int>> candidates;
    std::vector<int> boundary;
    for (int f : s_.faces)
      if (s_.face_zone[std::size_t(f)] == 1)
        for (int k = 0; k < 3; ++k)
          if (is_boundary(3 * f + k)) boundary.push_back(3 * f + k);
    std::sort(boundary.begin(), boundary.end());
    std::vector<char> done(boundary.size(), 0);  // per boundary half-edge, in `boundary`'s order
    auto index_of = [&](int h) { return std::size_t(std::lower_bound(boundary.begin(), boundary.end(), h) - boundary.begin()); };
    for (std::size_t i0 = 0; i0 < boundary.size(); ++i0) {
      if (done[i0]) continue;
      std::vector<int> cycle;
      const int h0 = boundary[i0];
      int h = h0;
      do {
        cycle.push_back(h);
        done[index_of(h)] = 1;
        h = next_boundary(h);
      } while (h != h0 && cycle.size() <= boundary.size());
      split_into_simple(cycle, zone_of_face, candidates);
    }
    // Nearest first.
    std::vector<std::pair<double, std::size_t>> order;
    for (std::size_t i = 0; i < candidates.size(); ++i) {
      double d = std::numeric_limits<double>::infinity();
      for (int v : candidates[i]) d = std::min(d, dist(m.vertices[std::size_t(v)], centre_));
      order.push_back({d, i});
    }
    std::sort(order.begin(), order.end());
    const bool generator = c_.kind == Kind::Generator;
    for (const auto& [d, i] : order) {
      (void)d;
      const std::vector<int>& path = candidates[i];
      if (generator && cx_.topology.contractible_fast(path)) continue;
      return finish(path, out);
    }
    return false;
  }

  // A boundary cycle (half-edges) that visits a vertex twice is cut there into simple loops; those that border
  // zone-2 faces along their whole length are candidates (vertex lists).
  template <class ZoneOfFace>
  void split_into_simple(const std::vector<int>& cycle, ZoneOfFace&& zone_of_face, std::vector<std::vector<int>>& out) const {
    const MeshAdjacency& adj = cx_.adj;
    const SurfaceMesh& m = cx_.mesh;
    std::vector<int> stack_v;
    std::vector<char> stack_ok;
    for (int h : cycle) {
      const int v = m.faces[std::size_t(MeshAdjacency::face(h))][std::size_t(h % 3)];
      const char ok = zone_of_face(adj.twin[std::size_t(h)]) == 2;
      auto at = std::find(stack_v.begin(), stack_v.end(), v);
      if (at != stack_v.end()) {
        const std::size_t from = std::size_t(at - stack_v.begin());
        std::vector<int> loop(stack_v.begin() + std::ptrdiff_t(from), stack_v.end());
        bool all = std::all_of(stack_ok.begin() + std::ptrdiff_t(from), stack_ok.end(), [](char x) { return x != 0; });
        if (all && loop.size() >= 3) out.push_back(loop);
        stack_v.resize(from);
        stack_ok.resize(from);
      }
      stack_v.push_back(v);
      stack_ok.push_back(ok);
    }
    if (stack_v.size() >= 3 && std::all_of(stack_ok.begin(), stack_ok.end(), [](char x) { return x != 0; })) out.push_back(stack_v);
  }

  bool finish(const std::vector<int>& path, InputLoop& out) {
    const SurfaceMesh& m = cx_.mesh;
    ShortenResult s;
    if (cx_.options.shorten) {
      ShortenOptions so;
      so.max_rings = cx_.options.max_rings;
      s = shorten_loop(m, cx_.adj, path, so);
    } else {
      s.edge_path = path;
      s.points = loop_points(m, path);
    }
    const bool generator = c_.kind == Kind::Generator;
    Loop& l = out.loop;
    l.raw_length = loop_length(m, path);
    if (generator && cx_.topology.contractible_fast(s.edge_path)) {
      l.note = "the shortened loop is contractible on the input (its class was lost): left unshortened";
      s.edge_path = path;
      s.points = loop_points(m, path);
      s.strip_faces.clear();
    } else if (cx_.options.shorten && s.rings == 0) {
      l.note = "left unshortened: no annulus band around it on the input mesh";
    }
    out.separating = cx_.topology.separates(s.edge_path);
    out.verified = generator ? true : (out.separating || !cx_.topology.contractible_fast(s.edge_path));
    l.found = true;
    l.points = s.points;
    l.edge_path = s.edge_path;
    out.where = locate_loop_points(m, cx_.adj, s);
    describe_loop(l);
    return true;
  }

  const Context& cx_;
  const Choke& c_;
  const std::array<std::int32_t, 4>& simplex_;
  Scratch& s_;
  const bool handle_;
  const std::int32_t saddle_;
  const Neighbours& adjacency_;
  const P3 centre_;
  std::vector<std::int32_t> lobes_;  // lobe_candidates(), the same for every flood of this choke
};

}  // namespace

std::vector<InputLoop> trace_tet_loops(const TetField& field, const SurfaceMesh& input, const std::vector<Choke>& chokes,
                                       const std::vector<std::array<std::int32_t, 4>>& choke_simplices,
                                       const TetLoopOptions& options) {
  std::vector<InputLoop> out(chokes.size());
  if (chokes.empty()) return out;
  if (std::int64_t(input.vertices.size()) != field.input_vertices)
    throw InternalError("tet loops: the input mesh has " + std::to_string(input.vertices.size()) + " vertices, the complex " +
                        std::to_string(field.input_vertices));
  const Neighbours inside = neighbours_on_side(field, true), outside = neighbours_on_side(field, false);
  std::vector<std::int64_t> tet_start(field.vertices.size() + 1, 0);
  for (const auto& t : field.tets)
    for (std::int32_t v : t) ++tet_start[std::size_t(v) + 1];
  for (std::size_t v = 0; v < field.vertices.size(); ++v) tet_start[v + 1] += tet_start[v];
  std::vector<std::int32_t> tet_of(std::size_t(tet_start.back()));
  {
    std::vector<std::int64_t> fill(tet_start.begin(), tet_start.end() - 1);
    for (std::size_t t = 0; t < field.tets.size(); ++t)
      for (std::int32_t v : field.tets[t]) tet_of[std::size_t(fill[std::size_t(v)]++)] = std::int32_t(t);
  }
  const MeshAdjacency adj = build_adjacency(input);
  SurfaceTopology topology(input, adj);
  P3 lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
  for (const auto& p : field.vertices)
    for (int a = 0; a < 3; ++a) lo[std::size_t(a)] = std::min(lo[std::size_t(a)], p[std::size_t(a)]), hi[std::size_t(a)] = std::max(hi[std::size_t(a)], p[std::size_t(a)]);
  Context cx{field, input, adj, topology, inside, outside, tet_start, tet_of, options};
  cx.extent = dist(lo, hi);
  cx.unit = std::min(field.spacing > 0 ? field.spacing : cx.extent / 64, cx.extent / 64);
  tbb::enumerable_thread_specific<Scratch> scratch;
  tbb::parallel_for(std::size_t(0), chokes.size(), [&](std::size_t i) {
    const auto t0 = std::chrono::steady_clock::now();
    const Choke& c = chokes[i];
    Scratch& s = scratch.local();
    s.prepare(field.vertices.size(), input.faces.size());
    static const std::array<std::int32_t, 4> kNone{-1, -1, -1, -1};
    const auto& simplex = c.simplex >= 0 && std::size_t(c.simplex) < choke_simplices.size() ? choke_simplices[std::size_t(c.simplex)] : kNone;
    ChokeTracer(cx, c, simplex, s).trace(out[i]);
    s.clear();
    out[i].transfer_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  });
  return out;
}

}  // namespace chokeloops

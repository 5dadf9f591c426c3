#pragma once
// The implicit Freudenthal (Kuhn) triangulation of a box of grid vertices: every cube is split into six
// tetrahedra sharing its main diagonal. Nothing is stored per simplex; ids and faces come from indices.
//
// Ids. A simplex is named by its base vertex v (the corner with the smallest coordinates) and a local code:
//   edge     = 7*v  + (m-1)        vertices v, v+m                     m = nonzero subset of {x,y,z}
//   triangle = 12*v + t            vertices v, v+u, v+u+w              (u,w) disjoint nonempty subsets, t = their index
//   tet      = 6*v  + p            vertices v, v+a, v+a+b, v+(1,1,1)   (a,b,c) the p-th permutation of the axes
// A subset is a 3-bit mask (bit 0 = x). An id is valid when all its vertices lie in the box.
// Each vertex has 14 neighbours (±the seven masks); the complex is a flag complex, so any set of pairwise
// adjacent vertices is a simplex.
#include <algorithm>
#include <array>
#include <cstdint>

#include "chokeloops/grid.h"

namespace chokeloops {

using Id = std::int64_t;

namespace freudenthal {

// Offset (dx,dy,dz) of the 3-bit subset mask m.
inline std::array<int, 3> mask_offset(int m) { return {m & 1, (m >> 1) & 1, (m >> 2) & 1}; }

// The 14 neighbours of a vertex: index n < 7 is +mask(n+1), n >= 7 is -mask(n-6).
inline std::array<int, 3> neighbor_offset(int n) {
  auto o = mask_offset(n < 7 ? n + 1 : n - 6);
  if (n >= 7) o = {-o[0], -o[1], -o[2]};
  return o;
}

// (u,w) for triangle code t: the 12 ordered pairs of disjoint nonempty masks.
struct TriangleCode { int u, w; };
inline const std::array<TriangleCode, 12>& triangle_codes() {
  static const std::array<TriangleCode, 12> codes = [] {
    std::array<TriangleCode, 12> c{};
    int n = 0;
    for (int u = 1; u < 8; ++u)
      for (int w = 1; w < 8; ++w)
        if ((u & w) == 0) c[n++] = {u, w};
    return c;
  }();
  return codes;
}
// Permutation p of the axes, as three single-bit masks.
inline std::array<int, 3> tet_axes(int p) {
  static const int perms[6][3] = {{1, 2, 4}, {1, 4, 2}, {2, 1, 4}, {2, 4, 1}, {4, 1, 2}, {4, 2, 1}};
  return {perms[p][0], perms[p][1], perms[p][2]};
}

// Link of a vertex: a triangulated 2-sphere on the 14 neighbours, with 36 edges and 24 triangles.
struct Link {
  std::array<std::array<int, 2>, 36> edges;
  std::array<std::array<int, 3>, 24> triangles;
  std::array<std::uint16_t, 14> adjacency;  // bit b of adjacency[a]: a and b are joined by a link edge
  // For each link edge, the two link triangles containing it.
  std::array<std::array<int, 2>, 36> edge_triangles;
};
const Link& vertex_link();

}  // namespace freudenthal

// Division of a 31-bit index by a fixed divisor as a multiply and a shift (round-up reciprocal): exact for every
// n < 2^31 and d < 2^31, and ~10x cheaper than the division it replaces in the coordinates of a vertex.
struct DivideBy31 {
  std::uint64_t magic = 0;
  int shift = 0;
  DivideBy31() = default;
  explicit DivideBy31(std::uint64_t d) {
    int l = 0;
    while ((std::uint64_t(1) << l) < d) ++l;
    shift = 32 + l;
    magic = std::uint64_t(((unsigned __int128)1 << shift) / d + (((unsigned __int128)1 << shift) % d != 0));
  }
  std::uint64_t operator()(std::uint64_t n) const { return (n * magic) >> shift; }
};

class FreudenthalComplex {
 public:
  explicit FreudenthalComplex(std::array<int, 3> dims) : dims_(dims) {
    sx_ = 1;
    sy_ = dims[0];
    sz_ = Id(dims[0]) * dims[1];
    fast_ = dims[0] > 0 && sz_ > 0 && sz_ < (Id(1) << 31);
    if (fast_) by_x_ = DivideBy31(std::uint64_t(dims[0])), by_slice_ = DivideBy31(std::uint64_t(sz_));
  }
  const std::array<int, 3>& dims() const { return dims_; }
  Id vertex_count() const { return sz_ * dims_[2]; }
  Id edge_id_bound() const { return 7 * vertex_count(); }
  Id triangle_id_bound() const { return 12 * vertex_count(); }
  Id tet_id_bound() const { return 6 * vertex_count(); }

  std::array<int, 3> coords(Id v) const {
    if (fast_ && std::uint64_t(v) < (std::uint64_t(1) << 31)) {
      const std::uint64_t z = by_slice_(std::uint64_t(v)), r = std::uint64_t(v) - z * std::uint64_t(sz_);
      const std::uint64_t y = by_x_(r);
      return {int(r - y * std::uint64_t(dims_[0])), int(y), int(z)};
    }
    return {int(v % dims_[0]), int((v / dims_[0]) % dims_[1]), int(v / sz_)};
  }
  Id vertex(int i, int j, int k) const { return i + sy_ * j + sz_ * k; }
  bool inside(int i, int j, int k) const {
    return i >= 0 && j >= 0 && k >= 0 && i < dims_[0] && j < dims_[1] && k < dims_[2];
  }
  Id offset(int m) const { return (m & 1 ? sx_ : 0) + (m & 2 ? sy_ : 0) + (m & 4 ? sz_ : 0); }
  // Linear offset of neighbour n (see freudenthal::neighbor_offset); check `neighbor_inside` first.
  Id neighbor_delta(int n) const { return n < 7 ? offset(n + 1) : -offset(n - 6); }
  bool neighbor_inside(const std::array<int, 3>& c, int n) const {
    auto o = freudenthal::neighbor_offset(n);
    return inside(c[0] + o[0], c[1] + o[1], c[2] + o[2]);
  }
  // True when base vertex v plus mask m stays in the box.
  bool corner_inside(Id v, int m) const {
    auto c = coords(v);
    auto o = freudenthal::mask_offset(m);
    return c[0] + o[0] < dims_[0] && c[1] + o[1] < dims_[1] && c[2] + o[2] < dims_[2];
  }

  bool edge_valid(Id e) const { return e >= 0 && e < edge_id_bound() && corner_inside(e / 7, int(e % 7) + 1); }
  bool triangle_valid(Id t) const {
    if (t < 0 || t >= triangle_id_bound()) return false;
    auto c = freudenthal::triangle_codes()[t % 12];
    return corner_inside(t / 12, c.u | c.w);
  }
  bool tet_valid(Id T) const { return T >= 0 && T < tet_id_bound() && corner_inside(T / 6, 7); }

  std::array<Id, 2> edge_vertices(Id e) const { Id v = e / 7; return {v, v + offset(int(e % 7) + 1)}; }
  std::array<Id, 3> triangle_vertices(Id t) const {
    Id v = t / 12;
    auto c = freudenthal::triangle_codes()[t % 12];
    return {v, v + offset(c.u), v + offset(c.u | c.w)};
  }
  std::array<Id, 4> tet_vertices(Id T) const {
    Id v = T / 6;
    auto a = freudenthal::tet_axes(int(T % 6));
    return {v, v + offset(a[0]), v + offset(a[0] | a[1]), v + offset(7)};
  }

  // Id of the simplex spanned by the given vertices (any order), or -1 when they span no simplex.
  Id edge_id(Id a, Id b) const;
  Id triangle_id(Id a, Id b, Id c) const;
  Id tet_id(Id a, Id b, Id c, Id d) const;

  std::array<Id, 3> triangle_edges(Id t) const {
    auto v = triangle_vertices(t);
    return {edge_id(v[0], v[1]), edge_id(v[0], v[2]), edge_id(v[1], v[2])};
  }
  std::array<Id, 4> tet_triangles(Id T) const {
    auto v = tet_vertices(T);
    return {triangle_id(v[1], v[2], v[3]), triangle_id(v[0], v[2], v[3]), triangle_id(v[0], v[1], v[3]),
            triangle_id(v[0], v[1], v[2])};
  }

  // Number of valid simplices of each dimension, by closed formulas.
  std::array<Id, 4> simplex_counts() const;

 private:
  std::array<int, 3> dims_;
  Id sx_, sy_, sz_;
  bool fast_ = false;  // coordinates by DivideBy31 (the slice size and every index below 2^31)
  DivideBy31 by_x_, by_slice_;
};

// The total order on vertices: by value, then by linear index (the symbolic perturbation).
inline bool vertex_less(const float* f, Id a, Id b) { return f[a] < f[b] || (f[a] == f[b] && a < b); }

// Lexicographic order of simplices of a lower-star filtration: compare the vertex lists sorted from
// highest to lowest; a proper prefix (a face) comes first. This is the filtration every stage uses.
template <size_t N>
std::array<Id, N> sorted_descending(const float* f, std::array<Id, N> v) {
  std::sort(v.begin(), v.end(), [f](Id a, Id b) { return vertex_less(f, b, a); });
  return v;
}
template <size_t N, size_t M>
bool simplex_less(const float* f, const std::array<Id, N>& a_desc, const std::array<Id, M>& b_desc) {
  for (size_t i = 0; i < std::min(N, M); ++i) {
    if (a_desc[i] == b_desc[i]) continue;
    return vertex_less(f, a_desc[i], b_desc[i]);
  }
  return N < M;
}

}  // namespace chokeloops

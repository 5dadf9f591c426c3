#include "chokeloops/topology/complex.h"

#include <cmath>
#include <sstream>

#include "chokeloops/grid.h"
#include "common/first_non_finite.h"

namespace chokeloops {

void validate_grid(const ScalarGrid& grid) {
  for (int d : grid.dims)
    if (d < 2) throw Error("grid is empty or flat (dims " + std::to_string(grid.dims[0]) + "x" +
                           std::to_string(grid.dims[1]) + "x" + std::to_string(grid.dims[2]) + "); need at least 2 vertices per axis");
  if (Id(grid.values.size()) != grid.vertex_count()) throw Error("grid storage does not match its dimensions");
  if (grid.vertex_count() >= (Id(1) << 31)) throw Error("grid has more than 2^31 vertices; use a coarser resolution", 3);
  const std::size_t n = grid.values.size(), first = detail::first_non_finite(grid.values.data(), n);
  if (first < n) {
    std::ostringstream s;
    s << "grid value at vertex " << first << " is not finite (" << grid.values[first] << ")";
    throw Error(s.str());
  }
}

namespace freudenthal {

static bool is_step(std::array<int, 3> d) {  // d is ±(a nonzero 0/1 vector)
  bool pos = d[0] >= 0 && d[1] >= 0 && d[2] >= 0 && d[0] <= 1 && d[1] <= 1 && d[2] <= 1;
  bool neg = d[0] <= 0 && d[1] <= 0 && d[2] <= 0 && d[0] >= -1 && d[1] >= -1 && d[2] >= -1;
  return (pos || neg) && (d[0] || d[1] || d[2]);
}

const Link& vertex_link() {
  static const Link link = [] {
    Link L{};
    int ne = 0, nt = 0;
    for (int a = 0; a < 14; ++a) {
      L.adjacency[a] = 0;
      for (int b = 0; b < 14; ++b) {
        auto oa = neighbor_offset(a), ob = neighbor_offset(b);
        if (a != b && is_step({ob[0] - oa[0], ob[1] - oa[1], ob[2] - oa[2]})) L.adjacency[a] |= std::uint16_t(1u << b);
      }
    }
    for (int a = 0; a < 14; ++a)
      for (int b = a + 1; b < 14; ++b)
        if (L.adjacency[a] >> b & 1) L.edges[ne++] = {a, b};
    for (int a = 0; a < 14; ++a)
      for (int b = a + 1; b < 14; ++b)
        for (int c = b + 1; c < 14; ++c)
          if ((L.adjacency[a] >> b & 1) && (L.adjacency[a] >> c & 1) && (L.adjacency[b] >> c & 1))
            L.triangles[nt++] = {a, b, c};
    if (ne != 36 || nt != 24) throw InternalError("Freudenthal link is not a 14-vertex sphere");
    for (int e = 0; e < 36; ++e) {
      int n = 0;
      for (int t = 0; t < 24; ++t) {
        auto& tr = L.triangles[t];
        int hits = (tr[0] == L.edges[e][0] || tr[1] == L.edges[e][0] || tr[2] == L.edges[e][0]) +
                   (tr[0] == L.edges[e][1] || tr[1] == L.edges[e][1] || tr[2] == L.edges[e][1]);
        if (hits == 2) L.edge_triangles[e][n++] = t;
      }
      if (n != 2) throw InternalError("Freudenthal link edge is not shared by two triangles");
    }
    return L;
  }();
  return link;
}

}  // namespace freudenthal

namespace {
// Mask of the 0/1 vector q - p, or -1 when q - p is not such a vector.
int step_mask(const std::array<int, 3>& p, const std::array<int, 3>& q) {
  int m = 0;
  for (int a = 0; a < 3; ++a) {
    int d = q[a] - p[a];
    if (d < 0 || d > 1) return -1;
    if (d) m |= 1 << a;
  }
  return m;
}
template <size_t N>
void sort_by_coordinate_sum(std::array<std::array<int, 3>, N>& c, std::array<Id, N>& v) {
  for (size_t i = 1; i < N; ++i)
    for (size_t j = i; j > 0 && c[j][0] + c[j][1] + c[j][2] < c[j - 1][0] + c[j - 1][1] + c[j - 1][2]; --j) {
      std::swap(c[j], c[j - 1]);
      std::swap(v[j], v[j - 1]);
    }
}
}  // namespace

Id FreudenthalComplex::edge_id(Id a, Id b) const {
  std::array<Id, 2> v{a, b};
  std::array<std::array<int, 3>, 2> c{coords(a), coords(b)};
  sort_by_coordinate_sum(c, v);
  int m = step_mask(c[0], c[1]);
  return m > 0 ? 7 * v[0] + (m - 1) : -1;
}

Id FreudenthalComplex::triangle_id(Id a, Id b, Id c) const {
  std::array<Id, 3> v{a, b, c};
  std::array<std::array<int, 3>, 3> p{coords(a), coords(b), coords(c)};
  sort_by_coordinate_sum(p, v);
  int u = step_mask(p[0], p[1]), w = step_mask(p[1], p[2]);
  if (u <= 0 || w <= 0 || (u & w)) return -1;
  const auto& codes = freudenthal::triangle_codes();
  for (int t = 0; t < 12; ++t)
    if (codes[t].u == u && codes[t].w == w) return 12 * v[0] + t;
  return -1;
}

Id FreudenthalComplex::tet_id(Id a, Id b, Id c, Id d) const {
  std::array<Id, 4> v{a, b, c, d};
  std::array<std::array<int, 3>, 4> p{coords(a), coords(b), coords(c), coords(d)};
  sort_by_coordinate_sum(p, v);
  int m0 = step_mask(p[0], p[1]), m1 = step_mask(p[1], p[2]), m2 = step_mask(p[2], p[3]);
  if (m0 <= 0 || m1 <= 0 || m2 <= 0 || (m0 | m1 | m2) != 7 || (m0 & m1) || (m1 & m2) || (m0 & m2)) return -1;
  for (int q = 0; q < 6; ++q) {
    auto ax = freudenthal::tet_axes(q);
    if (ax[0] == m0 && ax[1] == m1) return 6 * v[0] + q;
  }
  return -1;
}

std::array<Id, 4> FreudenthalComplex::simplex_counts() const {
  auto count_with = [&](int m) {
    auto o = freudenthal::mask_offset(m);
    return Id(dims_[0] - o[0]) * (dims_[1] - o[1]) * (dims_[2] - o[2]);
  };
  Id e = 0, t = 0;
  for (int m = 1; m < 8; ++m) e += count_with(m);
  for (auto c : freudenthal::triangle_codes()) t += count_with(c.u | c.w);
  return {vertex_count(), e, t, 6 * count_with(7)};
}

}  // namespace chokeloops

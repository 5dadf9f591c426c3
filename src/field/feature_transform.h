#pragma once
// Private to src/field: the exact feature transform of levelset_edt.cpp (same declaration as levelset.cpp's).
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cstdint>
#include <vector>

#include "chokeloops/grid.h"
#include "common/grid_array.h"

namespace chokeloops::detail {

struct Site {
  std::int64_t vertex;  // linear index of the site vertex
  float p[3];           // boundary point, in grid index units (vertex (i,j,k) at (i,j,k))
};
// Vertices not `known` get sign * distance (per-axis spacing) to the point of their nearest site.
void complete_by_feature_transform(ScalarGrid& grid, const std::vector<std::uint8_t>& known,
                                   const std::vector<Site>& sites, GridArray<std::int32_t>* nearest_site = nullptr);
// Each vertex's nearest site by the same transform (-1 where there is none), the grid left as it is: for a
// caller that computes the values itself.
GridArray<std::int32_t> nearest_sites(const ScalarGrid& grid, const std::vector<Site>& sites);

// The sites of a grid, in vertex order: site_at(i, j, k, v, site) fills `site` and returns true for each
// vertex (i, j, k) of linear index v that is one. Slices run in parallel; the order does not depend on it.
template <class SiteAt>
std::vector<Site> collect_sites(const ScalarGrid& g, SiteAt&& site_at) {
  std::vector<std::vector<Site>> per_slice(static_cast<std::size_t>(g.dims[2]));
  tbb::parallel_for(tbb::blocked_range<int>(0, g.dims[2]), [&](const tbb::blocked_range<int>& r) {
    for (int k = r.begin(); k != r.end(); ++k)
      for (int j = 0; j < g.dims[1]; ++j)
        for (int i = 0; i < g.dims[0]; ++i) {
          Site site;
          if (site_at(i, j, k, g.index(i, j, k), site)) per_slice[std::size_t(k)].push_back(site);
        }
  });
  std::vector<Site> sites;
  for (auto& slice : per_slice) sites.insert(sites.end(), slice.begin(), slice.end());
  return sites;
}

// The nearest sign change along the six grid edges at vertex v (linear interpolation): its axis, direction
// (-1, +1) and parameter t in [0, 1) along the edge; false when every neighbour has v's sign.
inline bool nearest_edge_crossing(const ScalarGrid& g, std::int64_t v, const int ijk[3], int& axis, int& dir, double& t) {
  const float* f = g.values.data();
  const std::int64_t stride[3] = {1, g.dims[0], std::int64_t(g.dims[0]) * g.dims[1]};
  const bool negative = f[v] < 0;
  axis = -1;
  t = 2.0;
  for (int a = 0; a < 3; ++a)
    for (int s : {-1, 1}) {
      if (ijk[a] + s < 0 || ijk[a] + s >= g.dims[a]) continue;
      const float fn = f[v + s * stride[a]];
      if ((fn < 0) == negative) continue;
      const double crossing = double(f[v]) / (double(f[v]) - double(fn));
      if (crossing < t) t = crossing, axis = a, dir = s;
    }
  return axis >= 0;
}

}  // namespace chokeloops::detail

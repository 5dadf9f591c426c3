#pragma once
// Private to src/field: the exact feature transform of levelset_edt.cpp (same declaration as levelset.cpp's).
#include <cstdint>
#include <vector>

#include "chokeloops/grid.h"

namespace chokeloops::detail {
struct Site {
  std::int64_t vertex;  // linear index of the site vertex
  float p[3];           // boundary point, in grid index units (vertex (i,j,k) at (i,j,k))
};
// Vertices not `known` get sign * distance (per-axis spacing) to the point of their nearest site.
void complete_by_feature_transform(ScalarGrid& grid, const std::vector<std::uint8_t>& known,
                                   const std::vector<Site>& sites, std::vector<std::int32_t>* nearest_site = nullptr);
}  // namespace chokeloops::detail

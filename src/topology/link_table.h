#pragma once
// Connected components of every subset of a vertex's 14-neighbour link (a 2-sphere), tabulated once.
// Lower/upper links of a vertex are such subsets; their component counts classify the vertex
// (minimum, regular, join saddle, split saddle, maximum) without touching any simplex.
#include <array>
#include <cstdint>
#include <vector>

namespace chokeloops::detail {

struct LinkComponents {
  std::uint8_t count = 0;
  std::array<std::uint16_t, 7> masks{};  // one bit mask of link vertices per component
};

// Table indexed by a 14-bit subset mask.
const std::vector<LinkComponents>& link_component_table();

}  // namespace chokeloops::detail

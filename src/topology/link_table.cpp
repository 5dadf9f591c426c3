#include "link_table.h"

#include "chokeloops/grid.h"

#include <stdexcept>

#include "chokeloops/topology/complex.h"

namespace chokeloops::detail {

const std::vector<LinkComponents>& link_component_table() {
  static const std::vector<LinkComponents> table = [] {
    const auto& link = freudenthal::vertex_link();
    std::vector<LinkComponents> t(1 << 14);
    for (unsigned mask = 0; mask < (1u << 14); ++mask) {
      unsigned left = mask;
      LinkComponents& c = t[mask];
      while (left) {
        unsigned comp = left & (~left + 1), frontier = comp;
        while (frontier) {
          int b = __builtin_ctz(frontier);
          frontier &= frontier - 1;
          unsigned grow = link.adjacency[b] & mask & ~comp;
          comp |= grow;
          frontier |= grow;
        }
        if (c.count == c.masks.size()) throw InternalError("link subset with more than 7 components");
        c.masks[c.count++] = std::uint16_t(comp);
        left &= ~comp;
      }
    }
    return t;
  }();
  return table;
}

}  // namespace chokeloops::detail

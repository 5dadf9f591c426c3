#pragma once
// Linking numbers of closed polylines, and the cycle a generator's choke closes: together they check that a
// generator's loop cuts its own handle (tunnel), which non-contractibility on the surface alone does not say.
//
// A handle generator's choke is the edge where a cycle of the solid closes; its loop bounds a membrane across
// that cycle, so the two link an odd number of times. A curve of the surface in another class (e.g. the rim
// of a flat membrane along a thin wall, which goes around the tunnel instead of across the handle) is also
// non-contractible on the surface but links the cycle an even number of times.
#include <array>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <vector>

#include "chokeloops/grid.h"
#include "chokeloops/surface/surface.h"
#include "chokeloops/topology/chokes.h"

namespace chokeloops {

// Linking number of two disjoint closed polylines (each closed by its last-to-first segment), counted from
// the crossings of their projection along a fixed generic direction. nullopt: the projection is degenerate
// at a crossing for every direction tried (a curve meets the other, or nearly).
std::optional<int> linking_number(const Polyline3& a, const Polyline3& b);

// A closed polyline prepared for its linking numbers with many others (a generator's loop of two thousand
// points against a hundred cycles of the other side): its projections are made and bucketed once, and each
// other curve costs about its own length. with(b) is linking_number(curve, b). Keeps a reference to
// `curve`; one thread at a time (the views are made on first use).
class LinkingCurve {
 public:
  explicit LinkingCurve(const Polyline3& curve);
  ~LinkingCurve();
  std::optional<int> with(const Polyline3& other) const;

  struct Point { double x, y, h; };  // in a view: the plane's coordinates and the height along the direction

 private:
  struct View {  // the curve projected along one direction, its segments bucketed in a k x k grid of cells
    std::vector<Point> points;
    double x0 = std::numeric_limits<double>::max(), y0 = std::numeric_limits<double>::max();
    double x1 = std::numeric_limits<double>::lowest(), y1 = std::numeric_limits<double>::lowest();
    double span = 0, cell = 1;
    int k = 1;
    std::vector<std::uint32_t> start, segments;  // cell c's segments: segments[start[c] .. start[c + 1])
    int cell_x(double v) const { return cell_of(v, x0); }
    int cell_y(double v) const { return cell_of(v, y0); }
    int cell_of(double v, double origin) const {
      const double c = (v - origin) / cell;
      return c <= 0 ? 0 : c >= k - 1 ? k - 1 : int(c);
    }
  };
  const View& view(int dir) const;
  std::optional<long> crossing_sum(const View& a, const std::vector<Point>& b) const;
  const Polyline3& curve_;
  mutable std::array<std::unique_ptr<View>, 4> views_;
};

// The cycle a generator's choke closes, as grid vertices in world coordinates: the saddle, one lobe, a
// shortest path (in steps of the Freudenthal grid) to the other lobe through the vertices beyond the saddle
// in its side's filtration (the solid below it for a handle, the outside above it for a tunnel), back to the
// saddle. Every vertex has the side's strict sign, so the cycle does not meet the marching surface. Empty
// when there is no such cycle: not a generator, a lobe outside the grid, a choke of depth 0, or lobes the
// region does not join (which a generator's pairing rules out).
Polyline3 generator_cycle(const ScalarGrid& grid, const Choke& choke);

}  // namespace chokeloops

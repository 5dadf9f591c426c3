#pragma once
// Private to src/loops: a surface's faces bucketed in cubic cells, and the section of a set of faces by a
// plane (the closed curve around a point with the least area), shared by SurfaceSections (plane_sections.h)
// and the molecules' channel sections (channels.cpp).
#include <array>
#include <cstdint>
#include <vector>

#include "chokeloops/surface/surface.h"

namespace chokeloops::detail {

// The closed curve where the plane (p, n) cuts `faces` that winds around p and encloses the least area (empty
// if none); faces whose first vertex is farther than max_radius from p are left out.
Polyline3 section_of(const SurfaceMesh& surface, const std::vector<int>& faces, const std::array<double, 3>& p,
                     const std::array<double, 3>& n, double max_radius);

// Faces bucketed by their first vertex in cubic cells, so that a section looks only at the faces near it.
class FaceCells {
 public:
  FaceCells(const SurfaceMesh& surface, double cell);

  // What near_plane reads for one plane: the box of cells within r of p and the axis the plane is steepest to.
  struct PlaneQuery {
    std::array<double, 3> p{}, nrm{};
    double r = 0;
    int a = 0, u = 1, v = 2;
    std::array<int, 3> lo{}, hi{};
    bool empty = true;
  };
  PlaneQuery plane_query(const std::array<double, 3>& p, const std::array<double, 3>& nrm, double r) const;

  // Faces in the cells the plane (p, n) crosses within r of p (their first vertex is within r) that the plane
  // cuts, in a fixed order: a slab of cells instead of the ball's volume. Needs cells at least as wide as any face.
  std::vector<int> near_plane(const SurfaceMesh& surface, const std::array<double, 3>& p, const std::array<double, 3>& nrm,
                              double r) const;
  // Whether near_plane lists face f for `q`, and then its place in that list (keys rise along it).
  bool listed(const SurfaceMesh& surface, const PlaneQuery& q, int f, std::uint64_t& key) const;

  // Faces whose first vertex is within r of p, in increasing order.
  std::vector<int> near(const SurfaceMesh& surface, const std::array<double, 3>& p, double r) const;

  // Every face whose first vertex is within `reach` of the segment a-b, and others near it: those in the cells
  // the segment passes through and in the cells within ceil(reach / cell) of them. Unordered, each once.
  void near_segment(const std::array<double, 3>& a, const std::array<double, 3>& b, double reach, std::vector<int>& out) const;

  double cell() const { return cell_; }

 private:
  int cell_of(const std::array<double, 3>& v) const;
  std::array<int, 3> cell_coords(const std::array<double, 3>& v) const;
  // The cells along axis a that the plane can cut in column (iu, iv), clipped to q's box.
  void column_range(const PlaneQuery& q, int iu, int iv, int& ia0, int& ia1) const;

  double cell_;
  std::array<double, 3> lo_{};
  std::array<int, 3> n_{};
  std::vector<int> start_, items_;
};

}  // namespace chokeloops::detail

#pragma once
// Plane sections of a surface: the closed curve where a plane through p cuts the surface that winds around
// p and encloses the least area. HOLE's and the generator loops' cross-sections (channels.h, membranes.h).
#include <array>
#include <memory>
#include <vector>

#include "chokeloops/surface/mesh_adjacency.h"
#include "chokeloops/surface/surface.h"

namespace chokeloops {

// The section by the plane (p, n) among the faces whose first vertex is within `max_radius` of p (empty if none).
Polyline3 cross_section_loop(const SurfaceMesh& surface, const std::array<double, 3>& p, const std::array<double, 3>& n,
                             double max_radius);

// The same curve for many planes over one bucketing of the surface's faces. Without an adjacency each
// section reads the cells its plane crosses; with one (by_ray), it follows only the curves through the faces
// that a ray from p in the plane meets, which every curve around p crosses: the same curve, at the cost of
// the curves near p rather than of the whole plane's cut. Thread-safe (const).
class SurfaceSections {
 public:
  explicit SurfaceSections(const SurfaceMesh& surface, const MeshAdjacency* adjacency = nullptr);
  ~SurfaceSections();
  // `faces`, when given, gets the face of each segment point k -> k + 1 (the last closing the curve) where the
  // curve was followed through the adjacency, and stays empty otherwise.
  Polyline3 around(const std::array<double, 3>& p, const std::array<double, 3>& n, double max_radius, bool by_ray = true,
                   std::vector<int>* faces = nullptr) const;
  // Whether the segment a-b meets no face of the surface (false when in doubt: a touch within rounding).
  bool segment_clear(const std::array<double, 3>& a, const std::array<double, 3>& b) const;

 private:
  struct Cells;
  const SurfaceMesh& surface_;
  const MeshAdjacency* adjacency_;
  std::unique_ptr<Cells> cells_;
};

}  // namespace chokeloops

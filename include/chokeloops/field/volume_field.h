#pragma once
// Stage `levelset` for volumes (DESIGN §6 "Volumes"): a scalar image thresholded at an iso value, or one
// label of a label map, becomes a signed distance (negative inside) in millimetres on the image's own
// voxel lattice (anisotropic spacing kept, no resampling unless voxel_size asks), padded by a margin of
// outside voxels.
//
// The boundary: inside is {value >= iso} ({value < iso} with inside_below); a label map's label N is the
// mask {value == N} taken at iso 1/2, so its boundary lies halfway between an inside and an outside voxel.
// Along every grid edge whose ends differ the boundary point is where the linear interpolation of the
// image meets the iso value; every vertex gets its distance in mm to the nearest such point (exact
// feature transform with per-axis spacing). No value is exactly 0: a voxel exactly at the iso value is
// inside at -1e-3 voxel, so the solid {phi <= 0} and the persistence agree without ties.
// Connectivity: the level set is read on the Freudenthal complex of the voxel lattice (DESIGN §2), whose
// edges are the 6 axis neighbours plus the diagonals along (1,1,0), (1,0,1), (0,1,1), (1,1,1) and their
// opposites: two inside voxels touching only along such a diagonal are connected, along the other
// diagonals they are not (the convention every stage — persistence, surface, membranes — shares).
#include <array>
#include <cstddef>
#include <string>

#include "chokeloops/grid.h"
#include "chokeloops/io/volume_io.h"

namespace chokeloops {

struct VolumeFieldOptions {
  bool has_iso = false;
  double iso = 0;                 // scalar image: the boundary value (stored units)
  bool inside_below = false;      // inside = value < iso instead of value >= iso
  bool has_label = false;
  double label = 0;               // label map: the label whose voxels are inside
  double margin = -1;             // mm of outside padding; < 0: max(10% of the longest side, 4 voxels)
  double voxel_size = 0;          // > 0: resample to this isotropic spacing (mm) first, along the image's axes
};

// The grid's axis-aligned frame (vertex (i,j,k) at origin + spacing*(i,j,k), image voxel (0,0,0) at 0)
// to the image's world: x_world = linear * x_grid + offset (linear = direction cosines).
struct WorldFrame {
  bool set = false;
  std::array<std::array<double, 3>, 3> linear{};
  std::array<double, 3> offset{0, 0, 0};
  std::string convention;         // "RAS", "LPS", ...
  std::string source;             // where the transform came from ("sform", "qform", "space directions"...)
  std::array<double, 3> apply(const std::array<double, 3>& p) const;
  std::array<double, 3> rotate(const std::array<double, 3>& v) const;  // directions (normals)
};

struct VolumeField {
  ScalarGrid grid;                // signed distance, mm, negative inside
  WorldFrame frame;
  std::array<int, 3> pad{0, 0, 0};  // grid vertex (i,j,k) = image voxel (i,j,k) - pad
  std::size_t inside_voxels = 0;
  std::size_t boundary_sites = 0;
};

// With voxel_size > 0 the image is first resampled onto an isotropic lattice along its own axes (voxel
// (0,0,0) kept in place): the function that is >= 0 inside (value - iso, or +-1/2 for a label's mask) is
// interpolated trilinearly and read at 0 as above, so a mask's boundary still runs halfway between its voxels.
// Throws Error(2) when neither or both of iso/label are given, the label is absent or the mask is empty
// or fills the whole image (no boundary), or the iso value is not finite; Error(3) when the grid would not
// fit in memory.
VolumeField volume_to_levelset(const VolumeImage& image, const VolumeFieldOptions& options);

}  // namespace chokeloops

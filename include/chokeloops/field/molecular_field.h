#pragma once
// Stage `levelset` for molecules (DESIGN §6): the signed distance (negative inside, Å) to the van der Waals
// surface (union of atom spheres), the solvent-accessible surface (spheres grown by the probe) or the
// solvent-excluded surface (the SAS shrunk back by the probe), sampled on a padded regular grid.
#include <array>
#include <cstddef>
#include <string>
#include <vector>

#include "chokeloops/grid.h"
#include "chokeloops/io/molecule_io.h"

namespace chokeloops {

enum class MolecularSurface { Vdw, Sas, Ses };
const char* to_string(MolecularSurface s);

struct MolecularFieldOptions {
  MolecularSurface surface = MolecularSurface::Vdw;
  double probe = 1.4;          // Å (sas, ses)
  double voxel_size = 0.25;    // Å
  double margin = -1;          // Å of padding around the spheres; < 0: max(6 Å, 4 voxels)
  std::size_t max_memory = 0;  // bytes; 0: default_max_memory()
};

// Exact distance queries against a set of spheres through a uniform cell list.
class AtomLocator {
 public:
  AtomLocator(std::vector<std::array<double, 3>> centres, std::vector<double> radii, double cell = 3.0);
  // min_i |x - c_i| - r_i (negative inside a sphere); *nearest = the atom attaining it.
  double distance(const std::array<double, 3>& x, int* nearest = nullptr) const;
  // Indices of the atoms with |x - c_i| - r_i <= d, in increasing index order.
  std::vector<int> within(const std::array<double, 3>& x, double d) const;
  const std::array<double, 3>& centre(int i) const { return c_[std::size_t(i)]; }
  double radius(int i) const { return r_[std::size_t(i)]; }
  int size() const { return int(c_.size()); }

 private:
  template <class F> void visit_box(const std::array<double, 3>& lo, const std::array<double, 3>& hi, F&& f) const;
  std::vector<std::array<double, 3>> c_;
  std::vector<double> r_;
  double cell_, rmax_ = 0;
  std::array<double, 3> lo_{};
  std::array<int, 3> n_{};
  std::vector<int> start_, items_;  // CSR: atoms of cell k are items_[start_[k] .. start_[k+1])
};

// The radii the surface's distance is measured against: vdw radius (+ probe for sas).
std::vector<double> surface_radii(const Molecule& mol, MolecularSurface surface, double probe);

// Near the spheres (within 3 Å or 4 voxels of the chosen surface) every grid value is the exact distance
// min_i(|x - c_i| - r_i); farther out, the distance to the atom whose centre is nearest (an upper bound,
// off by at most the spread of the radii). The SES inside the SAS is p minus the exact feature transform's
// distance to the SAS's zero crossings; outside the SAS it is the SAS value plus p, which is exact.
// Throws Error code 3 when the grid would exceed the memory budget (the message names a voxel size that
// fits).
ScalarGrid molecular_field(const Molecule& mol, const MolecularFieldOptions& options);

// Bytes molecular_field needs for a box of `voxels` vertices (the guard's model).
std::size_t estimate_molecular_field_bytes(std::size_t voxels, MolecularSurface surface);

}  // namespace chokeloops

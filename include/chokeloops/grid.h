#pragma once
// A dense scalar field sampled at the vertices of a regular grid: the plain data every stage passes on.
// Vertex (i,j,k) sits at origin + h*(i,j,k), h = voxel_size on every axis, or the per-axis `spacing` of an
// anisotropic grid (medical volumes); its linear index is i + nx*(j + ny*k). Positions are in the grid's own
// axis-aligned frame; a volume's index-to-world rotation is applied only when positions are written.
#include <array>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace chokeloops {

// Every error a user can cause (bad input, impossible parameters) is thrown as this, with a message
// that names the problem and what to do. `exit_code` is what the CLI returns: 2 bad input, 3 resources.
struct Error : std::runtime_error {
  int exit_code;
  explicit Error(const std::string& msg, int code = 2) : std::runtime_error(msg), exit_code(code) {}
};

// A failed internal self-check: a bug in chokeloops, never the user's input. The CLI exits with
// kInternalErrorExitCode and asks for a report naming the input; a library caller can tell it from Error.
struct InternalError : std::logic_error {
  explicit InternalError(const std::string& msg) : std::logic_error(msg) {}
};
constexpr int kInternalErrorExitCode = 4;

struct ScalarGrid {
  std::array<int, 3> dims{0, 0, 0};          // number of vertices along x, y, z
  std::array<double, 3> origin{0, 0, 0};     // world position of vertex (0,0,0)
  double voxel_size = 1.0;                   // spacing in input units (anisotropic grid: the smallest spacing)
  std::array<double, 3> spacing{0, 0, 0};    // anisotropic grid: spacing per axis (all > 0); 0: voxel_size
  std::vector<float> values;                 // size nx*ny*nz, x fastest

  std::int64_t vertex_count() const { return std::int64_t(dims[0]) * dims[1] * dims[2]; }
  std::int64_t index(int i, int j, int k) const { return i + std::int64_t(dims[0]) * (j + std::int64_t(dims[1]) * k); }
  double h(int axis) const { return spacing[axis] > 0 ? spacing[axis] : voxel_size; }
  bool anisotropic() const { return spacing[0] > 0 && !(spacing[0] == spacing[1] && spacing[1] == spacing[2]); }
  std::array<double, 3> world(std::array<int, 3> ijk) const {
    return {origin[0] + h(0) * ijk[0], origin[1] + h(1) * ijk[1], origin[2] + h(2) * ijk[2]};
  }
};

// Throws Error when the grid is empty, has a dimension < 2, mismatched storage, or a non-finite value.
void validate_grid(const ScalarGrid& grid);

}  // namespace chokeloops

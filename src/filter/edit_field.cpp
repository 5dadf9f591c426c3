// apply_edits, restore (edit_field.h).
#include "edit_field.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <unordered_set>

#include "chokeloops/field/levelset.h"
#include "chokeloops/topology/complex.h"

namespace chokeloops::detail {

// Moves every edit's voxels to their new side and gives the vertices around them the distance to the new
// surface where it is nearer than the old one. Returns what to restore.
Undo apply_edits(ScalarGrid& grid, const std::vector<const FilterEdit*>& edits) {
  Undo undo;
  if (edits.empty()) return undo;
  FreudenthalComplex cx(grid.dims);
  auto set = [&](Id v, float value) {
    undo.old_values.push_back({v, grid.values[std::size_t(v)]});
    grid.values[std::size_t(v)] = value;
  };
  // Every edit's side first, so that each neighbourhood below sees all the new signs near it. A flipped
  // vertex sits half a voxel past the new surface, as a mask's boundary does between voxels.
  const float half = float(0.5 * grid.voxel_size);
  const float kSmallest = float(1e-3 * grid.voxel_size);
  std::unordered_set<Id> flipped;
  for (const FilterEdit* e : edits)
    for (Id v : e->voxels) {
      set(v, e->side == Side::Handle ? half : -half);
      flipped.insert(v);
    }
  // Then each edit's neighbourhood (its voxels' box grown by its depth and two voxels), one after the other in
  // the edits' order: redistanced from the signs on that box, a vertex takes the new distance where it is
  // nearer than its value (the new surface is there); its side never changes, and no magnitude is 0.
  for (const FilterEdit* edit : edits) {
    const FilterEdit& e = *edit;
    std::array<int, 3> lo{grid.dims[0], grid.dims[1], grid.dims[2]}, hi{-1, -1, -1};
    for (Id v : e.voxels) {
      const auto p = cx.coords(v);
      for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], p[a]), hi[a] = std::max(hi[a], p[a]);
    }
    ScalarGrid sub;
    for (int a = 0; a < 3; ++a) {
      const int m = int(std::ceil(e.depth / grid.h(a))) + 2;
      lo[a] = std::max(0, lo[a] - m);
      hi[a] = std::min(grid.dims[a] - 1, hi[a] + m);
      sub.dims[a] = hi[a] - lo[a] + 1;
    }
    sub.voxel_size = grid.voxel_size;
    sub.spacing = grid.spacing;
    sub.origin = grid.world(lo);
    sub.values.resize(std::size_t(sub.vertex_count()));
    for (int k = 0; k < sub.dims[2]; ++k)
      for (int j = 0; j < sub.dims[1]; ++j)
        for (int i = 0; i < sub.dims[0]; ++i)
          sub.values[std::size_t(sub.index(i, j, k))] = grid.values[std::size_t(grid.index(lo[0] + i, lo[1] + j, lo[2] + k))];
    redistance_from_signs(sub);
    for (int k = 0; k < sub.dims[2]; ++k)
      for (int j = 0; j < sub.dims[1]; ++j)
        for (int i = 0; i < sub.dims[0]; ++i) {
          const Id v = grid.index(lo[0] + i, lo[1] + j, lo[2] + k);
          const float now = grid.values[std::size_t(v)], near = std::abs(sub.values[std::size_t(sub.index(i, j, k))]);
          const bool inside = now <= 0;
          const float magnitude = std::max(flipped.count(v) ? near : std::min(std::abs(now), near), kSmallest);
          const float value = inside ? -magnitude : magnitude;
          if (value != now) set(v, value);
        }
  }
  return undo;
}

void restore(ScalarGrid& grid, const Undo& undo) {
  for (auto it = undo.old_values.rbegin(); it != undo.old_values.rend(); ++it) grid.values[it->first] = it->second;
}

}  // namespace chokeloops::detail

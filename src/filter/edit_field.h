#pragma once
// Writing a batch of the filter's edits into the field, and taking it back: each edit's vertices change side,
// and the vertices around them take the distance to the new surface where it is nearer than their value.
// Every other value stays bit-identical.
#include <utility>
#include <vector>

#include "chokeloops/filter/filter.h"

namespace chokeloops::detail {

// The values an edit overwrote, in order (restored from the last), so that a failed check can put them back.
struct Undo {
  std::vector<std::pair<Id, float>> old_values;
};

// Moves every edit's voxels to their new side (half a voxel past the new surface) and redistances each edit's
// neighbourhood (its voxels' box grown by its depth and two voxels) from the signs there. Returns what to restore.
Undo apply_edits(ScalarGrid& grid, const std::vector<const FilterEdit*>& edits);

// Puts back the values `undo` recorded.
void restore(ScalarGrid& grid, const Undo& undo);

}  // namespace chokeloops::detail

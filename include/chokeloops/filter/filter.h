#pragma once
// Stage `filter`: removes handle/tunnel pairs of the genus from a signed distance by cutting the handle (its
// membrane's voxels leave the solid) or filling the tunnel (they join it), then checks the result by
// persistence. Values away from the edits stay bit-identical.
//
// A pair of the genus (DESIGN §2, dim-1 pair b <= 0 < d) has one handle generator (depth -b, the narrowest
// section of the handle) and one tunnel generator (distance d, where its hole closes); removing either
// lowers the genus by one. A pair's persistence here is d - b, the field's own measure of how big the
// pair is (TTK's simplification removes pairs by the same number).
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "chokeloops/loops/membranes.h"
#include "chokeloops/topology/chokes.h"
#include "chokeloops/topology/persistence.h"

namespace chokeloops {

enum class FilterMode { Auto, Cut, Fill };  // auto: per pair, the edit that changes fewer voxels

struct FilterOptions {
  // Which pairs go. With none of these set nothing is selected (filter_grid throws Error).
  bool has_max_depth = false;
  Threshold max_depth;        // an edit's depth at most this (% of R_in for cuts, of R_out for fills)
  bool has_max_persistence = false;
  Threshold max_persistence;  // pair persistence d - b at most this (% of R_in + R_out)
  int keep_genus = -1;        // >= 0: keep this many of the most persistent pairs, remove the others
  FilterMode mode = FilterMode::Auto;
  int max_rounds = 16;        // edits are re-derived from the edited field until nothing selected is left
  LoopOptions membrane;       // flood boxes (box_factor, box_margin)
  // May vertex v change side? (e.g. a label map: only its own voxels or background). Empty: every vertex.
  std::function<bool(Id v)> can_change;
};

struct FilterEdit {
  Side side = Side::Handle;  // Handle: the handle was cut; Tunnel: the tunnel was filled
  int round = 0;
  double depth = 0;          // of the generator edited
  double persistence = 0;    // of its pair, d - b
  std::array<double, 3> point{0, 0, 0};  // the choke point, grid frame
  std::vector<Id> voxels;    // vertices that changed side, ascending
  double volume = 0;         // voxels times the voxel volume
};

struct FilterSummary {
  int genus = 0, components = 0, cavities = 0;  // handle generators, components, sealed cavities
};

struct FilterReport {
  FilterSummary before, after;
  int selected = 0;                    // pairs the criteria selected in the first round
  std::vector<FilterEdit> edits;       // every edit kept, in the order applied
  std::vector<std::string> notes;      // pairs selected but not removed, with why
  int rounds = 0;
  std::size_t voxels_changed = 0;      // vertices whose sign changed
  std::size_t values_changed = 0;      // vertices whose value changed (sign or distance)
  double max_edit_depth = 0;
  double R_in = 0, R_out = 0;          // of the input
  std::map<std::string, double> timings_ms;
};

// Edits `grid` in place (a signed distance, negative inside). Throws Error when no criterion is given or
// --keep-genus asks for more than the genus; a check that fails after an edit undoes that edit and notes
// it. A selected pair that cannot be removed is listed in notes, never hidden.
FilterReport filter_grid(ScalarGrid& grid, const FilterOptions& options, const ProgressFn& progress = {});

// Components, genus and sealed cavities of the solid {phi <= 0}, from persistence.
FilterSummary topology_summary(const ScalarGrid& grid);

}  // namespace chokeloops

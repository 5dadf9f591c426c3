#pragma once
// What a batch of side changes does to the topology of the solid {phi <= 0}, exactly and without
// persistence: components from one labelling of both sides, the genus from the Euler characteristic,
// whose change is local (the stars of the vertices that changed side).
//
// Why this is exact. The solid and the outside are full subcomplexes of the Freudenthal triangulation
// (a simplex belongs to a side when all its vertices do), the complexes the lower-star persistence
// filters by. A batch's changed vertices fall into groups (connected by Freudenthal edges). A group
// leaves components and cavities alone when, before and after, the vertices of the group and its
// neighbours on each side all carry one label of that side: then no component is split, joined,
// created or removed through it, and, groups being apart, none through several. With b0 and b2 kept,
// the genus b1 = b0 + b2 - chi drops by the group's change of chi, a sum over simplices of its stars.
#include <cstdint>
#include <string>
#include <unordered_map>
#include <vector>

#include "chokeloops/grid.h"
#include "chokeloops/topology/complex.h"

namespace chokeloops::detail {

// Components of each side by Freudenthal edges; a vertex carries the id of its own side's component.
struct SideLabels {
  std::vector<std::int32_t> label;
  std::vector<char> outside_reaches_border;  // per outside id (ids of inside components are not used here)
  int inside_components = 0;
  int cavities = 0;  // outside components that do not reach the grid's border (sealed in the solid)
};
SideLabels label_sides(const ScalarGrid& grid);

// The vertices that changed side, with the side each had before (true: inside).
using SideChanges = std::unordered_map<Id, bool>;

struct GroupVerdict {
  bool keeps_components = true;  // inside: no component split, joined, created or removed through it
  bool keeps_cavities = true;    // outside: the same, so no cavity sealed or opened
  bool on_border = false;        // it changes a vertex on the grid's border (the outside's border status)
  int euler_change = 0;          // chi(after) - chi(before) of the solid over the group's stars
};

// The verdict on one group of changed vertices (`group`, all in `changes`), from the labels of the
// grid before the batch and of the grid as it is now (after it).
GroupVerdict judge_group(const ScalarGrid& grid, const FreudenthalComplex& cx, const std::vector<Id>& group,
                         const SideChanges& changes, const SideLabels& before, const SideLabels& after);

// The same verdict without labelling the grid, where the group's surroundings settle it: the vertices around the
// group of each side, before and after, joined through that side within a box a few voxels around the group are
// joined in the grid, so one label each. When some side's vertices are not joined there (a handle longer than the
// box, or really split), `decided` is false and judge_group, with the labels of the whole grid, must judge; a
// decided verdict is the one judge_group gives.
struct LocalVerdict {
  GroupVerdict verdict;
  bool decided = false;
};
LocalVerdict judge_group_locally(const ScalarGrid& grid, const FreudenthalComplex& cx, const std::vector<Id>& group,
                                 const SideChanges& changes);

}  // namespace chokeloops::detail

#pragma once
// Private to src/pipeline: the checks every analysis (meshes, fields, molecules, volumes) runs on its loops
// before reporting them, so that no front-end can report a wrong generator or hide a missing loop.
#include <string>
#include <vector>

#include "chokeloops/loops/membranes.h"
#include "chokeloops/surface/topology.h"

namespace chokeloops {

// Never a silently wrong generator: shortening keeps the chosen curve's class, and this safety net checks that
// it did; a generator loop that became contractible is reported as missing. Loops with `skip[i]` set (when
// given) were verified otherwise and are left alone.
void drop_contractible_generators(std::vector<Loop>& loops, SurfaceTopology& topology,
                                  const std::vector<bool>* skip = nullptr);

// One warning line counting the chokes that got no loop (each loop's note says why).
void warn_about_missing_loops(const std::vector<Loop>& loops, std::vector<std::string>& warnings);

}  // namespace chokeloops

#pragma once
// Private to src/pipeline: the stages and checks every analysis (meshes, fields, molecules, volumes) shares
// between its chokes and its report, so that no front-end can skip the surface's self-check, report a wrong
// generator or hide a missing loop.
#include <memory>
#include <string>
#include <vector>

#include "chokeloops/analyze.h"
#include "chokeloops/loops/membranes.h"
#include "chokeloops/surface/mesh_adjacency.h"
#include "chokeloops/surface/topology.h"

namespace chokeloops {

// The surface stage: r.surface and r.surface_stats from r.grid, timed as "surface"; returns the surface's
// adjacency, which the statistics are read from and the loop stage reuses, and the faces' components in
// `face_label` (face_components numbering) for the loop stage's topology. A closed surface whose genus
// differs from the handle generators is a bug (InternalError; CHOKELOOPS_TEST_FAULT=self-check forces it, so
// that tests see how a bug is reported); an open one gets a warning.
MeshAdjacency extract_checked_surface(AnalyzeResult& r, std::vector<int>& face_label);
// Its checks alone, for a pipeline that builds r.surface and r.surface_stats itself (before r.chokes are known).
void check_surface(AnalyzeResult& r);

// What the loop stage shares between all chokes: the surface's adjacency, and its topology when some choke
// is a generator (the choice of a generator's curve and the check below need it). The topology refers to the
// adjacency beside it, so a context stays where it was made: it is filled in place and never moved.
struct LoopContext {
  LoopContext() = default;
  LoopContext(const LoopContext&) = delete;
  LoopContext& operator=(const LoopContext&) = delete;
  MeshAdjacency adjacency;
  std::unique_ptr<SurfaceTopology> topology;  // null when no choke is a generator
};
// Whether some choke is a generator: only then does the loop stage need the surface's topology.
bool any_generator(const AnalyzeResult& r);
void prepare_loops(const AnalyzeResult& r, MeshAdjacency adjacency, std::vector<int> face_label, LoopContext& context);
// The same with the topology built or not as `with_topology` says, before the chokes are known (r.surface and
// r.surface_stats are read).
void prepare_loops(const AnalyzeResult& r, MeshAdjacency adjacency, std::vector<int> face_label, bool with_topology,
                   LoopContext& context);

// Never a silently wrong generator: shortening keeps the chosen curve's class, and this safety net checks that
// it did; a generator loop that became contractible is reported as missing. Loops with `skip[i]` set (when
// given) were verified otherwise and are left alone.
void drop_contractible_generators(std::vector<Loop>& loops, SurfaceTopology& topology,
                                  const std::vector<bool>* skip = nullptr);

// One warning line counting the chokes that got no loop (each loop's note says why); those with `by_design[i]`
// set (when given) were left without one on purpose and are not counted.
void warn_about_missing_loops(const std::vector<Loop>& loops, std::vector<std::string>& warnings,
                              const std::vector<bool>* by_design = nullptr);

}  // namespace chokeloops

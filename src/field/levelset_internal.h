#pragma once
// Private to src/field: what the mesh path (levelset.cpp) and the .vdb path (levelset_vdb.cpp) of the
// level-set stage share.
#include <chrono>
#include <string>

#include <openvdb/openvdb.h>

#include "chokeloops/field/levelset.h"
#include "feature_transform.h"

namespace chokeloops::levelset_detail {

using Clock = std::chrono::steady_clock;
// A level set whose values are further than this from the exact distance to its zero level set is redistanced.
constexpr double kDistanceToleranceVoxels = 1.0;

double since(Clock::time_point t0);
// Throws Error (exit code 3) naming a --resolution that fits when the box needs more than the allowed memory.
void check_memory(const openvdb::CoordBBox& box, const LevelSetOptions& o, double h, double longest,
                  const std::string& who);
void count_sides(LevelSetResult& r);
void emit_warnings(const LevelSetResult& r, const LevelSetOptions& o);

}  // namespace chokeloops::levelset_detail

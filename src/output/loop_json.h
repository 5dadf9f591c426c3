#pragma once
// Private to the report writers: the fields of one loop that loops.json, input_loops.json and the tet path's
// loops.json share (DESIGN §5; names are a contract: add, never rename).
#include <nlohmann/json.hpp>

#include "chokeloops/field/volume_field.h"
#include "chokeloops/loops/input_loops.h"

namespace chokeloops::detail {

nlohmann::json point_json(const std::array<double, 3>& p);

// Everything of loops.json's entry but its "choke_simplex", which names the complex's simplex.
nlohmann::json loop_fields_json(const Loop& loop, std::size_t id, const WorldFrame& frame);

// What a loop on the input mesh adds: verified, check, edge_path, input_points.
void add_input_loop_fields(nlohmann::json& entry, const InputLoop& loop);

}  // namespace chokeloops::detail

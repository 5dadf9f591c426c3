// The analysis's last stage for mesh inputs (analyze.h add_input_loops): the loops on the user's own mesh.
#include <chrono>

#include "chokeloops/analyze.h"

namespace chokeloops {

void add_input_loops(AnalyzeResult& r, const std::string& input) {
  const auto t = std::chrono::steady_clock::now();
  try {
    r.input_mesh = load_input_mesh(input);
    r.input_loops = transfer_loops(r.input_mesh, r.surface, r.loops);
    r.has_input_loops = true;
  } catch (const Error& e) {
    r.warnings.push_back(std::string("no loops on the input mesh: ") + e.what());
  }
  if (r.has_input_loops) {
    int lost = 0;
    for (std::size_t i = 0; i < r.loops.size(); ++i) lost += r.loops[i].found && !r.input_loops[i].loop.found;
    if (lost)
      r.warnings.push_back(std::to_string(lost) + " loop(s) could not be carried onto the input mesh (see their note in input_loops.json)");
    if (r.input_mesh.repaired)
      r.warnings.push_back("the input mesh is not a closed manifold: input_loops.json refers to the repaired mesh's vertex and face ids");
  }
  r.timings_ms["input_loops"] = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
}

}  // namespace chokeloops

// `chokeloops cut` behind the command line (cut_mesh.h cut_mesh_file): the loops analyze carried onto the input
// mesh, read back from input_loops.json, and the same mesh they refer to.
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "chokeloops/grid.h"
#include "chokeloops/loops/cut_mesh.h"
#include "chokeloops/loops/input_loops.h"

namespace chokeloops {

namespace {
std::string lower_extension(const std::string& path) {
  std::string e = std::filesystem::path(path).extension().string();
  std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return e;
}
}  // namespace

CutResult cut_mesh_file(const std::string& input, const std::string& outdir, const std::string& output,
                        const CutSelection& selection, std::vector<int>* cut_ids) {
  const std::string ext = lower_extension(output);
  if (ext != ".off" && ext != ".ply" && ext != ".obj" && ext != ".stl")
    throw Error("output '" + output + "' must end in .off, .ply, .obj or .stl");
  const std::string report = outdir + "/input_loops.json";
  std::ifstream in(report);
  if (!in) throw Error("cannot read '" + report + "': run chokeloops analyze " + input + " -o " + outdir + " first");
  nlohmann::json j;
  try {
    in >> j;
  } catch (const std::exception& e) {
    throw Error("'" + report + "' is not valid JSON: " + e.what());
  }
  const std::string name = std::filesystem::path(input).filename().string();
  if (!j.contains("input") || j["input"] != name || !j.contains("loops") || !j.contains("input_mesh"))
    throw Error("'" + report + "' was not written for " + name + " (run chokeloops analyze " + input + " -o " + outdir + ")");
  const InputMesh mesh = load_input_mesh(input);
  if (j["input_mesh"].value("vertices", std::size_t(0)) != mesh.mesh.vertices.size() ||
      j["input_mesh"].value("faces", std::size_t(0)) != mesh.mesh.faces.size())
    throw Error("'" + report + "' was written for another version of " + name + " (vertex or face counts differ)");

  const auto& loops = j["loops"];
  std::vector<int> ids;
  if (!selection.ids.empty()) {
    for (int id : selection.ids) {
      if (id < 0 || std::size_t(id) >= loops.size())
        throw Error("no loop " + std::to_string(id) + " in '" + report + "' (" + std::to_string(loops.size()) + " loops)");
      if (!loops[std::size_t(id)].value("found", false))
        throw Error("loop " + std::to_string(id) + " is not on the input mesh: " + loops[std::size_t(id)].value("note", std::string()));
      ids.push_back(id);
    }
  } else {
    const std::string side = selection.handles ? "handle" : "tunnel";
    for (std::size_t i = 0; i < loops.size(); ++i)
      if (loops[i].value("side", "") == side && loops[i].value("kind", "") == "generator" && loops[i].value("found", false))
        ids.push_back(int(i));
    if (ids.empty()) throw Error("no " + side + " generator on the input mesh in '" + report + "': nothing to cut");
  }
  std::vector<std::vector<int>> paths;
  for (int id : ids) paths.push_back(loops[std::size_t(id)].at("edge_path").get<std::vector<int>>());
  TriangleMesh tm{mesh.mesh.vertices, mesh.mesh.faces};
  CutResult r = cut_along_loops(tm, paths, ids);
  write_mesh(r.mesh, output);
  if (cut_ids) *cut_ids = ids;
  return r;
}

}  // namespace chokeloops

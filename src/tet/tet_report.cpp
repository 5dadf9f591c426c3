// The tet path's files (analyze_tet.h): those of the grid path for a mesh, with the input mesh as the surface.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "chokeloops/output/mesh_write.h"
#include "chokeloops/tet/analyze_tet.h"
#include "output/loop_json.h"

namespace chokeloops {

namespace {

std::string tet_report_json(const TetAnalysis& a, const ChokeParameters& params, const std::string& input) {
  using nlohmann::json;
  json j;
  j["input"] = std::filesystem::path(input).filename().string();
  j["complex"] = "tetgen";
  j["units"] = "input";
  j["tets"] = {{"vertices", a.vertices}, {"tets", a.tets},
               {"simplices", {a.simplices[0], a.simplices[1], a.simplices[2], a.simplices[3]}}};
  const MeshReport& m = a.input_report;
  j["surface"] = {{"vertices", a.input.vertices.size()}, {"faces", a.input.faces.size()}, {"components", m.components},
                  {"genus", m.genus}, {"closed", m.closed}, {"euler", m.euler}};
  const ChokeSet& c = a.chokes;
  j["scales"] = {{"R_in", c.R_in}, {"R_out", c.R_out}};
  j["parameters"] = {{"d_max", params.d_max.text()},
                     {"min_persistence", params.min_persistence.text()},
                     {"d_max_abs_handle", c.d_max_handle},
                     {"d_max_abs_tunnel", c.d_max_tunnel},
                     {"min_persistence_abs_handle", c.min_persistence_handle},
                     {"min_persistence_abs_tunnel", c.min_persistence_tunnel},
                     {"side", params.handles && params.tunnels ? "both" : params.handles ? "handle" : "tunnel"}};
  j["counts"] = {{"handle_generators", c.handle_generators}, {"tunnel_generators", c.tunnel_generators},
                 {"components", c.components},           {"gaps", c.gaps},
                 {"sealed_cavities", c.sealed_cavities}};
  json loops = json::array();
  for (std::size_t i = 0; i < a.loops.size(); ++i) {
    const InputLoop& l = a.loops[i];
    json e = detail::loop_fields_json(l.loop, i, WorldFrame{});
    const Choke& k = l.loop.choke;
    json vertices = json::array();
    if (k.simplex >= 0 && std::size_t(k.simplex) < a.pair_simplices.size())
      for (std::int32_t v : a.pair_simplices[std::size_t(k.simplex)])
        if (v >= 0) vertices.push_back(v);
    e["choke_simplex"] = {{"dim", k.simplex_dim}, {"vertices", vertices}, {"saddle_vertex", k.saddle}};
    detail::add_input_loop_fields(e, l);
    loops.push_back(e);
  }
  j["loops"] = loops;
  json hd = json::array(), td = json::array();
  for (auto& p : c.handle_diagram) hd.push_back({p[0], p[1]});
  for (auto& p : c.tunnel_diagram) td.push_back({p[0], p[1]});
  j["diagram"] = {{"handle", hd}, {"tunnel", td}};
  j["warnings"] = json::array();
  json timings = json::object();
  for (auto& kv : a.timings_ms) timings[kv.first] = std::round(kv.second * 10) / 10;
  j["timings_ms"] = timings;
  return j.dump(1) + "\n";
}

}  // namespace

void write_chokes_csv(const ChokeSet& chokes, const std::string& path) {
  std::ofstream out(path);
  if (!out) throw Error("cannot write " + path);
  out.precision(9);
  out << "side,kind,depth,persistence,birth,death,x,y,z\n";
  for (const Choke& c : chokes.chokes)
    out << to_string(c.side) << ',' << to_string(c.kind) << ',' << c.depth << ',' << c.persistence << ',' << c.birth << ','
        << c.death << ',' << c.point[0] << ',' << c.point[1] << ',' << c.point[2] << '\n';
  if (!out) throw Error("cannot write " + path);
}

void write_tet_report(const TetAnalysis& a, const ChokeParameters& params, const std::string& input, const std::string& outdir) {
  std::error_code ec;
  std::filesystem::create_directories(outdir, ec);
  if (ec || !std::filesystem::is_directory(outdir)) throw Error("cannot create output directory '" + outdir + "': " + ec.message());
  write_ply(a.input, outdir + "/surface.ply");
  std::vector<Polyline3> polylines;
  for (const InputLoop& l : a.loops)
    if (l.loop.found) polylines.push_back(l.loop.points);
  write_loops_ply(polylines, outdir + "/loops.ply");
  write_loops_obj(polylines, outdir + "/loops.obj");
  std::ofstream out(outdir + "/loops.json");
  out << tet_report_json(a, params, input);
  if (!out) throw Error("cannot write '" + outdir + "/loops.json' (disk full?)");
  write_chokes_csv(a.chokes, outdir + "/chokes.csv");
}

}  // namespace chokeloops

// Stage `report`: the files other programs rely on (DESIGN §5). Field names are a contract: add, never rename.
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "chokeloops/analyze.h"
#include "chokeloops/output/mesh_write.h"
#include "output/loop_json.h"

namespace chokeloops {

namespace detail {

nlohmann::json point_json(const std::array<double, 3>& p) { return nlohmann::json::array({p[0], p[1], p[2]}); }

nlohmann::json loop_fields_json(const Loop& l, std::size_t id, const WorldFrame& wf) {
  auto pos = [&](const std::array<double, 3>& p) { return wf.set ? wf.apply(p) : p; };
  const Choke& c = l.choke;
  nlohmann::json pts = nlohmann::json::array();
  for (auto& p : l.points) pts.push_back(point_json(pos(p)));
  return {{"id", id},
          {"side", to_string(c.side)},
          {"kind", to_string(c.kind)},
          {"depth", c.depth},
          {"persistence", c.persistence},
          {"birth", c.birth},
          {"death", c.death},
          {"length", l.length},
          {"choke_point", point_json(pos(c.point))},
          {"centroid", point_json(pos(l.centroid))},
          {"normal", point_json(wf.set ? wf.rotate(l.normal) : l.normal)},
          {"radius_min", l.radius_min},
          {"radius_mean", l.radius_mean},
          {"raw_length", l.raw_length},
          {"found", l.found},
          {"note", l.note},
          {"points", pts}};
}

void add_input_loop_fields(nlohmann::json& e, const InputLoop& il) {
  e["verified"] = il.verified;
  if (il.verified)
    e["check"] = il.loop.choke.kind == Kind::Generator ? "non-contractible" : il.separating ? "separating" : "non-separating";
  e["edge_path"] = il.loop.edge_path;
  nlohmann::json where = nlohmann::json::array();
  for (const InputPoint& w : il.where) {
    if (w.vertex >= 0) where.push_back({{"vertex", w.vertex}, {"face", w.face}});
    else where.push_back({{"edge", {w.edge[0], w.edge[1]}}, {"t", w.t}, {"face", w.face}});
  }
  e["input_points"] = where;
}

}  // namespace detail

namespace {
using detail::point_json;

// One entry of loops.json's "loops" (input_loops.json's entries start from it too).
nlohmann::json loop_json(const Loop& l, std::size_t id, const FreudenthalComplex& cx, const WorldFrame& wf) {
  nlohmann::json e = detail::loop_fields_json(l, id, wf);
  const Choke& c = l.choke;
  auto sc = cx.coords(c.saddle);
  e["choke_simplex"] = {{"dim", c.simplex_dim}, {"id", c.simplex}, {"grid_vertex", {sc[0], sc[1], sc[2]}}};
  return e;
}
}  // namespace

std::string report_json(const AnalyzeResult& r, const AnalyzeOptions& options) {
  // Volumes: every position is written in the image's world (mm, its convention), not the grid's frame.
  const WorldFrame& wf = r.frame;
  using nlohmann::json;
  json j;
  j["input"] = std::filesystem::path(r.input).filename().string();
  j["complex"] = "grid";
  j["units"] = wf.set ? "mm" : "input";
  if (wf.set) {
    json m = json::array();
    for (int row = 0; row < 3; ++row)
      m.push_back({wf.linear[row][0], wf.linear[row][1], wf.linear[row][2], wf.offset[row]});
    j["coordinates"] = {{"convention", wf.convention}, {"frame", "world"}, {"source", wf.source},
                        {"grid_to_world", m}};
  }
  j["voxel_size"] = r.grid.voxel_size;
  j["grid"] = {{"dims", {r.grid.dims[0], r.grid.dims[1], r.grid.dims[2]}},
               {"origin", {r.grid.origin[0], r.grid.origin[1], r.grid.origin[2]}}};
  if (r.resolution > 0) j["grid"]["resolution"] = r.resolution;
  const SurfaceStats& st = r.surface_stats;
  j["surface"] = {{"vertices", st.vertices}, {"faces", st.faces}, {"components", st.components},
                  {"genus", st.genus}, {"closed", st.closed_manifold}, {"euler", st.euler}};
  if (r.input_genus >= 0) j["surface"]["input_genus"] = r.input_genus;
  j["scales"] = {{"R_in", r.chokes.R_in}, {"R_out", r.chokes.R_out}};
  j["parameters"] = {{"d_max", options.chokes.d_max.text()},
                     {"min_persistence", options.chokes.min_persistence.text()},
                     {"d_max_abs", r.chokes.d_max_handle},
                     {"d_max_abs_handle", r.chokes.d_max_handle},
                     {"d_max_abs_tunnel", r.chokes.d_max_tunnel},
                     {"min_persistence_abs_handle", r.chokes.min_persistence_handle},
                     {"min_persistence_abs_tunnel", r.chokes.min_persistence_tunnel},
                     {"side", options.chokes.handles && options.chokes.tunnels ? "both" : options.chokes.handles ? "handle" : "tunnel"}};
  j["counts"] = {{"handle_generators", r.chokes.handle_generators},
                 {"tunnel_generators", r.chokes.tunnel_generators},
                 {"components", r.chokes.components},
                 {"gaps", r.chokes.gaps},
                 {"sealed_cavities", r.chokes.sealed_cavities},
                 {"pairs", {r.diagram.count(0), r.diagram.count(1), r.diagram.count(2)}}};
  FreudenthalComplex cx(r.grid.dims);
  json loops = json::array();
  for (std::size_t i = 0; i < r.loops.size(); ++i) loops.push_back(loop_json(r.loops[i], i, cx, wf));
  j["loops"] = loops;
  json hd = json::array(), td = json::array();
  for (auto& p : r.chokes.handle_diagram) hd.push_back({p[0], p[1]});
  for (auto& p : r.chokes.tunnel_diagram) td.push_back({p[0], p[1]});
  j["diagram"] = {{"handle", hd}, {"tunnel", td}};
  auto filtered = [](const std::array<double, 2>& c, double scale) {
    if (c[1] <= 0) return json(nullptr);
    return json{{"depth", c[0]}, {"persistence", c[1]}, {"persistence_percent", scale > 0 ? 100 * c[1] / scale : 0}};
  };
  j["strongest_filtered"] = {{"handle", filtered(r.chokes.strongest_filtered_handle, r.chokes.R_in)},
                             {"tunnel", filtered(r.chokes.strongest_filtered_tunnel, r.chokes.R_out)}};
  if (r.loops_omitted > 0) j["loops_omitted"] = r.loops_omitted;
  if (!r.extra_json.empty()) {
    const json extra = json::parse(r.extra_json);  // kept alive while its items are read
    for (auto it = extra.begin(); it != extra.end(); ++it) j[it.key()] = it.value();
  }
  j["warnings"] = r.warnings;
  json timings = json::object();
  for (auto& kv : r.timings_ms) timings[kv.first] = std::round(kv.second * 10) / 10;
  j["timings_ms"] = timings;
  return j.dump(1) + "\n";
}

std::string input_loops_json(const AnalyzeResult& r) {
  using nlohmann::json;
  json j;
  j["input"] = std::filesystem::path(r.input).filename().string();
  j["units"] = "input";
  const MeshReport& m = r.input_mesh.report;
  j["input_mesh"] = {{"vertices", r.input_mesh.mesh.vertices.size()}, {"faces", r.input_mesh.mesh.faces.size()},
                     {"repaired", r.input_mesh.repaired}, {"closed", m.closed}, {"components", m.components},
                     {"genus", m.genus}, {"euler", m.euler}};
  int added = 0;
  for (char a : r.input_mesh.added_face) added += a;
  if (r.input_mesh.repaired) j["input_mesh"]["faces_added_by_repair"] = added;
  FreudenthalComplex cx(r.grid.dims);
  json loops = json::array();
  int carried = 0;
  double transfer_ms = 0;
  for (std::size_t i = 0; i < r.input_loops.size(); ++i) {
    const InputLoop& il = r.input_loops[i];
    json e = loop_json(il.loop, i, cx, WorldFrame{});
    e["grid_length"] = il.grid_length;
    detail::add_input_loop_fields(e, il);
    loops.push_back(e);
    carried += il.loop.found;
    transfer_ms += il.transfer_ms;
  }
  j["counts"] = {{"loops", r.input_loops.size()}, {"carried", carried}};
  j["loops"] = loops;
  j["timings_ms"] = {{"input_loops", std::round((r.timings_ms.count("input_loops") ? r.timings_ms.at("input_loops") : 0) * 10) / 10},
                     {"per_loop_sum", std::round(transfer_ms * 10) / 10}};
  return j.dump(1) + "\n";
}

void write_report(const AnalyzeResult& r, const AnalyzeOptions& options, const std::string& outdir) {
  std::error_code ec;
  std::filesystem::create_directories(outdir, ec);
  if (ec || !std::filesystem::is_directory(outdir))
    throw Error("cannot create output directory '" + outdir + "': " + ec.message());
  const WorldFrame& wf = r.frame;
  if (wf.set) {
    SurfaceMesh world = r.surface;
    for (auto& v : world.vertices) v = wf.apply(v);
    write_ply(world, outdir + "/surface.ply");
  } else {
    write_ply(r.surface, outdir + "/surface.ply");
  }
  std::vector<Polyline3> polylines;
  for (const Loop& l : r.loops)
    if (l.found) {
      polylines.push_back(l.points);
      if (wf.set)
        for (auto& p : polylines.back()) p = wf.apply(p);
    }
  write_loops_ply(polylines, outdir + "/loops.ply");
  write_loops_obj(polylines, outdir + "/loops.obj");
  std::ofstream out(outdir + "/loops.json");
  out << report_json(r, options);
  if (!out) throw Error("cannot write '" + outdir + "/loops.json' (disk full?)");
  if (r.has_input_loops) {
    std::vector<Polyline3> on_input;
    for (const InputLoop& l : r.input_loops)
      if (l.loop.found) on_input.push_back(l.loop.points);
    write_loops_ply(on_input, outdir + "/input_loops.ply");
    // The mesh the input loops' ids refer to (the file's triangles, or their repair): view.html shows it.
    write_ply(r.input_mesh.mesh, outdir + "/input_mesh.ply");
    std::ofstream in(outdir + "/input_loops.json");
    in << input_loops_json(r);
    if (!in) throw Error("cannot write '" + outdir + "/input_loops.json' (disk full?)");
  }
}

}  // namespace chokeloops

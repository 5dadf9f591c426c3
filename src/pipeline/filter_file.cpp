#include "chokeloops/filter/filter_file.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <limits>

#include <nlohmann/json.hpp>

#include "chokeloops/io/vdb_io.h"
#include "chokeloops/io/volume_io.h"
#include "chokeloops/output/mesh_write.h"
#include "chokeloops/surface/surface.h"
#include "chokeloops/topology/complex.h"

namespace chokeloops {

namespace {

bool ends_with(const std::string& s, const std::string& tail) {
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

// Vertices with an axis neighbour on the other side: where the zero level set passes.
template <class Fn>
void for_surface_vertices(const ScalarGrid& g, Fn&& fn) {
  const std::int64_t st[3] = {1, g.dims[0], std::int64_t(g.dims[0]) * g.dims[1]};
  for (int k = 0; k < g.dims[2]; ++k)
    for (int j = 0; j < g.dims[1]; ++j)
      for (int i = 0; i < g.dims[0]; ++i) {
        const std::int64_t v = g.index(i, j, k);
        const int ijk[3] = {i, j, k};
        const bool in = g.values[std::size_t(v)] <= 0;
        for (int a = 0; a < 3; ++a)
          if ((ijk[a] > 0 && (g.values[std::size_t(v - st[a])] <= 0) != in) ||
              (ijk[a] + 1 < g.dims[a] && (g.values[std::size_t(v + st[a])] <= 0) != in)) {
            fn(v);
            break;
          }
      }
}

// Hausdorff distance between the zero level sets of two fields on the same grid, to about a voxel: the
// largest distance from one surface's vertices to the other surface, both ways.
double surface_hausdorff(const ScalarGrid& before, const ScalarGrid& after) {
  ScalarGrid exact_after = after;
  redistance_from_signs(exact_after);
  ScalarGrid exact_before = before;
  redistance_from_signs(exact_before);
  double h = 0;
  for_surface_vertices(after, [&](std::int64_t v) { h = std::max(h, double(std::abs(exact_before.values[std::size_t(v)]))); });
  for_surface_vertices(before, [&](std::int64_t v) { h = std::max(h, double(std::abs(exact_after.values[std::size_t(v)]))); });
  return h;
}

// The stored value a voxel gets to be inside (or outside) the mask the options define.
double value_for(const VolumeImage& image, const VolumeFieldOptions& f, bool inside) {
  if (f.has_label) return inside ? f.label : 0.0;
  const double iso = f.iso;
  const double at = image.integer_type ? std::ceil(iso) : iso;                       // >= iso
  const double below = image.integer_type ? std::ceil(iso) - 1 : std::nextafter(iso, -1e300);  // < iso
  return inside != f.inside_below ? at : below;
}

void check_output(const FilterSummary& got, const FilterSummary& want, const std::string& path) {
  if (got.genus != want.genus || got.components != want.components || got.cavities != want.cavities)
    throw InternalError("filter: " + path + " read back has genus " + std::to_string(got.genus) + ", " +
                        std::to_string(got.components) + " components, " + std::to_string(got.cavities) +
                        " cavities, where the filter left " + std::to_string(want.genus) + ", " +
                        std::to_string(want.components) + ", " + std::to_string(want.cavities));
}

}  // namespace

FilterFileResult filter_file(const std::string& input, const std::string& output, const FilterFileOptions& options,
                             const ProgressFn& progress) {
  FilterFileResult res;
  res.input = input;
  res.output = output;
  if (output.empty()) throw Error("no output given (-o OUTPUT)");
  const std::filesystem::path parent = std::filesystem::path(output).parent_path();
  std::error_code ec;
  if (!parent.empty() && !std::filesystem::is_directory(parent, ec) && !std::filesystem::create_directories(parent, ec))
    throw Error("cannot create the directory of " + output + ": " + ec.message(), 3);
  if (is_volume_path(input)) {
    res.kind = "volume";
    if (options.field.voxel_size > 0)
      throw Error(input + ": a volume is filtered on its own voxels; resampling (voxel_size) would change every one");
    const VolumeImage image = read_volume(input, options.volume);
    const VolumeField field = volume_to_levelset(image, options.field);
    const ScalarGrid& before = field.grid;
    ScalarGrid grid = field.grid;
    FreudenthalComplex cx(grid.dims);
    auto voxel_of = [&](Id v, std::array<int, 3>& q) {
      const auto p = cx.coords(v);
      for (int a = 0; a < 3; ++a) {
        q[a] = p[a] - field.pad[a];
        if (q[a] < 0 || q[a] >= image.dims[a]) return false;
      }
      return true;
    };
    FilterOptions fo = options.filter;
    // Only voxels of the image change; a label map's fill takes background voxels, never another label's.
    fo.can_change = [&](Id v) {
      std::array<int, 3> q;
      if (!voxel_of(v, q)) return false;
      if (!options.field.has_label || grid.values[std::size_t(v)] <= 0) return true;
      return image.values[std::size_t(q[0] + std::int64_t(image.dims[0]) * (q[1] + std::int64_t(image.dims[1]) * q[2]))] == 0;
    };
    res.report = filter_grid(grid, fo, progress);
    std::vector<std::pair<std::int64_t, double>> changes;
    for (std::size_t v = 0; v < grid.values.size(); ++v) {
      const bool in = grid.values[v] <= 0;
      if (in == (before.values[v] <= 0)) continue;
      std::array<int, 3> q;
      if (!voxel_of(Id(v), q)) throw InternalError("filter: an edit changed a vertex outside the image");
      changes.push_back({q[0] + std::int64_t(image.dims[0]) * (q[1] + std::int64_t(image.dims[1]) * q[2]),
                         value_for(image, options.field, in)});
    }
    write_edited_volume(image, changes, output);
    res.voxel_size = grid.voxel_size;
    res.grid_vertices = grid.values.size();
    res.hausdorff = surface_hausdorff(before, grid);
    const VolumeImage back = read_volume(output, options.volume);
    res.output_check = topology_summary(volume_to_levelset(back, options.field).grid);
    check_output(res.output_check, res.report.after, output);
    return res;
  }
  const bool vdb = ends_with(input, ".vdb");
  res.kind = vdb ? "vdb" : "mesh";
  if (vdb && !ends_with(output, ".vdb")) throw Error(output + ": a .vdb input is filtered into a .vdb level set: name the output *.vdb");
  if (!vdb && !ends_with(output, ".ply")) throw Error(output + ": a mesh is filtered into the filtered surface as .ply: name the output *.ply");
  LevelSetResult ls = make_levelset(input, options.levelset);
  ScalarGrid grid = std::move(ls.grid);
  const ScalarGrid before = grid;
  res.report = filter_grid(grid, options.filter, progress);
  res.voxel_size = grid.voxel_size;
  res.grid_vertices = grid.values.size();
  res.hausdorff = surface_hausdorff(before, grid);
  if (vdb) {
    write_vdb(grid, output);
    res.output_check = topology_summary(read_vdb_dense(output));
  } else {
    const SurfaceMesh surface = extract_zero_surface(grid);
    write_ply(surface, output);
    const SurfaceStats s = surface_stats(surface);
    // The surface's components are the solid's and its cavities' boundaries; its genus the handle count.
    res.output_check = {s.genus, s.components - res.report.after.cavities, res.report.after.cavities};
  }
  check_output(res.output_check, res.report.after, output);
  return res;
}

std::string filter_report_json(const FilterFileResult& r) {
  using nlohmann::json;
  auto summary = [](const FilterSummary& s) { return json{{"genus", s.genus}, {"components", s.components}, {"cavities", s.cavities}}; };
  json edits = json::array();
  for (const FilterEdit& e : r.report.edits)
    edits.push_back({{"kind", e.side == Side::Handle ? "cut" : "fill"},
                     {"side", e.side == Side::Handle ? "handle" : "tunnel"},
                     {"round", e.round},
                     {"location", {e.point[0], e.point[1], e.point[2]}},
                     {"depth", e.depth},
                     {"persistence", e.persistence},
                     {"voxels", e.voxels.size()},
                     {"volume", e.volume}});
  json j = {{"input", r.input},
            {"output", r.output},
            {"kind", r.kind},
            {"voxel_size", r.voxel_size},
            {"before", summary(r.report.before)},
            {"after", summary(r.report.after)},
            {"output_read_back", summary(r.output_check)},
            {"pairs_selected", r.report.selected},
            {"pairs_removed", r.report.before.genus - r.report.after.genus},
            {"rounds", r.report.rounds},
            {"voxels_changed", r.report.voxels_changed},
            {"voxels_changed_percent", r.grid_vertices ? 100.0 * double(r.report.voxels_changed) / double(r.grid_vertices) : 0.0},
            {"values_changed", r.report.values_changed},
            {"max_edit_depth", r.report.max_edit_depth},
            {"hausdorff", r.hausdorff},
            {"R_in", r.report.R_in},
            {"R_out", r.report.R_out},
            {"edits", edits},
            {"notes", r.report.notes},
            {"timings_ms", r.report.timings_ms}};
  return j.dump(1);
}

}  // namespace chokeloops

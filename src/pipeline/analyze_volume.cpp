#include "chokeloops/analyze_volume.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <set>
#include <sstream>

#include <nlohmann/json.hpp>
#include <tbb/parallel_for.h>

#include "chokeloops/loops/membrane_voxels.h"
#include "chokeloops/topology/complex.h"
#include "common/caller_progress.h"

namespace chokeloops {

namespace {
using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); }
}  // namespace

VolumeAnalysis analyze_volume(const VolumeImage& image, const VolumeFieldOptions& field, const AnalyzeOptions& options,
                              const ProgressFn& progress) {
  auto t0 = Clock::now();
  if (progress && !progress("levelset", 0)) throw Error("interrupted");
  VolumeField vf = volume_to_levelset(image, field);
  const double levelset_ms = ms_since(t0);
  VolumeAnalysis a;
  a.pad = vf.pad;
  std::ostringstream what;
  if (field.has_label) what << "label " << field.label;
  else what << "iso " << field.iso << (field.inside_below ? " (inside below)" : "");
  a.what = what.str();
  // The label volumes (write_loop_volumes) go on from the loop stage's floods.
  AnalyzeOptions with_membranes = options;
  with_membranes.record_membranes = true;
  a.result = analyze_grid(std::move(vf.grid), with_membranes, progress, image.path);
  AnalyzeResult& r = a.result;
  r.frame = vf.frame;
  r.timings_ms["levelset"] = levelset_ms;
  r.timings_ms["total"] = ms_since(t0);
  std::vector<std::string> warnings = image.warnings;
  warnings.insert(warnings.end(), r.warnings.begin(), r.warnings.end());
  r.warnings = warnings;
  nlohmann::json v = {{"format", image.format},
                      {"dims", {image.dims[0], image.dims[1], image.dims[2]}},
                      {"spacing_mm", {image.spacing[0], image.spacing[1], image.spacing[2]}},
                      {"datatype", image.datatype},
                      {"volume", image.volume},
                      {"volumes", image.volumes},
                      {"mask", a.what},
                      {"inside_voxels", vf.inside_voxels},
                      {"padding_voxels", {vf.pad[0], vf.pad[1], vf.pad[2]}}};
  if (field.voxel_size > 0) v["resampled_to_mm"] = field.voxel_size;
  nlohmann::json affine = nlohmann::json::array();
  for (auto& row : image.affine) affine.push_back({row[0], row[1], row[2], row[3]});
  v["index_to_world"] = affine;
  r.extra_json = nlohmann::json{{"volume", v}}.dump();
  return a;
}

std::vector<long long> image_labels(const VolumeImage& image) {
  std::set<long long> labels;
  for (float x : image.values) {
    if (x != std::floor(x))
      throw Error(image.path + ": value " + std::to_string(x) + " is not an integer: --labels needs a label map (use --iso for a scalar image)");
    if (x != 0) labels.insert((long long)x);
    if (labels.size() > 10000) throw Error(image.path + ": more than 10000 labels: not a label map (use --iso)");
  }
  return {labels.begin(), labels.end()};
}

std::vector<int> topology_defects(const AnalyzeResult& r, int expected_genus) {
  std::vector<int> gens;
  for (int i = 0; i < int(r.loops.size()); ++i)
    if (r.loops[i].choke.side == Side::Handle && r.loops[i].choke.kind == Kind::Generator) gens.push_back(i);
  std::stable_sort(gens.begin(), gens.end(), [&](int a, int b) {
    const Choke &ca = r.loops[a].choke, &cb = r.loops[b].choke;
    return ca.death - ca.birth > cb.death - cb.birth;
  });
  if (int(gens.size()) <= expected_genus) return {};
  return std::vector<int>(gens.begin() + std::max(0, expected_genus), gens.end());
}

LoopVolumes write_loop_volumes(const VolumeAnalysis& a, const VolumeImage& image, const std::string& outdir,
                               const ProgressFn& progress) {
  const AnalyzeResult& r = a.result;
  // Positions are in the grid frame (mm along the image's axes, image voxel (0,0,0) at 0), whether or not the
  // grid was resampled from the image.
  const std::array<double, 3>& h = image.spacing;
  const double step = 0.4 * std::min({h[0], h[1], h[2], r.grid.h(0), r.grid.h(1), r.grid.h(2)});
  std::vector<std::int32_t> loops(std::size_t(image.voxel_count()), 0), membranes(loops.size(), 0);
  auto voxel = [&](const int q[3]) {
    return std::size_t(q[0]) + std::size_t(image.dims[0]) * (std::size_t(q[1]) + std::size_t(image.dims[1]) * q[2]);
  };
  // Grid-frame position -> nearest image voxel (image voxel (0,0,0) is at the frame's 0).
  auto mark = [&](const std::array<double, 3>& p, std::int32_t id) {
    int q[3];
    for (int c = 0; c < 3; ++c) {
      q[c] = int(std::lround(p[c] / h[c]));
      if (q[c] < 0 || q[c] >= image.dims[c]) return;
    }
    loops[voxel(q)] = id;
  };
  for (int i = 0; i < int(r.loops.size()); ++i) {
    const Loop& l = r.loops[i];
    if (!l.found || l.points.size() < 3) continue;
    const std::size_t n = l.points.size();
    for (std::size_t s = 0; s < n; ++s) {
      const auto &p = l.points[s], &q = l.points[(s + 1) % n];
      const double len = std::sqrt((q[0] - p[0]) * (q[0] - p[0]) + (q[1] - p[1]) * (q[1] - p[1]) + (q[2] - p[2]) * (q[2] - p[2]));
      const int m = std::max(1, int(std::ceil(len / step)));
      for (int k = 0; k <= m; ++k) {
        const double t = double(k) / m;
        mark({p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1]), p[2] + t * (q[2] - p[2])}, i + 1);
      }
    }
  }
  // The membranes: the voxels whose flip removes the loop's handle (cut, in the solid) or tunnel (fill, in the
  // outside), as `chokeloops filter` would edit them: in boxes no wider than its widest (membrane_box_cap).
  // Each loop's own membrane, independent of the others.
  std::vector<MembraneVoxels> shores(r.loops.size());
  const std::array<RegionBounds, 2> bounds = region_bounds(r.grid);
  // The loop stage flooded the first boxes of many chokes' sequences already (AnalyzeResult::membranes).
  // Progress and a request to stop go through the calling thread, as in the loop stage (the grey-matter
  // map's membranes take seconds).
  if (progress && !progress("label volumes", 0)) throw Error("interrupted");
  detail::CallerProgress stage(progress, "label volumes", r.loops.size());
  tbb::parallel_for(std::size_t(0), r.loops.size(), [&](std::size_t i) {
    if (stage.stopped()) return;
    if (r.loops[i].found) {
      const MembraneProgress* from = i < r.membranes.size() ? &r.membranes[i] : nullptr;
      shores[i] = closing_membrane_voxels(r.grid, r.loops[i].choke, label_membrane_options(r.grid, r.loops[i].choke),
                                          MembraneShape::Sheet, true, &bounds, from);
    }
    stage.item_done();
  });
  stage.finish();
  const FreudenthalComplex cx(r.grid.dims);
  LoopVolumes out;
  for (std::size_t i = 0; i < shores.size(); ++i) {
    if (r.loops[i].found && !shores[i].found)
      out.warnings.push_back("loop " + std::to_string(i) + " has no membrane voxels: " + shores[i].note);
    for (Id v : shores[i].shore) {
      const auto p = cx.coords(v);
      int q[3];
      bool inside = true;
      for (int c = 0; c < 3; ++c) {
        q[c] = int(std::lround((r.grid.origin[c] + p[c] * r.grid.h(c)) / h[c]));
        inside = inside && q[c] >= 0 && q[c] < image.dims[c];
      }
      if (inside) membranes[voxel(q)] = std::int32_t(i + 1);
    }
  }
  out.files = {label_volume_name(image, "loops"), label_volume_name(image, "membranes")};
  write_label_volume(image, loops, outdir + "/" + out.files[0]);
  write_label_volume(image, membranes, outdir + "/" + out.files[1]);
  return out;
}

}  // namespace chokeloops

#include "chokeloops/analyze_volume.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <set>
#include <sstream>

#include <nlohmann/json.hpp>

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
  a.result = analyze_grid(std::move(vf.grid), options, progress, image.path);
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

std::vector<std::string> write_loop_volumes(const VolumeAnalysis& a, const VolumeImage& image, const std::string& outdir) {
  const AnalyzeResult& r = a.result;
  const std::array<double, 3> h{r.grid.h(0), r.grid.h(1), r.grid.h(2)};
  const double step = 0.4 * std::min({h[0], h[1], h[2]});
  std::vector<std::int32_t> loops(std::size_t(image.voxel_count()), 0), membranes(loops.size(), 0);
  // Grid-frame position -> nearest image voxel (image voxel (0,0,0) is at the frame's 0).
  auto mark = [&](std::vector<std::int32_t>& vol, const std::array<double, 3>& p, std::int32_t id) {
    int q[3];
    for (int c = 0; c < 3; ++c) {
      q[c] = int(std::lround(p[c] / h[c]));
      if (q[c] < 0 || q[c] >= image.dims[c]) return;
    }
    vol[std::size_t(q[0]) + std::size_t(image.dims[0]) * (std::size_t(q[1]) + std::size_t(image.dims[1]) * q[2])] = id;
  };
  auto lerp = [](const std::array<double, 3>& x, const std::array<double, 3>& y, double t) {
    return std::array<double, 3>{x[0] + t * (y[0] - x[0]), x[1] + t * (y[1] - x[1]), x[2] + t * (y[2] - x[2])};
  };
  auto dist = [](const std::array<double, 3>& x, const std::array<double, 3>& y) {
    return std::sqrt((x[0] - y[0]) * (x[0] - y[0]) + (x[1] - y[1]) * (x[1] - y[1]) + (x[2] - y[2]) * (x[2] - y[2]));
  };
  for (int i = 0; i < int(r.loops.size()); ++i) {
    const Loop& l = r.loops[i];
    if (!l.found || l.points.size() < 3) continue;
    const std::int32_t id = i + 1;
    const std::size_t n = l.points.size();
    for (std::size_t s = 0; s < n; ++s) {
      const auto &p = l.points[s], &q = l.points[(s + 1) % n];
      const int m = std::max(1, int(std::ceil(dist(p, q) / step)));
      for (int k = 0; k <= m; ++k) mark(loops, lerp(p, q, double(k) / m), id);
      // The disc: the triangle (centroid, p, q), sampled along lines from the centroid.
      const double reach = std::max(dist(l.centroid, p), dist(l.centroid, q));
      const int rings = std::max(1, int(std::ceil(reach / step)));
      for (int u = 0; u <= rings; ++u) {
        const double t = double(u) / rings;
        const auto a0 = lerp(l.centroid, p, t), a1 = lerp(l.centroid, q, t);
        const int mm = std::max(1, int(std::ceil(dist(a0, a1) / step)));
        for (int k = 0; k <= mm; ++k) mark(membranes, lerp(a0, a1, double(k) / mm), id);
      }
    }
  }
  std::vector<std::string> names = {label_volume_name(image, "loops"), label_volume_name(image, "membranes")};
  write_label_volume(image, loops, outdir + "/" + names[0]);
  write_label_volume(image, membranes, outdir + "/" + names[1]);
  return names;
}

}  // namespace chokeloops

// `chokeloops analyze IMAGE --iso T | --label N | --labels all -o OUTDIR`: one analysis per mask, the usual
// report (positions in the image's world mm), loops/membranes label volumes and, with --labels all, an
// index of the labels.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>

#include <nlohmann/json.hpp>

#include "analyze_volume_cli.h"
#include "chokeloops/output/view.h"

namespace chokeloops::cli {

namespace {

nlohmann::json summarize(const VolumeAnalysis& a, const AnalyzeOptions& options, const VolumeCliOptions& vo,
                         const std::string& outdir, const std::vector<std::string>& volumes, bool quiet) {
  const AnalyzeResult& r = a.result;
  int counts[2][2] = {{0, 0}, {0, 0}};
  for (auto& l : r.loops) counts[l.choke.side == Side::Tunnel][l.choke.kind == Kind::Choke] += 1;
  std::vector<int> defects = vo.expect_genus >= 0 ? topology_defects(r, vo.expect_genus) : std::vector<int>{};
  if (!quiet) {
    std::printf("%s [%s]: grid %dx%dx%d (spacing %.4g %.4g %.4g mm), surface %lld vertices, genus %d, %d component(s)\n",
                r.input.c_str(), a.what.c_str(), r.grid.dims[0], r.grid.dims[1], r.grid.dims[2], r.grid.h(0),
                r.grid.h(1), r.grid.h(2), (long long)r.surface_stats.vertices, r.surface_stats.genus,
                r.surface_stats.components);
    std::printf("handle generators %d, tunnel generators %d; loops traced: handle %d generator(s), %d choke(s), tunnel %d generator(s), %d choke(s)\n",
                r.chokes.handle_generators, r.chokes.tunnel_generators, counts[0][0], counts[0][1], counts[1][0], counts[1][1]);
    if (r.loops_omitted > 0)
      std::printf("loops traced for the %d most persistent chokes; %d more not traced (--max-loops all traces every one)\n",
                  int(r.loops.size()), r.loops_omitted);
    if (vo.expect_genus >= 0) {
      const int beyond = std::max(0, r.chokes.handle_generators - vo.expect_genus);
      std::printf("topology defects: %d handle(s) beyond the expected genus %d", beyond, vo.expect_genus);
      if (!defects.empty()) {
        std::printf("; loop ids (most persistent first):");
        for (std::size_t i = 0; i < defects.size() && i < 20; ++i) std::printf(" %d", defects[i]);
        if (defects.size() > 20) std::printf(" ... (%zu in loops.json)", defects.size());
      }
      std::printf("\n");
    }
    std::printf("coordinates: world mm, %s (%s)\n", r.frame.convention.c_str(), r.frame.source.c_str());
    // The label volumes (a membrane per loop) and the report files are part of the run's time: with every
    // loop traced the membranes can cost more than the loop stage.
    const double volumes_ms = r.timings_ms.count("volumes") ? r.timings_ms.at("volumes") : 0.0;
    const double report_ms = r.timings_ms.count("report") ? r.timings_ms.at("report") : 0.0;
    std::printf("time: levelset %.0f ms, persistence %.0f ms, surface %.0f ms, loops %.0f ms, check %.0f ms, label volumes %.0f ms, "
                "report %.0f ms, total %.0f ms\n",
                r.timings_ms.at("levelset"), r.timings_ms.at("persistence"), r.timings_ms.at("surface"),
                r.timings_ms.at("loops"), r.timings_ms.at("check"), volumes_ms, report_ms,
                r.timings_ms.at("total") + volumes_ms + report_ms);
    std::printf("wrote %s/{surface.ply,loops.ply,loops.obj,loops.json,%s,%s%s}\n", outdir.c_str(), volumes[0].c_str(),
                volumes[1].c_str(), vo.view ? ",view.html" : "");
  }
  (void)options;
  return {{"mask", a.what},
          {"genus", r.surface_stats.genus},
          {"components", r.surface_stats.components},
          {"handle_generators", r.chokes.handle_generators},
          {"tunnel_generators", r.chokes.tunnel_generators},
          {"loops", r.loops.size()},
          {"loops_omitted", r.loops_omitted},
          {"topology_defects", defects.size()}};
}

VolumeAnalysis analyze_one(const VolumeImage& image, const VolumeFieldOptions& field, const AnalyzeOptions& options,
                           const VolumeCliOptions& vo, const std::string& outdir, const ProgressFn& progress,
                           nlohmann::json& summary) {
  VolumeAnalysis a = analyze_volume(image, field, options, progress);
  if (vo.expect_genus >= 0) {
    nlohmann::json extra = nlohmann::json::parse(a.result.extra_json);
    extra["expected_genus"] = vo.expect_genus;
    extra["topology_defects"] = topology_defects(a.result, vo.expect_genus);
    a.result.extra_json = extra.dump();
  }
  // The label volumes first, so that loops.json carries their warnings too.
  std::error_code ec;
  std::filesystem::create_directories(outdir, ec);
  auto since = [](std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
  };
  auto t = std::chrono::steady_clock::now();
  const LoopVolumes volumes = write_loop_volumes(a, image, outdir, progress);
  a.result.timings_ms["volumes"] = since(t);
  if (progress) progress("done", 1);
  a.result.warnings.insert(a.result.warnings.end(), volumes.warnings.begin(), volumes.warnings.end());
  t = std::chrono::steady_clock::now();
  write_report(a.result, options, outdir);
  if (vo.view) write_view_html(outdir);
  a.result.timings_ms["report"] = since(t);
  for (auto& w : a.result.warnings) std::cerr << "chokeloops analyze: warning: " << w << "\n";
  summary = summarize(a, options, vo, outdir, volumes.files, false);
  return a;
}

}  // namespace

int run_volume(const std::string& input, const std::string& outdir, const AnalyzeOptions& options,
               const VolumeCliOptions& vo, const ProgressFn& progress) {
  VolumeImage image = read_volume(input, vo.volume);
  nlohmann::json summary;
  if (!vo.all_labels) {
    analyze_one(image, vo.field, options, vo, outdir, progress, summary);
    return 0;
  }
  std::vector<long long> labels = image_labels(image);
  if (labels.empty()) throw Error(input + ": the label map has no non-zero label");
  nlohmann::json index = {{"input", input}, {"labels", nlohmann::json::array()}};
  for (long long label : labels) {
    VolumeFieldOptions f = vo.field;
    f.has_label = true;
    f.label = double(label);
    const std::string dir = outdir + "/label_" + std::to_string(label);
    analyze_one(image, f, options, vo, dir, progress, summary);
    summary["label"] = label;
    summary["directory"] = "label_" + std::to_string(label);
    index["labels"].push_back(summary);
  }
  std::ofstream out(outdir + "/labels.json");
  out << index.dump(1) << "\n";
  if (!out) throw Error("cannot write " + outdir + "/labels.json", 3);
  std::printf("wrote %s/labels.json (%zu labels)\n", outdir.c_str(), labels.size());
  return 0;
}

}  // namespace chokeloops::cli

#include "chokeloops/analyze.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>

#include "chokeloops/surface/mesh_adjacency.h"
#include "chokeloops/surface/topology.h"
#include "loop_checks.h"

namespace chokeloops {

namespace {
using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); }

bool is_vdb(const std::string& path) {
  return path.size() >= 4 && path.compare(path.size() - 4, 4, ".vdb") == 0;
}

LevelSetResult levelset_at(const std::string& input, LevelSetOptions options, int resolution) {
  options.resolution = resolution;
  options.voxel_size = 0;
  options.quiet = true;
  options.keep_vdb = false;
  return make_levelset(input, options);
}

// Surface genus and components at a given resolution, for the genus guard.
SurfaceStats surface_stats_at(const std::string& input, const LevelSetOptions& options, int resolution) {
  return surface_stats(extract_zero_surface(levelset_at(input, options, resolution).grid));
}

// Whether a level set of `voxels` vertices fits in the budget make_levelset will enforce.
bool levelset_fits(double voxels, const LevelSetOptions& options) {
  const std::size_t budget = options.max_memory ? options.max_memory : default_max_memory();
  return estimate_levelset_bytes(std::size_t(voxels)) <= budget;
}

// A self-intersecting mesh bounds a solid whose surface need not have the mesh's genus: no grid recovers
// it. Asked only when the genus differs (CGAL's test costs ~0.3 s per 100K faces).
std::string self_intersection_note(const std::string& input) {
  try {
    MeshRepairOptions o;
    o.check_self_intersections = true;
    RepairedMesh m = repair_mesh(read_mesh(input), input, o);
    if (m.report.self_intersecting)
      return "; note that the input intersects itself, and the solid it bounds need not have the mesh's genus";
  } catch (const std::exception&) {
  }
  return "";
}
}  // namespace

AnalyzeResult analyze_grid(ScalarGrid grid, const AnalyzeOptions& options, const ProgressFn& progress,
                           const std::string& name) {
  AnalyzeResult r;
  r.input = name;
  r.grid = std::move(grid);
  auto t_start = Clock::now();
  auto stage = [&](const char* s, double f) {
    if (progress && !progress(s, f)) throw Error("interrupted");
  };
  auto t = Clock::now();
  r.diagram = lower_star_persistence(
      r.grid, [&](const char*, double f) { stage("persistence", f); return true; }, options.levelset.max_memory);
  r.timings_ms["persistence"] = ms_since(t);

  t = Clock::now();
  stage("chokes", 0);
  r.chokes = find_chokes(r.grid, r.diagram, options.chokes);
  if (options.max_loops >= 0 && int(r.chokes.chokes.size()) > options.max_loops) {
    // Tens of thousands of generators (raw probability maps): trace the most persistent first.
    std::stable_sort(r.chokes.chokes.begin(), r.chokes.chokes.end(), [](const Choke& a, const Choke& b) {
      return a.death - a.birth > b.death - b.birth;
    });
    r.loops_omitted = int(r.chokes.chokes.size()) - options.max_loops;
    r.chokes.chokes.resize(std::size_t(options.max_loops));
  }
  r.timings_ms["chokes"] = ms_since(t);

  stage("surface", 0);
  std::vector<int> face_label;
  MeshAdjacency adjacency = extract_checked_surface(r, face_label);

  t = Clock::now();
  stage("loops", 0);
  LoopContext context;
  prepare_loops(r, std::move(adjacency), std::move(face_label), context);
  if (std::getenv("CHOKELOOPS_DEBUG_MEMBRANES")) std::fprintf(stderr, "loop stage: prepare %.0f ms\n", ms_since(t));
  r.loops = trace_loops(r.grid, r.surface, context.adjacency, r.chokes.chokes, options.loops, context.topology.get(),
                        r.surface_stats.closed_manifold && r.loops_omitted == 0 ? int(r.surface_stats.genus) : -1,
                        options.record_membranes ? &r.membranes : nullptr, progress);
  r.timings_ms["loops"] = ms_since(t);
  t = Clock::now();
  if (context.topology && options.check_generators) drop_contractible_generators(r.loops, *context.topology);
  r.timings_ms["check"] = ms_since(t);
  warn_about_missing_loops(r.loops, r.warnings);
  stage("done", 1);
  r.timings_ms["total"] = ms_since(t_start);
  return r;
}

AnalyzeResult analyze(const std::string& input, const AnalyzeOptions& options, const ProgressFn& progress) {
  auto t0 = Clock::now();
  if (progress && !progress("levelset", 0)) throw Error("interrupted");
  LevelSetOptions ls_options = options.levelset;
  ls_options.keep_vdb = false;
  ls_options.quiet = true;
  int resolution = ls_options.voxel_size > 0 ? 0 : ls_options.resolution;
  std::vector<std::string> warnings;
  int input_genus = -1;
  std::string auto_failure;  // set when --resolution auto finds no grid that keeps the input's topology
  // The search's last grid is the one analysed: kept rather than made again (Neptune: 2 s at 472).
  LevelSetResult searched;
  auto t = Clock::now();
  if (options.resolution_auto && !is_vdb(input)) {
    // The coarsest grid whose surface keeps the closed input's genus and components, from 64 voxels up to
    // 1024 or the largest grid that fits in memory, whichever comes first.
    ls_options.voxel_size = 0;
    LevelSetResult probe = levelset_at(input, ls_options, 64);
    input_genus = probe.report.closed ? probe.report.genus : -1;
    const int input_components = int(probe.report.components);
    resolution = options.levelset.resolution;
    if (input_genus >= 0) {
      const double probe_voxels = double(probe.grid.values.size()), probe_voxel_size = probe.grid.voxel_size;
      int finest = 0;
      SurfaceStats finest_stats;
      bool found = false;
      bool memory_bound = false;
      for (int res = 64; res <= 1024; res = int(res * 1.25)) {
        // The box grows as the cube of the resolution (the margin is a fixed fraction of the object).
        const double f = double(res) / 64.0;
        if (!levelset_fits(probe_voxels * f * f * f, ls_options)) {
          memory_bound = true;
          break;
        }
        // The genus alone can match by accident: on Neptune at 80 thin parts break off (7 components) and
        // the genus happens to be right; the components must match too.
        if (res == 64) {
          searched = std::move(probe);
        } else {
          searched = LevelSetResult{};  // one grid at a time
          searched = levelset_at(input, ls_options, res);
        }
        SurfaceStats st = surface_stats(extract_zero_surface(searched.grid));
        finest = res;
        finest_stats = st;
        if (st.genus == input_genus && st.components == input_components) {
          found = true;
          break;
        }
      }
      if (finest == 0) finest = 64;  // not even 64 fits the budget: make_levelset below refuses it with the fix
      resolution = finest;
      if (!found) {
        const double voxel = probe_voxel_size * 64.0 / finest;
        char h[32];
        std::snprintf(h, sizeof h, "%.4g", voxel);
        auto_failure = "--resolution auto: no grid up to " + std::to_string(finest) + " voxels (" +
                       (memory_bound ? "the largest that fits in memory" : "the search's limit") +
                       ") keeps the input's genus " + std::to_string(input_genus) + " and " +
                       std::to_string(input_components) + " component(s); at " + std::to_string(finest) +
                       " the surface has genus " + std::to_string(finest_stats.genus) + " and " +
                       std::to_string(finest_stats.components) +
                       " component(s), so the input has handles, tunnels or gaps thinner than " + h +
                       " (the voxel there)";
      }
    }
    ls_options.resolution = resolution;
  }
  // With --resolution auto, the level set time is the whole search's.
  LevelSetResult ls = searched.grid.values.empty() ? make_levelset(input, ls_options) : std::move(searched);
  double levelset_ms = ms_since(t);
  if (!is_vdb(input) && ls.report.closed) input_genus = ls.report.genus;
  ScalarGrid grid = std::move(ls.grid);
  AnalyzeResult r = analyze_grid(std::move(grid), options, progress, input);
  r.levelset_info = std::move(ls);
  r.levelset_info.grid = ScalarGrid{};
  r.input_genus = input_genus;
  r.resolution = resolution;
  r.timings_ms["levelset"] = levelset_ms;
  for (auto& w : r.levelset_info.warnings) warnings.push_back(w);
  if (!auto_failure.empty()) {
    warnings.push_back(auto_failure + self_intersection_note(input));
  } else if (input_genus >= 0 && r.surface_stats.genus != input_genus) {
    // Never a silently different genus: find and name a resolution that keeps it.
    // Two finer grids at most (x1.5, x2.25), and only those that fit in memory.
    std::string hint = "a finer --resolution (or --resolution auto)";
    if (resolution > 0) {
      const double voxels = double(r.grid.values.size());
      for (double factor : {1.5, 2.25}) {
        int res = int(resolution * factor);
        if (!levelset_fits(voxels * factor * factor * factor, ls_options)) break;
        if (surface_stats_at(input, ls_options, res).genus == input_genus) { hint = "--resolution " + std::to_string(res); break; }
      }
    }
    warnings.push_back("the grid is too coarse: the input mesh has genus " + std::to_string(input_genus) +
                       " but its surface at this resolution has genus " + std::to_string(r.surface_stats.genus) +
                       "; rerun with " + hint + self_intersection_note(input));
  }
  warnings.insert(warnings.end(), r.warnings.begin(), r.warnings.end());
  r.warnings = warnings;
  if (!is_vdb(input) && options.input_loops) add_input_loops(r, input);
  r.timings_ms["total"] = ms_since(t0);
  return r;
}

MeshAdjacency extract_checked_surface(AnalyzeResult& r, std::vector<int>& face_label) {
  const auto t = Clock::now();
  r.surface = extract_zero_surface(r.grid);
  MeshAdjacency adjacency = build_adjacency(r.surface);
  r.surface_stats = surface_stats(r.surface, adjacency, &face_label);
  r.timings_ms["surface"] = ms_since(t);
  check_surface(r);
  return adjacency;
}

void check_surface(AnalyzeResult& r) {
  const char* fault = std::getenv("CHOKELOOPS_TEST_FAULT");
  const bool injected = fault && std::string(fault) == "self-check";
  if ((r.surface_stats.genus != r.chokes.handle_generators && r.surface_stats.closed_manifold) || injected)
    throw InternalError("self-check failed: surface genus " + std::to_string(r.surface_stats.genus) + " differs from the " +
                        std::to_string(r.chokes.handle_generators) + " handle generators");
  if (!r.surface_stats.closed_manifold)
    r.warnings.push_back("the surface touches the border of the grid and is not closed; enlarge --margin");
}

bool any_generator(const AnalyzeResult& r) {
  return std::any_of(r.chokes.chokes.begin(), r.chokes.chokes.end(), [](const Choke& c) { return c.kind == Kind::Generator; });
}

void prepare_loops(const AnalyzeResult& r, MeshAdjacency adjacency, std::vector<int> face_label, LoopContext& context) {
  prepare_loops(r, std::move(adjacency), std::move(face_label), any_generator(r), context);
}

void prepare_loops(const AnalyzeResult& r, MeshAdjacency adjacency, std::vector<int> face_label, bool with_topology,
                   LoopContext& context) {
  context.adjacency = std::move(adjacency);
  // One topology of the surface serves the choice of every generator's curve and the check after.
  if (with_topology)
    context.topology = std::make_unique<SurfaceTopology>(r.surface, context.adjacency, std::move(face_label),
                                                         int(r.surface_stats.components));
}

void drop_contractible_generators(std::vector<Loop>& loops, SurfaceTopology& topology, const std::vector<bool>* skip) {
  for (std::size_t i = 0; i < loops.size(); ++i) {
    Loop& l = loops[i];
    if ((skip && (*skip)[i]) || !l.found || l.choke.kind != Kind::Generator) continue;
    if (topology.contractible_fast(l.edge_path)) {
      l.found = false;
      l.note = "the generator's loop is contractible on the surface after shortening; no valid generator loop";
      l.points.clear();
      l.edge_path.clear();
    }
  }
}

void warn_about_missing_loops(const std::vector<Loop>& loops, std::vector<std::string>& warnings,
                              const std::vector<bool>* by_design) {
  int missing = 0;
  for (std::size_t i = 0; i < loops.size(); ++i) missing += !loops[i].found && !(by_design && (*by_design)[i]);
  if (missing)
    warnings.push_back(std::to_string(missing) + " choke(s) have no loop (see each loop's note); they are listed with empty points");
}

}  // namespace chokeloops

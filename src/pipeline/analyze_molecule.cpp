// The molecule pipeline. It runs analyze_grid's stages itself because tunnel loops come first from the
// exact bottlenecks (the surface's cross-section there, cheap and inside the pore) and only the chokes
// without one, and the handles, grow membranes: on a bumpy molecular surface a membrane loop of a channel
// can run far from the pore (gramicidin: 35.7 Å against a lumen of ~7.5 Å) and costs most of the run.
// Tunnels narrower than the probe (--min-radius) and handles shallower than it are gaps and contacts between
// atoms: they keep their bottleneck or depth and a note, and are not traced.
#include "chokeloops/analyze_molecule.h"

#include <tbb/task_group.h>

#include <algorithm>
#include <chrono>
#include <cstdio>

#include "chokeloops/field/memory_budget.h"
#include "loop_checks.h"

namespace chokeloops {

namespace {
// What the surface's adjacency (vertex-face lists, twins, vertex cells) and its statistics' scratch
// (per-vertex counts, the components' union-find and labels) take at most, from its vertex and face counts.
std::size_t adjacency_and_stats_bytes(std::size_t vertices, std::size_t faces) {
  return 40 * (vertices + faces) + (std::size_t(16) << 20);
}
// A rough field's persistence peaks near 40 bytes a voxel (README, Performance); a molecule's field is far
// smoother, so this bounds it from above.
constexpr std::size_t kPersistenceBoundPerVoxel = 48;
// What the loop stage's topology adds to them: its vertex labels and union-find (8 bytes a vertex), the
// homology basis's byte a half-edge and DFS interval a face (11 bytes a face).
std::size_t topology_bytes(std::size_t vertices, std::size_t faces) { return 12 * vertices + 12 * faces; }
}  // namespace

MoleculeAnalysis analyze_molecule(const std::string& path, const AnalyzeOptions& analyze, const MoleculeOptions& options,
                                  const ProgressFn& progress) {
  using Clock = std::chrono::steady_clock;
  auto ms = [](Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); };
  auto stage = [&](const char* s, double f) {
    if (progress && !progress(s, f)) throw Error("interrupted");
  };
  const auto t0 = Clock::now();
  stage("read", 0);
  MoleculeAnalysis m;
  AnalyzeResult& r = m.result;
  r.input = path;
  m.molecule = read_molecule(path, options.read);
  r.timings_ms["read"] = ms(t0);

  MolecularFieldOptions fo = options.field;
  if (analyze.levelset.voxel_size > 0) fo.voxel_size = analyze.levelset.voxel_size;
  if (analyze.levelset.margin >= 0) fo.margin = analyze.levelset.margin;
  if (analyze.levelset.max_memory) fo.max_memory = analyze.levelset.max_memory;
  auto t = Clock::now();
  stage("levelset", 0);
  r.grid = molecular_field(m.molecule, fo);
  r.timings_ms["levelset"] = ms(t);

  // The surface does not depend on the diagram: once it is marched, its adjacency and statistics, and (on a
  // surface with handles) its topology and homology basis for the loop stage, are built beside the
  // persistence, the chokes and the channels, which leave part of a core idle (their sequential phases), when
  // the budget certainly holds both; otherwise the adjacency after the persistence, and the topology beside
  // the channels (which only read the surface). Each is timed on its own; they overlap.
  t = Clock::now();
  stage("surface", 0);
  r.surface = extract_zero_surface(r.grid);
  double surface_ms = ms(t);
  const std::size_t budget = analyze.levelset.max_memory ? analyze.levelset.max_memory : default_max_memory();
  // The persistence's guard gets what the surface (and, beside it, its structures) leaves of the budget.
  const std::size_t V = r.surface.vertices.size(), F = r.surface.faces.size();
  const std::size_t surface_bytes = V * sizeof(r.surface.vertices[0]) + F * sizeof(r.surface.faces[0]);
  const std::size_t beside = adjacency_and_stats_bytes(V, F) + topology_bytes(V, F);
  const std::size_t voxels = std::size_t(r.grid.dims[0]) * std::size_t(r.grid.dims[1]) * std::size_t(r.grid.dims[2]);
  const bool overlap = budget > surface_bytes + beside &&
                       budget - surface_bytes - beside >= kPersistenceBoundPerVoxel * voxels;
  const std::size_t persistence_budget =
      std::max<std::size_t>(1, budget - std::min(budget, surface_bytes + (overlap ? beside : 0)));
  std::vector<int> face_label;
  MeshAdjacency surface_adjacency;
  LoopContext context;
  auto build_surface_structures = [&] {
    const auto ts = Clock::now();
    surface_adjacency = build_adjacency(r.surface);
    r.surface_stats = surface_stats(r.surface, surface_adjacency, &face_label);
    surface_ms += ms(ts);
  };
  // The loop stage's topology of the surface: its components, then its homology basis (serial passes over all
  // its faces, about 1 s on maltoporin's 17.7M).
  auto build_topology = [&](bool with_topology) {
    prepare_loops(r, std::move(surface_adjacency), std::move(face_label), with_topology, context);
    if (context.topology) context.topology->prepare_homology();
  };
  std::vector<std::array<double, 3>> centres;
  std::vector<double> vdw_radii;
  for (auto& a : m.molecule.atoms) centres.push_back(a.pos), vdw_radii.push_back(a.radius);
  // The SES's outside distance is the vdW one wherever a probe fits, so its bottlenecks are measured there.
  AtomLocator vdw(centres, vdw_radii);
  AtomLocator surf(centres, surface_radii(m.molecule, fo.surface == MolecularSurface::Sas ? MolecularSurface::Sas
                                                                                           : MolecularSurface::Vdw, fo.probe));
  auto find_channels = [&] {
    const auto tc = Clock::now();
    stage("channels", 0);
    m.channels = analyze_channels(r.grid, r.surface, surf, vdw, r.chokes.chokes, options.channels);
    r.timings_ms["channels"] = ms(tc);
  };
  // Only generators need the topology; a surface with handles has some, and one of genus 0 may still have
  // some (open at the grid's border), so there the topology waits for the chokes.
  bool topology_ready = false;
  double topology_ms = 0;  // r.timings_ms is written by this thread only
  tbb::task_group surface_task;
  if (overlap)
    surface_task.run([&] {
      build_surface_structures();
      if (r.surface_stats.genus > 0) {
        const auto ts = Clock::now();
        build_topology(true);
        topology_ready = true;
        topology_ms = ms(ts);
      }
    });
  try {
    t = Clock::now();
    r.diagram = lower_star_persistence(
        r.grid, [&](const char*, double f) { stage("persistence", f); return true; },
        persistence_budget);
    r.timings_ms["persistence"] = ms(t);
    t = Clock::now();
    stage("chokes", 0);
    r.chokes = find_chokes(r.grid, r.diagram, analyze.chokes);
    r.timings_ms["chokes"] = ms(t);
    if (overlap) find_channels();
  } catch (...) {
    if (overlap) surface_task.wait();
    throw;
  }
  if (overlap) surface_task.wait();
  else build_surface_structures();
  r.timings_ms["surface"] = surface_ms;
  if (topology_ready) r.timings_ms["topology"] = topology_ms;
  check_surface(r);
  const bool with_topology = any_generator(r);
  if (topology_ready && !with_topology) context.topology.reset();  // as prepare_loops: none without generators
  if (!topology_ready) {  // beside the channels, which run in parallel and only read the surface
    const auto tt = Clock::now();
    tbb::task_group topology_task;
    topology_task.run([&] { build_topology(with_topology); });
    if (!overlap) find_channels();
    topology_task.wait();
    r.timings_ms["topology"] = ms(tt);
  }

  t = Clock::now();
  stage("loops", 0);
  const MeshAdjacency& adjacency = context.adjacency;
  SurfaceTopology* topology = context.topology.get();
  r.loops.assign(r.chokes.chokes.size(), Loop{});
  std::vector<bool> done(r.chokes.chokes.size(), false);
  for (const Channel& c : m.channels) {
    const Choke& choke = r.chokes.chokes[std::size_t(c.loop)];
    if (!c.traced) {  // narrower than the probe: a bottleneck and a note, no loop
      r.loops[std::size_t(c.loop)].choke = choke;
      r.loops[std::size_t(c.loop)].note = c.note;
      done[std::size_t(c.loop)] = true;
      continue;
    }
    if (c.section.empty()) continue;
    Loop l = section_loop(choke, c.section, r.surface, adjacency);
    // a generator's loop must be non-contractible; a cross-section that is not falls back to the membrane
    if (choke.kind == Kind::Generator && (l.edge_path.empty() || !topology || topology->contractible_fast(l.edge_path)))
      continue;
    r.loops[std::size_t(c.loop)] = std::move(l);
    done[std::size_t(c.loop)] = true;
  }
  std::vector<bool> narrow_handle(r.chokes.chokes.size(), false);
  std::vector<Choke> rest;
  std::vector<std::size_t> rest_index;
  for (std::size_t i = 0; i < r.chokes.chokes.size(); ++i) {
    if (done[i]) continue;
    if (r.chokes.chokes[i].side == Side::Tunnel && !options.channels.trace_unsectioned) {
      r.loops[i].choke = r.chokes.chokes[i];
      r.loops[i].note = "no cross-section of the surface around the bottleneck; membranes not traced (--sections-only)";
      done[i] = true;
      continue;
    }
    // A handle of a vdW surface is a ring of atoms closed where two of them barely overlap: its depth is that
    // contact's neck. Below the probe radius it is a contact, not a wall around a channel, and its membrane
    // costs most of the run (gramicidin: every handle is under 0.31 A deep).
    if (r.chokes.chokes[i].side == Side::Handle && r.chokes.chokes[i].depth < options.channels.min_radius) {
      char buf[200];
      std::snprintf(buf, sizeof buf, "ring of atoms closed by a contact %.3f A deep, thinner than --min-radius %g A: "
                    "not traced", r.chokes.chokes[i].depth, options.channels.min_radius);
      r.loops[i].choke = r.chokes.chokes[i];
      r.loops[i].note = buf;
      done[i] = narrow_handle[i] = true;
      continue;
    }
    rest.push_back(r.chokes.chokes[i]), rest_index.push_back(i);
  }
  std::vector<Loop> traced = trace_loops(r.grid, r.surface, adjacency, rest, analyze.loops, topology, -1, nullptr, progress);
  for (std::size_t k = 0; k < traced.size(); ++k) r.loops[rest_index[k]] = std::move(traced[k]);
  r.timings_ms["loops"] = ms(t);
  t = Clock::now();
  if (topology && analyze.check_generators) drop_contractible_generators(r.loops, *topology, &done);
  r.timings_ms["check"] = ms(t);
  std::vector<bool> narrow = narrow_handle;
  int n_narrow = 0, n_handles = 0, n_thin = int(std::count(narrow_handle.begin(), narrow_handle.end(), true));
  for (const Channel& c : m.channels)
    if (!c.traced) narrow[std::size_t(c.loop)] = true, ++n_narrow;
  for (const Choke& c : r.chokes.chokes) n_handles += c.side == Side::Handle;
  warn_about_missing_loops(r.loops, r.warnings, &narrow);
  if (n_narrow || n_thin) {
    char buf[400];
    std::string what;
    if (n_narrow) {
      std::snprintf(buf, sizeof buf, "%d of %zu tunnels are narrower (bottleneck and lining reported, no profile or "
                    "loop)", n_narrow, m.channels.size());
      what = buf;
    }
    if (n_thin) {
      std::snprintf(buf, sizeof buf, "%d of %d handles are rings of atoms closed by thinner contacts (not traced)",
                    n_thin, n_handles);
      what += (what.empty() ? "" : "; ") + std::string(buf);
    }
    std::snprintf(buf, sizeof buf, "--min-radius %g A: %s; --min-radius 0 traces all", options.channels.min_radius,
                  what.c_str());
    r.warnings.push_back(buf);
  }
  r.warnings.insert(r.warnings.begin(), m.molecule.warnings.begin(), m.molecule.warnings.end());
  stage("done", 1);
  r.timings_ms["total"] = ms(t0);
  return m;
}

}  // namespace chokeloops

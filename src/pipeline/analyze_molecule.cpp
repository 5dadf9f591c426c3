#include "chokeloops/analyze_molecule.h"

#include <chrono>

#include "chokeloops/surface/mesh_adjacency.h"

namespace chokeloops {

MoleculeAnalysis analyze_molecule(const std::string& path, const AnalyzeOptions& analyze, const MoleculeOptions& options,
                                  const ProgressFn& progress) {
  using Clock = std::chrono::steady_clock;
  auto ms = [](Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); };
  const auto t0 = Clock::now();
  if (progress && !progress("read", 0)) throw Error("interrupted");
  MoleculeAnalysis m;
  m.molecule = read_molecule(path, options.read);
  const double read_ms = ms(t0);
  MolecularFieldOptions fo = options.field;
  if (analyze.levelset.voxel_size > 0) fo.voxel_size = analyze.levelset.voxel_size;
  if (analyze.levelset.margin >= 0) fo.margin = analyze.levelset.margin;
  if (analyze.levelset.max_memory) fo.max_memory = analyze.levelset.max_memory;
  auto t = Clock::now();
  if (progress && !progress("levelset", 0)) throw Error("interrupted");
  ScalarGrid grid = molecular_field(m.molecule, fo);
  const double field_ms = ms(t);
  m.result = analyze_grid(std::move(grid), analyze, progress, path);

  t = Clock::now();
  if (progress && !progress("channels", 0)) throw Error("interrupted");
  std::vector<std::array<double, 3>> centres;
  std::vector<double> vdw_radii;
  for (auto& a : m.molecule.atoms) centres.push_back(a.pos), vdw_radii.push_back(a.radius);
  // The SES's outside distance is the vdW one wherever a probe fits, so its bottlenecks are measured there.
  AtomLocator vdw(centres, vdw_radii);
  AtomLocator surf(centres, surface_radii(m.molecule, fo.surface == MolecularSurface::Sas ? MolecularSurface::Sas
                                                                                           : MolecularSurface::Vdw, fo.probe));
  MeshAdjacency adjacency = build_adjacency(m.result.surface);
  m.channels = analyze_channels(m.result.grid, m.result.surface, adjacency, surf, vdw, m.result.loops, options.channels);
  int missing = 0;
  for (auto& l : m.result.loops) missing += !l.found;
  for (auto it = m.result.warnings.begin(); it != m.result.warnings.end();)
    it = it->find("choke(s) have no loop") != std::string::npos ? m.result.warnings.erase(it) : it + 1;
  if (missing)
    m.result.warnings.push_back(std::to_string(missing) + " choke(s) have no loop (see each loop's note); they are listed with empty points");
  m.result.timings_ms["channels"] = ms(t);
  m.result.timings_ms["read"] = read_ms;
  m.result.timings_ms["levelset"] = field_ms;
  m.result.warnings.insert(m.result.warnings.begin(), m.molecule.warnings.begin(), m.molecule.warnings.end());
  m.result.timings_ms["total"] = ms(t0);
  return m;
}

}  // namespace chokeloops

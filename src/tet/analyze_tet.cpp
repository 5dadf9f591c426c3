#include "chokeloops/tet/analyze_tet.h"

#include <algorithm>
#include <chrono>
#include <limits>

#include "chokeloops/grid.h"

namespace chokeloops {

namespace {

// The grid's pairs hold floats. A value above 0 must stay above it: "0+" (denorm_min) and tiny distances would
// round to 0 and move a tunnel's death into the solid, losing the pair from the genus.
float to_float_keeping_sign(double x) {
  const float f = float(x);
  return x > 0 && f <= 0 ? std::numeric_limits<float>::denorm_min() : f;
}

}  // namespace

TetAnalysis analyze_tet_complex(const TriangleMesh& mesh, const TetOptions& tet, const ChokeParameters& params,
                                bool trace_loops, const TetLoopOptions& loops) {
  TetAnalysis a;
  a.input.vertices = mesh.vertices;
  a.input.faces = mesh.faces;
  a.input_report = mesh_topology(mesh);
  const TetField field = tetrahedralize_with_distance(mesh, tet);
  a.timings_ms["tetgen"] = field.seconds_tetgen * 1e3;
  a.timings_ms["distance"] = field.seconds_distance * 1e3;
  a.vertices = std::int64_t(field.vertices.size());
  a.tets = std::int64_t(field.tets.size());
  const TetDiagram d = tet_lower_star_persistence(std::int32_t(field.vertices.size()), field.tets, field.values, &field.inside_tets);
  a.simplices = d.simplices;
  a.timings_ms["persistence"] = (d.seconds_build + d.seconds_reduce) * 1e3;
  const auto t0 = std::chrono::steady_clock::now();
  // The grid's pair record, with each pair's simplices kept in a table that the ids index.
  std::vector<std::array<std::int32_t, 4>>& simplices = a.pair_simplices;
  std::vector<PersistencePair> pairs;
  for (const TetPersistencePair& p : d.pairs) {
    PersistencePair q;
    q.dim = p.dim;
    q.birth = to_float_keeping_sign(p.birth);
    q.death = to_float_keeping_sign(p.death);
    q.birth_vertex = p.birth_vertex;
    q.death_vertex = p.death_vertex;
    q.birth_simplex = Id(simplices.size());
    simplices.push_back(p.birth_simplex);
    q.death_simplex = Id(simplices.size());
    simplices.push_back(p.death_simplex);
    pairs.push_back(q);
  }
  const auto [lo, hi] = std::minmax_element(field.values.begin(), field.values.end());
  a.chokes = find_chokes(pairs, d.essential.size(), std::max(0.0, -*lo), std::max(0.0, *hi), params, [&](int, Id s) {
    std::array<double, 3> c{0, 0, 0};
    int n = 0;
    for (std::int32_t v : simplices[std::size_t(s)])
      if (v >= 0) {
        ++n;
        for (int k = 0; k < 3; ++k) c[std::size_t(k)] += field.vertices[std::size_t(v)][std::size_t(k)];
      }
    for (double& x : c) x /= std::max(n, 1);
    return c;
  });
  a.timings_ms["chokes"] = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  if (trace_loops) {
    const auto t1 = std::chrono::steady_clock::now();
    a.loops = trace_tet_loops(field, a.input, a.chokes.chokes, simplices, loops);
    a.timings_ms["loops"] = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t1).count();
  }
  return a;
}

}  // namespace chokeloops

// Generator loops in their side's class (generator_class.h): the cycles, the linking test, the plane sections.
#include "generator_class.h"

#include <tbb/parallel_for.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdint>
#include <cstdlib>
#include <limits>

#include "chokeloops/loops/channels.h"
#include "chokeloops/loops/linking.h"
#include "chokeloops/loops/shorten.h"
#include "chokeloops/surface/topology.h"

namespace chokeloops::detail {

namespace {
struct Box {
  std::array<double, 3> lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
};
Box box_of(const Polyline3& curve) {
  Box b;
  for (const auto& p : curve)
    for (int a = 0; a < 3; ++a) b.lo[a] = std::min(b.lo[a], p[a]), b.hi[a] = std::max(b.hi[a], p[a]);
  return b;
}
// A plane between the boxes of a curve and a cycle: the two cannot link.
bool apart(const Box& b, const SideCycle& z) {
  for (int a = 0; a < 3; ++a)
    if (z.hi[a] < b.lo[a] || z.lo[a] > b.hi[a]) return true;
  return false;
}
// The direction of cycle P at its point i: over four of its points, not one step's axis (the cycle is a path
// of grid vertices).
std::array<double, 3> cycle_direction(const Polyline3& P, std::size_t i) {
  const std::size_t n = P.size();
  const auto& a = P[(i + n - 2) % n];
  const auto& b = P[(i + 2) % n];
  return {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
}

// The grid's diagonal: a section radius that holds every face.
double grid_diagonal(const ScalarGrid& grid) {
  double reach = 0;
  for (int a = 0; a < 3; ++a) reach += std::pow(grid.origin[a] + grid.h(a) * (grid.dims[a] - 1) - grid.origin[a], 2);
  return std::sqrt(reach);
}

}  // namespace

void make_generator_cycles(const ScalarGrid& grid, const std::vector<Choke>& chokes, GeneratorCycles& out) {
  std::vector<std::size_t> generators;
  for (std::size_t i = 0; i < chokes.size(); ++i)
    if (chokes[i].kind == Kind::Generator) generators.push_back(i);
  out.storage.assign(generators.size(), SideCycle{});
  out.by_side = {};
  out.own.assign(chokes.size(), nullptr);
  tbb::parallel_for(std::size_t(0), generators.size(), [&](std::size_t k) {
    SideCycle& z = out.storage[k];
    z.points = generator_cycle(grid, chokes[generators[k]]);
    const Box b = box_of(z.points);
    z.lo = b.lo, z.hi = b.hi;
  });
  const bool debug = std::getenv("CHOKELOOPS_DEBUG_MEMBRANES") != nullptr;
  for (std::size_t k = 0; k < generators.size(); ++k) {
    const Choke& c = chokes[generators[k]];
    if (debug)
      std::fprintf(stderr, "membranes: %s generator depth %g: cycle of %zu points\n", to_string(c.side), c.depth, out.storage[k].points.size());
    if (out.storage[k].points.empty()) continue;
    out.by_side[c.side == Side::Handle ? 0 : 1].push_back(&out.storage[k]);
    out.own[generators[k]] = &out.storage[k];
  }
}

int linked_cycle(const Polyline3& curve, const std::vector<const SideCycle*>& cycles) {
  const Box box = box_of(curve);
  const LinkingCurve linking(curve);
  for (std::size_t k = 0; k < cycles.size(); ++k) {
    const SideCycle& z = *cycles[k];
    if (apart(box, z)) continue;
    const auto lk = linking.with(z.points);
    if (lk && *lk != 0) return int(k);
  }
  return -1;
}

bool section_cannot_link_odd(const SurfaceSections& sections, const Polyline3& cycle, const std::array<double, 3>& p,
                             const std::array<double, 3>& n) {
  // Crossings in the cycle's order; a vertex on the plane counts as on its positive side, as if the plane
  // were moved a little toward the negative one.
  std::vector<std::array<double, 3>> crossings;
  auto side = [&](const std::array<double, 3>& x) { return (x[0] - p[0]) * n[0] + (x[1] - p[1]) * n[1] + (x[2] - p[2]) * n[2]; };
  for (std::size_t k = 0; k < cycle.size(); ++k) {
    const auto &a = cycle[k], &b = cycle[(k + 1) % cycle.size()];
    const double da = side(a), db = side(b);
    if ((da >= 0) == (db >= 0)) continue;
    const double t = da / (da - db);
    crossings.push_back({a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]), a[2] + t * (b[2] - a[2])});
  }
  const std::size_t m = crossings.size();
  std::vector<std::size_t> group(m);
  for (std::size_t k = 0; k < m; ++k) group[k] = k;
  auto root = [&](std::size_t x) {
    while (group[x] != x) x = group[x] = group[group[x]];
    return x;
  };
  auto join = [&](std::size_t a, std::size_t b) {
    const std::size_t ra = root(a), rb = root(b);
    if (ra != rb && sections.segment_clear(crossings[a], crossings[b])) group[ra] = rb;
  };
  // Neighbours along the cycle first (near each other, short segments), then any two groups still odd.
  for (std::size_t k = 0; k + 1 < m; ++k) join(k, k + 1);
  auto odd_groups = [&] {
    std::vector<char> odd(m, 0);
    for (std::size_t k = 0; k < m; ++k) odd[root(k)] ^= 1;
    std::vector<std::size_t> out;
    for (std::size_t k = 0; k < m; ++k)
      if (odd[k]) out.push_back(k);
    return out;
  };
  std::vector<std::size_t> odd = odd_groups();
  // More odd groups than this (the grey-matter map's planes have at most 8) are left to the sections: the
  // pairs' segments would cost more than they do.
  constexpr std::size_t kMostOddGroups = 32;
  if (odd.size() > kMostOddGroups) return false;
  for (std::size_t i = 0; i < odd.size(); ++i)
    for (std::size_t j = i + 1; j < odd.size(); ++j) join(odd[i], odd[j]);
  return odd_groups().empty();
}

bool section_bounds_on_its_side(const SurfaceMesh& surface, const MeshAdjacency& adjacency, SurfaceTopology& topology,
                                const Polyline3& section, const std::vector<const SideCycle*>& other_side, const SideCycle* own,
                                std::vector<int>& path, const std::vector<int>* faces) {
  // Cheapest test first: the own cycle (one), then the other side's, then the surface's homology.
  if (own) {
    const auto lk = linking_number(section, own->points);
    if (!lk || *lk % 2 == 0) return false;
  }
  if (linked_cycle(section, other_side) >= 0) return false;
  // The side of the section's own strip of faces is an edge loop of its class already; snapping its points
  // to edges was a third of a long section's checks (0.2-0.9 ms on the pierced block's 2,000-point ones).
  if (faces) path = strip_side_loop(surface, adjacency, *faces);
  if (path.empty()) {
    try {
      path = snap_polyline_to_edge_path(surface, adjacency, section);
    } catch (const Error&) {
      return false;
    }
  }
  return path.size() >= 3 && !topology.null_homologous(path);
}

bool generator_plane_start(const ScalarGrid& grid, const SurfaceMesh& surface, const MeshAdjacency& adjacency,
                           SurfaceTopology& topology, const SurfaceSections& sections, const Choke& c,
                           const std::vector<const SideCycle*>& other_side, const SideCycle& own, Polyline3& out,
                           std::vector<int>& out_path, std::vector<int>& out_faces) {
  const Polyline3& P = own.points;
  const std::size_t n = P.size();
  if (n < 5) return false;
  std::size_t nearest = 0;
  double nearest_d2 = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < n; ++i) {
    const double d2 = std::pow(P[i][0] - c.point[0], 2) + std::pow(P[i][1] - c.point[1], 2) + std::pow(P[i][2] - c.point[2], 2);
    if (d2 < nearest_d2) nearest_d2 = d2, nearest = i;
  }
  const std::array<double, 3> tangent = cycle_direction(P, nearest);
  if (tangent == std::array<double, 3>{0, 0, 0}) return false;
  // Any radius: the innermost curve round the choke is followed from the choke outward (SurfaceSections).
  std::vector<int> faces;
  Polyline3 section = sections.around(c.point, tangent, grid_diagonal(grid), true, &faces);
  std::vector<int> path;
  if (section.size() < 3 || !section_bounds_on_its_side(surface, adjacency, topology, section, other_side, &own, path, &faces))
    return false;
  out = std::move(section);
  out_path = std::move(path);
  out_faces = std::move(faces);
  return true;
}

bool shorten_plane_start(const SurfaceMesh& surface, const MeshAdjacency& adjacency, const std::vector<int>& faces,
                         std::size_t min_faces, double max_move, ShortenResult& out) {
  if (faces.size() < min_faces) return false;
  ShortenOptions options;
  options.max_move = max_move;
  try {
    out = shorten_strip_loop(surface, adjacency, faces, options);
  } catch (const Error&) {
    return false;  // not a strip after all
  }
  return !out.at_band_edge && out.points.size() >= 3;
}

bool generator_section_loop(const ScalarGrid& grid, const SurfaceMesh& surface, const MeshAdjacency& adjacency,
                            SurfaceTopology& topology, const SurfaceSections& sections_of, const Choke& c,
                            const std::vector<const SideCycle*>& other_side, const SideCycle* own, Polyline3& out,
                            std::vector<int>& out_path, bool debug) {
  struct Plane {
    std::array<double, 3> point, normal;
  };
  std::vector<Plane> planes;
  constexpr int kDirections = 48;  // a Fibonacci spiral over the half sphere
  for (int k = 0; k < kDirections; ++k) {
    const double z = 1 - (k + 0.5) / kDirections, rho = std::sqrt(1 - z * z), phi = k * M_PI * (3 - std::sqrt(5.0));
    planes.push_back({c.point, {rho * std::cos(phi), rho * std::sin(phi), z}});
  }
  std::array<double, 3> lo = grid.origin, hi;
  for (int a = 0; a < 3; ++a) hi[a] = grid.origin[a] + grid.h(a) * (grid.dims[a] - 1);
  if (own) {
    const Polyline3& P = own->points;
    const std::size_t n = P.size(), step = std::max<std::size_t>(1, n / 40);
    for (std::size_t i = 0; i < n; i += step) {
      bool in_grid = true;
      for (int a = 0; a < 3; ++a) in_grid &= P[i][a] >= lo[a] && P[i][a] <= hi[a];
      if (!in_grid) continue;  // the part of a tunnel's cycle that goes round the outside of the grid
      const auto d = cycle_direction(P, i);
      Eigen::Vector3d t(d[0], d[1], d[2]);
      if (t.norm() == 0) continue;
      t.normalize();
      planes.push_back({P[i], {t[0], t[1], t[2]}});
    }
  }
  const double h = grid.voxel_size;
  // Radius by radius: a curve that closes only beyond radius r is longer than 2r, so a passing curve no
  // longer than that ends the search (wide sections over the whole surface are what cost here).
  std::vector<char> done(planes.size(), 0);
  double best_length = 1e300;
  const std::array<double, 3> radii{6 * c.depth + 6 * h, 24 * c.depth + 12 * h, grid_diagonal(grid)};
  for (std::size_t level = 0; level < radii.size(); ++level) {
    const double radius = radii[level];
    // The planes whose sections cannot link the own cycle once are left out from the second radius on: the
    // test costs about what a section costs at the first.
    if (own && level == 1) {
      std::vector<std::size_t> open;
      for (std::size_t i = 0; i < planes.size(); ++i)
        if (!done[i]) open.push_back(i);
      tbb::parallel_for(std::size_t(0), open.size(), [&](std::size_t k) {
        const Plane& plane = planes[open[k]];
        if (section_cannot_link_odd(sections_of, own->points, plane.point, plane.normal)) done[open[k]] = 1;
      });
    }
    std::vector<std::size_t> index;
    for (std::size_t i = 0; i < planes.size(); ++i)
      if (!done[i]) index.push_back(i);
    std::vector<Polyline3> sections(index.size());
    tbb::parallel_for(std::size_t(0), index.size(), [&](std::size_t i) {
      sections[i] = sections_of.around(planes[index[i]].point, planes[index[i]].normal, radius);
    });
    std::vector<std::pair<double, std::size_t>> order;
    for (std::size_t i = 0; i < sections.size(); ++i)
      if (sections[i].size() >= 3) order.push_back({closed_length(sections[i]), i}), done[index[i]] = 1;
    std::stable_sort(order.begin(), order.end());
    for (const auto& [length, i] : order) {
      std::vector<int> path;
      if (!section_bounds_on_its_side(surface, adjacency, topology, sections[i], other_side, own, path)) continue;
      if (debug)
        std::fprintf(stderr, "membranes: %s generator depth %g: plane section %g long (plane %zu of %zu, radius %g)\n", to_string(c.side),
                     c.depth, length, index[i], planes.size(), radius);
      if (length < best_length) {
        best_length = length;
        out = std::move(sections[i]);
        out_path = std::move(path);
      }
      break;
    }
    if (best_length <= 2 * radius) return true;  // a wider radius holds no shorter one
  }
  return best_length < 1e300;
}

bool drop_dependent_generators(std::vector<Loop>& loops, const GeneratorCycles& cycles, std::size_t max_loops) {
  bool checked = true;
  for (int side = 0; side < 2; ++side) {
    const Side s = side == 0 ? Side::Handle : Side::Tunnel;
    const std::vector<const SideCycle*>& own_side = cycles.by_side[std::size_t(side)];
    std::vector<std::size_t> order;
    for (std::size_t i = 0; i < loops.size(); ++i)
      if (loops[i].found && loops[i].choke.kind == Kind::Generator && loops[i].choke.side == s) order.push_back(i);
    if (order.empty() || own_side.empty()) continue;
    if (order.size() > max_loops) {
      checked = false;
      continue;
    }
    std::stable_sort(order.begin(), order.end(),
                     [&](std::size_t a, std::size_t b) { return loops[a].choke.persistence > loops[b].choke.persistence; });
    const std::size_t words = (own_side.size() + 63) / 64;
    std::vector<std::vector<std::uint64_t>> rows(order.size(), std::vector<std::uint64_t>(words, 0));
    tbb::parallel_for(std::size_t(0), order.size(), [&](std::size_t r) {
      const Polyline3& curve = loops[order[r]].points;
      const Box box = box_of(curve);
      const LinkingCurve linking(curve);
      for (std::size_t k = 0; k < own_side.size(); ++k) {
        const SideCycle& z = *own_side[k];
        if (apart(box, z)) continue;
        const auto lk = linking.with(z.points);
        if (lk && (*lk & 1)) rows[r][k / 64] |= std::uint64_t(1) << (k % 64);
      }
    });
    // Gaussian elimination over Z/2, one row at a time: basis[p] has its lowest set bit at p.
    std::vector<std::vector<std::uint64_t>> basis(own_side.size());
    for (std::size_t r = 0; r < order.size(); ++r) {
      std::vector<std::uint64_t>& row = rows[r];
      bool independent = false;
      for (;;) {
        std::size_t w = 0;
        while (w < words && row[w] == 0) ++w;
        if (w == words) break;
        const std::size_t p = w * 64 + std::size_t(__builtin_ctzll(row[w]));
        if (basis[p].empty()) {
          basis[p] = row;
          independent = true;
          break;
        }
        for (std::size_t q = 0; q < words; ++q) row[q] ^= basis[p][q];
      }
      if (independent) continue;
      Loop& l = loops[order[r]];
      Loop dropped;
      dropped.choke = l.choke;
      dropped.trace_ms = l.trace_ms;
      l = std::move(dropped);
      l.note = "its loop was in the class of more persistent generator loops of its side (its linking numbers with the "
               "side's cycles add nothing to theirs): not reported";
    }
  }
  return checked;
}

}  // namespace chokeloops::detail

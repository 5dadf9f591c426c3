#include "chokeloops/topology/chokes.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <sstream>

namespace chokeloops {

const char* to_string(Side side) { return side == Side::Handle ? "handle" : "tunnel"; }
const char* to_string(Kind kind) { return kind == Kind::Generator ? "generator" : "choke"; }

Threshold Threshold::parse(const std::string& text) {
  Threshold t;
  std::string number = text;
  t.percent = !text.empty() && text.back() == '%';
  if (t.percent) number.pop_back();
  char* end = nullptr;
  t.value = std::strtod(number.c_str(), &end);
  if (number.empty() || end != number.c_str() + number.size() || !std::isfinite(t.value) || t.value < 0)
    throw Error("'" + text + "' is not a length: give a percentage like 50% or a non-negative length in input units");
  return t;
}

std::string Threshold::text() const {
  std::ostringstream s;
  s << value << (percent ? "%" : "");
  return s.str();
}

namespace {

std::array<double, 3> centroid(const ScalarGrid& grid, const FreudenthalComplex& cx, int dim, Id simplex) {
  std::array<double, 3> c{0, 0, 0};
  auto add = [&](Id v, double w) {
    auto p = grid.world(cx.coords(v));
    for (int a = 0; a < 3; ++a) c[a] += w * p[a];
  };
  if (dim == 1) for (Id v : cx.edge_vertices(simplex)) add(v, 0.5);
  if (dim == 2) for (Id v : cx.triangle_vertices(simplex)) add(v, 1.0 / 3);
  return c;
}

void keep_stronger(std::array<double, 2>& best, const Choke& c) {
  if (c.persistence > best[1] || (c.persistence == best[1] && c.depth < best[0])) best = {c.depth, c.persistence};
}

}  // namespace

ChokeSet find_chokes(const ScalarGrid& grid, const PersistenceDiagram& diagram, const ChokeParameters& params) {
  FreudenthalComplex cx(grid.dims);
  auto [lo, hi] = std::minmax_element(grid.values.begin(), grid.values.end());
  return find_chokes(diagram.pairs, diagram.essential.size(), std::max(0.0, -double(*lo)), std::max(0.0, double(*hi)), params,
                     [&](int dim, Id simplex) { return centroid(grid, cx, dim, simplex); });
}

ChokeSet find_chokes(const std::vector<PersistencePair>& pairs, std::size_t essential_classes, double R_in, double R_out,
                     const ChokeParameters& params, const std::function<std::array<double, 3>(int, Id)>& centroid) {
  ChokeSet out;
  out.R_in = R_in;
  out.R_out = R_out;
  out.d_max_handle = params.d_max.resolve(out.R_in);
  out.d_max_tunnel = params.d_max.resolve(out.R_out);
  out.min_persistence_handle = params.min_persistence.resolve(out.R_in);
  out.min_persistence_tunnel = params.min_persistence.resolve(out.R_out);
  out.components = int(essential_classes);

  for (std::size_t pi = 0; pi < pairs.size(); ++pi) {
    const PersistencePair& p = pairs[pi];
    const double b = p.birth, d = p.death;
    Choke c;
    c.birth = b;
    c.death = d;
    // The solid is {phi <= 0}, as the surface extraction takes it (a vertex at exactly 0 is inside): a pair
    // alive at 0 is born at or below it and dies above it. Fields with exact zeros (an image whose voxels
    // sit exactly at the iso value) made `b < 0` here miss handles the surface has.
    if (p.dim == 1 && b <= 0 && d > 0) {
      // One handle and one tunnel of the genus. As in the paper (section 3.2), a generator's persistence is
      // how long the side it cuts lives on: the handle's until the deepest core (R_in) is reached, the
      // tunnel's until the box is filled (R_out). Reported, never filtered.
      c.pair = int(pi);
      Choke h = c;
      h.side = Side::Handle;
      h.kind = Kind::Generator;
      h.depth = b < 0 ? -b : 0.0;
      h.persistence = out.R_in - h.depth;
      h.simplex_dim = 1;
      h.simplex = p.birth_simplex;
      h.saddle = p.birth_vertex;
      h.lobes = p.birth_lobes;
      Choke t = c;
      t.side = Side::Tunnel;
      t.kind = Kind::Generator;
      t.depth = d;
      t.persistence = out.R_out - t.depth;
      t.simplex_dim = 2;
      t.simplex = p.death_simplex;
      t.saddle = p.death_vertex;
      t.lobes = p.death_lobes;
      ++out.handle_generators;
      ++out.tunnel_generators;
      if (params.handles) out.chokes.push_back(h);
      if (params.tunnels) out.chokes.push_back(t);
      out.handle_diagram.push_back({h.depth, h.persistence});
      out.tunnel_diagram.push_back({t.depth, t.persistence});
    } else if (p.dim == 0 && d <= 0) {
      c.side = Side::Handle;
      c.kind = Kind::Choke;
      c.depth = d < 0 ? -d : 0.0;
      c.persistence = d - b;
      c.simplex_dim = 1;
      c.simplex = p.death_simplex;
      c.saddle = p.death_vertex;
      c.lobes = p.death_lobes;
      out.handle_diagram.push_back({c.depth, c.persistence});
      if (params.handles && c.depth <= out.d_max_handle && c.persistence > 0) {
        if (c.persistence >= out.min_persistence_handle) out.chokes.push_back(c);
        else keep_stronger(out.strongest_filtered_handle, c);
      }
    } else if (p.dim == 2 && b > 0) {
      c.side = Side::Tunnel;
      c.kind = Kind::Choke;
      c.depth = b;
      c.persistence = d - b;
      c.simplex_dim = 2;
      c.simplex = p.birth_simplex;
      c.saddle = p.birth_vertex;
      c.lobes = p.birth_lobes;
      out.tunnel_diagram.push_back({c.depth, c.persistence});
      if (params.tunnels && c.depth <= out.d_max_tunnel && c.persistence > 0) {
        if (c.persistence >= out.min_persistence_tunnel) out.chokes.push_back(c);
        else keep_stronger(out.strongest_filtered_tunnel, c);
      }
    } else if (p.dim == 0 && b <= 0 && d > 0) {
      ++out.gaps;
    } else if (p.dim == 2 && b <= 0 && d > 0) {
      ++out.sealed_cavities;
    }
  }
  out.components += out.gaps;
  for (Choke& c : out.chokes) c.point = centroid(c.simplex_dim, c.simplex);
  std::stable_sort(out.chokes.begin(), out.chokes.end(), [](const Choke& a, const Choke& b) {
    if (a.kind != b.kind) return a.kind == Kind::Generator;
    if (a.side != b.side) return a.side == Side::Handle;
    if (a.depth != b.depth) return a.depth < b.depth;
    return a.simplex < b.simplex;
  });
  return out;
}

}  // namespace chokeloops

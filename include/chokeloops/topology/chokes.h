#pragma once
// Stage `chokes`: reads the persistence pairs of the signed distance as DESIGN §2's table says and keeps
// the handle/tunnel generators (always) and the additional chokes that pass d_max and min_persistence.
#include <array>
#include <functional>
#include <string>
#include <vector>

#include "chokeloops/grid.h"
#include "chokeloops/topology/persistence.h"

namespace chokeloops {

enum class Side { Handle, Tunnel };
enum class Kind { Generator, Choke };
const char* to_string(Side side);
const char* to_string(Kind kind);

// A length given as a percentage of a scale ("50%") or as an absolute length in input units ("0.02").
struct Threshold {
  double value = 0;
  bool percent = true;
  static Threshold parse(const std::string& text);  // throws Error on anything else
  double resolve(double scale) const { return percent ? value / 100.0 * scale : value; }
  std::string text() const;
};

struct ChokeParameters {
  Threshold d_max{50, true};
  Threshold min_persistence{10, true};
  bool handles = true, tunnels = true;
};

struct Choke {
  Side side = Side::Handle;
  Kind kind = Kind::Choke;
  double depth = 0;        // inscribed radius at the choke (distance outside the surface, for tunnels)
  double persistence = 0;  // how much longer the separated part lives (generators: see chokes.cpp)
  double birth = 0, death = 0;        // the pair's filtration values
  int simplex_dim = 1;                // 1: choke edge (handles), 2: choke triangle (tunnels)
  Id simplex = -1;                    // id of the choke simplex (complex.h)
  Id saddle = -1;                     // its highest vertex
  std::array<Id, 2> lobes{-1, -1};    // one vertex on each side of the membrane (-2: outside the box)
  std::array<double, 3> point{0, 0, 0};  // choke point: centroid of the choke simplex, world coordinates
  int pair = -1;                      // generators: index of their pair in the diagram (a handle and a tunnel share it)
};

struct ChokeSet {
  std::vector<Choke> chokes;           // generators first, then chokes; each group by depth
  double R_in = 0, R_out = 0;          // largest inscribed radius; largest exterior distance in the box
  double d_max_handle = 0, d_max_tunnel = 0;            // thresholds resolved in input units
  double min_persistence_handle = 0, min_persistence_tunnel = 0;
  int handle_generators = 0, tunnel_generators = 0;
  int components = 0;                  // components of the solid (essential class + gaps)
  int gaps = 0;                        // dim-0 pairs b < 0 <= d: separate parts meeting outside
  int sealed_cavities = 0;             // dim-2 pairs b <= 0 < d
  // Per side, the most persistent additional candidate that d_max admits but min_persistence filters out
  // ({depth, persistence}; persistence 0: none). Persistence is sampled, so a loop near the threshold can
  // come and go with the grid; this says how far the threshold is from the next loop.
  std::array<double, 2> strongest_filtered_handle{0, 0}, strongest_filtered_tunnel{0, 0};
  // Every candidate point (depth, persistence) of each side, for persistence diagrams.
  std::vector<std::array<double, 2>> handle_diagram, tunnel_diagram;
};

ChokeSet find_chokes(const ScalarGrid& grid, const PersistenceDiagram& diagram, const ChokeParameters& params);

// The same reading of the pairs of any complex (essential_classes: of dimension 0, the components of the box),
// with R_in / R_out its deepest inside and farthest outside values and `centroid(dim, simplex)` placing a choke
// simplex given by the pair's simplex id.
ChokeSet find_chokes(const std::vector<PersistencePair>& pairs, std::size_t essential_classes, double R_in, double R_out,
                     const ChokeParameters& params, const std::function<std::array<double, 3>(int, Id)>& centroid);

}  // namespace chokeloops

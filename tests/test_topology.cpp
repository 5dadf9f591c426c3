// Topological checks of loops on extracted surfaces: CGAL contractibility, separation, polyline snapping.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>

#include "analytic_fields.h"
#include "chokeloops/surface/mesh_adjacency.h"
#include "chokeloops/surface/surface.h"
#include "chokeloops/surface/topology.h"

using namespace chokeloops;

namespace {
SurfaceMesh cube_surface(int n, const Sdf& sdf) { return extract_zero_surface(sample_field({n, n, n}, sdf)); }
Polyline3 circle(std::array<double, 3> c, std::array<double, 3> u, std::array<double, 3> v, double r, int n = 200) {
  Polyline3 p;
  for (int i = 0; i < n; ++i) {
    double t = 2 * M_PI * i / n;
    p.push_back({c[0] + r * (std::cos(t) * u[0] + std::sin(t) * v[0]), c[1] + r * (std::cos(t) * u[1] + std::sin(t) * v[1]),
                 c[2] + r * (std::cos(t) * u[2] + std::sin(t) * v[2])});
  }
  return p;
}
void expect_edge_loop(const SurfaceMesh& m, const std::vector<int>& loop) {
  auto A = build_adjacency(m);
  ASSERT_GE(loop.size(), 3u);
  for (size_t i = 0; i < loop.size(); ++i) ASSERT_TRUE(A.has_edge(m, loop[i], loop[(i + 1) % loop.size()]));
}
}  // namespace

TEST(Topology, TorusMeridianAndLongitudeAreEssentialAndNonSeparating) {
  const double R = 0.3, r = 0.12;
  auto m = cube_surface(64, analytic::torus(R, r));
  SurfaceTopology topo(m);
  auto meridian = snap_polyline_to_edge_path(m, circle({0.5 + R, 0.5, 0.5}, {1, 0, 0}, {0, 0, 1}, r));
  expect_edge_loop(m, meridian);
  EXPECT_TRUE(loop_is_simple(meridian));
  EXPECT_NEAR(loop_length(m, meridian), 2 * M_PI * r, 0.25 * 2 * M_PI * r);  // edge paths zigzag
  EXPECT_FALSE(topo.contractible(meridian));
  EXPECT_FALSE(topo.separates(meridian));
  auto longitude = snap_polyline_to_edge_path(m, circle({0.5, 0.5, 0.5}, {1, 0, 0}, {0, 1, 0}, R + r));
  expect_edge_loop(m, longitude);
  EXPECT_TRUE(loop_is_simple(longitude));
  EXPECT_FALSE(topo.contractible(longitude));
  EXPECT_FALSE(topo.separates(longitude));
  // The inner equator is homotopic to the outer one, both essential.
  auto inner = snap_polyline_to_edge_path(m, circle({0.5, 0.5, 0.5}, {1, 0, 0}, {0, 1, 0}, R - r));
  EXPECT_FALSE(topo.contractible(inner));
  // A small circle around a point on the outer equator: contractible and separating.
  auto small = snap_polyline_to_edge_path(m, circle({0.5 + R + r, 0.5, 0.5}, {0, 1, 0}, {0, 0, 1}, 0.05));
  expect_edge_loop(m, small);
  EXPECT_TRUE(topo.contractible(small));
  EXPECT_TRUE(topo.separates(small));
  // The free functions agree.
  EXPECT_FALSE(loop_is_contractible(m, meridian));
  EXPECT_TRUE(loop_separates_surface(m, small));
}

TEST(Topology, SphereEquatorContractibleAndSeparating) {
  auto m = cube_surface(48, analytic::ball(0.3));
  auto eq = snap_polyline_to_edge_path(m, circle({0.5, 0.5, 0.5}, {1, 0, 0}, {0, 1, 0}, 0.3));
  expect_edge_loop(m, eq);
  EXPECT_TRUE(loop_is_simple(eq));
  EXPECT_TRUE(loop_is_contractible(m, eq));
  EXPECT_TRUE(loop_separates_surface(m, eq));
}

TEST(Topology, DoubleTorusHandleMeridiansAndLoopsOnTheInnerSphereOfAHollowBall) {
  auto dt = analytic::double_torus();  // tori centred at 0.5 -/+ 0.17 in x, R = 0.17, r = 0.07
  auto m = cube_surface(96, dt);
  SurfaceTopology topo(m);
  // Meridian of the left torus on its far side (x = 0.33 - 0.17).
  auto mer = snap_polyline_to_edge_path(m, circle({0.33 - 0.17, 0.5, 0.5}, {1, 0, 0}, {0, 0, 1}, 0.07));
  expect_edge_loop(m, mer);
  EXPECT_FALSE(topo.contractible(mer));
  EXPECT_FALSE(topo.separates(mer));
  auto hollow = [](double x, double y, double z) {
    double r = std::sqrt((x - .5) * (x - .5) + (y - .5) * (y - .5) + (z - .5) * (z - .5));
    return std::max(r - 0.4, 0.25 - r);
  };
  auto h = cube_surface(48, hollow);
  SurfaceTopology th(h);
  auto inner = snap_polyline_to_edge_path(h, circle({0.5, 0.5, 0.5}, {1, 0, 0}, {0, 1, 0}, 0.25));
  auto outer = snap_polyline_to_edge_path(h, circle({0.5, 0.5, 0.5}, {1, 0, 0}, {0, 1, 0}, 0.4));
  EXPECT_NE(th.component_of_vertex(inner[0]), th.component_of_vertex(outer[0]));
  EXPECT_TRUE(th.contractible(inner));
  EXPECT_TRUE(th.separates(inner));  // separates its own component (the inner sphere)
  EXPECT_TRUE(th.separates(outer));
}

TEST(Topology, RejectsBrokenLoops) {
  auto m = cube_surface(24, analytic::ball(0.3));
  SurfaceTopology topo(m);
  EXPECT_THROW(topo.contractible({}), Error);
  EXPECT_THROW(topo.contractible({0, int(m.vertices.size())}), Error);
  EXPECT_THROW(topo.separates({0, 1, 2, 3, 4, 5, 6, 7, 8, 9}), Error);  // not consecutive along edges
}

TEST(Topology, SeparationOfLoopsThatAreNotSimpleOrPassAPinch) {
  // Simple loops through discs are decided by their Z/2 class; these two kinds are not, and must still get
  // the answer of removing their edges.
  auto m = cube_surface(64, analytic::torus(0.3, 0.12));
  SurfaceTopology topo(m);
  auto mer = snap_polyline_to_edge_path(m, circle({0.5 + 0.3, 0.5, 0.5}, {1, 0, 0}, {0, 0, 1}, 0.12));
  std::vector<int> twice(mer);
  twice.insert(twice.end(), mer.begin(), mer.end());
  ASSERT_FALSE(loop_is_simple(twice));
  EXPECT_TRUE(topo.null_homologous(twice));  // twice is zero mod 2...
  EXPECT_FALSE(topo.separates(twice));       // ...yet the torus stays connected without the meridian's edges
  EXPECT_FALSE(topo.separates(mer));

  // A tube of 4 rings of 8 whose two ends close on one vertex (a sphere with two points made one): every
  // edge has two faces, but vertex 0 has two discs of faces around it.
  const int n = 8, rings = 4;
  SurfaceMesh pinched;
  pinched.vertices.push_back({0, 0, -1});
  for (int r = 0; r < rings; ++r)
    for (int i = 0; i < n; ++i)
      pinched.vertices.push_back({std::cos(2 * M_PI * i / n), std::sin(2 * M_PI * i / n), double(r)});
  auto at = [&](int r, int i) { return 1 + r * n + (i % n); };
  for (int r = 0; r + 1 < rings; ++r)
    for (int i = 0; i < n; ++i) {
      pinched.faces.push_back({at(r, i), at(r, i + 1), at(r + 1, i + 1)});
      pinched.faces.push_back({at(r, i), at(r + 1, i + 1), at(r + 1, i)});
    }
  for (int i = 0; i < n; ++i) {
    pinched.faces.push_back({0, at(0, i + 1), at(0, i)});
    pinched.faces.push_back({0, at(rings - 1, i), at(rings - 1, i + 1)});
  }
  SurfaceTopology tp(pinched);
  std::vector<int> along{0};  // from the pinch along the tube and back into it: the tube cut open stays one piece
  for (int r = 0; r < rings; ++r) along.push_back(at(r, 0));
  ASSERT_TRUE(loop_is_simple(along));
  EXPECT_FALSE(tp.separates(along));
  std::vector<int> ring;  // around the tube: its two halves meet only at the pinch vertex, not along an edge
  for (int i = 0; i < n; ++i) ring.push_back(at(1, i));
  EXPECT_TRUE(tp.separates(ring));
}

TEST(Topology, FastContractibilityAgreesWithCgal) {
  // Two tori (genus 2) joined by a bar along x: a circle around the bar separates the surface into two
  // genus-1 halves, so it is essential although it separates: the case a separation test alone gets wrong.
  auto torus_a = analytic::torus(0.12, 0.05, {0.25, 0.5, 0.5}), torus_b = analytic::torus(0.12, 0.05, {0.75, 0.5, 0.5});
  auto shape = [&](double x, double y, double z) {
    double bar = std::max(std::hypot(y - 0.5, z - 0.5) - 0.04, std::abs(x - 0.5) - 0.15);
    return std::min({torus_a(x, y, z), torus_b(x, y, z), bar});
  };
  auto m = cube_surface(96, shape);
  ASSERT_EQ(surface_stats(m).genus, 2);
  SurfaceTopology topo(m);
  auto snap = [&](Polyline3 p) { return snap_polyline_to_edge_path(m, p); };
  struct Case { const char* name; std::vector<int> loop; bool contractible, separates; };
  std::vector<Case> cases = {
      {"bar", snap(circle({0.5, 0.5, 0.5}, {0, 1, 0}, {0, 0, 1}, 0.04)), false, true},
      {"meridian", snap(circle({0.25 - 0.12, 0.5, 0.5}, {1, 0, 0}, {0, 0, 1}, 0.05)), false, false},
      {"longitude", snap(circle({0.75, 0.5, 0.5}, {1, 0, 0}, {0, 1, 0}, 0.12 - 0.05)), false, false},
      {"small", snap(circle({0.25 - 0.17, 0.5, 0.5}, {0, 1, 0}, {0, 0, 1}, 0.02)), true, true},
  };
  for (auto& c : cases) {
    SCOPED_TRACE(c.name);
    ASSERT_TRUE(loop_is_simple(c.loop));
    EXPECT_EQ(topo.contractible(c.loop), c.contractible);
    EXPECT_EQ(topo.contractible_fast(c.loop), c.contractible);
    EXPECT_EQ(topo.separates(c.loop), c.separates);
    EXPECT_EQ(topo.null_homologous(c.loop), c.separates);  // for a simple loop: null in Z/2 iff it separates
  }
  // Simple loops are decided by the floods alone, whichever way they run along the faces' orientation.
  SurfaceTopology floods(m);
  for (auto& c : cases) {
    SCOPED_TRACE(c.name);
    std::vector<int> reversed(c.loop.rbegin(), c.loop.rend());
    for (const auto* loop : {&c.loop, &reversed}) {
      EXPECT_EQ(floods.contractible_fast(*loop), c.contractible);
      EXPECT_EQ(floods.null_homologous(*loop), c.separates);
    }
  }
  EXPECT_EQ(floods.cgal_queries(), 0);
  // A sphere's equator (separating, both sides disks) and a loop on a hollow ball's inner sphere.
  auto s = cube_surface(48, analytic::ball(0.3));
  SurfaceTopology ts(s);
  auto eq = snap_polyline_to_edge_path(s, circle({0.5, 0.5, 0.5}, {1, 0, 0}, {0, 1, 0}, 0.3));
  EXPECT_TRUE(ts.contractible_fast(eq));
  // A non-simple loop (the equator twice) goes to CGAL and stays contractible there.
  std::vector<int> twice(eq);
  twice.insert(twice.end(), eq.begin(), eq.end());
  EXPECT_TRUE(ts.contractible_fast(twice));
  auto meridian_twice = cases[1].loop;
  meridian_twice.insert(meridian_twice.end(), cases[1].loop.begin(), cases[1].loop.end());
  EXPECT_FALSE(topo.contractible_fast(meridian_twice));
  EXPECT_TRUE(topo.null_homologous(meridian_twice));  // twice is zero mod 2, yet essential (CGAL decides)
  auto three_times = meridian_twice;
  three_times.insert(three_times.end(), cases[1].loop.begin(), cases[1].loop.end());
  EXPECT_FALSE(topo.null_homologous(three_times));
  EXPECT_FALSE(topo.contractible_fast(three_times));
}

namespace {
// The oracle: a closed edge path is null in H1(closed surface; Z/2) exactly when the faces of its component
// can be 2-coloured so that the colours differ across the edges it uses an odd number of times.
bool null_by_face_colouring(const SurfaceMesh& m, const MeshAdjacency& A, const std::vector<int>& loop) {
  std::map<std::pair<int, int>, int> parity;
  for (size_t i = 0; i < loop.size(); ++i) {
    int a = loop[i], b = loop[(i + 1) % loop.size()];
    parity[{std::min(a, b), std::max(a, b)}] ^= 1;
  }
  int h0 = A.halfedge(m, loop[0], loop[1]);
  if (h0 < 0) h0 = A.halfedge(m, loop[1], loop[0]);
  std::vector<int> colour(m.faces.size(), -1), queue{MeshAdjacency::face(h0)};
  colour[queue[0]] = 0;
  for (size_t q = 0; q < queue.size(); ++q) {
    int f = queue[q];
    for (int k = 0; k < 3; ++k) {
      int a = m.faces[f][k], b = m.faces[f][(k + 1) % 3];
      auto it = parity.find({std::min(a, b), std::max(a, b)});
      int want = colour[f] ^ (it == parity.end() ? 0 : it->second);
      int g = MeshAdjacency::face(A.twin[3 * f + k]);
      if (colour[g] < 0) colour[g] = want, queue.push_back(g);
      else if (colour[g] != want) return false;
    }
  }
  return true;
}

// Shortest edge path from a to b by breadth-first search (a excluded, b included).
std::vector<int> edge_path(const SurfaceMesh& m, const MeshAdjacency& A, int a, int b) {
  std::map<int, int> from{{a, a}};
  std::vector<int> queue{a}, around;
  for (size_t q = 0; q < queue.size() && !from.count(b); ++q) {
    A.neighbours(m, queue[q], around);
    for (int w : around)
      if (from.emplace(w, queue[q]).second) queue.push_back(w);
  }
  std::vector<int> path;
  for (int v = b; v != a; v = from.at(v)) path.push_back(v);
  return {path.rbegin(), path.rend()};
}
}  // namespace

TEST(Topology, HomologyBasisAgreesWithFaceColouringOnRandomCycles) {
  // Three closed components: a genus-2 solid (two tori and a bar), a genus-1 torus and a sphere; cycles
  // through three random vertices of one component, in every class the basis can tell apart.
  auto double_torus = analytic::double_torus(0.1, 0.04, 0.2, {0.3, 0.3, 0.5});
  auto torus = analytic::torus(0.1, 0.04, {0.7, 0.7, 0.5});
  auto ball = analytic::ball(0.08, {0.75, 0.25, 0.5});
  auto m = cube_surface(96, [&](double x, double y, double z) { return std::min({double_torus(x, y, z), torus(x, y, z), ball(x, y, z)}); });
  auto st = surface_stats(m);
  ASSERT_EQ(st.components, 3);
  ASSERT_EQ(st.genus, 3);
  auto A = build_adjacency(m);
  SurfaceTopology topo(m, A);
  std::vector<int> label;
  face_components(m, label);
  std::vector<std::vector<int>> vertices_of(3);
  for (size_t f = 0; f < m.faces.size(); ++f) vertices_of[label[f]].push_back(m.faces[f][0]);
  std::uint64_t state = 12345;
  auto next = [&](size_t n) { state = state * 6364136223846793005ull + 1442695040888963407ull; return size_t(state >> 33) % n; };
  int null = 0, essential = 0;
  for (int trial = 0; trial < 120; ++trial) {
    const auto& vs = vertices_of[trial % 3];
    int a = vs[next(vs.size())], b = vs[next(vs.size())], c = vs[next(vs.size())];
    std::vector<int> loop;
    for (auto [s, t] : {std::pair{a, b}, std::pair{b, c}, std::pair{c, a}})
      for (int v : edge_path(m, A, s, t)) loop.push_back(v);
    if (loop.size() < 3) continue;
    const bool expected = null_by_face_colouring(m, A, loop);
    EXPECT_EQ(topo.null_homologous(loop), expected) << "trial " << trial;
    (expected ? null : essential) += 1;
  }
  // Both answers occur (random triangles on a torus wind around it often enough).
  EXPECT_GT(null, 10);
  EXPECT_GT(essential, 10);
  EXPECT_EQ(topo.cgal_queries(), 0);
}

TEST(Topology, RepeatsAndSpursLeaveTheLoopTheyHangOn) {
  // A pentagon 1 2 3 4 9 with a repeat (4 4), a spur out and back (2 5 2), and a spur across the start (the
  // path ends 9 1 9 and closes back to 1): the pentagon is what is left, rotated at most.
  std::vector<int> path{1, 2, 2, 5, 2, 3, 4, 4, 9, 1, 9};
  remove_repeats_and_spurs(path);
  ASSERT_EQ(path.size(), 5u);
  const auto at = std::find(path.begin(), path.end(), 1);
  ASSERT_NE(at, path.end());
  std::rotate(path.begin(), at, path.end());
  EXPECT_EQ(path, (std::vector<int>{1, 2, 3, 4, 9}));
  // Nested spurs collapse in turn; a figure-eight through 1 keeps both of its loops.
  std::vector<int> nested{1, 2, 3, 6, 7, 6, 3, 4};
  remove_repeats_and_spurs(nested);
  EXPECT_EQ(nested, (std::vector<int>{1, 2, 3, 4}));
  std::vector<int> eight{1, 2, 3, 1, 4, 5};
  remove_repeats_and_spurs(eight);
  EXPECT_EQ(eight, (std::vector<int>{1, 2, 3, 1, 4, 5}));
  // A path that is all spur has nothing left to go round.
  std::vector<int> spur{1, 2, 3, 2};
  remove_repeats_and_spurs(spur);
  EXPECT_LT(spur.size(), 3u);
}

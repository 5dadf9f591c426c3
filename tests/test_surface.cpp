// Zero-surface extraction on the Freudenthal tets: topology (genus = first Betti number of the solid),
// orientation, watertightness, determinism, speed; and the PLY/OBJ writers.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <limits>
#include <sstream>

#include "analytic_fields.h"
#include "chokeloops/output/mesh_write.h"
#include "chokeloops/surface/mesh_adjacency.h"
#include "chokeloops/surface/surface.h"

using namespace chokeloops;

namespace {
ScalarGrid cube_field(int n, const Sdf& sdf, double lo = 0, double hi = 1) {
  return sample_field({n, n, n}, sdf, {lo, lo, lo}, {hi, hi, hi});
}
void expect_closed_topology(const SurfaceStats& s, int components, int genus) {
  EXPECT_TRUE(s.closed_manifold);
  EXPECT_EQ(s.boundary_edges, 0);
  EXPECT_EQ(s.nonmanifold_edges, 0);
  EXPECT_EQ(s.nonmanifold_vertices, 0);
  EXPECT_EQ(s.inconsistent_edges, 0);
  EXPECT_EQ(s.components, components);
  EXPECT_EQ(s.genus, genus);
  EXPECT_EQ(s.euler, 2 * s.components - 2 * s.genus);
  for (int g : s.component_genus) EXPECT_GE(g, 0);
  EXPECT_GT(s.enclosed_volume, 0);  // outward normals
}
}  // namespace

TEST(Surface, SphereIsGenusZeroWithOutwardNormals) {
  auto g = cube_field(48, analytic::ball(0.3));
  auto m = extract_zero_surface(g);
  auto s = surface_stats(m);
  expect_closed_topology(s, 1, 0);
  double vol = 4.0 / 3.0 * M_PI * 0.3 * 0.3 * 0.3, area = 4 * M_PI * 0.09;
  EXPECT_NEAR(s.enclosed_volume, vol, 0.01 * vol);
  EXPECT_EQ(surface_vertex_on_edge(m, 0), -1);
  EXPECT_NEAR(s.area, area, 0.03 * area);
  ASSERT_EQ(m.vertex_edge.size(), m.vertices.size());
  FreudenthalComplex K(g.dims);
  for (size_t i = 0; i < m.vertices.size(); ++i) {  // each vertex on a crossing edge, strictly inside it
    Id e = m.vertex_edge[i];
    ASSERT_TRUE(K.edge_valid(e));
    auto ev = K.edge_vertices(e);
    ASSERT_NE(g.values[ev[0]] <= 0, g.values[ev[1]] <= 0);
    if (i) ASSERT_LT(m.vertex_edge[i - 1], e);  // ordered by edge id, one vertex per edge
    ASSERT_EQ(surface_vertex_on_edge(m, e), int(i));
    auto a = g.world(K.coords(ev[0])), b = g.world(K.coords(ev[1]));
    double da = 0, db = 0;
    for (int d = 0; d < 3; ++d) da += std::pow(m.vertices[i][d] - a[d], 2), db += std::pow(m.vertices[i][d] - b[d], 2);
    ASSERT_GT(std::sqrt(da), 0.5e-3 * g.voxel_size);
    ASSERT_GT(std::sqrt(db), 0.5e-3 * g.voxel_size);
  }
}

TEST(Surface, TorusGenusOne) {
  auto s = surface_stats(extract_zero_surface(cube_field(64, analytic::torus(0.3, 0.12))));
  expect_closed_topology(s, 1, 1);
  double vol = 2 * M_PI * M_PI * 0.3 * 0.12 * 0.12;
  EXPECT_NEAR(s.enclosed_volume, vol, 0.02 * vol);
}

TEST(Surface, DoubleTorusGenusTwo) {
  auto s = surface_stats(extract_zero_surface(cube_field(64, analytic::double_torus())));
  expect_closed_topology(s, 1, 2);
  EXPECT_EQ(s.euler, -2);
}

TEST(Surface, HollowBallIsTwoSpheres) {
  auto hollow = [](double x, double y, double z) {
    double r = std::sqrt((x - .5) * (x - .5) + (y - .5) * (y - .5) + (z - .5) * (z - .5));
    return std::max(r - 0.4, 0.25 - r);
  };
  auto s = surface_stats(extract_zero_surface(cube_field(48, hollow)));
  expect_closed_topology(s, 2, 0);
  EXPECT_EQ(s.euler, 4);
  double vol = 4.0 / 3.0 * M_PI * (0.4 * 0.4 * 0.4 - 0.25 * 0.25 * 0.25);
  EXPECT_NEAR(s.enclosed_volume, vol, 0.02 * vol);  // inner sphere oriented inward (towards the cavity)
}

TEST(Surface, VaryingTorusAndTangleCubeAndPiercedBall) {
  auto s1 = surface_stats(extract_zero_surface(cube_field(96, analytic::varying_torus(), -0.3, 1.3)));
  expect_closed_topology(s1, 1, 1);
  auto s2 = surface_stats(extract_zero_surface(cube_field(96, analytic::tangle_cube())));
  EXPECT_TRUE(s2.closed_manifold);
  EXPECT_EQ(s2.genus, 5);  // the tangle cube is a genus-5 surface
  EXPECT_EQ(s2.euler, 2 * s2.components - 2 * s2.genus);
  auto s3 = surface_stats(extract_zero_surface(cube_field(96, analytic::pierced_hollow_ball())));
  expect_closed_topology(s3, 1, 0);
}

TEST(Surface, ZeroValuesAreInsideAndStayManifold) {
  // Quantised field: many vertices exactly 0 (inside); the surface must stay a closed manifold with the
  // topology of the solid subcomplex.
  auto g = cube_field(40, analytic::torus(0.3, 0.12));
  for (auto& v : g.values) v = std::round(v * 40.0f) / 40.0f;
  auto m = extract_zero_surface(g);
  auto s = surface_stats(m);
  EXPECT_TRUE(s.closed_manifold);
  EXPECT_EQ(s.euler, 2 * s.components - 2 * s.genus);
  for (auto& t : m.faces) {
    for (int c = 0; c < 3; ++c) {
      auto& a = m.vertices[t[c]];
      auto& b = m.vertices[t[(c + 1) % 3]];
      double d = std::hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]);
      ASSERT_GT(d, 1e-4 * g.voxel_size);
    }
  }
}

TEST(Surface, RandomFieldsSatisfyEulerIdentity) {
  for (int seed = 1; seed <= 4; ++seed) {
    auto g = cube_field(40, analytic::random_gaussians(30, seed));
    // pad: force outside on the border so the surface is closed
    for (int k = 0; k < 40; ++k)
      for (int j = 0; j < 40; ++j)
        for (int i = 0; i < 40; ++i)
          if (i == 0 || j == 0 || k == 0 || i == 39 || j == 39 || k == 39) g.values[g.index(i, j, k)] = 1;
    auto s = surface_stats(extract_zero_surface(g));
    EXPECT_TRUE(s.closed_manifold) << seed;
    EXPECT_EQ(s.euler, 2 * s.components - 2 * s.genus) << seed;
  }
}

// Every count of the march against the Freudenthal complex itself, on blocky random fields whose uniform
// runs start and stop anywhere along rows of every length from 2 to 19 (the march skips eight uniform
// cubes of a row at a time): one surface vertex per edge whose ends differ, one or two triangles per
// tetrahedron with one, three or two corners inside, and Euler characteristic twice that of the solid (the
// subcomplex spanned by the inside vertices; the border is outside, so the surface is closed).
TEST(Surface, CountsMatchTheFreudenthalComplexOnEveryRowLength) {
  std::uint64_t state = 12345;
  auto next = [&] {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return double(state >> 11) / double(1ull << 53);
  };
  for (int nx = 2; nx <= 19; ++nx) {
    const int ny = 7 + nx % 3, nz = 6 + nx % 4;
    ScalarGrid g;
    g.dims = {nx, ny, nz};
    g.voxel_size = 1;
    g.values.resize(std::size_t(nx) * ny * nz);
    const int block = 2 + nx % 4;  // blocks of one sign, then a few single vertices flipped
    std::vector<float> block_value(std::size_t(nx / block + 1) * (ny / block + 1) * (nz / block + 1));
    for (auto& b : block_value) b = next() < 0.45 ? -1.f : 1.f;
    for (int k = 0; k < nz; ++k)
      for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) {
          const std::size_t b = std::size_t(i / block) + std::size_t(nx / block + 1) *
                                (std::size_t(j / block) + std::size_t(ny / block + 1) * std::size_t(k / block));
          float v = block_value[b] * float(0.25 + next());
          if (next() < 0.04) v = -v;
          if (i == 0 || j == 0 || k == 0 || i == nx - 1 || j == ny - 1 || k == nz - 1) v = 1;
          g.values[g.index(i, j, k)] = v;
        }
    auto in = [&](int i, int j, int k) { return g.values[g.index(i, j, k)] <= 0; };
    auto at = [&](int i, int j, int k, int m) { return in(i + (m & 1), j + (m >> 1 & 1), k + (m >> 2 & 1)); };
    std::int64_t crossing_edges = 0, triangles = 0, chi = 0;
    for (int k = 0; k < nz; ++k)
      for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) {
          auto fits = [&](int m) { return i + (m & 1) < nx && j + (m >> 1 & 1) < ny && k + (m >> 2 & 1) < nz; };
          const bool v = in(i, j, k);
          chi += v;
          for (int m = 1; m < 8; ++m) {
            if (!fits(m)) continue;
            crossing_edges += at(i, j, k, m) != v;
            chi -= v && at(i, j, k, m);
            for (int p = 1; p < m; ++p)  // triangles {v, v + p, v + m}, p a proper part of m
              if ((p & m) == p) chi += v && at(i, j, k, p) && at(i, j, k, m);
          }
          if (!fits(7)) continue;
          for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b) {
              if (a == b) continue;
              const int m1 = 1 << a, m2 = m1 | 1 << b;
              const int inside = int(v) + at(i, j, k, m1) + at(i, j, k, m2) + at(i, j, k, 7);
              chi -= inside == 4;
              triangles += inside == 2 ? 2 : inside % 4 != 0 ? 1 : 0;
            }
        }
    const SurfaceMesh m = extract_zero_surface(g);
    const SurfaceStats st = surface_stats(m);
    EXPECT_EQ(std::int64_t(m.vertices.size()), crossing_edges) << nx;
    EXPECT_EQ(std::int64_t(m.faces.size()), triangles) << nx;
    EXPECT_TRUE(st.closed_manifold) << nx;
    EXPECT_EQ(st.euler, 2 * chi) << nx;
  }
}

TEST(Surface, DeterministicAcrossThreadCounts) {
  auto g = cube_field(64, analytic::double_torus());
  SurfaceMesh a, b;
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
    a = extract_zero_surface(g);
  }
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 2);
    b = extract_zero_surface(g);
  }
  EXPECT_EQ(a.vertices, b.vertices);
  EXPECT_EQ(a.faces, b.faces);
  EXPECT_EQ(a.vertex_edge, b.vertex_edge);
}

TEST(Surface, ComponentsAndStatisticsAreTheSameForAnyThreadCount) {
  // Several components (random bumps), joined by a concurrent union-find and summed in parallel chunks.
  auto g = cube_field(72, analytic::random_gaussians(40, 7));
  const SurfaceMesh m = extract_zero_surface(g);
  std::vector<int> one_label, two_labels;
  SurfaceStats one, two;
  int one_count = 0, two_count = 0;
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
    one_count = face_components(m, one_label);
    one = surface_stats(m);
  }
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 2);
    two_count = face_components(m, two_labels);
    two = surface_stats(m);
  }
  EXPECT_GT(one_count, 1);
  EXPECT_EQ(one_count, two_count);
  EXPECT_EQ(one_label, two_labels);
  // labels follow the faces' order: the first face of each component is where its label first appears
  int seen = 0;
  for (int l : one_label) {
    ASSERT_LE(l, seen);
    seen += l == seen;
  }
  EXPECT_EQ(one.components, two.components);
  EXPECT_EQ(one.genus, two.genus);
  EXPECT_EQ(one.component_genus, two.component_genus);
  EXPECT_EQ(one.enclosed_volume, two.enclosed_volume);
  EXPECT_EQ(one.area, two.area);
}

TEST(Surface, Extracts256CubedGyroidAsAClosedManifold) {
  // A gyroid with 8 periods across the box: several million triangles (its time is bench_analyze's surface stage).
  auto gyroid = [](double x, double y, double z) {
    const double w = 2 * M_PI * 8;
    return std::sin(w * x) * std::cos(w * y) + std::sin(w * y) * std::cos(w * z) + std::sin(w * z) * std::cos(w * x);
  };
  auto g = cube_field(256, gyroid);
  auto t0 = std::chrono::steady_clock::now();
  auto m = extract_zero_surface(g);
  double sec = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("256^3 gyroid: %zu vertices, %zu faces in %.3f s\n", m.vertices.size(), m.faces.size(), sec);
  EXPECT_GT(m.faces.size(), 2000000u);
  auto s = surface_stats(m);
  EXPECT_EQ(s.nonmanifold_edges, 0);
  EXPECT_EQ(s.nonmanifold_vertices, 0);
  EXPECT_EQ(s.inconsistent_edges, 0);

  auto s2 = surface_stats(extract_zero_surface(cube_field(256, analytic::double_torus())));
  EXPECT_EQ(s2.genus, 2);
  EXPECT_TRUE(s2.closed_manifold);
}

TEST(MeshWrite, PlyAndObjFiles) {
  auto m = extract_zero_surface(cube_field(24, analytic::ball(0.3)));
  std::string dir = ::testing::TempDir();
  write_ply(m, dir + "/surf.ply");
  std::ifstream in(dir + "/surf.ply", std::ios::binary);
  std::string all((std::istreambuf_iterator<char>(in)), {});
  auto end = all.find("end_header\n");
  ASSERT_NE(end, std::string::npos);
  EXPECT_NE(all.find("element vertex " + std::to_string(m.vertices.size())), std::string::npos);
  EXPECT_EQ(all.size() - end - 11, m.vertices.size() * 12 + m.faces.size() * 13);
  std::vector<Polyline3> loops = {{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}}, {{0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}}};
  write_loops_ply(loops, dir + "/loops.ply");
  write_loops_obj(loops, dir + "/loops.obj");
  std::ifstream o(dir + "/loops.obj");
  std::string obj((std::istreambuf_iterator<char>(o)), {});
  EXPECT_NE(obj.find("o loop_1\n"), std::string::npos);
  EXPECT_NE(obj.find("l 4 5 6 7 4\n"), std::string::npos);
  std::ifstream lp(dir + "/loops.ply", std::ios::binary);
  std::string ply((std::istreambuf_iterator<char>(lp)), {});
  EXPECT_NE(ply.find("element edge 7"), std::string::npos);
  EXPECT_THROW(write_ply(m, "/nonexistent-dir/x.ply"), Error);
}

TEST(Surface, EmptyWhenNothingCrosses) {
  auto g = cube_field(8, [](double, double, double) { return 1.0; });
  auto m = extract_zero_surface(g);
  EXPECT_TRUE(m.vertices.empty());
  EXPECT_TRUE(m.faces.empty());
  auto s = surface_stats(m);
  EXPECT_EQ(s.components, 0);
  EXPECT_EQ(s.genus, 0);
  g.values[3] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_THROW(extract_zero_surface(g), Error);
  // A solid touching the box border gives an open surface: boundary edges are reported, no genus.
  auto open = extract_zero_surface(cube_field(16, [](double, double, double z) { return z - 0.5; }));
  auto so = surface_stats(open);
  EXPECT_GT(so.boundary_edges, 0);
  EXPECT_FALSE(so.closed_manifold);
  EXPECT_EQ(so.component_genus, std::vector<int>{-1});
}

// The counts on meshes that are not closed manifolds, each kind alone, with the numbers worked out by hand.
TEST(Surface, StatisticsOfBrokenMeshesCountEachDefect) {
  const std::vector<std::array<double, 3>> tet_vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  const std::vector<std::array<int, 3>> tet_faces = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};  // outward
  SurfaceMesh tet;
  tet.vertices = tet_vertices, tet.faces = tet_faces;
  expect_closed_topology(surface_stats(tet), 1, 0);
  EXPECT_NEAR(surface_stats(tet).enclosed_volume, 1.0 / 6, 1e-12);

  // Two tetrahedra sharing only vertex 0: a vertex with two fans, every edge fine.
  SurfaceMesh bowtie = tet;
  for (int k = 1; k < 4; ++k) bowtie.vertices.push_back({-tet_vertices[k][0], -tet_vertices[k][1], -tet_vertices[k][2]});
  for (auto f : tet_faces) {
    for (int& v : f) v = v == 0 ? 0 : v + 3;
    bowtie.faces.push_back({f[0], f[2], f[1]});  // mirrored: flip to keep it outward
  }
  SurfaceStats s = surface_stats(bowtie);
  EXPECT_EQ(s.edges, 12);
  EXPECT_EQ(s.nonmanifold_vertices, 1);
  EXPECT_EQ(s.nonmanifold_edges + s.boundary_edges + s.inconsistent_edges, 0);
  EXPECT_EQ(s.components, 1);
  EXPECT_FALSE(s.closed_manifold);
  EXPECT_EQ(s.component_genus, std::vector<int>{-1});

  // Three triangles on one edge (a book): one non-manifold edge, six boundary edges.
  SurfaceMesh book;
  book.vertices = {{0, 0, 0}, {0, 0, 1}, {1, 0, 0}, {0, 1, 0}, {-1, 0, 0}};
  book.faces = {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}};
  s = surface_stats(book);
  EXPECT_EQ(s.edges, 7);
  EXPECT_EQ(s.nonmanifold_edges, 1);
  EXPECT_EQ(s.boundary_edges, 6);
  EXPECT_FALSE(s.closed_manifold);

  // A tetrahedron with one face turned over: its three edges are used twice in one direction.
  SurfaceMesh flipped = tet;
  flipped.faces[3] = {1, 3, 2};
  s = surface_stats(flipped);
  EXPECT_EQ(s.inconsistent_edges, 3);
  EXPECT_EQ(s.boundary_edges + s.nonmanifold_edges, 0);
  EXPECT_FALSE(s.closed_manifold);
  EXPECT_EQ(s.component_genus, std::vector<int>{-1});

  // A square of two triangles and, apart, a closed tetrahedron: two components, one of them closed.
  SurfaceMesh two = tet;
  const int o = int(two.vertices.size());
  for (auto p : std::vector<std::array<double, 3>>{{5, 0, 0}, {6, 0, 0}, {6, 1, 0}, {5, 1, 0}}) two.vertices.push_back(p);
  two.faces.push_back({o, o + 1, o + 2});
  two.faces.push_back({o, o + 2, o + 3});
  s = surface_stats(two);
  EXPECT_EQ(s.components, 2);
  EXPECT_EQ(s.boundary_edges, 4);
  EXPECT_EQ(s.edges, 6 + 5);
  EXPECT_EQ(s.component_genus, (std::vector<int>{0, -1}));
  EXPECT_EQ(s.genus, 0);
  EXPECT_EQ(s.euler, 2 + 1);

  // Each vertex's neighbours, read from its faces, are the other ends of its edges, rising, on every mesh
  // above and on a marched torus; edges and edge tests agree with them.
  SurfaceMesh torus = extract_zero_surface(cube_field(40, analytic::torus(0.3, 0.12)));
  for (const SurfaceMesh* m : {&tet, &bowtie, &book, &flipped, &two, &torus}) {
    std::vector<std::vector<int>> expected(m->vertices.size());
    for (const auto& f : m->faces)
      for (int k = 0; k < 3; ++k) {
        expected[std::size_t(f[k])].push_back(f[(k + 1) % 3]);
        expected[std::size_t(f[(k + 1) % 3])].push_back(f[k]);
      }
    const MeshAdjacency A = build_adjacency(*m);
    std::vector<int> got;
    std::int64_t ends = 0;
    for (std::size_t v = 0; v < m->vertices.size(); ++v) {
      auto& e = expected[v];
      std::sort(e.begin(), e.end());
      e.erase(std::unique(e.begin(), e.end()), e.end());
      A.neighbours(*m, int(v), got);
      ASSERT_EQ(got, e) << "vertex " << v;
      ends += std::int64_t(e.size());
      for (int w : e) ASSERT_TRUE(A.has_edge(*m, int(v), w) && A.has_edge(*m, w, int(v)));
      if (!e.empty()) EXPECT_FALSE(A.has_edge(*m, int(v), int(v)));
    }
    EXPECT_EQ(ends, 2 * surface_stats(*m, A).edges);
  }
  EXPECT_GT(torus.vertices.size(), 1000u);
}

// The adjacency's nearest-vertex search visits its cells ring by ring and stops early: it must answer as a
// scan of every vertex does (nearest within the radius among the accepted ones, the lowest index on a tie),
// for points on, near and far from the surface, outside its box, and radii from a fraction of a cell to the
// whole box.
TEST(Surface, NearestVertexAgreesWithAScanOfEveryVertex) {
  const SurfaceMesh mesh = extract_zero_surface(cube_field(40, analytic::torus(0.3, 0.12)));
  const MeshAdjacency adj = build_adjacency(mesh);
  ASSERT_GT(adj.cell_size, 0);
  std::uint64_t state = 12345;
  auto uniform = [&] {  // deterministic, in [0, 1)
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return double(state >> 11) / double(1ull << 53);
  };
  const double radii[] = {0.3 * adj.cell_size, 1.5 * adj.cell_size, 6 * adj.cell_size, 10.0};
  int found = 0, checked = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    std::array<double, 3> p;
    if (trial % 3 == 0) {  // on a vertex, nudged
      p = mesh.vertices[std::size_t(trial * 7919) % mesh.vertices.size()];
      for (double& x : p) x += (uniform() - 0.5) * adj.cell_size;
    } else {
      for (double& x : p) x = -0.2 + 1.4 * uniform();  // beyond the surface's box too
    }
    const double radius = radii[trial % 4];
    const int modulus = trial % 2 ? 3 : 1;  // every third vertex refused, or none
    auto accept = [&](int v) { return v % modulus != 0 || modulus == 1; };
    int expected = -1;
    double best = radius * radius;
    for (int v = 0; v < int(mesh.vertices.size()); ++v) {
      const auto& q = mesh.vertices[std::size_t(v)];
      const double d2 = (q[0] - p[0]) * (q[0] - p[0]) + (q[1] - p[1]) * (q[1] - p[1]) + (q[2] - p[2]) * (q[2] - p[2]);
      if (accept(v) && (d2 < best || (d2 == best && expected >= 0 && v < expected))) best = d2, expected = v;
    }
    EXPECT_EQ(adj.nearest_vertex(mesh, p, radius, accept), expected) << "trial " << trial;
    found += expected >= 0;
    ++checked;
  }
  EXPECT_GT(found, checked / 4);       // the test sees real answers,
  EXPECT_LT(found, checked);           // and points with none in reach
}

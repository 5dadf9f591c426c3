#pragma once
// Small analytic triangle meshes shared by the tests.
#include <cmath>

#include "chokeloops/io/mesh_io.h"

namespace chokeloops::test {

// Torus around z: major radius R, minor radius a, nu x nv quads split in two; closed, outward oriented.
// Vertex (i, j) is i * nv + j, so vertices 0 .. nv-1 form a meridian edge loop.
inline TriangleMesh polyhedral_torus(double R, double a, int nu, int nv) {
  TriangleMesh m;
  const double pi = std::acos(-1.0);
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      double u = 2 * pi * i / nu, w = 2 * pi * j / nv;
      m.vertices.push_back({(R + a * std::cos(w)) * std::cos(u), (R + a * std::cos(w)) * std::sin(u), a * std::sin(w)});
    }
  auto id = [&](int i, int j) { return ((i + nu) % nu) * nv + (j + nv) % nv; };
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      m.faces.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      m.faces.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return m;
}

}  // namespace chokeloops::test

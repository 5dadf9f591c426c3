// Fast generalised winding number (Barill et al. 2018, first-order dipoles), stage `levelset`.
#include "chokeloops/field/winding_number.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "chokeloops/grid.h"

namespace chokeloops {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr std::int32_t kLeafSize = 8;

// Solid angle of triangle abc seen from the origin (Van Oosterom & Strackee 1983), signed: positive
// when its normal (b - a) x (c - a) points away from the origin (the origin is behind it).
double solid_angle(const double* a, const double* b, const double* c) {
  const double la = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
  const double lb = std::sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
  const double lc = std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
  const double det = a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
                     a[2] * (b[0] * c[1] - b[1] * c[0]);
  const double ab = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
  const double bc = b[0] * c[0] + b[1] * c[1] + b[2] * c[2];
  const double ca = c[0] * a[0] + c[1] * a[1] + c[2] * a[2];
  return 2.0 * std::atan2(det, la * lb * lc + ab * lc + bc * la + ca * lb);
}

double triangle_solid_angle(const std::array<double, 9>& t, const std::array<double, 3>& q) {
  const double a[3] = {t[0] - q[0], t[1] - q[1], t[2] - q[2]};
  const double b[3] = {t[3] - q[0], t[4] - q[1], t[5] - q[2]};
  const double c[3] = {t[6] - q[0], t[7] - q[1], t[8] - q[2]};
  return solid_angle(a, b, c);
}

}  // namespace

WindingNumber::WindingNumber(const TriangleMesh& mesh, double beta) : beta_(beta) {
  if (mesh.faces.empty()) throw Error("winding number: the mesh has no triangles");
  const std::size_t nv = mesh.vertices.size();
  tri_.reserve(mesh.faces.size());
  std::vector<std::array<double, 3>> centroid;
  centroid.reserve(mesh.faces.size());
  for (auto& f : mesh.faces) {
    std::array<double, 9> t;
    for (int k = 0; k < 3; ++k) {
      if (f[k] < 0 || std::size_t(f[k]) >= nv) throw Error("winding number: a face references a missing vertex");
      for (int d = 0; d < 3; ++d) t[3 * k + d] = mesh.vertices[std::size_t(f[k])][d];
    }
    tri_.push_back(t);
    centroid.push_back({(t[0] + t[3] + t[6]) / 3, (t[1] + t[4] + t[7]) / 3, (t[2] + t[5] + t[8]) / 3});
  }
  std::vector<std::int32_t> order(tri_.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = std::int32_t(i);
  nodes_.reserve(2 * tri_.size() / kLeafSize + 2);
  build(0, std::int32_t(tri_.size()), order, centroid);
  std::vector<std::array<double, 9>> sorted(tri_.size());
  for (std::size_t i = 0; i < order.size(); ++i) sorted[i] = tri_[std::size_t(order[i])];
  tri_.swap(sorted);
}

std::int32_t WindingNumber::build(std::int32_t first, std::int32_t count, std::vector<std::int32_t>& order,
                                  const std::vector<std::array<double, 3>>& centroid) {
  const std::int32_t id = std::int32_t(nodes_.size());
  nodes_.push_back({});
  Node n{};
  double wsum = 0, lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
  for (std::int32_t i = first; i < first + count; ++i) {
    const auto& t = tri_[std::size_t(order[std::size_t(i)])];
    const double u[3] = {t[3] - t[0], t[4] - t[1], t[5] - t[2]}, v[3] = {t[6] - t[0], t[7] - t[1], t[8] - t[2]};
    const double av[3] = {0.5 * (u[1] * v[2] - u[2] * v[1]), 0.5 * (u[2] * v[0] - u[0] * v[2]),
                          0.5 * (u[0] * v[1] - u[1] * v[0])};
    const double area = std::sqrt(av[0] * av[0] + av[1] * av[1] + av[2] * av[2]);
    const auto& c = centroid[std::size_t(order[std::size_t(i)])];
    for (int d = 0; d < 3; ++d) {
      n.area_vec[d] += av[d];
      n.centre[d] += area * c[d];
      lo[d] = std::min(lo[d], c[d]);
      hi[d] = std::max(hi[d], c[d]);
    }
    wsum += area;
  }
  for (int d = 0; d < 3; ++d) n.centre[d] = wsum > 0 ? n.centre[d] / wsum : 0.5 * (lo[d] + hi[d]);
  double r2 = 0;
  for (std::int32_t i = first; i < first + count; ++i) {
    const auto& t = tri_[std::size_t(order[std::size_t(i)])];
    for (int k = 0; k < 3; ++k) {
      const double dx = t[3 * k] - n.centre[0], dy = t[3 * k + 1] - n.centre[1], dz = t[3 * k + 2] - n.centre[2];
      r2 = std::max(r2, dx * dx + dy * dy + dz * dz);
    }
  }
  n.radius = std::sqrt(r2);
  n.first = first;
  n.count = count;
  n.left = n.right = -1;
  if (count > kLeafSize) {
    int axis = 0;
    for (int d = 1; d < 3; ++d)
      if (hi[d] - lo[d] > hi[axis] - lo[axis]) axis = d;
    const std::int32_t half = count / 2;
    std::nth_element(order.begin() + first, order.begin() + first + half, order.begin() + first + count,
                     [&](std::int32_t a, std::int32_t b) {
                       const double ca = centroid[std::size_t(a)][axis], cb = centroid[std::size_t(b)][axis];
                       return ca < cb || (ca == cb && a < b);
                     });
    n.left = build(first, half, order, centroid);
    n.right = build(first + half, count - half, order, centroid);
  }
  nodes_[std::size_t(id)] = n;
  return id;
}

double WindingNumber::exact(const std::array<double, 3>& q) const {
  double sum = 0;
  for (auto& t : tri_) sum += triangle_solid_angle(t, q);
  return sum / (4 * kPi);
}

double WindingNumber::operator()(const std::array<double, 3>& q) const {
  double sum = 0;
  std::int32_t stack[128];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& n = nodes_[std::size_t(stack[--top])];
    const double d[3] = {n.centre[0] - q[0], n.centre[1] - q[1], n.centre[2] - q[2]};
    const double dist2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    if (dist2 > beta_ * beta_ * n.radius * n.radius) {
      // far: the cluster's dipole, (c - q) . A / |c - q|^3
      const double dist = std::sqrt(dist2);
      sum += (d[0] * n.area_vec[0] + d[1] * n.area_vec[1] + d[2] * n.area_vec[2]) / (dist2 * dist);
    } else if (n.left < 0 || top + 2 > 128) {
      for (std::int32_t i = n.first; i < n.first + n.count; ++i) sum += triangle_solid_angle(tri_[std::size_t(i)], q);
    } else {
      stack[top++] = n.left;
      stack[top++] = n.right;
    }
  }
  return sum / (4 * kPi);
}

}  // namespace chokeloops

// Step 3 of shorten_loop: the triangle strip around the edge loop, the funnel algorithm through its
// unfolding, Gauss-Seidel polishing of the portal crossings and strip side swaps at apexes below pi.
#include <algorithm>
#include <cmath>
#include <vector>

#include "shortener.h"

namespace chokeloops::shorten_detail {

namespace {

struct P2 { double x, y; };

double len2(P2 a, P2 b) { return std::sqrt((a.x - b.x) * (a.x - b.x) + (a.y - b.y) * (a.y - b.y)); }  // hypot: 3x slower here
// Mononen's triarea2: > 0 when c lies to the right of a->b (y up).
double triarea2(P2 a, P2 b, P2 c) { return (c.x - a.x) * (b.y - a.y) - (b.x - a.x) * (c.y - a.y); }
bool same(P2 a, P2 b) { return a.x == b.x && a.y == b.y; }
// Portals from `from` on to `to` round a closed strip of m portals.
int portals_ahead(int m, int from, int to) {
  const int d = to - from;
  if (d >= 0 && d < m) return d;
  if (d < 0 && d >= -m) return d + m;
  return (d % m + m) % m;
}
// x mod m for 0 <= x < 3m, without a division: the strip's loops take an index round the strip at every
// portal, and `% m` with m known only at run time is a division (the swap rounds ~7% faster without them).
int wrap(int x, int m) {
  if (x >= m) x -= m;
  if (x >= m) x -= m;
  return x;
}

// A thread's funnel arrays, kept between calls: a shortening runs the funnel hundreds of times.
struct FunnelScratch {
  std::vector<P2> L2, R2;
  std::vector<int> Lv, Rv;
  std::vector<P2> pts;
  std::vector<int> pidx, pside;
};

}  // namespace

bool Shortener::fan(int a, int p, int b, bool left, std::vector<int>& out, double& angle) const {
  out.clear();
  angle = 0;
  int limit = adj.vf_start[p + 1] - adj.vf_start[p] + 1;
  if (left) {
    int h = adj.halfedge(mesh, a, p);
    if (h < 0) return false;
    for (int it = 0; it < limit; ++it) {
      if (!face_in(h / 3)) return false;
      out.push_back(h / 3);
      int g = MeshAdjacency::next(h);  // p -> x
      angle += angle3(mesh.vertices[p], mesh.vertices[vert(h)], mesh.vertices[vert_to(g)]);
      if (vert_to(g) == b) return true;
      h = adj.twin[g];
      if (h < 0) return false;
    }
    return false;
  } else {
    int r = adj.halfedge(mesh, p, a);  // p -> a, face right of a->p
    if (r < 0) return false;
    for (int it = 0; it < limit; ++it) {
      if (!face_in(r / 3)) return false;
      out.push_back(r / 3);
      int q = MeshAdjacency::prev(r);  // y -> p
      angle += angle3(mesh.vertices[p], mesh.vertices[vert_to(r)], mesh.vertices[vert(q)]);
      if (vert(q) == b) return true;
      r = adj.twin[q];
      if (r < 0) return false;
    }
    return false;
  }
}

bool Shortener::strip_from_edge_loop(const std::vector<int>& P, std::vector<int>& S) const {
  S.clear();
  const size_t n = P.size();
  std::vector<int> fl, fr;
  for (size_t i = 0; i < n; ++i) {
    int a = P[(i + n - 1) % n], p = P[i], b = P[(i + 1) % n];
    double al = 0, ar = 0;
    bool okl = fan(a, p, b, true, fl, al), okr = fan(a, p, b, false, fr, ar);
    if (!okl && !okr) return false;
    const auto& use = (okl && (!okr || al <= ar)) ? fl : fr;
    for (int f : use)
      if (S.empty() || S.back() != f) S.push_back(f);
  }
  while (S.size() > 1 && S.back() == S.front()) S.pop_back();
  return S.size() >= 2 && portals_ok(S);
}

bool Shortener::portals_ok(const std::vector<int>& S, const std::vector<std::array<int, 2>>* ranges) const {
  auto ok = [&](std::size_t j) { return portal_of(S[j], S[j + 1 == S.size() ? 0 : j + 1]) >= 0; };
  if (!ranges) {
    for (std::size_t j = 0; j < S.size(); ++j)
      if (!ok(j)) return false;
    return true;
  }
  for (const auto& range : *ranges)
    for (std::size_t j = std::size_t(range[0]); j <= std::size_t(range[1]); ++j)
      if (!ok(j)) return false;
  return true;
}

int Shortener::portal_of(int f, int g) const {
  for (int k = 0; k < 3; ++k) {
    int h = 3 * g + k, t = adj.twin[h];
    if (t >= 0 && t / 3 == f) return h;
  }
  return -1;
}

double Shortener::funnel(const std::vector<int>& S, int c, std::vector<double>& s, std::vector<Apex>& apexes) {
  apexes.clear();
  funnel_segment(S, c, int(S.size()), s[c], s[c], s, apexes);
  return params_length(S, s);
}

void Shortener::funnel_segment(const std::vector<int>& S, int from, int count, double s_from, double s_to,
                               std::vector<double>& s, std::vector<Apex>& apexes, double* end_angle, double* plane_length) {
  const int m = int(S.size());
  thread_local FunnelScratch scratch;
  auto& [L2, R2, Lv, Rv, pts, pidx, pside] = scratch;
  L2.resize(count + 1), R2.resize(count + 1), Lv.resize(count + 1), Rv.resize(count + 1);
  // Unfold: 2D coordinates of portal endpoints, in traversal order i = 0..count (portal from+i).
  int h = portal_of(S[std::size_t(from)], S[std::size_t(wrap(from + 1, m))]);
  Lv[0] = vert(h), Rv[0] = vert_to(h);
  L2[0] = {0, 0};
  R2[0] = {dist3(mesh.vertices[Lv[0]], mesh.vertices[Rv[0]]), 0};
  for (int i = 1; i <= count; ++i) {
    const int he = h;  // entry half-edge x->y inside the face S[from+i]
    const int at = wrap(from + i, m);
    h = portal_of(S[std::size_t(at)], S[std::size_t(wrap(at + 1, m))]);  // exit portal: its endpoints are vertices of that face
    int x = vert(he), y = vert_to(he), z = vert(MeshAdjacency::prev(he));
    P2 X = L2[i - 1], Y = R2[i - 1];
    double dxy = len2(X, Y), dxz = dist3(mesh.vertices[x], mesh.vertices[z]), dyz = dist3(mesh.vertices[y], mesh.vertices[z]);
    double a = (dxz * dxz - dyz * dyz + dxy * dxy) / (2 * dxy);
    double bb = std::sqrt(std::max(0.0, dxz * dxz - a * a));
    P2 u{(Y.x - X.x) / dxy, (Y.y - X.y) / dxy}, perp{-u.y, u.x};
    P2 Z{X.x + a * u.x + bb * perp.x, X.y + a * u.y + bb * perp.y};
    int lx = vert(h), ry = vert_to(h);
    auto pos = [&](int v) { return v == x ? X : v == y ? Y : Z; };
    Lv[i] = lx, Rv[i] = ry;
    L2[i] = pos(lx), R2[i] = pos(ry);
  }
  // Funnel portals: start point, portals 1..count-1, end point.
  auto at = [](P2 a, P2 b, double t) { return P2{a.x + t * (b.x - a.x), a.y + t * (b.y - a.y)}; };
  const P2 start = at(L2[0], R2[0], s_from), end = at(L2[count], R2[count], s_to);
  auto portal_left = [&](int i) { return i == 0 ? start : i == count ? end : L2[i]; };
  auto portal_right = [&](int i) { return i == 0 ? start : i == count ? end : R2[i]; };
  pts.assign(1, start);
  pidx.assign(1, 0);
  pside.assign(1, -1);
  // Each funnel point carries its portal index and side (0 left endpoint, 1 right, -1 start point); a
  // reset funnel side inherits the apex's, so a re-added apex keeps its true position.
  P2 apex = start, left = start, right = start;
  int apexIndex = 0, leftIndex = 0, rightIndex = 0;
  int apexSide = -1, leftSide = -1, rightSide = -1;
  for (int i = 1; i <= count; ++i) {
    P2 l = portal_left(i), r = portal_right(i);
    int lside = i == count ? -1 : 0, rside = i == count ? -1 : 1;
    if (triarea2(apex, right, r) <= 0.0) {
      if (same(apex, right) || triarea2(apex, left, r) > 0.0) {
        right = r, rightIndex = i, rightSide = rside;
      } else {
        pts.push_back(left), pidx.push_back(leftIndex), pside.push_back(leftSide);
        apex = left, apexIndex = leftIndex, apexSide = leftSide;
        left = right = apex, leftIndex = rightIndex = apexIndex, leftSide = rightSide = apexSide;
        i = apexIndex;
        continue;
      }
    }
    if (triarea2(apex, left, l) >= 0.0) {
      if (same(apex, left) || triarea2(apex, right, l) < 0.0) {
        left = l, leftIndex = i, leftSide = lside;
      } else {
        pts.push_back(right), pidx.push_back(rightIndex), pside.push_back(rightSide);
        apex = right, apexIndex = rightIndex, apexSide = rightSide;
        left = right = apex, leftIndex = rightIndex = apexIndex, leftSide = rightSide = apexSide;
        i = apexIndex;
        continue;
      }
    }
  }
  pts.push_back(end), pidx.push_back(count), pside.push_back(-1);
  if (plane_length) {
    *plane_length = 0;
    for (std::size_t k = 0; k + 1 < pts.size(); ++k) *plane_length += len2(pts[k], pts[k + 1]);
  }
  if (end_angle) {
    // The angles the first and last segments make with the cut portal, each in its own unfolding (the
    // portal's two copies are congruent), sum to the angle through the strip at the crossing held.
    *end_angle = -1;
    const int n = int(pts.size());
    int first = 1, last = n - 2;
    while (first < n && same(pts[first], start)) ++first;
    while (last >= 0 && same(pts[last], end)) --last;
    if (first < n && last >= 0) {
      auto angle = [](P2 at, P2 a, P2 b) {
        const P2 u{a.x - at.x, a.y - at.y}, v{b.x - at.x, b.y - at.y};
        return std::atan2(std::fabs(u.x * v.y - u.y * v.x), u.x * v.x + u.y * v.y);
      };
      const P2 other_start = s_from == 0.0 ? R2[0] : L2[0], other_end = s_to == 0.0 ? R2[count] : L2[count];
      *end_angle = angle(start, other_start, pts[first]) + angle(end, other_end, pts[last]);
    }
  }
  // Crossing parameters. The funnel assumes a sleeve that unfolds without overlapping itself; where the
  // strip overlaps (tiny faces near clamped vertices, fans of more than 2*pi) its 2D length can be
  // optimistic, so callers measure the polyline actually built from the crossings.
  for (size_t k = 0; k + 1 < pts.size(); ++k) {
    if (pside[k] >= 0) {
      int i = pidx[k];
      s[std::size_t(wrap(from + i, m))] = pside[k] == 0 ? 0.0 : 1.0;
      apexes.push_back({wrap(from + i, m), pside[k] == 0 ? Lv[i] : Rv[i]});
    }
    P2 A = pts[k], B = pts[k + 1];
    for (int i = pidx[k] + 1; i < pidx[k + 1]; ++i) {
      P2 Lp = L2[i], Rp = R2[i];
      P2 d{B.x - A.x, B.y - A.y}, e{Rp.x - Lp.x, Rp.y - Lp.y};
      double den = e.x * d.y - e.y * d.x;
      double t = std::fabs(den) < 1e-300 ? 0.5 : ((A.x - Lp.x) * d.y - (A.y - Lp.y) * d.x) / den;
      s[std::size_t(wrap(from + i, m))] = std::min(1.0, std::max(0.0, t));
    }
  }
}

P3 Shortener::crossing(const std::vector<int>& S, const std::vector<double>& s, int j) const {
  const int m = int(S.size());
  int h = portal_of(S[std::size_t(j)], S[std::size_t(wrap(j + 1, m))]);
  return lerp3(mesh.vertices[vert(h)], mesh.vertices[vert_to(h)], s[j]);
}

double Shortener::params_length(const std::vector<int>& S, const std::vector<double>& s) const {
  const int m = int(S.size());
  double L = 0;
  P3 first = crossing(S, s, 0), prev = first;
  for (int j = 1; j < m; ++j) {
    P3 q = crossing(S, s, j);
    L += dist3(prev, q);
    prev = q;
  }
  return L + dist3(prev, first);
}

double Shortener::polish(const std::vector<int>& S, std::vector<double>& s, int sweeps) const {
  const int m = int(S.size());
  std::vector<int> ph(m);
  for (int j = 0; j < m; ++j) ph[j] = portal_of(S[std::size_t(j)], S[std::size_t(wrap(j + 1, m))]);
  auto point = [&](int j) { return lerp3(mesh.vertices[vert(ph[j])], mesh.vertices[vert_to(ph[j])], s[j]); };
  double L = params_length(S, s);
  for (int it = 0; it < sweeps; ++it) {
    for (int j = 0; j < m; ++j) {
      P3 P = point((j + m - 1) % m), Q = point((j + 1) % m);
      const P3& A = mesh.vertices[vert(ph[j])];
      const P3& B = mesh.vertices[vert_to(ph[j])];
      double len = dist3(A, B);
      if (len <= 0) continue;
      P3 d{(B[0] - A[0]) / len, (B[1] - A[1]) / len, (B[2] - A[2]) / len};
      auto split = [&](const P3& X, double& along, double& off) {
        P3 v{X[0] - A[0], X[1] - A[1], X[2] - A[2]};
        along = v[0] * d[0] + v[1] * d[1] + v[2] * d[2];
        P3 o{v[0] - along * d[0], v[1] - along * d[1], v[2] - along * d[2]};
        off = std::sqrt(o[0] * o[0] + o[1] * o[1] + o[2] * o[2]);
      };
      double ap, hp, aq, hq;
      split(P, ap, hp);
      split(Q, aq, hq);
      double tau = hp + hq > 0 ? ap + (aq - ap) * hp / (hp + hq) : 0.5 * (ap + aq);
      s[j] = std::min(1.0, std::max(0.0, tau / len));
    }
    double Ln = params_length(S, s);
    bool done = Ln > L - 1e-12 * L;
    L = std::min(L, Ln);
    if (done) break;
  }
  return L;
}

Polyline3 Shortener::strip_points(const std::vector<int>& S, const std::vector<double>& s) const {
  Polyline3 out;
  const int m = int(S.size());
  for (int j = 0; j < m; ++j) {
    int h = portal_of(S[j], S[(j + 1) % m]);
    P3 p = lerp3(mesh.vertices[vert(h)], mesh.vertices[vert_to(h)], s[j]);
    if (out.empty() || dist3(out.back(), p) > 0) out.push_back(p);
  }
  while (out.size() > 1 && dist3(out.back(), out.front()) == 0) out.pop_back();
  return out;
}

double Shortener::relax(const std::vector<int>& S, int c, std::vector<double>& s, std::vector<Apex>& apexes) {
  const int m = int(S.size());
  double best = funnel(S, c, s, apexes);
  int stalled = 0;
  for (int it = 0; it < 100 && stalled < 2; ++it) {
    c = (c + m / 2 + (it % 2)) % m;  // a portal far from the last cut
    double L = funnel(S, c, s, apexes);
    stalled = L < best - 1e-8 * best ? 0 : stalled + 1;
    best = std::min(best, L);
  }
  return best;
}

// Why one or two funnels can suffice: with the crossing of the cut portal held, the funnel gives the
// shortest loop through that crossing. The loop's length is a convex function of its crossings, so that
// loop is the strip's shortest as soon as moving the held crossing along its portal does not shorten it:
// when the loop runs straight through it (angle pi between its segments there), or, held at a vertex, when
// the angle through the strip between its segments there is at least pi. The cut goes where the swaps
// changed least (an apex they left, else a portal), and once more at the apex the first funnel found
// farthest from its cut; relax() only when neither holds. relax() alternates cuts and takes three or more.
double Shortener::funnel_through_apex(const std::vector<int>& S, std::vector<double>& s, std::vector<Apex>& apexes,
                                      const std::vector<std::array<int, 2>>& dirty) {
  const int m = int(S.size());
  auto forward = [m](int from, int to) { return portals_ahead(m, from, to); };
  auto clearance = [&](int portal) {
    int nearest = m;
    for (const auto& range : dirty) nearest = std::min({nearest, forward(portal, range[0]), forward(range[1], portal)});
    return nearest;
  };
  int cut = -1, vertex = -1, best = -1;
  for (const Apex& a : apexes)
    if (const int c = clearance(a.portal); c > best) best = c, cut = a.portal, vertex = a.vertex;
  if (cut < 0)
    for (int p = 0; p < m; ++p)
      if (const int c = clearance(p); c > best) best = c, cut = p;
  thread_local std::vector<double> held;  // kept by the thread: a loop's rounds hold a funnel hundreds of times
  thread_local std::vector<Apex> found;
  double length = 0;
  // One funnel cut at `portal`, held at `vertex` (or, with -1, at the crossing it has); true when optimal.
  auto try_cut = [&](int portal, int at_vertex) {
    held.assign(s.begin(), s.end());
    const int h = portal_of(S[std::size_t(portal)], S[std::size_t(portal + 1) % std::size_t(m)]);
    if (at_vertex >= 0) {
      if (at_vertex != vert(h) && at_vertex != vert_to(h)) return false;
      held[std::size_t(portal)] = at_vertex == vert(h) ? 0.0 : 1.0;
    }
    const double at = held[std::size_t(portal)];
    found.clear();
    double angle = -1, plane = 0;
    funnel_segment(S, portal, m, at, at, held, found, &angle, &plane);
    ++apex_funnels;
    constexpr double kTolerance = 1e-9;  // radians
    const bool on_vertex = at == 0.0 || at == 1.0;
    if (angle < 0 || (on_vertex ? angle < M_PI - kTolerance : std::fabs(angle - M_PI) > kTolerance)) return false;
    // Where the strip's unfolding overlaps itself the funnel's path can leave it (seen on the pierced
    // block's loops of 1600 faces and more): the path is the strip's only when the polyline through its
    // crossings is as long as the path in the plane.
    length = params_length(S, held);
    if (!(std::fabs(length - plane) <= 1e-12 * plane)) return false;
    if (on_vertex) found.push_back({portal, at == 0.0 ? vert(h) : vert_to(h)});
    std::sort(found.begin(), found.end(), [](const Apex& x, const Apex& y) { return x.portal < y.portal; });
    s.swap(held);
    apexes.swap(found);
    return true;
  };
  if (cut >= 0) {
    if (try_cut(cut, vertex)) return length;
    int again = -1, far = -1;
    for (const Apex& a : found)
      if (const int d = std::min(forward(cut, a.portal), forward(a.portal, cut)); d > far) far = d, again = int(&a - found.data());
    if (again >= 0) {
      const Apex a = found[std::size_t(again)];
      if (try_cut(a.portal, a.vertex)) return length;
    }
  }
  ++apex_funnels_relaxed;
  return relax(S, 0, s, apexes);
}

// Why windows suffice: the shortest path through a sleeve between two fixed points is unique, and where it
// bends it wraps a sleeve vertex (an apex). Between two apexes that a swap did not move, the path is the
// shortest one through the faces between them; so if the funnel over a window from apex E1 to apex E2 still
// bends at the apexes I1, I2 next to them inside, the path from E1 to I1 and from I2 to E2 is what it was,
// the bends at E1 and E2 are as before, and the whole loop is what a funnel over the whole strip gives.
double Shortener::refunnel(const std::vector<int>& S, std::vector<double>& s, std::vector<Apex>& apexes,
                           const std::vector<std::array<int, 2>>& dirty) {
  const int m = int(S.size());
  thread_local std::vector<Apex> found, merged;  // kept by the thread, as the funnel's own arrays
  std::vector<char> pending(dirty.size(), 1);
  auto forward = [m](int from, int to) { return portals_ahead(m, from, to); };
  for (std::size_t r = 0; r < dirty.size(); ++r) {
    if (!pending[r]) continue;
    pending[r] = 0;
    int first = dirty[r][0], last = dirty[r][1];
    const int A = int(apexes.size());
    bool done = false;
    for (int k = 1; A > 0 && !done;) {
      // i1: the nearest apex at or before the range's first portal; i2: at or after its last (cyclic)
      int i1 = 0, i2 = 0;
      for (int i = 1; i < A; ++i) {
        if (forward(apexes[i].portal, first) < forward(apexes[i1].portal, first)) i1 = i;
        if (forward(last, apexes[i].portal) < forward(last, apexes[i2].portal)) i2 = i;
      }
      const int inner_span = ((i2 - i1) % A + A) % A;
      if (inner_span + 2 * k >= A) break;  // the window would wrap round the loop
      const Apex e1 = apexes[((i1 - k) % A + A) % A], e2 = apexes[(i2 + k) % A];
      const int count = forward(e1.portal, e2.portal);
      if (count == 0) break;
      // A range still to be redone inside the window changes the path next to its ends: take it in.
      bool absorbed = false;
      for (std::size_t q = r + 1; q < dirty.size(); ++q)
        if (pending[q] && forward(e1.portal, dirty[q][0]) < count) {
          pending[q] = 0;
          if (forward(e1.portal, dirty[q][0]) < forward(e1.portal, first)) first = dirty[q][0];
          if (forward(e1.portal, dirty[q][1]) > forward(e1.portal, last)) last = dirty[q][1];
          absorbed = true;
        }
      if (absorbed) continue;
      const Apex in1 = apexes[((i1 - k + 1) % A + A) % A], in2 = apexes[(i2 + k - 1) % A];
      // The funnel can list one vertex at two portals in a row (a bend of zero length between them): an
      // inner apex at its window end's vertex checks nothing.
      if (in1.vertex == e1.vertex || in2.vertex == e2.vertex) { ++k; continue; }
      found.clear();
      funnel_segment(S, e1.portal, count, s[e1.portal], s[e2.portal], s, found);
      auto has = [&](const Apex& x) {
        for (const Apex& f : found)
          if (f.vertex == x.vertex) return true;
        return false;
      };
      if (!has(in1) || !has(in2)) {
        // Each try funnels its whole window again: doubling the apexes taken in on each side costs at most
        // about twice the window that passes, where one more apex a try cost that window times half the
        // tries (the pierced block's long loops: 45% of the windows' portals were in windows that failed).
        k = std::max(k + 1, std::min(2 * k, (A - inner_span - 1) / 2));
        continue;
      }
      merged.clear();
      for (const Apex& a : apexes) {
        const int d = forward(e1.portal, a.portal);
        if (d == 0 || d >= count) merged.push_back(a);
      }
      merged.insert(merged.end(), found.begin(), found.end());
      std::sort(merged.begin(), merged.end(), [](const Apex& x, const Apex& y) { return x.portal < y.portal; });
      apexes.swap(merged);
      done = true;
      ++refunnel_windows;
    }
    if (!done) {
      ++refunnel_fallbacks;
      return funnel_through_apex(S, s, apexes, dirty);
    }
  }
  return params_length(S, s);
}

bool Shortener::other_fan(int v, int fa, int fb, int fa_next, std::vector<int>& run) const {
  // Start from the edge of fa at v that is NOT shared with fa_next.
  int hstart = -1;
  for (int k = 0; k < 3; ++k) {
    int h = 3 * fa + k;
    bool at_v = vert(h) == v || vert_to(h) == v;
    if (!at_v) continue;
    int t = adj.twin[h];
    if (t >= 0 && t / 3 == fa_next) continue;
    hstart = h;
  }
  if (hstart < 0) return false;
  const std::size_t start = run.size();
  run.push_back(fa);
  int h = hstart;
  int limit = adj.vf_start[v + 1] - adj.vf_start[v] + 1;
  for (int it = 0; it < limit; ++it) {
    int t = adj.twin[h];
    if (t < 0) break;
    int g = t / 3;
    if (!face_in(g)) break;
    run.push_back(g);
    if (g == fb) return true;
    // the other edge of g at v
    int nh = -1;
    for (int k = 0; k < 3; ++k) {
      int e = 3 * g + k;
      if (e == t) continue;
      if (vert(e) == v || vert_to(e) == v) nh = e;
    }
    if (nh < 0) break;
    h = nh;
  }
  run.resize(start);
  return false;
}

double Shortener::corner_angle(int f, int v) const {
  const int* place = band.in_face.find(f);
  if (!place) return angle_at_corner(mesh, f, v);
  if (corner_angle_of.size() != 3 * band.faces.size()) corner_angle_of.assign(3 * band.faces.size(), -1.0);
  double& kept = corner_angle_of[3 * std::size_t(*place) + std::size_t(corner_of(mesh, f, v))];
  if (kept < 0) kept = angle_at_corner(mesh, f, v);
  return kept;
}

double Shortener::total_angle(int v) const {
  const int l = local_of(v);
  if (l >= 0) {
    if (total_angle_of.size() != band.global.size()) total_angle_of.assign(band.global.size(), -1.0);
    double& kept = total_angle_of[std::size_t(l)];
    if (kept < 0) kept = sum_of_angles(v);
    return kept;
  }
  return sum_of_angles(v);
}

double Shortener::sum_of_angles(int v) const {
  double a = 0;
  for (int i = adj.vf_start[v]; i < adj.vf_start[v + 1]; ++i) a += angle_at_corner(mesh, adj.vf[i], v);
  return a;
}

bool Shortener::interior_vertex(int v) const {
  if (adj.closed_oriented) return true;  // every edge has its twin
  for (int i = adj.vf_start[v]; i < adj.vf_start[v + 1]; ++i)
    for (int k = 0; k < 3; ++k)
      if (adj.twin[3 * adj.vf[i] + k] < 0) return false;
  return true;
}

int Shortener::swap_batch(std::vector<int>& S, std::vector<double>& s, const std::vector<Apex>& apexes, int limit,
                          std::vector<Apex>& kept, std::vector<std::array<int, 2>>& dirty) {
  const int m = int(S.size());
  // A round's scratch, kept by the thread: a loop takes tens of rounds (hundreds on long ones), each of which
  // allocated its candidates' runs, the new strip and three strip-sized tables.
  struct Cand { double other; int a, len; std::size_t run_at, run_size; };
  thread_local std::vector<Cand> cands;
  thread_local std::vector<int> runs, start_of, renumbered, NS;
  thread_local std::vector<char> used;
  thread_local std::vector<double> Ns;
  cands.clear();
  runs.clear();
  for (auto& ap : apexes) {
    int v = ap.vertex;
    if (!interior_vertex(v)) continue;
    // Run of strip faces containing v around portal ap.portal (between S[p] and S[p+1]).
    int a = ap.portal, b = wrap(ap.portal + 1, m), len = 2;
    while (len < m && contains(S[std::size_t(wrap(a + m - 1, m))], v)) a = wrap(a + m - 1, m), ++len;
    while (len < m && contains(S[std::size_t(wrap(b + 1, m))], v)) b = wrap(b + 1, m), ++len;
    if (len >= m - 2) continue;
    int fa = S[a], fb = S[b];
    // Entry crossing (portal a-1, opposite v in fa) and exit crossing (portal b).
    int hin = portal_of(S[std::size_t(wrap(a + m - 1, m))], fa), hout = portal_of(fb, S[std::size_t(wrap(b + 1, m))]);
    if (hin < 0 || hout < 0) continue;
    P3 qin = lerp3(mesh.vertices[vert(hin)], mesh.vertices[vert_to(hin)], s[std::size_t(wrap(a + m - 1, m))]);
    P3 qout = lerp3(mesh.vertices[vert(hout)], mesh.vertices[vert_to(hout)], s[b]);
    double run_angle = 0;
    for (int i = 0, j = a; i < len; ++i, j = wrap(j + 1, m)) run_angle += corner_angle(S[j], v);
    auto outer_vertex = [&](int f, int neighbour) {  // vertex u of f with edge (v,u) not shared with neighbour
      auto& t = mesh.faces[f];
      for (int k = 0; k < 3; ++k)
        if (t[k] != v && !contains(neighbour, t[k])) return t[k];
      return -1;
    };
    int ua = outer_vertex(fa, S[std::size_t(wrap(a + 1, m))]), ub = outer_vertex(fb, S[std::size_t(wrap(b + m - 1, m))]);
    if (ua < 0 || ub < 0) continue;
    double theta = run_angle - angle3(mesh.vertices[v], qin, mesh.vertices[ua]) - angle3(mesh.vertices[v], qout, mesh.vertices[ub]);
    double other = total_angle(v) - theta;
    if (!(other < M_PI - 1e-9)) continue;
    const std::size_t run_at = runs.size();
    if (!other_fan(v, fa, fb, S[std::size_t(wrap(a + 1, m))], runs)) continue;
    cands.push_back({other, a, len, run_at, runs.size() - run_at});
  }
  std::stable_sort(cands.begin(), cands.end(), [](const Cand& x, const Cand& y) { return x.other < y.other; });
  // A batch that swaps at every apex leaves the funnel no apex to be held at (Shortener::funnel_through_apex
  // then takes two funnels): the one of largest far-side angle waits a round. Cage: 8% more rounds, 17%
  // fewer funnels, the same loops.
  if (limit > 1 && cands.size() >= 2 && cands.size() == apexes.size()) limit = int(cands.size()) - 1;
  used.assign(std::size_t(m), 0);
  start_of.assign(std::size_t(m), -1);
  int chosen = 0, first_end = -1;
  for (size_t ci = 0; ci < cands.size(); ++ci) {
    auto& c = cands[ci];
    if (chosen >= limit) break;
    bool free = true;
    for (int i = -1; i <= c.len && free; ++i) free = !used[std::size_t(wrap(c.a + i + m, m))];
    if (!free) continue;
    for (int i = -1; i <= c.len; ++i) used[std::size_t(wrap(c.a + i + m, m))] = 1;
    start_of[c.a] = int(ci);
    if (first_end < 0) first_end = wrap(c.a + c.len, m);
    ++chosen;
  }
  if (!chosen) return 0;
  NS.clear();
  Ns.clear();
  // renumbered: the new index of each old portal that the swaps kept, else -1
  renumbered.assign(std::size_t(m), -1);
  dirty.clear();
  for (int i = 0; i < m;) {
    int j = wrap(first_end + i, m);
    if (start_of[j] >= 0) {
      auto& c = cands[start_of[j]];
      const int first = int(NS.size()) - 1;  // the old portal a-1, kept: a run never starts NS
      for (std::size_t k = 0; k < c.run_size; ++k) NS.push_back(runs[c.run_at + k]), Ns.push_back(0.5);
      Ns.back() = s[std::size_t(wrap(c.a + c.len - 1, m))];  // portal after fb is the old portal b
      renumbered[std::size_t(wrap(c.a + c.len - 1, m))] = int(NS.size()) - 1;
      dirty.push_back({first, int(NS.size()) - 1});
      i += c.len;
    } else {
      renumbered[j] = int(NS.size());
      NS.push_back(S[j]), Ns.push_back(s[j]);
      ++i;
    }
  }
  // The strip was whole before (strip_from_edge_loop and every batch check it): only the portals into, through
  // and out of the new runs can fail (on a loop of 4000 faces a check of the whole strip cost a funnel's tenth).
  if (!portals_ok(NS, &dirty)) return 0;
  kept.clear();
  for (const Apex& ap : apexes)
    if (renumbered[ap.portal] >= 0) kept.push_back({renumbered[ap.portal], ap.vertex});
  std::sort(kept.begin(), kept.end(), [](const Apex& x, const Apex& y) { return x.portal < y.portal; });
  S.swap(NS);
  s.swap(Ns);
  return chosen;
}

}  // namespace chokeloops::shorten_detail

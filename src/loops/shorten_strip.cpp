// Step 3 of shorten_loop: the triangle strip around the edge loop, the funnel algorithm through its
// unfolding (again only where swaps changed it) and Gauss-Seidel polishing of the portal crossings; the
// side swaps themselves are in shorten_swaps.cpp.
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

// A point of the funnel: where it lies in the unfolding, its portal and side (0 left, 1 right, -1 an end).
struct FunnelPoint {
  P2 p;
  int index, side;
};

// A thread's funnel arrays, kept between calls: a shortening runs the funnel hundreds of times.
struct FunnelScratch {
  std::vector<P2> L2, R2;
  std::vector<int> Lv, Rv;
  std::vector<P2> pts;
  std::vector<int> pidx, pside;
  std::vector<FunnelPoint> chain;
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
                               std::vector<double>& s, std::vector<Apex>& apexes, double* end_angle, double* plane_length,
                               double* loop_length) {
  const int m = int(S.size());
  thread_local FunnelScratch scratch;
  // Named references, not a structured binding: the lambdas below capture them (C++17).
  auto &L2 = scratch.L2, &R2 = scratch.R2;
  auto &Lv = scratch.Lv, &Rv = scratch.Rv;
  auto& pts = scratch.pts;
  auto &pidx = scratch.pidx, &pside = scratch.pside;
  auto& chain = scratch.chain;
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
    // Z's place along and off the entry edge comes from the face's squared edge lengths in 3D, so that the
    // chain from face to face carries no square root or division (the unfolding was most of a funnel's time).
    // The entry edge's direction in the plane is brought to unit length by a Newton step from its 3D length:
    // the unfolded edge is that long but for rounding, which would otherwise grow along the strip (4e-13
    // after 400 faces, past what funnel_through_apex's length check allows on the block's long loops).
    const P3 &px = mesh.vertices[std::size_t(x)], &py = mesh.vertices[std::size_t(y)], &pz = mesh.vertices[std::size_t(z)];
    const double xy2 = dist3_squared(px, py), xz2 = dist3_squared(px, pz), yz2 = dist3_squared(py, pz);
    const double inverse = 1 / std::sqrt(xy2);
    const double a = 0.5 * (xz2 - yz2 + xy2) * inverse;
    const double bb = std::sqrt(std::max(0.0, xz2 - a * a));
    const P2 e{Y.x - X.x, Y.y - X.y};
    const double unit = inverse * (1.5 - 0.5 * (e.x * e.x + e.y * e.y) * inverse * inverse);
    P2 u{e.x * unit, e.y * unit}, perp{-u.y, u.x};
    P2 Z{X.x + a * u.x + bb * perp.x, X.y + a * u.y + bb * perp.y};
    int lx = vert(h), ry = vert_to(h);
    auto pos = [&](int v) { return v == x ? X : v == y ? Y : Z; };
    Lv[i] = lx, Rv[i] = ry;
    L2[i] = pos(lx), R2[i] = pos(ry);
  }
  // Funnel portals: start point, portals 1..count-1, end point.
  auto at = [](P2 a, P2 b, double t) { return P2{a.x + t * (b.x - a.x), a.y + t * (b.y - a.y)}; };
  const P2 start = at(L2[0], R2[0], s_from), end = at(L2[count], R2[count], s_to);
  pts.assign(1, start);
  pidx.assign(1, 0);
  pside.assign(1, -1);
  // The funnel as a deque (Lee and Preparata): its apex, the left chain from the apex towards `head` and the
  // right chain towards `tail`, each a convex chain of portal ends the path would bend round. A new end pops
  // the points of its own chain that it sees past; when that chain is left with the apex alone and the new
  // end lies across the other chain, the path bends round that chain's first points, which become apexes.
  // Each point enters and leaves once: linear in the portals, where the funnel that starts again from its
  // apex after each bend read 2.4 portals per portal on the pierced block's long loops (4.7 on the cage).
  // Each point carries its portal index and side (0 left end, 1 right, -1 the start or end point).
  chain.resize(std::size_t(2 * count + 3));
  int head = count + 1, tail = count + 1, apex = count + 1;
  chain[std::size_t(apex)] = {start, 0, -1};
  auto emit = [&](const FunnelPoint& q) { pts.push_back(q.p), pidx.push_back(q.index), pside.push_back(q.side); };
  auto add_right = [&](const FunnelPoint& q) {
    if (same(chain[std::size_t(tail)].p, q.p)) return;
    while (tail > apex && triarea2(chain[std::size_t(tail - 1)].p, chain[std::size_t(tail)].p, q.p) <= 0.0) --tail;
    if (tail == apex) {
      while (head < apex && triarea2(chain[std::size_t(apex)].p, chain[std::size_t(apex - 1)].p, q.p) <= 0.0) emit(chain[std::size_t(--apex)]);
      tail = apex;
    }
    chain[std::size_t(++tail)] = q;
  };
  auto add_left = [&](const FunnelPoint& q) {
    if (same(chain[std::size_t(head)].p, q.p)) return;
    while (head < apex && triarea2(chain[std::size_t(head + 1)].p, chain[std::size_t(head)].p, q.p) >= 0.0) ++head;
    if (head == apex) {
      while (tail > apex && triarea2(chain[std::size_t(apex)].p, chain[std::size_t(apex + 1)].p, q.p) >= 0.0) emit(chain[std::size_t(++apex)]);
      head = apex;
    }
    chain[std::size_t(--head)] = q;
  };
  for (int i = 1; i < count; ++i) {
    add_right({R2[std::size_t(i)], i, 1});
    add_left({L2[std::size_t(i)], i, 0});
  }
  // The end point as a left end: the path from the apex to it runs along what is left of the left chain.
  add_left({end, count, -1});
  for (int k = apex - 1; k > head; --k) emit(chain[std::size_t(k)]);
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
  if (loop_length) {
    // The polyline through the crossings, from the portals' vertices the unfolding already read (what
    // params_length gives, without finding each portal again).
    auto crossing_at = [&](int i) {
      return lerp3(mesh.vertices[std::size_t(Lv[i])], mesh.vertices[std::size_t(Rv[i])], s[std::size_t(wrap(from + i, m))]);
    };
    const P3 first = crossing_at(0);
    P3 previous = first;
    double length = 0;
    for (int i = 1; i < count; ++i) {
      const P3 q = crossing_at(i);
      length += dist3(previous, q);
      previous = q;
    }
    *loop_length = length + dist3(previous, first);
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
    funnel_segment(S, portal, m, at, at, held, found, &angle, &plane, &length);
    ++apex_funnels;
    constexpr double kTolerance = 1e-9;  // radians
    const bool on_vertex = at == 0.0 || at == 1.0;
    if (angle < 0 || (on_vertex ? angle < M_PI - kTolerance : std::fabs(angle - M_PI) > kTolerance)) return false;
    // Where the strip's unfolding overlaps itself the funnel's path can leave it (seen on the pierced
    // block's loops of 1600 faces and more): the path is the strip's only when the polyline through its
    // crossings is as long as the path in the plane.
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
      // A window over half the strip costs what the funnel over the whole strip does, and may still fail.
      if (count == 0 || 2 * count > m) break;
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

}  // namespace chokeloops::shorten_detail

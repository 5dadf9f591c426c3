#include "chokeloops/loops/shorten.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <numeric>
#include <queue>
#include <unordered_map>
#include <unordered_set>

#include <tbb/parallel_for.h>

#include "chokeloops/surface/topology.h"

namespace chokeloops {

namespace {

using P3 = std::array<double, 3>;
struct P2 { double x, y; };

double dist3(const P3& a, const P3& b) {
  return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}
P3 lerp3(const P3& a, const P3& b, double s) { return {a[0] + s * (b[0] - a[0]), a[1] + s * (b[1] - a[1]), a[2] + s * (b[2] - a[2])}; }
double angle3(const P3& v, const P3& a, const P3& b) {  // angle at v between v->a and v->b
  P3 u{a[0] - v[0], a[1] - v[1], a[2] - v[2]}, w{b[0] - v[0], b[1] - v[1], b[2] - v[2]};
  P3 c{u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
  double cn = std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
  return std::atan2(cn, u[0] * w[0] + u[1] * w[1] + u[2] * w[2]);
}
double len2(P2 a, P2 b) { return std::hypot(a.x - b.x, a.y - b.y); }
// Mononen's triarea2: > 0 when c lies to the right of a->b (y up).
double triarea2(P2 a, P2 b, P2 c) { return (c.x - a.x) * (b.y - a.y) - (b.x - a.x) * (c.y - a.y); }
bool same(P2 a, P2 b) { return a.x == b.x && a.y == b.y; }

// Everything about the annulus band around the loop.
struct Band {
  std::unordered_set<int> in_face;  // mesh faces of the band
  std::vector<int> faces;
  std::unordered_map<int, int> local;  // mesh vertex -> band vertex
  std::vector<int> global;          // band vertex -> mesh vertex
  std::unordered_map<int, int> sign;  // cut crossing sign per mesh half-edge
  int winding = 0;                  // of the input loop
  std::vector<int> cut_vertices;    // band vertices at one end of each crossed edge, along the cut
};

struct Shortener {
  const SurfaceMesh& mesh;
  const MeshAdjacency& adj;
  Band band;

  Shortener(const SurfaceMesh& m, const MeshAdjacency& a) : mesh(m), adj(a) {}

  int vert(int h) const { return mesh.faces[h / 3][h % 3]; }          // source of half-edge h
  int vert_to(int h) const { return mesh.faces[h / 3][(h % 3 + 1) % 3]; }
  bool face_in(int f) const { return f >= 0 && band.in_face.count(f); }
  int local_of(int v) const {
    auto it = band.local.find(v);
    return it == band.local.end() ? -1 : it->second;
  }
  int hsign(int h) const {
    auto it = band.sign.find(h);
    return it == band.sign.end() ? 0 : it->second;
  }
  // Half-edge a->b in any face, or -1 - (half-edge b->a) when only the reverse exists.
  int signed_edge_sign(int a, int b) const {
    int h = adj.halfedge(mesh, a, b);
    if (h >= 0) return hsign(h);
    int r = adj.halfedge(mesh, b, a);
    return r >= 0 ? -hsign(r) : 0;
  }

  // ---- Step 1: band ------------------------------------------------------------------------------
  // Builds the band of faces allowed by `allowed_vertex` and checks that it is an annulus; sets the cut.
  // `region`: mesh vertices near the loop; `allowed[i]` and `near_loop[i]` (2: on the loop, 1: one ring
  // away) refer to region[i]; `rid` maps mesh vertices to region indices.
  bool build_band(const std::vector<int>& region, const std::unordered_map<int, int>& rid,
                  const std::vector<char>& allowed, const std::vector<char>& near, const std::vector<int>& loop) {
    Band B;
    auto allowed_vertex = [&](int v) { auto it = rid.find(v); return it != rid.end() && allowed[it->second]; };
    auto near_loop = [&](int v) { auto it = rid.find(v); return it == rid.end() ? 0 : int(near[it->second]); };
    // Collect faces around allowed vertices.
    std::vector<int> cand;
    for (size_t i = 0; i < region.size(); ++i)
      if (allowed[i])
        for (int j = adj.vf_start[region[i]]; j < adj.vf_start[region[i] + 1]; ++j) cand.push_back(adj.vf[j]);
    std::sort(cand.begin(), cand.end());
    cand.erase(std::unique(cand.begin(), cand.end()), cand.end());
    for (int f : cand) {
      auto& t = mesh.faces[f];
      bool ok = true;
      for (int k = 0; k < 3; ++k) ok = ok && (allowed_vertex(t[k]) || near_loop(t[k]));
      if (!ok) continue;
      // faces touching the loop are always allowed; others need all vertices allowed
      if (!(allowed_vertex(t[0]) && allowed_vertex(t[1]) && allowed_vertex(t[2]))) {
        bool touches = near_loop(t[0]) == 2 || near_loop(t[1]) == 2 || near_loop(t[2]) == 2;
        if (!touches) continue;
      }
      B.in_face.insert(f);
      B.faces.push_back(f);
    }
    if (B.faces.empty()) return false;
    for (int f : B.faces)
      for (int k = 0; k < 3; ++k) {
        int v = mesh.faces[f][k];
        if (B.local.emplace(v, int(B.global.size())).second) B.global.push_back(v);
      }
    band = std::move(B);
    Band& b = band;
    // Euler characteristic, boundary, fans.
    std::int64_t V = std::int64_t(b.global.size()), F = std::int64_t(b.faces.size()), E = 0;
    std::vector<int> faces_at(V, 0), interior_at(V, 0), boundary_at(V, 0);
    std::vector<int> bparent(V);
    std::iota(bparent.begin(), bparent.end(), 0);
    auto find = [&](int x) { while (bparent[x] != x) x = bparent[x] = bparent[bparent[x]]; return x; };
    for (int f : b.faces)
      for (int k = 0; k < 3; ++k) {
        int h = 3 * f + k, t = adj.twin[h];
        int a = b.local.at(vert(h)), c = b.local.at(vert_to(h));
        ++faces_at[a];
        bool interior = t >= 0 && face_in(t / 3);
        if (interior) {
          if (h < t) {
            ++E;
            ++interior_at[a], ++interior_at[c];
          }
        } else {
          ++E;
          ++boundary_at[a], ++boundary_at[c];
          bparent[find(a)] = find(c);
        }
      }
    if (V - E + F != 0) return false;
    int boundary_components = 0;
    for (int v = 0; v < V; ++v) {
      if (boundary_at[v] != 0 && boundary_at[v] != 2) return false;
      int fans = boundary_at[v] ? faces_at[v] - interior_at[v] : 1;
      if (fans != 1) return false;
      if (boundary_at[v] && find(v) == v) ++boundary_components;
    }
    if (boundary_components != 2) return false;
    // Connected (face flood).
    {
      std::vector<int> stack{b.faces[0]};
      std::vector<char> seen(mesh.faces.size(), 0);
      seen[b.faces[0]] = 1;
      size_t reached = 1;
      while (!stack.empty()) {
        int f = stack.back();
        stack.pop_back();
        for (int k = 0; k < 3; ++k) {
          int t = adj.twin[3 * f + k];
          if (t >= 0 && face_in(t / 3) && !seen[t / 3]) seen[t / 3] = 1, ++reached, stack.push_back(t / 3);
        }
      }
      if (reached != b.faces.size()) return false;
    }
    // Cut: BFS over band faces from faces on boundary curve A to a face on boundary curve B.
    int rootA = -1;
    for (int v = 0; v < V && rootA < 0; ++v)
      if (boundary_at[v]) rootA = find(v);
    // Boundary half-edge of f on the given curve, or -1.
    auto on_curve = [&](int f, bool curveA) {
      for (int k = 0; k < 3; ++k) {
        int h = 3 * f + k, t = adj.twin[h];
        if (t >= 0 && face_in(t / 3)) continue;
        bool isA = find(b.local.at(vert(h))) == rootA;
        if (isA == curveA) return h;
      }
      return -1;
    };
    std::unordered_map<int, int> parent_h;  // face -> half-edge (in the parent face) crossed to reach it
    std::queue<int> q;
    for (int f : b.faces)
      if (on_curve(f, true) >= 0) parent_h[f] = -1, q.push(f);
    int target = -1;
    while (!q.empty() && target < 0) {
      int f = q.front();
      q.pop();
      if (on_curve(f, false) >= 0) { target = f; break; }
      for (int k = 0; k < 3; ++k) {
        int h = 3 * f + k, t = adj.twin[h];
        if (t < 0 || !face_in(t / 3) || parent_h.count(t / 3)) continue;
        parent_h[t / 3] = h;
        q.push(t / 3);
      }
    }
    if (target < 0) return false;
    // The cut runs from the midpoint of a boundary edge on curve A through the faces to the midpoint of
    // one on curve B; those two boundary edges count as crossed too (a loop along the boundary around
    // the cut's end would otherwise wind once).
    auto set_sign = [&](int h, int sg) {
      b.sign[h] = sg;
      if (adj.twin[h] >= 0) b.sign[adj.twin[h]] = -sg;
    };
    set_sign(on_curve(target, false), +1);
    int f = target;
    b.cut_vertices.clear();
    for (; parent_h[f] >= 0; f = parent_h[f] / 3) {
      set_sign(parent_h[f], +1);
      b.cut_vertices.push_back(b.local.at(vert(parent_h[f])));
    }
    set_sign(on_curve(f, true), -1);
    int w = 0;
    for (size_t i = 0; i < loop.size(); ++i) w += signed_edge_sign(loop[i], loop[(i + 1) % loop.size()]);
    b.winding = w;
    return w == 1 || w == -1;
  }

  // ---- Step 2: shortest edge loop in the band ----------------------------------------------------
  struct Arc { int to; double len; int sign; };
  std::vector<int> arc_start;
  std::vector<Arc> arcs;
  void build_arcs() {
    std::vector<std::vector<Arc>> tmp(band.global.size());
    for (int f : band.faces)
      for (int k = 0; k < 3; ++k) {
        int h = 3 * f + k;
        int a = band.local.at(vert(h)), c = band.local.at(vert_to(h));
        double L = dist3(mesh.vertices[vert(h)], mesh.vertices[vert_to(h)]);
        int s = hsign(h);
        tmp[a].push_back({c, L, s});
        tmp[c].push_back({a, L, -s});
      }
    arc_start.assign(tmp.size() + 1, 0);
    arcs.clear();
    for (size_t v = 0; v < tmp.size(); ++v) {
      std::sort(tmp[v].begin(), tmp[v].end(), [](const Arc& x, const Arc& y) { return x.to < y.to || (x.to == y.to && x.sign < y.sign); });
      tmp[v].erase(std::unique(tmp[v].begin(), tmp[v].end(), [](const Arc& x, const Arc& y) { return x.to == y.to && x.sign == y.sign; }), tmp[v].end());
      arcs.insert(arcs.end(), tmp[v].begin(), tmp[v].end());
      arc_start[v + 1] = int(arcs.size());
    }
  }
  // Shortest loop through band vertex s winding `band.winding` times; returns mesh vertices.
  std::vector<int> shortest_loop_through(int s, double& length) const {
    const int NL = 7, L0 = 3;  // sheets -3..3
    const int n = int(band.global.size());
    std::vector<double> d(size_t(n) * NL, std::numeric_limits<double>::infinity());
    std::vector<int> from(size_t(n) * NL, -1);
    using QE = std::pair<double, int>;
    std::priority_queue<QE, std::vector<QE>, std::greater<QE>> q;
    int src = s * NL + L0, dst = s * NL + L0 + band.winding;
    d[src] = 0;
    q.push({0, src});
    while (!q.empty()) {
      auto [dv, node] = q.top();
      q.pop();
      if (dv > d[node]) continue;
      if (node == dst) break;
      int v = node / NL, layer = node % NL;
      for (int i = arc_start[v]; i < arc_start[v + 1]; ++i) {
        int nl = layer + arcs[i].sign;
        if (nl < 0 || nl >= NL) continue;
        int w = arcs[i].to * NL + nl;
        double nd = dv + arcs[i].len;
        if (nd < d[w]) d[w] = nd, from[w] = node, q.push({nd, w});
      }
    }
    if (std::isinf(d[dst])) { length = std::numeric_limits<double>::infinity(); return {}; }
    length = d[dst];
    std::vector<int> path;
    for (int node = dst; node != src; node = from[node]) path.push_back(band.global[node / NL]);
    std::reverse(path.begin(), path.end());  // starts after s, ends with s
    std::rotate(path.begin(), path.end() - 1, path.end());
    return path;
  }

  // ---- Step 3: strip and funnel ------------------------------------------------------------------
  // Fan of faces around path vertex p (from in-edge a->p to out-edge p->b), on the left or the right.
  bool fan(int a, int p, int b, bool left, std::vector<int>& out, double& angle) const {
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
  bool strip_from_edge_loop(const std::vector<int>& P, std::vector<int>& S) const {
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
  // Portal j: half-edge (in S[j+1]) whose twin lies in S[j]; left = its source, right = its target.
  std::vector<int> portal_h;
  bool portals_ok(const std::vector<int>& S) const {
    for (size_t j = 0; j < S.size(); ++j)
      if (portal_of(S[j], S[(j + 1) % S.size()]) < 0) return false;
    return true;
  }
  int portal_of(int f, int g) const {
    for (int k = 0; k < 3; ++k) {
      int h = 3 * g + k, t = adj.twin[h];
      if (t >= 0 && t / 3 == f) return h;
    }
    return -1;
  }

  // Funnel through the strip cut at portal c with the loop crossing it at parameter s_c. Fills s (per
  // portal) and the apex list (portal index, mesh vertex). Returns the length.
  struct Apex { int portal; int vertex; };
  double funnel(const std::vector<int>& S, int c, std::vector<double>& s, std::vector<Apex>& apexes) {
    const int m = int(S.size());
    portal_h.resize(m);
    for (int j = 0; j < m; ++j) portal_h[j] = portal_of(S[j], S[(j + 1) % m]);
    // Unfold: 2D coordinates of portal endpoints, in traversal order i = 0..m (portal c+i).
    std::vector<P2> L2(m + 1), R2(m + 1);
    std::vector<int> Lv(m + 1), Rv(m + 1);
    {
      int h = portal_h[c];
      Lv[0] = vert(h), Rv[0] = vert_to(h);
      L2[0] = {0, 0};
      R2[0] = {dist3(mesh.vertices[Lv[0]], mesh.vertices[Rv[0]]), 0};
    }
    for (int i = 1; i <= m; ++i) {
      int f = S[(c + i) % m];
      int he = portal_h[(c + i - 1) % m];  // entry half-edge x->y inside f
      int x = vert(he), y = vert_to(he), z = vert(MeshAdjacency::prev(he));
      P2 X = L2[i - 1], Y = R2[i - 1];
      double dxy = len2(X, Y), dxz = dist3(mesh.vertices[x], mesh.vertices[z]), dyz = dist3(mesh.vertices[y], mesh.vertices[z]);
      double a = (dxz * dxz - dyz * dyz + dxy * dxy) / (2 * dxy);
      double bb = std::sqrt(std::max(0.0, dxz * dxz - a * a));
      P2 u{(Y.x - X.x) / dxy, (Y.y - X.y) / dxy}, perp{-u.y, u.x};
      P2 Z{X.x + a * u.x + bb * perp.x, X.y + a * u.y + bb * perp.y};
      int ho = portal_h[(c + i) % m];  // exit portal: its endpoints are vertices of f
      int lx = vert(ho), ry = vert_to(ho);
      auto pos = [&](int v) { return v == x ? X : v == y ? Y : Z; };
      (void)f;
      Lv[i] = lx, Rv[i] = ry;
      L2[i] = pos(lx), R2[i] = pos(ry);
    }
    // Funnel portals: start point, portals 1..m-1, end point.
    auto at = [](P2 a, P2 b, double t) { return P2{a.x + t * (b.x - a.x), a.y + t * (b.y - a.y)}; };
    P2 start = at(L2[0], R2[0], s[c]), end = at(L2[m], R2[m], s[c]);
    std::vector<P2> pl(m + 1), pr(m + 1);
    pl[0] = pr[0] = start;
    pl[m] = pr[m] = end;
    for (int i = 1; i < m; ++i) pl[i] = L2[i], pr[i] = R2[i];
    std::vector<P2> pts{start};
    std::vector<int> pidx{0};
    std::vector<int> pside{-1};
    // Each funnel point carries its portal index and side (0 left endpoint, 1 right, -1 start point); a
    // reset funnel side inherits the apex's, so a re-added apex keeps its true position.
    P2 apex = start, left = pl[0], right = pr[0];
    int apexIndex = 0, leftIndex = 0, rightIndex = 0;
    int apexSide = -1, leftSide = -1, rightSide = -1;
    for (int i = 1; i <= m; ++i) {
      P2 l = pl[i], r = pr[i];
      int lside = i == m ? -1 : 0, rside = i == m ? -1 : 1;
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
    pts.push_back(end), pidx.push_back(m), pside.push_back(-1);
    double length = 0;
    for (size_t k = 0; k + 1 < pts.size(); ++k) length += len2(pts[k], pts[k + 1]);
    // Crossing parameters.
    std::vector<double> ns(m);
    ns[c] = s[c];
    apexes.clear();
    for (size_t k = 0; k + 1 < pts.size(); ++k) {
      if (pside[k] >= 0) {
        int i = pidx[k];
        ns[(c + i) % m] = pside[k] == 0 ? 0.0 : 1.0;
        apexes.push_back({(c + i) % m, pside[k] == 0 ? Lv[i] : Rv[i]});
      }
      P2 A = pts[k], B = pts[k + 1];
      for (int i = pidx[k] + 1; i < pidx[k + 1]; ++i) {
        P2 Lp = L2[i], Rp = R2[i];
        P2 d{B.x - A.x, B.y - A.y}, e{Rp.x - Lp.x, Rp.y - Lp.y};
        double den = e.x * d.y - e.y * d.x;
        double t = std::fabs(den) < 1e-300 ? 0.5 : ((A.x - Lp.x) * d.y - (A.y - Lp.y) * d.x) / den;
        ns[(c + i) % m] = std::min(1.0, std::max(0.0, t));
      }
    }
    s = ns;
    // The funnel assumes a sleeve that unfolds without overlapping itself; where the strip overlaps (tiny
    // faces near clamped vertices, fans of more than 2*pi) its length can be optimistic, so report the
    // length of the polyline actually built from the crossings.
    (void)length;
    return params_length(S, s);
  }

  P3 crossing(const std::vector<int>& S, const std::vector<double>& s, int j) const {
    const int m = int(S.size());
    int h = portal_of(S[j], S[(j + 1) % m]);
    return lerp3(mesh.vertices[vert(h)], mesh.vertices[vert_to(h)], s[j]);
  }
  double params_length(const std::vector<int>& S, const std::vector<double>& s) const {
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
  // Gauss-Seidel on the crossing parameters: each crossing moves to the point of its portal that is
  // closest to its neighbours (unfolding the two faces around the portal). The length is a convex
  // function of the parameters, so this only polishes what the funnel left.
  double polish(const std::vector<int>& S, std::vector<double>& s, int sweeps) const {
    const int m = int(S.size());
    std::vector<int> ph(m);
    for (int j = 0; j < m; ++j) ph[j] = portal_of(S[j], S[(j + 1) % m]);
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
  Polyline3 strip_points(const std::vector<int>& S, const std::vector<double>& s) const {
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
  // Alternate the cut portal until the length stops decreasing.
  double relax(const std::vector<int>& S, int c, std::vector<double>& s, std::vector<Apex>& apexes) {
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

  // Faces around v from f_a the other way round to f_b (f_a and f_b included), or empty.
  std::vector<int> other_fan(int v, int fa, int fb, int fa_next) const {
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
    if (hstart < 0) return {};
    std::vector<int> run{fa};
    int h = hstart;
    int limit = adj.vf_start[v + 1] - adj.vf_start[v] + 1;
    for (int it = 0; it < limit; ++it) {
      int t = adj.twin[h];
      if (t < 0) return {};
      int g = t / 3;
      if (!face_in(g)) return {};
      run.push_back(g);
      if (g == fb) return run;
      // the other edge of g at v
      int nh = -1;
      for (int k = 0; k < 3; ++k) {
        int e = 3 * g + k;
        if (e == t) continue;
        if (vert(e) == v || vert_to(e) == v) nh = e;
      }
      if (nh < 0) return {};
      h = nh;
    }
    return {};
  }
  double total_angle(int v) const {
    double a = 0;
    for (int i = adj.vf_start[v]; i < adj.vf_start[v + 1]; ++i) {
      auto& t = mesh.faces[adj.vf[i]];
      int k = t[0] == v ? 0 : t[1] == v ? 1 : 2;
      a += angle3(mesh.vertices[v], mesh.vertices[t[(k + 1) % 3]], mesh.vertices[t[(k + 2) % 3]]);
    }
    return a;
  }
  bool interior_vertex(int v) const {
    for (int i = adj.vf_start[v]; i < adj.vf_start[v + 1]; ++i)
      for (int k = 0; k < 3; ++k)
        if (adj.twin[3 * adj.vf[i] + k] < 0) return false;
    return true;
  }
  bool contains(int f, int v) const { auto& t = mesh.faces[f]; return t[0] == v || t[1] == v || t[2] == v; }

  // Side swaps at every apex whose angle on the far side is below pi, for non-overlapping runs at once
  // (smallest far-side angle first). Returns the number of swaps made.
  int swap_batch(std::vector<int>& S, std::vector<double>& s, const std::vector<Apex>& apexes, int& cut, int limit) {
    const int m = int(S.size());
    struct Cand { double other; int a, len; std::vector<int> run; };
    std::vector<Cand> cands;
    for (auto& ap : apexes) {
      int v = ap.vertex;
      if (!interior_vertex(v)) continue;
      // Run of strip faces containing v around portal ap.portal (between S[p] and S[p+1]).
      int a = ap.portal, b = (ap.portal + 1) % m, len = 2;
      while (len < m && contains(S[(a + m - 1) % m], v)) a = (a + m - 1) % m, ++len;
      while (len < m && contains(S[(b + 1) % m], v)) b = (b + 1) % m, ++len;
      if (len >= m - 2) continue;
      int fa = S[a], fb = S[b];
      // Entry crossing (portal a-1, opposite v in fa) and exit crossing (portal b).
      int hin = portal_of(S[(a + m - 1) % m], fa), hout = portal_of(fb, S[(b + 1) % m]);
      if (hin < 0 || hout < 0) continue;
      P3 qin = lerp3(mesh.vertices[vert(hin)], mesh.vertices[vert_to(hin)], s[(a + m - 1) % m]);
      P3 qout = lerp3(mesh.vertices[vert(hout)], mesh.vertices[vert_to(hout)], s[b]);
      double run_angle = 0;
      for (int i = 0, j = a; i < len; ++i, j = (j + 1) % m) {
        auto& t = mesh.faces[S[j]];
        int k = t[0] == v ? 0 : t[1] == v ? 1 : 2;
        run_angle += angle3(mesh.vertices[v], mesh.vertices[t[(k + 1) % 3]], mesh.vertices[t[(k + 2) % 3]]);
      }
      auto outer_vertex = [&](int f, int neighbour) {  // vertex u of f with edge (v,u) not shared with neighbour
        auto& t = mesh.faces[f];
        for (int k = 0; k < 3; ++k)
          if (t[k] != v && !contains(neighbour, t[k])) return t[k];
        return -1;
      };
      int ua = outer_vertex(fa, S[(a + 1) % m]), ub = outer_vertex(fb, S[(b + m - 1) % m]);
      if (ua < 0 || ub < 0) continue;
      double theta = run_angle - angle3(mesh.vertices[v], qin, mesh.vertices[ua]) - angle3(mesh.vertices[v], qout, mesh.vertices[ub]);
      double other = total_angle(v) - theta;
      if (!(other < M_PI - 1e-9)) continue;
      auto run = other_fan(v, fa, fb, S[(a + 1) % m]);
      if (run.size() < 2) continue;
      cands.push_back({other, a, len, run});
    }
    std::stable_sort(cands.begin(), cands.end(), [](const Cand& x, const Cand& y) { return x.other < y.other; });
    std::vector<char> used(m, 0);
    std::vector<int> start_of(m, -1);
    int chosen = 0, first_end = -1;
    for (size_t ci = 0; ci < cands.size(); ++ci) {
      auto& c = cands[ci];
      if (chosen >= limit) break;
      bool free = true;
      for (int i = -1; i <= c.len && free; ++i) free = !used[(c.a + i + m) % m];
      if (!free) continue;
      for (int i = -1; i <= c.len; ++i) used[(c.a + i + m) % m] = 1;
      start_of[c.a] = int(ci);
      if (first_end < 0) first_end = (c.a + c.len) % m;
      ++chosen;
    }
    if (!chosen) return 0;
    std::vector<int> NS;
    std::vector<double> Ns;
    for (int i = 0; i < m;) {
      int j = (first_end + i) % m;
      if (start_of[j] >= 0) {
        auto& c = cands[start_of[j]];
        for (size_t k = 0; k < c.run.size(); ++k) NS.push_back(c.run[k]), Ns.push_back(0.5);
        Ns.back() = s[(c.a + c.len - 1) % m];  // portal after fb is the old portal b
        i += c.len;
      } else {
        NS.push_back(S[j]), Ns.push_back(s[j]);
        ++i;
      }
    }
    if (!portals_ok(NS)) return 0;
    S.swap(NS);
    s.swap(Ns);
    cut = 0;  // old portal first_end, crossing known
    return chosen;
  }
};

}  // namespace

ShortenResult shorten_loop(const SurfaceMesh& mesh, const MeshAdjacency& adj, const std::vector<int>& loop,
                           const ShortenOptions& opt) {
  ShortenResult R;
  if (loop.empty()) throw Error("loop is empty");
  for (size_t i = 0; i < loop.size(); ++i) {
    int a = loop[i], b = loop[(i + 1) % loop.size()];
    if (a < 0 || b < 0 || size_t(a) >= mesh.vertices.size() || size_t(b) >= mesh.vertices.size())
      throw Error("loop vertex index out of range");
    if (loop.size() > 1 && !adj.has_edge(a, b)) throw Error("loop vertices are not joined by a mesh edge");
  }
  R.edge_path = loop;
  R.points = loop_points(mesh, loop);
  R.input_length = R.edge_path_length = R.length = closed_length(R.points);
  if (loop.size() < 3) return R;

  // Rings (BFS hops) and surface distance (Dijkstra along edges) from the loop, both bounded; all per-vertex
  // data lives on this region so that the cost follows the band, not the mesh.
  const int max_rings = std::max(1, opt.max_rings);
  std::unordered_map<int, int> rid;
  std::vector<int> region, ring;
  for (int v : loop)
    if (rid.emplace(v, int(region.size())).second) region.push_back(v), ring.push_back(0);
  for (size_t i = 0; i < region.size(); ++i) {
    int v = region[i];
    if (ring[i] >= max_rings) continue;
    for (int j = adj.vv_start[v]; j < adj.vv_start[v + 1]; ++j) {
      int w = adj.vv[j];
      if (rid.emplace(w, int(region.size())).second) region.push_back(w), ring.push_back(ring[i] + 1);
    }
  }
  std::vector<double> dist;
  if (opt.max_move > 0) {
    dist.assign(region.size(), std::numeric_limits<double>::infinity());
    using QE = std::pair<double, int>;
    std::priority_queue<QE, std::vector<QE>, std::greater<QE>> q;
    for (int v : loop) dist[rid[v]] = 0, q.push({0, rid[v]});
    while (!q.empty()) {
      auto [d, i] = q.top();
      q.pop();
      if (d > dist[i] || d > opt.max_move) continue;
      int v = region[i];
      for (int j = adj.vv_start[v]; j < adj.vv_start[v + 1]; ++j) {
        auto it = rid.find(adj.vv[j]);
        if (it == rid.end()) continue;
        double nd = d + dist3(mesh.vertices[v], mesh.vertices[adj.vv[j]]);
        if (nd < dist[it->second]) dist[it->second] = nd, q.push({nd, it->second});
      }
    }
  }
  std::vector<char> near_loop(region.size(), 0);
  for (size_t i = 0; i < region.size(); ++i)
    if (ring[i] <= 1) near_loop[i] = ring[i] == 0 ? 2 : 1;

  Shortener sh(mesh, adj);
  auto try_rings = [&](int k) {
    std::vector<char> allowed(region.size(), 0);
    for (size_t i = 0; i < region.size(); ++i)
      if (ring[i] <= k && (dist.empty() || dist[i] <= opt.max_move)) allowed[i] = 1;
    return sh.build_band(region, rid, allowed, near_loop, loop);
  };
  // The widest annulus band: max_rings, else halve until one works, then bisect between that and the
  // last failure (wider bands stop being annuli when they wrap around or swallow a handle).
  int rings = 0;
  if (try_rings(max_rings)) {
    rings = max_rings;
  } else {
    int bad = max_rings, good = 0;
    for (int k = max_rings / 2; k >= 1; k /= 2) {
      if (try_rings(k)) { good = k; break; }
      bad = k;
    }
    if (good) {
      while (bad - good > 1) {
        int mid = (good + bad) / 2;
        if (try_rings(mid)) good = mid; else bad = mid;
      }
      if (!try_rings(good)) good = 0;  // leave the band of `good` rings built
    }
    rings = good;
  }
  R.rings = rings;
  if (!rings) return R;

  // Step 2.
  sh.build_arcs();
  // Every loop of the class crosses the cut, so loops through vertices sampled along the cut (which runs
  // across the band) find the best place in the band; then loops through the midpoint of the best one.
  std::vector<int> best;
  double best_len = std::numeric_limits<double>::infinity();
  int s = sh.local_of(loop[0]);
  {
    std::vector<int> starts{s};
    const auto& cv = sh.band.cut_vertices;
    const int samples = 16;
    for (int i = 0; i < samples && !cv.empty(); ++i) starts.push_back(cv[size_t(i) * cv.size() / samples]);
    std::sort(starts.begin() + 1, starts.end());
    starts.erase(std::unique(starts.begin() + 1, starts.end()), starts.end());
    // The searches are independent (they only read the band): run them in parallel, then pick in the
    // sequential order, so the choice does not depend on the thread count.
    std::vector<std::vector<int>> paths(starts.size());
    std::vector<double> lengths(starts.size(), std::numeric_limits<double>::infinity());
    tbb::parallel_for(std::size_t(0), starts.size(), [&](std::size_t i) {
      if (starts[i] >= 0) paths[i] = sh.shortest_loop_through(starts[i], lengths[i]);
    });
    for (std::size_t i = 0; i < starts.size(); ++i)
      if (!paths[i].empty() && lengths[i] < best_len - 1e-12) best = paths[i], best_len = lengths[i], s = starts[i];
    if (!best.empty()) {
      double acc = 0;
      for (size_t i = 0; i + 1 < best.size(); ++i) {
        acc += dist3(mesh.vertices[best[i]], mesh.vertices[best[i + 1]]);
        if (acc >= best_len / 2) { s = sh.local_of(best[i + 1]); break; }
      }
    }
  }
  for (int it = 0; it < 16 && s >= 0; ++it) {
    double L;
    auto P = sh.shortest_loop_through(s, L);
    if (P.empty() || !(L < best_len - 1e-12)) break;
    best = P, best_len = L;
    double acc = 0;  // next start: the vertex at half the length
    int mid = best[0];
    for (size_t i = 0; i + 1 < best.size(); ++i) {
      acc += dist3(mesh.vertices[best[i]], mesh.vertices[best[i + 1]]);
      if (acc >= best_len / 2) { mid = best[i + 1]; break; }
    }
    s = sh.local_of(mid);
  }
  if (best.empty()) return R;
  R.edge_path = best;
  R.edge_path_length = best_len;
  R.points = loop_points(mesh, best);
  R.length = closed_length(R.points);

  // Step 3.
  std::vector<int> S;
  if (!sh.strip_from_edge_loop(best, S)) {
    if (std::getenv("CHOKELOOPS_DEBUG_SHORTEN")) std::fprintf(stderr, "no triangle strip around the edge loop\n");
    return R;
  }
  std::vector<double> sp(S.size(), 0.5);
  std::vector<Shortener::Apex> apexes;
  int cut = 0;
  double L = sh.relax(S, cut, sp, apexes);
  int flat_rounds = 0;
  for (int it = 0; it < 400 && R.swaps < opt.max_swaps; ++it) {
    std::vector<int> S2 = S;
    std::vector<double> s2 = sp;
    int c2 = 0;
    int n = sh.swap_batch(S2, s2, apexes, c2, 1 << 30);
    if (!n) break;
    std::vector<Shortener::Apex> ap2;
    double L2 = sh.relax(S2, c2, s2, ap2);
    if (!(L2 < L - 1e-12 * L) && n > 1) {  // the batch did not help: the single best swap alone
      S2 = S, s2 = sp, c2 = 0;
      n = sh.swap_batch(S2, s2, apexes, c2, 1);
      L2 = sh.relax(S2, c2, s2, ap2);
    }
    if (std::getenv("CHOKELOOPS_DEBUG_SHORTEN"))
      std::fprintf(stderr, "swap round %d: %d swaps, %.9f -> %.9f (strip %zu)\n", it, n, L, L2, S2.size());
    if (!(L2 < L + 1e-9 * L)) break;  // a swap below pi shortens; allow relaxation noise only
    if (!(L2 < L - 1e-12 * L) && ++flat_rounds > 3) break;
    S.swap(S2), sp.swap(s2), apexes.swap(ap2), L = std::min(L, L2);
    R.swaps += n;
  }
  sh.polish(S, sp, 200);
  auto pts = sh.strip_points(S, sp);
  double Lp = closed_length(pts);
  if (std::getenv("CHOKELOOPS_DEBUG_SHORTEN"))
    std::fprintf(stderr, "edge loop %.9f (%zu vertices), strip %zu faces, relaxed %.9f, polished %.9f\n", R.length,
                 best.size(), S.size(), L, Lp);
  if (pts.size() >= 3 && Lp <= R.length) {
    R.points = pts;
    R.length = Lp;
    R.strip_faces = S;
  }
  return R;
}

ShortenResult shorten_loop(const SurfaceMesh& mesh, const std::vector<int>& loop, const ShortenOptions& options) {
  auto adj = build_adjacency(mesh);
  return shorten_loop(mesh, adj, loop, options);
}

ShortenResult shorten_polyline(const SurfaceMesh& mesh, const MeshAdjacency& adj, const Polyline3& polyline,
                               const ShortenOptions& options) {
  auto loop = snap_polyline_to_edge_path(mesh, adj, polyline);
  return shorten_loop(mesh, adj, loop, options);
}

}  // namespace chokeloops

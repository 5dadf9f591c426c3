// thinned_pinch_voxels: a pair removed by simple-point flips plus one pinch (membrane_voxels.h).
//
// Why. A disc across a handle (or a tunnel) is the smallest edit, but on rough fields the disc can join two
// components, open a cavity or not close at all, because what lies around the choke is tangled with other
// pieces. A simple point's flip changes neither side's topology (its link on each side is a disc), so a
// set of simple flips followed by one flip whose link on its side is two discs (and an annulus on the
// other) changes the topology in exactly one way: that side loses a handle, or splits in two if its two
// pieces do not meet elsewhere. The thinning therefore cannot join components or open cavities.
#include <algorithm>
#include <array>
#include <cmath>
#include <queue>
#include <utility>
#include <vector>

#include "chokeloops/loops/membrane_voxels.h"
#include "topology/link_table.h"

namespace chokeloops {

namespace {

// The components of a vertex's link on each side, from the table the persistence engine classifies by.
const detail::LinkComponents& pieces(std::uint16_t on) { return detail::link_component_table()[on]; }
constexpr std::uint16_t kWholeLink = 0x3fff;

// How many vertices a search for where a pinch's two pieces meet may visit (a handle of the whole brain's size
// is a few million vertices around).
constexpr std::size_t kMeetBudget = std::size_t(1) << 23;

struct Thinning {
  const ScalarGrid& grid;
  const FreudenthalComplex cx;
  std::array<int, 3> lo{}, n{};
  std::vector<std::uint8_t> flip;  // per box vertex: 1 flipped

  Thinning(const ScalarGrid& g, const std::array<int, 3>& centre, int reach) : grid(g), cx(g.dims) {
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::max(0, centre[a] - reach);
      n[a] = std::min(g.dims[a] - 1, centre[a] + reach) - lo[a] + 1;
    }
    flip.assign(std::size_t(n[0]) * n[1] * n[2], 0);
  }
  // The box index of v, or -1 outside the box.
  std::int64_t local(Id v) const {
    const auto p = cx.coords(v);
    for (int a = 0; a < 3; ++a)
      if (p[a] < lo[a] || p[a] >= lo[a] + n[a]) return -1;
    return std::int64_t(p[0] - lo[0]) + std::int64_t(n[0]) * (std::int64_t(p[1] - lo[1]) + std::int64_t(n[1]) * (p[2] - lo[2]));
  }
  bool flipped(Id v) const {
    const std::int64_t l = local(v);
    return l >= 0 && flip[std::size_t(l)];
  }
  void set(Id v, bool on) { flip[std::size_t(local(v))] = on; }
  bool inside_now(Id v) const { return (grid.values[std::size_t(v)] <= 0) != flipped(v); }
  // The link neighbours on v's side now (v is at least a voxel from the grid's sides).
  std::uint16_t same_side_link(Id v) const {
    const bool side = inside_now(v);
    std::uint16_t on = 0;
    for (int k = 0; k < 14; ++k)
      if (inside_now(v + cx.neighbor_delta(k)) == side) on |= std::uint16_t(1u << k);
    return on;
  }
  // Its flip changes neither side's topology: its link on each side is one disc.
  static bool simple(std::uint16_t on) { return pieces(on).count == 1 && pieces(std::uint16_t(~on & kWholeLink)).count == 1; }
  // Its flip lowers its side's genus or splits the side: two discs on its side, an annulus on the other.
  static bool pinch(std::uint16_t on) { return pieces(on).count == 2 && pieces(std::uint16_t(~on & kWholeLink)).count == 1; }
  // Whether the two pieces of v's link on its side meet without v anywhere in the grid: a search from each
  // piece in turn, so that a small piece (a speck that would break off) is settled in its own time. Gives up
  // (false) after `budget` vertices. The marks are a byte per grid vertex, made at the first search and
  // cleared after each from its queues (a hash set of millions of vertices took 40 bytes each).
  bool pieces_meet(Id v, std::uint16_t on, std::size_t budget) {
    const auto& piece = pieces(on).masks;
    const bool side = inside_now(v);
    if (meet_mark.empty()) meet_mark.assign(std::size_t(cx.vertex_count()), 0);
    std::array<std::vector<Id>, 2> queue;
    std::array<std::size_t, 2> head{0, 0};
    const bool met = [&] {
      meet_mark[std::size_t(v)] = 3;  // 1, 2: reached from that piece; 3: v
      for (int k = 0; k < 14; ++k) {
        if (!(on >> k & 1)) continue;
        const int which = piece[0] >> k & 1 ? 0 : 1;
        const Id u = v + cx.neighbor_delta(k);
        std::uint8_t& m = meet_mark[std::size_t(u)];
        const std::uint8_t from = std::uint8_t(which + 1);
        if (m && m != from) return true;
        if (!m) m = from, queue[std::size_t(which)].push_back(u);
      }
      for (int turn = 0; queue[0].size() + queue[1].size() < budget; turn ^= 1) {
        const std::size_t s = std::size_t(turn);
        if (head[s] == queue[s].size()) return false;  // this piece's part of the side ends here: they do not meet
        const Id w = queue[s][head[s]++];
        const auto p = cx.coords(w);
        for (int k = 0; k < 14; ++k) {
          if (!cx.neighbor_inside(p, k)) continue;
          const Id u = w + cx.neighbor_delta(k);
          std::uint8_t& m = meet_mark[std::size_t(u)];
          if (m == 3 || m == turn + 1) continue;
          if (m) return true;
          if (inside_now(u) != side) continue;
          m = std::uint8_t(turn + 1);
          queue[s].push_back(u);
        }
      }
      return false;
    }();
    meet_mark[std::size_t(v)] = 0;
    for (const auto& q : queue)
      for (Id u : q) meet_mark[std::size_t(u)] = 0;
    return met;
  }
  std::vector<std::uint8_t> meet_mark;
};

}  // namespace

MembraneVoxels thinned_pinch_voxels(const ScalarGrid& grid, const Choke& c, const std::function<bool(Id)>& can_change) {
  MembraneVoxels out;
  const FreudenthalComplex cx(grid.dims);
  const bool inside = c.side == Side::Handle;
  const double h = grid.voxel_size;
  const float limit = float(c.depth + 0.5 * h);
  const auto sc = cx.coords(c.saddle);
  // A handle that is a ribbon wider than the ball thins to a sheet held by the ball's side, with no pinch: the
  // ball grows until it takes in the ribbon's edges, from which the sheet then thins to a wire. A tunnel whose
  // narrowest place lies between two components has pinches only further along its channel (the grey-matter
  // map's last pairs needed a box of 64).
  const int first_reach = int(std::ceil(c.depth / h)) + 1;
  const int max_reach = std::max(64, 4 * first_reach);
  if ((grid.values[std::size_t(c.saddle)] <= 0) != inside) {
    out.note = "its saddle is no longer on its side";
    return out;
  }
  Thinning t(grid, sc, max_reach + 1);
  Id pinch = -1;
  std::vector<Id> order;  // the flips, in the order made
  for (int reach = first_reach;; reach = std::min(max_reach, 2 * reach)) {
    std::fill(t.flip.begin(), t.flip.end(), 0);
    order.clear();
    auto in_ball = [&](Id v) {
      const auto p = cx.coords(v);
      for (int a = 0; a < 3; ++a)
        if (std::abs(p[a] - sc[a]) > reach || p[a] < 1 || p[a] > grid.dims[a] - 2) return false;
      return true;
    };
    // Only the piece of the side around the saddle within the ball: a flip in another piece (a cavity next to a
    // tunnel, another component next to a handle) would change nothing, and would tie that piece to the edit.
    std::vector<std::uint8_t> piece_of_saddle(t.flip.size(), 0);
    {
      std::vector<Id> stack{c.saddle};
      piece_of_saddle[std::size_t(t.local(c.saddle))] = 1;
      while (!stack.empty()) {
        const Id v = stack.back();
        stack.pop_back();
        const auto p = cx.coords(v);
        for (int k = 0; k < 14; ++k) {
          if (!cx.neighbor_inside(p, k)) continue;
          const Id u = v + cx.neighbor_delta(k);
          if (!in_ball(u) || (grid.values[std::size_t(u)] <= 0) != inside) continue;
          std::uint8_t& m = piece_of_saddle[std::size_t(t.local(u))];
          if (!m) m = 1, stack.push_back(u);
        }
      }
    }
    auto candidate = [&](Id v) {
      if (!in_ball(v) || !piece_of_saddle[std::size_t(t.local(v))]) return false;
      const float f = grid.values[std::size_t(v)];
      return std::abs(f) <= limit && (!can_change || can_change(v));
    };
    using Entry = std::pair<float, Id>;  // |f|, then the id: the same order on every run
    std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> queue;
    auto push_candidates_around = [&](Id v) {
      const auto p = cx.coords(v);
      for (int k = 0; k < 14; ++k) {
        if (!cx.neighbor_inside(p, k)) continue;
        const Id u = v + cx.neighbor_delta(k);
        if (!t.flipped(u) && candidate(u)) queue.push({std::abs(grid.values[std::size_t(u)]), u});
      }
    };
    // Start from the generator's side where it meets the other side, nearest the surface first.
    for (int dz = -reach; dz <= reach; ++dz)
      for (int dy = -reach; dy <= reach; ++dy)
        for (int dx = -reach; dx <= reach; ++dx) {
          if (!cx.inside(sc[0] + dx, sc[1] + dy, sc[2] + dz)) continue;
          const Id v = cx.vertex(sc[0] + dx, sc[1] + dy, sc[2] + dz);
          if (candidate(v) && t.same_side_link(v) != kWholeLink) queue.push({std::abs(grid.values[std::size_t(v)]), v});
        }
    while (!queue.empty() && pinch < 0) {
      const Id v = queue.top().second;
      queue.pop();
      if (t.flipped(v)) continue;
      const std::uint16_t on = t.same_side_link(v);
      if (Thinning::simple(on)) {
        t.set(v, true);
        order.push_back(v);
        push_candidates_around(v);
        continue;
      }
      if (Thinning::pinch(on) && t.pieces_meet(v, on, kMeetBudget)) pinch = v;  // else it would split the side
    }
    if (pinch >= 0 || reach == max_reach) break;
  }
  if (pinch < 0) {
    out.note = "thinning the " + std::string(inside ? "solid" : "outside") + " near the saddle met no pinch";
    return out;
  }
  // Only what the pinch needs: every flip that can be taken back without changing the topology of the field
  // with the pinch flipped is taken back, deepest first; a flip not taken back is looked at again when a
  // neighbour's is.
  t.set(pinch, true);
  using Entry = std::pair<float, Id>;
  std::priority_queue<Entry> regrow;  // deepest first, then the larger id
  for (Id v : order) regrow.push({std::abs(grid.values[std::size_t(v)]), v});
  while (!regrow.empty()) {
    const Id v = regrow.top().second;
    regrow.pop();
    if (v == pinch || !t.flipped(v) || !Thinning::simple(t.same_side_link(v))) continue;
    t.set(v, false);
    const auto p = cx.coords(v);
    for (int k = 0; k < 14; ++k) {
      const Id u = v + cx.neighbor_delta(k);
      if (cx.neighbor_inside(p, k) && u != pinch && t.flipped(u)) regrow.push({std::abs(grid.values[std::size_t(u)]), u});
    }
  }
  for (Id v : order)
    if (t.flipped(v)) out.shore.push_back(v);
  out.shore.push_back(pinch);
  std::sort(out.shore.begin(), out.shore.end());
  out.shore.erase(std::unique(out.shore.begin(), out.shore.end()), out.shore.end());
  out.found = true;
  return out;
}

}  // namespace chokeloops

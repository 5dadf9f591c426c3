// The two-lobe priority flood (two_lobe_flood.h), shared by the loop tracer and the filter.
#include "two_lobe_flood.h"

#include <algorithm>
#include <cmath>

namespace chokeloops::detail {

namespace {

// The flood with one cell word of type Word a box vertex: 16 bits when the levels fit (most floods), else 32.
// The flood is bound by the reads of its cells, so a narrower word is a smaller working set.
template <class Word>
FloodOutcome flood_with(const ScalarGrid& grid, const FreudenthalComplex& cx, const Choke& c, const BoxExtent& extent,
                        int seed_radius, bool by_distance, FloodBox& box, std::vector<Word>& cell, const RegionBounds* bounds) {
  const float* f = grid.values.data();
  const bool handle = c.side == Side::Handle;
  const Id s = c.saddle;
  // "Below" = earlier in the flood's order: the filtration for handles, its reverse for tunnels.
  auto below = [&](Id v) { return handle ? vertex_less(f, v, s) : vertex_less(f, s, v); };
  auto sc = cx.coords(s);
  auto& lo = box.lo;
  auto& hi = box.hi;
  auto& n = box.n;
  flood_box_range(extent, sc, grid.dims, bounds, lo, hi);
  for (int a = 0; a < 3; ++a) {
    if (hi[a] < lo[a]) return FloodOutcome::Grow;  // the saddle's region is empty here: no lobe to flood
    n[a] = hi[a] - lo[a] + 1;
  }
  const Id base = box.base = cx.vertex(lo[0], lo[1], lo[2]);
  const Id gy = box.gy = grid.dims[0], gz = box.gz = Id(grid.dims[0]) * grid.dims[1];
  const std::size_t ly = box.ly = std::size_t(n[0]), lz = box.lz = std::size_t(n[0]) * n[1];
  struct Node { Id v; std::uint32_t li; std::array<int, 3> p; };  // p: local coordinates
  auto node_at = [&](const std::array<int, 3>& p) {
    return Node{base + p[0] + gy * p[1] + gz * p[2], std::uint32_t(p[0] + ly * p[1] + lz * p[2]), p};
  };
  std::array<std::array<int, 3>, 14> offsets;
  for (int k = 0; k < 14; ++k) offsets[k] = freudenthal::neighbor_offset(k);
  auto for_neighbours = [&](const Node& x, auto&& fn) {
    for (const auto& o : offsets) {
      std::array<int, 3> q{x.p[0] + o[0], x.p[1] + o[1], x.p[2] + o[2]};
      if (q[0] < 0 || q[1] < 0 || q[2] < 0 || q[0] >= n[0] || q[1] >= n[1] || q[2] >= n[2]) continue;
      fn(node_at(q));
    }
  };
  // One 32-bit word per box vertex, written once in memory order: its zone (bits 0-1: 0 not reached
  // yet, 1 or 2, kOutside beyond the region), a border bit, and its level in the flood (bits 3-31). The
  // flood is memory-bound (perf: the reads of a newly met neighbour's zone and value were two cache
  // misses, two thirds of its time); one word makes it one, and spares a scattered read of the grid.
  constexpr std::uint32_t kZone = FloodBox::kZone, kOutside = FloodBox::kOutside, kBorder = FloodBox::kBorder;
  constexpr int kLevelShift = FloodBox::kLevelShift;
  const double level = grid.voxel_size / FloodBox::kLevelsPerVoxel;
  const double fs = f[s];
  // Flood levels (a bucket queue), quantised to 1/64 voxel; 0 for everything on the seeds' side of the saddle.
  auto bucket_of = [&](float value) {
    double d = handle ? (double(value) - fs) : (fs - double(value));  // grows from the saddle toward the surface
    return d <= 0 ? std::size_t(0) : std::size_t(d / level) + 1;
  };
  const std::size_t last_bucket = bucket_of(0.0f) + 1;
  if (last_bucket >= (std::size_t(1) << (8 * sizeof(Word) - kLevelShift)))
    throw Error("membrane flood: choke too deep for the level queue");
  cell.resize(lz * n[2]);
  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j) {
      const float* row = f + base + gy * j + gz * k;
      Word* out = cell.data() + ly * std::size_t(j) + lz * std::size_t(k);
      const bool border_row = k == 0 || j == 0 || k == n[2] - 1 || j == n[1] - 1;
      for (int i = 0; i < n[0]; ++i) {
        const bool inside = handle ? row[i] <= 0 : row[i] > 0;
        std::uint32_t w = inside ? std::uint32_t(std::min(last_bucket, bucket_of(row[i]))) << kLevelShift : kOutside;
        if (border_row || i == 0 || i == n[0] - 1) w |= kBorder;
        out[i] = Word(w);
      }
    }
  auto zone = [&](std::uint32_t li) { return cell[li] & kZone; };
  auto set_zone = [&](std::uint32_t li, std::uint32_t z) { cell[li] = Word((cell[li] & ~kZone) | z); };

  // Seeds: the two pieces of {below the saddle} that hold the lobes, found in a seed box of about the
  // choke's depth; around a handle they join farther away, which the flood below must not see.
  const int seed_r = std::min(extent.smallest(), seed_radius);
  auto in_seed_box = [&](const std::array<int, 3>& p) {
    for (int a = 0; a < 3; ++a)
      if (std::abs(lo[a] + p[a] - sc[a]) > seed_r) return false;
    return true;
  };
  std::vector<Node> seeds;
  box.seed_centroid = {};
  box.seed_count = {0, 0};
  for (int side = 0; side < 2; ++side) {
    std::vector<Node> stack;
    Id lobe = c.lobes[side];
    if (lobe == -2) {  // the lobe is the outside of the grid: every border vertex of the box beyond the saddle
      for (int k = 0; k < n[2]; ++k)
        for (int j = 0; j < n[1]; ++j)
          for (int i = 0; i < n[0]; ++i) {
            std::array<int, 3> gpos{lo[0] + i, lo[1] + j, lo[2] + k};
            bool border = false;
            for (int a = 0; a < 3; ++a) border |= gpos[a] == 0 || gpos[a] == grid.dims[a] - 1;
            Node x = node_at({i, j, k});
            if (border && below(x.v)) stack.push_back(x);
          }
    } else if (lobe >= 0 && below(lobe)) {
      auto gp = cx.coords(lobe);
      std::array<int, 3> p{gp[0] - lo[0], gp[1] - lo[1], gp[2] - lo[2]};
      if (p[0] >= 0 && p[1] >= 0 && p[2] >= 0 && p[0] < n[0] && p[1] < n[1] && p[2] < n[2]) stack.push_back(node_at(p));
    }
    if (stack.empty()) return FloodOutcome::Grow;
    for (const Node& x : stack) {
      if (zone(x.li) == std::uint32_t(2 - side)) return FloodOutcome::Shrink;
      set_zone(x.li, std::uint32_t(side + 1));
    }
    while (!stack.empty()) {
      Node x = stack.back();
      stack.pop_back();
      seeds.push_back(x);
      for (int a = 0; a < 3; ++a) box.seed_centroid[side][a] += lo[a] + x.p[a];
      box.seed_count[side] += 1;
      bool joined = false;
      for_neighbours(x, [&](const Node& u) {
        if (!below(u.v) || !in_seed_box(u.p)) return;
        const std::uint32_t l = zone(u.li);
        if (l == 0) { set_zone(u.li, std::uint32_t(side + 1)); stack.push_back(u); }
        else if (l != std::uint32_t(side + 1)) joined = true;
      });
      if (joined) return FloodOutcome::Shrink;
    }
  }

  // Priority flood through the solid (the outside, for tunnels) in filtration order, by the levels above
  // (O(1) per vertex; first in, first out within a level, so the result is deterministic); remember the
  // labelled vertices next to the surface.
  // The queue holds local indices only (4 bytes, not a 24-byte Node): a big box queues millions.
  auto node_of = [&](std::uint32_t li) {
    const int k = int(li / lz), rest = int(li % lz);
    return node_at({rest % n[0], rest / n[0], k});
  };
  // The level queue's buckets are the thread's, kept between floods with their storage (a small box's flood
  // fills a few hundred buckets of a few dozen vertices each, and growing each from nothing cost a third of its
  // time): an emptied bucket keeps its storage when it is small and the kept ones hold at most kKeptEntries
  // in all, else it is freed, so that a big flood's memory goes as it empties, as it did when none was kept.
  constexpr std::size_t kKeptEntries = std::size_t(1) << 20, kKeptPerBucket = std::size_t(1) << 12;
  std::size_t retained = 0;
  static thread_local std::vector<std::vector<std::uint32_t>> buckets;
  std::size_t used = last_bucket + 1;  // buckets 0 .. used - 1 are this flood's
  if (buckets.size() < used) buckets.resize(used);
  for (std::size_t b = 0; b < used; ++b) buckets[b].clear();
  for (const Node& x : seeds) buckets[0].push_back(x.li);
  // Vertices off the box's border visit their 14 neighbours by fixed local offsets, without decoding
  // coordinates or checking bounds; the border bit sends the others down the checked path. Same
  // neighbour order either way: same labels.
  std::array<std::int64_t, 14> local_delta;
  for (int k = 0; k < 14; ++k)
    local_delta[k] = offsets[k][0] + std::int64_t(ly) * offsets[k][1] + std::int64_t(lz) * offsets[k][2];
  // Only the shore where the two zones meet can hold interface segments: a surface face whose corners
  // carry both labels lies in one tetrahedron, whose labelled corners are pairwise neighbours of both
  // zones. So the zones' contact is marked during the flood (whichever of two touching vertices is
  // reached second sees the other), and only that part of the shore is labelled below: on a big box
  // it is a thin sheet, where the whole shore is millions of vertices.
  // The byte offsets, from a vertex's cell, of the rows its neighbours lie in (each row's -1..+1 share a line
  // or two): the rows j and j+-1 of the planes k and k+-1 that the 14 slots reach.
  constexpr std::size_t kPrefetchAhead = 8;
  std::array<std::int64_t, 7> prefetch_rows;
  {
    int m = 0;
    for (int dk = -1; dk <= 1; ++dk)
      for (int dj = -1; dj <= 1; ++dj) {
        bool reached = false;
        for (const auto& o : offsets) reached |= o[1] == dj && o[2] == dk;
        if (reached && m < 7) prefetch_rows[std::size_t(m++)] = (std::int64_t(ly) * dj + std::int64_t(lz) * dk) * std::int64_t(sizeof(Word));
      }
    for (; m < 7; ++m) prefetch_rows[std::size_t(m)] = 0;
  }
  static thread_local std::vector<std::uint8_t> contact;
  contact.assign(cell.size(), 0);
  box.contact = &contact;
  std::vector<std::uint32_t> shore_local;
  // The loop reads the cells, the contact marks and the buckets through plain pointers: through the vectors
  // (a reference and thread_locals) every read went back for their data pointers, the stores between them
  // might have moved.
  Word* const cells = cell.data();
  std::uint8_t* const touching = contact.data();
  std::vector<std::uint32_t>* bucket = buckets.data();  // again after the by-distance flood adds a bucket
  for (std::size_t b = 0; b < used; ++b) {
    for (std::size_t q = 0; q < bucket[b].size(); ++q) {
      // The flood waits on its cells' cache misses (perf: half its time on one load): ask for the cells
      // around a vertex a few places ahead in the queue (its neighbours' rows) while this one is visited.
      if (q + kPrefetchAhead < bucket[b].size()) {
        const std::uintptr_t ahead = reinterpret_cast<std::uintptr_t>(cells + bucket[b][q + kPrefetchAhead]);
        for (std::int64_t row : prefetch_rows) __builtin_prefetch(reinterpret_cast<const void*>(ahead + std::uintptr_t(row)));
      }
      const std::uint32_t xl = bucket[b][q];
      const std::uint32_t lx = cells[xl] & kZone;
      bool at_shore = false;
      auto visit = [&](std::uint32_t ul) {
        Word& w = cells[ul];
        const std::uint32_t lu = w & kZone;
        if (lu == kOutside) { at_shore = true; return; }
        if (lu != 0 && lu != lx) { touching[xl] = touching[ul] = 1; return; }
        if (lu == 0) {
          w = Word(w | lx);
          if (!by_distance) {
            bucket[std::max(b, std::size_t(w >> kLevelShift))].push_back(ul);
          } else {
            if (b + 1 == used) {
              if (used == buckets.size()) buckets.emplace_back(), bucket = buckets.data();
              bucket[used++].clear();
            }
            bucket[b + 1].push_back(ul);
          }
        }
      };
      if (cells[xl] & kBorder) {
        for_neighbours(node_of(xl), [&](const Node& u) { visit(u.li); });
      } else {
        for (int k = 0; k < 14; ++k) visit(std::uint32_t(std::int64_t(xl) + local_delta[k]));
      }
      if (at_shore) shore_local.push_back(xl);
    }
    const std::size_t capacity = buckets[b].capacity();
    if (capacity <= kKeptPerBucket && retained + capacity <= kKeptEntries) {
      retained += capacity;
      buckets[b].clear();
    } else {
      std::vector<std::uint32_t>().swap(buckets[b]);
    }
  }
  {
    std::size_t kept = 0;
    for (const auto& stored : buckets) kept += stored.capacity();
    for (std::size_t b = buckets.size(); b-- > 0 && kept > kKeptEntries;) {
      kept -= buckets[b].capacity();
      std::vector<std::uint32_t>().swap(buckets[b]);
    }
  }
  for (int side = 0; side < 2; ++side)
    for (int a = 0; a < 3; ++a) box.seed_centroid[side][a] /= double(std::max<std::size_t>(1, box.seed_count[side]));
  box.shore.clear();
  for (std::uint32_t xl : shore_local)
    if (contact[xl]) box.shore.push_back(xl);
  return FloodOutcome::Flooded;
}

}  // namespace

FloodOutcome flood_two_lobes(const ScalarGrid& grid, const FreudenthalComplex& cx, const Choke& c, int r, int seed_radius,
                             bool by_distance, FloodBox& box, const RegionBounds* bounds) {
  return flood_two_lobes(grid, cx, c, BoxExtent::cube(r), seed_radius, by_distance, box, bounds);
}

FloodOutcome flood_two_lobes(const ScalarGrid& grid, const FreudenthalComplex& cx, const Choke& c, const BoxExtent& extent,
                             int seed_radius, bool by_distance, FloodBox& box, const RegionBounds* bounds) {
  // The levels from the saddle's value to the surface's (flood_with), and 0 and one past the last.
  const double levels =
      std::abs(double(grid.values[std::size_t(c.saddle)])) / (grid.voxel_size / FloodBox::kLevelsPerVoxel) + 3;
  // Reused by the thread's next flood: a big box is tens of megabytes, and fresh pages cost a fault each.
  static thread_local std::vector<std::uint16_t> cell16;
  static thread_local std::vector<std::uint32_t> cell32;
  if (levels < double(std::size_t(1) << (16 - FloodBox::kLevelShift))) {
    box.cell16 = &cell16, box.cell = nullptr;
    return flood_with(grid, cx, c, extent, seed_radius, by_distance, box, cell16, bounds);
  }
  box.cell = &cell32, box.cell16 = nullptr;
  return flood_with(grid, cx, c, extent, seed_radius, by_distance, box, cell32, bounds);
}

bool box_covers(const BoxExtent& extent, const std::array<int, 3>& saddle, const RegionBounds& bounds) {
  for (int a = 0; a < 3; ++a)
    if (saddle[a] - extent.below[a] > bounds.lo[a] || saddle[a] + extent.above[a] < bounds.hi[a]) return false;
  return true;
}

void grow_box(BoxExtent& extent, const std::array<char, 6>& open_sides, const std::array<int, 3>& saddle,
              const RegionBounds& bounds, int full) {
  auto radius = [&](int side) -> int& { return side < 3 ? extent.below[side] : extent.above[side - 3]; };
  auto can_grow = [&](int side) {
    const int a = side % 3;
    return side < 3 ? saddle[a] - extent.below[a] > bounds.lo[a] : saddle[a] + extent.above[a] < bounds.hi[a];
  };
  bool some = false;
  for (int side = 0; side < 6; ++side) some |= open_sides[std::size_t(side)] && can_grow(side);
  for (int side = 0; side < 6; ++side) {
    if (some && !(open_sides[std::size_t(side)] && can_grow(side))) continue;
    int& r = radius(side);
    r = std::min(full, int(std::ceil(r * 1.8)));
    if (2 * r >= full) r = full;
  }
}

void mark_open_sides(const ScalarGrid& grid, const SurfaceMesh& surface, const InterfaceSegments& segments,
                     const SegmentsAtEdge& at, const FloodBox& box, const std::array<double, 3>& point, double near,
                     std::array<char, 6>& open_sides) {
  std::vector<char> seen(segments.size(), 0);
  std::vector<int> stack;
  std::vector<std::int64_t> ends;
  for (int first = 0; first < int(segments.size()); ++first) {
    if (seen[std::size_t(first)]) continue;
    seen[std::size_t(first)] = 1;
    stack.assign(1, first);
    ends.clear();
    double d = 1e300;
    while (!stack.empty()) {
      const int s = stack.back();
      stack.pop_back();
      for (std::int64_t e : segments[std::size_t(s)]) {
        const auto p = edge_midpoint(surface, e);
        d = std::min(d, std::hypot(p[0] - point[0], p[1] - point[1], p[2] - point[2]));
        const auto& pair = at.at(e);
        if (pair[1] < 0) { ends.push_back(e); continue; }
        const int t = pair[0] == s ? pair[1] : pair[0];
        if (!seen[std::size_t(t)]) seen[std::size_t(t)] = 1, stack.push_back(t);
      }
    }
    if (d > near) continue;
    for (std::int64_t e : ends) {
      const auto p = edge_midpoint(surface, e);
      int nearest = 0;
      double best = 1e300;
      for (int a = 0; a < 3; ++a) {
        const double u = (p[a] - grid.origin[a]) / grid.h(a);
        const double below = u - box.lo[a], above = box.hi[a] - u;
        if (below < best) best = below, nearest = a;
        if (above < best) best = above, nearest = a + 3;
      }
      open_sides[std::size_t(nearest)] = 1;
    }
  }
}

}  // namespace chokeloops::detail

namespace chokeloops {

std::array<RegionBounds, 2> region_bounds(const ScalarGrid& grid) {
  const auto& d = grid.dims;
  std::array<RegionBounds, 2> out;
  for (auto& b : out) b.lo = {d[0], d[1], d[2]}, b.hi = {-1, -1, -1};
  for (int k = 0; k < d[2]; ++k)
    for (int j = 0; j < d[1]; ++j) {
      const float* row = grid.values.data() + grid.index(0, j, k);
      for (int i = 0; i < d[0]; ++i) {
        RegionBounds& b = out[row[i] <= 0 ? 0 : 1];
        const std::array<int, 3> p{i, j, k};
        for (int a = 0; a < 3; ++a) b.lo[a] = std::min(b.lo[a], p[a]), b.hi[a] = std::max(b.hi[a], p[a]);
      }
    }
  // Every Freudenthal neighbour is one step away on each axis.
  for (auto& b : out)
    for (int a = 0; a < 3; ++a)
      if (b.hi[a] >= 0) b.lo[a] = std::max(0, b.lo[a] - 1), b.hi[a] = std::min(d[a] - 1, b.hi[a] + 1);
  return out;
}

}  // namespace chokeloops

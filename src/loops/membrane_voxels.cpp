#include "chokeloops/loops/membrane_voxels.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>

#include "two_lobe_flood.h"

namespace chokeloops {

namespace {

// The contact vertex of the box nearest the saddle (the saddle itself when the zones meet there, as they
// usually do: it is where they first touch).
std::int64_t start_of_sheet(const detail::FloodBox& box, const std::array<int, 3>& saddle_local) {
  std::int64_t best = -1, best_d2 = 0;
  for (std::uint32_t li = 0; li < box.size(); ++li) {
    if (!box.in_contact(li)) continue;
    const auto p = box.local(li);
    std::int64_t d2 = 0;
    for (int a = 0; a < 3; ++a) d2 += std::int64_t(p[a] - saddle_local[a]) * (p[a] - saddle_local[a]);
    if (best < 0 || d2 < best_d2) best = li, best_d2 = d2;
  }
  return best;
}

// Calls fn(local index) for each of the 14 Freudenthal neighbours of box vertex p that lie in the box.
template <class Fn>
void for_box_neighbours(const detail::FloodBox& box, const std::array<int, 3>& p, Fn&& fn) {
  for (int k = 0; k < 14; ++k) {
    const auto o = freudenthal::neighbor_offset(k);
    const std::array<int, 3> u{p[0] + o[0], p[1] + o[1], p[2] + o[2]};
    if (u[0] < 0 || u[1] < 0 || u[2] < 0 || u[0] >= box.n[0] || u[1] >= box.n[1] || u[2] >= box.n[2]) continue;
    fn(std::uint32_t(u[0] + box.ly * u[1] + box.lz * u[2]));
  }
}

// Pieces of the region that hung on the shore only (a spur of a noisy surface, a pocket behind a fill)
// would become components or cavities of their own once it changes side: they change side with it. A piece
// is such when it lies inside the box without reaching its sides and holds neither seed piece.
// A piece's search stops as soon as the piece is known to stay (it holds a vertex of level 0, reaches the
// box's side, or meets a piece already known to stay, which is then the same piece): the two zones' bodies
// are most of a big box, and walking them whole for every membrane cost more than its flood. Pieces that
// go are walked whole, as before, and in the same order.
void add_debris(const detail::FloodBox& box, const ScalarGrid& grid, std::vector<std::uint32_t>& shore) {
  constexpr std::uint8_t kShore = 1, kSeen = 2, kStays = 3;
  static thread_local std::vector<std::uint8_t> mark;
  mark.assign(box.size(), 0);
  for (std::uint32_t li : shore) mark[li] = kShore;
  const std::size_t original = shore.size();
  std::vector<std::uint32_t> piece;
  for (std::size_t q = 0; q < original; ++q) {
    for_box_neighbours(box, box.local(shore[q]), [&](std::uint32_t start) {
      const std::uint32_t z = box.zone(start);
      if (mark[start] || (z != 1 && z != 2)) return;
      piece.assign(1, start);
      mark[start] = kSeen;
      bool keep = false;  // reaches the box's side inside the grid, or holds a seed (level 0 of the flood)
      for (std::size_t i = 0; i < piece.size() && !keep; ++i) {
        const std::uint32_t li = piece[i];
        if (box.level(li) == 0) keep = true;
        const auto p = box.local(li);
        for (int a = 0; a < 3; ++a) {
          const int g = box.lo[a] + p[a];
          if ((p[a] == 0 || p[a] == box.n[a] - 1) && g != 0 && g != grid.dims[a] - 1) keep = true;
        }
        for_box_neighbours(box, p, [&](std::uint32_t ul) {
          if (mark[ul] == kStays) keep = true;
          const std::uint32_t zu = box.zone(ul);
          if (mark[ul] || (zu != 1 && zu != 2)) return;
          mark[ul] = kSeen;
          piece.push_back(ul);
        });
      }
      if (keep) {
        for (std::uint32_t li : piece) mark[li] = kStays;
      } else {
        shore.insert(shore.end(), piece.begin(), piece.end());
      }
    });
  }
}

enum class Sheet { Closed, Open, AtGridBorder };

// The connected set of box vertices `member` accepts through `start` (14-neighbourhood); Open when it reaches
// the box's side inside the grid (the membrane goes on beyond the box).
template <class Member>
Sheet collect_sheet(const detail::FloodBox& box, const ScalarGrid& grid, std::uint32_t start, Member&& member,
                    std::vector<std::uint32_t>& sheet) {
  static thread_local std::vector<std::uint8_t> seen;
  seen.assign(box.size(), 0);
  sheet.assign(1, start);
  seen[start] = 1;
  Sheet result = Sheet::Closed;
  for (std::size_t q = 0; q < sheet.size(); ++q) {
    const std::uint32_t li = sheet[q];
    const auto p = box.local(li);
    if (box.on_border(li)) {
      for (int a = 0; a < 3; ++a) {
        const int g = box.lo[a] + p[a];
        const bool box_side = p[a] == 0 || p[a] == box.n[a] - 1;
        if (box_side && g != 0 && g != grid.dims[a] - 1) return Sheet::Open;
        if (box_side) result = Sheet::AtGridBorder;
      }
    }
    for_box_neighbours(box, p, [&](std::uint32_t ul) {
      if (seen[ul] || !member(ul)) return;
      seen[ul] = 1;
      sheet.push_back(ul);
    });
  }
  return result;
}

// The piece through the saddle of the slab {0 <= (x - saddle).n < W} within the region, n along the line
// between the seed pieces and W the largest step a Freudenthal edge makes along n: every path from one
// side of the slab to the other steps on it.
Sheet plane_piece(const detail::FloodBox& box, const ScalarGrid& grid, const std::array<int, 3>& sc, std::vector<Id>& out) {
  std::array<double, 3> n;
  double len = 0;
  for (int a = 0; a < 3; ++a) n[a] = box.seed_centroid[1][a] - box.seed_centroid[0][a], len += n[a] * n[a];
  len = std::sqrt(len);
  if (len == 0) n = {1, 0, 0};
  else for (double& x : n) x /= len;
  double W = 0;
  for (int k = 0; k < 7; ++k) {
    const auto o = freudenthal::neighbor_offset(k);
    W = std::max(W, std::abs(o[0] * n[0] + o[1] * n[1] + o[2] * n[2]));
  }
  const std::array<int, 3> s_local{sc[0] - box.lo[0], sc[1] - box.lo[1], sc[2] - box.lo[2]};
  auto member = [&](std::uint32_t li) {
    const std::uint32_t z = box.zone(li);
    if (z != 1 && z != 2) return false;  // outside the region (or not reached)
    const auto p = box.local(li);
    const double s = (p[0] - s_local[0]) * n[0] + (p[1] - s_local[1]) * n[1] + (p[2] - s_local[2]) * n[2];
    return s >= 0 && s < W;
  };
  const std::uint32_t start = std::uint32_t(s_local[0] + box.ly * s_local[1] + box.lz * s_local[2]);
  out.clear();
  if (!member(start)) return Sheet::Closed;
  std::vector<std::uint32_t> piece;
  const Sheet result = collect_sheet(box, grid, start, member, piece);
  if (result == Sheet::Closed) {
    add_debris(box, grid, piece);
    for (std::uint32_t li : piece) out.push_back(box.global(li));
  }
  std::sort(out.begin(), out.end());
  return result;
}

// Noise that hangs on a saddle's piece only is a few vertices.
constexpr std::size_t kSpeck = 8;

// The pieces of the piece's own side that hung on it only (a speck of noise, a pocket of a few voxels), at
// most `max_vertices` each: they would become components or cavities of their own once the piece changes side,
// so they change side with it. Appended to `piece`, which ends sorted.
void add_small_debris(const ScalarGrid& grid, const FreudenthalComplex& cx, std::vector<Id>& piece,
                      std::size_t max_vertices) {
  const bool inside = grid.values[std::size_t(piece.front())] <= 0;
  auto same_side = [&](Id u) { return (grid.values[std::size_t(u)] <= 0) == inside; };
  std::vector<Id> taken(piece.begin(), piece.end()), tried;
  std::sort(taken.begin(), taken.end());
  auto known = [](const std::vector<Id>& sorted, Id v) { return std::binary_search(sorted.begin(), sorted.end(), v); };
  const std::size_t original = piece.size();
  for (std::size_t q = 0; q < original; ++q) {
    const auto p = cx.coords(piece[q]);
    for (int k = 0; k < 14; ++k) {
      if (!cx.neighbor_inside(p, k)) continue;
      const Id start = piece[q] + cx.neighbor_delta(k);
      if (!same_side(start) || known(taken, start) || std::find(tried.begin(), tried.end(), start) != tried.end()) continue;
      std::vector<Id> speck{start};
      bool small = true;
      for (std::size_t i = 0; i < speck.size() && small; ++i) {
        const auto c = cx.coords(speck[i]);
        for (int m = 0; m < 14 && small; ++m) {
          if (!cx.neighbor_inside(c, m)) continue;
          const Id u = speck[i] + cx.neighbor_delta(m);
          if (!same_side(u) || known(taken, u) || std::find(speck.begin(), speck.end(), u) != speck.end()) continue;
          if (speck.size() == max_vertices) small = false;
          else speck.push_back(u);
        }
      }
      if (!small) {
        tried.insert(tried.end(), speck.begin(), speck.end());
        continue;
      }
      piece.insert(piece.end(), speck.begin(), speck.end());
      taken.insert(taken.end(), speck.begin(), speck.end());
      std::sort(taken.begin(), taken.end());
    }
  }
  std::sort(piece.begin(), piece.end());
}

// The choke's saddle with the vertices joined to it between the surface and the pair's own level (a handle's
// birth b <= f <= 0, a tunnel's 0 < f <= death), within a voxel of the saddle: the piece that the pair's simplex
// needs to exist at level 0.
MembraneVoxels level_piece(const ScalarGrid& grid, const FreudenthalComplex& cx, const Choke& c) {
  constexpr int kReach = 1;  // voxels from the saddle: the surface moves by about that much, as for a noise pair
  MembraneVoxels out;
  const bool handle = c.side == Side::Handle;
  auto in_piece = [&](Id v) {
    const float f = grid.values[std::size_t(v)];
    return handle ? f >= c.birth && f <= 0 : f > 0 && f <= c.death;
  };
  std::vector<Id> piece{c.saddle};
  const auto centre = cx.coords(c.saddle);
  for (std::size_t q = 0; q < piece.size(); ++q) {
    const auto p = cx.coords(piece[q]);
    for (int k = 0; k < 14; ++k) {
      if (!cx.neighbor_inside(p, k)) continue;
      const auto o = freudenthal::neighbor_offset(k);
      bool near = true;
      for (int a = 0; a < 3; ++a) near = near && std::abs(p[a] + o[a] - centre[a]) <= kReach;
      const Id u = piece[q] + cx.neighbor_delta(k);
      if (!near || !in_piece(u) || std::find(piece.begin(), piece.end(), u) != piece.end()) continue;
      piece.push_back(u);
    }
  }
  add_small_debris(grid, cx, piece, kSpeck);
  out.shore = std::move(piece);
  out.found = true;
  out.at_saddle = true;
  return out;
}

// Whether flipping v alone would lower the genus of its side: the part of its link on its side is two pieces
// (chi 2), so that v joins two sheets there, a pinch of the level set.
bool pinches(const ScalarGrid& grid, const FreudenthalComplex& cx, Id v, bool inside) {
  const auto& link = freudenthal::vertex_link();
  const auto p = cx.coords(v);
  bool on[14];
  for (int k = 0; k < 14; ++k)
    on[k] = cx.neighbor_inside(p, k) && (grid.values[std::size_t(v + cx.neighbor_delta(k))] <= 0) == inside;
  int chi = 0;
  for (int k = 0; k < 14; ++k) chi += on[k];
  for (const auto& e : link.edges) chi -= on[e[0]] && on[e[1]];
  for (const auto& t : link.triangles) chi += on[t[0]] && on[t[1]] && on[t[2]];
  return chi == 2;
}

// The pinch of the generator's side nearest the surface within two voxels of the saddle (ties: the smallest id).
// A noise pair is born at its saddle, but at level 0 the vertices between its birth and the surface may have
// made the saddle a simple point and moved the thin place next to it.
MembraneVoxels nearby_pinch(const ScalarGrid& grid, const FreudenthalComplex& cx, const Choke& c) {
  constexpr int kReach = 2;
  MembraneVoxels out;
  const bool inside = c.side == Side::Handle;
  const auto sc = cx.coords(c.saddle);
  Id best = -1;
  float best_f = 0;
  for (int dz = -kReach; dz <= kReach; ++dz)
    for (int dy = -kReach; dy <= kReach; ++dy)
      for (int dx = -kReach; dx <= kReach; ++dx) {
        if (!cx.inside(sc[0] + dx, sc[1] + dy, sc[2] + dz)) continue;
        const Id v = cx.vertex(sc[0] + dx, sc[1] + dy, sc[2] + dz);
        const float f = std::abs(grid.values[std::size_t(v)]);
        if ((grid.values[std::size_t(v)] <= 0) != inside || !pinches(grid, cx, v, inside)) continue;
        if (best < 0 || f < best_f || (f == best_f && v < best)) best = v, best_f = f;
      }
  if (best < 0) {
    out.note = "no pinch of its side within two voxels of the saddle";
    return out;
  }
  out.shore = {best};
  add_small_debris(grid, cx, out.shore, kSpeck);
  out.found = true;
  out.at_saddle = true;
  return out;
}

// The Sheet ([0]) and Plane ([1]) membranes that are `wanted`, from one sequence of flood boxes: both shapes
// read the same floods and differ only in what they take from a flooded box, so each comes out as it would
// alone, and a choke whose sheet never closes (flooded up to the whole grid) pays for those floods once, not
// twice. Stops at the first box where membrane[stop_at] closes. A flood that throws ends every shape still
// open, with the error as its note (and in `failure`). `from`: the sequence's first boxes, taken already.
struct SheetAndPlane {
  std::array<MembraneVoxels, 2> membrane;
  std::exception_ptr failure;
};

SheetAndPlane sheet_and_plane(const ScalarGrid& grid, const FreudenthalComplex& cx, const Choke& c, const LoopOptions& options,
                              const std::array<RegionBounds, 2>* bounds, std::array<bool, 2> open, int stop_at,
                              const MembraneProgress* from = nullptr) {
  SheetAndPlane out;
  const bool resume = from && from->saddle == c.saddle && from->stop_at == stop_at && from->wanted == open;
  detail::MembraneSequence sequence = resume ? detail::MembraneSequence(grid, c, options, *from)
                                             : detail::MembraneSequence(grid, c, options, open, stop_at);
  static const bool debug = std::getenv("CHOKELOOPS_DEBUG_MEMBRANES") != nullptr;
  while (!sequence.done()) {
    detail::FloodBox box;
    detail::FloodOutcome outcome;
    const int r = sequence.radius();
    try {
      const auto t_flood = std::chrono::steady_clock::now();
      outcome = detail::flood_two_lobes(grid, cx, c, r, sequence.seed_radius(), false, box,
                                        bounds ? &(*bounds)[c.side == Side::Handle ? 0 : 1] : nullptr);
      if (debug)
        std::fprintf(stderr, "membrane voxels: %s %s depth %g box %d: flood of %zu voxels, outcome %d, %.3f ms\n", to_string(c.side),
                     to_string(c.kind), c.depth, r, box.size(), int(outcome),
                     std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t_flood).count());
    } catch (const Error& e) {
      out.failure = std::current_exception();
      sequence.fail(e.what());
      break;
    }
    sequence.take(outcome, box);
  }
  out.membrane = sequence.release().membrane;
  return out;
}

}  // namespace

namespace detail {

namespace {

// Where a sequence stands before its first box.
MembraneProgress before_first_box(const ScalarGrid& grid, const Choke& c, const LoopOptions& options, std::array<bool, 2> open,
                                  int stop_at) {
  MembraneProgress p;
  p.saddle = c.saddle;
  for (auto& m : p.membrane) m.note = "the membrane did not close near the choke";
  p.wanted = p.open = open;
  p.stop_at = stop_at;
  p.radius = options.first_box_radius(c.depth, grid.voxel_size);
  p.seed_radius = options.seed_radius(c.depth, grid.voxel_size);
  p.done = !(open[0] || open[1]);
  return p;
}

}  // namespace

MembraneSequence::MembraneSequence(const ScalarGrid& grid, const Choke& c, const LoopOptions& options, std::array<bool, 2> open,
                                   int stop_at)
    : MembraneSequence(grid, c, options, before_first_box(grid, c, options, open, stop_at)) {}

MembraneSequence::MembraneSequence(const ScalarGrid& grid, const Choke& c, const LoopOptions& options, MembraneProgress from)
    : grid_(grid),
      saddle_(FreudenthalComplex(grid.dims).coords(c.saddle)),
      full_(std::max({grid.dims[0], grid.dims[1], grid.dims[2]})),
      cap_(options.max_box_radius > 0 ? std::min(full_, options.max_box_radius) : full_),
      p_(std::move(from)) {}

void MembraneSequence::fail(const std::string& why) {
  for (int k = 0; k < 2; ++k)
    if (p_.open[std::size_t(k)]) p_.membrane[std::size_t(k)].note = why;
  p_.done = true;
}

void MembraneSequence::take(FloodOutcome outcome, const FloodBox& box) {
  constexpr int kMostBoxes = 16;
  const int r = p_.radius;
  auto& open = p_.open;
  ++p_.attempts;
  if (outcome == FloodOutcome::Shrink) {
    if (p_.seed_radius <= 1) {
      p_.done = true;
      return;
    }
    p_.seed_radius = p_.seed_radius * 2 / 3;
    p_.done = p_.attempts >= kMostBoxes;
    return;
  }
  if (outcome == FloodOutcome::Flooded && open[1]) {
    MembraneVoxels& m = p_.membrane[1];
    const Sheet s = plane_piece(box, grid_, saddle_, m.shore);
    if (s == Sheet::AtGridBorder) {
      m.note = "the cut plane reaches the side of the grid";
      m.shore.clear();
      open[1] = false;
    } else if (s != Sheet::Open) {
      m.found = !m.shore.empty();
      m.box_radius = r;
      if (m.found) m.note.clear();
      open[1] = false;
    }
  }
  if (outcome == FloodOutcome::Flooded && open[0]) {
    MembraneVoxels& m = p_.membrane[0];
    const auto& sc = saddle_;
    const std::int64_t start = start_of_sheet(box, {sc[0] - box.lo[0], sc[1] - box.lo[1], sc[2] - box.lo[2]});
    std::vector<std::uint32_t> sheet;
    const Sheet s = start < 0 ? Sheet::AtGridBorder
                              : collect_sheet(box, grid_, std::uint32_t(start), [&](std::uint32_t li) { return box.in_contact(li); }, sheet);
    if (start < 0) {
      m.note = "the two zones of the membrane flood never met";
      open[0] = false;
    } else if (s == Sheet::AtGridBorder) {
      m.note = "the membrane reaches the side of the grid: it is not a disc bounded by the surface";
      open[0] = false;
    } else if (s != Sheet::Open) {
      // Either shore alone separates the zones (every path from one to the other steps from a shore vertex
      // of the first to one of the second): the smaller changes fewer voxels.
      std::array<std::vector<std::uint32_t>, 2> shores;
      for (std::uint32_t li : sheet) shores[box.zone(li) == 1 ? 0 : 1].push_back(li);
      const int pick = shores[1].size() < shores[0].size() ? 1 : 0;
      add_debris(box, grid_, shores[pick]);
      m.shore.clear();
      for (std::uint32_t li : shores[pick]) m.shore.push_back(box.global(li));
      std::sort(m.shore.begin(), m.shore.end());
      m.found = !m.shore.empty();
      m.box_radius = r;
      if (m.found) m.note.clear();
      open[0] = false;
    }
  }
  if (p_.membrane[std::size_t(p_.stop_at)].found) {
    // Only the shape the sequence stops at is taken then (closing_membrane_voxels): a recorded sequence
    // (MembraneProgress) does not keep the other's voxels until the label volumes are written.
    MembraneVoxels& other = p_.membrane[std::size_t(1 - p_.stop_at)];
    if (p_.wanted[std::size_t(1 - p_.stop_at)]) {
      std::vector<Id>().swap(other.shore);
      other.found = false;
      other.note = "not kept: the other shape closed first";
    }
    p_.done = true;
    return;
  }
  if (!(open[0] || open[1]) || r >= cap_) {
    p_.done = true;
    return;
  }
  p_.radius = std::min(cap_, int(std::ceil(r * 1.8)));
  if (2 * p_.radius >= full_) p_.radius = cap_;
  p_.done = p_.attempts >= kMostBoxes;
}

}  // namespace detail

MembraneVoxels membrane_voxels(const ScalarGrid& grid, const Choke& c, const LoopOptions& options, MembraneShape shape,
                               const std::array<RegionBounds, 2>* bounds) {
  MembraneVoxels out;
  FreudenthalComplex cx(grid.dims);
  if (shape == MembraneShape::Saddle) {
    out.found = true;
    out.at_saddle = true;
    out.shore = {c.saddle};
    // A tunnel's triangle joins the solid only with all its vertices: those outside besides the saddle too.
    if (c.simplex_dim == 2 && c.simplex >= 0) {
      for (Id v : cx.triangle_vertices(c.simplex))
        if (v != c.saddle && grid.values[std::size_t(v)] > 0) out.shore.push_back(v);
    }
    add_small_debris(grid, cx, out.shore, kSpeck);
    return out;
  }
  if (shape == MembraneShape::LevelPiece) return level_piece(grid, cx, c);
  if (shape == MembraneShape::NearbyPinch) return nearby_pinch(grid, cx, c);
  const std::size_t k = shape == MembraneShape::Plane ? 1 : 0;
  std::array<bool, 2> wanted{k == 0, k == 1};
  SheetAndPlane both = sheet_and_plane(grid, cx, c, options, bounds, wanted, int(k));
  if (both.failure) std::rethrow_exception(both.failure);
  return std::move(both.membrane[k]);
}

int membrane_box_cap(const ScalarGrid& grid, const Choke& choke, const LoopOptions& options, bool wide) {
  const int base = options.first_box_radius(choke.depth, grid.voxel_size);
  return wide ? std::max(64, 16 * base) : std::max(16, 4 * base);
}

LoopOptions label_membrane_options(const ScalarGrid& grid, const Choke& choke) {
  LoopOptions options;
  options.max_box_radius = membrane_box_cap(grid, choke, options, true);
  return options;
}

bool thinner_than_half_a_voxel(const ScalarGrid& grid, const Choke& choke) { return choke.depth < 0.5 * grid.voxel_size; }

MembraneVoxels closing_membrane_voxels(const ScalarGrid& grid, const Choke& choke, const LoopOptions& options,
                                       MembraneShape first, bool saddle_alone, const std::array<RegionBounds, 2>* bounds,
                                       const MembraneProgress* from) {
  if (saddle_alone && thinner_than_half_a_voxel(grid, choke)) {
    MembraneVoxels m = membrane_voxels(grid, choke, options, MembraneShape::Saddle, bounds);
    if (m.found) return m;
  }
  // Both shapes from one sequence of floods: `first` if it closes, else the other (closed or not, with its note).
  const std::size_t k = first == MembraneShape::Plane ? 1 : 0;
  SheetAndPlane both = sheet_and_plane(grid, FreudenthalComplex(grid.dims), choke, options, bounds, {true, true}, int(k), from);
  return std::move(both.membrane[both.membrane[k].found ? k : 1 - k]);
}

}  // namespace chokeloops

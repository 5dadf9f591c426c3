// Membranes and loops by a two-lobe priority flood.
//
// Why this construction. DESIGN §3 lists three: the paper's greedy one-ring growth, the separatrix of the
// choke cell in a discrete gradient, and a priority flood from the two merging pieces. The flood needs no
// gradient, no tet clusters and no special cases at degenerate saddles; every choke reduces to "which of two
// seeds reaches this surface vertex first, moving through the solid in filtration order". Measured on the
// analytic shapes of the tests (dumbbell neck, varying torus at 192^3), its interface meets the surface on
// the choke's cross-section within a voxel, and the shortened loop is within 1-3% of the true
// circumference; its cost is that of a flood in a box of radius ~2.5 depth around the choke, so it scales
// with the loop, not with the grid.
//
// Details that matter (from the prototype notes in DESIGN §3): the seeds are exactly the two pieces of
// {v below the saddle} that the choke simplex joins (the pair's lobes), found inside the box, and the flood
// then absorbs every other piece; the connectivity is the Freudenthal complex's (14 neighbours) everywhere;
// the seed pieces are found in a small box of about the depth (around a handle they join farther away),
// and the flood box grows until the interface closes on the surface near the choke (a generator's box only
// on the sides where a curve through the choke runs out of it: a membrane across a thick block is a thin sheet).
//
// Generators two voxels deep or more first try the plane through the choke square to their cycle
// (LoopOptions::plane_start): across a handle the grid resolves it cuts where the membrane does, for a fifth of
// the cost; its section is kept only when it bounds on its side and shortens to an essential loop (on thinner
// ones, pinholes of a thin sheet, the plane cuts the sheet instead; README, "Generators from the plane square
// to their cycle").
// Generators: the zones' interface can have several curves on the surface. A generator's loop must be
// non-contractible there, so its curves are asked in order of distance from the choke and the nearest one
// that is not null in Z/2 homology (SurfaceTopology::null_homologous, one face flood) is taken. On a flat core (the
// cup's thin wall at 256^3) the filtration order lets one zone enclose the other and every curve of the
// membrane is contractible, in every box; the same box is then flooded by distance from the seeds (the
// interface is their bisector, a straight cut across the wall), which gives a valid loop. Non-contractible is
// not enough: a curve must also bound on the choke's side, i.e. link no cycle of the other side's generators
// (generator_class.h); where no interface curve does, the plane sections of generator_class.h are tried.
// CHOKELOOPS_DEBUG_MEMBRANES=1 traces the choice on stderr.
#include "chokeloops/loops/membranes.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <unordered_map>

#include "common/caller_progress.h"
#include "chokeloops/topology/complex.h"
#include "chokeloops/loops/shorten.h"
#include "chokeloops/surface/topology.h"
#include "chokeloops/loops/channels.h"
#include "generator_class.h"
#include "slide.h"
#include "surface_interface.h"
#include "two_lobe_flood.h"

namespace chokeloops {

namespace {

// GrowContractible: curves closed near the choke, but (for a generator) each is contractible on the surface.
enum class Attempt { Found, Grow, GrowContractible, Shrink };

class LoopTracer {
 public:
  LoopTracer(const ScalarGrid& grid, const SurfaceMesh& surface, const MeshAdjacency& adjacency, SurfaceTopology* topology,
             const std::array<std::vector<const detail::SideCycle*>, 2>* generator_cycles)
      : g_(grid), cx_(grid.dims), S_(surface), A_(adjacency), T_(topology), other_cycles_(generator_cycles),
        bounds_(detail::region_bounds(grid)), debug_(std::getenv("CHOKELOOPS_DEBUG_MEMBRANES") != nullptr),
        debug_far_curves_(std::getenv("CHOKELOOPS_DEBUG_FAR_CURVES") != nullptr) {}

  static constexpr int kThinCoreBox = 48;
  // A generator this many voxels deep or more starts from its plane section (LoopOptions::plane_start).
  static constexpr double kPlaneStartDepth = 2;
  static constexpr double kSectionsFirstVoxels = 1 << 20;
  static constexpr const char* kSectionNote =
      "the membrane's interface gave no curve that bounds on its side (a flat core, e.g. a thin wall): the loop is the "
      "shortest plane section, through the choke or square to its cycle, that is essential, links no cycle of the other "
      "side and links its own cycle once";

  // `record`: where this loop's floods leave the choke's label-volume membrane (trace_loops).
  Loop trace(const Choke& c, const LoopOptions& options, const detail::SideCycle* own_cycle, MembraneProgress* record) const {
    // A choke's boxes are cubes grown as the label volumes grow theirs (a generator's first box too, and the
    // next ones while its curves are contractible): the floods of its loop are the first floods of its
    // membrane's sequence, as long as their boxes and seeds are that sequence's. (A choke thinner than half a
    // voxel gets its saddle alone there, no flood: nothing to record.)
    std::optional<detail::MembraneSequence> sequence;
    if (record && !thinner_than_half_a_voxel(g_, c))
      sequence.emplace(g_, c, label_membrane_options(g_, c), std::array<bool, 2>{true, true}, 0);
    detail::MembraneSequence* feed = sequence ? &*sequence : nullptr;
    Loop loop = trace_loop(c, options, own_cycle, feed);
    if (sequence && loop.found) *record = sequence->release();  // the label volumes draw found loops only
    return loop;
  }

 private:
  Loop trace_loop(const Choke& c, const LoopOptions& options, const detail::SideCycle* own_cycle, detail::MembraneSequence*& feed) const {
    Loop loop;
    loop.choke = c;
    const double h = g_.voxel_size;
    const int full = std::max({g_.dims[0], g_.dims[1], g_.dims[2]});
    const int r0 = options.first_box_radius(c.depth, h);
    const int seed_r0 = options.seed_radius(c.depth, h);
    bool only_contractible = false;
    // A generator's loop must bound on its own side: it links no cycle of the other side (linking.h).
    CurveCheck check;
    if (c.kind == Kind::Generator && T_ && other_cycles_) {
      check.other_side = &(*other_cycles_)[c.side == Side::Handle ? 1 : 0];
      check.own = own_cycle;
    }
    Polyline3 raw;
    std::vector<int> raw_path;  // raw snapped to surface edges, when try_box already did it
    // A generator whose every interface curve near the choke is contractible sits on a flat core (a thin
    // wall): there the filtration order spreads the two zones erratically (one can enclose the other) and
    // the membrane need not cut the handle; a bigger box does not change that. Flooding the same box by
    // distance from the two seeds instead puts the interface on their bisector, a cut straight across the
    // wall.
    detail::BoxExtent box = detail::BoxExtent::cube(r0);
    int seed_r = seed_r0;
    const detail::RegionBounds& bounds = bounds_[c.side == Side::Handle ? 0 : 1];
    const auto saddle_at = cx_.coords(c.saddle);
    // The plane sections depend on the choke alone, not on the box: tried once at most.
    bool sections_tried = false;
    auto try_sections = [&] {
      sections_tried = true;
      if (!detail::generator_section_loop(g_, S_, A_, *T_, sections(), c, *check.other_side, check.own, raw, raw_path, debug_))
        return false;
      loop.found = true;
      loop.note = kSectionNote;
      return true;
    };
    // A generator's membrane that has not closed on the surface in a box of kSectionsFirstVoxels is a sheet
    // spreading along walls (see below): the sections come before the first box that reaches that size.
    auto sections_before_box = [&] {
      return c.kind == Kind::Generator && !sections_tried && check.other_side &&
             box_voxels(box, saddle_at, bounds) >= kSectionsFirstVoxels;
    };
    if (options.plane_start && c.kind == Kind::Generator && check.other_side && own_cycle &&
        c.depth >= kPlaneStartDepth * h) {
      Polyline3 section;
      std::vector<int> section_path, section_faces;
      const bool taken = detail::generator_plane_start(g_, S_, A_, *T_, sections(), c, *check.other_side, *own_cycle, section,
                                                       section_path, section_faces);
      if (debug_) std::fprintf(stderr, "membranes: %s generator depth %g: plane start %s\n", to_string(c.side), c.depth, taken ? "taken" : "refused");
      if (taken) {
        Loop from_section = loop;
        from_section.found = true;
        try {
          if (finish_loop(from_section, options, section, section_path, true, &section_faces)) return from_section;
        } catch (const Error&) {
          // its membrane, as for any other generator
        }
        if (debug_) std::fprintf(stderr, "membranes: %s generator depth %g: plane start not shortened\n", to_string(c.side), c.depth);
      }
    }
    for (int attempt = 0; attempt < 48; ++attempt) {
      // Where an earlier box did not close the membrane, the sections are tried before this one is flooded
      // rather than after: they depend on the choke alone, so the loop changes only where this box's flood
      // would have closed it, and on the pierced block the 29 generators that reached this size all ended in
      // the sections or flooded on (its floods were 2.8 s of the loop stage's 22 s of CPU).
      if (attempt > 0 && sections_before_box() && try_sections()) break;
      auto t_box = std::chrono::steady_clock::now();
      std::array<char, 6> open_sides{};
      const int rejections_before = check.rejections;
      Attempt a = try_box(c, box, seed_r, false, raw, raw_path, check, open_sides, feed);
      const bool rejected_here = check.rejections > rejections_before;
      const int r = box.largest();
      if (debug_)
        std::fprintf(stderr, "membranes: %s %s depth %g box %d (%d %d %d / %d %d %d) seed %d: attempt %d, %.2f ms\n", to_string(c.side),
                     to_string(c.kind), c.depth, r, box.below[0], box.below[1], box.below[2], box.above[0], box.above[1],
                     box.above[2], seed_r, int(a),
                     std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t_box).count());
      const bool whole = detail::box_covers(box, saddle_at, bounds);
      // At the whole grid a flat core goes to the plane sections below: the flood by distance there
      // gave no loop in 32 tries on the pierced block (0.2 s each), and on the cup a loop 0.5% longer
      // than the section's.
      if (a == Attempt::GrowContractible && whole) {
        only_contractible = true;
        break;
      }
      // A generator thinner than a voxel (a pinhole or a hair-thin bar of a noisy mask) tries the sections
      // as soon as its box reaches kThinCoreBox voxels, and floods on only if none is its loop: on the
      // grey-matter map at 128 such generators flooded every box up to the whole grid, twice per box (40 s
      // of the loop stage's CPU), and the few loops those floods closed ran hundreds of millimetres round
      // the brain for a pinhole where the sections give one of a few.
      if (a == Attempt::GrowContractible && c.depth < h && r >= kThinCoreBox && !sections_tried && check.other_side &&
          try_sections())
        break;
      const bool contractible = a == Attempt::GrowContractible;
      // Where the curves were essential but linked a cycle of the other side, the flood by distance is meant
      // for something else (a flat core, whose curves are all contractible): the sections come first there,
      // and the flood by distance is left for boxes whose curves were all contractible. (On the pierced block
      // the three generators with no loop flooded the whole solid by distance twice after their sections,
      // 0.8 s of the stage's CPU; no loop changed there, on the cage, fertility, Neptune or the grey-matter map.)
      if (contractible && check.rejected() && !sections_tried && check.other_side && try_sections()) break;
      if (contractible && !rejected_here) {
        only_contractible = true;
        a = try_box(c, box, seed_r, true, raw, raw_path, check, open_sides, feed);
      }
      if (a == Attempt::Found) { loop.found = true; loop.box_radius = r; break; }
      // An essential curve that links a cycle of the other side is a membrane spread along a wall beside
      // another tunnel (handle); bigger boxes spread it further. On the pierced block 27 of the 30
      // generators that met one ended in the plane sections after flooding the whole solid (0.4 s each),
      // and none found its loop in a bigger box: the sections come first, and the boxes grow on only if
      // none of them is the loop.
      if (check.rejected() && !sections_tried && check.other_side && try_sections()) break;
      // A generator's membrane that has not closed on the surface in a box of kSectionsFirstVoxels is a sheet
      // spreading along walls: on the pierced block the 30 of 100 generators whose boxes grew past it flooded
      // on, most of them to the whole solid (0.5 s each on average), and 26 of those 30 ended in the plane
      // sections anyway. The sections are tried there first, and the boxes grow on only if none of them is the
      // loop. (A first box of that size is flooded first: the check above waits for a box that did not close.)
      if (sections_before_box() && try_sections()) break;
      if (a == Attempt::Grow || a == Attempt::GrowContractible) {
        if (whole) break;
        // A generator's box grows only on the sides where a curve through the choke runs out of it: a
        // membrane across a block's whole section is a thin sheet, and a cube that holds it floods the block
        // (the pierced block's handle generators: 99 floods of the whole solid, 0.5 s each). A generator's
        // curve must be essential and link no cycle of the other side, which a curve bent by a box too narrow
        // for its membrane is not; a choke's curve has no such check, and on the pierced block a box grown by
        // sides gave one choke a loop twice as long as the whole grid's flood gives. So a choke's box, and a
        // box whose curves were contractible or wrongly linked (no matter of where the box cuts the
        // membrane), becomes the cube of its largest side and grows as a whole.
        if (contractible || c.kind != Kind::Generator) open_sides = {}, box = detail::BoxExtent::cube(r);
        detail::grow_box(box, open_sides, saddle_at, bounds, full);
      } else {
        if (seed_r <= 1) break;
        seed_r = seed_r * 2 / 3;
      }
    }
    if (!loop.found && check.other_side && !sections_tried) try_sections();
    if (!loop.found) {
      loop.note = check.rejected() ? "every essential interface curve of the membrane near the choke links a cycle of the other side: "
                                   "none bounds on its own side, so none is reported"
                  : only_contractible
                      ? "every interface curve of the membrane near the choke is contractible on the surface (a flat core, e.g. a thin wall)"
                      : "the membrane did not close on the surface near the choke";
      return loop;
    }
    finish_loop(loop, options, raw, raw_path, false);
    return loop;
  }

  // Shortens and describes a found loop from its curve `raw` (and `raw_path`, its edge path when known).
  // `shortened_or_nothing`: where the curve cannot be shortened (no annulus band round it) or its shortest
  // loop slips off a generator's handle (null-homologous), false is returned and the loop is left half made,
  // instead of reporting the curve unshortened.
  bool finish_loop(Loop& loop, const LoopOptions& options, const Polyline3& raw, const std::vector<int>& raw_path,
                   bool shortened_or_nothing, const std::vector<int>* raw_faces = nullptr) const {
    const Choke& c = loop.choke;
    const double h = g_.voxel_size;
    auto t_shorten = std::chrono::steady_clock::now();
    loop.raw_length = closed_length(raw);
    loop.points = raw;
    if (options.shorten) {
      ShortenOptions so;
      so.max_move = c.depth + 3 * h;
      // The interface already crosses the choke's narrowest section, so the searches from vertices along
      // the band's cut find nothing the descent from the loop itself does not: without them the cage's 127
      // loops came out 83 identical, none longer by more than 1.3e-7 of its length, 44 shorter by up to
      // 0.17%, for 2.4 searches a loop instead of 6.4 (a loop that ends at its band's edge still slides).
      so.cut_samples = 0;
      // Most loops settle within a few rings of the interface: the cage's 127 came out identical in a band
      // of 8 rings first (12 only for the 15 that reached its edge), and its median loop went 5.7 -> 4.6 ms
      // with two smaller changes (README, "A narrow band first").
      so.first_rings = 8;
      // A plane start's long section is shortened from its own faces where that finishes near it (README,
      // "From the plane section's own faces"); otherwise, and for any other curve, the band search.
      ShortenResult best;
      const bool from_strip =
          raw_faces && detail::shorten_plane_start(S_, A_, *raw_faces, options.strip_start_faces, so.max_move, best);
      if (debug_ && raw_faces && raw_faces->size() >= options.strip_start_faces)
        std::fprintf(stderr, "membranes: %s %s depth %g: strip start %s\n", to_string(c.side), to_string(c.kind), c.depth,
                     from_strip ? "kept" : "not kept (still moving, moved past max_move, or no strip)");
      if (!from_strip) best = raw_path.empty() ? shorten_polyline(S_, A_, raw, so) : shorten_loop(S_, A_, raw_path, so);
      // A loop that stayed clear of its band's edge is the narrowest section within max_move already.
      auto slide = [&](ShortenResult& r) {
        if (r.rings > 0 && options.slide && r.at_band_edge) detail::slide_to_narrowest(g_, S_, A_, r, so, c.depth + 2 * h, debug_);
      };
      slide(best);
      // The curve's points snapped to their nearest vertices are a second start: where no band around the
      // side path is an annulus (on sub-voxel structures a side can touch itself), and for a choke whose
      // loop came out under half its curve's length, a curve far from any geodesic (a rim wandering over a
      // pitted cortex) where the start decides which local loop it ends in; the shorter loop is kept. (A
      // generator's other start could lie in another homology class: its side path alone is shortened.)
      const bool other_start = !raw_path.empty() && (best.rings == 0 || (c.kind != Kind::Generator && best.length < 0.5 * loop.raw_length));
      if (other_start) {
        try {
          // Often the snapped points are the side path itself (150 of the grey-matter map's 424 second
          // starts), whose loop `best` already is.
          const std::vector<int> snapped_path = snap_polyline_to_edge_path(S_, A_, raw);
          if (snapped_path != raw_path) {
            ShortenResult snapped = shorten_loop(S_, A_, snapped_path, so);
            slide(snapped);
            if (snapped.rings > 0 && (best.rings == 0 || snapped.length < best.length)) best = std::move(snapped);
          }
        } catch (const Error&) {
          // keep the side path's loop
        }
      }
      // A generator's loop must stay essential. Where a band crosses a handle thinner than a voxel, the shortest
      // loop in it can slip off that handle (on the grey-matter map a 3 mm plane section came out contractible):
      // the curve that was checked is then reported unshortened.
      if (c.kind == Kind::Generator && T_ && best.rings > 0 && !raw_path.empty() && T_->null_homologous(best.edge_path)) {
        if (shortened_or_nothing) return false;
        loop.edge_path = raw_path;
        loop.note += std::string(loop.note.empty() ? "" : "; ") + "not shortened: its shortest loop in the band is null-homologous";
        describe_loop(loop);
        return true;
      }
      if (best.rings == 0 && shortened_or_nothing) return false;
      if (best.rings == 0) loop.note += std::string(loop.note.empty() ? "" : "; ") + "not shortened: no annulus band around the loop";
      // Unshortened (best.length is then its edge path's), the interface curve itself may be shorter than
      // its edge path (it cuts across faces).
      if (best.points.size() >= 3 && (best.rings > 0 || best.length < loop.raw_length)) loop.points = best.points;
      loop.edge_path = best.edge_path;
      loop.from_strip = from_strip;
    } else {
      loop.edge_path = raw_path.empty() ? snap_polyline_to_edge_path(S_, A_, raw) : raw_path;
    }
    describe_loop(loop);
    if (debug_)
      std::fprintf(stderr, "membranes: %s %s depth %g: shortened/slid in %.0f ms\n", to_string(c.side), to_string(c.kind), c.depth,
                   std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t_shorten).count());
    return true;
  }

  // The grid vertices the box around `saddle` holds within the side's bounds (what its flood reads).
  double box_voxels(const detail::BoxExtent& box, const std::array<int, 3>& saddle, const detail::RegionBounds& bounds) const {
    std::array<int, 3> lo, hi;
    detail::flood_box_range(box, saddle, g_.dims, &bounds, lo, hi);
    double voxels = 1;
    for (int a = 0; a < 3; ++a) voxels *= std::max(0, hi[a] - lo[a] + 1);
    return voxels;
  }

  struct CurveCheck {
    const std::vector<const detail::SideCycle*>* other_side = nullptr;  // null: not checked
    const detail::SideCycle* own = nullptr;                              // the choke's own cycle, if it could be made
    // Essential curves turned down so far because they link one of them (a box's own: the growth over its
    // try_box).
    int rejections = 0;
    bool rejected() const { return rejections > 0; }
  };

  // open_sides: set to the box's sides (below x y z, above x y z) where a curve through the choke runs out of
  // the box, when none closes there.
  // `feed`: the choke's label-volume membrane sequence, given this box's flood when the box is its next one
  // (else set to null: the sequences part there).
  Attempt try_box(const Choke& c, const detail::BoxExtent& extent, int seed_radius, bool by_distance, Polyline3& out,
                  std::vector<int>& out_path, CurveCheck& check, std::array<char, 6>& open_sides,
                  detail::MembraneSequence*& feed) const {
    const int r = extent.largest();
    const bool handle = c.side == Side::Handle;
    detail::FloodBox box;
    const auto t_flood = std::chrono::steady_clock::now();
    const detail::FloodOutcome flooded = detail::flood_two_lobes(g_, cx_, c, extent, seed_radius, by_distance, box, &bounds_[handle ? 0 : 1]);
    if (debug_)
      std::fprintf(stderr, "membranes: %s %s depth %g box %d: flood of %zu voxels, %.3f ms\n", to_string(c.side), to_string(c.kind), c.depth, r,
                   box.size(), std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t_flood).count());
    // A flood by distance is not one of the sequence's (it floods its box once more, in another order).
    if (feed && !feed->done() && !by_distance) {
      const bool cube = extent.smallest() == r && extent.largest() == r;
      if (cube && r == feed->radius() && seed_radius == feed->seed_radius()) feed->take(flooded, box);
      else feed = nullptr;
    }
    switch (flooded) {
      case detail::FloodOutcome::Grow: return Attempt::Grow;
      case detail::FloodOutcome::Shrink: return Attempt::Shrink;
      case detail::FloodOutcome::Flooded: break;
    }

    // Where the zones meet on the surface; its closed curves near the choke are the candidates.
    static thread_local detail::StampedMarks<std::int8_t> vertex_label;
    detail::SurfaceInterface interface;
    detail::surface_interface(g_, cx_, S_, A_, box, handle, vertex_label, interface);
    const double h = g_.voxel_size;
    struct Candidate { double distance; Polyline3 curve; std::vector<std::int64_t> edges; };
    std::vector<Candidate> candidates;
    for (detail::InterfaceCurve& curve : interface.closed) {
      double d = 1e300;
      for (auto& p : curve.points)
        d = std::min(d, std::hypot(p[0] - c.point[0], p[1] - c.point[1], p[2] - c.point[2]));
      // Each far curve costs a flood of the surface's faces: asked for apart from the rest of the log.
      if (debug_far_curves_ && c.kind == Kind::Generator && d > c.depth + 4 * h && T_) {
        bool ct = true;
        try { ct = T_->null_homologous(snap_polyline_to_edge_path(S_, A_, curve.points)); } catch (const Error&) {}
        std::fprintf(stderr, "membranes: %s generator depth %g box %d: far curve at %g, %zu points %s\n", to_string(c.side),
                     c.depth, r, d, curve.points.size(), ct ? "null-homologous" : "ESSENTIAL");
      }
      if (d <= c.depth + 4 * h) candidates.push_back({d, std::move(curve.points), std::move(curve.edges)});
    }
    if (candidates.empty()) {
      detail::mark_open_sides(g_, S_, interface.segments, interface.at, box, c.point, c.depth + 4 * h, open_sides);
      return Attempt::Grow;
    }
    // Nearest first; the curves come from sorted faces, so ties resolve the same way on every run.
    std::stable_sort(candidates.begin(), candidates.end(),
                     [](const Candidate& a, const Candidate& b) { return a.distance < b.distance; });
    if (c.kind != Kind::Generator || !T_) {
      out = std::move(candidates[0].curve);
      out_path = std::move(detail::label_side_paths(S_, candidates[0].edges, vertex_label)[0]);
      if (out_path.size() < 3) out_path.clear();  // both sides collapsed: the curve is snapped instead
      return Attempt::Found;
    }
    // A generator's membrane is a disk across its handle (tunnel); its boundary must be non-trivial on the
    // surface. Where the core is flat (a thin wall) the two zones also meet along the wall, and that
    // interface curve bounds a disk on the surface: it may be the nearest one, so each curve is asked in turn.
    for (std::size_t i = 0; i < candidates.size(); ++i) {
      // Null in Z/2 homology rather than contractible: one flood for any curve (a snapped curve may touch
      // itself, where the exact contractibility test would need CGAL's structure over the whole surface), and
      // a generator's curve must be non-null anyway: a disk across a handle cuts it, so its boundary cannot
      // separate the surface. The curve's edge paths (its two sides, then its points snapped) are asked in
      // turn: where the rim of a sub-voxel handle touches itself, one side can close up around nothing.
      auto sides = detail::label_side_paths(S_, candidates[i].edges, vertex_label);
      std::vector<int> path;
      bool contractible = true;
      for (int k = 0; k < 3 && contractible; ++k) {
        if (k < 2) {
          path = std::move(sides[std::size_t(k)]);
        } else {
          try {
            path = snap_polyline_to_edge_path(S_, A_, candidates[i].curve);
          } catch (const Error&) {
            break;  // not a connected curve on the surface
          }
        }
        contractible = path.size() < 3 || T_->null_homologous(path);
      }
      if (debug_)
        std::fprintf(stderr, "membranes: %s generator depth %g box %d: curve %zu/%zu at %g, %zu points, %s\n",
                     to_string(c.side), c.depth, r, i + 1, candidates.size(), candidates[i].distance,
                     candidates[i].curve.size(), contractible ? "null-homologous" : "essential");
      if (contractible) continue;
      // Essential on the surface, but it need not bound on the choke's side: the rim of a membrane spread
      // along a thin wall goes around the tunnel beside it (seen on a cup's wall), and links that tunnel's
      // cycle. A curve that bounds in the solid (the outside) links no cycle of the outside (the solid).
      if (check.other_side) {
        const int k = detail::linked_cycle(candidates[i].curve, *check.other_side);
        if (debug_) std::fprintf(stderr, "membranes:   links other-side cycle %d\n", k);
        if (k >= 0) {
          ++check.rejections;
          continue;
        }
      }
      out = std::move(candidates[i].curve);
      out_path = std::move(path);
      return Attempt::Found;
    }
    return Attempt::GrowContractible;
  }

  const ScalarGrid& g_;
  FreudenthalComplex cx_;
  const SurfaceMesh& S_;
  const MeshAdjacency& A_;
  SurfaceTopology* T_;  // null: generators are not checked while their curve is chosen
  // The surface's faces bucketed for plane sections, made by the first generator that needs them.
  const SurfaceSections& sections() const {
    std::call_once(sections_once_, [&] { sections_ = std::make_unique<SurfaceSections>(S_, &A_); });
    return *sections_;
  }
  mutable std::once_flag sections_once_;
  mutable std::unique_ptr<SurfaceSections> sections_;
  const std::array<std::vector<const detail::SideCycle*>, 2>* other_cycles_ = nullptr;  // [handle, tunnel] generator cycles
  const std::array<detail::RegionBounds, 2> bounds_;  // the solid's and the outside's: floods stay inside them
  bool debug_, debug_far_curves_;
};

}  // namespace

void describe_loop(Loop& loop) {
  const auto& P = loop.points;
  loop.length = closed_length(P);
  std::array<double, 3> mean, n;
  best_fit_plane(P, mean, n);
  double rmin = 1e300, rsum = 0;
  const Eigen::Vector3d centre(mean[0], mean[1], mean[2]);
  for (auto& p : P) {
    const double r = (Eigen::Vector3d(p[0], p[1], p[2]) - centre).norm();
    rmin = std::min(rmin, r);
    rsum += r;
  }
  // A sign convention makes the normal reproducible: its largest component is positive.
  int big = 0;
  for (int a = 1; a < 3; ++a)
    if (std::abs(n[std::size_t(a)]) > std::abs(n[std::size_t(big)])) big = a;
  if (n[std::size_t(big)] < 0) n = {-n[0], -n[1], -n[2]};
  loop.centroid = mean;
  loop.normal = n;
  loop.radius_min = rmin;
  loop.radius_mean = rsum / double(P.size());
}

std::vector<Loop> trace_loops(const ScalarGrid& grid, const SurfaceMesh& surface, const MeshAdjacency& adjacency,
                              const std::vector<Choke>& chokes, const LoopOptions& options, SurfaceTopology* topology, int genus,
                              std::vector<MembraneProgress>* membranes, const ProgressFn& progress) {
  if (membranes) membranes->assign(chokes.size(), MembraneProgress{});
  // Every generator's cycle, once: each generator's loop is checked against the other side's.
  const bool debug = std::getenv("CHOKELOOPS_DEBUG_MEMBRANES") != nullptr;
  auto t_stage = std::chrono::steady_clock::now();
  auto lap = [&](const char* what) {
    if (!debug) return;
    const auto now = std::chrono::steady_clock::now();
    std::fprintf(stderr, "loop stage: %s %.0f ms\n", what, std::chrono::duration<double, std::milli>(now - t_stage).count());
    t_stage = now;
  };
  detail::GeneratorCycles cycles;
  if (topology) detail::make_generator_cycles(grid, chokes, cycles);
  lap("generator cycles");
  LoopTracer tracer(grid, surface, adjacency, topology, topology ? &cycles.by_side : nullptr);
  std::vector<Loop> loops(chokes.size());
  // Longest first, each thread taking the next choke when it is free: a few chokes can cost most of the
  // stage (on maltoporin two of 22 tunnels flood the whole molecule, over a second each), and a split of the
  // list into halves left one thread with both. Their cycle's extent (or else their depth) says which; each
  // loop is traced on its own, so the order changes no result.
  std::vector<std::size_t> order(chokes.size());
  std::vector<double> extent(chokes.size(), 0.0);
  for (std::size_t i = 0; i < chokes.size(); ++i) {
    order[i] = i;
    const detail::SideCycle* cycle = topology && i < cycles.own.size() ? cycles.own[i] : nullptr;
    extent[i] = cycle ? std::hypot(cycle->hi[0] - cycle->lo[0], cycle->hi[1] - cycle->lo[1], cycle->hi[2] - cycle->lo[2])
                      : chokes[i].depth;
  }
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return extent[a] > extent[b]; });
  const int workers = std::max(1, std::min(tbb::this_task_arena::max_concurrency(), int(chokes.size())));
  // The surface's homology basis, which every generator's curve is checked with, is one serial pass over the
  // surface (85 ms on the cage, 0.6 s on the pierced block): the first worker builds it while the others trace
  // the chokes, which need no basis, instead of waiting on the first generator that asks for it.
  const bool build_basis = topology && std::any_of(chokes.begin(), chokes.end(), [](const Choke& c) { return c.kind == Kind::Generator; });
  std::atomic<bool> basis_ready{!build_basis};
  std::vector<std::size_t> chokes_only;
  for (std::size_t i : order)
    if (chokes[i].kind != Kind::Generator) chokes_only.push_back(i);
  std::unique_ptr<std::atomic<char>[]> taken(new std::atomic<char>[chokes.size()]());
  std::atomic<std::size_t> next{0}, next_choke{0};
  // A big map's stage runs for tens of seconds (the grey-matter map's 1,938 loops, a membrane protein's
  // thousands): its progress goes out as loops finish, and a caller that asks to stop (Ctrl-C in Python) is
  // heard between loops rather than at the stage's end.
  detail::CallerProgress stage(progress, "loops", chokes.size());
  auto take = [&](std::atomic<std::size_t>& cursor, const std::vector<std::size_t>& list) -> std::ptrdiff_t {
    for (std::size_t k = cursor++; k < list.size(); k = cursor++)
      if (!taken[list[k]].exchange(1)) return std::ptrdiff_t(list[k]);
    return -1;
  };
  // One choke whose loop cannot be made (e.g. a membrane interface spanning two surface components of a
  // raw segmentation) is reported without a loop; it does not stop the others.
  tbb::parallel_for(0, workers, [&](int worker) {
   prepare_shortening_scratch(surface);
   if (worker == 0 && build_basis) {
     try {
       topology->prepare_homology();
     } catch (...) {
       stage.fail(std::current_exception());
       return;
     }
     basis_ready = true;
   }
   for (;;) {
    if (stage.stopped()) break;
    std::ptrdiff_t picked = basis_ready ? -1 : take(next_choke, chokes_only);
    if (picked < 0) picked = take(next, order);
    if (picked < 0) break;
    const std::size_t i = std::size_t(picked);
    const auto t0 = std::chrono::steady_clock::now();
    try {
      // Isolated: a trace waiting in a parallel loop of its own (plane sections, a slide) takes up no part
      // of another worker's trace, whose time would count as this loop's.
      tbb::this_task_arena::isolate([&] {
        loops[i] = tracer.trace(chokes[i], options, topology ? cycles.own[i] : nullptr, membranes ? &(*membranes)[i] : nullptr);
      });
    } catch (const Error& e) {
      loops[i] = Loop{};
      loops[i].choke = chokes[i];
      loops[i].note = std::string("no loop: ") + e.what();
    } catch (...) {
      // Anything else (memory running out) ends the stage: the other workers stop at their next loop, rather
      // than trace the rest of the list before the exception reaches the caller.
      stage.fail(std::current_exception());
      break;
    }
    loops[i].trace_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    stage.item_done();
   }
  }, tbb::simple_partitioner());
  release_shortening_scratch();
  stage.finish();
  if (debug) {
    double sum = 0, mx = 0;
    for (const Loop& l : loops) sum += l.trace_ms, mx = std::max(mx, l.trace_ms);
    for (const Loop& l : loops)
      std::fprintf(stderr, "loop stage: trace %s %s depth %g found %d: %.1f ms\n", to_string(l.choke.side), to_string(l.choke.kind),
                   l.choke.depth, int(l.found), l.trace_ms);
    std::fprintf(stderr, "loop stage: traces' own times sum %.0f ms, longest %.0f ms, %d workers\n", sum, mx, workers);
  }
  lap("traces");
  if (topology && genus > 0) {
    int handles = 0, tunnels = 0;
    for (const Choke& c : chokes)
      if (c.kind == Kind::Generator) ++(c.side == Side::Handle ? handles : tunnels);
    if (handles == genus && tunnels == genus && int(cycles.by_side[0].size()) == genus && int(cycles.by_side[1].size()) == genus)
      detail::drop_dependent_generators(loops, cycles);
  }
  lap("independence");
  return loops;
}

}  // namespace chokeloops

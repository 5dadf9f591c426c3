// The filter: rounds of (persistence -> select pairs -> membranes -> edits -> check).
//
// Why membranes. A pair of the genus is removed by changing the side of as few vertices as possible
// where the handle (or the tunnel) is narrowest. The two-lobe flood's contact sheet at the handle
// generator is a disc across the handle through its narrowest section; one shore of it separates the
// two lobes, so moving it out of the solid cuts the handle and nothing else (and the same in the
// outside fills a tunnel). The values near an edit become the distance to the new surface where that is
// nearer than the old one; every other value stays bit-identical.
//
// Why rounds and a check. Each batch of edits is judged exactly, group by group (edits whose changed
// vertices touch form a group; batch_check.h): a group must keep the components and sealed cavities (each
// side's vertices around it joined, searched near the group, or else one labelling of both sides) and lower
// the genus (its local change of the Euler characteristic). Noise pairs whose saddle fails are tried again in
// the same round with other small pieces (Attempt). Groups that fail are noted and undone, the others stay,
// with no bisection and no persistence per check; one persistence per round then finds the pairs left and
// must agree with what the checks predicted (else an internal error). Pairs selected but left (e.g.
// their membrane did not close, or their edit was undone) are asked again in the next round, from the
// edited field, with the other membrane shape first (the flood's sheet on odd rounds, a plane on even
// ones), the other side of the pair preferred, and never again as a lone saddle vertex.
#include "chokeloops/filter/filter.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <functional>
#include <optional>
#include <sstream>
#include <unordered_set>

#include "chokeloops/field/levelset.h"
#include "chokeloops/loops/membrane_voxels.h"
#include "chokeloops/topology/complex.h"
#include "batch_check.h"
#include "edit_field.h"

namespace chokeloops {

namespace {

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

struct Analysis {
  ChokeSet chokes;
  FilterSummary summary;
};

Analysis analyse(const ScalarGrid& grid) {
  Analysis a;
  const PersistenceDiagram diagram = lower_star_persistence(grid);
  ChokeParameters only_generators;
  only_generators.d_max = Threshold{0, false};
  only_generators.min_persistence = Threshold{1e30, false};
  a.chokes = find_chokes(grid, diagram, only_generators);
  a.summary = {a.chokes.handle_generators, a.chokes.components, a.chokes.sealed_cavities};
  return a;
}

struct GenusPair {
  Choke handle, tunnel;
  double persistence = 0;  // d - b
};

std::vector<GenusPair> genus_pairs(const ChokeSet& chokes) {
  std::map<int, GenusPair> by_pair;
  for (const Choke& c : chokes.chokes) {
    if (c.kind != Kind::Generator) continue;
    GenusPair& p = by_pair[c.pair];
    (c.side == Side::Handle ? p.handle : p.tunnel) = c;
    p.persistence = c.death - c.birth;
  }
  std::vector<GenusPair> pairs;
  for (auto& [index, p] : by_pair) pairs.push_back(p);
  // Most persistent first; ties by the handle's simplex, so the order is the same on every run.
  std::stable_sort(pairs.begin(), pairs.end(), [](const GenusPair& a, const GenusPair& b) {
    if (a.persistence != b.persistence) return a.persistence > b.persistence;
    return a.handle.simplex < b.handle.simplex;
  });
  return pairs;
}

std::string where(const Choke& c) {
  std::ostringstream s;
  s.precision(4);
  s << "(" << c.point[0] << ", " << c.point[1] << ", " << c.point[2] << ")";
  return s.str();
}

// What a noise pair's edit tries, in turn, while the check refuses it: its saddle alone, the other side's
// saddle, its level piece, the other side's, the pinch nearest its saddle, the other side's, then its membrane
// (a disc, not at the saddle). Any pair whose disc fails (or does not close) is then thinned to a pinch on its
// side, then on the other (thinned_pinch_voxels): that can neither join components nor open cavities. Each is
// tried in the next wave of the same round, with no persistence run between.
enum Attempt { kSaddle, kOtherSaddle, kLevelPiece, kOtherLevelPiece, kPinch, kOtherPinch, kDisc, kThin, kOtherThin };
// An edit waiting to be applied, with its pair's generators, so that it can be made again.
struct PendingEdit : FilterEdit {
  const Choke* first = nullptr;  // the generator chosen for the pair
  const Choke* other = nullptr;  // the pair's other generator, when that side may be edited too
  int attempt = kDisc;
};

std::vector<const FilterEdit*> views(const std::vector<PendingEdit>& edits) {
  std::vector<const FilterEdit*> v;
  for (const PendingEdit& e : edits) v.push_back(&e);
  return v;
}

// "cutting the handle of depth D at (x, y, z)": how the notes name an edit.
std::string describe(const FilterEdit& e) {
  std::ostringstream s;
  s << (e.side == Side::Handle ? "cutting the handle" : "filling the tunnel") << " of depth " << e.depth << " at (" << e.point[0]
    << ", " << e.point[1] << ", " << e.point[2] << ")";
  return s.str();
}

bool close_to(const std::array<double, 3>& a, const std::array<double, 3>& b, double h) {
  return std::abs(a[0] - b[0]) <= h && std::abs(a[1] - b[1]) <= h && std::abs(a[2] - b[2]) <= h;
}

// The batch's edits joined into groups: edits whose changed vertices touch (share a Freudenthal edge or a
// vertex) act together and are judged, kept or undone together.
struct BatchGroups {
  detail::SideChanges changes;            // every vertex that changed side, with its side before
  std::vector<std::vector<Id>> vertices;  // per group, its changed vertices
  std::vector<std::vector<std::size_t>> edits;  // per group, indices into the batch
};

BatchGroups group_changes(const ScalarGrid& grid, const FreudenthalComplex& cx, const std::vector<PendingEdit>& batch,
                          const detail::Undo& undo) {
  BatchGroups g;
  for (const auto& [v, old] : undo.old_values)
    if (!g.changes.count(v)) g.changes.emplace(v, old <= 0);  // the first record holds the value before
  for (auto it = g.changes.begin(); it != g.changes.end();)
    it = it->second == (grid.values[std::size_t(it->first)] <= 0) ? g.changes.erase(it) : std::next(it);
  std::vector<std::size_t> parent(batch.size());
  for (std::size_t i = 0; i < parent.size(); ++i) parent[i] = i;
  auto find = [&](std::size_t i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  std::unordered_map<Id, std::size_t> owner;
  for (std::size_t i = 0; i < batch.size(); ++i)
    for (Id v : batch[i].voxels) {
      if (!g.changes.count(v)) continue;
      const auto [it, fresh] = owner.emplace(v, i);
      if (!fresh) parent[find(i)] = find(it->second);
    }
  for (const auto& [v, i] : owner) {
    const auto c = cx.coords(v);
    for (int k = 0; k < 14; ++k) {
      if (!cx.neighbor_inside(c, k)) continue;
      const auto it = owner.find(v + cx.neighbor_delta(k));
      if (it != owner.end()) parent[find(i)] = find(it->second);
    }
  }
  std::map<std::size_t, std::size_t> group_of_root;
  for (std::size_t i = 0; i < batch.size(); ++i) {
    const auto [it, fresh] = group_of_root.emplace(find(i), g.edits.size());
    if (fresh) g.edits.emplace_back(), g.vertices.emplace_back();
    g.edits[it->second].push_back(i);
  }
  for (const auto& [v, i] : owner) g.vertices[group_of_root[find(i)]].push_back(v);
  for (auto& vs : g.vertices) std::sort(vs.begin(), vs.end());
  return g;
}

// Applies the edits and keeps the groups of them that remove pairs of the genus and nothing else: the
// components and sealed cavities stay, the genus drops, never below `floor` (the pairs --keep-genus keeps).
// A group may lower the genus by more than one pair (an edit can take tiny pairs along). Groups that fail
// are noted and undone, and the rest applied again until every group passes. Most groups are judged from
// their surroundings alone; `labels`, the current field's when known, are computed (and follow the field) only
// for the groups whose surroundings do not settle it. `now` is the field's analysis, recomputed once at the end
// for the next round, and checked against what the checks predicted: the same components and cavities, the
// genus lowered by the groups' changes of the Euler characteristic. An edit at a noise pair's saddle that
// failed (the vertices around the saddle close the handle without it, or the saddle was a speck's only
// bridge) is made again by `remake` (the next Attempt) and waits for the next wave.
std::vector<FilterEdit> apply_checked(ScalarGrid& grid, std::vector<PendingEdit> edits, Analysis& now,
                                      std::optional<detail::SideLabels>& labels,
                                      const std::function<bool(PendingEdit&, std::string&, bool)>& remake,
                                      int last_attempt, int floor, std::vector<std::string>& notes,
                                      std::vector<std::pair<Side, std::array<double, 3>>>& failed, double& t_labels,
                                      double& t_persistence) {
  const FreudenthalComplex cx(grid.dims);
  int genus = now.summary.genus;
  std::vector<FilterEdit> kept;
  std::vector<PendingEdit> waiting;
  // Waves: a batch is applied and judged until every group in it passes; edits that touched others that
  // failed with them wait for the next wave, judged on the field the batch left.
  while (!edits.empty() || !waiting.empty()) {
    if (edits.empty()) {
      edits = std::move(waiting), waiting.clear();
      // A thinning is made again on the field as the waves before left it: its flips are simple only there.
      std::vector<std::string> why_not(edits.size());
      std::vector<char> ready(edits.size(), 1);
      tbb::parallel_for(std::size_t(0), edits.size(), [&](std::size_t i) {
        if (edits[i].attempt >= kThin) ready[i] = remake(edits[i], why_not[i], true);
      });
      std::vector<PendingEdit> still;
      for (std::size_t i = 0; i < edits.size(); ++i) {
        if (ready[i]) {
          still.push_back(std::move(edits[i]));
          continue;
        }
        failed.push_back({edits[i].side, edits[i].point});
        notes.push_back(describe(edits[i]) + ": " + why_not[i] + ": undone");
      }
      edits = std::move(still);
      if (edits.empty()) continue;
    }
    const detail::Undo undo = detail::apply_edits(grid, views(edits));
    const BatchGroups groups = group_changes(grid, cx, edits, undo);
    const std::size_t n_groups = groups.edits.size();
    std::vector<detail::GroupVerdict> verdicts(n_groups);
    std::vector<char> decided(n_groups);
    tbb::parallel_for(std::size_t(0), n_groups, [&](std::size_t gi) {
      const detail::LocalVerdict local = detail::judge_group_locally(grid, cx, groups.vertices[gi], groups.changes);
      verdicts[gi] = local.verdict;
      decided[gi] = local.decided;
    });
    std::optional<detail::SideLabels> after;
    if (std::find(decided.begin(), decided.end(), 0) != decided.end()) {
      const auto t_l = Clock::now();
      if (!labels) {  // the field before the batch, labelled with the batch taken back for a moment
        std::vector<std::pair<Id, float>> redo;
        for (const auto& [v, old] : undo.old_values) redo.push_back({v, grid.values[std::size_t(v)]});
        detail::restore(grid, undo);
        labels = detail::label_sides(grid);
        for (const auto& [v, value] : redo) grid.values[std::size_t(v)] = value;
      }
      after = detail::label_sides(grid);
      for (std::size_t gi = 0; gi < n_groups; ++gi)
        if (!decided[gi]) verdicts[gi] = detail::judge_group(grid, cx, groups.vertices[gi], groups.changes, *labels, *after);
      t_labels += ms_since(t_l);
    }
    // The groups in the order their best pair would be removed (least persistent first), so that the floor
    // keeps the most persistent.
    std::vector<std::size_t> order(groups.edits.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    auto persistence = [&](std::size_t gi) {
      double p = 0;
      for (std::size_t e : groups.edits[gi]) p = std::max(p, edits[e].persistence);
      return p;
    };
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return persistence(a) < persistence(b); });
    enum Fate : char { Keep, Drop, Wait, Remake };
    std::vector<Fate> fate(edits.size(), Keep);
    std::vector<std::string> remake_why(edits.size());  // why the attempt to be remade failed
    bool all_pass = true;
    int batch_genus = genus;
    for (std::size_t gi : order) {
      const detail::GroupVerdict& v = verdicts[gi];
      std::string why;
      if (groups.vertices[gi].empty()) why = "changed no vertex's side";
      else if (v.on_border) why = "reached the side of the grid";
      else if (!v.keeps_components) why = "split, joined or removed a component";
      else if (!v.keeps_cavities) why = "sealed or opened a cavity";
      else if (v.euler_change <= 0) why = "did not lower the genus";
      else if (batch_genus - v.euler_change < std::max(floor, 0)) why = "would lower the genus below the pairs kept";
      if (why.empty()) {
        batch_genus -= v.euler_change;
        continue;
      }
      all_pass = false;
      // Touching edits that fail together are tried one at a time: the group's most persistent edit stays in
      // this batch, the others wait for the next wave.
      const std::vector<std::size_t>& members = groups.edits[gi];
      if (members.size() > 1 && !v.on_border) {
        const std::size_t first = *std::max_element(members.begin(), members.end(), [&](std::size_t a, std::size_t b) {
          return edits[a].persistence < edits[b].persistence;
        });
        for (std::size_t e : members) fate[e] = e == first ? Keep : Wait;
        continue;
      }
      if (members.size() == 1 && edits[members[0]].attempt < last_attempt && !v.on_border && !groups.vertices[gi].empty() &&
          (v.euler_change <= 0 || !v.keeps_components || !v.keeps_cavities)) {
        fate[members[0]] = Remake;
        remake_why[members[0]] = why;
        continue;
      }
      for (std::size_t e : members) {
        fate[e] = Drop;
        failed.push_back({edits[e].side, edits[e].point});
        notes.push_back(describe(edits[e]) + " " + why + ": undone");
      }
    }
    if (all_pass) {
      labels = std::move(after);
      genus = batch_genus;
      for (auto& e : edits) kept.push_back(std::move(static_cast<FilterEdit&>(e)));
      edits.clear();
      continue;
    }
    detail::restore(grid, undo);
    std::vector<PendingEdit> rest;
    std::vector<std::size_t> remade;
    for (std::size_t i = 0; i < edits.size(); ++i) {
      if (fate[i] == Keep) rest.push_back(std::move(edits[i]));
      else if (fate[i] == Wait) waiting.push_back(std::move(edits[i]));
      else if (fate[i] == Remake) remade.push_back(i);
    }
    // On the field before this batch, in parallel (each membrane is a flood of its own).
    std::vector<std::string> why_not(remade.size());
    std::vector<char> ready(remade.size());
    tbb::parallel_for(std::size_t(0), remade.size(), [&](std::size_t r) { ready[r] = remake(edits[remade[r]], why_not[r], false); });
    for (std::size_t r = 0; r < remade.size(); ++r) {
      PendingEdit& e = edits[remade[r]];
      if (ready[r]) {
        waiting.push_back(std::move(e));
        continue;
      }
      failed.push_back({e.side, e.point});
      notes.push_back(describe(e) + " " + remake_why[remade[r]] + "; " + why_not[r] + ": undone");
    }
    edits = std::move(rest);
  }
  if (kept.empty()) return kept;
  const FilterSummary predicted{genus, now.summary.components, now.summary.cavities};
  if (floor >= 0 && genus == floor) {
    // --keep-genus reached: no pair is left to select, and the summary is known exactly without a
    // persistence run (the file path still reads its output back and checks it by persistence).
    now = Analysis{};
    now.summary = predicted;
    return kept;
  }
  const auto t_p = Clock::now();
  now = analyse(grid);
  t_persistence += ms_since(t_p);
  if (now.summary.genus != predicted.genus || now.summary.components != predicted.components ||
      now.summary.cavities != predicted.cavities)
    throw InternalError("filter: persistence finds genus " + std::to_string(now.summary.genus) + ", " +
                        std::to_string(now.summary.components) + " components, " + std::to_string(now.summary.cavities) +
                        " cavities after a batch where labels and the Euler characteristic predict " +
                        std::to_string(predicted.genus) + ", " + std::to_string(predicted.components) + ", " +
                        std::to_string(predicted.cavities));
  return kept;
}

}  // namespace

FilterSummary topology_summary(const ScalarGrid& grid) { return analyse(grid).summary; }

FilterReport filter_grid(ScalarGrid& grid, const FilterOptions& options, const ProgressFn& progress) {
  validate_grid(grid);
  if (!options.has_max_depth && !options.has_max_persistence && options.keep_genus < 0)
    throw Error("nothing to select: give --max-depth, --max-persistence or --keep-genus");
  FilterReport report;
  const auto t_start = Clock::now();
  const std::vector<float> original = grid.values;
  Analysis first = analyse(grid);
  report.timings_ms["persistence"] = ms_since(t_start);
  report.before = first.summary;
  report.R_in = first.chokes.R_in;
  report.R_out = first.chokes.R_out;
  if (options.keep_genus > report.before.genus)
    throw Error("--keep-genus " + std::to_string(options.keep_genus) + " is more than the genus of the input (" +
                std::to_string(report.before.genus) + "): nothing to remove");
  const double d_cut = options.max_depth.resolve(report.R_in), d_fill = options.max_depth.resolve(report.R_out);
  const double p_max = options.max_persistence.resolve(report.R_in + report.R_out);
  const double voxel_volume = grid.h(0) * grid.h(1) * grid.h(2);
  Analysis now = std::move(first);
  std::optional<detail::SideLabels> labels;  // labelled only when a check needs the whole grid
  double t_membranes = 0, t_edits = 0, t_labels = 0, t_persistence = 0;
  std::vector<std::string> unresolved, undone;
  std::vector<std::pair<Side, std::array<double, 3>>> failed;  // edits undone as splitting or sealing
  int idle_rounds = 0;
  bool wide_boxes = false;
  for (int round = 1; round <= options.max_rounds; ++round) {
    if (progress && !progress("filter", double(round - 1) / options.max_rounds)) throw Error("interrupted", 3);
    const std::vector<GenusPair> pairs = genus_pairs(now.chokes);
    struct Candidate {
      const GenusPair* pair;
      bool cut, fill;
      MembraneVoxels cut_voxels, fill_voxels;
    };
    std::vector<Candidate> candidates;
    for (std::size_t i = 0; i < pairs.size(); ++i) {
      if (options.keep_genus >= 0 && int(i) < options.keep_genus) continue;
      const GenusPair& p = pairs[i];
      if (options.has_max_persistence && p.persistence > p_max) continue;
      const bool cut = options.mode != FilterMode::Fill && (!options.has_max_depth || p.handle.depth <= d_cut);
      const bool fill = options.mode != FilterMode::Cut && (!options.has_max_depth || p.tunnel.depth <= d_fill);
      if (cut || fill) candidates.push_back({&p, cut, fill, {}, {}});
    }
    if (round == 1) report.selected = int(candidates.size());
    unresolved.clear();
    if (candidates.empty()) {
      undone.clear();
      break;
    }
    report.rounds = round;
    const auto t_m = Clock::now();
    // Odd rounds try the flood's contact sheet first, even rounds a plane straight across.
    const MembraneShape shape = round % 2 == 1 ? MembraneShape::Sheet : MembraneShape::Plane;
    auto failed_before = [&](const Choke& g) {
      for (const auto& [side, point] : failed)
        if (side == g.side && close_to(point, g.point, grid.voxel_size)) return true;
      return false;
    };
    // Boxes stay near the pair (a few times the box its depth asks for) until a round keeps nothing; then
    // they may grow to 16 times that (at least 64 voxels), for the few pairs left. Not to the whole grid:
    // on the noisy 256^3 cube the last 4 sub-voxel pairs flooded it for 16 s in vain, and on the grey-matter
    // map the wider cap removes the same 875 pairs with the same 3290 voxels.
    auto allowed = [&](MembraneVoxels m) {
      if (m.found && options.can_change)
        for (Id v : m.shore)
          if (!options.can_change(v)) {
            m.found = false;
            m.note = "its membrane would change voxels that may not change";
            break;
          }
      return m;
    };
    auto membrane_of = [&](const Choke& g, bool saddle_alone, MembraneShape shape) {
      LoopOptions lo = options.membrane;
      lo.max_box_radius = membrane_box_cap(grid, g, lo, wide_boxes);
      return allowed(closing_membrane_voxels(grid, g, lo, shape, saddle_alone));
    };
    tbb::parallel_for(std::size_t(0), candidates.size() * 2, [&](std::size_t job) {
      Candidate& c = candidates[job / 2];
      const bool cut = job % 2 == 0;
      if (!(cut ? c.cut : c.fill)) return;
      const Choke& g = cut ? c.pair->handle : c.pair->tunnel;
      // An edit of this generator undone before is not tried again as its saddle alone.
      (cut ? c.cut_voxels : c.fill_voxels) = membrane_of(g, !failed_before(g), shape);
    });
    t_membranes += ms_since(t_m);
    // The next of a pair's attempts that closes (see Attempt): a noise pair's pieces at its saddle (the other
    // side's only when it is as thin), its disc, then the thinning on either side.
    // Thinning only for the pairs the rounds before could not remove: its edits are wider than a disc, and
    // made early they change the field around pairs that a disc removes later.
    const int last_attempt = wide_boxes ? kOtherThin : kDisc;
    auto remake = [&](PendingEdit& e, std::string& why_not, bool again) {
      const bool other_ok = e.other && e.other->depth < 0.5 * grid.voxel_size && !failed_before(*e.other);
      std::string last;
      for (int next = again ? e.attempt : e.attempt + 1; next <= last_attempt; ++next) {
        const bool on_other = next == kOtherSaddle || next == kOtherLevelPiece || next == kOtherPinch || next == kOtherThin;
        if (on_other && !(next == kOtherThin ? e.other != nullptr : other_ok)) continue;
        const Choke& g = on_other ? *e.other : *e.first;
        MembraneVoxels m;
        if (next == kDisc) m = membrane_of(g, false, shape);
        else if (next >= kThin) m = thinned_pinch_voxels(grid, g, options.can_change);
        else {
          const MembraneShape piece = next <= kOtherSaddle       ? MembraneShape::Saddle
                                      : next <= kOtherLevelPiece ? MembraneShape::LevelPiece
                                                                 : MembraneShape::NearbyPinch;
          m = allowed(membrane_voxels(grid, g, options.membrane, piece));
        }
        if (!m.found) {
          last = m.note;
          continue;
        }
        e.attempt = next;
        e.side = g.side;
        e.depth = g.depth;
        e.point = g.point;
        e.voxels = std::move(m.shore);
        e.volume = double(e.voxels.size()) * voxel_volume;
        return true;
      }
      why_not = std::string("neither the saddles, their level pieces, the pinches near them") +
                (wide_boxes ? ", a disc nor a thinning to a pinch" : " nor a disc") + " removed the pair, and " + last;
      return false;
    };
    std::vector<PendingEdit> edits;
    for (const Candidate& c : candidates) {
      const MembraneVoxels* pick = nullptr;
      Side side = Side::Handle;
      const bool cut_ok = c.cut && c.cut_voxels.found, fill_ok = c.fill && c.fill_voxels.found;
      // A side whose edit split a component or sealed a cavity in an earlier round gives way to the other.
      const bool cut_failed = cut_ok && fill_ok && failed_before(c.pair->handle);
      const bool fill_failed = cut_ok && fill_ok && failed_before(c.pair->tunnel);
      const bool cut_smaller = c.cut_voxels.shore.size() <= c.fill_voxels.shore.size();
      if (cut_ok && (!fill_ok || (cut_failed != fill_failed ? fill_failed : cut_smaller))) pick = &c.cut_voxels;
      else if (fill_ok) pick = &c.fill_voxels, side = Side::Tunnel;
      if (!pick) {
        // No membrane closed: thinned to a pinch instead (once the rounds with discs alone are over), on the
        // side the criteria allow first.
        PendingEdit e;
        e.first = c.cut ? &c.pair->handle : &c.pair->tunnel;
        if (c.cut && c.fill) e.other = &c.pair->tunnel;
        e.attempt = kDisc;
        e.round = round;
        e.persistence = c.pair->persistence;
        std::string why_not;
        if (wide_boxes && remake(e, why_not, false)) {
          edits.push_back(std::move(e));
          continue;
        }
        const std::string why = c.cut ? c.cut_voxels.note : c.fill_voxels.note;
        unresolved.push_back("the pair at " + where(c.pair->handle) + " (handle depth " + std::to_string(c.pair->handle.depth) +
                             ", tunnel depth " + std::to_string(c.pair->tunnel.depth) + "): " + why);
        continue;
      }
      const Choke& g = side == Side::Handle ? c.pair->handle : c.pair->tunnel;
      PendingEdit e;
      e.first = &g;
      if (c.cut && c.fill) e.other = side == Side::Handle ? &c.pair->tunnel : &c.pair->handle;
      e.attempt = pick->at_saddle ? kSaddle : kDisc;
      e.side = side;
      e.round = round;
      e.depth = g.depth;
      e.persistence = c.pair->persistence;
      e.point = g.point;
      e.voxels = pick->shore;
      e.volume = double(e.voxels.size()) * voxel_volume;
      edits.push_back(std::move(e));
    }
    const auto t_e = Clock::now();
    undone.clear();
    std::vector<FilterEdit> kept =
        apply_checked(grid, std::move(edits), now, labels, remake, last_attempt, options.keep_genus, undone, failed, t_labels, t_persistence);
    t_edits += ms_since(t_e);
    // A round without progress is retried once with the other flood order before giving up.
    idle_rounds = kept.empty() ? idle_rounds + 1 : 0;
    if (idle_rounds == 1 && !wide_boxes) wide_boxes = true, idle_rounds = 0;
    for (auto& e : kept) report.edits.push_back(std::move(e));
    if (idle_rounds == 2) break;
  }
  // What the last rounds could not do (earlier failures that a later round redid are not news).
  for (auto& u : undone) report.notes.push_back(u);
  for (auto& u : unresolved) report.notes.push_back("not removed: " + u);
  report.timings_ms["membranes"] = t_membranes;
  report.timings_ms["edits and checks"] = t_edits;
  report.timings_ms["labels"] = t_labels;
  report.timings_ms["persistence after edits"] = t_persistence;
  report.after = now.summary;
  for (const FilterEdit& e : report.edits) report.max_edit_depth = std::max(report.max_edit_depth, e.depth);
  for (std::size_t v = 0; v < grid.values.size(); ++v) {
    if (grid.values[v] != original[v]) ++report.values_changed;
    if ((grid.values[v] <= 0) != (original[v] <= 0)) ++report.voxels_changed;
  }
  report.timings_ms["total"] = ms_since(t_start);
  return report;
}

}  // namespace chokeloops

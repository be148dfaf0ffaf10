// quad/attempt.cpp — one layout choice at one component, end to end: trace, build patches,
// quantize, fill, repair and measure (extract_once), and the second reading of a layout.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <optional>
#include <set>
#include <thread>

#include "quad/detail/attempt.h"
#include "quad/detail/cage.h"
#include "quad/detail/choose.h"
#include "quad/detail/patches.h"
#include "quad/detail/repair.h"

namespace genbrep {

namespace quad_detail {

// Rounds of place_irregulars (windows edited in one round share no vertex, so a cluster
// takes several); more rounds change nothing.
constexpr int kPlaceRounds = 16;

// Sequences of edits one placing may score per cage quad (PlaceSettings::max_scored), so
// that its cost grows with the cage rather than with how tangled the cage is (docs/
// quad_method.md, step 5).
constexpr double kPlaceScoredPerQuad = 300;


// Per cage vertex: an irregular vertex a singularity of `singular` explains
// (matched_irregulars at `density`).
std::vector<char> explained_vertices(const quad_detail::CageChecks& checks, const QuadCage& cage,
                                     const std::vector<quad_detail::SingularPoint>& singular,
                                     double density) {
  std::vector<int> left;
  std::vector<char> explained(cage.vertices.rows(), 0);
  const std::vector<quad_detail::Irregular> irregular = quad_detail::matched_irregulars(
      checks, cage, quad_detail::CageIncidence(cage), singular, density, &left);
  for (size_t e = 0; e < irregular.size(); ++e) explained[irregular[e].vertex] = !left[e];
  return explained;
}

// How often evened_out holds more vertices and evens out again (holding one moves its
// neighbours, which can move another's match).
constexpr int kHoldRounds = 3;

// A copy of `cage` evened out (relax_cage: 10 sweeps, half steps). With `singular`, an
// irregular vertex a singularity explained before and none explains after (moved past its
// reach, or its singularity matched to a neighbour drawn nearer) is held where it was and
// the copy evened out again from `cage`, up to kHoldRounds times
// (QuadOptions::hold_explained); how many were held goes to *held_count.
QuadCage evened_out(const quad_detail::CageChecks& checks, const QuadCage& cage,
                    const quad_detail::Dropped& dropped,
                    const std::vector<quad_detail::SingularPoint>* singular, double density,
                    int* held_count) {
  *held_count = 0;
  QuadCage relaxed = cage;
  quad_detail::relax_cage(checks, relaxed, 10, 0.5, dropped);
  if (!singular) return relaxed;
  const std::vector<char> before = explained_vertices(checks, cage, *singular, density);
  std::vector<char> held(before.size(), 0);
  for (int round = 0; round < kHoldRounds; ++round) {
    const std::vector<char> after = explained_vertices(checks, relaxed, *singular, density);
    bool more = false;
    for (size_t v = 0; v < held.size(); ++v)
      if (before[v] && !after[v] && !held[v]) held[v] = 1, more = true, ++*held_count;
    if (!more) break;
    relaxed = cage;
    quad_detail::relax_cage(checks, relaxed, 10, 0.5, dropped, &held);
  }
  return relaxed;
}

// The chain vertices of three quads on a smooth stretch of their loop the edits onto
// singularities move off it (QuadOptions::place_chain_vertices; 0 without).
int chain_vertices_left(const QuadCage& cage, const QuadOptions& options) {
  return options.place_chain_vertices ? quad_detail::chain_vertices_to_shed(cage) : 0;
}

// Irregular vertices beside a singularity of `singular` that does not explain them (a −1
// singularity drawn as a 6 and a 3, or a 5 with a 3–5 pair beside it) are moved onto it by
// local edits (place_irregulars, as `options` says: density, draw_pairs_together,
// place_edits, place_climb, place_climb_last, place_rivals, place_chain_vertices,
// settle_rings, settle_sweeps); kept in *cage and *stats if the cage stays valid with fewer
// such vertices (with place_chain_vertices, such vertices and chain vertices of three quads
// where two would do, together).
void place_onto_singularities(const quad_detail::Surface& surface,
                              const quad_detail::CageChecks& checks, QuadCage* cage,
                              QuadStats* stats, quad_detail::Messages* messages,
                              const quad_detail::Dropped& dropped, const QuadOptions& options,
                              const std::vector<quad_detail::SingularPoint>& singular,
                              double* scored) {
  const double density = options.density;
  QuadCage placed = *cage;
  quad_detail::PlaceSettings settings;
  settings.draw_pairs_together = options.draw_pairs_together;
  settings.max_edits = options.place_edits;
  settings.climb = options.place_climb;
  settings.climb_last = options.place_climb_last;
  settings.rivals = options.place_rivals;
  settings.chain_vertices = options.place_chain_vertices;
  settings.settle_rings = options.settle_rings;
  settings.settle_sweeps = options.settle_sweeps;
  settings.max_scored = kPlaceScoredPerQuad * static_cast<double>(cage->quads.rows());
  const int windows = quad_detail::place_irregulars(checks, placed, singular, density, kPlaceRounds,
                                                    settings, dropped, scored);
  if (!windows) return;
  const int off = quad_detail::irregular_off_singularities(checks, *cage, singular, density);
  const int left = quad_detail::open_squeezed(checks, placed, 24);
  const QuadStats placed_stats = quad_detail::measure_cage(placed, checks);
  const int placed_off =
      quad_detail::irregular_off_singularities(checks, placed, singular, density);
  const int shed = chain_vertices_left(*cage, options);
  const int placed_shed = chain_vertices_left(placed, options);
  std::string why;
  if (!left && !placed_stats.flipped_quads && !placed_stats.degenerate_quads &&
      placed_off + placed_shed < off + shed && cage_is_manifold(placed, &why)) {
    messages->notes.push_back(
        "component " + std::to_string(surface.component) + ": " + std::to_string(windows) +
        " local edits moved irregular vertices onto the singularities beside them (away from "
        "singularities " +
        std::to_string(off) + " → " + std::to_string(placed_off) +
        (shed || placed_shed ? "; chain vertices of three quads where two would do " +
                                   std::to_string(shed) + " → " + std::to_string(placed_shed)
                             : std::string()) +
        ")");
    const int folded = stats->collapsed_quads;
    *cage = std::move(placed);
    *stats = placed_stats;
    stats->collapsed_quads = folded;
  } else {
    messages->notes.push_back(
        "component " + std::to_string(surface.component) + ": " + std::to_string(windows) +
        " local edits onto singularities not kept (" +
        (left ? std::to_string(left) + " quads left squeezed or turned over"
         : placed_stats.flipped_quads || placed_stats.degenerate_quads
             ? std::to_string(placed_stats.flipped_quads + placed_stats.degenerate_quads) +
                   " quads flipped or degenerate"
         : placed_off + placed_shed >= off + shed
             ? "no fewer irregular vertices away from singularities" +
                   std::string(options.place_chain_vertices
                                   ? " and chain vertices of three quads where two would do"
                                   : "")
             : "not a valid 2-manifold: " + why) +
        ")");
  }
}

// The cage evened out (evened_out, holding what `singular` explains if
// QuadOptions::hold_explained), kept in *cage and *stats if it stays valid and its corners
// come closer to 90°.
void even_out_kept(const quad_detail::Surface& surface, const quad_detail::CageChecks& checks,
                   QuadCage* cage, QuadStats* stats, quad_detail::Messages* messages,
                   const quad_detail::Dropped& dropped, const QuadOptions& options,
                   const std::vector<quad_detail::SingularPoint>* singular) {
  int held = 0;
  QuadCage relaxed = evened_out(checks, *cage, dropped, options.hold_explained ? singular : nullptr,
                                options.density, &held);
  QuadStats relaxed_stats = quad_detail::measure_cage(relaxed, checks);
  if (relaxed_stats.flipped_quads || relaxed_stats.degenerate_quads ||
      relaxed_stats.mean_angle_deviation_deg >= stats->mean_angle_deviation_deg)
    return;
  if (held)
    messages->notes.push_back("component " + std::to_string(surface.component) + ": " +
                              std::to_string(held) +
                              " irregular vertices held where singularities explain them while "
                              "the cage was evened out");
  relaxed_stats.collapsed_quads = stats->collapsed_quads;
  *cage = std::move(relaxed);
  *stats = relaxed_stats;
}

// Measures a filled cage; squeezed or turned-over quads are untangled first, and that is
// reported. A valid cage is then evened out (even_out_kept). With `singular`, irregular
// vertices none of them explains are placed first (place_onto_singularities), and those
// they explain are held in the evening out, which runs QuadOptions::place_passes times;
// the placing runs again before it while some are still unexplained.
QuadStats measure_untangled(const quad_detail::Surface& surface,
                            const quad_detail::CageChecks& checks, QuadCage* cage,
                            quad_detail::Messages* messages, const quad_detail::Dropped& dropped,
                            const QuadOptions& options,
                            const std::vector<quad_detail::SingularPoint>* singular,
                            double* scored) {
  QuadStats stats = quad_detail::measure_cage(*cage, checks);
  if (stats.flipped_quads || stats.degenerate_quads) {
    const int bad = stats.flipped_quads + stats.degenerate_quads;
    int collapsed = 0;
    const int moved = quad_detail::untangle_cage(checks, *cage, 24, &collapsed, dropped);
    stats = quad_detail::measure_cage(*cage, checks);
    stats.collapsed_quads = collapsed;
    messages->warnings.push_back("component " + std::to_string(surface.component) + ": " +
                           std::to_string(bad) + " degenerate or flipped quads after filling; " +
                           std::to_string(moved) + " cage vertices around them smoothed" +
                           (collapsed ? ", " + std::to_string(collapsed) +
                                            " quads that stayed folded collapsed along a diagonal"
                                      : std::string()) +
                           ", " + std::to_string(stats.flipped_quads + stats.degenerate_quads) +
                           " left");
  }
  if (stats.flipped_quads || stats.degenerate_quads) return stats;
  // Irregular vertices the layout left in ± pairs (collapsed slivers, merged nodes) are
  // cancelled by diagonal collapses and edge rotations where the quads allow it; kept if
  // the cage stays valid.
  QuadCage cancelled = *cage;
  if (const int pairs = quad_detail::cancel_irregular_pairs(checks, cancelled, 4, dropped)) {
    const QuadStats cancelled_stats = quad_detail::measure_cage(cancelled, checks);
    std::string why;
    if (!cancelled_stats.flipped_quads && !cancelled_stats.degenerate_quads &&
        cancelled_stats.irregular_vertices < stats.irregular_vertices &&
        cage_is_manifold(cancelled, &why)) {
      messages->notes.push_back("component " + std::to_string(surface.component) + ": " +
                             std::to_string(pairs) +
                             " diagonal collapses, edge rotations or vertex splits cancelled "
                             "irregular vertices in pairs (" + std::to_string(stats.irregular_vertices) + " → " +
                             std::to_string(cancelled_stats.irregular_vertices) + ")");
      const int folded = stats.collapsed_quads;
      *cage = std::move(cancelled);
      stats = cancelled_stats;
      stats.collapsed_quads = folded;
    }
  }
  const int passes = singular ? std::max(1, options.place_passes) : 1;
  for (int pass = 0; pass < passes; ++pass) {
    if (singular &&
        (pass == 0 ||
         quad_detail::irregular_off_singularities(checks, *cage, *singular, options.density) ||
         chain_vertices_left(*cage, options)))
      place_onto_singularities(surface, checks, cage, &stats, messages, dropped, options,
                               *singular, scored);
    even_out_kept(surface, checks, cage, &stats, messages, dropped, options, singular);
  }
  return stats;
}


std::string same_layout(int c) {
  return "quad: component " + std::to_string(c) + ": the same layout as an earlier choice";
}

// Why a layout choice's attempt failed (its error's message); a cancellation or bad input
// is thrown on, as is anything not a genbrep Error.
std::string attempt_failure(const std::exception_ptr& error) {
  try {
    std::rethrow_exception(error);
  } catch (const Error& e) {
    if (e.code() == Code::Cancelled || e.code() == Code::InvalidInput) throw;
    return e.what();
  }
}


// The patches (indices into the layout's patches) that the quads of `cage` left turned
// over or degenerate came from: each such quad's centre is matched to the nearest quad
// centre of `filled`, the cage as fill_patches made it, whose patch `quad_patch` gives.
std::set<int> patches_of_bad_quads(const quad_detail::CageChecks& checks, const QuadCage& cage,
                                   const QuadCage& filled, const std::vector<int>& quad_patch) {
  auto centre = [](const QuadCage& of, int q) {
    Vec3 sum = Vec3::Zero();
    for (int k = 0; k < 4; ++k) sum += of.vertices.row(of.quads(q, k)).transpose();
    return Vec3(0.25 * sum);
  };
  std::vector<Vec3> filled_centres;
  for (int q = 0; q < filled.quads.rows(); ++q) filled_centres.push_back(centre(filled, q));
  std::set<int> patches;
  for (int q = 0; q < cage.quads.rows(); ++q) {
    Vec3 c[4];
    for (int k = 0; k < 4; ++k) c[k] = cage.vertices.row(cage.quads(q, k)).transpose();
    if (!degenerate_quad(cage, q) && !quad_detail::turned_over(checks.normals, checks.locator, c))
      continue;
    const Vec3 at = centre(cage, q);
    int nearest = -1;
    double best = 1e300;
    for (size_t f = 0; f < filled_centres.size(); ++f) {
      const double d = (filled_centres[f] - at).squaredNorm();
      if (d < best) best = d, nearest = static_cast<int>(f);
    }
    if (nearest >= 0) patches.insert(quad_patch[nearest]);  // one entry per filled quad
  }
  return patches;
}


// The notes on how an attempt's layout was mended: patches merged to balance, cusps read as
// quarter turns, arcs at 0 edges, tangles merged and filled again.
void note_layout_repairs(int c, int merged, int straightened, bool relaxed, int tangle_rounds,
                         int tangle_patches, quad_detail::Messages* messages) {
  if (merged)
    messages->notes.push_back("component " + std::to_string(c) + ": " + std::to_string(merged) +
                           " patches whose sides could not balance merged with a neighbour");
  if (straightened)
    messages->notes.push_back("component " + std::to_string(c) + ": " +
                           std::to_string(straightened) +
                           " cusp corners read as quarter turns after all, so that the "
                           "layout's sides balance");
  if (relaxed)
    messages->notes.push_back("component " + std::to_string(c) +
                           ": the layout's sides balance only with some interior arcs at 0 edges");
  if (tangle_rounds)
    messages->notes.push_back("component " + std::to_string(c) + ": " +
                           std::to_string(tangle_patches) +
                           " patches under quads the untangling left turned over merged with a "
                           "neighbour and the layout filled again (" +
                           std::to_string(tangle_rounds) + (tangle_rounds > 1 ? " rounds)" : " round)"));
}

// The traced curves with the options the rest of an attempt reads: a choice that traced the
// same curves as an earlier one with the same options gives its result.
std::size_t traced_key(const Layout& layout, const QuadOptions& options) {
  std::size_t traced = (options.fit_corners ? (options.global_corners ? 3u : 2u) : 1u) * 1000003u +
                       static_cast<std::size_t>(options.max_balance_rounds) * 2u +
                       (options.kink_nodes ? 1u : 0u);
  for (const auto& curve : layout.curves)
    for (int v : curve.vertices) traced = traced * 1000003u + static_cast<std::size_t>(v) + 1;
  return traced;
}

// The quantized layout: arcs' ends and counts, patches' sides.
std::size_t quantized_key(const PatchLayout& patches) {
  std::size_t fingerprint = patches.arcs.size();
  for (const auto& arc : patches.arcs)
    for (int value : {arc.vertices.front(), arc.vertices.back(), arc.count})
      fingerprint = fingerprint * 1000003u + static_cast<std::size_t>(value);
  for (const auto& patch : patches.patches)
    for (const auto& side : patch.sides)
      for (const auto& [a, reversed] : side)
        fingerprint = fingerprint * 1000003u + static_cast<std::size_t>(2 * a + reversed);
  return fingerprint;
}

// One attempt at one component: layout, quantization, filling, into *out. Throws
// Error{StageFailure} when the layout cannot be quantized or the filled cage is invalid,
// or when a fingerprint is in `seen` (a layout an earlier choice already had), or once
// `dropped`. Reads only its arguments, so attempts run on several threads at once.
// `costly_nodes`: the layout's Layout::costly_nodes.
void extract_once(const ComponentInputs& in, const QuadOptions& options,
                  const std::set<std::size_t>& seen, const quad_detail::Dropped& dropped,
                  const std::vector<std::pair<Vec3, double>>& costly_nodes, Reading* out) {
  const quad_detail::Surface& surface = in.surface;
  const quad_detail::CageChecks& checks = in.checks;
  const std::vector<quad_detail::SingularPoint>& singular = in.singular;
  LayoutKeys* keys = &out->keys;
  QuadCage* cage = &out->cage;
  QuadStats* stats = &out->stats;
  quad_detail::Messages* messages = &out->messages;
  AttemptWork* work = &out->work;
  const auto start = std::chrono::steady_clock::now();
  const int c = surface.component;
  quad_detail::Layout layout = quad_detail::start_layout(surface);
  layout.costly_nodes = costly_nodes;
  // The work so far: tracing, rounds of building patches, branch-and-bound nodes × arcs
  // of quantization, quads filled, sequences of edits scored placing irregular vertices
  // (weights: QuadOptions::work_per_component).
  const double triangles = static_cast<double>(surface.mesh.n_faces());
  double branching = 0, scored = 0;
  auto work_so_far = [&] {
    return triangles * (2 + layout.patch_rounds) + 15 * branching +
           850 * static_cast<double>(cage->quads.rows()) + 4 * scored;
  };
  // Also when the attempt fails part way.
  struct Tally {
    std::function<double()> so_far;
    double* total;
    ~Tally() { *total = so_far(); }
  } tally{work_so_far, &work->total};
  quad_detail::trace_separatrices(surface, layout, options, *messages);
  // The rest is deterministic in the traced curves and the options it reads: a choice
  // that traced the same curves as an earlier one with the same options gives its result.
  const std::size_t traced = traced_key(layout, options);
  keys->traced = traced;
  work->traced = work_so_far();
  GENBREP_CHECK(!seen.count(traced), Code::StageFailure, same_layout(c));
  // A layout whose sides cannot balance (a strip that would need a loop arc at 0 edges)
  // has its unbalanced patches merged with a neighbour, a few rounds at most.
  quad_detail::PatchLayout patches;
  std::string failure;
  bool relaxed = false;
  int merged = 0, straightened = 0, tangle_rounds = 0, tangle_patches = 0;
  std::set<std::pair<int, int>> merged_arcs;  // stretches merge_patch took off, by their ends
  // Each round changes the layout in a few places: only the patches there are read again.
  quad_detail::PatchReading reading;
  // A cage whose untangling leaves quads turned over (a tangle) has the
  // patches those quads came from merged with a neighbour, and the layout quantized and
  // filled again (QuadOptions::max_tangle_rounds).
  for (int repair = 0;; ++repair) {
    quad_detail::Messages layout_messages;  // of the last round only
    for (int round = 0;; ++round) {
      dropped.check();
      layout_messages = {};
      patches = quad_detail::build_patches(surface, layout, options, layout_messages, &reading);
      const bool quantized = quad_detail::quantize(patches, options, &failure, &relaxed);
      branching += static_cast<double>(patches.quantize_nodes) * static_cast<double>(patches.arcs.size());
      if (quantized) break;
      int now = 0, taken = 0;
      // Cusp readings at an unbalanced patch are taken back first (always: they are
      // readings, not changes to the layout); only where there are none are the patches
      // merged.
      const std::vector<int> unbalanced = quad_detail::unbalanced_patches(patches);
      for (int p : unbalanced) taken += quad_detail::straighten_cusps(layout, patches, p);
      if (!taken && round < options.max_balance_rounds)
        for (int p : unbalanced)
          now += quad_detail::merge_patch(surface, layout, patches, p, &merged_arcs);
      GENBREP_CHECK(now + taken > 0, Code::StageFailure,
                    "quad: component " + std::to_string(c) + ": quantization of " +
                        std::to_string(patches.patches.size()) + " patches: " + failure +
                        (merged ? " (after merging " + std::to_string(merged) +
                                      " unbalanced patches)"
                                : std::string()));
      merged += now;
      straightened += taken;
    }
    if (repair == 0) {
      // Different choices often give the same quantized layout: it is filled only once.
      const std::size_t fingerprint = quantized_key(patches);
      keys->quantized = fingerprint;
      work->quantized = work_so_far();
      GENBREP_CHECK(!seen.count(fingerprint), Code::StageFailure, same_layout(c));
    }
    dropped.check();
    quad_detail::Messages filled_messages;  // of this fill only
    std::vector<int> quad_patch;
    *cage = quad_detail::fill_patches(surface, layout, patches, filled_messages, &quad_patch);
    const QuadCage filled = *cage;
    dropped.check();
    if (const int doublets = quad_detail::remove_doublets(*cage))
      filled_messages.notes.push_back("component " + std::to_string(c) + ": " +
                                      std::to_string(doublets) +
                                      " doublets (interior vertices of two quads) removed");
    *stats = measure_untangled(surface, checks, cage, &filled_messages, dropped, options,
                               options.place_irregulars ? &singular : nullptr, &scored);
    std::set<int> tangled;  // the patches the quads left turned over came from
    if ((stats->flipped_quads || stats->degenerate_quads) && repair < options.max_tangle_rounds)
      tangled = patches_of_bad_quads(checks, *cage, filled, quad_patch);
    int now = 0;
    for (int p : tangled)
      now += quad_detail::merge_patch(surface, layout, patches, p, &merged_arcs);
    if (!now) {
      messages->append(layout_messages);
      messages->append(filled_messages);
      break;
    }
    ++tangle_rounds;
    tangle_patches += now;
  }
  note_layout_repairs(c, merged, straightened, relaxed, tangle_rounds, tangle_patches, messages);
  stats->oversized_quads = quad_detail::oversized_quads(checks, *cage, options.density, kOversized);
  if (stats->oversized_quads) {
    char text[200];
    std::snprintf(text, sizeof text,
                  "component %d: %d quads have an edge longer than %gx the target edge length "
                  "(quantization squeezed patches whose opposite sides differ)",
                  c, stats->oversized_quads, kOversized);
    messages->warnings.push_back(text);
  }
  stats->patches = static_cast<int>(patches.patches.size());
  stats->squeezed_arcs = quad_detail::squeezed_arcs(patches, in.unraised_density);
  stats->separatrices = layout.separatrices;
  stats->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (layout.dropped_traces)
    messages->notes.push_back("component " + std::to_string(c) + ": " +
                           std::to_string(layout.dropped_traces) + " traces dropped");
  std::string why;
  GENBREP_CHECK(cage_is_manifold(*cage, &why), Code::StageFailure,
                "quad: component " + std::to_string(c) + ": the cage is not a valid 2-manifold: " + why);
  GENBREP_CHECK(stats->flipped_quads == 0 && stats->degenerate_quads == 0, Code::StageFailure,
                "the cage has " + std::to_string(stats->flipped_quads) + " flipped and " +
                    std::to_string(stats->degenerate_quads) + " degenerate quads");
  // The irregular vertices no singularity explains, each priced within kOffNodeRadius ×
  // its reach (in kSingularReach units: local target edges or its own edges) if read again.
  out->unexplained.clear();
  for (const quad_detail::Irregular& x :
       count_off_singularities(checks, *cage, singular, options.density, stats))
    out->unexplained.push_back(
        {x.point, kOffNodeRadius * x.reach / quad_detail::kSingularReach});
  stats->size_field_quads = in.asked;
}

// QuadOptions::off_node_price: the layout of `options` traced and read again, the nodes
// near the irregular vertices the first reading left away from singularities (its
// `unexplained`) priced higher; the second cage is kept in *first (cage, stats, messages)
// if better_second_reading says so, and the work of both is counted. A second attempt that
// fails leaves the first as it was.
void read_off_nodes_again(const ComponentInputs& in, const QuadOptions& options,
                          const quad_detail::Dropped& dropped, Reading* first) {
  Reading again;
  std::string failure;
  try {
    extract_once(in, options, {}, dropped, first->unexplained, &again);
  } catch (const Error& e) {
    if (e.code() != Code::StageFailure) throw;
    failure = e.what();
  }
  first->work.total += again.work.total;
  dropped.check();
  QuadStats* stats = &first->stats;
  quad_detail::Messages* messages = &first->messages;
  const int c = in.surface.component, before = stats->irregular_off_singularities;
  const std::string head = "component " + std::to_string(c) + ": the layout read again with " +
                           "the nodes near its " + std::to_string(before) +
                           " irregular vertices away from singularities priced higher";
  if (!failure.empty()) {
    messages->notes.push_back(head + " failed (" + failure + "); the first reading kept");
    return;
  }
  const int after = again.stats.irregular_off_singularities;
  if (!quad_detail::better_second_reading(again.stats, *stats)) {
    messages->notes.push_back(head + ": " + std::to_string(after) +
                              " away from singularities, not better; the first reading kept");
    return;
  }
  again.messages.notes.push_back(head + ": " + std::to_string(before) + " → " +
                                 std::to_string(after) + " away from singularities");
  first->cage = std::move(again.cage);
  *stats = again.stats;
  *messages = std::move(again.messages);
  first->unexplained = std::move(again.unexplained);
}

}  // namespace quad_detail

}  // namespace genbrep

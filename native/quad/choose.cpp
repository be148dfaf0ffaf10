// quad/choose.cpp — extract_cages: per organic component, layout choices tried and the best
// cage kept (quad/quad.h).
#include "quad/quad.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <functional>
#include <optional>
#include <set>
#include <thread>

#include "quad/detail/cage.h"
#include "quad/detail/attempt.h"
#include "quad/detail/choose.h"
#include "quad/detail/patches.h"
#include "quad/detail/repair.h"

namespace genbrep {
namespace quad_detail {
namespace {

// A step's warnings go to the result's diagnostics, its notes to its notes.
void add_messages(const quad_detail::Messages& messages, QuadResult* out) {
  out->diagnostics.insert(out->diagnostics.end(), messages.warnings.begin(), messages.warnings.end());
  out->notes.insert(out->notes.end(), messages.notes.begin(), messages.notes.end());
}

// How often the component's triangles are split for tracing (kTraceEdgesPerCageEdge): the
// mean target size over the mean length of its edges.
int refine_levels(const quad_detail::Surface& s, const QuadOptions& options) {
  double size = 0, length = 0;
  int edges = 0;
  for (int v : s.vertices) size += s.vertex_size[v];
  size /= std::max<size_t>(1, s.vertices.size()) * options.density;
  for (auto e : s.mesh.edges()) {
    const auto h = s.mesh.halfedge_handle(e, 0);
    if (!s.in(s.face(h.idx())) && !s.in(s.face(h.idx() ^ 1))) continue;
    length += (s.point[s.to(h.idx())] - s.point[s.from(h.idx())]).norm();
    ++edges;
  }
  if (!edges || length <= 0) return 0;
  int levels = 0;
  for (double span = size / (length / edges); span < kTraceEdgesPerCageEdge &&
                                              levels < options.max_refine_levels;
       span *= 2)
    ++levels;
  return levels;
}

// The quads the size field asks for on the component at `density`: Σ area / (size_u ·
// size_v) over its triangles, times density² (QuadStats::size_field_quads).
double size_field_quads(const quad_detail::Surface& s, double density) {
  double quads = 0;
  for (auto f : s.mesh.faces())
    if (s.in(f.idx())) quads += s.face_quads(f.idx());
  return quads * (density * density);
}

// The factor (≥ 1) by which the density must rise for the component's cage to have
// `vertices_per_singular_quarter` vertices per quarter turn of traced singularity index.
double density_raise(const quad_detail::Surface& s, const QuadOptions& options) {
  if (options.vertices_per_singular_quarter <= 0) return 1;
  int quarters = 0;
  for (const Singularity& sing : s.field.singularities)
    if (sing.component == s.component && !sing.on_boundary) quarters += std::abs(sing.index);
  const double quads = size_field_quads(s, options.density);
  const double wanted = options.vertices_per_singular_quarter * quarters;
  return quads > 0 && quads < wanted ? std::sqrt(wanted / quads) : 1.0;
}

// Whether a cage meets the quality targets (interior valence 4 ≥ 95%, boundary valence 3
// ≥ 90%, mean corner deviation ≤ 12°).
bool meets_targets(const QuadStats& s) {
  return s.interior_valence4_fraction() >= 0.95 && s.boundary_valence3_fraction() >= 0.90 &&
         s.mean_angle_deviation_deg <= 12.0;
}

// Meets them with a margin (valence 4 ≥ 98%, valence 3 ≥ 95%, ≤ 8°), has no irregular
// vertex away from the field's singularities and follows the size field's density: no
// other layout choice is tried.
bool comfortably_meets_targets(const QuadStats& s) {
  return s.interior_valence4_fraction() >= 0.98 && s.boundary_valence3_fraction() >= 0.95 &&
         s.mean_angle_deviation_deg <= 8.0 && s.irregular_off_singularities == 0 &&
         s.size_field_miss() == 0;
}



void extract_component(const TriMesh& design, const Partition& partition, const CrossField& field,
                       const QuadOptions& options, int c, QuadResult* out);
}  // namespace
}  // namespace quad_detail

QuadResult extract_cages(const TriMesh& design, const Partition& partition,
                         const CrossField& field, const QuadOptions& options,
                         const Context& context) {
  GENBREP_CHECK(partition.face_component.size() == design.n_faces() &&
                    field.direction.rows() == static_cast<Eigen::Index>(design.n_faces()),
                Code::InvalidInput, "quad: the partition or field does not match the design (" +
                    std::to_string(design.n_faces()) + " triangles)");
  GENBREP_CHECK(options.density > 0, Code::InvalidInput, "quad: density must be positive");
  QuadResult result;
  for (int c = 0; c < partition.organic_components; ++c) {
    context.step("quad", double(c) / std::max(1, partition.organic_components));
    try {
      quad_detail::extract_component(design, partition, field, options, c, &result);
    } catch (const Error& e) {
      if (e.code() == Code::Cancelled || e.code() == Code::InvalidInput) throw;
      result.failures.push_back({c, e.what()});
      result.diagnostics.push_back("component " + std::to_string(c) + ": no cage: " + e.what());
    }
  }
  context.step("quad", 1.0);
  return result;
}


namespace quad_detail {
// Two cages whose density misses (QuadStats::size_field_miss, a log ratio) differ by at
// most this are even on density.
constexpr double kEvenDensityMiss = 0.1;
// The ranking (better_cage, detail/choose.h), each count with a margin within which two
// cages are even, so that a small gain on one count does not outweigh the ones after it:
// a cage within 0.8–1.2× the quads its size field asks for beats one outside, and of two
// outside the nearer; then fewer squeezed arcs (a row of patches gutted to balance);
// then fewer irregular vertices away from singularities (none against some always wins,
// otherwise within 15% or 2 even); then fewer skewed quads, then fewer oversized quads
// (each within 20% or 5 even); then fewer irregular vertices (within 5% even); then the
// smaller mean corner deviation.
bool better_cage(const QuadStats& a, const QuadStats& b) {
  return better_cage(a, meets_targets(a), b, meets_targets(b));
}
namespace {
// Whether counts x and y differ by more than `at_least` and `share` of the larger: not even.
bool uneven(int x, int y, double at_least, double share) {
  return std::abs(x - y) > std::max(at_least, share * std::max(x, y));
}
}  // namespace
bool better_cage(const QuadStats& a, bool meets_a, const QuadStats& b, bool meets_b) {
  if (meets_a != meets_b) return meets_a;
  if ((a.collapsed_quads > 0) != (b.collapsed_quads > 0)) return a.collapsed_quads == 0;
  const double miss_a = a.size_field_miss(), miss_b = b.size_field_miss();
  if (meets_a && (miss_a == 0) != (miss_b == 0)) return miss_a == 0;
  if (meets_a && std::abs(miss_a - miss_b) > kEvenDensityMiss) return miss_a < miss_b;
  if (meets_a && a.squeezed_arcs != b.squeezed_arcs) return a.squeezed_arcs < b.squeezed_arcs;
  const int off_a = a.irregular_off_singularities, off_b = b.irregular_off_singularities;
  if (meets_a && off_a != off_b && (std::min(off_a, off_b) == 0 || uneven(off_a, off_b, 1, 0.15)))
    return off_a < off_b;
  if (meets_a && uneven(a.skewed_quads, b.skewed_quads, 5, 0.2))
    return a.skewed_quads < b.skewed_quads;
  if (meets_a && uneven(a.oversized_quads, b.oversized_quads, 5, 0.2))
    return a.oversized_quads < b.oversized_quads;
  if (meets_a && uneven(a.irregular_vertices, b.irregular_vertices, 0, 0.05))
    return a.irregular_vertices < b.irregular_vertices;
  return a.mean_angle_deviation_deg < b.mean_angle_deviation_deg;
}

// A second reading is kept only if it leaves fewer irregular vertices off singularities
// (what it is for) and is the better cage: better_cage alone can prefer one with more of
// them for a quad the first reading had collapsed.
bool better_second_reading(const QuadStats& second, const QuadStats& first) {
  return second.irregular_off_singularities < first.irregular_off_singularities &&
         better_cage(second, first);
}
namespace {

// A layout choice: how it differs from the requested layout (empty for that one), and the
// options it runs with.
struct Variant {
  std::string what;
  QuadOptions options;
};

// The layout choices of a component in the order they are tried.
std::vector<Variant> layout_choices(const QuadOptions& options) {
  std::vector<Variant> variants;
  const std::pair<const char*, std::function<void(QuadOptions&)>> layouts[] = {
      {"", [](QuadOptions&) {}},
      {"singularity pairs within 2x the cancel distance cancelled",
       [](QuadOptions& o) { o.pair_cancel_distance *= 2; }},
      {"separatrices joined to nearly parallel curves",
       [](QuadOptions& o) { o.join_parallel = !o.join_parallel; }},
      {"singularity pairs within 2x the cancel distance cancelled, separatrices joined to "
       "nearly parallel curves",
       [](QuadOptions& o) { o.pair_cancel_distance *= 2, o.join_parallel = !o.join_parallel; }},
      {"separatrices crossing", [](QuadOptions& o) { o.cross_separatrices = !o.cross_separatrices; }},
      {"singularities within 2x the absorb distance left to the boundary",
       [](QuadOptions& o) { o.boundary_absorb_distance *= 2; }},
      {"both distances doubled",
       [](QuadOptions& o) { o.pair_cancel_distance *= 2, o.boundary_absorb_distance *= 2; }},
      {"both distances doubled, separatrices crossing", [](QuadOptions& o) {
         o.pair_cancel_distance *= 2, o.boundary_absorb_distance *= 2;
         o.cross_separatrices = !o.cross_separatrices;
       }}};
  // Merging unbalanced patches is tried only after every choice without it (but joins and
  // the requested layout).
  for (bool balance : {false, true})
    for (const auto& [what, change] : layouts)
      for (int corners : {0, 1, 2}) {  // as asked; all at once or patch by patch; re-read
        QuadOptions o = options;
        change(o);
        if (corners == 1 && !o.fit_corners) continue;
        if (corners == 1) o.global_corners = !o.global_corners;
        if (corners == 2) o.fit_corners = !o.fit_corners;
        const bool flip_corners = corners != 0;
        std::string name = what;
        if (flip_corners) {
          name += name.empty() ? "" : ", ";
          name += corners == 1 ? (o.global_corners ? "corners chosen for all patches at once"
                                                   : "corners fitted patch by patch")
                  : o.fit_corners ? "corners fitted as rectangles"
                                  : "corners re-read one at a time";
        }
        // Joins leave layouts that often balance only once a join is taken back (merging
        // an unbalanced patch drops its shortest arc, the link): they are tried with
        // merging in the first pass already, and not again.
        if (o.join_parallel && balance) continue;
        if (balance) {
          name += name.empty() ? "" : ", ";
          name += "unbalanced patches merged";
        } else if (!o.join_parallel && !(what[0] == '\0' && corners != 2)) {
          // The requested layout (corners chosen either way) merges unbalanced patches too:
          // a layout one small patch from balancing is otherwise lost to a sparser choice.
          o.max_balance_rounds = 0;
        }
        variants.push_back({name, o});
      }
  // The requested layout with its arrivals recorded the other way (QuadOptions::
  // arrival_chord) comes second, so that it runs beside the requested one and is compared
  // with it on every component (min_choices_after_meeting).
  {
    QuadOptions o = variants[0].options;
    o.arrival_chord = !o.arrival_chord;
    variants.insert(variants.begin() + 1,
                    {o.arrival_chord ? "arrivals recording their chord"
                                     : "arrivals recording the field's direction",
                     o});
  }
  return variants;
}

// One layout choice's attempt as the search takes it.
struct Attempt : Reading {
  std::exception_ptr error;
  // A cage that meets the targets but for its corner angles is squared before it is
  // judged (the targets are the output cage's, and squaring makes it): the copy, if it
  // came closer to 90°. Choices are still compared on the angles before squaring.
  std::optional<Squared> squared;
  bool squaring_tried = false;
  bool dropped = false;  // it ended in an error after it was told to stop
  bool needs_squaring() const {
    QuadStats square = stats;
    square.mean_angle_deviation_deg = 0;
    return !error && !meets_targets(stats) && meets_targets(square);
  }
  QuadStats judged() const {  // what the targets are checked on
    QuadStats judged = stats;
    if (squared) judged.mean_angle_deviation_deg = squared->mean_deg;
    return judged;
  }
};

// The search among a component's layout choices (extract_component): the component
// refined for tracing, the attempts run in batches on threads and taken in order, the best
// cage kept and reported, or the fallback cage.
class ComponentSearch {
 public:
  ComponentSearch(const TriMesh& design, const Partition& partition, const CrossField& field,
                  const QuadOptions& options, int c, QuadResult* out);
  void run();

 private:
  bool out_of_work(size_t tried);
  void keep(size_t k, Attempt& a, bool meets);
  bool wants_second_reading(size_t k, const Attempt& a);
  void read_again(size_t k, Attempt* a, const quad_detail::Dropped& dropped);
  void attempt(size_t k, const std::set<std::size_t>& seen, Attempt* a, const quad_detail::Dropped& dropped, bool first_only = false);
  void search();
  void try_without_kinks();
  void report_kept();
  void fall_back();

  const QuadOptions& options;
  const int c;
  QuadResult* out;
  std::vector<Variant> variants;
  const quad_detail::Surface coarse;
  double asked = 0;
  int levels = 0;
  quad_detail::RefinedDesign refined;
  std::optional<quad_detail::Surface> refined_surface;
  const quad_detail::Surface* surface_ = nullptr;  // the refined surface, or coarse
  std::optional<quad_detail::CageChecks> checks_;
  int triangles = 0;  // of the (refined) component
  std::vector<quad_detail::SingularPoint> singular;  // the component's field singularities
  std::set<std::size_t> seen_layouts;
  std::string first_failure, requested_failure;
  int best = -1;
  QuadCage best_cage;
  QuadStats best_stats;
  bool best_meets = false, best_squaring_tried = false;
  std::optional<Squared> best_squared;
  // The requested layout's cage, if it was valid (as judged: its angles after squaring).
  std::optional<QuadStats> requested_stats;
  quad_detail::Messages best_messages;
  // Once a cage meets the targets, more choices are tried only within a work budget:
  // choices × the (refined) component's triangles (QuadOptions::work_after_meeting), but
  // at least min_choices_after_meeting, counting only choices that traced a new layout (a
  // repeated one stops after tracing).
  int first_meeting = -1, tried_after_meeting = 0;
  int choices_after_meeting = 0;
  double work_spent = 0;
  int threads = 1;
  std::optional<ComponentInputs> inputs;
  bool pair_readings = false;
};

ComponentSearch::ComponentSearch(const TriMesh& design, const Partition& partition,
                                 const CrossField& field, const QuadOptions& options, int c,
                                 QuadResult* out)
    : options(options), c(c), out(out), variants(layout_choices(options)),
      coarse(design, partition, field, c) {
  // Raise the density where singularities are dense (QuadOptions::vertices_per_singular_quarter).
  const double raise = density_raise(coarse, options);
  if (raise > 1) {
    char text[160];
    std::snprintf(text, sizeof text,
                  "component %d: density raised %.2gx so that its singularities are at most "
                  "1 in %.0f cage vertices",
                  c, raise, options.vertices_per_singular_quarter);
    out->notes.push_back(text);
    for (auto& variant : variants) variant.options.density *= raise;
  }
  asked = size_field_quads(coarse, variants[0].options.density);
  const auto preparing = std::chrono::steady_clock::now();
  levels = refine_levels(coarse, variants[0].options);
  refined = quad_detail::refine_component(design, partition, field, c, levels);
  const bool finer = refined.mesh.n_faces() > 0;  // else: nothing needed splitting
  if (finer) refined_surface.emplace(refined.mesh, refined.partition, refined.field, c);
  surface_ = refined_surface ? &*refined_surface : &coarse;
  const quad_detail::Surface& surface = *surface_;
  // Checks run on the unrefined component: the same surface, a sixteenth of the triangles.
  checks_.emplace(coarse);
  for (auto f : surface.mesh.faces()) triangles += surface.in(f.idx());
  if (finer) {
    char text[200];
    std::snprintf(text, sizeof text,
                  "component %d: refined round its singularities%s for tracing (%d triangles) "
                  "in %.1f s",
                  c, levels > 0 ? (" and " + std::to_string(1 << (2 * levels)) + "x").c_str() : "",
                  triangles,
                  std::chrono::duration<double>(std::chrono::steady_clock::now() - preparing).count());
    out->notes.push_back(text);
  }
  // The component's field singularities (QuadStats).
  for (const auto& point : field.singularities)
    if (point.component == c) singular.push_back({coarse.point[point.vertex], point.index});
  // Once a cage meets the targets, more choices are tried only within a work budget:
  // choices × the (refined) component's triangles (QuadOptions::work_after_meeting), but
  // at least min_choices_after_meeting, counting only choices that traced a new layout (a
  // repeated one stops after tracing).
  choices_after_meeting =
      std::max(options.min_choices_after_meeting,
               static_cast<int>(options.work_after_meeting / std::max(1, triangles)));
  // Choices run in batches of `threads` at once (each attempt reads only shared constant
  // data); their results are taken in order, exactly as if they had run one after another:
  // a layout an earlier choice of the same batch already had counts as repeated, and a
  // batch's later results are dropped once the search would have stopped.
  threads = std::max(
      1, options.parallel_choices > 0
             ? options.parallel_choices
             : std::min(4, static_cast<int>(std::thread::hardware_concurrency())));
  inputs.emplace(ComponentInputs{surface, *checks_, singular, asked, options.density});
  // QuadOptions::pair_second_readings: the first batch holds the requested layout and its
  // pair (its arrivals flipped), however many threads there are (not where the work allows
  // the requested one only: work_per_component 0).
  pair_readings =
      options.pair_second_readings && options.work_per_component > 0 && variants.size() >= 2;
}

void ComponentSearch::run() {
  search();
  try_without_kinks();
  if (best >= 0)
    report_kept();
  else
    fall_back();
}

// The work the attempts spent, summed in choice order (QuadOptions::work_per_component).
bool ComponentSearch::out_of_work(size_t tried) {
  if (tried == 0 || work_spent < options.work_per_component) return false;
  char text[200];
  std::snprintf(text, sizeof text,
                "component %d: stopped trying layout choices after %.3g units of work "
                "(work_per_component), %zu of %zu tried",
                c, work_spent, tried, variants.size());
  out->diagnostics.push_back(text);
  return true;
}

// Choice k's attempt becomes the cage kept so far.
void ComponentSearch::keep(size_t k, Attempt& a, bool meets) {
  best = static_cast<int>(k);
  best_cage = std::move(a.cage);
  best_stats = a.stats;
  best_meets = meets;
  best_squared = std::move(a.squared);
  best_squaring_tried = a.squaring_tried;
  best_messages = std::move(a.messages);
}

// Choice k's second reading (read_off_nodes_again), where its first left irregular
// vertices away from singularities: off_node_share of them, or off_node_count.
bool ComponentSearch::wants_second_reading(size_t k, const Attempt& a) {
  const QuadOptions& o = variants[k].options;
  const int off = a.stats.irregular_off_singularities;
  return !a.error && o.off_node_price > 0 && off > 0 &&
         (off >= o.off_node_share * a.stats.irregular_vertices ||
          (o.off_node_count > 0 && off >= o.off_node_count));
}

void ComponentSearch::read_again(size_t k, Attempt* a, const quad_detail::Dropped& dropped) {
  if (!wants_second_reading(k, *a)) return;
  try {
    read_off_nodes_again(*inputs, variants[k].options, dropped, a);
  } catch (...) {
    a->error = std::current_exception();
    a->dropped = dropped.stopped();
  }
}

// Choice k's attempt: its first reading, and its second unless `first_only`.
void ComponentSearch::attempt(size_t k, const std::set<std::size_t>& seen, Attempt* a, const quad_detail::Dropped& dropped, bool first_only) {
  try {
    extract_once(*inputs, variants[k].options, seen, dropped, {}, a);
  } catch (...) {
    a->error = std::current_exception();
    a->dropped = dropped.stopped();
    return;
  }
  if (!first_only) read_again(k, a, dropped);
}

// The layout choices in batches, until the search stops.
void ComponentSearch::search() {
  const quad_detail::CageChecks& checks = *checks_;
  bool stop = false;
  for (size_t k = 0; k < variants.size() && !stop;) {
    if (out_of_work(k)) break;
    if (first_meeting >= 0 && tried_after_meeting >= choices_after_meeting) break;
    const bool pair = pair_readings && k == 0;
    const size_t batch =
        std::min(variants.size() - k, static_cast<size_t>(pair ? std::max(threads, 2) : threads));
    std::vector<Attempt> attempts(batch);
    // The layouts seen before the batch, as every attempt of it reads them (the search
    // adds to seen_layouts while later attempts still run).
    const std::set<std::size_t> seen_before = seen_layouts;
    // Results are taken as their attempts end, in order; once the search stops, the
    // batch's later attempts are dropped rather than run for results the search would not
    // look at. Also when a result throws: every worker is told and joined.
    std::atomic<bool> drop{false};
    std::vector<std::thread> workers;
    struct JoinAll {
      std::atomic<bool>& drop;
      std::vector<std::thread>& workers;
      ~JoinAll() {
        drop = true;
        for (auto& worker : workers)
          if (worker.joinable()) worker.join();
      }
    } join_all{drop, workers};
    // On one thread the requested layout's pair runs after the requested layout, on this one.
    for (size_t i = 1; i < batch && threads > 1; ++i)
      workers.emplace_back([&, i, first = k, only = pair && i == 1] {
        attempt(first + i, seen_before, &attempts[i], quad_detail::Dropped(&drop), only);
        quad_detail::release_quantize_thread();
      });
    attempt(k, seen_before, &attempts[0], quad_detail::Dropped(), pair);
    if (pair) {
      // The pair's first readings, then their second readings (pair_second_readings).
      if (threads > 1)
        workers[0].join();
      else
        attempt(k + 1, seen_before, &attempts[1], quad_detail::Dropped(), true);
      bool again[2];
      for (int i : {0, 1}) {
        const Attempt &a = attempts[i], &other = attempts[1 - i];
        again[i] = wants_second_reading(k + i, a);
        if (!again[i] || other.error || other.stats.irregular_off_singularities) continue;
        // Beside one that left none: only where, with none left and the corner angles
        // even, it would be kept over that one.
        QuadStats none_left = a.stats;
        none_left.irregular_off_singularities = 0;
        none_left.mean_angle_deviation_deg = other.stats.mean_angle_deviation_deg;
        again[i] = quad_detail::better_cage(none_left, meets_targets(a.stats), other.stats,
                                            meets_targets(other.stats));
        if (!again[i])
          out->notes.push_back(
              "component " + std::to_string(c) + ": " +
              (i == 0 ? "the requested layout" : "the layout with " + variants[k + 1].what) +
              " not read again: " +
              (i == 0 ? "the layout with " + variants[k + 1].what : "the requested one") +
              " left no irregular vertex away from singularities, and would be kept even if "
              "a second reading left none (pair_second_readings)");
      }
      if (again[1] && threads > 1)
        workers[0] = std::thread([&, first = k] {
          read_again(first + 1, &attempts[1], quad_detail::Dropped(&drop));
          quad_detail::release_quantize_thread();
        });
      if (again[0]) read_again(k, &attempts[0], quad_detail::Dropped());
      if (again[1] && threads == 1) read_again(k + 1, &attempts[1], quad_detail::Dropped());
    }
    // The batch's first cage needs squaring before it is judged, and would end the search
    // if it then meets the targets (no choice is tried after meeting): the others are
    // dropped and it is squared on every thread. If it still misses, the others that had
    // ended before the drop are taken as they are, and the next batch starts at the first
    // one that was cut short.
    size_t taken = batch;
    for (size_t i = 0; i < taken && !stop; ++i, ++k) {
      // The requested layout's pair is taken whatever the work (pair_second_readings).
      if (i > 0 && ((first_meeting >= 0 && tried_after_meeting >= choices_after_meeting) ||
                    (!(pair && i == 1) && out_of_work(k)))) {
        stop = true;
        break;
      }
      if (i > 0 && i - 1 < workers.size() && workers[i - 1].joinable()) workers[i - 1].join();
      Attempt& a = attempts[i];
      // Repeated layouts, as the sequential search sees them, and the work it would spend.
      bool grew = false, repeated = false;
      double work = a.work.total;
      if (a.keys.traced) {
        repeated = seen_layouts.count(*a.keys.traced) > 0;
        if (repeated) work = a.work.traced;
        if (!repeated) grew = seen_layouts.insert(*a.keys.traced).second;
      }
      if (!repeated && a.keys.quantized) {
        repeated = !seen_layouts.insert(*a.keys.quantized).second;
        if (repeated) work = a.work.quantized;
        grew |= !repeated;
      }
      work_spent += work;
      std::string failure;
      if (repeated) {
        failure = same_layout(c);
      } else if (a.error) {
        failure = attempt_failure(a.error);
      }
      if (!failure.empty()) {
        tried_after_meeting += first_meeting >= 0 && grew;
        if (first_failure.empty()) first_failure = failure;
        if (k == 0) requested_failure = failure;
        continue;
      }
      tried_after_meeting += first_meeting >= 0;
      if (a.needs_squaring()) {
        int squaring_threads = i + 1 == batch ? threads : 1;  // the batch's others still run
        if (i == 0 && batch > 1 && first_meeting < 0 && choices_after_meeting == 0) {
          drop = true;
          for (auto& worker : workers)
            if (worker.joinable()) worker.join();
          taken = 1;
          while (taken < batch && !attempts[taken].dropped) ++taken;
          squaring_threads = threads;
        }
        a.squared = square_copy(checks, variants[k].options.density, squaring_threads, a.cage,
                                a.stats);
        a.squaring_tried = true;
      }
      const QuadStats judged = a.judged();
      const bool meets = meets_targets(judged);
      if (k == 0) requested_stats = judged;
      // Collapsed quads mean the layout itself was broken there: such a cage ranks below
      // every collapse-free one (better_cage), but a valid field-aligned cage still beats the
      // fallback, which is not aligned at all.
      if (best < 0 || quad_detail::better_cage(a.stats, meets, best_stats, best_meets))
        keep(k, a, meets);
      if (comfortably_meets_targets(judged) && !judged.collapsed_quads && best == int(k))
        stop = true;
      if (first_meeting < 0 && meets) first_meeting = static_cast<int>(k);
    }
  }
}

void ComponentSearch::try_without_kinks() {
  // Last field-aligned resort before the fallback cage: the requested layout without kink
  // nodes (QuadOptions::kink_nodes). Their corners can leave a layout that no integer counts
  // balance even after merges, and where every choice the component's work allowed failed so, the layout as it is
  // read without them still gives a field-aligned cage. One more attempt, on this thread.
  if (best < 0 && variants[0].options.kink_nodes) {
    Variant plain = variants[0];
    plain.what = "no quarter turn along a curve read as a node";
    plain.options.kink_nodes = false;
    variants.push_back(plain);
    Attempt a;
    attempt(variants.size() - 1, {}, &a, quad_detail::Dropped());
    if (a.error)
      attempt_failure(a.error);  // a failure here leaves the fallback cage
    else
      keep(variants.size() - 1, a, meets_targets(a.judged()));
  }
}

// The kept cage squared, counted and reported.
void ComponentSearch::report_kept() {
  const quad_detail::CageChecks& checks = *checks_;
  add_messages(best_messages, out);
  if (best > 0) {
    std::string why = "the requested one failed: " + requested_failure;
    if (requested_stats && !meets_targets(*requested_stats)) {
      char text[240];
      std::snprintf(text, sizeof text,
                    "the requested one missed the targets: %.1f%% interior valence 4, %.1f%% "
                    "boundary valence 3, %.1f° mean corner deviation",
                    100 * requested_stats->interior_valence4_fraction(),
                    100 * requested_stats->boundary_valence3_fraction(),
                    requested_stats->mean_angle_deviation_deg);
      why = text;
    } else if (requested_stats) {
      char text[240];
      std::snprintf(text, sizeof text,
                    "%d irregular vertices (%d away from singularities), %.1f° mean corner "
                    "deviation, %d collapsed quads; the requested one: %d (%d), %.1f°, %d",
                    best_stats.irregular_vertices, best_stats.irregular_off_singularities,
                    best_stats.mean_angle_deviation_deg, best_stats.collapsed_quads,
                    requested_stats->irregular_vertices,
                    requested_stats->irregular_off_singularities,
                    requested_stats->mean_angle_deviation_deg, requested_stats->collapsed_quads);
      why = text;
    }
    out->notes.push_back("component " + std::to_string(c) +
                         ": the cage uses the layout with " + variants[best].what + " (" + why +
                         ")");
  }
  if (best_squared)
    keep_squared(std::move(*best_squared), c, &best_cage, &best_stats, &out->notes);
  else if (!best_squaring_tried)
    square_kept(checks, variants[best].options.density, c, threads, &best_cage, &best_stats,
                &out->notes);
  // Counted again on the squared cage: squaring moves the vertices round an irregular
  // one, and with them its mean edge, so its reach.
  count_off_singularities(checks, best_cage, singular, variants[best].options.density,
                          &best_stats);
  if (!meets_targets(best_stats)) {
    char text[240];
    std::snprintf(text, sizeof text,
                  "component %d: no layout choice met the targets; the cage is the best "
                  "field-aligned one (%.1f%% interior valence 4, %.1f%% boundary valence 3, "
                  "%.1f° mean corner deviation, %d quads collapsed along a diagonal)",
                  c, 100 * best_stats.interior_valence4_fraction(),
                  100 * best_stats.boundary_valence3_fraction(),
                  best_stats.mean_angle_deviation_deg, best_stats.collapsed_quads);
    out->diagnostics.push_back(text);
  }
  out->cages.push_back(std::move(best_cage));
  out->stats.push_back(best_stats);
}

void ComponentSearch::fall_back() {
  const quad_detail::CageChecks& checks = *checks_;
  const quad_detail::Surface& surface = *surface_;
  // Last resort: the split coarse remesh, valid by construction but not field-aligned.
  // A coarse remesh of a thin part can fold; then it is made finer.
  double size = 0;
  for (int v : surface.vertices) size += surface.vertex_size[v];
  size /= std::max<size_t>(1, surface.vertices.size()) * options.density;
  const auto start = std::chrono::steady_clock::now();
  QuadCage cage;
  QuadStats stats;
  double scale = 0;
  bool valid = false;
  quad_detail::Messages untangled;  // of the rejected tries too: only the last one's is kept
  for (double factor : {2.0, 1.5, 1.0, 0.75}) {
    cage = quad_detail::fallback_cage(coarse, factor * size);
    untangled = {};
    stats = measure_untangled(surface, checks, &cage, &untangled, quad_detail::Dropped(), options);
    scale = factor;
    std::string why;
    valid = !stats.flipped_quads && !stats.degenerate_quads && cage_is_manifold(cage, &why);
    if (valid) break;
  }
  stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  stats.fallback = true;
  GENBREP_CHECK(valid, Code::StageFailure,
                first_failure + " (and " + std::to_string(variants.size() - 1) +
                    " alternative layouts and the fallback cage failed too)");
  char scale_text[16];
  std::snprintf(scale_text, sizeof scale_text, "%.2g", scale);
  out->diagnostics.push_back(
      "component " + std::to_string(c) + ": no field-aligned layout gave a valid cage (" +
      first_failure + "); the cage is the FALLBACK: a coarse remesh (edge " + scale_text +
      " x the target) split into quads, not aligned with the field, "
      "with irregular vertices wherever triangles could not be paired");
  add_messages(untangled, out);
  square_kept(checks, variants[0].options.density / scale, c, threads, &cage, &stats, &out->notes);
  count_off_singularities(checks, cage, singular, variants[0].options.density, &stats);
  out->cages.push_back(std::move(cage));
  stats.size_field_quads = asked;
  out->stats.push_back(stats);
}

// One component. The layout depends on a few discrete choices (how corners are read,
// whether separatrices join nearly parallel curves, which singularity pairs cancel, which
// singularities the boundary absorbs, whether separatrices cross, whether unbalanced
// patches are merged, what a curve arriving at a singularity records). They are tried in
// turn, each from scratch (a layout equal to an earlier one is not filled again), until a
// cage meets the targets with a margin and has no irregular vertex away from the field's
// singularities (comfortably_meets_targets), or until the work budget after the first cage
// that meets them is spent (QuadOptions::work_after_meeting, min_choices_after_meeting). Kept:
// among the cages meeting the targets, preferably one that needed no quad collapsed (a collapse
// leaves a valence-6 vertex whose pulled limit surface can fold), then the density nearest the
// size field's, then the fewest squeezed arcs, then the fewest irregular
// vertices away from the field's singularities (counts within 15% or 2 even, unless one is none),
// then the fewest skewed quads (within 20% or 5 even), then the fewest quads over 2.5x the
// target edge (the same), then the fewest irregular vertices (counts within 5% of each other
// are even), then the smallest mean corner deviation (better_cage); if none
// meets them, the valid cage with the smallest mean corner deviation. The choice that was used is
// reported when it is not the requested one.
void extract_component(const TriMesh& design, const Partition& partition, const CrossField& field,
                       const QuadOptions& options, int c, QuadResult* out) {
  ComponentSearch(design, partition, field, options, c, out).run();
}

}  // namespace

}  // namespace quad_detail
}  // namespace genbrep

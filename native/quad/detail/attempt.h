// quad/detail/attempt.h — internals of quad/: one layout choice tried at one component
// (attempt.cpp) and what the search among choices reads of it (choose.cpp).
#pragma once
#include <exception>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "quad/detail/cage.h"
#include "quad/detail/repair.h"

namespace genbrep::quad_detail {

// Quads with an edge longer than this × the local target edge length are oversized
// (QuadStats::oversized_quads).
constexpr double kOversized = 2.5;
// A second reading prices the nodes within this × an unexplained vertex's reach (in
// kSingularReach units) of it: about the ring of patches around it.
constexpr double kOffNodeRadius = 1.0;

// The layout's two fingerprints, set as extract_once reaches them: the traced curves (with
// the options the rest reads) and the quantized patch layout.
struct LayoutKeys {
  std::optional<std::size_t> traced, quantized;
};

// An attempt's work (QuadOptions::work_per_component) when it reached each fingerprint and
// at its end: a choice whose layout the search has already seen is charged only what the
// search one choice at a time would have spent on it, up to the fingerprint that repeats.
struct AttemptWork {
  double traced = 0, quantized = 0, total = 0;
};

// What every attempt at one component reads, the same for all of them: the (refined)
// surface the layout is traced on, the checks on the unrefined component, the field's
// singularities there, the quads the size field asks for (QuadStats::size_field_quads), and
// the density asked before any raise for dense singularities (QuadStats::squeezed_arcs).
struct ComponentInputs {
  const quad_detail::Surface& surface;
  const quad_detail::CageChecks& checks;
  const std::vector<quad_detail::SingularPoint>& singular;
  double asked;
  double unraised_density;
};

// What one reading of a layout gives: its fingerprints, the cage with its statistics and
// messages, the work spent, and per irregular vertex of the cage no singularity explains
// the spot a second reading prices higher (read_off_nodes_again).
struct Reading {
  LayoutKeys keys;
  QuadCage cage;
  QuadStats stats;
  quad_detail::Messages messages;
  AttemptWork work;
  std::vector<std::pair<Vec3, double>> unexplained;
};

// One attempt at one component: layout, quantization, filling, into *out. Throws
// Error{StageFailure} when the layout cannot be quantized or the filled cage is invalid,
// or when a fingerprint is in `seen` (a layout an earlier choice already had), or once
// `dropped`. Reads only its arguments, so attempts run on several threads at once.
// `costly_nodes`: the layout's Layout::costly_nodes.
void extract_once(const ComponentInputs& in, const QuadOptions& options,
                  const std::set<std::size_t>& seen, const Dropped& dropped,
                  const std::vector<std::pair<Vec3, double>>& costly_nodes, Reading* out);
// QuadOptions::off_node_price: the layout of `options` traced and read again, the nodes
// near the irregular vertices the first reading left away from singularities (its
// `unexplained`) priced higher; the second cage is kept in *first (cage, stats, messages)
// if better_second_reading says so, and the work of both is counted. A second attempt that
// fails leaves the first as it was.
void read_off_nodes_again(const ComponentInputs& in, const QuadOptions& options,
                          const Dropped& dropped, Reading* first);
// Measures a filled cage; squeezed or turned-over quads are untangled first, and that is
// reported. A valid cage is then evened out (even_out_kept). With `singular`, irregular
// vertices none of them explains are placed first (place_onto_singularities), and those
// they explain are held in the evening out, which runs QuadOptions::place_passes times;
// the placing runs again before it while some are still unexplained. Each placing scores
// at most kPlaceScoredPerQuad sequences per quad; how many it scored goes to *scored.
QuadStats measure_untangled(const Surface& surface, const CageChecks& checks, QuadCage* cage,
                            Messages* messages, const Dropped& dropped,
                            const QuadOptions& options,
                            const std::vector<SingularPoint>* singular = nullptr,
                            double* scored = nullptr);
// A cage with its corners squared (square_cage: 10 sweeps, on `threads` threads, the same
// result for any number), if it stays valid and its corners come closer to 90°.
struct Squared {
  QuadCage cage;
  double mean_deg = 0, max_deg = 0;  // corner deviation after squaring
  int skewed_quads = 0, oversized_quads = 0, moved = 0;
  double seconds = 0;
};
std::optional<Squared> square_copy(const CageChecks& checks, double density, int threads,
                                   const QuadCage& cage, const QuadStats& stats);
// The kept cage takes its squared copy (square_copy, or the one its attempt made already),
// reported. Only the kept cage: layout choices are compared as filled and evened out,
// where a distorted layout (a fan of rows over collapsed slivers) still shows in its
// angles; squaring would hide that.
void keep_squared(Squared&& squared, int c, QuadCage* cage, QuadStats* stats,
                  Diagnostics* notes);
// square_copy, kept (keep_squared) if it comes closer to 90°.
void square_kept(const CageChecks& checks, double density, int c, int threads, QuadCage* cage,
                 QuadStats* stats, Diagnostics* notes);
// The message an attempt fails with when its layout repeats an earlier choice's.
std::string same_layout(int c);
// Why a layout choice's attempt failed (its error's message); a cancellation or bad input
// is thrown on, as is anything not a genbrep Error.
std::string attempt_failure(const std::exception_ptr& error);

}  // namespace genbrep::quad_detail

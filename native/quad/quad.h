// quad/quad.h — a pure-quad control cage per organic component (paper §6, "quad partition
// of Ω"), by a quantized patch layout instead of the paper's integer-grid map
// (docs/quad_method.md says why).
// Takes: the design's halfedge mesh (closed, 2-manifold, outward-oriented), its Partition
// (organic components, boundary loops with the organic side on the left) and the
// CrossField of field/ (per-face 4-RoSy direction, size_u/size_v, singularities).
// Method, per component (one file per step):
//   1. refine for tracing (refine.cpp): where the component's singularities are dense for
//      the quads its sizes give, the density is raised; its triangles are split round its
//      singular vertices and until a cage edge spans a few mesh edges.
//   2. trace separatrices (trace.cpp): from every interior singularity and concave boundary
//      corner, along mesh edges, until they meet a loop or an earlier curve (a motorcycle
//      graph, embedded by construction).
//   3. build patches (arcs.cpp, patches.cpp): curves split into arcs at nodes; patches that
//      are not four-sided disks get extra cuts, or lose a stretch of separatrix.
//   4. read corners (corners.cpp): each patch's corners from the angles at its nodes, all
//      patches at once (a min-cost flow) so that a node keeps its quarter turns.
//   5. quantize (quantize.cpp): an integer count per arc, opposite sides equal (an exact
//      integer program, GLPK); patches that cannot balance are merged with a neighbour.
//   6. fill (fill.cpp): each patch's integer rectangle mapped onto it (a Tutte map).
//   7. repair (untangle.cpp, cancel.cpp, place.cpp): squeezed or turned-over quads opened up
//      or collapsed, irregular vertices in ± pairs cancelled, and those no singularity
//      explains edited onto the singularities beside them.
//   8. choose among layouts (choose.cpp, attempt.cpp): steps 2–7 run for several layout
//      choices, on threads, within a work budget; the best cage is kept (better_cage), or
//      the fallback cage (fallback.cpp: a split coarse remesh) if none is valid.
//   9. square (square.cpp): the kept cage's corners moved closer to 90° on the surface.
//  10. measure (measure.cpp): QuadStats, also for any other cage (measure_cage).
// Words used in the code: a reading is one pass of steps 3–7 over a traced layout (a layout
// is read again with higher prices near what a first reading left); an unexplained vertex
// is an irregular vertex no singularity explains; the pair is the requested layout with
// its arrivals recorded the other way. In place.cpp: a sequence climbs when it passes
// through more unexplained vertices on its way to fewer; rivals are irregular vertices
// beyond a window that take its singularities; a chain vertex sheds a quad it does not
// need; settling evens out the rings round an edit before it is judged.
// Gives: one QuadCage per organic component that could be meshed, in component order, with
// vertices on the design, quads counter-clockwise seen from outside, one boundary chain per
// loop of the component (chain_loop = the partition loop index), statistics and messages.
// Guarantees: only quads; the cage is a 2-manifold (patches are disks, shared arcs share
// their samples); every loop is one closed chain on the loop's polyline. Where the cage
// falls short of what was asked (squeezed quads, quads untangled, a search cut short,
// targets missed, the fallback cage) `diagnostics` says so; how it was made goes to
// `notes`. A component with no valid cage gets a QuadFailure naming why.
// Deterministic on any machine and load. Complexity: O(F log F) per layout choice for the
// layout, one sparse factorisation per patch for the filling.
#pragma once
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "core/cage.h"
#include "core/context.h"
#include "core/error.h"
#include "core/types.h"
#include "field/field.h"
#include "partition/partition.h"

namespace genbrep {

struct QuadOptions {
  // For callers.
  // Global density multiplier on the field's sizes (dimensionless; 2: twice as many quads
  // per side). Default 1.
  double density = 1.0;
  // Work per component for trying layout choices (units counted from the attempts
  // themselves: tracing 2 per triangle, each round of building patches 1 per triangle,
  // each branch-and-bound node 15 per arc, filling and untangling 850 per quad, each
  // sequence of edits scored placing irregular vertices 4; about 2.5 million per second
  // of one core), so that the search stops at the same choice on
  // every machine. The requested layout always runs (and its pair:
  // pair_second_readings); 0: it alone. Default 3e7.
  double work_per_component = 3e7;
  // Layout choices tried at once, one thread each (0: the hardware threads, at most 4).
  // The kept cage does not depend on it. Default 0.
  int parallel_choices = 0;
  // Each integer program's time limit (seconds, at least 1), a last resort: quantization
  // stops at quantize_gap first. Default 10.
  double quantize_seconds = 10;
  // Interior cage vertices wanted per quarter turn of singularity index; where the field's
  // sizes give fewer, the density is raised for that component (noted). 0: never raise.
  // Default 35.
  double vertices_per_singular_quarter = 35.0;

  // The method's settings: the layout choices (choose.cpp) vary some of them, and tests
  // set them to compare alternatives; a caller has no reason to.
  // Singularities of opposite sign closer than this × the local target edge length cancel
  // and are not traced (dimensionless).
  double pair_cancel_distance = 1.0;
  // Singularities closer than this × the local target edge length to a loop are left to
  // the boundary (dimensionless).
  double boundary_absorb_distance = 0.75;
  // Separatrices pass transversally through earlier ones (a layout choice).
  bool cross_separatrices = false;
  // A separatrix closer than join_parallel_distance cage edges to an earlier, nearly
  // parallel curve joins it across a short link curve (a layout choice).
  bool join_parallel = false;
  double join_parallel_distance = 0.3;
  // Patches whose angles do not give four corners: the four nodes that best make a
  // rectangle (true), or one angle re-read at a time (a layout choice).
  bool fit_corners = true;
  // With fit_corners: corners chosen for all patches at once (corners.cpp) before patch by
  // patch (a layout choice).
  bool global_corners = true;
  // A quarter turn of a traced curve against the field is read as a node (arcs.cpp:
  // mark_kinks); the last field-aligned try before the fallback reads none.
  bool kink_nodes = true;
  // Two curves meeting at under 45° are a cusp: the sector reads 0 quarter turns and a
  // small patch there collapses onto one curve.
  bool cusp_corners = true;
  // A four-cornered patch whose opposite sides differ by more than this factor (the longer
  // at least 3 cage edges) is a wedge and gets one more cut across. 0: never.
  double wedge_cut_ratio = 2.0;
  // Rounds of extra cuts, and rounds in a row without fewer patches to fix, before a
  // layout choice fails (0: no such stop).
  int max_fix_rounds = 64;
  int fix_rounds_without_progress = 24;
  // Rounds of merging patches whose sides cannot balance (0 in some layout choices), and
  // of merging patches under quads the untangling left turned over.
  int max_balance_rounds = 16;
  int max_tangle_rounds = 3;
  // A curve ending at a singular vertex within this fraction of the separatrix spacing of
  // a free direction takes that direction; further off, with arrival_chord, it records
  // the chord it came in along (the requested layout's pair flips arrival_chord).
  double arrival_snap = 0.25;
  bool arrival_chord = true;
  // Moving irregular vertices onto singularities (place.cpp): on/off, drawing 3–5 pairs
  // together, the longest sequence of edits, how many more unexplained vertices a sequence
  // may pass through (and in rounds that made no edit), counting the vertices beyond a
  // window that take its singularities, moving chain vertices of three quads off smooth
  // stretches of their loop, the rings and sweeps evened out before an edit is judged,
  // holding explained vertices in the evening out, and how often edits and evening out run.
  bool place_irregulars = true;
  bool draw_pairs_together = true;
  int place_edits = 8;
  int place_climb = 1;
  int place_climb_last = 2;
  bool place_rivals = true;
  bool place_chain_vertices = true;
  int settle_rings = 2;
  int settle_sweeps = 10;
  bool hold_explained = true;
  int place_passes = 2;
  // A cage that leaves irregular vertices away from singularities (at least off_node_share
  // of its irregular vertices, or off_node_count) is read again with nodes near them
  // priced off_node_price per quarter turn; the better cage is kept. 0: never.
  double off_node_price = 4.0;
  double off_node_share = 0.02;
  int off_node_count = 2;
  // The requested layout and its pair (its arrivals flipped) are both tried whatever the
  // work (work_per_component above 0), and both read once before either is read again.
  bool pair_second_readings = true;
  // After the first cage that meets the targets, more choices while choices × triangles
  // stays within work_after_meeting, and at least min_choices_after_meeting.
  double work_after_meeting = 6e5;
  int min_choices_after_meeting = 1;
  // Quantization stops once provably within this fraction of the optimum (GLPK mip_gap).
  double quantize_gap = 0.005;
  // The most times a component's triangles are split for tracing (each halving its edges;
  // refine.cpp), towards kTraceEdgesPerCageEdge mesh edges per target cage edge.
  int max_refine_levels = 2;
};

// Quality of one cage, measured on the cage itself (what report.json shows).
// A quad with a corner more than this far from 90° is skewed (QuadStats::skewed_quads).
constexpr double kSkewedDegrees = 45.0;

struct QuadStats {
  int quads = 0;
  int vertices = 0;
  int interior_vertices = 0;
  int interior_valence4 = 0;
  int boundary_vertices = 0;
  int boundary_valence3 = 0;   // valence counts edges: 3 = one edge into the interior
  int irregular_vertices = 0;  // interior ≠ 4 plus boundary ≠ 3
  double mean_angle_deviation_deg = 0;  // mean |corner angle − 90°| over all quad corners
  double max_angle_deviation_deg = 0;
  // Quads with a corner more than kSkewedDegrees (45°) off square: what the mean hides (a
  // band of rows crowded into one patch's narrow part, a crumpled junction).
  int skewed_quads = 0;
  // Quad normal · design normal at the design vertex closest to its centre ≤ 0, or the
  // quad spans a thin part (its normal over 75° from the design's at all four corners),
  // or, unless within 30° of that vertex's normal, it faces against or stands more than
  // 80° on the component's triangles under its centre (quad_detail::turned_over; the
  // stage measures so, measure_cage(cage, design) by the vertex alone).
  int flipped_quads = 0;
  int degenerate_quads = 0;  // a corner angle below 1° or a repeated corner
  int patches = 0;
  int separatrices = 0;
  bool fallback = false;  // no field-aligned layout worked: the split coarse remesh (not aligned)
  int collapsed_quads = 0;  // quads that stayed folded after smoothing, collapsed (untangle)
  // Quads with an edge longer than 2.5× the local target edge length (quantization
  // squeezed their patch; quad_detail::oversized_quads).
  int oversized_quads = 0;
  // Arcs of the quantized layout (patch sides between nodes) that got at most half the
  // cage edges the size field asks for on them, of those where it asks 3 or more: a row of
  // patches gutted to make opposite sides equal. Measured against the size field at
  // QuadOptions::density, not at the density raised for dense singularities, under which
  // arcs left at 0 edges to balance are common (quad_detail::squeezed_arcs).
  int squeezed_arcs = 0;
  // Interior vertices of valence ≠ 4 whose quarter turns no field singularity of the same
  // sign within two local target edges explains (each singularity explains its own index
  // once): irregular vertices the layout put where the field has none
  // (quad_detail::irregular_off_singularities).
  int irregular_off_singularities = 0;
  // Those vertices, each with the quarter turns no singularity explains there (of the
  // 4 − quads it carries: 1 at valence 3, −1 at valence 5; a vertex of valence 7 beside
  // two −1 singularities has −1 left).
  struct OffSingularity {
    int vertex;         // of the cage
    int valence;        // quads at it
    int quarter_turns;  // left unexplained
  };
  std::vector<OffSingularity> off_singularities;
  // The quads the size field asks for on the component at the density used (after any
  // raise for dense singularities): Σ area / (size_u · size_v) · density² over its faces.
  // quads / size_field_quads is how closely the cage's density follows the field's.
  double size_field_quads = 0;
  double seconds = 0;
  double interior_valence4_fraction() const {
    return interior_vertices ? double(interior_valence4) / interior_vertices : 1.0;
  }
  double boundary_valence3_fraction() const {
    return boundary_vertices ? double(boundary_valence3) / boundary_vertices : 1.0;
  }
  // How far the cage's quads are outside 0.8–1.2× what its size field asks for, as a
  // log ratio (0 within, or while that is not known): how layout choices are told apart on
  // density (quad_detail::better_cage).
  double size_field_miss() const {
    if (size_field_quads <= 0 || quads <= 0) return 0;
    const double ratio = quads / size_field_quads;
    return std::max({0.0, std::log(0.8 / ratio), std::log(ratio / 1.2)});
  }
};

struct QuadFailure {
  int component = -1;
  std::string reason;  // why no cage: the layout or quantization failed, or the cage was invalid
};

struct QuadResult {
  // One valid cage per organic component that could be meshed (cages[i].component says
  // which); a component whose layout fails, or whose cage has flipped or degenerate quads,
  // gets no cage and a QuadFailure instead: never an invalid cage, never a silent gap.
  std::vector<QuadCage> cages;
  std::vector<QuadStats> stats;  // same order as cages
  std::vector<QuadFailure> failures;
  Diagnostics diagnostics;       // warnings: "component 2: 3 quads have an edge longer ..."
  Diagnostics notes;             // "component 2: 7 patch corners re-read ...", ...
};

QuadResult extract_cages(const TriMesh& design, const Partition& partition,
                         const CrossField& field, const QuadOptions& options,
                         const Context& context);

// The statistics of any cage against the design it approximates (used by extract_cages;
// public so the pipeline and tests can measure other cages the same way).
QuadStats measure_cage(const QuadCage& cage, const TriMesh& design);

}  // namespace genbrep

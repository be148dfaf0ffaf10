// quad/detail/repair.h — internals of quad/: repairs of a filled cage: untangling (untangle.cpp),
// cancelling irregular pairs (cancel.cpp), moving irregular vertices onto singularities
// (place.cpp), evening out and squaring (square.cpp), and the fallback cage (fallback.cpp).
#pragma once
#include <vector>

#include "quad/detail/cage.h"

namespace genbrep::quad_detail {

// Collapses the shorter diagonal of each quad in `bad` whose diagonal ends share no other
// quad, are not both on chains, and whose other corners keep ≥ 3 quads (the cage stays a
// pure-quad 2-manifold); quads sharing a corner with an earlier collapse are skipped.
// The merged vertex goes to the diagonal's midpoint, projected onto the component, or
// stays at the end that lies on a chain; vertices are renumbered (chains and creases
// follow). Returns the count.
// `diagonal` (optional, one per quad of `bad`): collapse that diagonal (0: corners 0–2,
// 1: corners 1–3) instead of the shorter one.
// `done` (optional) receives the quads of `bad` that were collapsed (indices before).
// `doublets`: an interior other corner may also be left with 2 quads (a doublet, which
// remove_doublets then dissolves by joining its two quads); untangling's last resort when
// a fold's other corners have 3 quads each.
int collapse_diagonals(const ComponentLocator& locator, QuadCage& cage,
                       const std::vector<int>& bad, const std::vector<int>& diagonal = {},
                       std::vector<int>* done = nullptr, bool doublets = false);
// Cancels irregular vertices in pairs by diagonal collapses (the simplification step of
// Tarini et al. 2010, "Practical quad mesh simplification"): a quad with four interior
// corners is collapsed along a diagonal when that leaves fewer irregular vertices among
// its corners (merged valence a + c − 2 ≤ 5, the other two corners keep ≥ 3 quads), the
// best gains first; the quads around the merged vertices are then opened by smoothing.
// A collapse next to a quad that comes out squeezed or turned over (and stays so after
// smoothing) is left out and the rest tried again, at most 4 times; then the next round
// looks for new candidates; a round with no collapse tries edge rotations
// (rotate_edges_for_pairs); at most `max_rounds` rounds. Then vertex splits
// (split_vertices_for_pairs), at most `max_rounds` rounds of them. Returns the collapses,
// rotations and splits (0: the cage is unchanged).
int cancel_irregular_pairs(const CageChecks& checks, QuadCage& cage, int max_rounds,
                           const Dropped& dropped = Dropped());
// How place_irregulars searches and judges (the defaults: the search as first written;
// QuadOptions fills them in the pipeline).
struct PlaceSettings {
  // A sequence leaving as many unexplained vertices and no more irregular ones is made too
  // if it brings them nearer to ones of opposite sign (QuadOptions::draw_pairs_together).
  bool draw_pairs_together = false;
  int max_edits = 3;      // the longest sequence tried (QuadOptions::place_edits)
  // How many more unexplained vertices than before a sequence of two edits or more may
  // leave on its way to leaving fewer (QuadOptions::place_climb).
  int climb = 0;
  // Where a round of edits makes none, every window is searched again climbing by one
  // more, up to this (QuadOptions::place_climb_last).
  int climb_last = 0;
  // Windows count the cage's irregular vertices beyond them that compete for their
  // singularities (QuadOptions::place_rivals).
  bool rivals = false;
  // Chain vertices that may shed a quad start windows, and no singularity explains them
  // (QuadOptions::place_chain_vertices).
  bool chain_vertices = false;
  int settle_rings = 0;   // rings evened out beyond the changed vertices' neighbours
  int settle_sweeps = 3;  // sweeps of that evening out
  // Sequences scored, at most, over all windows and rounds (0: no limit); once reached no
  // window is started, so that the search costs at most about this much on any cage.
  double max_scored = 0;
};
// Moves irregular vertices no singularity explains (irregular_off_singularities) onto the
// singularities beside them, or cancels them (place.cpp): around each, sequences of up to
// two edits (three where two do not help, then one more at a time after the best of those
// up to `settings.max_edits`) — edge rotation, diagonal collapse, split of a vertex of 5–8
// quads; none moving a chain or crease vertex or giving one a quad, though a chain vertex
// of three quads on a smooth stretch of its loop may lose one — are scored on the window's
// connectivity (fewest unexplained vertices, then fewest irregular); of those leaving fewer
// unexplained, the best few are evened out around their changed vertices in turn and the
// first whose quads are neither squeezed nor turned over is made (those vertices, their
// neighbours and `settings.settle_rings` rings more move, `settings.settle_sweeps` times
// each to the mean of its neighbours, onto the component; a dislocation cancelled against a
// singular vertex shifts rows a few edges wide, whose quads one ring cannot open). Windows
// edited in one round are disjoint; at most `max_rounds` rounds (where one makes no edit,
// the next searches every window again climbing by one more, up to settings.climb_last).
// A window counts the cage's irregular vertices beyond it that compete for its
// singularities (settings.rivals). The caller opens squeezed quads and checks the cage.
// Returns the windows edited (0: the cage is unchanged); the sequences scored go to
// *scored (settings.max_scored).
int place_irregulars(const CageChecks& checks, QuadCage& cage,
                     const std::vector<SingularPoint>& singular, double density, int max_rounds,
                     const PlaceSettings& settings = PlaceSettings(),
                     const Dropped& dropped = Dropped(), double* scored = nullptr);
// The chain vertices of `cage` of three quads or more where their loop is smooth (the
// quads' corners at it sum to under 225°: two quads would cover it), which
// place_irregulars may take a quad from.
int chain_vertices_to_shed(const QuadCage& cage);
// Rotates interior cage edges where that leaves fewer irregular vertices: the edge u–w
// between quads (u, w, a, b) and (w, u, c, d) becomes c–a or d–b (u and w lose a quad, the
// new ends gain one; all four interior, u and w keep ≥ 3 quads), the best gains first, no
// two sharing a quad or a changed vertex; one whose new quads come out squeezed or turned
// over is undone. Vertices do not move. Returns the rotations made.
int rotate_edges_for_pairs(const CageChecks& checks, QuadCage& cage);
// Splits an interior vertex u of six quads in two where that leaves fewer irregular
// vertices: a new quad (p, u, q, w) between two opposite edge neighbours p and q, u
// keeping the three quads on one side and a new vertex w taking the other three (both
// then of four quads; p and q gain one: a valence-3 beside the valence-6 vertex becomes
// regular, so a −1 singularity drawn as a 6 and a 3 becomes one 5). The inverse of a
// diagonal collapse. u and w move a third of the way towards their sides, onto the
// component; a split whose quads come out squeezed or turned over is undone; none
// touches another's vertices; p, q not on chains or already joined. Returns the splits.
int split_vertices_for_pairs(const CageChecks& checks, QuadCage& cage);
// Evens out a valid cage: for `sweeps` sweeps every free vertex (not on a chain, not
// `held`) moves `step` of the way to the mean of its neighbours, in its tangent plane and
// back onto the component; a move that would make one of its quads squeezed or turned over
// is undone. Returns the vertices moved in the last sweep.
int relax_cage(const CageChecks& checks, QuadCage& cage, int sweeps, double step,
               const Dropped& dropped = Dropped(), const std::vector<char>* held = nullptr);
// Squares a valid cage's quads: for `sweeps` sweeps every free vertex takes a gradient
// step (in its tangent plane, back onto the component) on the squared deviations of the
// corners it moves (its own and its neighbours' in its quads) from their ideal angles
// (a full turn shared by the quads at an inner vertex; a chain vertex's angle sum as
// filled, shared evenly); a step that does not lower them, or makes a quad squeezed or
// turned over, or makes an edge longer than twice the target length (size field over
// `density`) and than it was, is refused. Irregular and chain vertices stay. Returns the
// vertices moved in the last sweep. Vertices that read each other's positions never move
// at once; the others of a sweep move on `threads` threads (the same result for any
// number).
int square_cage(const CageChecks& checks, QuadCage& cage, int sweeps, double density,
                int threads = 1);
// Removes doublets: an interior cage vertex with only two quads, which share two edges,
// goes and the two quads become one. Returns how many (collapsed sliver patches leave
// them; the limit surface folds at a doublet).
int remove_doublets(QuadCage& cage);
// Smooths the interior vertices around squeezed (a corner under 5°) or turned-over quads,
// as the untangling does, for at most `max_rounds` rounds; returns how many stay so.
int open_squeezed(const CageChecks& checks, QuadCage& cage, int max_rounds);
// Opens up degenerate or turned-over quads of a filled cage: the interior cage vertices
// within a few rings of them are smoothed and projected back onto the component, for at
// most `max_rounds` rounds (untangle.cpp). Quads still bad after smoothing get a diagonal
// collapsed (when the link condition allows) and the smoothing is repeated; `collapsed`
// counts them (each leaves irregular vertices). Returns how many vertices moved.
int untangle_cage(const CageChecks& checks, QuadCage& cage, int max_rounds, int* collapsed,
                  const Dropped& dropped = Dropped());

// Last resort: a pure-quad cage that is not field-aligned (fallback.cpp), from a coarse
// remesh at `coarse_edge_length` split once (cage edges about half that long).
QuadCage fallback_cage(const Surface& s, double coarse_edge_length);

}  // namespace genbrep::quad_detail

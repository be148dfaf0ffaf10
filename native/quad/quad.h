// quad/quad.h — a pure-quad control cage per organic component (paper §6, "quad partition
// of Ω"), by a quantized patch layout instead of the paper's integer-grid map
// (docs/quad_method.md says why and what it measures).
// Takes: the design's halfedge mesh (closed, 2-manifold, outward-oriented), its Partition
// (organic components, boundary loops with the organic side on the left) and the
// CrossField of field/ (per-face 4-RoSy direction, size_u/size_v, singularities).
// Method, per component:
//   0. density and resolution: where the component's singularities are dense for the
//      quads its sizes give (a genus-4 lattice needs 96), the density is raised so that
//      they stay a small fraction of the cage vertices (vertices_per_singular_quarter,
//      reported); then the component's triangles are split (refine.cpp, same surface)
//      round its singular vertices until each has two edges per separatrix, and then
//      until a cage edge spans a few mesh edges, since separatrices follow mesh edges.
//   1. layout: separatrices leave every interior singularity (one per sector of its cross)
//      and every concave boundary corner, follow the field along mesh edges and stop where
//      they meet a loop or an earlier separatrix (a motorcycle graph: separatrices can
//      only meet at mesh vertices, so the graph is embedded by construction). ± pairs of
//      singularities closer than `pair_cancel_distance` are not traced (they cancel).
//      Patches that are not topological disks with four corners get extra field-aligned
//      cuts from their boundary; corners are read from the angles between the curves
//      (at each node all together, so that its sectors add up to its quarter turns),
//      and where a patch does not read four, re-read for all patches at once (a min-cost
//      flow, corners.cpp) so that a node keeps the quarter turns it has, or patch by patch.
//      Sliver patches that cannot be cut (one triangle between curves) and dangling
//      separatrices are merged away by taking a stretch of separatrix off the layout.
//   2. quantization: every layout arc gets an integer count ≥ 1 near length / size; the
//      two pairs of opposite sides of every patch get equal sums (an exact integer
//      program, GLPK); interior arcs may get 0 where the sides balance only so. If even
//      that has no solution, the patches an imbalance LP names are merged with a
//      neighbour and the layout is rebuilt (a few rounds).
//   4. repair: doublets left by collapsed sliver patches are removed; quads the filling
//      squeezed or turned over are opened up by local smoothing on the surface, and a
//      quad that stays folded has a diagonal collapsed; where quads stay turned over even
//      so (a tangle), the patches they came from are merged with a neighbour and the
//      layout quantized and filled again (a few rounds). The cage must then be a
//      2-manifold with no doublet. Irregular vertices left in ± pairs are cancelled by
//      diagonal collapses, edge rotations and vertex splits; then those no field
//      singularity explains (a −1 singularity drawn as a 6 and a 3, a 3–5 pair beside a
//      5) are edited onto the singularities beside them or away: per such vertex the best
//      sequence of at most two of those edits (three where two do not help) in a window
//      of a few rings (place.cpp).
//      A cage that still has irregular vertices away from singularities has its layout
//      read again with a higher price on the nodes near them (off_node_price), the better
//      cage kept. Several layout choices are tried (reported); the
//      fallback cage (a split coarse remesh) is the last resort.
//   5. squaring: the kept cage's inner vertices of four quads move on the surface to bring
//      its corners closer to square while keeping its rows even and its edge lengths
//      (untangle.cpp square_cage); chains and irregular vertices stay. Choices are
//      compared before it, so a distorted layout cannot hide behind squared quads; but a
//      cage that misses only the corner-angle target is squared before it is judged
//      (the targets are the output cage's): the 6 x 6 net's requested cage, 12.9° as
//      filled and 10.4° squared, was passed over for a layout with 0.6x the quads the
//      size field asks, found after 40 s of further choices.
//   3. filling: every patch is mapped to its integer rectangle (Tutte map with the sides
//      sampled by arc length) and the grid's points are lifted back to the surface.
// Gives: one QuadCage per organic component, in component order, with vertices on the
// design, quads counter-clockwise seen from outside, one boundary chain per loop of the
// component (chain_loop = the partition loop index), and per-cage statistics and
// diagnostics.
// Guarantees: only quads; the cage is manifold by construction (patches are disks, shared
// arcs share their samples); every loop is one closed chain whose vertices lie on the
// loop's polyline. Where the cage falls short of what was asked (quads squeezed beyond
// 2.5x the target, quads untangled after filling, a search cut short, targets missed, the
// fallback cage) it says so in `diagnostics` (warnings) and counts it in the statistics,
// never silent; how the cage was made (refinement, re-read corners, collapsed slivers,
// the layout choice kept, squaring) goes to `notes`. A component whose layout cannot be
// made valid throws Error{StageFailure} naming it.
// Deterministic. Complexity: O(F log F) for the layout and one sparse factorisation per
// patch (Tutte map) for the filling; point location O(P·T_patch) per patch.
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
  // Singularities of opposite sign closer than this times the local target edge length
  // (mean of size_u, size_v) are a cancelling pair and are not traced (dimensionless).
  double pair_cancel_distance = 1.0;
  // Singularities closer than this times the local target edge length to a boundary loop
  // are left to the boundary (not traced): see trace_separatrices (dimensionless).
  double boundary_absorb_distance = 0.75;
  // Let separatrices pass transversally through earlier ones (fewer T-junctions, but
  // edge-snapped crossings leave sliver patches on level-set meshes: off by default).
  bool cross_separatrices = false;
  // Join parallel curves: a separatrix that comes closer than join_parallel_distance cage
  // edges to an earlier, nearly parallel curve joins it there across a short link curve
  // (trace.cpp), instead of converging onto it at a shallow angle further on (a wedge
  // patch that quantization can only balance by squeezing its long side). One of the
  // layout choices (extract_component); off in the requested layout because on clean
  // fields it only adds jogs.
  bool join_parallel = false;
  double join_parallel_distance = 0.3;
  // Patches whose angles do not give four corners: choose the four nodes that best make a
  // rectangle (angles and opposite side lengths), or re-read one angle at a time (false).
  bool fit_corners = true;
  // A sector's quarter turns are read at its node together with the node's other sectors
  // (the curves' directions rounded once onto one grid), so a node's readings add up to its
  // quarter turns; false: each sector's angle rounded alone. Over the nets of genus 9-64
  // at three voxel sizes (bench/quad_sweep) irregular vertices off singularities 1492 ->
  // 1445, skewed quads 6248 -> 5928.
  bool node_readings = true;
  // A vertex where a traced curve turns a quarter turn against the field (its walk snapped
  // to the other cross direction, where the field turns fast under it) is read with the
  // direction the curve came along (layout.cpp: mark_kinks): a node that reads the turn as
  // a corner, or at a junction or the curve's last vertex, the sectors read with that
  // tangent; not a turn hidden inside an arc or a node's tangent, which the corner reading
  // makes up at another node with an irregular vertex. On the genus-49 net at h 0.14, 212
  // of its 1580 patches turned three quarter turns at their nodes with no singularity
  // inside, 64 of them with such a turn along an arc. 25 nets (genus 9-49, h 0.1-0.14):
  // irregular vertices off singularities 64 → 36, oversized / skewed quads 627 / 708 →
  // 461 / 548; genus 64 30 → 1, 472 / 295 → 309 / 230 (48 and 5 reading only the vertices
  // of one curve). Turns within kCaptureReach of a singular end are not read (with them:
  // lattice 1 unexplained and 31-34 oversized quads in every layout choice, where it has 0
  // and 1), except near the irregular vertices a first cage left unexplained, when the
  // layout is read again (off_node_price): 25 nets 36 → 32, 461 / 548 → 457 / 541. Their
  // corners can leave a layout no integer counts balance (lattice's requested one): where
  // every choice the component's work allows fails, the requested layout is read once
  // more without them before the fallback cage.
  bool kink_nodes = true;
  // Irregular vertices the layout leaves beside a singularity that does not explain them
  // (a −1 singularity drawn as a 6 and a 3, a 3–5 pair beside a 5) are moved onto it by
  // local connectivity edits (quad_detail::place_irregulars), kept if the cage stays valid
  // with fewer of them.
  bool place_irregulars = true;
  // With place_irregulars: edits that leave as many unexplained vertices but bring them
  // nearer to unexplained ones of opposite sign are made too, so that a 3 and a 5 the
  // layout left a few edges apart (a dislocation where rows shift) meet and cancel in a
  // later round. 25 nets (genus 9-49, h 0.1-0.14): 297 → 245 irregular vertices off
  // singularities, oversized / skewed quads 2070 / 2124 → 2059 / 2111; genus 64 181 → 165.
  bool draw_pairs_together = true;
  // The longest sequence of edits place_irregulars tries around one unexplained vertex:
  // every sequence of one or two, of three where those do not help (the first two leaving
  // no more unexplained), and from four on, one edit more at a time after the 64 best
  // sequences so far leaving no more unexplained. A 6 and a 3 beside a −1 singularity
  // (the 4 x 4 net at h 0.13) need four. 48 conversions (bench/quad_judge; unexplained /
  // oversized / skewed / s): 3: 49 / 1401 / 1289 / 467; 4: 40 / 1413 / 1301 / 450;
  // 5: 34 / 1406 / 1293 / 466; 8: 33 / 1405 / 1287 / 443 (every sequence of four instead
  // of the best 64 taken on: 38 / 1449 / 1352 / 677, genus 64 at h 0.14 alone 37 → 213 s).
  int place_edits = 8;
  // How many more unexplained vertices than it started with a sequence of those edits may
  // leave on its way (after two edits or more) to leaving fewer: the 64 best such
  // sequences are taken on beside the 64 best that leave no more. A 6 or a 5 whose partner
  // (a 3) is a few edges away can only be brought to it through one more: an edit moves an
  // irregular vertex only by leaving a 3–5 pair behind. 48 conversions (bench/quad_judge;
  // unexplained / oversized / skewed / s): 0: 16 / 1097 / 1036 / 588; 1: 8 / 1119 / 1054 /
  // 649. Scratch runs over the same 48's report.json: 1, with each chosen sequence scored
  // again once evened out (kept only if still fewer): 33 / 1107 / 1046. Over the 47
  // without genus 64 at h 0.14: 0: 15 / 988 / 973; 1: 8 / 1012 / 991; 2: 10 / 960 / 943,
  // the genus-49 nets 2-3x slower (46-60 s → 100-164 s).
  int place_climb = 1;
  // Where a round of those edits makes none, every window is searched again climbing by
  // one more, up to place_climb_last: the cost of climbing higher only where nothing else
  // moves. With place_rivals, 48 conversions (scratch runs with --field-obj, sums over
  // report.json; unexplained / oversized / skewed / wall s): 1: 7 / 1084 / 1055 / 556;
  // 2: 3 / 1084 / 1050 / 588. Without place_rivals, climbing to 3 in the last rounds, or
  // 10 edits there, left no fewer than climbing to 2 on the four conversions that kept
  // some.
  int place_climb_last = 2;
  // Each window counts, beside its own vertices, the cage's irregular vertices beyond it
  // that its singularities can explain: the cage's matching gives a singularity to the
  // nearest vertex wherever it is, and a window that leaves them out finds a vertex of long
  // edges by a junction's cluster of −1 singularities explained by one that a nearer vertex
  // a few rings away, or across a strut, takes, and never searches it (the genus-49 net at
  // h 0.11: 32 such windows). The same 48, with place_climb_last 2: without them 6 / 1116
  // / 1051 / 516 s, with them 3 / 1084 / 1050 / 588 s (8 / 1119 / 1054 / 526 s before
  // either).
  bool place_rivals = true;
  // Chain vertices of three quads where their loop is smooth (a straight or convex stretch,
  // where two quads would cover it) are moved off the loop by those edits like irregular
  // vertices no singularity explains: each starts a window of its own, a singularity never
  // explains it, and the cage is kept where the edits leave fewer of the two together. A
  // −1 singularity a row or two in from the loop was otherwise drawn on the loop (a chain
  // vertex of three quads, two of them squeezed), and nothing searched it: no interior
  // vertex was left unexplained there. 48 conversions (scratch runs with --field-obj;
  // unexplained / oversized / skewed / such chain vertices of 10360 / wall s): off 3 / 1084
  // / 1050 / 8 / 476, on 3 / 1082 / 1038 / 0 / 521.
  bool place_chain_vertices = true;
  // Where a sequence of those edits is tried on the cage, the vertices it changed, their
  // neighbours and settle_rings rings more are evened out (settle_sweeps sweeps, each
  // vertex to the mean of its neighbours) before its quads are judged (squeezed or turned
  // over: not made). A 3–5 dislocation beside a cluster of −1 singularities cancels
  // against the singular vertex it meets only by shifting a row a few edges wide (the
  // genus-49 net at h 0.1: a 3 and a 5 in the middle of a junction go, and the 5 at the
  // fillet's singularity moves onto it); one ring and 3 sweeps left its quads squeezed.
  // 48 conversions (bench/quad_judge; unexplained / oversized / skewed / s), rings and
  // sweeps: 0, 3 (before): 27 / 1251 / 1162 / 504; 0, 10: 27 / 1261 / 1133 / 499; 2, 3:
  // 24 / 1284 / 1153 / 494; 2, 10: 22 / 1226 / 1139 / 510; 2, 20: 25 / 1264 / 1129 / 524;
  // 3, 10: 22 / 1250 / 1137 / 508.
  int settle_rings = 2;
  int settle_sweeps = 10;
  // The evening out that ends each reading (after those edits) holds an irregular vertex
  // a singularity explained before it and none explains after (moved past its reach, or
  // its singularity matched to a neighbour drawn nearer) where it was, and evens out the
  // rest again. 48 conversions (bench/quad_judge; unexplained / oversized / skewed / s,
  // counted before squaring): off 33 / 1405 / 1287 / 443, on 31 / 1392 / 1286 / 456.
  bool hold_explained = true;
  // How often the evening out after the edits onto singularities (place_irregulars) runs
  // on one reading's cage; the edits run again before it only while irregular vertices are
  // left that no singularity explains (the evening out moves vertices, and with them what
  // a window's search reaches and scores). 48 conversions (bench/quad_judge; unexplained /
  // oversized / skewed / s): 1: 32 / 1392 / 1286 / 474; 2: 27 / 1251 / 1162 / 504; 3: 29 /
  // 1257 / 1155 / 544 (both again only while some are left). With the evening out run
  // twice on every cage, not only where some are left: 16 / 1248 / 1155 / 588 →
  // 16 / 1097 / 1040 / 588 (until then a cage the edits left without unexplained vertices
  // was evened out once, one with some left twice).
  int place_passes = 2;
  // A curve that ends at a singular vertex within this fraction of the separatrix spacing
  // of a direction no curve leaves it along yet (measured over a target edge length back
  // along the curve) takes that direction, so the singularity's own separatrix is not
  // traced beside it as an extra spoke; 0: the direction recorded is the field's on the
  // last mesh edge, which near a singularity can lie over half the spacing off. 25 nets
  // (genus 9-49, h 0.1-0.14): irregular vertices off singularities 245 → 233, skewed
  // quads 2111 → 1795, oversized 2059 → 1879 (0.2: 261, 0.3: 249; the nearest free
  // direction at any angle: one net's layouts could not be quantized); genus 64 165 → 64
  // of ~1700, skewed 857 → 456.
  double arrival_snap = 0.25;
  // A curve that ends at a singular vertex further off every free direction than
  // arrival_snap records there the chord it comes in along (over a target edge length),
  // not the field's direction on the last mesh edge: a direction within half the spacing
  // of the chord then counts as taken, and is not traced beside it. false: the field's.
  // With max_balance_rounds 16 (8 left one net's layouts unbalanced; 16 and 32 balance
  // it): 25 nets (genus 9-49, h 0.1-0.14) 206 → 175 irregular vertices off
  // singularities, oversized / skewed quads 1872 / 1781 → 1465 / 1343; but genus 64
  // 65 → 84, oversized / skewed 851 / 460 → 1108 / 640 (docs/quad_method.md).
  bool arrival_chord = true;
  // A cage that leaves irregular vertices away from singularities has its layout traced and
  // read again with the price of a node whose sectors do not add up to its quarter turns
  // (corner_node_price) raised to off_node_price at the nodes within off_node_radius local
  // target edges of them, and the better of the two cages is kept (better_cage): there the
  // corner reading had settled for a node off its quarter turns (an extra quad at a
  // singular node, a T-junction read as a corner) where re-reading a sector or two of the
  // patches around would do. 25 nets (genus 9–49, h 0.1–0.14): irregular vertices off
  // singularities 151 → 105, oversized quads 1297 → 1363, skewed 1340 → 1288; genus 64
  // 65 → 48 (prices 4 and 8, radii 0.6–2 alike; raised at every singular node instead:
  // 151 → 136, genus 64 65 → 76). It costs a second attempt where the first leaves any:
  // genus 64 at h 0.12, 18 → 32 s in all; the fixtures' kept cages are unchanged.
  // 0: never.
  double off_node_price = 4.0;
  double off_node_radius = 1.0;
  // The second reading is a whole attempt more: it is made only where the first leaves at
  // least this share of the cage's irregular vertices away from singularities. 25 nets at
  // 35 vertices per quarter turn (off singularities / oversized / quad s): never read
  // again 93 / 792 / 302; always 61 / 596 / 470; from 2% on (the genus-49 net's 2.8 to 5.7%,
  // the 50k-triangle region's 1%, which then stays under 10 s) the figures in
  // docs/quad_method.md. 0: wherever there are any.
  double off_node_share = 0.02;
  // ... and also where it leaves at least this many, whatever their share (0: by share
  // only). At 3, 48 conversions (bench/quad_judge) went 64 → 52 left unexplained,
  // oversized 1428 → 1423, skewed 1382 → 1357, 375 → 424 s, but rendered, the genus-16
  // net at h 0.11 (4 → 0 there) kept a cage whose stub at (−0.3, 2.1) has 2–3 quads
  // across where the other choice had 6. With better_cage ranking squeezed arcs
  // (QuadStats::squeezed_arcs) before unexplained vertices: 64 → 57, oversized 1409,
  // skewed 1344, and that net keeps the stub 6 across; with a second reading kept only
  // where it leaves fewer (read_off_nodes_again): 54, 1398, 1311, 430 s; from 2 instead of
  // 3: 49, 1401, 1289, 473 s (the 4 x 4 net at h 0.1 reads its hole corner again and
  // leaves none: a valence 7 and a 3 there before).
  int off_node_count = 2;
  // The requested layout and its sibling (arrival_chord flipped), which always run side by
  // side, both make their first reading before either is read again (with any number of
  // threads). Beside one that left no irregular vertex away from singularities, the other
  // is read again only where, with none left and their corner angles taken as even, it
  // would be kept over that one (better_cage): a cage with none beats every cage with some,
  // so a second reading could only win on the tie-breakers after that, and the first
  // reading's angles are not the second's. The 8 x 8 net at h 0.12 read its requested
  // layout again for 9.3 s on one core after the sibling, the cage kept, had left none.
  // Not where work_per_component is 0 (the requested layout alone).
  bool pair_second_readings = true;
  // With fit_corners: the patches' corners are first chosen all at once (a min-cost flow
  // over every sector, quad/corners.cpp), so that a re-read sector is balanced at its node
  // by the patch across rather than left as an irregular vertex; what that cannot make
  // four-sided is fitted patch by patch. false: patch by patch only (the next layout
  // choice either way).
  bool global_corners = true;
  // What a node whose sectors do not add up to its quarter turns (an irregular vertex off
  // the singularities) costs, per quarter turn, against re-reading sectors (a sector's
  // cost: how much further its angle is from the new reading, in quarter turns). Since
  // every separatrix leaves its singularity (refine.cpp's splits), 25 nets (genus 9-49,
  // bench/quad_sweep at h 0.1-0.14) leave 437 / 360 / 298 / 302 / 309 / 339 irregular
  // vertices off singularities at 1 / 1.5 / 2 / 2.5 / 3 / 4 (oversized quads 2580 → 2068
  // at 2, skewed 2756 → 2123), genus 64 189 / 181 / 178 / 173 at 1 / 2 / 2.5 / 3; the
  // fixtures none at any of these.
  double corner_node_price = 2.0;
  // Re-reading a sector of a patch one corner off also costs this times how far the patch
  // is then from a rectangle (best_corners' side term: Σ 2 |difference| / sum over its
  // pairs of opposite side targets). Nets of genus 9-49, irregular vertices off
  // singularities / quads over 2.5x the target: 0: 153 / 514; 0.25: 196 / 336; 0.5: 193 /
  // 332; 1: 182 / 478 (patch by patch: 298 / 324).
  double corner_side_weight = 0.5;
  // Two curves meeting at a node at less than 45° are a cusp: field lines converging, not a
  // corner. The sector between them reads 0 quarter turns, so the patch there is a
  // triangle with an empty side, which quantization collapses onto one curve, instead of a
  // triangle that needs a forced fourth corner (a valence-3 vertex beside a valence-5
  // one). Only where that patch is small and off the loops; false: such sectors read as
  // quarter turns.
  bool cusp_corners = true;
  // A cusp patch collapses only while thin: on average under this many target edges wide
  // (its area over its length), the side across from its empty side under
  // cusp_collapse_across target edges. Wider ones read their cusps as quarter turns. At
  // 0.5 and 1 (earlier versions) the 5 x 5 net's CLI cage had 100 irregular vertices away
  // from singularities; at 0.75 and 1.5, 90 (docs/quad_method.md).
  double cusp_collapse_width = 0.75;
  double cusp_collapse_across = 1.5;
  // A four-cornered patch one of whose pairs of opposite sides differs by more than this
  // factor (the longer at least 3 cage edges) is a wedge, a triangle read as a rectangle:
  // quantization could balance it only by squeezing the longer side, so it gets one more
  // cut across. 0: never.
  double wedge_cut_ratio = 2.0;
  // Rounds of extra cuts for patches that are not disks with four corners.
  int max_fix_rounds = 64;
  // Rounds of extra cuts stop (the layout choice fails) once this many rounds in a row
  // have left no fewer patches to fix (optional wedge cuts not counted) than the fewest
  // an earlier round left: such a layout keeps trading one invalid patch for another (the
  // 5 x 5 net's requested layout: 2 to 5 for 55 rounds). The 3 x 3 net's requested
  // layout needs 22 such rounds before its last patch becomes a disk. 0: never.
  int fix_rounds_without_progress = 24;
  // A patch that is not a disk is cut from the points of its boundary farthest from any
  // node, at most this many from one stretch between nodes (24 in all): the middle of one
  // long arc can lie where the patch is a strip one triangle wide, where no cut traces.
  // With no limit (0, earlier versions) the CLI 6 x 6 net's requested layout cycled
  // (round 33 gave back round 31's layout); with 3 it converges (docs/quad_method.md).
  int middle_cuts_per_stretch = 3;
  // A pinched patch (a disk whose boundary passes one vertex twice, e.g. round an island
  // of curves that touches its outer boundary at one vertex) is first cut by the shortest
  // path between its boundary's two stretches either side of that vertex (cut_pinch):
  // cuts from the middle of an arc only peel pieces off it. false: not.
  bool cut_pinches = true;
  // Rounds of merging patches whose sides cannot balance, before quantization gives up.
  // With arrival_chord, 8 were too few for the genus-49 net at h 0.1; 16 are enough.
  int max_balance_rounds = 16;
  // Rounds of merging the patches under quads that the untangling left turned over (a
  // tangle) with a neighbour and filling the layout again, before the layout choice fails.
  int max_tangle_rounds = 3;
  // After the first layout choice whose cage meets issue 5's targets, further choices are
  // tried (the best cage is kept) as long as choices × the component's triangles (after
  // refinement) stays within this, counting only choices that traced a layout not seen
  // before; the search stops at once when a cage meets the targets with a margin and has
  // no irregular vertex away from singularities. 6e5: all
  // choices on components of ≤ 25k triangles, 3 on lattice's 190k.
  double work_after_meeting = 6e5;
  // Choices tried after the first one that meets the targets however large the component
  // (work_after_meeting allows none over 600k triangles). The second choice is the
  // requested layout with arrival_chord flipped, and it runs beside the requested one on
  // a second thread: on two cores it costs wall time only where it takes longer (genus 64
  // at h 0.12 alone: quad 11.7 → 16.5 s; the genus-36 net's requested layout has every
  // irregular vertex at a singularity, so its search stops there: 8.2 s). The layout depends
  // chaotically on such a choice (bench/quad_sweep's nets: a different chord length gave
  // 175 → 223 irregular vertices off singularities, single nets 6 → 26 and 15 → 5), so of two
  // the better is kept: 25 nets (genus 9–49, h 0.1–0.14) 175 → 151 off singularities,
  // oversized quads 1465 → 1297; genus 64 84 → 65, oversized 1108 → 834. 0: as the
  // budget allows.
  int min_choices_after_meeting = 1;
  // Quantization's integer program stops once its solution is provably within this
  // fraction of the optimal cost (GLPK's mip_gap). A genus-64 net's programs (7–8k arcs)
  // then stop in 2–4 s instead of running into the time limit (below) at a gap of 0.1%,
  // whose solution depended on the machine's speed; the fixtures' programs are solved at
  // the root or within a few nodes either way.
  double quantize_gap = 0.005;
  // Work per component for trying layout choices, counted from the attempts themselves so
  // that the search stops at the same choice on every machine and at any load: tracing
  // counts 2 per triangle of the (refined) component, each round of building patches 1
  // per triangle, each branch-and-bound node of quantization 15 per arc, filling and
  // untangling 850 per quad (weights from timing the genus-64 net's attempts: about 2.5
  // million units per second of one core of the machine in README). Once the attempts
  // taken in choice order have spent it, no further choice is taken (the requested one
  // always runs) and the best cage so far is kept, or the fallback cage if none is valid.
  // A genus-64 net (bench/run net8) otherwise tries every choice at 15-25 s each.
  double work_per_component = 3e8;
  // Each integer program's time limit, a last resort: quantization stops at quantize_gap
  // first on every layout measured (a genus-64 net's within 4.3 s).
  double quantize_seconds = 10;
  // Layout choices tried at once, each on its own thread (0: the machine's hardware
  // threads, at most 4). The kept cage does not depend on it: results are taken in
  // choice order as if run one after another, the work budget included.
  int parallel_choices = 0;
  // Global density multiplier on the field's sizes (2 ⇒ twice as many quads per side).
  double density = 1.0;
  // Separatrices follow mesh edges: the component's triangles are split (at most
  // max_refine_levels times, each halving its edges) until a target cage edge spans at
  // least this many mesh edges. 0: trace on the design's own edges (but for the splits
  // round singular vertices, refine.cpp, which are always made).
  double trace_edges_per_cage_edge = 4.0;
  int max_refine_levels = 2;
  // Interior cage vertices wanted per quarter turn of singularity index (Σ|index| over the
  // component's traced singularities); where the field's sizes give fewer, the density is
  // raised for that component (reported). A valence-5 vertex is one quarter turn: 35 keeps
  // irregular vertices, with those the layout adds, under the 5% of issue 5 (nets 96.6–
  // 97.5% valence 4, lattice 97.7%). Raising more is worse: tracing is refined at most
  // max_refine_levels times, so a denser cage has fewer mesh edges per cage edge to trace
  // in, and more slivers and corner mismatches. 25 nets (irregular vertices off
  // singularities / oversized / skewed; every layout that leaves any read again, as
  // before off_node_share): 50: 105 / 1363 / 1288; 40: 75 / 819 / 865;
  // 35: 61 / 596 / 685; 30: 70 / 718 / 857. On net7 at h 0.14, 80 and 120 gave 59 and 71 off
  // (30 at 50). 0: never raise.
  double vertices_per_singular_quarter = 35.0;
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
  // patches gutted to make opposite sides equal (the genus-16 net at h 0.11: a stub 2-3
  // quads across, its end an arc of 2 edges where the size field asks 4.1). Measured
  // against the size field at QuadOptions::density, not at the density raised for dense
  // singularities (the nets' 2.2×, under which arcs left at 0 edges to balance are
  // common). Oversized quads (an edge over 2.5× the raised target) miss it.
  // quad_detail::squeezed_arcs.
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

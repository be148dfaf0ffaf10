// quad/detail/layout.h — internals of quad/: the layout curves (boundary loops and traced
// separatrices), field-guided tracing along mesh edges (trace.cpp), and how a node's
// sectors are read (arcs.cpp, corners.cpp).
#pragma once
#include <algorithm>
#include <set>
#include <utility>
#include <vector>

#include "quad/detail/surface.h"

namespace genbrep::quad_detail {

// Layout curves: the component's loops first (closed), then traced separatrices (open,
// from a start node to the vertex where they hit the layout).
struct Curve {
  std::vector<int> vertices;
  std::vector<Vec3> direction;  // per vertex: unit tangent along the curve
  bool closed = false;
  int loop = -1;                // partition loop index for loops
  bool link = false;            // a separatrix's short jog onto a parallel curve (trace.cpp)
};

struct Layout {
  std::vector<Curve> curves;
  std::vector<int> edge_curve;       // per mesh edge: curve on it, -1 none
  std::vector<char> claimed;         // per vertex: on a curve
  std::vector<char> node;            // per vertex: layout node
  std::vector<Vec3> halfedge_dir;    // per halfedge on a curve: tangent at from(h) along h
  std::vector<char> on_loop;         // per vertex: on a boundary loop
  bool allow_crossing = false;      // separatrices (not repair cuts) cross transversally
  double length_cap = 0;             // traces cross others only before this length
  double merge_parallel = 0;         // join a nearly parallel curve closer than this × size
  double arrival_snap = 0;           // QuadOptions::arrival_snap (0: off)
  bool arrival_chord = false;        // QuadOptions::arrival_chord
  int parallel_joins = 0;
  // Cusp sectors (by outgoing halfedge) read as quarter turns after all, because the
  // layout did not balance with them (straighten_cusps).
  std::set<int> no_cusp;
  // Where a node whose sectors do not add up to its quarter turns costs
  // QuadOptions::off_node_price instead of kCornerNodePrice: (point, radius), the
  // irregular vertices an earlier cage of this layout left away from singularities.
  std::vector<std::pair<Vec3, double>> costly_nodes;
  std::vector<int> attractors;       // traced singular vertices (separatrices end on them)
  // Per attractor: its separatrix directions (a walk heads for it only along a free one).
  std::vector<std::vector<Vec3>> attractor_directions;
  int separatrices = 0;
  int cancelled_pairs = 0;
  int dropped_traces = 0;
  int patch_rounds = 0;  // build_patches rounds run on this layout (the search's work budget)
  // The index of v among the attractors, -1 if it is not a traced singular vertex.
  int attractor_index(int v) const {
    const auto at = std::find(attractors.begin(), attractors.end(), v);
    return at == attractors.end() ? -1 : static_cast<int>(at - attractors.begin());
  }
  bool attractor(int v) const { return attractor_index(v) >= 0; }
  // Whether p lies within one of the costly_nodes spots.
  bool costly(const Vec3& p) const {
    for (const auto& [point, radius] : costly_nodes)
      if ((p - point).norm() <= radius) return true;
    return false;
  }
};

// A walk heads straight for a singular vertex ahead once within this × the local target
// edge length (at density 1) of it (trace_direction): its last steps there follow the way
// to the singularity, not the field, so a turn against the field among them is not read
// as a corner (QuadOptions::kink_nodes), except near an irregular vertex an earlier cage
// of the layout left unexplained (Layout::costly_nodes; layout.cpp: mark_kinks).
constexpr double kCaptureReach = 0.75;

// Starts a layout from the component's loops (nodes at boundary singularities).
Layout start_layout(const Surface& s);
// Marks curve c on the edge/halfedge tables (after its vertices and directions are set).
void register_curve(const Surface& s, Layout& layout, int c);
// Takes the stretch vertices[first..last] of open curve c off the layout; what remains
// before it stays curve c (empty if nothing), what remains after it becomes a new curve.
// Vertices of the stretch are released unless another curve or a singularity holds them.
void remove_arc(const Surface& s, Layout& layout, int c, int first, int last);
// Walks from `vertex` along d (first step restricted to the `allowed` outgoing halfedges),
// snapping to the field at every vertex if `snap_to_field`, until it reaches a claimed
// vertex (motorcycle graph), and registers the curve; false (nothing registered) if it
// cannot leave or finds no end. With layout.merge_parallel > 0 a walk that comes that
// close (× the local target size) to an earlier, nearly parallel curve ends there and a
// link curve (Curve::link) of at most two edges joins it to that curve.
bool trace_direction(const Surface& s, Layout& layout, int vertex, std::vector<int> allowed,
                     Vec3 d, bool snap_to_field);
// Traces from `vertex` into the sector from outgoing halfedge `first` counter-clockwise to
// `last` (first == last: the whole fan), towards polar angle `fraction` of the sector,
// snapped to the nearest field direction. Returns false (and traces nothing) when no edge
// leaves into the sector. Stops at the first claimed vertex (motorcycle graph).
bool trace_from(const Surface& s, Layout& layout, int vertex, int first, int last,
                double fraction, bool snap_to_field);
// A cut across a pinched patch (a disk whose boundary passes a vertex twice): the shortest
// path along mesh edges through the patch's `faces` from a vertex of `from` to one of
// `to` (the boundary's two stretches between its visits of that vertex), through
// unclaimed vertices only, registered as a curve with field-snapped directions. A cut from
// the middle of an arc seldom reaches the other stretch: it peels a piece off the patch,
// and the pinch stays. False (nothing registered) if there is no such path.
bool cut_pinch(const Surface& s, Layout& layout, const std::vector<int>& faces,
               const std::vector<int>& from, const std::vector<int>& to);
// Separatrices of every interior singularity and concave boundary corner.
void trace_separatrices(const Surface& s, Layout& layout, const QuadOptions& options,
                        Messages& messages);

// The angle (radians, counter-clockwise) of the patch sector at from(h_out) between its
// boundary halfedges h_out (leaving) and h_in (entering), read from the curves' tangents,
// or from the curves themselves where the tangents nearly coincide (a cusp ≈ 0 against a
// full turn) and at a singular vertex of `valence` > 0 (scaled by valence / 4).
double sector_angle(const Surface& s, const Layout& layout, int h_out, int h_in, int valence);

// The quarter turns of the patch sector at from(h_out) that starts along h_out, read
// together with every other sector at that node: the curves' directions there are placed
// on one grid of quarter turns (each rounded once, at the offset that puts them closest to
// it), and a sector reads the difference of its two ends. A node's sectors then add up to
// what their angles do (4 inside, a traced singularity's `valence`), where rounding each
// sector alone can leave an irregular vertex (curves at 45°, 180° and 270° read 2 + 1 + 2).
// -1 where the node is on a loop, has one curve, or its sectors' angles do not add up to a
// whole number of quarter turns.
int node_quarters(const Surface& s, const Layout& layout, int h_out, int valence);

}  // namespace genbrep::quad_detail

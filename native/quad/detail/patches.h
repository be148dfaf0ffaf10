// quad/detail/patches.h — internals of quad/: the patch layout: arcs between nodes, four-sided
// patches and their corners (patches.cpp, corners.cpp), integer counts (quantize.cpp), merging
// patches that cannot balance (arcs.cpp) and filling them with quads (fill.cpp).
#pragma once
#include <map>
#include <memory>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "quad/detail/layout.h"

namespace genbrep::quad_detail {

struct Arc {
  std::vector<int> vertices;  // node to node along a curve
  int curve = -1;
  double length = 0;
  double target = 0;          // length / local size
  int count = 1;              // quantized number of cage edges
};

struct Patch {
  std::vector<int> faces;
  // Four sides counter-clockwise (patch on the left); each a list of (arc, reversed).
  std::vector<std::vector<std::pair<int, bool>>> sides;
  double quads = 0;  // Σ area / (size_u · size_v) over its faces: the quads it holds at density 1
  std::vector<int> cusps;  // outgoing boundary halfedges of its cusp corners (empty sides)
};

struct PatchLayout {
  std::vector<Arc> arcs;
  std::vector<int> halfedge_arc;       // per halfedge on an arc: arc id, -1 none
  std::vector<Patch> patches;
  std::vector<std::vector<int>> loop_arcs;  // per curve that is a loop: its arcs in order
  int recornered = 0;
  int cusps = 0;  // patches with a cusp corner (an empty side), collapsed by quantization
  int removed_stretches = 0;
  int pinches_cut = 0;  // pinched disks cut between their two stretches (cut_pinch)
  // Of quantize's integer programs: the last one's cost, and the branch-and-bound nodes
  // of all it solved (each counts at least its root).
  double quantize_cost = 0;
  int quantize_nodes = 0;
};

// Counter-clockwise angle in (0, 2π] from a to b in the tangent plane of normal n.
double ccw_angle(const Vec3& a, const Vec3& b, const Vec3& n);
// Splits the layout's curves into arcs at its nodes (into out.arcs, out.halfedge_arc,
// out.loop_arcs): a vertex is a node where curves meet or end, and with `kink_nodes` where
// a curve turns a quarter turn against the field (arcs.cpp: mark_kinks).
void build_arcs(const Surface& s, Layout& layout, bool kink_nodes, PatchLayout& out);
// The next patch-boundary halfedge after h: rotate around to(h) inside the patch.
int next_on_boundary(const Surface& s, const Layout& layout, int h);
// Takes the stretch `vertices` (consecutive along one open curve, either way round) off the
// layout; false if it is no longer there (an earlier fix changed that curve).
bool remove_stretch(const Surface& s, Layout& layout, std::vector<int> vertices);
// The vertices of the shortest of `arcs` that lies on an open curve (a separatrix or cut,
// not a loop) and whose ends are not in `passed`; empty if there is none.
std::vector<int> shortest_open_arc(const Layout& layout, const PatchLayout& patches,
                                   const std::vector<int>& arcs,
                                   const std::set<std::pair<int, int>>& passed = {});

// A thin cusp patch collapses onto one curve only while on average under kCuspCollapseWidth
// target edges wide (area over length) and its side across from the empty side is under
// kCuspCollapseAcross target edges; a wider one squeezes the quads beside it.
constexpr double kCuspCollapseWidth = 0.75, kCuspCollapseAcross = 1.5;
// Cuts into a patch that is not a disk start at most this many from one stretch between
// nodes: the middle of one long arc can lie where no cut traces, and the rounds then cycle.
constexpr int kMiddleCutsPerStretch = 3;
// What a node whose sectors do not add up to its quarter turns costs, per quarter turn,
// against re-reading sectors (choose_corners' node price outside Layout::costly_nodes).
constexpr double kCornerNodePrice = 2.0;
// Re-reading a sector of a patch one corner off also costs this times how far the patch is
// then from a rectangle (best_corners' side term), which the flow alone cannot weigh.
constexpr double kCornerSideWeight = 0.5;

// Σ target (length / local size, at density 1) of the arcs on side k of `patch`.
double side_target(const std::vector<Arc>& arcs, const Patch& patch, int k);

// What build_patches read of a layout: its patches (faces, boundary cycles, corner
// readings) and the layout as it was when they were read. Handed to the next
// build_patches call on the same layout after a few changes (a merged patch, cusps taken
// back), it lets that call read again only the patches around the changes. Owned by the
// caller, one per layout; empty: everything is read.
struct PatchReading {
  PatchReading();
  ~PatchReading();
  struct State;
  std::unique_ptr<State> state;
};

// A patch's corner at a layout node: the sector of the patch between the boundary
// halfedges leaving and entering the node, its angle and its quarter turns.
struct Corner {
  int halfedge_out;  // patch boundary halfedge leaving the node
  int halfedge_in;   // patch boundary halfedge entering it
  double angle;
  int quarters;   // as used: the reading, or its override
  int read = 2;   // the reading
};

struct Cycle {
  std::vector<int> halfedges;  // patch on the left, in order
  std::vector<Corner> nodes;   // nodes met along the cycle, in order
};

// Per patch: its faces, and its cycles and Euler characteristic as read from the layout
// (corner readings before overrides).
struct Examined {
  std::vector<int> faces;
  long chi = 0;
  std::vector<Cycle> cycles;
};

// The four corners of a disk patch among the nodes of its boundary cycle that best make a
// rectangle: corner angles near a quarter turn, other nodes near straight, and the two
// pairs of opposite sides of nearly equal length (in target edges, as quantization needs
// them equal). A cusp (read 0) stays one and counts as two corners with an empty side
// between them, so 4 − 2 · cusps corners are chosen. Exhaustive over the choices among the
// m nodes (m ≤ 40 here). Returns the quarters of every node (0, 1 or 2), or nothing when
// there are too few nodes or too many.
std::vector<int> best_corners(const std::vector<Corner>& nodes, const std::vector<double>& after,
                              double* best_cost);
// A sector's quarter turns: its override, if any, else its reading. Once the rounds stall,
// an override no longer hides a dangling end (build_patches).
int read_with_override(const std::map<int, int>& quarter_override, const Corner& k, bool stalled);
// Whether a patch of one boundary cycle passes a vertex twice (a pinched disk).
bool passes_a_vertex_twice(const Surface& s, const std::vector<Cycle>& cycles);
// The corners of every patch chosen at once (corners.cpp) before build_patches looks at
// each alone: disks (one cycle, χ = 1, no vertex twice, no reflex or dangling reading) take
// part; the others keep their readings and are cut. The choices go into quarter_override;
// returns how many sectors it re-read.
int read_corners_together(const Surface& s, const Layout& layout, const QuadOptions& options,
                          const std::map<int, int>& singular_valence, const PatchLayout& out,
                          const std::vector<Examined*>& patches, bool stalled,
                          std::map<int, int>& quarter_override);

// One sector of a patch boundary at a layout node, for choose_corners.
struct SectorChoice {
  int patch = -1;      // the patch (0 .. patches − 1), or -1: left out, its readings kept
  int node = -1;       // the node (vertex)
  double angle = 0;    // the sector's angle (radians; sector_angle)
  int quarters = 2;    // its reading (overrides applied)
  bool free = false;   // read 1 or 2, may become the other
  double side_cost = 0;  // added to the cost of re-reading it (quarter turns)
};
// Quarter turns for every sector, chosen at once (corners.cpp): every patch of `patches`
// whose free sectors can make it four-cornered is made so, with the fewest quarter turns
// moved off the angles and the fewest nodes whose sectors do not add up to their
// `node_target` (vertex → quarter turns; 4 where absent), each such unit priced
// `node_price` quarter turns of angle, or at a node of `node_prices` its own price.
// Returns the chosen quarters, in the order given.
std::vector<int> choose_corners(const std::vector<SectorChoice>& sectors, int patches,
                                const std::map<int, int>& node_target, double node_price,
                                const std::map<int, double>& node_prices = {});

// Splits curves into arcs and faces into patches; fixes patches that are not four-cornered
// disks with extra traces. Throws Error{StageFailure} if some patch stays invalid.
// `reading` (optional): what an earlier call on this layout read; updated to what this one
// read. The patches are the same with or without it.
PatchLayout build_patches(const Surface& s, Layout& layout, const QuadOptions& options,
                          Messages& messages, PatchReading* reading = nullptr);

// Integer counts per arc (≥ 1, near length / size) with equal opposite sides, by an exact
// integer program (quantize.cpp); false with the reason in `failure` if none exists.
// `relaxed`: the layout needed long interior arcs at 0 edges to balance (reported).
// Each integer program stops once within options.quantize_gap of the optimum, or at
// options.quantize_seconds (at least 1 s) as a last resort.
bool quantize(PatchLayout& patches, const QuadOptions& options, std::string* failure,
              bool* relaxed);
// The arcs with at most kSqueezedShare of the cage edges the size field asks for on them
// at `density` (Arc::target × density; the caller's, before any raise for dense
// singularities), among those where it asks kSqueezedTarget or more
// (QuadStats::squeezed_arcs).
constexpr double kSqueezedShare = 0.5, kSqueezedTarget = 3.0;
int squeezed_arcs(const PatchLayout& patches, double density);
// Frees the calling thread's integer-programming state (GLPK keeps one per thread); for
// threads that ran quantize and end.
void release_quantize_thread();

// The patches whose side equalities cannot all hold even with every interior arc free to be
// 0 (loop arcs ≥ 1), or only with a side of a patch on a loop at 0 (quantize keeps an edge
// there): those that need slack in the LP that minimises the total imbalance.
std::vector<int> unbalanced_patches(const PatchLayout& patches);
// Merges `patch` with a neighbour by taking the shortest separatrix arc on its boundary off
// the layout (build_patches is then run again); false if it has none left to remove.
// `removed` holds the ends (lower first) of the stretches taken off so far, and an arc
// between such ends is passed over: a fix in build_patches can trace a stretch taken off
// again, and taking it off once more gives back the same layout round after round.
bool merge_patch(const Surface& s, Layout& layout, const PatchLayout& patches, int patch,
                 std::set<std::pair<int, int>>* removed);
// Takes back the cusp readings of `patch`, or if it has none, of every cusp patch that
// shares an arc with it (Layout::no_cusp; build_patches is then run again); returns how
// many were taken back.
int straighten_cusps(Layout& layout, const PatchLayout& patches, int patch);

// Cage from the quantized layout. `quad_patch` (optional): per quad of the cage, the index
// of the patch (in patches.patches) it fills.
QuadCage fill_patches(const Surface& s, const Layout& layout, const PatchLayout& patches,
                      Messages& messages, std::vector<int>* quad_patch = nullptr);

}  // namespace genbrep::quad_detail

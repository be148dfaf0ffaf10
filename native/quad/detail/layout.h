// quad/detail/layout.h — internals of quad/: the surface view of one organic component,
// field-guided tracing along mesh edges, the patch layout and its filling.
#pragma once
#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <atomic>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "core/cage.h"
#include "core/error.h"
#include "core/types.h"
#include "field/field.h"
#include "partition/partition.h"
#include "quad/quad.h"

namespace genbrep::quad_detail {

// What a step says about its work, as QuadResult splits it: `warnings` where the cage
// falls short of what was asked (a repair, a squeezed quad, a fallback), `notes` on how it
// was made (refinement, collapsed slivers, the layout choice kept).
// Set by the layout search once an attempt's result can no longer be used (an earlier
// choice of the same batch made the search stop, quad.cpp): the attempt gives up at its
// next check (between phases, sweeps, rounds) instead of running to its end. Default: never.
class Dropped {
 public:
  Dropped() = default;
  explicit Dropped(const std::atomic<bool>* flag) : flag_(flag) {}
  // Throws Error{StageFailure} once the attempt is dropped.
  void check() const {
    GENBREP_CHECK(!stopped(), Code::StageFailure,
                  "quad: a layout choice dropped (the search stopped before it)");
  }
  bool stopped() const { return flag_ && flag_->load(std::memory_order_relaxed); }

 private:
  const std::atomic<bool>* flag_ = nullptr;
};

struct Messages {
  Diagnostics warnings;
  Diagnostics notes;
  void append(const Messages& other) {
    warnings.insert(warnings.end(), other.warnings.begin(), other.warnings.end());
    notes.insert(notes.end(), other.notes.begin(), other.notes.end());
  }
};

// The design with one component's triangles split round its singular vertices (two edges
// per separatrix at each) and then `levels` (≥ 0) times (refine.cpp): the same surface,
// finer for tracing; vertex indices and the first child of every triangle keep their
// index, so loops and singularities carry over unchanged. Empty (no faces) where nothing
// needed splitting.
struct RefinedDesign {
  TriMesh mesh;
  Partition partition;
  CrossField field;
  int levels = 0;
};
RefinedDesign refine_component(const TriMesh& design, const Partition& partition,
                               const CrossField& field, int component, int levels);

// Read-only geometry of one organic component with the field on it.
struct Surface {
  Surface(const TriMesh& mesh, const Partition& partition, const CrossField& field,
          int component);
  const TriMesh& mesh;
  const Partition& partition;
  const CrossField& field;
  int component;
  std::vector<Vec3> point;          // per vertex
  std::vector<Vec3> face_normal;    // per face (unit)
  std::vector<Vec3> vertex_normal;  // per vertex, from the component's faces only
  std::vector<double> vertex_size;  // mean target edge length of the component faces around
  std::vector<int> vertices;        // vertices touched by the component's faces
  bool in(int face) const { return face >= 0 && partition.face_component[face] == component; }
  // Face of the halfedge (-1 at a mesh border). Inline: the layout's flood fill and
  // patch examination call these for every halfedge of the component, every round.
  int face(int halfedge) const {
    const auto fh = mesh.face_handle(mesh.halfedge_handle(halfedge));
    return fh.is_valid() ? fh.idx() : -1;
  }
  int from(int halfedge) const {
    return mesh.from_vertex_handle(mesh.halfedge_handle(halfedge)).idx();
  }
  int to(int halfedge) const { return mesh.to_vertex_handle(mesh.halfedge_handle(halfedge)).idx(); }
  int opposite(int halfedge) const { return halfedge ^ 1; }
  // Next outgoing halfedge counter-clockwise around from(h): the face between them is face(h).
  int ccw(int halfedge) const;
  double corner_angle(int halfedge) const;  // angle at from(h) inside face(h)
  // The cross direction of `face` closest to `d` (one of its four rotations).
  Vec3 snap(int face, const Vec3& d) const;
  // Target edge length along direction d on `face` (size_u or size_v, whichever arm d follows).
  double size_along(int face, const Vec3& d) const;
  Vec3 tangent(int vertex, const Vec3& d) const;  // d projected into the vertex tangent plane
  // Quads the field's sizes put on a component face at density 1: area / (size_u · size_v).
  double face_quads(int face) const { return quads_on_face[face]; }
  std::vector<double> quads_on_face;  // per face; 0 off the component
};

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
  // QuadOptions::off_node_price instead of corner_node_price: (point, radius), the
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
// whole number of quarter turns (QuadOptions::node_readings).
int node_quarters(const Surface& s, const Layout& layout, int h_out, int valence);

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

// Closest points on the component's triangles (locate.cpp), with the normal of the face hit.
class ComponentLocator {
 public:
  explicit ComponentLocator(const Surface& s);
  ~ComponentLocator();
  Vec3 closest(const Vec3& p, Vec3* normal) const;
  // The same, starting the search from triangle *hint (a previous answer near p; -1: none)
  // and leaving the triangle hit there: the same point, found faster.
  Vec3 closest(const Vec3& p, Vec3* normal, int* hint) const;
  // The unit normals of the component's triangles that hold the point closest to p: its
  // triangle's, or where that point lies on an edge or a vertex (a point off a crease)
  // those of every component triangle there, so that the answer does not depend on which
  // of them the search met first (the hint).
  std::vector<Vec3> normals_at(const Vec3& p, int* hint) const;

 private:
  struct Impl;
  const Surface& surface_;
  std::unique_ptr<Impl> impl_;
};

// A quad whose normal is more than 75° from the design's at every corner spans a thin
// part (DesignNormals::spans_thin_part); a quad wrapping a third of a round strut is at
// 60°.
constexpr double kThinPartCosine = 0.26;

// The one test for a turned-over quad, shared by measure_cage and untangle_cage: the quad's
// normal (cross product of its diagonals) against the area-weighted vertex normal of the
// design vertex nearest its centroid (a uniform grid over the design's box, cells about
// 1.5 mean edges wide, vertices bucketed per cell; the nearest found exactly in O(1) cells
// for a point on the surface), and the thin-part test at its corners.
class DesignNormals {
 public:
  explicit DesignNormals(const TriMesh& design);
  int nearest_vertex(const Vec3& p) const;   // -1 if the design has no vertex
  Vec3 nearest_normal(const Vec3& p) const;  // zero if the design has no vertex
  // The same, and whether that vertex sits on a crease: one of its triangles' normals more
  // than acos(kFaceCheckCosine) = 30° from its normal, so that its normal does not stand
  // for the surface round it.
  Vec3 nearest_normal(const Vec3& p, bool* creased) const;
  // Whether a quad faces against the design: its normal ((c2 − c0) × (c3 − c1)) against
  // the design's at the vertex nearest its centre, or it spans a thin part.
  bool flipped(const Vec3 (&corner)[4]) const;
  // Whether the design turns away from the quad at all four corners (its normal there
  // more than acos(kThinPartCosine) from the quad's, `across` unnormalized): a quad cut
  // across a strut, its corners on opposite sides (seen on a genus-9 net, h 0.1: corners on
  // faces facing ±x, the quad facing −z, its centre 0.19 from the design).
  bool spans_thin_part(const Vec3 (&corner)[4], const Vec3& across) const;

 private:
  std::vector<Vec3> point_, normal_;
  std::vector<char> creased_;  // per vertex (nearest_normal)
  Vec3 lo_;
  double cell_ = 1;
  std::array<long, 3> cells_{};   // per axis
  std::vector<int> first_;        // per cell (x fastest) and one past the last: into vertex_
  std::vector<int> vertex_;       // the vertices of each cell, ascending
  std::array<long, 3> key(const Vec3& p) const;
};

// Per cage vertex: whether it lies on a boundary chain (never moved or merged away by
// untangle.cpp, not counted by irregular_off_singularities), the quads around it and its
// edge neighbours.
struct CageIncidence {
  explicit CageIncidence(const QuadCage& cage)
      : on_chain(cage.vertices.rows(), 0),
        quads_of(cage.vertices.rows()),
        neighbours(cage.vertices.rows()) {
    for (const auto& chain : cage.boundary_chains)
      for (int v : chain) on_chain[v] = 1;
    for (int q = 0; q < cage.quads.rows(); ++q)
      for (int k = 0; k < 4; ++k) {
        const int a = cage.quads(q, k), b = cage.quads(q, (k + 1) % 4);
        quads_of[a].push_back(q);
        neighbours[a].insert(b), neighbours[b].insert(a);
      }
  }
  std::vector<char> on_chain;
  std::vector<std::vector<int>> quads_of;
  std::vector<std::set<int>> neighbours;
};

// What measuring and repairing a cage test against, built once per component: closest
// points on the component and the design's vertex normals.
struct CageChecks {
  explicit CageChecks(const Surface& s) : surface(s), locator(s), normals(s.mesh) {}
  const Surface& surface;
  ComponentLocator locator;
  DesignNormals normals;
};

// Quads with an edge longer than `factor` × the local target edge length (the component's
// size at the design vertex nearest the quad's centre, divided by `density`): where
// quantization squeezed a patch whose opposite sides differ, its quads stretch across
// (quad.cpp).
int oversized_quads(const CageChecks& checks, const QuadCage& cage, double density,
                    double factor);
// A field singularity: where, and its index in quarter turns (−1: five quads meet there).
struct SingularPoint {
  Vec3 point;
  int index;
};
// How far a singularity explains an irregular vertex, in edges (the vertex's own mean
// edge or the local target edge, the longer): a traced singular node can end up about one
// edge off after the evening out and the merges of quantization (lattice: valence-5
// vertices 1.0–1.6 target edges from their −1 singularity; merged ones, valence 6 and 7,
// up to 2.2 target edges where the cage is twice as coarse as the target).
constexpr double kSingularReach = 2.0;
// Interior vertices of `cage` (not on a boundary chain) of valence ≠ 4 whose quarter turns
// (4 − valence) are not all explained by singularities of `singular` of the same sign
// within kSingularReach edges (the vertex's mean edge, or the local target edge — the
// design's size at the nearest vertex over `density` — if longer). Each singularity
// explains at most |index| quarter turns, nearest
// vertex–singularity pairs first; a valence-3 vertex beside a −1 singularity, or a second
// valence-5 vertex beside one, is not explained. O(irregular × singular).
int irregular_off_singularities(const CageChecks& checks, const QuadCage& cage,
                                const std::vector<SingularPoint>& singular, double density);
// An irregular interior cage vertex as irregular_off_singularities matches it: the quarter
// turns it carries (4 − valence), where it is, and how far a singularity explains it.
struct Irregular {
  int vertex;  // ties between equal distances go by vertex, then singularity
  int carries;
  Vec3 point;
  double reach;
};
// kSingularReach × (the vertex's mean edge, or the local target edge if longer).
double singular_reach(const CageChecks& checks, const QuadCage& cage,
                      const CageIncidence& incidence, int v, double density);
// A singularity of the same sign within reach of an irregular vertex (`entry`: its index
// in the list matched).
struct Explaining {
  double distance;
  int entry, point;
};
// Appends the singularities that can explain `irregular` (entry `entry`) to `pairs`.
void explaining_pairs(const Irregular& irregular, int entry,
                      const std::vector<SingularPoint>& singular, std::vector<Explaining>* pairs);
// The order the matching takes pairs in: nearest first, then by the entry's vertex
// (`vertex`), then by singularity. No two pairs share a key.
inline std::tuple<double, int, int> pair_order(const Explaining& pair, int vertex) {
  return {pair.distance, vertex, pair.point};
}
// Sorts `pairs` by pair_order, `vertex_of(entry)` giving each entry's vertex.
template <class VertexOf>
void sort_pairs(std::vector<Explaining>& pairs, VertexOf vertex_of) {
  std::sort(pairs.begin(), pairs.end(), [&](const Explaining& a, const Explaining& b) {
    return pair_order(a, vertex_of(a.entry)) < pair_order(b, vertex_of(b.entry));
  });
}
// irregular_off_singularities' matching of `pairs` (sorted here by pair_order): nearest
// first, each singularity explaining at most |index| quarter turns. Per entry of
// `irregular`, the quarter turns left unexplained (0: explained), into `carries`.
void match_pairs(std::vector<Explaining>& pairs, const std::vector<Irregular>& irregular,
                 const std::vector<SingularPoint>& singular, std::vector<int>* carries);
// The same with `pairs` already sorted, and `carries` holding, per entry, the quarter turns
// it carries.
void match_sorted_pairs(const std::vector<Explaining>& pairs,
                        const std::vector<SingularPoint>& singular, std::vector<int>* carries);
// The interior irregular vertices of `cage` (`incidence` its CageIncidence) as
// irregular_off_singularities matches them, and per entry in `left` the quarter turns no
// singularity explains.
std::vector<Irregular> matched_irregulars(const CageChecks& checks, const QuadCage& cage,
                                          const CageIncidence& incidence,
                                          const std::vector<SingularPoint>& singular,
                                          double density, std::vector<int>* left);

// measure_cage (quad.h) with the design's normals already built.
QuadStats measure_cage(const QuadCage& cage, const DesignNormals& normals);
// The same with the component: a quad is flipped by turned_over, which also finds one
// that stands on the surface under it. The stage measures with this one.
QuadStats measure_cage(const QuadCage& cage, const CageChecks& checks);
// Whether a quad faces against the component's triangles at the point closest to its
// centre, or stands on them: its normal (the cross product of its diagonals) more than
// kStandingDegrees from theirs (ComponentLocator::normals_at). *hint as in
// ComponentLocator::closest.
constexpr double kStandingDegrees = 80.0;
bool faces_away(const ComponentLocator& locator, const Vec3 (&corner)[4], int* hint = nullptr);
// The one test for a turned-over quad where the component is at hand (measure_cage with
// the checks, and the untangling's, evening out's and squaring's quad_is_bad, so that a
// move they allow never makes a cage the measure rejects): DesignNormals::flipped, and
// unless the quad's normal is within acos(kFaceCheckCosine) = 30° of the nearest design
// vertex's and that vertex is not on a crease, faces_away. (On a crease the vertex's
// normal is the mean of two sides: a quad folded over the genus-16 net's crease (h 0.12,
// node price 2) agreed with it but was 95° from the triangle under its centre.) The
// design vertex nearest a quad's centre can lie round a fillet from the surface under it:
// the 5 x 5 net (h 0.12, traces reaching singularities by route_to) had quads at 92° and
// 114° to the triangle under them that agreed with that vertex within 45°, the bound
// before. Looking up every quad costs 2.2 s on the 6 x 6 net.
constexpr double kFaceCheckCosine = 0.866;
bool turned_over(const DesignNormals& normals, const ComponentLocator& locator,
                 const Vec3 (&corner)[4], int* hint = nullptr);

// Opens up degenerate or turned-over quads of a filled cage: the interior cage vertices
// within a few rings of them are smoothed and projected back onto the component, for at
// most `max_rounds` rounds (untangle.cpp). Returns how many vertices moved.
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
// Returns the windows edited (0: the cage is unchanged).
int place_irregulars(const CageChecks& checks, QuadCage& cage,
                     const std::vector<SingularPoint>& singular, double density, int max_rounds,
                     const PlaceSettings& settings = PlaceSettings(),
                     const Dropped& dropped = Dropped());
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
// Whether a quad with corners `c` has a corner under `min_corner_degrees` (or two corners
// at one point), or is turned over (turned_over). *hint as in ComponentLocator::closest.
bool corners_bad(const ComponentLocator& locator, const DesignNormals& normals,
                 const Vec3 (&c)[4], double min_corner_degrees, int* hint = nullptr);
// Smooths the interior vertices around squeezed (a corner under 5°) or turned-over quads,
// as the untangling does, for at most `max_rounds` rounds; returns how many stay so.
int open_squeezed(const CageChecks& checks, QuadCage& cage, int max_rounds);
// Quads still bad after smoothing get a diagonal collapsed (when the link condition allows)
// and the smoothing is repeated; `collapsed` counts them (each leaves irregular vertices).
int untangle_cage(const CageChecks& checks, QuadCage& cage, int max_rounds, int* collapsed,
                  const Dropped& dropped = Dropped());

// Whether cage a is to be kept rather than cage b among a component's layout choices:
// meeting issue 5's targets, then no collapsed quad, then (both meeting) density, squeezed
// arcs, irregular vertices off singularities, skewed quads, irregular vertices, each with
// its margin, then the smaller mean corner deviation (quad.cpp).
bool better_cage(const QuadStats& a, const QuadStats& b);
// The same with whether each meets the targets given (judged on its squared angles).
bool better_cage(const QuadStats& a, bool meets_a, const QuadStats& b, bool meets_b);
// Whether a layout's second reading (QuadOptions::off_node_price) is kept over its first:
// fewer irregular vertices off singularities, and better_cage.
bool better_second_reading(const QuadStats& second, const QuadStats& first);

// The angle at `at` between the edges to a and b, in radians (measure_cage, the untangle,
// the squaring).
double corner_angle(const Vec3& at, const Vec3& a, const Vec3& b);

// Last resort: a pure-quad cage that is not field-aligned (fallback.cpp), from a coarse
// remesh at `coarse_edge_length` split once (cage edges about half that long).
QuadCage fallback_cage(const Surface& s, double coarse_edge_length);

// Cage from the quantized layout. `quad_patch` (optional): per quad of the cage, the index
// of the patch (in patches.patches) it fills.
QuadCage fill_patches(const Surface& s, const Layout& layout, const PatchLayout& patches,
                      Messages& messages, std::vector<int>* quad_patch = nullptr);

}  // namespace genbrep::quad_detail

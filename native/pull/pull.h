// pull/pull.h — boundary pull, paper §7.1–7.3.
// Takes: an organic surface as an open triangle sheet per organic component, each of its
// boundary loops tagged with the solids it borders (§7.1), and the input solids.
// Gives: the sheet with every boundary loop moved so that D(∂O) = max_t F(c(t)) ≤ η < 0,
// where F = σ·D_S, D_S the signed distance to the union S of the loop's bordering solids
// (≤ 0 inside) and σ the side of S the organic surface lies on (+1 outside: material grown
// from a keep-in or reaching a keep-out; −1 inside: a seed's eroded part). The boundary
// displacement is blended into a few rings of the interior so no triangle folds.
// The curve itself is abstract (BoundaryCurve: samples as sparse weights over control
// points, c(t_j) = Σ N_i(t_j) c_i), so the same descent pulls the polyline boundary of the
// stand-in sheet (hat functions over its boundary vertices) and, once fit/ lands, the limit
// boundary of a cage (EDGE_ONLY: the uniform cubic B-spline of the boundary chain, or the
// weights LimitSurface::weights gives on boundary edges).
// Guarantees: deterministic; a loop that does not converge within max_iterations is
// reported with the points that stay outside (a gap between solids, §9.1), never hidden.
// Complexity: O(iterations · samples · |S| · log |T_S|) distance queries per loop.
#pragma once
#include <array>
#include <vector>

#include "core/cage.h"
#include "core/error.h"
#include "core/types.h"
#include "incidence/incidence.h"
#include "partition/partition.h"

namespace genbrep {

// One boundary loop of a sheet: sheet vertex indices, closed (last joins first), organic
// side on the left (partition's convention), with the solids it borders.
struct SheetLoop {
  std::vector<int> vertices;
  std::vector<int> solids;
  int partition_loop = -1;
};

// The organic surface of one component as an open, oriented (outward of the design)
// triangle sheet whose boundary is exactly its loops.
struct OrganicSheet {
  int component = -1;
  TriangleMesh mesh;  // triangle_source: design triangle (stand-in) or cage quad
  std::vector<SheetLoop> loops;
};

// The stand-in organic surfaces: the organic triangles of each component of the partition,
// with `tangential_rounds` rounds of tangential Laplacian smoothing (λ = 1/2) of interior
// vertices: level sets of fields constant along an axis give exactly coplanar strips whose
// rounded slivers overlap, which exact predicates see as self-intersections; moving
// vertices within their tangent plane removes them and keeps the shape (it is a stand-in
// for the fitted surface, which replaces it).
std::vector<OrganicSheet> organic_sheets(const TriangleMesh& design, const Partition& partition,
                                         int tangential_rounds = 3);

// A closed curve c(t) = Σ N_i(t) c_i, sampled: sample s is Σ weights[k]·c[controls[k]] for
// k in [offsets[s], offsets[s+1]).
struct BoundaryCurve {
  int control_count = 0;
  std::vector<int> offsets{0};
  std::vector<int> controls;
  std::vector<double> weights;
  int sample_count() const { return static_cast<int>(offsets.size()) - 1; }
};

// The closed polyline through n control points (hat basis), `samples_per_edge` samples per
// edge starting at each control point.
BoundaryCurve polyline_curve(int control_count, int samples_per_edge);
// The closed uniform cubic B-spline of n ≥ 3 control points: the Catmull–Clark limit
// boundary of a cage chain under EDGE_ONLY (no boundary creases), for the cage variant.
BoundaryCurve cubic_bspline_curve(int control_count, int samples_per_span);

// F(p) = σ · min_j D_j(p) over a set of solids (the union's signed distance outside,
// its depth bound inside) and its gradient, the unit normal at the projection point (§7.2's
// normal approximation; central differences when p lies on the surface).
class SideDistance {
 public:
  SideDistance(const SolidSet& solids, std::vector<int> members, int side);
  double value(const Vec3& p, Vec3* gradient = nullptr) const;

 private:
  const SolidSet* solids_;
  std::vector<int> members_;
  int side_;
  double scale_;
};

struct PullOptions {
  int max_iterations = 100;     // descent steps per η (paper: e.g. 100)
  double overshoot = 0.25;      // each step aims at (1 + overshoot)·η, dimensionless
  int samples_per_edge = 4;     // stand-in polyline: samples per boundary edge
  int blend_rings = 3;          // interior rings the boundary displacement fades over
  int max_blend_rings = 24;     // rings are doubled up to this while triangles fold
  // Cages (pull_cage): n, the limit tessellation's segments per cage edge; the boundary is
  // pulled at those limit samples and at samples_per_edge points on each chord between
  // them, so the tessellated boundary polyline is inside S, not only the limit curve.
  int cage_samples_per_edge = 4;
  int cage_blend_rings = 2;     // rings of the quad graph the boundary move fades over
  int cage_max_blend_rings = 8; // doubled up to this while a tessellation triangle folds
  // §7.2 local refinement (pull_cage): rounds of boundary vertex insertion where a chain
  // does not converge, each followed by a new pull; 0 disables it.
  int max_insertions = 3;
  // A refinement round is not made when the refined cage would have more than
  // max_insertion_growth × the input cage's quads + 64 (strips cross the whole component;
  // a boundary stuck nearly everywhere is not the local failure insertion is for).
  double max_insertion_growth = 4.0;
};

struct CurvePull {
  bool converged = false;
  int iterations = 0;
  double max_before = 0;         // max_t F(c(t)) before, design units
  double max_after = 0;          // and after
  std::vector<int> stuck_samples;  // samples still above η
};

// §7.2: gradient descent on the control points until max_t F(c(t)) ≤ η. Each violating
// sample asks for the displacement δ = −(F − η')·∇F (η' = (1+overshoot)·η); a control
// point takes the largest of N_i·δ/ΣN_k² over the samples in its support.
CurvePull pull_curve(const BoundaryCurve& curve, const SideDistance& distance, double eta,
                     const PullOptions& options, std::vector<Vec3>* controls);

struct LoopPull {
  int side = 1;                  // σ: +1 organic outside the loop's solids, −1 inside
  CurvePull curve;
  double max_displacement = 0;   // design units
  std::vector<Vec3> stuck_points;  // positions of samples still above η
  int inserted_vertices = 0;       // cages: boundary vertices inserted into this chain (§7.2)
};

struct SheetPull {
  OrganicSheet sheet;            // the pulled sheet (same topology as the input)
  double eta = 0;
  std::vector<LoopPull> loops;   // per sheet loop
  int blend_rings = 0;           // rings actually used
  int folded_triangles = 0;      // triangles whose normal turned over (0 unless reported)
  bool converged() const;
  Diagnostics diagnostics;
};

// Pulls every loop of `sheet` to η (< 0) and blends the displacement into the interior.
SheetPull pull_sheet(const OrganicSheet& sheet, const SolidSet& solids, double eta,
                     const PullOptions& options);

// ---- Cages (§7.2 on the limit boundary of a fitted QuadCage) ----

// The limit surface of `cage` tessellated with `samples_per_edge` segments per cage edge
// (fit/tessellate_limit) as an OrganicSheet: loops[i] is the tessellation's boundary
// vertex cycle of cage.boundary_chains[i] (it starts at the chain's first cage vertex and
// runs in the chain's direction), tagged with chain_solids[i] and partition_loop =
// cage.chain_loop[i] (or -1). triangle_source = cage quad. Throws Error{Internal} when a
// chain does not run along the tessellation's boundary (chains and quads disagree).
OrganicSheet cage_sheet(const QuadCage& cage, const std::vector<std::vector<int>>& chain_solids,
                        int samples_per_edge);

// §7.2's "local insertion of a new boundary vertex" on a quad cage, kept pure-quad,
// manifold and free of T-junctions: each listed boundary edge (a, b) (either direction) is
// split at its midpoint and the split is carried across its quad strip — every quad the
// strip enters is cut in two through the midpoints of the entry edge and its opposite edge
// — until the strip reaches a boundary edge again (that edge's chain gets a vertex too) or
// closes on itself. A quad crossed by two strips is cut in four around a new centre point.
// Chains get the new vertices in order, creased edges become two creased edges, quads keep
// their orientation; old vertices keep their indices, new ones follow.
// Positions: the new control points (and nothing else) are the least-squares solution
// that keeps the limit surface closest to the old one at 5×5 samples on every quad whose
// limit they influence (old limit evaluated at the same parameters of the old quad), with
// a 1e-6 pull towards the edge midpoints / quad centres for uniqueness; the midpoints are
// kept instead when they give the smaller maximal change.
// Throws Error{Internal} when an edge is not a boundary edge of the cage.
struct CageRefinement {
  QuadCage cage;
  std::vector<int> inserted_per_chain;  // new vertices per boundary chain
  int strip_quads = 0;                  // old quads cut (the strips' lengths, summed)
  double midpoint_change = 0;  // max |S_new − S_old| at the samples with midpoint positions
  double limit_change = 0;     // the same with the positions kept
  bool least_squares = false;  // kept the least-squares positions (they changed the limit's
                               // maximum less than the midpoints; else the midpoints)
  bool over_limit = false;     // more quads than max_quads: midpoints only, no least squares
};
// `max_quads` (≥ 0): a refinement with more quads is only counted (its new points stay at
// the midpoints): the caller will not use it, and the least squares over a cage of 100k+
// quads cut by strips across a high-genus component needed 18 GB.
CageRefinement refine_cage_boundary(const QuadCage& cage,
                                    const std::vector<std::array<int, 2>>& edges,
                                    Eigen::Index max_quads = -1);

struct CagePull {
  QuadCage cage;   // the pulled cage: boundary control points moved, the move faded inward
  SheetPull sheet; // its limit tessellation (cage_sheet); loops[i] ↔ chain i; η, per-loop
                   // descent results, blend rings (of the quad graph), folds, diagnostics
};

// §7.2 on a cage: per chain, the descent of pull_curve on the exact limit boundary (sample
// weights from LimitSurface::weights on the chain's boundary edges, so creases and
// irregular corners are honoured) until F ≤ η everywhere on the tessellated boundary;
// the move then fades linearly over cage_blend_rings rings of the quad graph (doubled
// while a tessellation triangle turns over). A blend that moves the boundary again (the
// limit boundary near irregular vertices can depend on interior points) is re-pulled, at
// most 3 rounds. chain_solids[i]: the solids chain i borders. σ per chain as for sheets,
// on the unpulled tessellation.
// Where a chain still does not converge, the boundary edges holding its stuck samples are
// refined (refine_cage_boundary) on the unpulled cage, which is then pulled again from the
// start: at most options.max_insertions rounds. The returned cage is the refined one (its
// topology can differ from `cage`); LoopPull::inserted_vertices counts per chain and a
// diagnostic names the chains that got vertices.
// `sides`: σ per chain when the caller knows it (an extended cage's chains lie inside their
// solids, so the rings next to them cannot tell); empty: from the cage as above.
CagePull pull_cage(const QuadCage& cage, const std::vector<std::vector<int>>& chain_solids,
                   const SolidSet& solids, double eta, const PullOptions& options,
                   const std::vector<int>& sides = {});

// A cage extended into its solids (extend.cpp): one row of quads beyond every boundary
// chain, each new vertex out from its chain vertex to the first point half a local chain
// edge deep inside the chain's solids (F = σ·D_S as for the pull), or the deepest one where
// the solid is thinner, at most 8 chain edges out: across the chain (away from its quads'
// centroids), else half way to the solid's inward normal, else along it, per vertex and
// then one direction for the whole chain, directions smoothed and widths evened along the
// chain; the first row whose control polygon crosses neither itself nor the quads at the
// chain. The fitted quads keep their control points; the
// chains become the new rows (same order and orientation, same chain_loop); creases stay.
// For where the fitted boundary is too far outside its solids for the pull's fade: the
// extension's boundary starts inside them and the pull only corrects it.
struct ExtendedCage {
  QuadCage cage;
  std::vector<int> sides;  // σ per chain, from the cage before the extension
  bool extended = false;
  double widest = 0;    // largest row width, design units
  std::string problem;  // why not extended, in words
};
ExtendedCage extend_cage(const QuadCage& cage, const std::vector<std::vector<int>>& chain_solids,
                         const SolidSet& solids);

}  // namespace genbrep

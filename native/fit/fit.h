// fit/fit.h — Catmull–Clark fitting of a quad cage to an organic region (paper §6.3).
//
// The limit surface. A QuadCage is a Catmull–Clark control mesh evaluated exactly as
// Blender's Subdivision Surface modifier evaluates it with use_limit_surface on: OpenSubdiv,
// CREASE_UNIFORM, boundary VTX_BOUNDARY_EDGE_ONLY (Blender 'ALL'; EDGE_AND_CORNER when
// scheme.boundary_smooth_all is false), adaptive refinement to isolation level
// scheme.quality, Gregory-basis end caps at irregular vertices, edge sharpness =
// 10·crease² (BKE_subdiv_crease_to_sharpness_f) and, like Blender, a vertex with exactly
// two edges takes the smaller sharpness of the two as vertex sharpness. Surface parameters
// are (quad, u, v) with u, v in [0, 1]: (0,0) at the quad's corner 0, u along corner 0→1,
// v along corner 0→3 (OpenSubdiv's ptex coordinates; one ptex face per quad). Where every
// vertex of the quad's 1-ring is regular the limit is the bicubic uniform B-spline of the
// 16 control points (exact); near extraordinary vertices it is Blender's approximation
// (Gregory patches below level `quality`), not Stam's exact limit.
//
// fit_cage. Takes: an initial cage (topology from quad/, positions roughly on the region),
// the region (the organic component's triangles: an open or closed surface) and its
// boundary curves (closed polylines, boundary_curves[i] belongs to cage.boundary_chains[i]).
// Gives: the fitted cage (same topology, or a pure-quad refinement of it for Tight and
// BoundaryTight) and a FitReport. Strategies, §6.3:
//   Smooth         min L2: least squares of limit points at the foot-point parameters of
//                  the region's vertices (area-weighted; points inside its triangles
//                  instead when it has fewer than points_per_control_point per control
//                  point) and of boundary-curve points
//                  (matched to the limit boundary curve), plus a small umbrella fairness
//                  term on the control points, alternated with re-projection for `rounds`.
//   Tight          L∞ < δ: Smooth, then wherever the two-sided distance exceeds δ the
//                  edge rings (chords) through the offending quads are split (pure quad,
//                  conforming, no new irregular vertices: local across a ring, global
//                  along it) and the cage refitted; repeated until the bound holds or
//                  the next split would exceed max_control_points (reported).
//   BoundaryTight  first the boundary control points alone, so the limit boundary curve
//                  (EDGE_ONLY: the uniform cubic B-spline of the chain) is within δ of the
//                  region's boundary curves both ways (boundary chords split where not),
//                  then the interior in L2 with the boundary fixed.
// Guarantees: the returned cage is pure quad with valid boundary chains; the report's
// distances are measured, not estimated; numerical failure keeps the last good positions
// and is reported in diagnostics; a fit whose limit surface intersects itself where the
// initial cage's does not is repeated with the control points around the fold held
// smoother, and undone if it still folds (the initial cage is returned, report.kept_initial);
// where the initial cage's limit surface intersects itself too, the fit is kept and the
// diagnostics say that both fold.
// Deterministic (no threads, no unordered iteration).
// Complexity per round: O(Q·s²) limit evaluations (Q quads, s samples per edge), O(N log)
// closest-point queries for N region vertices, one sparse LDLᵀ of the control points.
#pragma once
#include <array>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "core/cage.h"
#include "core/context.h"
#include "core/error.h"
#include "core/types.h"

namespace genbrep {

struct LimitSample {
  Vec3 position = Vec3::Zero();
  Vec3 du = Vec3::Zero();  // ∂S/∂u, design units per unit of quad parameter
  Vec3 dv = Vec3::Zero();
  Vec3 normal() const { return du.cross(dv).normalized(); }  // outward for CCW quads
};

// A point of the limit surface as parameters, with its position and distance to the query.
struct FootPoint {
  int quad = -1;
  double u = 0, v = 0;
  Vec3 position = Vec3::Zero();
  double distance = 0;
};

// Sparse weights of one limit point over the cage's control points, sorted by index.
using LimitWeights = std::vector<std::pair<int, double>>;

// The limit surface of one cage. Built from the cage's topology, creases and scheme
// (throws Error{InvalidInput} on a cage OpenSubdiv rejects); positions can be replaced
// without rebuilding. Not thread-safe for concurrent set_control_points.
class LimitSurface {
 public:
  explicit LimitSurface(const QuadCage& cage);
  ~LimitSurface();
  LimitSurface(LimitSurface&&) noexcept;
  LimitSurface& operator=(LimitSurface&&) noexcept;

  int quad_count() const;
  int control_point_count() const;
  const Quads& quads() const;
  // Replace the control points (same count as the cage's vertices).
  void set_control_points(const Vertices& control_points);

  LimitSample evaluate(int quad, double u, double v) const;
  // The limit point at (quad, u, v) is Σ w·P[i] over these (i, w); Σ w = 1.
  LimitWeights weights(int quad, double u, double v) const;
  // Closest limit points: a tessellation with samples_per_edge segments per quad edge
  // gives the start, Gauss–Newton within the quad refines it (a local minimum of
  // |S(u,v) − p| near the global one; exact up to 1e-10 relative in the parameters).
  std::vector<FootPoint> project(const std::vector<Vec3>& points, int samples_per_edge = 6) const;
  // See tessellate_limit.
  TriangleMesh tessellate(int samples_per_edge) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// A watertight triangulation of the limit surface: each quad sampled on the grid
// u, v = i/n, j/n (n = samples_per_edge ≥ 1; Blender's level L shows n = 2^L), samples on
// shared cage edges and vertices shared, each grid cell cut along its (0,0)–(1,1)
// diagonal. Vertices: corners of the cage first (cage vertex order), then edge samples,
// then interior samples; triangle_source = quad index. Deterministic.
TriangleMesh tessellate_limit(const QuadCage& cage, int samples_per_edge);

enum class FitStrategy { Smooth, Tight, BoundaryTight };
const char* strategy_name(FitStrategy strategy);  // "smooth", "tight", "boundary_tight"
// The inverse of strategy_name; false for any other name.
bool parse_strategy(const std::string& name, FitStrategy* strategy);

struct FitOptions {
  FitStrategy strategy = FitStrategy::Smooth;
  // δ: the two-sided distance bound, design units. 0 = 3 × the region's median edge
  // length (≈ 3h for level-set designs; the pipeline passes 3h explicitly).
  double delta = 0;
  // μ: weight of the umbrella fairness Σ|P_i − mean(neighbours)|² (averaged over control
  // points) against the area-averaged squared data distance. Dimensionless. With little
  // fairness the re-projected least squares slides control points along the surface and
  // bunches rows where the surface turns tightly (μ = 10⁻³: the 5 × 5 net's cage went from
  // 24 to 164 quads over 4:1, its worst distance 0.026 of δ = 0.21); at 0.3 the rows keep
  // the quad stage's spacing (22) and the worst distance is 0.026 there, at most 0.042
  // (δ/9) on every fixture.
  double fairness_weight = 0.3;
  // Weight of the boundary-curve term against the area term (1 = the whole boundary
  // weighs as much as the whole area). Dimensionless.
  double boundary_weight = 0.2;
  // Data points per control point at least: a region with fewer vertices than that is
  // sampled inside its triangles instead (a cage as dense as the region would otherwise
  // have quads without data, which the least squares folds).
  double points_per_control_point = 4;
  // Least-squares solves alternated with re-projection, per cage topology.
  int rounds = 4;
  // Tight/BoundaryTight stop refining when the next split would exceed this many control
  // points (the report then says the bound did not hold).
  int max_control_points = 20000;
  int max_refinements = 8;
  // Segments per quad edge of the tessellation used to start projections.
  int projection_samples = 6;
  // ... reduced (to no fewer than 3) while the start grid would have more triangles than
  // this (2 · samples² per quad): only cages of over 2800 quads are affected.
  double max_projection_triangles = 2e5;
  // Segments per quad edge at which the limit surface is sampled to measure limit →
  // design distances (and per boundary edge for the boundary curve).
  int measure_samples = 4;
  // Segments per quad edge of the limit tessellation tested for self-intersection: a fit
  // that folds the surface where the initial cage's does not is undone (0: no test).
  int fold_check_samples = 4;
  // A fit that folds is first repeated with the fairness of the control points around the
  // folded quads multiplied by fold_stiffness (compounding), this many times, and then
  // again while each round leaves fewer folded quads, up to twice as many times.
  int fold_smoothing_rounds = 3;
  double fold_stiffness = 30;
  int fold_rings = 2;  // quad rings around the folded quads whose corners are held smoother
  int fold_smoothing_solves = 2;  // least-squares solves (with re-projection) per round
};

// Measured, not estimated. "design → limit": each data point (region vertex, or triangle
// sample for a coarse region) to its foot point on the
// limit surface; "limit → design": limit samples (measure_samples per quad edge) to the
// closest point of the region's triangles. Boundary: chain limit curves vs boundary_curves.
struct FitReport {
  int component = -1;
  FitStrategy strategy = FitStrategy::Smooth;
  int control_points = 0;
  int quads = 0;
  double delta = 0;  // δ used, design units
  double rms_design_to_limit = 0, max_design_to_limit = 0;
  double rms_limit_to_design = 0, max_limit_to_design = 0;
  double max_boundary_distance = 0;  // two-sided, limit boundary curves vs boundary_curves
  int rounds = 0;                    // least-squares solves done
  int refinements = 0;               // chord-split steps done
  double seconds = 0;
  // Tight and Smooth: max two-sided surface distance ≤ δ (for Smooth only informative);
  // BoundaryTight: the boundary distance ≤ δ (true when there are no boundary curves).
  bool bound_held = false;
  // The fit folded the limit surface and was undone: the cage is the initial one.
  bool kept_initial = false;
  Diagnostics diagnostics;
};

struct Fitted {
  QuadCage cage;
  FitReport report;
};

Fitted fit_cage(const QuadCage& initial, const TriangleMesh& region,
                const std::vector<std::vector<Vec3>>& boundary_curves, const FitOptions& options,
                const Context& ctx);

// Splits every quad crossed by the chords (edge rings) through the given cage edges
// (vertex pairs): each split edge gets its midpoint, a quad crossed once becomes two, a
// quad crossed in both directions four (with its centroid). Boundary chains and creases
// follow. The result is pure quad and conforming with no new irregular vertices.
QuadCage split_chords(const QuadCage& cage, const std::vector<std::array<int, 2>>& edges);

}  // namespace genbrep

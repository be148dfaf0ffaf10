// fit/detail/problem.h — what fit.cpp and measure.cpp share: the fitting data of one region,
// the limit boundary curves of a cage's chains, and the measurements (fit/fit.h contract).
#pragma once
#include <vector>

#include "fit/detail/closest.h"
#include "fit/fit.h"

namespace genbrep::fit_detail {

// The region as data for the fit: the vertices used by its triangles with area weights
// (summing to 1), and the boundary-curve points with length weights (summing to 1).
struct Problem {
  explicit Problem(const TriangleMesh& region)
      : region(region), tree(region.vertices, region.triangles) {}
  const TriangleMesh& region;
  TriangleTree tree;
  std::vector<Vec3> points;
  std::vector<double> point_weights;
  std::vector<std::vector<Vec3>> curves;  // closed polylines, curves[i] ↔ chain i
  std::vector<Vec3> curve_points;
  std::vector<double> curve_weights;
  std::vector<int> curve_chain;  // chain of each curve point
  double median_edge = 0;
};

// A cage chain edge (chain[i] → chain[i+1]) as the boundary edge `k` of `quad`.
struct ChainEdge {
  int quad = -1;
  int k = 0;
  bool reversed = false;  // the quad runs the edge chain[i+1] → chain[i]
};
// Validates that consecutive chain vertices are boundary edges of the cage.
std::vector<std::vector<ChainEdge>> chain_edges(const QuadCage& cage);
// Parameters on the quad of chain edge `e` at t ∈ [0, 1] from chain[i] to chain[i+1], and
// d(u, v)/dt.
void chain_parameters(const ChainEdge& e, double t, double* u, double* v, double* du_dt,
                      double* dv_dt);

// A boundary-curve point's foot on its chain's limit curve.
struct CurveFoot {
  int edge = -1;  // chain edge index
  double t = 0;
  FootPoint foot;
};
std::vector<CurveFoot> project_on_chains(const LimitSurface& surface,
                                         const std::vector<std::vector<ChainEdge>>& chains,
                                         const std::vector<Vec3>& points,
                                         const std::vector<int>& point_chain, int samples);

// Two-sided distances of one fitted state; per-quad and per-chain-edge worst values drive
// the refinement.
struct Measurement {
  std::vector<FootPoint> feet;               // design → limit, per Problem::points
  std::vector<CurveFoot> curve_feet;         // boundary curve → limit curve, per curve point
  std::vector<double> quad_limit_to_design;  // worst limit sample of each quad
  std::vector<std::vector<double>> chain_edge_distance;  // worst two-sided per chain edge
  double rms_design_to_limit = 0, max_design_to_limit = 0;
  double rms_limit_to_design = 0, max_limit_to_design = 0;
  double max_boundary = 0;
};
Measurement measure(const LimitSurface& surface, const std::vector<std::vector<ChainEdge>>& chains,
                    const Problem& problem, const FitOptions& options);

}  // namespace genbrep::fit_detail

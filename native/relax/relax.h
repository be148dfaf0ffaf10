// relax/relax.h — organic boundary relaxation (paper §5.3).
// Takes: the design as arrays (closed, 2-manifold, outward-oriented; the mesh the
// partition was computed on) and its Partition (per-triangle I(T), boundary loops).
// Gives: a new design mesh whose boundary loops are smooth and evenly sampled, its
// Partition (labels carried through, loops retraced with partition_faces), per-loop
// statistics before/after, the largest loop displacement, and diagnostics.
// Method: (a) remesh a channel (the triangles within `channel_rings` rings of the loop
// vertices) with CGAL's isotropic remeshing at a uniform target length; the partition
// label of each triangle is its patch, so label borders are constraints that may be
// split, collapsed and slid along themselves but never cross a triangle; vertices are
// projected onto the original design. (b) Surface-restricted curve smoothing (after
// Hofer & Pottmann): Taubin λ|μ steps move each loop vertex towards/away from the mean of
// its loop neighbours (smoothing without shrinking the organic region), every moved
// vertex is projected onto the original design and kept within d of the original loop
// polyline; the channel vertices off every label border then follow (Laplacian steps
// projected onto the design). A move that would flip or collapse a triangle (normal
// against the design's normal at its projection) is halved, then skipped and counted.
// Folded triangles the remesh leaves are unfolded (edge flip or vertex move) first.
// Guarantees: the result is closed, 2-manifold and oriented; every vertex lies on the
// original design surface (up to rounding of a closest-point query); no triangle faces
// against the design; loop vertices lie within d of the original loops; the organic
// components and the number of loops are those of the input. A step that cannot keep
// these is undone (the remesh as a whole, a smoothing move locally) and reported in
// `diagnostics`: the worst case returns the input mesh unchanged. Deterministic.
// Complexity: O(|T| log |T|) for the trees and the remesh of the channel, plus
// O(iterations · |channel| log |T|) closest-point queries for the smoothing.
#pragma once
#include <vector>

#include "core/context.h"
#include "core/error.h"
#include "core/types.h"
#include "partition/partition.h"

namespace genbrep {

struct RelaxOptions {
  // d: the farthest a loop may move from where it was, design units. 0 = the design's
  // median edge length (about the solver's voxel size). The pipeline passes the
  // incidence tolerance here.
  double tolerance = 0;
  // Channel remesh target edge length, design units. 0 = the median length of the
  // boundary edges (so the loop keeps its sampling density, only evened out).
  double target_edge_length = 0;
  // Width of the channel in vertex rings around the loop vertices (paper: 2).
  int channel_rings = 2;
  // Isotropic remeshing iterations (split, collapse, flip, relax, project); 0 skips (a).
  int remesh_iterations = 3;
  // Taubin λ|μ rounds of curve smoothing, each followed by a tangential relaxation of
  // the channel; 0 skips (b).
  int smoothing_iterations = 20;
  double taubin_lambda = 0.5;  // shrinking step towards the neighbours' mean
  double taubin_mu = -0.53;    // inflating step; |μ| > λ removes the shrinkage
  // A moved triangle must keep cos(angle to the design normal at its projection) above
  // this (dimensionless); lower accepts more distortion, never a flip.
  double min_normal_cosine = 0.2;
  // Organic area may shrink by at most this fraction; otherwise smoothing is undone.
  double max_area_loss = 0.05;
};

// Shape of one closed loop.
struct LoopShape {
  int vertices = 0;
  double mean_edge_length = 0;  // design units
  double edge_length_cv = 0;    // standard deviation / mean of the edge lengths
  // Mean |turning angle| at the loop vertices (radians): the angle between consecutive
  // edges projected into the tangent plane (area-weighted vertex normal). 0 = straight.
  double mean_turning_angle = 0;
  double max_turning_angle = 0;  // radians; above π/2 the interior angle is not "flat" (§6.1)
};

struct LoopRelaxation {
  int original_loop = -1;  // index into the input partition's loops
  LoopShape before, after;
  double max_displacement = 0;  // largest distance of a new loop vertex from the old loop
};

struct Relaxed {
  // Closed, 2-manifold, oriented; triangle_source = the input face (the input design's
  // triangle_source of the triangle it came from).
  TriangleMesh design;
  // Per new triangle, the input design triangle it came from: the one nearest to its
  // centroid (itself, for triangles the relaxation did not touch).
  std::vector<int> triangle_origin;
  Partition partition;  // of `design`; loops[i] corresponds to loops[i] of `loops` below
  std::vector<LoopRelaxation> loops;
  double tolerance = 0;           // d used, design units
  double target_edge_length = 0;  // channel remesh length used, design units
  double max_displacement = 0;    // over all loops, design units (≤ tolerance)
  double organic_area_before = 0, organic_area_after = 0;
  int channel_triangles = 0;  // input triangles in the remeshed channel
  bool remeshed = false;      // step (a) kept
  int skipped_moves = 0;      // smoothing moves refused to keep the guarantees
  Diagnostics diagnostics;    // warnings: a step undone, folds left after the remesh
  Diagnostics notes;          // how it went: folds repaired, moves skipped, vertices kept
};

// The shape statistics of a closed vertex cycle of `mesh` (used before and after).
LoopShape loop_shape(const TriMesh& mesh, const std::vector<int>& loop);

Relaxed relax(const TriangleMesh& design, const Partition& partition, const RelaxOptions& options,
              const Context& context);

}  // namespace genbrep

// field/field.h — curvature, cross field and size field on the organic region (paper §6.1–6.2).
// Takes: the design's halfedge mesh (closed, 2-manifold, outward-oriented) and its Partition
// (organic components, boundary loops with the organic side on the left).
// Gives, per triangle of the design (zero/NaN-free defaults on incident triangles):
//   - a curvature tensor estimate: principal curvatures κ1 ≥ κ2 (positive where the
//     surface bends away from its outward normal, e.g. +1/r on a sphere) and directions;
//   - a smooth 4-RoSy cross field, stored as one representative unit direction in the
//     triangle's plane (the other three are its quarter-turn rotations about the normal);
//   - target edge lengths (d_u, d_v) along the representative direction and along its
//     quarter turn (§6.2, eq. 6 of Bommes et al. 2009);
// and the field's singular vertices with their indices in quarter turns.
// Method: per component, one sparse Hermitian solve of the Knöppel et al. 2013 energy
// (faces store u = e^{4iθ}; connection Laplacian over the component's interior edges plus a
// curvature-alignment term weighted by anisotropy); no greedy period-jump rounding. Faces
// along the boundary loops are Dirichlet-constrained to the loop tangent in a channel whose
// width is a multiple of the target edge length; the channel's values come from a small
// preliminary solve (smoothest extension of the tangent from the loop inwards).
// Guarantees: every organic face has a unit direction in its plane; the indices of a
// component sum to 4·χ (Poincaré–Hopf, boundary vertices included); a loop vertex whose
// interior angle lies in (π/2, 3π/2) has index 0: the period jumps on the spokes of its fan
// are matched to the loop's turning, so where the raw loop zigzags (before §5.3 relaxation)
// the compensating singularities sit one ring inside instead. Exception: a loop vertex whose
// fan is a single triangle (an "ear") cannot align with both loop edges; its index is
// rounded and counted in `diagnostics`. Numerical trouble (degenerate triangles,
// non-integer indices) is reported in `diagnostics`, never thrown.
// Deterministic: no unordered iteration, no seeds.
// Complexity: O(F) for curvature, size field and singularities; one sparse LDLᵀ
// factorisation per organic component (about O(F^1.5) for surface meshes).
#pragma once
#include <Eigen/Dense>
#include <string>
#include <vector>

#include "core/context.h"
#include "core/error.h"
#include "core/types.h"
#include "partition/partition.h"

namespace genbrep {

struct FieldOptions {
  // Weight of the curvature-alignment term against smoothness (dimensionless). With 1 the
  // field follows fully anisotropic curvature directions averaged over about one target
  // edge length; 0 gives the smoothest field compatible with the boundary.
  double alignment_weight = 1.0;
  // Relative anisotropy |κ1−κ2| / (|κ1|+|κ2|+1/L) (L: the component's size) at which the
  // alignment weight is one half; below it the surface counts as umbilic or flat and the
  // field is driven by smoothness only.
  double anisotropy_threshold = 0.25;
  // Rounds of vertex↔face averaging of the curvature tensor (each widens it by one ring);
  // level-set meshes need a few to suppress the solver's grid noise.
  int curvature_smoothing = 3;
  // Width of the boundary channel as a multiple of the target edge length; triangles
  // closer than this to a loop (geodesic, along face centres) are hard-aligned with the
  // loop tangent. 0 constrains only the triangles touching the loop.
  double channel_width = 1.0;
  // Coarsest cage edge length in design units (used in flat areas, and as the length
  // scale of the solve); 0 = sqrt(organic area / target_quads).
  double target_edge_length = 0;
  int target_quads = 1000;  // quads on the whole organic region when deriving the length
  // User density: all target lengths are divided by it (2 ⇒ edges half as long).
  double density = 1.0;
  // ε of eq. 6: the allowed deviation (sagitta) of a cage edge from the surface, in design
  // units; 0 = tolerance_fraction · 2/κ_max, κ_max the curvature_percentile-th percentile
  // of max(|κ1|,|κ2|) over organic faces, so ε < 2/κ_max and the tightest features survive.
  double tolerance = 0;
  double tolerance_fraction = 0.05;
  double curvature_percentile = 0.98;
  // Finest allowed edge length in design units; 0 = the design's median edge length over
  // organic triangles (a cage is never finer than the design's own resolution).
  double min_edge_length = 0;
};

// A singular vertex of the cross field. index is in quarter turns: +1 is a valence-3
// vertex of the future quad mesh (index +1/4), −1 a valence-5 one (index −1/4).
struct Singularity {
  int vertex = -1;
  int index = 0;
  int component = -1;
  bool on_boundary = false;
};

using FaceVectors = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;

struct CrossField {
  // Per triangle of the design; rows of incident triangles are zero.
  FaceVectors direction;   // representative cross direction, unit, in the face plane
  FaceVectors principal1;  // unit direction of κ1 (for every face, organic or not)
  FaceVectors principal2;  // unit direction of κ2 = normal × principal1
  Eigen::VectorXd kappa1;  // principal curvatures, κ1 ≥ κ2, 1/design units
  Eigen::VectorXd kappa2;
  Eigen::VectorXd alignment;  // curvature-alignment confidence in [0, 1] (0 = umbilic/flat)
  Eigen::VectorXd size_u;     // target edge length along `direction`, design units
  Eigen::VectorXd size_v;     // target edge length along normal × `direction`
  // Per triangle: 0 free, 1 touches a boundary loop, 2 in the boundary channel; -1 incident.
  std::vector<int> constraint;
  std::vector<Singularity> singularities;  // sorted by component, then vertex

  // Lengths actually used, for the report.
  double target_edge_length = 0;  // coarsest length before clamping (after density)
  double min_edge_length = 0;     // clamp applied to size_u/size_v from below
  double tolerance = 0;           // ε of eq. 6
  double kappa_max = 0;           // the robust max |κ| ε was derived from
  Diagnostics diagnostics;        // warnings (degenerate triangles, non-integer indices)
  Diagnostics notes;              // the summary: components, singularities, lengths

  // Sum of singularity indices of one component, in quarter turns (= 4·χ).
  int index_sum(int component) const;
};

// Computes curvature, cross field, singularities and size field for every organic
// component of `partition`. Throws Error{InvalidInput} if the partition does not match
// the mesh, Error{Cancelled} through `context`.
CrossField compute_field(const TriMesh& design, const Partition& partition,
                         const FieldOptions& options, const Context& context);

// Debug output: an OBJ with a short cross (two line segments, each arm 0.4 of the face's
// mean edge length) at the centre of every organic face, and the singular vertices as
// points (`p`), in groups `cross`, `singularities_positive` and `singularities_negative`.
// Throws Error{FileError}.
void write_field_obj(const std::string& path, const TriMesh& design, const CrossField& field);

}  // namespace genbrep

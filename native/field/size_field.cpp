// field/size_field.cpp — anisotropic target edge lengths along the cross (§6.2).
// Eq. 6 of Bommes, Zimmer, Kobbelt, "Mixed-integer quadrangulation" (2009), as the paper
// uses it: d_t(κ_t) = 2·sqrt(2ε/|κ_t| − ε²), t ∈ {u, v}, the chord of a circle of radius
// 1/|κ_t| whose sagitta is ε — the longest edge that deviates at most ε from the surface.
// κ_t is the normal curvature along the cross direction t (Euler's formula from κ1, κ2).
// ε must stay below 2/|κ| (the chord formula's domain); deriving it from a robust κ_max
// (a high percentile, so single noisy triangles do not decide) keeps the tightest features
// resolved. Where ε exceeds the radius the chord is capped at the diameter. Lengths are
// divided by the user's density and clamped to [min, target]: never finer than the design's
// own resolution, never coarser than the target length of flat regions.
#include <algorithm>
#include <cmath>

#include "field/detail/field_detail.h"

namespace genbrep::field_detail {
namespace {

// The p-quantile (0..1) of values, by selection; 0 for an empty list.
double quantile(std::vector<double> values, double p) {
  if (values.empty()) return 0;
  const size_t k = std::min(values.size() - 1,
                            static_cast<size_t>(p * static_cast<double>(values.size() - 1) + 0.5));
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
  return values[k];
}

}  // namespace

void compute_size_field(const TriMesh& mesh, const Partition& partition,
                        const FieldOptions& options, double target_edge_length, CrossField* field) {
  const int nf = static_cast<int>(mesh.n_faces());
  std::vector<double> edge_lengths, curvatures;
  for (auto e : mesh.edges()) {
    const auto h = mesh.halfedge_handle(e, 0);
    if (partition.face_component[mesh.face_handle(h).idx()] < 0 &&
        partition.face_component[mesh.opposite_face_handle(h).idx()] < 0) {
      continue;
    }
    edge_lengths.push_back(mesh.calc_edge_length(e));
  }
  for (int f = 0; f < nf; ++f) {
    if (partition.face_component[f] >= 0) {
      curvatures.push_back(std::max(std::abs(field->kappa1[f]), std::abs(field->kappa2[f])));
    }
  }
  const double median_edge = quantile(edge_lengths, 0.5);
  field->min_edge_length = options.min_edge_length > 0 ? options.min_edge_length : median_edge;
  field->kappa_max = quantile(curvatures, options.curvature_percentile);
  field->tolerance = options.tolerance > 0  ? options.tolerance
                     : field->kappa_max > 0 ? options.tolerance_fraction * 2.0 / field->kappa_max
                                            : 0;
  double longest = target_edge_length;
  if (longest < field->min_edge_length) {
    field->diagnostics.push_back("field: target edge length " + std::to_string(longest) +
                                 " is below the minimum " + std::to_string(field->min_edge_length) +
                                 "; using the minimum");
    longest = field->min_edge_length;
  }
  field->target_edge_length = longest;

  const double epsilon = field->tolerance;
  auto length = [&](double kappa) {
    const double magnitude = std::abs(kappa);
    if (epsilon <= 0 || magnitude * longest < 1e-9) return longest;  // flat: the coarsest size
    const double radius = 1.0 / magnitude;
    const double sagitta = std::min(epsilon, radius);  // past the radius: the diameter
    const double chord =
        2.0 * std::sqrt(2.0 * sagitta * radius - sagitta * sagitta) / options.density;
    return std::clamp(chord, field->min_edge_length, longest);
  };
  field->size_u = Eigen::VectorXd::Zero(nf);
  field->size_v = Eigen::VectorXd::Zero(nf);
  for (int f = 0; f < nf; ++f) {
    if (partition.face_component[f] < 0) continue;
    // Normal curvature along the cross arms: κ(φ) = κ1 cos²φ + κ2 sin²φ (Euler).
    const double c = field->direction.row(f).dot(field->principal1.row(f));
    const double c2 = std::min(1.0, c * c);
    field->size_u[f] = length(field->kappa1[f] * c2 + field->kappa2[f] * (1 - c2));
    field->size_v[f] = length(field->kappa1[f] * (1 - c2) + field->kappa2[f] * c2);
  }
}

}  // namespace genbrep::field_detail

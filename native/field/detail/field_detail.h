// field/detail/field_detail.h — internals shared by the field stage's sources.
// Not part of the public API: only native/field/*.cpp include it.
#pragma once
#include <complex>
#include <vector>

#include "core/numbers.h"
#include "field/field.h"

namespace genbrep::field_detail {

using Complex = std::complex<double>;
constexpr double kQuarter = kPi / 2;

// An orthonormal frame per triangle: x along its first edge (projected), y = n × x.
// Degenerate triangles take their normal from their corners' neighbours so that every
// frame is valid; `degenerate` counts them.
struct FaceFrames {
  std::vector<Vec3> normal, x, y, centroid;
  std::vector<double> area;
  int degenerate = 0;
  // Angle of a vector in face f's frame, after projection to its plane.
  double angle(int f, const Vec3& d) const { return std::atan2(d.dot(y[f]), d.dot(x[f])); }
  Vec3 direction(int f, double theta) const {
    return std::cos(theta) * x[f] + std::sin(theta) * y[f];
  }
};

FaceFrames face_frames(const TriMesh& mesh);

// Per-face curvature (Rusinkiewicz 2004 per-face tensor from angle-weighted vertex normals,
// then `smoothing` rounds of area-weighted vertex↔face averaging). Fills kappa1/2 and
// principal1/2 of `field`, for every face.
void estimate_curvature(const TriMesh& mesh, const FaceFrames& frames, int smoothing,
                        CrossField* field);

// x reduced to (−π/4, π/4]: the period-jump matching of a 4-RoSy field.
inline double wrap_quarter(double x) { return x - kQuarter * std::round(x / kQuarter); }

// Interior angle of triangle f at the corner where halfedge h starts.
double corner_angle(const TriMesh& mesh, OpenMesh::HalfedgeHandle h);

// The fan of organic triangles around loop vertex v, walked counter-clockwise from the
// loop edge v→next (spoke 0) to the loop edge prev→v, unfolded: spoke j at angle Σ_{i<j} β_i.
// The loop tangent turns from 0 to α − π (α = Σ β, the interior angle); `tangent[j]` is the
// tangent's unfolded angle the field takes in face j: exact on the two faces with loop edges,
// interpolated at the middle of the others, so the field turns with the loop. Empty when
// v→next is not a loop edge of `component`.
struct BoundaryFan {
  std::vector<OpenMesh::HalfedgeHandle> spokes;  // spoke j leaves v; face j on its left
  std::vector<double> beta;                      // corner angle of face j at v
  std::vector<double> before;                    // unfolded angle of spoke j
  std::vector<double> tangent;                   // unfolded loop tangent for face j
  double alpha = 0;
};
BoundaryFan boundary_fan(const TriMesh& mesh, const Partition& partition, int component,
                         OpenMesh::VertexHandle v, OpenMesh::VertexHandle next);

// Solves the cross field of one organic component into theta (per design face, angle in
// the face frame) and marks field->constraint. Appends to field->diagnostics.
struct ComponentInput {
  int component = -1;
  std::vector<int> faces;                      // the component's faces, ascending
  std::vector<const BoundaryLoop*> loops;      // its loops
  const std::vector<int>* position = nullptr;  // per design face: index in its component's list
  double component_size = 1;                   // sqrt(area), the L of the anisotropy measure
};
void solve_component_field(const TriMesh& mesh, const Partition& partition,
                           const FaceFrames& frames, const ComponentInput& input,
                           const FieldOptions& options, double edge_length,
                           std::vector<double>* theta, CrossField* field);

// Singularities of one component from the face angles theta (see singularities.cpp).
void find_singularities(const TriMesh& mesh, const Partition& partition, const FaceFrames& frames,
                        const ComponentInput& input, const std::vector<double>& theta,
                        CrossField* field);

// Size field of §6.2 for the organic faces; sets the lengths of `field`.
void compute_size_field(const TriMesh& mesh, const Partition& partition,
                        const FieldOptions& options, double target_edge_length, CrossField* field);

}  // namespace genbrep::field_detail

// tests/support/solid_meshes.h — exact, closed, outward-oriented triangle meshes of the
// solids the corpus generator draws: boxes in any orientation, cylinders and tubes on any
// axis, and plates with holes. Round surfaces are faceted with their vertices on the exact
// surface; two meshes made with the same axis, radius and segment count share those
// vertices to the last bit, as a CAD exporter's coincident walls do.
#pragma once
#include <vector>

#include "core/types.h"

namespace genbrep::testing {

// Box of half extents `half` around `center`, its local axes the columns of `rotation`.
TriangleMesh oriented_box_mesh(const Vec3& center, const Vec3& half, const Eigen::Matrix3d& rotation);

// The solid between radii `inner` and `outer` around the axis base + t·direction,
// t in [t0, t1] (direction need not be unit; it is normalised). inner = 0 gives a capped
// solid cylinder. `segments` facets around.
TriangleMesh tube_mesh(const Vec3& base, const Vec3& direction, double t0, double t1, double inner,
                       double outer, int segments);

// A hole of a plate: centre (u, v) in the plate's local frame and radius.
struct PlateHole {
  double u = 0, v = 0, radius = 0;
};

// oriented_box_mesh with cylindrical through-holes along its third local axis, cut with
// CGAL's corefinement. Holes must lie inside the plate's outline and not overlap.
TriangleMesh plate_with_holes_mesh(const Vec3& center, const Vec3& half, const Eigen::Matrix3d& rotation,
                                   const std::vector<PlateHole>& holes, int segments);

// Facets for a circle of `radius` so that the chord stays within `sag` of it (24 to 128).
int circle_segments(double radius, double sag);

}  // namespace genbrep::testing

// tests/support/level_set.h — level-set-style designs for tests and benchmarks.
// A generative solver outputs the zero level set of a field sampled on a voxel grid;
// extract_level_set does the same with marching tetrahedra (Kuhn subdivision of each
// cube, so neighbouring cells agree): the result is closed, 2-manifold and oriented with
// normals towards f > 0, its vertices on grid edges, within about h of the true surface.
// Exact signed-distance primitives and exact triangle meshes of solids live here too.
#pragma once
#include <functional>

#include "core/types.h"

namespace genbrep::testing {

using Field = std::function<double(const Vec3&)>;

// Samples f at origin + h·(i,j,k), 0 <= i,j,k <= cells, and contours f = 0.
TriangleMesh extract_level_set(const Field& f, const Vec3& origin, double h,
                               const Eigen::Vector3i& cells);

double box_sdf(const Vec3& p, const Vec3& lo, const Vec3& hi);
double sphere_sdf(const Vec3& p, const Vec3& center, double radius);
double capsule_sdf(const Vec3& p, const Vec3& a, const Vec3& b, double radius);
// Torus around `center`, axis y, in the xz plane.
double torus_sdf(const Vec3& p, const Vec3& center, double major, double minor);
// An arch: the upper half (z >= center.z) of a y-axis torus, with flat ends.
double arch_sdf(const Vec3& p, const Vec3& center, double major, double minor);

// Exact solids as triangle meshes. box_mesh subdivides each face into n×n squares cut
// along the same diagonal, so interior face vertices have valence 6.
TriangleMesh box_mesh(const Vec3& lo, const Vec3& hi, int n = 1);
TriangleMesh cylinder_mesh(const Vec3& base, double radius, double height, int segments);

// Concatenates meshes (disjoint shells).
TriangleMesh merge(const std::vector<TriangleMesh>& meshes);

}  // namespace genbrep::testing

namespace genbrep::testing {
// Writes an OBJ file (for command-line tests and fixtures).
void write_obj(const std::string& path, const TriangleMesh& mesh);
}  // namespace genbrep::testing

// core/types.h — plain data that crosses stages and the binding.
// Meshes cross as arrays (libigl style): float64 vertices N×3, int32 triangles M×3, in
// world space and the design's units. The halfedge TriMesh (OpenMesh, double precision)
// is built from these where a stage needs adjacency.
#pragma once
#include <Eigen/Dense>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <string>
#include <vector>

namespace genbrep {

using Vec3 = Eigen::Vector3d;
using Vertices = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
using Triangles = Eigen::Matrix<int, Eigen::Dynamic, 3, Eigen::RowMajor>;

// Polygons as offsets + indices: face f has indices[offsets[f] .. offsets[f+1]).
struct PolygonSoup {
  Vertices vertices;
  std::vector<int> offsets{0};
  std::vector<int> indices;
  int face_count() const { return static_cast<int>(offsets.size()) - 1; }
};

// A triangle mesh as arrays; `triangle_source[t]` is the input face that triangle t came
// from (provenance through triangulation and cleaning).
struct TriangleMesh {
  Vertices vertices;
  Triangles triangles;
  std::vector<int> triangle_source;
};

struct OpenMeshTraits : public OpenMesh::DefaultTraits {
  using Point = OpenMesh::Vec3d;
  using Normal = OpenMesh::Vec3d;
};
using TriMesh = OpenMesh::TriMesh_ArrayKernelT<OpenMeshTraits>;

// Roles of input solids (DESIGN.md, "The job").
enum class Role { KeepIn, KeepOut, Seed };
const char* role_name(Role role);   // "keep_in", "keep_out", "seed"
bool parse_role(const std::string& name, Role* role);

// A named mesh: names travel with data so errors can say which object is wrong.
struct NamedMesh {
  std::string name;
  TriangleMesh mesh;
};

struct SolidInput {
  std::string name;
  Role role = Role::KeepIn;
  TriangleMesh mesh;
};

// "keep-in 'boss'": how messages name a solid.
std::string describe(const SolidInput& solid);

}  // namespace genbrep

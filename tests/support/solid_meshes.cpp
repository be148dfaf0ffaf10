#include "solid_meshes.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/corefinement.h>
#include <CGAL/Surface_mesh.h>
#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

#include "level_set.h"

namespace genbrep::testing {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Surface = CGAL::Surface_mesh<Kernel::Point_3>;
constexpr double kTwoPi = 6.28318530717958647692;

TriangleMesh to_mesh(const std::vector<Vec3>& vertices, const std::vector<std::array<int, 3>>& triangles) {
  TriangleMesh mesh;
  mesh.vertices.resize(static_cast<Eigen::Index>(vertices.size()), 3);
  for (size_t v = 0; v < vertices.size(); ++v) mesh.vertices.row(static_cast<Eigen::Index>(v)) = vertices[v];
  mesh.triangles.resize(static_cast<Eigen::Index>(triangles.size()), 3);
  for (size_t t = 0; t < triangles.size(); ++t)
    for (int c = 0; c < 3; ++c) mesh.triangles(static_cast<Eigen::Index>(t), c) = triangles[t][c];
  return mesh;
}

// Two unit vectors completing `d` to a right-handed orthonormal frame, fixed by d alone.
void perpendicular_pair(const Vec3& d, Vec3* u, Vec3* v) {
  const Vec3 ref = std::abs(d.z()) < 0.9 ? Vec3(0, 0, 1) : Vec3(1, 0, 0);
  *u = ref.cross(d).normalized();
  *v = d.cross(*u);
}

Surface to_surface(const TriangleMesh& mesh) {
  Surface s;
  std::vector<Surface::Vertex_index> ids;
  for (Eigen::Index v = 0; v < mesh.vertices.rows(); ++v)
    ids.push_back(s.add_vertex(Kernel::Point_3(mesh.vertices(v, 0), mesh.vertices(v, 1), mesh.vertices(v, 2))));
  for (Eigen::Index t = 0; t < mesh.triangles.rows(); ++t)
    s.add_face(ids[mesh.triangles(t, 0)], ids[mesh.triangles(t, 1)], ids[mesh.triangles(t, 2)]);
  return s;
}

TriangleMesh from_surface(const Surface& s) {
  std::vector<Vec3> vertices;
  std::vector<int> index(s.num_vertices() + s.number_of_removed_vertices(), -1);
  for (auto v : s.vertices()) {
    index[v.idx()] = static_cast<int>(vertices.size());
    const auto& p = s.point(v);
    vertices.emplace_back(p.x(), p.y(), p.z());
  }
  std::vector<std::array<int, 3>> triangles;
  for (auto f : s.faces()) {
    std::array<int, 3> t{};
    int c = 0;
    for (auto v : CGAL::vertices_around_face(s.halfedge(f), s)) t[c++] = index[v.idx()];
    triangles.push_back(t);
  }
  return to_mesh(vertices, triangles);
}

}  // namespace

int circle_segments(double radius, double sag) {
  // chord sag = r (1 - cos(π / n)) ≈ r π² / (2 n²)
  const double n = std::ceil(3.14159265358979 * std::sqrt(radius / (2 * sag)));
  return std::clamp(static_cast<int>(n), 24, 128);
}

TriangleMesh oriented_box_mesh(const Vec3& center, const Vec3& half, const Eigen::Matrix3d& rotation) {
  TriangleMesh box = box_mesh(-half, half);
  for (Eigen::Index v = 0; v < box.vertices.rows(); ++v)
    box.vertices.row(v) = (center + rotation * Vec3(box.vertices.row(v).transpose())).transpose();
  return box;
}

TriangleMesh tube_mesh(const Vec3& base, const Vec3& direction, double t0, double t1, double inner,
                       double outer, int segments) {
  const Vec3 d = direction.normalized();
  Vec3 u, v;
  perpendicular_pair(d, &u, &v);
  const int n = segments;
  std::vector<Vec3> vertices;
  auto ring = [&](double t, double r) {
    const int first = static_cast<int>(vertices.size());
    for (int i = 0; i < n; ++i) {
      const double a = kTwoPi * i / n;
      vertices.push_back(base + d * t + r * (std::cos(a) * u + std::sin(a) * v));
    }
    return first;
  };
  const int o0 = ring(t0, outer), o1 = ring(t1, outer);
  std::vector<std::array<int, 3>> triangles;
  auto quad = [&](int a, int b, int c, int e) {  // a b c e counter-clockwise seen from outside
    triangles.push_back({a, b, c});
    triangles.push_back({a, c, e});
  };
  for (int i = 0; i < n; ++i) quad(o0 + i, o0 + (i + 1) % n, o1 + (i + 1) % n, o1 + i);
  if (inner > 0) {
    const int i0 = ring(t0, inner), i1 = ring(t1, inner);
    for (int i = 0; i < n; ++i) {
      const int j = (i + 1) % n;
      quad(i0 + i, i1 + i, i1 + j, i0 + j);  // inner wall faces the axis
      quad(o1 + i, o1 + j, i1 + j, i1 + i);  // cap at t1
      quad(o0 + i, i0 + i, i0 + j, o0 + j);  // cap at t0
    }
  } else {
    vertices.push_back(base + d * t0);
    vertices.push_back(base + d * t1);
    const int c0 = n * 2, c1 = n * 2 + 1;
    for (int i = 0; i < n; ++i) {
      const int j = (i + 1) % n;
      triangles.push_back({c0, o0 + j, o0 + i});
      triangles.push_back({c1, o1 + i, o1 + j});
    }
  }
  return to_mesh(vertices, triangles);
}

TriangleMesh plate_with_holes_mesh(const Vec3& center, const Vec3& half, const Eigen::Matrix3d& rotation,
                                   const std::vector<PlateHole>& holes, int segments) {
  Surface plate = to_surface(oriented_box_mesh(center, half, rotation));
  const Vec3 axis = rotation.col(2);
  for (const PlateHole& hole : holes) {
    const Vec3 at = center + rotation * Vec3(hole.u, hole.v, 0);
    Surface drill = to_surface(tube_mesh(at, axis, -half.z() - 1, half.z() + 1, 0, hole.radius, segments));
    Surface cut;
    if (!CGAL::Polygon_mesh_processing::corefine_and_compute_difference(plate, drill, cut))
      throw std::runtime_error("plate_with_holes_mesh: the difference is not a closed 2-manifold");
    plate = std::move(cut);
  }
  return from_surface(plate);
}

}  // namespace genbrep::testing

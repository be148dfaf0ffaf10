// quad/locate.cpp — closest points on one organic component (CGAL AABB tree over its
// triangles), for the cage repairs that move or add cage vertices (untangle, fallback).
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Simple_cartesian.h>

#include "quad/detail/cage.h"

namespace genbrep::quad_detail {
namespace {
using Kernel = CGAL::Simple_cartesian<double>;
using Triangle = Kernel::Triangle_3;
using Primitive = CGAL::AABB_triangle_primitive<Kernel, std::vector<Triangle>::const_iterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;
}  // namespace

struct ComponentLocator::Impl {
  std::vector<Triangle> triangles;
  std::vector<int> face;  // design face of each triangle
  Tree tree;
};

ComponentLocator::ComponentLocator(const Surface& s) : surface_(s), impl_(new Impl) {
  for (auto f : s.mesh.faces()) {
    if (!s.in(f.idx())) continue;
    Vec3 c[3];
    int k = 0;
    for (auto v : s.mesh.fv_range(f)) c[k++] = s.point[v.idx()];
    if ((c[1] - c[0]).cross(c[2] - c[0]).norm() <= 0) continue;  // no closest point on it
    impl_->triangles.emplace_back(Kernel::Point_3(c[0].x(), c[0].y(), c[0].z()),
                                  Kernel::Point_3(c[1].x(), c[1].y(), c[1].z()),
                                  Kernel::Point_3(c[2].x(), c[2].y(), c[2].z()));
    impl_->face.push_back(f.idx());
  }
  GENBREP_CHECK(!impl_->triangles.empty(), Code::StageFailure,
                "quad: component " + std::to_string(s.component) + " has no triangle with area");
  impl_->tree.insert(impl_->triangles.begin(), impl_->triangles.end());
  // Built now, not on the first query: layout choices query one locator from several threads.
  impl_->tree.build();
  impl_->tree.accelerate_distance_queries();
}

ComponentLocator::~ComponentLocator() = default;

Vec3 ComponentLocator::closest(const Vec3& p, Vec3* normal) const {
  int hint = -1;
  return closest(p, normal, &hint);
}

Vec3 ComponentLocator::closest(const Vec3& p, Vec3* normal, int* hint) const {
  const Kernel::Point_3 query(p.x(), p.y(), p.z());
  // The hint's own closest point bounds the search: with a hint from a nearby query (a
  // vertex moved a little) only the few triangles closer than it are looked at.
  const auto hit =
      *hint >= 0 && *hint < static_cast<int>(impl_->triangles.size())
          ? impl_->tree.closest_point_and_primitive(
                query, {Kernel::Construct_projected_point_3()(impl_->triangles[*hint], query),
                        impl_->triangles.begin() + *hint})
          : impl_->tree.closest_point_and_primitive(query);
  *hint = static_cast<int>(hit.second - impl_->triangles.begin());
  if (normal) *normal = surface_.face_normal[impl_->face[*hint]];
  return Vec3(hit.first.x(), hit.first.y(), hit.first.z());
}

std::vector<Vec3> ComponentLocator::normals_at(const Vec3& p, int* hint) const {
  const Vec3 at = closest(p, nullptr, hint);
  const int f = impl_->face[*hint];
  const auto fh = surface_.mesh.face_handle(f);
  int v[3], k = 0;
  for (auto u : surface_.mesh.fv_range(fh)) v[k++] = u.idx();
  const Vec3 a = surface_.point[v[0]], b = surface_.point[v[1]], c = surface_.point[v[2]];
  const Vec3 n = (b - a).cross(c - a);
  const double area = n.squaredNorm();
  // Barycentric coordinates of the closest point; ≈ 0 where it lies on the opposite edge.
  const double w[3] = {(b - at).cross(c - at).dot(n) / area, (c - at).cross(a - at).dot(n) / area,
                       (a - at).cross(b - at).dot(n) / area};
  constexpr double kOnEdge = 1e-9;
  int on[3], weighted = 0;  // corners with weight: 1 is a vertex, 2 an edge, 3 the inside
  for (int i = 0; i < 3; ++i)
    if (w[i] > kOnEdge) on[weighted++] = i;
  std::vector<Vec3> out{surface_.face_normal[f]};
  auto add = [&](int g) {
    if (g >= 0 && g != f && surface_.in(g)) out.push_back(surface_.face_normal[g]);
  };
  if (weighted == 2) {  // on the edge between those two corners
    for (auto h : surface_.mesh.fh_range(fh)) {
      const int x = surface_.from(h.idx()), y = surface_.to(h.idx());
      if ((x == v[on[0]] || x == v[on[1]]) && (y == v[on[0]] || y == v[on[1]]))
        add(surface_.face(h.idx() ^ 1));
    }
  } else if (weighted == 1) {  // at a vertex: its fan
    for (auto g : surface_.mesh.vf_range(surface_.mesh.vertex_handle(v[on[0]]))) add(g.idx());
  }
  return out;
}

}  // namespace genbrep::quad_detail

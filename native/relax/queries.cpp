// relax/queries.cpp — closest points on the original design and on the original loops
// (CGAL AABB trees), normal agreement, vertex rings.
#include <CGAL/AABB_segment_primitive.h>
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <algorithm>

#include "core/numbers.h"
#include "core/error.h"
#include "relax/detail/relax_detail.h"

namespace genbrep::relax_detail {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Triangle = Kernel::Triangle_3;
using Segment3 = Kernel::Segment_3;
using TriangleTree = CGAL::AABB_tree<CGAL::AABB_traits<
    Kernel, CGAL::AABB_triangle_primitive<Kernel, std::vector<Triangle>::const_iterator>>>;
using SegmentTree = CGAL::AABB_tree<CGAL::AABB_traits<
    Kernel, CGAL::AABB_segment_primitive<Kernel, std::vector<Segment3>::const_iterator>>>;

Point to_point(const Vec3& p) { return Point(p.x(), p.y(), p.z()); }

// A triangle without area relative to its size: its closest points are undefined, and
// its edges are covered by its neighbours' in a closed mesh, so trees leave it out.
bool degenerate(const Vec3& a, const Vec3& b, const Vec3& c) {
  const double longest =
      std::max({(b - a).squaredNorm(), (c - b).squaredNorm(), (a - c).squaredNorm()});
  return (b - a).cross(c - a).norm() <= 1e-12 * longest;
}

}  // namespace

struct SurfaceProjector::Impl {
  std::vector<Triangle> triangles;
  std::vector<int> ids;  // design triangle of triangles[i]
  TriangleTree tree;
};

SurfaceProjector::SurfaceProjector(const TriangleMesh& design) : impl_(std::make_unique<Impl>()) {
  const auto& V = design.vertices;
  const auto& T = design.triangles;
  std::vector<Vec3> vertex_normals(static_cast<size_t>(V.rows()), Vec3::Zero());
  normals_.assign(static_cast<size_t>(T.rows()), Vec3::Zero());
  for (Eigen::Index t = 0; t < T.rows(); ++t) {
    const Vec3 a = V.row(T(t, 0)), b = V.row(T(t, 1)), c = V.row(T(t, 2));
    const Vec3 n = (b - a).cross(c - a);  // twice the area, along the normal
    for (int k = 0; k < 3; ++k) vertex_normals[T(t, k)] += n;
    if (degenerate(a, b, c)) continue;
    normals_[t] = n.normalized();
    impl_->triangles.emplace_back(to_point(a), to_point(b), to_point(c));
    impl_->ids.push_back(static_cast<int>(t));
  }
  for (Eigen::Index t = 0; t < T.rows(); ++t) {
    if (normals_[t].squaredNorm() > 0) continue;
    Vec3 n = Vec3::Zero();
    for (int k = 0; k < 3; ++k) n += vertex_normals[T(t, k)];
    if (n.squaredNorm() > 0) normals_[t] = n.normalized();
  }
  GENBREP_CHECK(!impl_->triangles.empty(), Code::InvalidInput,
                "relax: the design has no triangle with area");
  impl_->tree.insert(impl_->triangles.cbegin(), impl_->triangles.cend());
  impl_->tree.build();
  impl_->tree.accelerate_distance_queries();
}

SurfaceProjector::~SurfaceProjector() = default;

SurfaceProjector::Hit SurfaceProjector::nearest(const Vec3& p) const {
  const auto hit = impl_->tree.closest_point_and_primitive(to_point(p));
  Hit out;
  out.point = to_vec(hit.first);
  out.triangle = impl_->ids[static_cast<size_t>(hit.second - impl_->triangles.cbegin())];
  return out;
}

struct PolylineDistance::Impl {
  std::vector<Segment3> segments;
  std::vector<int> tags;
  SegmentTree tree;
};

PolylineDistance::PolylineDistance(std::vector<PolylineDistance::Segment> segments)
    : impl_(std::make_unique<Impl>()) {
  for (const auto& s : segments) {
    if ((s.b - s.a).squaredNorm() == 0) continue;
    impl_->segments.emplace_back(to_point(s.a), to_point(s.b));
    impl_->tags.push_back(s.tag);
  }
  if (impl_->segments.empty()) return;
  impl_->tree.insert(impl_->segments.cbegin(), impl_->segments.cend());
  impl_->tree.build();
  impl_->tree.accelerate_distance_queries();
}

PolylineDistance::~PolylineDistance() = default;

PolylineDistance::Hit PolylineDistance::nearest(const Vec3& p) const {
  Hit out;
  if (impl_->segments.empty()) {
    out.point = p;
    return out;
  }
  const auto hit = impl_->tree.closest_point_and_primitive(to_point(p));
  out.point = to_vec(hit.first);
  out.distance = (out.point - p).norm();
  out.tag = impl_->tags[static_cast<size_t>(hit.second - impl_->segments.cbegin())];
  return out;
}

Agreement normal_agreement(const Vec3& a, const Vec3& b, const Vec3& c,
                           const SurfaceProjector& projector, const Vec3* corner_normals) {
  if (degenerate(a, b, c)) return {-2, -2};
  const Vec3 n = (b - a).cross(c - a).normalized();
  Agreement out;
  out.centroid = n.dot(projector.normal(projector.nearest((a + b + c) / 3.0).triangle));
  out.best = out.centroid;
  const Vec3* corner[3] = {&a, &b, &c};
  for (int k = 0; k < 3; ++k) {
    const Vec3& m = corner_normals ? corner_normals[k]
                                   : projector.normal(projector.nearest(*corner[k]).triangle);
    out.best = std::max(out.best, n.dot(m));
  }
  return out;
}

std::vector<char> vertex_rings(const TriMesh& mesh, const std::vector<int>& seeds, int rings) {
  std::vector<char> in(mesh.n_vertices(), 0);
  std::vector<int> front;
  for (int v : seeds) {
    if (in[v]) continue;
    in[v] = 1;
    front.push_back(v);
  }
  for (int ring = 0; ring < rings; ++ring) {
    std::vector<int> next;
    for (int v : front) {
      for (const auto w : mesh.vv_range(mesh.vertex_handle(v))) {
        if (in[w.idx()]) continue;
        in[w.idx()] = 1;
        next.push_back(w.idx());
      }
    }
    front = std::move(next);
  }
  return in;
}

}  // namespace genbrep::relax_detail

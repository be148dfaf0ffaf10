// incidence/solids.cpp — CGAL AABB trees behind ClosedSurface, and union groups.
#include <CGAL/AABB_face_graph_triangle_primitive.h>
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/intersection.h>
#include <CGAL/Side_of_triangle_mesh.h>
#include <CGAL/Surface_mesh.h>

#include "core/union_find.h"
#include "incidence/incidence.h"

namespace genbrep {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using SurfaceMesh = CGAL::Surface_mesh<Point>;
using Primitive = CGAL::AABB_face_graph_triangle_primitive<SurfaceMesh>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;
using SideOf = CGAL::Side_of_triangle_mesh<SurfaceMesh, Kernel, CGAL::Default, Tree>;

struct ClosedSurface::Impl {
  SurfaceMesh mesh;
  Tree tree;
  std::unique_ptr<SideOf> side;
  Vec3 lo, hi;
};

ClosedSurface::ClosedSurface(const TriangleMesh& input) : impl_(std::make_unique<Impl>()) {
  auto& m = impl_->mesh;
  std::vector<SurfaceMesh::Vertex_index> vi;
  vi.reserve(static_cast<size_t>(input.vertices.rows()));
  for (Eigen::Index v = 0; v < input.vertices.rows(); ++v) {
    vi.push_back(m.add_vertex(Point(input.vertices(v, 0), input.vertices(v, 1), input.vertices(v, 2))));
  }
  for (Eigen::Index t = 0; t < input.triangles.rows(); ++t) {
    const auto f = m.add_face(vi[input.triangles(t, 0)], vi[input.triangles(t, 1)], vi[input.triangles(t, 2)]);
    GENBREP_CHECK(f != SurfaceMesh::null_face(), Code::Internal,
                  "surface mesh rejected a triangle of a validated solid");
  }
  impl_->tree.insert(faces(m).first, faces(m).second, m);
  impl_->tree.accelerate_distance_queries();
  impl_->side = std::make_unique<SideOf>(impl_->tree);
  impl_->lo = input.vertices.colwise().minCoeff().transpose();
  impl_->hi = input.vertices.colwise().maxCoeff().transpose();
}

ClosedSurface::~ClosedSurface() = default;
ClosedSurface::ClosedSurface(ClosedSurface&&) noexcept = default;
ClosedSurface& ClosedSurface::operator=(ClosedSurface&&) noexcept = default;

Vec3 ClosedSurface::nearest_point(const Vec3& p) const {
  const Point q = impl_->tree.closest_point(Point(p.x(), p.y(), p.z()));
  return Vec3(q.x(), q.y(), q.z());
}

double ClosedSurface::distance(const Vec3& p) const {
  return std::sqrt(CGAL::to_double(impl_->tree.squared_distance(Point(p.x(), p.y(), p.z()))));
}

bool ClosedSurface::inside(const Vec3& p) const {
  if ((p.array() < impl_->lo.array()).any() || (p.array() > impl_->hi.array()).any()) return false;
  return (*impl_->side)(Point(p.x(), p.y(), p.z())) != CGAL::ON_UNBOUNDED_SIDE;
}

double ClosedSurface::signed_distance(const Vec3& p) const {
  Vec3 nearest;
  return signed_distance(p, &nearest);
}

double ClosedSurface::signed_distance(const Vec3& p, Vec3* nearest) const {
  // As distance() computes it: the tree's squared distance is that to its closest point.
  const Point query(p.x(), p.y(), p.z());
  const Point q = impl_->tree.closest_point(query);
  *nearest = Vec3(q.x(), q.y(), q.z());
  const double d = std::sqrt(CGAL::to_double(CGAL::squared_distance(query, q)));
  return inside(p) ? -d : d;
}

const Vec3& ClosedSurface::min_corner() const { return impl_->lo; }
const Vec3& ClosedSurface::max_corner() const { return impl_->hi; }

bool ClosedSurface::intersects(const ClosedSurface& other) const {
  if ((impl_->hi.array() < other.impl_->lo.array()).any() ||
      (other.impl_->hi.array() < impl_->lo.array()).any()) {
    return false;
  }
  return CGAL::Polygon_mesh_processing::do_intersect(impl_->mesh, other.impl_->mesh);
}

SolidSet::SolidSet(std::vector<SolidInput> solids, Diagnostics* diagnostics)
    : solids_(std::move(solids)) {
  surfaces_.reserve(solids_.size());
  for (const auto& s : solids_) surfaces_.emplace_back(s.mesh);
  const int n = size();
  UnionFind groups(n);
  for (int i = 0; i < n; ++i) {
    for (int j = i + 1; j < n; ++j) {
      if (solids_[i].role != solids_[j].role || !surfaces_[i].intersects(surfaces_[j])) continue;
      groups.unite(i, j);
      if (diagnostics) {
        diagnostics->push_back(describe(i) + " and " + describe(j) +
                               " overlap and are treated as their union");
      }
    }
  }
  group_.resize(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) group_[i] = groups.find(i);
}

std::string SolidSet::describe(int solid) const { return genbrep::describe(solids_[solid]); }

}  // namespace genbrep

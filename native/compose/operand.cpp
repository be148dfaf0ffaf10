// compose/operand.cpp — CGAL's preconditions checked before corefinement.
// PMP::corefine and the corefine_and_compute_* Booleans require triangle meshes that do
// not self-intersect (degenerate faces count as self-intersections), and the Booleans
// require closed meshes that bound a volume. Violating them is undefined behaviour: a
// SIGSEGV inside the corefinement's intersection filter was seen on an unsmoothed voxel
// bracket. Every operand is checked here first; a failed check takes the next tier.
// Operands that nearly coincide are snapped onto each other first (snap_onto).
#include <CGAL/AABB_face_graph_triangle_primitive.h>
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/measure.h>
#include <CGAL/Polygon_mesh_processing/orientation.h>
#include <CGAL/Polygon_mesh_processing/repair_degeneracies.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Polygon_mesh_processing/shape_predicates.h>

#include <array>
#include <cmath>
#include <optional>

#include "compose/detail/exact.h"

namespace genbrep::detail {

namespace PMP = CGAL::Polygon_mesh_processing;

std::string unusable_operand(const ExactMesh& mesh, bool closed) {
  if (mesh.is_empty()) return "is empty";
  if (!CGAL::is_triangle_mesh(mesh)) return "is not a triangle mesh";
  if (!mesh.is_valid(false)) return "is not a valid halfedge mesh";
  int degenerate = 0;
  for (const auto f : mesh.faces()) degenerate += PMP::is_degenerate_triangle_face(f, mesh);
  if (degenerate > 0) return "has " + std::to_string(degenerate) + " degenerate triangles";
  if (closed && !CGAL::is_closed(mesh)) return "is not closed";
  std::vector<std::pair<ExactMesh::Face_index, ExactMesh::Face_index>> pairs;
  PMP::self_intersections(mesh, std::back_inserter(pairs));
  if (!pairs.empty()) return "intersects itself (" + std::to_string(pairs.size()) + " triangle pairs)";
  if (closed && !PMP::does_bound_a_volume(mesh)) return "does not bound a volume";
  return {};
}

std::string make_usable(ExactMesh* mesh, bool closed) {
  bool degenerate = false;
  for (const auto f : mesh->faces()) degenerate = degenerate || PMP::is_degenerate_triangle_face(f, *mesh);
  // Zero-area triangles (collinear corners) are valid input to the mesh stage but count as
  // self-intersections for CGAL: flip or collapse them away, which keeps the surface's
  // shape exactly (exact kernel), then check what remains.
  if (degenerate) {
    PMP::remove_degenerate_faces(*mesh);
    mesh->collect_garbage();
  }
  return unusable_operand(*mesh, closed);
}

int snap_onto(ExactMesh* a, const ExactMesh& b, double delta) {
  using Inexact = CGAL::Exact_predicates_inexact_constructions_kernel;
  using Plain = CGAL::Surface_mesh<Inexact::Point_3>;
  using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Inexact, CGAL::AABB_face_graph_triangle_primitive<Plain>>>;
  auto rounded = [](const ExactPoint& p) {
    return Inexact::Point_3(CGAL::to_double(p.x()), CGAL::to_double(p.y()), CGAL::to_double(p.z()));
  };
  if (a->is_empty() || b.is_empty()) return 0;
  Plain plain;
  for (const auto v : b.vertices()) plain.add_vertex(rounded(b.point(v)));
  for (const auto f : b.faces()) {
    std::vector<Plain::Vertex_index> corners;
    for (const auto v : CGAL::vertices_around_face(b.halfedge(f), b)) corners.emplace_back(v.idx());
    plain.add_face(corners);
  }
  CGAL::Bbox_3 box = PMP::bbox(plain);
  box = CGAL::Bbox_3(box.xmin() - delta, box.ymin() - delta, box.zmin() - delta, box.xmax() + delta,
                     box.ymax() + delta, box.zmax() + delta);
  Tree tree(faces(plain).first, faces(plain).second, plain);
  tree.accelerate_distance_queries();
  const Exact::FT squared_delta = Exact::FT(delta) * Exact::FT(delta);
  int moved = 0;
  for (const auto v : a->vertices()) {
    const ExactPoint& p = a->point(v);
    const Inexact::Point_3 q = rounded(p);
    if (!CGAL::do_overlap(q.bbox(), box)) continue;
    const auto [foot, face] = tree.closest_point_and_primitive(q);
    if (CGAL::squared_distance(q, foot) > delta * delta) continue;
    std::array<ExactPoint, 3> c;
    int k = 0;
    for (const auto w : CGAL::vertices_around_face(plain.halfedge(face), plain))
      c[k++] = b.point(ExactMesh::Vertex_index(w.idx()));
    // Onto a corner of the face within δ, else onto an edge's line within δ, else onto its
    // plane: exactly, so that what was nearly coplanar is coplanar.
    std::optional<ExactPoint> target;
    for (int i = 0; i < 3 && !target; ++i)
      if (CGAL::compare(CGAL::squared_distance(p, c[i]), squared_delta) != CGAL::LARGER) target = c[i];
    for (int i = 0; i < 3 && !target; ++i) {
      const Exact::Line_3 line(c[i], c[(i + 1) % 3]);
      if (CGAL::compare(CGAL::squared_distance(p, line), squared_delta) != CGAL::LARGER) target = line.projection(p);
    }
    if (!target) target = Exact::Plane_3(c[0], c[1], c[2]).projection(p);
    if (*target == p) continue;
    a->point(v) = *target;
    ++moved;
  }
  return moved;
}

double signed_volume(const ExactMesh& m) {
  double sum = 0, magnitude = 0;
  for (const auto f : m.faces()) {
    const auto h = m.halfedge(f);
    const auto& a = m.point(m.source(h));
    const auto& b = m.point(m.target(h));
    const auto& c = m.point(m.target(m.next(h)));
    const Vec3 pa(CGAL::to_double(a.x()), CGAL::to_double(a.y()), CGAL::to_double(a.z()));
    const Vec3 pb(CGAL::to_double(b.x()), CGAL::to_double(b.y()), CGAL::to_double(b.z()));
    const Vec3 pc(CGAL::to_double(c.x()), CGAL::to_double(c.y()), CGAL::to_double(c.z()));
    const double six = pa.dot(pb.cross(pc));
    sum += six;
    magnitude += std::abs(six);
  }
  if (std::abs(sum) <= 1e-9 * magnitude) return CGAL::to_double(PMP::volume(m));
  return sum / 6;
}

}  // namespace genbrep::detail

// compose/operand.cpp — CGAL's preconditions checked before corefinement.
// PMP::corefine and the corefine_and_compute_* Booleans require triangle meshes that do
// not self-intersect (degenerate faces count as self-intersections), and the Booleans
// require closed meshes that bound a volume. Violating them is undefined behaviour: a
// SIGSEGV inside the corefinement's intersection filter was seen on an unsmoothed voxel
// bracket. Every operand is checked here first; a failed check takes the next tier.
// Also here: the solids grown before the Booleans, and the Booleans' canonical order.
#include <CGAL/Polygon_mesh_processing/corefinement.h>
#include <CGAL/Polygon_mesh_processing/measure.h>
#include <CGAL/Polygon_mesh_processing/orientation.h>
#include <CGAL/Polygon_mesh_processing/repair_degeneracies.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Polygon_mesh_processing/shape_predicates.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>

#include "compose/detail/exact.h"

namespace genbrep::detail {

namespace PMP = CGAL::Polygon_mesh_processing;

InexactMesh to_inexact(const TriangleMesh& mesh) {
  InexactMesh out;
  for (Eigen::Index v = 0; v < mesh.vertices.rows(); ++v)
    out.add_vertex(InexactMesh::Point(mesh.vertices(v, 0), mesh.vertices(v, 1), mesh.vertices(v, 2)));
  for (Eigen::Index t = 0; t < mesh.triangles.rows(); ++t)
    out.add_face(InexactMesh::Vertex_index(static_cast<unsigned>(mesh.triangles(t, 0))),
                 InexactMesh::Vertex_index(static_cast<unsigned>(mesh.triangles(t, 1))),
                 InexactMesh::Vertex_index(static_cast<unsigned>(mesh.triangles(t, 2))));
  return out;
}

namespace {

using Plain = InexactMesh;

// `mesh` with the same combinatorics in the double kernel when every point is exactly a
// double (input solids, pulled cage tessellations), else nothing. Its predicates are exact
// too, so the checks answer the same, without building lazy exact numbers per test.
std::optional<Plain> as_doubles(const ExactMesh& mesh) {
  if (mesh.has_garbage()) return std::nullopt;
  Plain plain;
  for (const auto v : mesh.vertices()) {
    const ExactPoint& p = mesh.point(v);
    const double x = CGAL::to_double(p.x()), y = CGAL::to_double(p.y()), z = CGAL::to_double(p.z());
    if (ExactPoint(x, y, z) != p) return std::nullopt;
    plain.add_vertex(Plain::Point(x, y, z));
  }
  for (const auto f : mesh.faces()) {
    std::vector<Plain::Vertex_index> corners;
    for (const auto v : CGAL::vertices_around_face(mesh.halfedge(f), mesh)) corners.emplace_back(v.idx());
    if (plain.add_face(corners) == Plain::null_face()) return std::nullopt;
  }
  return plain;
}

template <class Mesh>
std::string unusable(const Mesh& mesh, bool closed) {
  if (mesh.is_empty()) return "is empty";
  if (!CGAL::is_triangle_mesh(mesh)) return "is not a triangle mesh";
  if (!mesh.is_valid(false)) return "is not a valid halfedge mesh";
  int degenerate = 0;
  for (const auto f : mesh.faces()) degenerate += PMP::is_degenerate_triangle_face(f, mesh);
  if (degenerate > 0) return "has " + std::to_string(degenerate) + " degenerate triangles";
  if (closed && !CGAL::is_closed(mesh)) return "is not closed";
  std::vector<std::pair<typename Mesh::Face_index, typename Mesh::Face_index>> pairs;
  PMP::self_intersections(mesh, std::back_inserter(pairs));
  if (!pairs.empty()) return "intersects itself (" + std::to_string(pairs.size()) + " triangle pairs)";
  if (closed && !PMP::does_bound_a_volume(mesh)) return "does not bound a volume";
  return {};
}

}  // namespace

std::string unusable_operand(const ExactMesh& mesh, bool closed) {
  if (mesh.is_empty()) return "is empty";
  if (!mesh.is_valid(false)) return "is not a valid halfedge mesh";
  if (const auto plain = as_doubles(mesh)) return unusable(*plain, closed);
  return unusable(mesh, closed);
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

TriangleMesh grown(const TriangleMesh& solid, double delta) {
  const Eigen::Index nv = solid.vertices.rows();
  std::vector<Vec3> weighted(static_cast<size_t>(nv), Vec3::Zero());
  std::vector<std::vector<Vec3>> normals(static_cast<size_t>(nv));
  for (Eigen::Index t = 0; t < solid.triangles.rows(); ++t) {
    Vec3 p[3];
    for (int k = 0; k < 3; ++k) p[k] = solid.vertices.row(solid.triangles(t, k)).transpose();
    const Vec3 n = (p[1] - p[0]).cross(p[2] - p[0]);
    if (n.norm() == 0) continue;  // a zero-area face has no side to move
    for (int k = 0; k < 3; ++k) {
      const Vec3 a = p[(k + 1) % 3] - p[k], b = p[(k + 2) % 3] - p[k];
      const double angle = std::atan2(a.cross(b).norm(), a.dot(b));
      const auto v = static_cast<size_t>(solid.triangles(t, k));
      weighted[v] += angle * n.normalized();
      normals[v].push_back(n.normalized());
    }
  }
  TriangleMesh out = solid;
  for (Eigen::Index v = 0; v < nv; ++v) {
    const Vec3& w = weighted[static_cast<size_t>(v)];
    if (w.norm() == 0) continue;
    const Vec3 m = w.normalized();
    double least = 1;
    for (const Vec3& n : normals[static_cast<size_t>(v)]) least = std::min(least, m.dot(n));
    out.vertices.row(v) += (delta / std::max(least, 0.2) * m).transpose();
  }
  return out;
}

namespace {

// `mesh` with its vertices in lexicographic order of their exact points and its faces in
// order of their corners (each from its smallest), so that the same solid is the same
// mesh. The corefinement's element order depends on where its two meshes' boxes happen
// to lie in memory (CGAL's box intersection breaks ties by address), which depends on
// everything the process allocated before; rounding and repair then depend on that order,
// and the same design composed differently from one run to the next.
ExactMesh in_canonical_order(const ExactMesh& mesh) {
  std::vector<ExactMesh::Vertex_index> order(mesh.vertices().begin(), mesh.vertices().end());
  std::sort(order.begin(), order.end(), [&](ExactMesh::Vertex_index a, ExactMesh::Vertex_index b) {
    return CGAL::compare_xyz(mesh.point(a), mesh.point(b)) == CGAL::SMALLER;
  });
  ExactMesh out;
  std::vector<ExactMesh::Vertex_index> renamed(mesh.number_of_vertices() + mesh.number_of_removed_vertices());
  for (const auto v : order) renamed[v.idx()] = out.add_vertex(mesh.point(v));
  std::vector<std::array<ExactMesh::Vertex_index, 3>> faces;
  faces.reserve(mesh.number_of_faces());
  for (const auto f : mesh.faces()) {
    std::array<ExactMesh::Vertex_index, 3> c;
    int k = 0;
    for (const auto v : CGAL::vertices_around_face(mesh.halfedge(f), mesh)) c[static_cast<size_t>(k++)] = renamed[v.idx()];
    std::rotate(c.begin(), std::min_element(c.begin(), c.end()), c.end());
    faces.push_back(c);
  }
  std::sort(faces.begin(), faces.end());
  for (const auto& c : faces) out.add_face(c[0], c[1], c[2]);
  return out;
}

}  // namespace

bool exact_boolean(const ExactMesh& a, const ExactMesh& b, bool unite, ExactMesh* out) {
  ExactMesh x = a, y = b, result;
  const bool ok = unite ? PMP::corefine_and_compute_union(x, y, result)
                        : PMP::corefine_and_compute_difference(x, y, result);
  // CGAL 5.5 can report success with an invalid halfedge structure: check what it returns.
  if (!ok || !result.is_valid(false) || !CGAL::is_closed(result) || !CGAL::is_triangle_mesh(result)) return false;
  ExactMesh ordered = in_canonical_order(result);
  if (ordered.number_of_faces() != result.number_of_faces() || !ordered.is_valid(false)) return false;
  *out = std::move(ordered);
  return true;
}

double signed_volume(const ExactMesh& m) {
  // Summed about one of its own points, not the origin (see validate(), mesh/validate.cpp).
  double sum = 0, magnitude = 0;
  Vec3 o = Vec3::Zero();
  if (!m.is_empty()) {
    const auto& p = m.point(*m.vertices().begin());
    o = Vec3(CGAL::to_double(p.x()), CGAL::to_double(p.y()), CGAL::to_double(p.z()));
  }
  for (const auto f : m.faces()) {
    const auto h = m.halfedge(f);
    const auto& a = m.point(m.source(h));
    const auto& b = m.point(m.target(h));
    const auto& c = m.point(m.target(m.next(h)));
    const Vec3 pa = Vec3(CGAL::to_double(a.x()), CGAL::to_double(a.y()), CGAL::to_double(a.z())) - o;
    const Vec3 pb = Vec3(CGAL::to_double(b.x()), CGAL::to_double(b.y()), CGAL::to_double(b.z())) - o;
    const Vec3 pc = Vec3(CGAL::to_double(c.x()), CGAL::to_double(c.y()), CGAL::to_double(c.z())) - o;
    const double six = pa.dot(pb.cross(pc));
    sum += six;
    magnitude += std::abs(six);
  }
  if (std::abs(sum) <= 1e-9 * magnitude) return CGAL::to_double(PMP::volume(m));
  return sum / 6;
}

}  // namespace genbrep::detail

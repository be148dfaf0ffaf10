// compose/round.cpp — the exact composition rounded to doubles without new intersections.
// Measured on fixture 'boss' (a keep-out bolt filling the bore of a keep-in boss, exported
// separately): the bore's vertices on the axes sit 1e-16 off the bolt's faces, so the
// exact Booleans cut slivers whose edges are 2e-17 to 7e-16 long. The exact result is
// closed and free of self-intersections; rounding the ends of those edges independently
// folds the slivers over their neighbours (24 intersecting triangle pairs). Collapsing
// edges far below any design tolerance before rounding removes the slivers; every
// vertex moves by less than `tolerance`.
// CGAL's assertions stay on in this file even in release builds (CGAL_DEBUG): its
// autorefinement and local repair are experimental in CGAL 5.5, and an input they cannot
// handle then throws (caught below: the repair is not taken) instead of running on with a
// broken structure. The repairs run only where the rounding crossed, so the checks cost
// nothing elsewhere.
#define CGAL_DEBUG
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/corefinement.h>
#include <CGAL/Polygon_mesh_processing/repair_degeneracies.h>
#include <CGAL/Polygon_mesh_processing/repair_self_intersections.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/boost/graph/Euler_operations.h>

#include <algorithm>
#include <cmath>

#include "compose/detail/exact.h"
#include "mesh/mesh.h"

namespace genbrep::detail {

namespace {

// An input vertex (design, cage tessellation or solid) is exactly a double; constructed
// intersection points in general are not.
bool is_double(const ExactPoint& p) {
  return ExactPoint(CGAL::to_double(p.x()), CGAL::to_double(p.y()), CGAL::to_double(p.z())) == p;
}

bool shorter(const ExactMesh& mesh, ExactMesh::Edge_index e, const Exact::FT& squared_limit) {
  const auto h = mesh.halfedge(e);
  return CGAL::compare(
             CGAL::squared_distance(mesh.point(mesh.source(h)), mesh.point(mesh.target(h))),
             squared_limit) == CGAL::SMALLER;
}

// Whether Euler::collapse_edge may take e: both faces triangles, the link condition (no
// pinch), and the out-degree ≥ 3 that its join_face requires at both ends and both apexes
// (checked first, as every CGAL precondition here: broken, join_face walks a face cycle
// that never returns to its start).
bool collapsible(const ExactMesh& mesh, ExactMesh::Edge_index e) {
  const auto h = mesh.halfedge(e), o = mesh.opposite(h);
  if (mesh.is_border(h) || mesh.is_border(o)) return false;
  if (!CGAL::is_triangle(h, mesh) || !CGAL::is_triangle(o, mesh)) return false;
  for (const auto v : {mesh.source(h), mesh.target(h), mesh.target(mesh.next(h)), mesh.target(mesh.next(o))})
    if (mesh.degree(v) < 3) return false;
  return CGAL::Euler::does_satisfy_link_condition(e, mesh);
}

}  // namespace

Rounded round_to_doubles(ExactMesh mesh, double tolerance) {
  Rounded out;
  // Collapses need a valid triangle mesh; anything else is only rounded (the caller's
  // checks then see what that gives).
  if (!CGAL::is_triangle_mesh(mesh) || !mesh.is_valid(false)) {
    out.mesh = to_double(mesh);
    return out;
  }
  const Exact::FT squared_limit = Exact::FT(tolerance) * Exact::FT(tolerance);
  // A collapse can make a neighbouring edge short or long again: repeat until a pass finds
  // nothing it may collapse.
  for (int pass = 0; pass < 8; ++pass) {
    std::vector<ExactMesh::Edge_index> candidates;
    for (const auto e : mesh.edges()) {
      if (shorter(mesh, e, squared_limit)) candidates.push_back(e);
    }
    int collapsed = 0;
    out.blocked = 0;
    for (const auto e : candidates) {
      if (mesh.is_removed(e) || !shorter(mesh, e, squared_limit)) continue;
      if (!collapsible(mesh, e)) {
        ++out.blocked;  // it would pinch the surface or break a precondition; the caller's check decides
        continue;
      }
      const auto h = mesh.halfedge(e);
      const ExactPoint p = mesh.point(mesh.source(h)), q = mesh.point(mesh.target(h));
      const ExactPoint kept = is_double(q) || !is_double(p) ? q : p;
      out.longest = std::max(out.longest, std::sqrt(CGAL::to_double(CGAL::squared_distance(p, q))));
      if (out.where.size() < 16)
        out.where.emplace_back(CGAL::to_double(kept.x()), CGAL::to_double(kept.y()),
                               CGAL::to_double(kept.z()));
      const auto v = CGAL::Euler::collapse_edge(e, mesh);
      mesh.point(v) = kept;
      ++collapsed;
    }
    out.collapsed += collapsed;
    if (collapsed == 0) break;
  }
  out.mesh = to_double(mesh);
  return out;
}

namespace {

bool crosses_itself(const TriangleMesh& mesh) {
  return CGAL::Polygon_mesh_processing::does_self_intersect(to_inexact(mesh));
}

// Whether two triangles of `mesh` that cross lie in one plane. CGAL 5.5's autorefinement
// fails an internal assertion on a mesh with such pairs (Corefinement/Visitor.h,
// "insert_ok"; without assertions it runs on and can crash, docs/compose_method.md), so
// where they occur it is not called.
bool crosses_coplanar(const ExactMesh& mesh) {
  std::vector<std::pair<ExactMesh::Face_index, ExactMesh::Face_index>> pairs;
  CGAL::Polygon_mesh_processing::self_intersections(mesh, std::back_inserter(pairs));
  auto corners = [&](ExactMesh::Face_index f, ExactPoint* p) {
    int k = 0;
    for (const auto v : CGAL::vertices_around_face(mesh.halfedge(f), mesh)) p[k++] = mesh.point(v);
  };
  for (const auto& [a, b] : pairs) {
    ExactPoint p[3], q[3];
    corners(a, p), corners(b, q);
    if (CGAL::coplanar(p[0], p[1], p[2], q[0]) && CGAL::coplanar(p[0], p[1], p[2], q[1]) &&
        CGAL::coplanar(p[0], p[1], p[2], q[2]))
      return true;
  }
  return false;
}

// CGAL's local repair of the faces that cross: removes them and a few rings around them
// and refills the holes (constrained smoothing or hole filling), leaving the rest of the
// mesh as it is, every new face within `envelope` of the old surface (CGAL's polyhedral
// envelope). Replaces out->mesh when the result is closed and the change local.
void repair_locally(Rounded* out, double envelope) {
  namespace PMP = CGAL::Polygon_mesh_processing;
  InexactMesh m = to_inexact(out->mesh);
  bool repaired = false;
  // Its smoothing checks for degenerate faces with CGAL_warning (printed, not thrown) and
  // goes on; the result is checked here.
  const auto previous = CGAL::set_warning_handler([](const char*, const char*, const char*, int, const char*) {});
  try {
    repaired = PMP::experimental::remove_self_intersections(
        m, CGAL::parameters::apply_per_connected_component(false).polyhedral_envelope_epsilon(envelope));
  } catch (const std::exception&) {
    repaired = false;
  }
  CGAL::set_warning_handler(previous);
  if (!repaired || !CGAL::is_closed(m)) return;
  m.collect_garbage();
  TriangleMesh mesh;
  mesh.vertices.resize(static_cast<Eigen::Index>(m.number_of_vertices()), 3);
  for (const auto v : m.vertices()) {
    const auto& p = m.point(v);
    mesh.vertices.row(static_cast<Eigen::Index>(v.idx())) << p.x(), p.y(), p.z();
  }
  mesh.triangles.resize(static_cast<Eigen::Index>(m.number_of_faces()), 3);
  for (const auto f : m.faces()) {
    int k = 0;
    for (const auto v : CGAL::vertices_around_face(m.halfedge(f), m))
      mesh.triangles(static_cast<Eigen::Index>(f.idx()), k++) = static_cast<int>(v.idx());
    mesh.triangle_source.push_back(static_cast<int>(f.idx()));
  }
  // Local means local: a repair that changed more than 1% of the faces or 0.1% of the
  // volume (hole filling can close over a whole region) is not taken.
  const double before = validate(out->mesh).signed_volume, after = validate(mesh).signed_volume;
  const double faces_before = static_cast<double>(out->mesh.triangles.rows());
  if (std::abs(static_cast<double>(mesh.triangles.rows()) - faces_before) > 0.01 * faces_before ||
      std::abs(after - before) > 1e-3 * std::abs(before))
    return;
  out->mesh = std::move(mesh);
  out->repaired = true;
  out->intersecting = crosses_itself(out->mesh);
}

}  // namespace

Rounded round_robustly(const ExactMesh& exact, double scale) {
  namespace PMP = CGAL::Polygon_mesh_processing;
  Rounded out = round_to_doubles(exact, 1e-10 * scale);
  out.intersecting = crosses_itself(out.mesh);
  // Where it crosses: take the rounded mesh back into exact arithmetic, where its
  // crossings are exact; remove its zero-area triangles, autorefine it and drop the
  // patches the crossings cut off (CGAL's autorefine_and_remove_self_intersections),
  // collapse short edges and round again. Each round moves vertices by at most the
  // rounding error and the collapse tolerance, and cuts only where the previous rounding
  // crossed. CGAL throws where three triangles cross along one segment; that ends the
  // rounds.
  // The volume before any repair: a round that changes it by more than 0.1% cut off more
  // than slivers (autorefinement can drop whole patches where it reads the crossings
  // wrong, docs/compose_method.md) and is not taken.
  const double volume = validate(out.mesh).signed_volume;
  for (int round = 0; round < 2 && out.intersecting; ++round) {
    ExactMesh again = to_exact(out.mesh);
    try {
      // Autorefinement's input: a valid closed triangle mesh without zero-area triangles
      // (which count as crossings it cannot cut); where they cannot all be removed, the
      // rounds end.
      if (!PMP::remove_degenerate_faces(again)) break;
      again.collect_garbage();
      if (!again.is_valid(false) || !CGAL::is_closed(again) || crosses_coplanar(again)) break;
      if (!PMP::experimental::autorefine_and_remove_self_intersections(again)) break;
    } catch (const std::exception&) {
      break;
    }
    again.collect_garbage();
    Rounded next = round_to_doubles(std::move(again), 1e-10 * scale);
    if (std::abs(validate(next.mesh).signed_volume - volume) > 1e-3 * std::abs(volume)) break;
    next.collapsed += out.collapsed;
    next.blocked += out.blocked;
    next.longest = std::max(next.longest, out.longest);
    if (next.where.empty()) next.where = out.where;
    next.refined = out.refined + 1;
    next.intersecting = crosses_itself(next.mesh);
    out = std::move(next);
  }
  // What still crosses: CGAL's local repair, the refilled faces within 1e-7 × the scene of
  // the faces they replace. Last, as it is by far the slower of the two.
  if (out.intersecting) repair_locally(&out, 1e-7 * scale);
  return out;
}

}  // namespace genbrep::detail

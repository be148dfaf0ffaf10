// compose/round.cpp — the exact composition rounded to doubles without new intersections.
// Measured on fixture 'boss' (a keep-out bolt filling the bore of a keep-in boss, exported
// separately): the bore's vertices on the axes sit 1e-16 off the bolt's faces, so the
// exact Booleans cut slivers whose edges are 2e-17 to 7e-16 long. The exact result is
// closed and free of self-intersections; rounding the ends of those edges independently
// folds the slivers over their neighbours (24 intersecting triangle pairs). Collapsing
// edges far below any design tolerance before rounding removes the slivers; every
// vertex moves by less than `tolerance`.
#include <CGAL/boost/graph/Euler_operations.h>

#include <algorithm>
#include <cmath>

#include "compose/detail/exact.h"

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

}  // namespace

Rounded round_to_doubles(ExactMesh mesh, double tolerance) {
  Rounded out;
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
      if (!CGAL::Euler::does_satisfy_link_condition(e, mesh)) {
        ++out.blocked;  // collapsing would pinch the surface; the caller's check decides
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

}  // namespace genbrep::detail

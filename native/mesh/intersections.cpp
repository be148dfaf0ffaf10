// mesh/intersections.cpp — triangles of one closed mesh that cross each other (CGAL's
// self_intersections: box intersection of the triangles' bounds, then exact predicates).
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>

#include <algorithm>

#include "core/union_find.h"
#include "mesh/mesh.h"

namespace genbrep {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using SurfaceMesh = CGAL::Surface_mesh<Point>;

// Whether triangles a and b are joined through triangles sharing edges.
bool edge_connected(const TriangleMesh& mesh, int a, int b) {
  std::vector<std::array<int, 3>> edges;  // (lo, hi, triangle)
  edges.reserve(3 * static_cast<size_t>(mesh.triangles.rows()));
  for (int t = 0; t < mesh.triangles.rows(); ++t)
    for (int k = 0; k < 3; ++k) {
      const int u = mesh.triangles(t, k), v = mesh.triangles(t, (k + 1) % 3);
      edges.push_back({std::min(u, v), std::max(u, v), t});
    }
  std::sort(edges.begin(), edges.end());
  UnionFind shells(static_cast<int>(mesh.triangles.rows()));
  for (size_t i = 1; i < edges.size(); ++i)
    if (edges[i][0] == edges[i - 1][0] && edges[i][1] == edges[i - 1][1]) shells.unite(edges[i][2], edges[i - 1][2]);
  return shells.find(a) == shells.find(b);
}

}  // namespace

SelfIntersections self_intersections(const TriangleMesh& mesh) {
  SurfaceMesh m;
  std::vector<SurfaceMesh::Vertex_index> vi;
  vi.reserve(static_cast<size_t>(mesh.vertices.rows()));
  for (Eigen::Index v = 0; v < mesh.vertices.rows(); ++v)
    vi.push_back(m.add_vertex(Point(mesh.vertices(v, 0), mesh.vertices(v, 1), mesh.vertices(v, 2))));
  std::vector<char> degenerate(static_cast<size_t>(mesh.triangles.rows()), 0);
  for (Eigen::Index t = 0; t < mesh.triangles.rows(); ++t) {
    const auto f = m.add_face(vi[mesh.triangles(t, 0)], vi[mesh.triangles(t, 1)], vi[mesh.triangles(t, 2)]);
    GENBREP_CHECK(f != SurfaceMesh::null_face() && static_cast<Eigen::Index>(f) == t, Code::Internal,
                  "surface mesh rejected triangle " + std::to_string(t) + " of a validated mesh");
    degenerate[t] = CGAL::collinear(m.point(vi[mesh.triangles(t, 0)]), m.point(vi[mesh.triangles(t, 1)]),
                                    m.point(vi[mesh.triangles(t, 2)]));
  }
  // A zero-area triangle's neighbours touch along its collapsed side, which CGAL counts as
  // crossing; marching cubes makes such triangles, so pairs where both triangles have a
  // corner on a zero-area triangle are left out.
  std::vector<char> beside_degenerate(static_cast<size_t>(mesh.vertices.rows()), 0);
  for (Eigen::Index t = 0; t < mesh.triangles.rows(); ++t)
    if (degenerate[t])
      for (int k = 0; k < 3; ++k) beside_degenerate[mesh.triangles(t, k)] = 1;
  auto touches_degenerate = [&](int t) {
    return beside_degenerate[mesh.triangles(t, 0)] || beside_degenerate[mesh.triangles(t, 1)] ||
           beside_degenerate[mesh.triangles(t, 2)];
  };
  std::vector<std::pair<SurfaceMesh::Face_index, SurfaceMesh::Face_index>> pairs;
  CGAL::Polygon_mesh_processing::self_intersections(m, std::back_inserter(pairs));
  SelfIntersections out;
  for (const auto& [f, g] : pairs) {
    const int a = static_cast<int>(f), b = static_cast<int>(g);
    if (degenerate[a] || degenerate[b] || (touches_degenerate(a) && touches_degenerate(b))) continue;
    const std::array<int, 2> pair{std::min(a, b), std::max(a, b)};
    if (out.pairs++ == 0 || pair < out.first) out.first = pair;
  }
  if (out.pairs > 0) out.first_in_one_shell = edge_connected(mesh, out.first[0], out.first[1]);
  return out;
}

}  // namespace genbrep

// quad/fallback.cpp — the last resort of quad/ for a component whose patch layout gives no
// valid cage: a pure-quad cage that is valid by construction but not field-aligned.
// 1. CGAL's isotropic remesher makes a coarse triangulation of the component (the caller
//    asks for twice the target edge length first, finer when that folds); boundary edges may be split and collapsed and their vertices
//    slide along the loops (relax_constraints), so the boundary stays on the loops.
// 2. Triangles are paired across their shared edge into quads, greedily from the pair whose
//    quad is closest to a rectangle; pairs worse than kMaxPairDeviation stay triangles.
// 3. One Catmull–Clark-style split: a face with k corners becomes k quads (corner, edge
//    midpoint, face centre, edge midpoint). New points are projected onto the component;
//    boundary midpoints onto their loop's polyline.
// The result is pure quad, manifold, and every loop is one closed chain on its loop; its
// irregular vertices are the coarse mesh's vertices of valence ≠ 4 and the centres of the
// unpaired triangles (valence 3), so it is reported as a fallback, below the targets a
// field-aligned layout reaches.
// Complexity: O(F log F) for the remesh and the pairing.
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/remesh.h>
#include <CGAL/Surface_mesh.h>

#include <algorithm>
#include <cmath>
#include <map>

#include "quad/detail/repair.h"

namespace genbrep::quad_detail {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Mesh = CGAL::Surface_mesh<Point>;
namespace PMP = CGAL::Polygon_mesh_processing;

// A pair of triangles is merged only if its quad's corners are all within this of 90°.
constexpr double kMaxPairDeviation = 50.0;


double max_corner_deviation(const Vec3 (&c)[4]) {
  double worst = 0;
  for (int k = 0; k < 4; ++k) {
    const Vec3 a = c[(k + 1) % 4] - c[k], b = c[(k + 3) % 4] - c[k];
    const double angle = std::atan2(a.cross(b).norm(), a.dot(b)) * 180 / kPi;
    worst = std::max(worst, std::abs(angle - 90));
  }
  return worst;
}

// Closest point on a closed polyline.
Vec3 closest_on_loop(const std::vector<Vec3>& loop, const Vec3& p, double* distance) {
  Vec3 best = loop.front();
  double best_d = 1e300;
  for (size_t i = 0; i < loop.size(); ++i) {
    const Vec3& a = loop[i];
    const Vec3& b = loop[(i + 1) % loop.size()];
    const Vec3 e = b - a;
    const double t = e.squaredNorm() > 0 ? std::clamp((p - a).dot(e) / e.squaredNorm(), 0.0, 1.0) : 0;
    const Vec3 q = a + t * e;
    const double d = (q - p).squaredNorm();
    if (d < best_d) best_d = d, best = q;
  }
  *distance = std::sqrt(best_d);
  return best;
}

}  // namespace

QuadCage fallback_cage(const Surface& s, double coarse_edge_length) {
  // 1. The component as a CGAL mesh, remeshed coarsely.
  Mesh mesh;
  std::map<int, Mesh::Vertex_index> vertex;
  for (int v : s.vertices) vertex[v] = mesh.add_vertex(Point(s.point[v].x(), s.point[v].y(), s.point[v].z()));
  for (auto f : s.mesh.faces()) {
    if (!s.in(f.idx())) continue;
    std::vector<Mesh::Vertex_index> corners;
    for (auto v : s.mesh.fv_range(f)) corners.push_back(vertex.at(v.idx()));
    GENBREP_CHECK(mesh.add_face(corners) != Mesh::null_face(), Code::StageFailure,
                  "quad: component " + std::to_string(s.component) +
                      ": its triangles do not form a manifold surface");
  }
  PMP::isotropic_remeshing(faces(mesh), coarse_edge_length, mesh,
                           PMP::parameters::number_of_iterations(5)
                               .protect_constraints(false)
                               .collapse_constraints(true)
                               .relax_constraints(true));
  mesh.collect_garbage();

  // 2. Greedy pairing of triangles into quads.
  std::vector<std::pair<double, Mesh::Halfedge_index>> candidates;
  for (auto e : mesh.edges()) {
    const auto h = mesh.halfedge(e);
    if (mesh.is_border(e)) continue;
    const Vec3 c[4] = {to_vec(mesh.point(mesh.source(h))),
                       to_vec(mesh.point(mesh.target(mesh.next(mesh.opposite(h))))),
                       to_vec(mesh.point(mesh.target(h))),
                       to_vec(mesh.point(mesh.target(mesh.next(h))))};
    const double deviation = max_corner_deviation(c);
    if (deviation <= kMaxPairDeviation) candidates.push_back({deviation, h});
  }
  std::stable_sort(candidates.begin(), candidates.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<char> paired(mesh.number_of_faces(), 0);
  std::vector<std::vector<Mesh::Vertex_index>> polygons;  // counter-clockwise from outside
  for (const auto& [deviation, h] : candidates) {
    const auto f = mesh.face(h), g = mesh.face(mesh.opposite(h));
    if (paired[f.idx()] || paired[g.idx()]) continue;
    paired[f.idx()] = paired[g.idx()] = 1;
    // Face f = (source h, target h, target next h); g adds the vertex across h.
    polygons.push_back({mesh.source(h), mesh.target(mesh.next(mesh.opposite(h))), mesh.target(h),
                        mesh.target(mesh.next(h))});
  }
  for (auto f : mesh.faces())
    if (!paired[f.idx()]) {
      std::vector<Mesh::Vertex_index> corners;
      for (auto v : vertices_around_face(mesh.halfedge(f), mesh)) corners.push_back(v);
      polygons.push_back(corners);
    }

  // 3. The split. Boundary midpoints go onto the loop nearest to them.
  const ComponentLocator locator(s);
  std::vector<std::vector<Vec3>> loops;
  std::vector<int> loop_index;
  for (int l = 0; l < static_cast<int>(s.partition.loops.size()); ++l) {
    if (s.partition.loops[l].component != s.component) continue;
    std::vector<Vec3> polyline;
    for (int v : s.partition.loops[l].vertices) polyline.push_back(s.point[v]);
    loops.push_back(polyline);
    loop_index.push_back(l);
  }
  auto nearest_loop = [&](const Vec3& p, Vec3* on) {
    int best = -1;
    double best_d = 1e300;
    for (int l = 0; l < static_cast<int>(loops.size()); ++l) {
      double d;
      const Vec3 q = closest_on_loop(loops[l], p, &d);
      if (d < best_d) best_d = d, best = l, *on = q;
    }
    return best;
  };
  QuadCage cage;
  cage.component = s.component;
  std::vector<Vec3> points;
  for (auto v : mesh.vertices()) points.push_back(to_vec(mesh.point(v)));  // index = v.idx()
  std::map<std::pair<int, int>, int> midpoint;
  auto edge_point = [&](Mesh::Vertex_index a, Mesh::Vertex_index b) {
    const std::pair<int, int> key{std::min<int>(a.idx(), b.idx()), std::max<int>(a.idx(), b.idx())};
    auto it = midpoint.find(key);
    if (it != midpoint.end()) return it->second;
    const Vec3 mid = 0.5 * (points[a.idx()] + points[b.idx()]);
    const auto h = mesh.halfedge(a, b);
    Vec3 at;
    if (mesh.is_border(mesh.edge(h))) nearest_loop(mid, &at);
    else at = locator.closest(mid, nullptr);
    points.push_back(at);
    return midpoint[key] = static_cast<int>(points.size()) - 1;
  };
  std::vector<std::array<int, 4>> quads;
  for (const auto& polygon : polygons) {
    const int k = static_cast<int>(polygon.size());
    Vec3 centre = Vec3::Zero();
    for (auto v : polygon) centre += points[v.idx()];
    points.push_back(locator.closest(centre / k, nullptr));
    const int c = static_cast<int>(points.size()) - 1;
    for (int i = 0; i < k; ++i) {
      const auto prev = polygon[(i + k - 1) % k], here = polygon[i], next = polygon[(i + 1) % k];
      quads.push_back({static_cast<int>(here.idx()), edge_point(here, next), c, edge_point(prev, here)});
    }
  }
  cage.vertices.resize(static_cast<Eigen::Index>(points.size()), 3);
  for (size_t i = 0; i < points.size(); ++i) cage.vertices.row(i) = points[i].transpose();
  cage.quads.resize(static_cast<Eigen::Index>(quads.size()), 4);
  for (size_t q = 0; q < quads.size(); ++q)
    for (int k = 0; k < 4; ++k) cage.quads(q, k) = quads[q][k];

  // Boundary chains: the border of the remeshed component, split at the midpoints, in the
  // direction of its faces (organic side on the left, as the loops run).
  std::vector<char> walked(mesh.number_of_halfedges(), 0);
  for (auto h0 : mesh.halfedges()) {
    if (walked[h0.idx()] || mesh.is_border(h0) || !mesh.is_border(mesh.opposite(h0))) continue;
    std::vector<int> chain;
    for (auto h = h0; !walked[h.idx()];) {
      walked[h.idx()] = 1;
      chain.push_back(static_cast<int>(mesh.source(h).idx()));
      chain.push_back(edge_point(mesh.source(h), mesh.target(h)));
      // Next face halfedge along the border: around target(h), the one whose opposite is
      // a border halfedge.
      auto next = mesh.next(h);
      while (!mesh.is_border(mesh.opposite(next))) next = mesh.next(mesh.opposite(next));
      h = next;
    }
    Vec3 on;
    const int l = nearest_loop(points[chain.front()], &on);
    GENBREP_CHECK(l >= 0, Code::StageFailure,
                  "quad: component " + std::to_string(s.component) + ": a border without a loop");
    for (int v : chain) {  // the remesher's border vertices too: exactly on the loop
      double d;
      cage.vertices.row(v) = closest_on_loop(loops[l], points[v], &d).transpose();
    }
    cage.boundary_chains.push_back(chain);
    cage.chain_loop.push_back(loop_index[l]);
  }
  return cage;
}

}  // namespace genbrep::quad_detail

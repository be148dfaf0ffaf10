// compose/contact.cpp — C = O ∩ ∂S (§7.1), the homeomorphism check of §7.3 and the
// organic cell Q = T ∪ caps that §8.2's classification works on.
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/connected_components.h>
#include <CGAL/Polygon_mesh_processing/corefinement.h>
#include <CGAL/Polygon_mesh_processing/measure.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Polygon_mesh_processing/shape_predicates.h>

#include <map>
#include <set>

#include "compose/detail/exact.h"

namespace genbrep::detail {

namespace PMP = CGAL::Polygon_mesh_processing;
using VertexIndex = ExactMesh::Vertex_index;
using FaceIndex = ExactMesh::Face_index;
using EdgeIndex = ExactMesh::Edge_index;
using HalfedgeIndex = ExactMesh::Halfedge_index;

ExactMesh to_exact(const TriangleMesh& mesh) {
  ExactMesh out;
  std::vector<VertexIndex> vi;
  for (Eigen::Index v = 0; v < mesh.vertices.rows(); ++v) {
    vi.push_back(out.add_vertex(ExactPoint(mesh.vertices(v, 0), mesh.vertices(v, 1), mesh.vertices(v, 2))));
  }
  for (Eigen::Index t = 0; t < mesh.triangles.rows(); ++t) {
    const auto f = out.add_face(vi[mesh.triangles(t, 0)], vi[mesh.triangles(t, 1)], vi[mesh.triangles(t, 2)]);
    GENBREP_CHECK(f != ExactMesh::null_face(), Code::Internal, "a triangle is not 2-manifold");
  }
  return out;
}

TriangleMesh to_double(const ExactMesh& mesh) {
  TriangleMesh out;
  std::map<VertexIndex, int> index;
  out.vertices.resize(static_cast<Eigen::Index>(mesh.number_of_vertices()), 3);
  for (const auto v : mesh.vertices()) {
    const int i = static_cast<int>(index.size());
    index[v] = i;
    const auto& p = mesh.point(v);
    out.vertices.row(i) << CGAL::to_double(p.x()), CGAL::to_double(p.y()), CGAL::to_double(p.z());
  }
  out.triangles.resize(static_cast<Eigen::Index>(mesh.number_of_faces()), 3);
  int t = 0;
  for (const auto f : mesh.faces()) {
    int k = 0;
    for (const auto v : CGAL::vertices_around_face(mesh.halfedge(f), mesh)) out.triangles(t, k++) = index[v];
    out.triangle_source.push_back(t++);
  }
  return out;
}

ExactMesh solid_union(const std::vector<SolidInput>& solids, const std::vector<int>& members) {
  auto checked = [&](int s) {
    ExactMesh mesh = to_exact(solids[s].mesh);
    const std::string unusable = make_usable(&mesh, true);
    GENBREP_CHECK(unusable.empty(), Code::StageFailure, "solid '" + solids[s].name + "' " + unusable);
    return mesh;
  };
  ExactMesh result = checked(members.at(0));
  for (size_t i = 1; i < members.size(); ++i) {
    ExactMesh other = checked(members[i]), out;
    GENBREP_CHECK(exact_boolean(result, other, true, &out), Code::StageFailure,
                  "the union of the solids bordering a loop is not 2-manifold ('" +
                      solids[members[0]].name + "' and '" + solids[members[i]].name + "')");
    result = std::move(out);
  }
  return result;
}

namespace {

using PointPair = std::pair<ExactPoint, ExactPoint>;
struct PairLess {
  bool operator()(const PointPair& a, const PointPair& b) const {
    PointLess less;
    if (less(a.first, b.first)) return true;
    if (less(b.first, a.first)) return false;
    return less(a.second, b.second);
  }
};

Vec3 to_vec(const ExactPoint& p) {
  return Vec3(CGAL::to_double(p.x()), CGAL::to_double(p.y()), CGAL::to_double(p.z()));
}

// Closed soup → mesh, merging exactly equal points.
bool build_closed(const std::vector<std::array<ExactPoint, 3>>& triangles, ExactMesh* out) {
  std::map<ExactPoint, VertexIndex, PointLess> index;
  for (const auto& t : triangles) {
    std::array<VertexIndex, 3> v;
    for (int k = 0; k < 3; ++k) {
      auto it = index.find(t[k]);
      if (it == index.end()) it = index.emplace(t[k], out->add_vertex(t[k])).first;
      v[k] = it->second;
    }
    if (out->add_face(v[0], v[1], v[2]) == ExactMesh::null_face()) return false;
  }
  return true;
}

std::array<ExactPoint, 3> corners(const ExactMesh& m, FaceIndex f, bool reversed) {
  const auto h = m.halfedge(f);
  std::array<ExactPoint, 3> p{m.point(m.source(h)), m.point(m.target(h)), m.point(m.target(m.next(h)))};
  if (reversed) std::swap(p[1], p[2]);
  return p;
}


}  // namespace

ContactCut cut_at_contact(const OrganicSheet& pulled, const ExactMesh& solid_union_mesh) {
  ContactCut cut;
  ExactMesh sheet = to_exact(pulled.mesh), solid = solid_union_mesh;
  // The sheet's points are doubles: its self-intersection test (predicates only) runs in
  // the filtered inexact kernel, exact all the same and about twice as fast as on the lazy
  // exact copy. Faces are added in the same order, so their indices match.
  const InexactMesh plain = to_inexact(pulled.mesh);
  std::vector<std::pair<FaceIndex, FaceIndex>> crossing;
  PMP::self_intersections(plain, std::back_inserter(crossing));
  if (!crossing.empty()) {
    int degenerate = 0;
    for (const auto& [f, g] : crossing) {
      degenerate += PMP::is_degenerate_triangle_face(f, sheet) || PMP::is_degenerate_triangle_face(g, sheet);
    }
    const Vec3 at = to_vec(sheet.point(sheet.target(sheet.halfedge(crossing[0].first))));
    cut.problem = "the pulled organic surface intersects itself (" + std::to_string(crossing.size()) +
                  " triangle pairs, " + std::to_string(degenerate) + " with a degenerate triangle, near " +
                  std::to_string(at.x()) + " " + std::to_string(at.y()) + " " + std::to_string(at.z()) + ")";
    return cut;
  }
  auto sheet_constrained = sheet.add_property_map<EdgeIndex, bool>("e:contact", false).first;
  auto solid_constrained = solid.add_property_map<EdgeIndex, bool>("e:contact", false).first;
  PMP::corefine(sheet, solid, CGAL::parameters::edge_is_constrained_map(sheet_constrained),
                CGAL::parameters::edge_is_constrained_map(solid_constrained));
  // Pieces of O between contact curves; corefinement keeps the input vertex indices.
  auto piece = sheet.add_property_map<FaceIndex, std::size_t>("f:piece", 0).first;
  const std::size_t n_pieces =
      PMP::connected_components(sheet, piece, CGAL::parameters::edge_is_constrained_map(sheet_constrained));
  std::map<std::size_t, int> vertex_loop;
  for (size_t l = 0; l < pulled.loops.size(); ++l) {
    for (int v : pulled.loops[l].vertices) vertex_loop[static_cast<std::size_t>(v)] = static_cast<int>(l);
  }
  std::vector<std::set<int>> piece_loops(n_pieces);
  for (const auto h : sheet.halfedges()) {
    if (!sheet.is_border(h)) continue;
    const auto f = sheet.face(sheet.opposite(h));
    for (const auto v : {sheet.source(h), sheet.target(h)}) {
      const auto it = vertex_loop.find(static_cast<std::size_t>(v));
      if (it != vertex_loop.end()) piece_loops[piece[f]].insert(it->second);
    }
    if (sheet_constrained[sheet.edge(h)]) {
      cut.problem = "a contact curve runs along the boundary of the organic surface";
      return cut;
    }
  }
  // C as cycles of constrained edges: every contact vertex must have exactly two.
  std::map<VertexIndex, std::vector<HalfedgeIndex>> out_edges;
  for (const auto e : sheet.edges()) {
    if (!sheet_constrained[e]) continue;
    const auto h = sheet.halfedge(e);
    out_edges[sheet.source(h)].push_back(h);
    out_edges[sheet.target(h)].push_back(sheet.opposite(h));
  }
  for (const auto& [v, hs] : out_edges) {
    if (hs.size() != 2) {
      const Vec3 at = to_vec(sheet.point(v));
      cut.problem = "contact curves " + std::string(hs.size() == 1 ? "end" : "touch") + " at (" +
                    std::to_string(at.x()) + ", " + std::to_string(at.y()) + ", " + std::to_string(at.z()) +
                    "): the boundary is not inside S everywhere";
      return cut;
    }
  }
  std::set<EdgeIndex> visited;
  std::vector<std::vector<HalfedgeIndex>> cycles;
  for (const auto& [start, hs] : out_edges) {
    if (visited.count(sheet.edge(hs[0]))) continue;
    std::vector<HalfedgeIndex> cycle;
    for (HalfedgeIndex h = hs[0];;) {
      visited.insert(sheet.edge(h));
      cycle.push_back(h);
      const auto& next = out_edges[sheet.target(h)];
      h = sheet.edge(next[0]) == sheet.edge(h) ? next[1] : next[0];
      if (visited.count(sheet.edge(h))) break;
    }
    cycles.push_back(std::move(cycle));
  }
  // §7.3 homeomorphism: the end of O at each loop is an annulus between that loop and
  // exactly one contact curve; the other side of every curve is kept (T).
  std::vector<int> piece_cycles(n_pieces, 0);
  cut.curve_loop.assign(cycles.size(), -1);
  for (size_t c = 0; c < cycles.size(); ++c) {
    std::set<std::size_t> sides[2];
    std::vector<Vec3> points;
    for (const auto h : cycles[c]) {
      sides[0].insert(piece[sheet.face(h)]);
      sides[1].insert(piece[sheet.face(sheet.opposite(h))]);
      points.push_back(to_vec(sheet.point(sheet.source(h))));
    }
    cut.curves.push_back(std::move(points));
    if (sides[0].size() != 1 || sides[1].size() != 1 || *sides[0].begin() == *sides[1].begin()) {
      cut.problem = "a contact curve does not separate the organic surface";
      return cut;
    }
    const std::size_t a = *sides[0].begin(), b = *sides[1].begin();
    ++piece_cycles[a];
    ++piece_cycles[b];
    const std::size_t end = piece_loops[a].empty() ? b : a;
    if (piece_loops[a].empty() == piece_loops[b].empty() || piece_loops[end].size() != 1) {
      cut.problem = "a contact curve is not between one boundary loop and the kept surface";
      return cut;
    }
    cut.curve_loop[c] = *piece_loops[end].begin();
  }
  std::vector<int> faces_per_piece(n_pieces, 0);
  std::vector<std::set<VertexIndex>> piece_vertices(n_pieces);
  std::vector<std::set<EdgeIndex>> piece_edges(n_pieces);
  for (const auto f : sheet.faces()) {
    ++faces_per_piece[piece[f]];
    for (const auto h : CGAL::halfedges_around_face(sheet.halfedge(f), sheet)) {
      piece_vertices[piece[f]].insert(sheet.target(h));
      piece_edges[piece[f]].insert(sheet.edge(h));
    }
  }
  std::set<int> loops_seen;
  for (std::size_t p = 0; p < n_pieces; ++p) {
    if (piece_loops[p].empty()) continue;
    const long euler = static_cast<long>(piece_vertices[p].size()) - static_cast<long>(piece_edges[p].size()) +
                       faces_per_piece[p];
    if (piece_loops[p].size() != 1 || piece_cycles[p] != 1 || euler != 0) {
      cut.problem = "the organic surface between boundary loop " + std::to_string(*piece_loops[p].begin()) +
                    " and ∂S is not an annulus (" + std::to_string(piece_loops[p].size()) + " loops, " +
                    std::to_string(piece_cycles[p]) + " contact curves, Euler characteristic " +
                    std::to_string(euler) + ")";
      return cut;
    }
    loops_seen.insert(*piece_loops[p].begin());
  }
  if (loops_seen.size() != pulled.loops.size() || cycles.size() != pulled.loops.size()) {
    cut.problem = std::to_string(cycles.size()) + " contact curves for " +
                  std::to_string(pulled.loops.size()) + " boundary loops";
    return cut;
  }
  cut.homeomorphic = true;
  // T: the pieces no loop touches. Its border halfedges (on C) select the caps on ∂S:
  // the solid face holding the same directed edge lies under T (Q is closed and oriented
  // when the caps enter reversed).
  std::vector<std::array<ExactPoint, 3>> cell, trimmed;
  std::set<PointPair, PairLess> t_border, t_edges;
  for (const auto f : sheet.faces()) {
    if (!piece_loops[piece[f]].empty()) continue;
    trimmed.push_back(corners(sheet, f, false));
    for (const auto h : CGAL::halfedges_around_face(sheet.halfedge(f), sheet)) {
      if (!sheet_constrained[sheet.edge(h)]) continue;
      const ExactPoint &s = sheet.point(sheet.source(h)), &t = sheet.point(sheet.target(h));
      t_border.insert({s, t});
      t_edges.insert({s, t});
      t_edges.insert({t, s});
    }
  }
  std::vector<char> is_cap(solid.number_of_faces() + solid.number_of_removed_faces(), 0);
  std::vector<FaceIndex> stack;
  for (const auto h : solid.halfedges()) {
    if (solid.is_border(h) || !solid_constrained[solid.edge(h)]) continue;
    if (t_border.count({solid.point(solid.source(h)), solid.point(solid.target(h))})) stack.push_back(solid.face(h));
  }
  while (!stack.empty()) {
    const FaceIndex f = stack.back();
    stack.pop_back();
    if (is_cap[f]) continue;
    is_cap[f] = 1;
    for (const auto h : CGAL::halfedges_around_face(solid.halfedge(f), solid)) {
      if (t_edges.count({solid.point(solid.source(h)), solid.point(solid.target(h))})) continue;
      const auto g = solid.face(solid.opposite(h));
      if (g != ExactMesh::null_face() && !is_cap[g]) stack.push_back(g);
    }
  }
  cell = trimmed;
  for (const auto f : solid.faces()) {
    if (is_cap[f]) cell.push_back(corners(solid, f, true));
  }
  cut.cell.component = pulled.component;
  if (!build_closed(cell, &cut.cell.closed) || !CGAL::is_closed(cut.cell.closed) ||
      !build_closed(trimmed, &cut.cell.trimmed)) {
    cut.problem = "the trimmed organic surface and its caps on ∂S do not close";
    return cut;
  }
  // Checked once here, as the Boolean operand it becomes (a bite turned inside out).
  cut.cell.volume = signed_volume(cut.cell.closed);
  cut.cell.additive = cut.cell.volume > 0;
  if (!cut.cell.additive) PMP::reverse_face_orientations(cut.cell.closed);
  const std::string unusable = make_usable(&cut.cell.closed, true);
  if (!cut.cell.additive) PMP::reverse_face_orientations(cut.cell.closed);
  if (!unusable.empty()) {
    cut.problem = "the organic cell (trimmed surface and caps) " + unusable;
    return cut;
  }
  cut.cell.usable = true;
  cut.has_cell = true;
  return cut;
}

}  // namespace genbrep::detail

// mesh/validate.cpp — counts of everything that makes a mesh unusable as a solid boundary.
#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/union_find.h"
#include "mesh/mesh.h"

namespace genbrep {
namespace {

struct DirectedEdge {
  int lo, hi;      // sorted endpoints: the undirected key
  int triangle;
  bool forward;    // true if the triangle runs lo -> hi
};

void append(std::ostringstream& out, int count, const char* what) {
  if (count == 0) return;
  if (out.tellp() > 0) out << ", ";
  out << count << ' ' << what;
}

}  // namespace

std::string MeshValidation::problems() const {
  std::ostringstream out;
  if (vertices == 0 || triangles == 0) return "empty: no triangles";
  append(out, non_finite_vertices, "vertices with NaN or infinite coordinates");
  append(out, repeated_index_triangles, "triangles that repeat a corner");
  append(out, boundary_edges, "boundary edges (the surface is open)");
  append(out, non_manifold_edges, "non-manifold edges (three or more triangles)");
  append(out, non_manifold_vertices, "non-manifold vertices");
  append(out, inconsistent_edges, "edges with inconsistent orientation");
  return out.str();
}

MeshValidation validate(const TriangleMesh& mesh) {
  MeshValidation v;
  const auto& V = mesh.vertices;
  const auto& T = mesh.triangles;
  v.vertices = static_cast<int>(V.rows());
  v.triangles = static_cast<int>(T.rows());
  for (Eigen::Index i = 0; i < V.rows(); ++i) {
    if (!V.row(i).allFinite()) ++v.non_finite_vertices;
  }
  std::vector<DirectedEdge> edges;
  edges.reserve(3 * static_cast<size_t>(T.rows()));
  for (int t = 0; t < v.triangles; ++t) {
    const int a = T(t, 0), b = T(t, 1), c = T(t, 2);
    if (a == b || b == c || c == a) {
      ++v.repeated_index_triangles;
      continue;
    }
    const Vec3 pa = V.row(a), pb = V.row(b), pc = V.row(c);
    const Vec3 cross = (pb - pa).cross(pc - pa);
    if (cross.squaredNorm() == 0) ++v.zero_area_triangles;
    if (cross.allFinite()) v.signed_volume += pa.dot(pb.cross(pc)) / 6.0;
    for (int k = 0; k < 3; ++k) {
      const int from = T(t, k), to = T(t, (k + 1) % 3);
      edges.push_back({std::min(from, to), std::max(from, to), t, from < to});
    }
  }
  std::sort(edges.begin(), edges.end(), [](const DirectedEdge& x, const DirectedEdge& y) {
    return std::tie(x.lo, x.hi, x.triangle) < std::tie(y.lo, y.hi, y.triangle);
  });
  // Shells join triangles over any shared edge; fans join the corners of a vertex over
  // manifold edges only, so a vertex with two fans is a pinch (non-manifold vertex).
  UnionFind shells(v.triangles);
  UnionFind corners(3 * v.triangles);
  auto corner = [&](int t, int vertex) {
    for (int k = 0; k < 3; ++k) {
      if (T(t, k) == vertex) return 3 * t + k;
    }
    return -1;
  };
  for (size_t i = 0; i < edges.size();) {
    size_t j = i;
    while (j < edges.size() && edges[j].lo == edges[i].lo && edges[j].hi == edges[i].hi) ++j;
    const size_t count = j - i;
    if (count == 1) ++v.boundary_edges;
    if (count > 2) ++v.non_manifold_edges;
    for (size_t k = i + 1; k < j; ++k) shells.unite(edges[i].triangle, edges[k].triangle);
    if (count == 2) {
      const auto& e0 = edges[i];
      const auto& e1 = edges[i + 1];
      if (e0.forward == e1.forward) ++v.inconsistent_edges;
      corners.unite(corner(e0.triangle, e0.lo), corner(e1.triangle, e0.lo));
      corners.unite(corner(e0.triangle, e0.hi), corner(e1.triangle, e0.hi));
    }
    i = j;
  }
  // Count fans per vertex: distinct corner roots among the vertex's corners.
  std::vector<std::pair<int, int>> vertex_fan;  // (vertex, fan root)
  vertex_fan.reserve(3 * static_cast<size_t>(v.triangles));
  std::vector<char> used(static_cast<size_t>(v.triangles), 0);
  for (const auto& e : edges) used[e.triangle] = 1;
  int shell_count = 0;
  for (int t = 0; t < v.triangles; ++t) {
    if (!used[t]) continue;
    if (shells.find(t) == t) ++shell_count;
    for (int k = 0; k < 3; ++k) vertex_fan.emplace_back(T(t, k), corners.find(3 * t + k));
  }
  v.shells = shell_count;
  std::sort(vertex_fan.begin(), vertex_fan.end());
  vertex_fan.erase(std::unique(vertex_fan.begin(), vertex_fan.end()), vertex_fan.end());
  for (size_t i = 0; i < vertex_fan.size();) {
    size_t j = i;
    while (j < vertex_fan.size() && vertex_fan[j].first == vertex_fan[i].first) ++j;
    if (j - i > 1) ++v.non_manifold_vertices;
    i = j;
  }
  return v;
}

TriangleMesh prepare_closed_mesh(const TriangleMesh& input, const std::string& what,
                                 Diagnostics* diagnostics, MeshValidation* validation) {
  if (input.triangles.rows() == 0 || input.vertices.rows() == 0) {
    throw Error(Code::InvalidInput, what + " is empty: it has no triangles", "mesh");
  }
  const int max_index = static_cast<int>(input.vertices.rows()) - 1;
  if (input.triangles.minCoeff() < 0 || input.triangles.maxCoeff() > max_index) {
    throw Error(Code::InvalidInput,
                what + " has triangle corners outside its " +
                    std::to_string(input.vertices.rows()) + " vertices",
                "mesh");
  }
  for (Eigen::Index i = 0; i < input.vertices.rows(); ++i) {
    if (!input.vertices.row(i).allFinite()) {
      int bad = 0;
      for (Eigen::Index j = 0; j < input.vertices.rows(); ++j) bad += !input.vertices.row(j).allFinite();
      throw Error(Code::InvalidInput,
                  what + " has " + std::to_string(bad) +
                      " vertices with NaN or infinite coordinates (first: vertex " +
                      std::to_string(i) + ")",
                  "mesh");
    }
  }
  TriangleMesh mesh = weld(input);
  // Triangles that welding collapsed onto a repeated corner carry no area: drop them.
  std::vector<int> keep;
  for (Eigen::Index t = 0; t < mesh.triangles.rows(); ++t) {
    const auto r = mesh.triangles.row(t);
    if (r(0) != r(1) && r(1) != r(2) && r(2) != r(0)) keep.push_back(static_cast<int>(t));
  }
  if (keep.size() != static_cast<size_t>(mesh.triangles.rows())) {
    const size_t dropped = mesh.triangles.rows() - keep.size();
    if (diagnostics) {
      diagnostics->push_back(what + ": dropped " + std::to_string(dropped) +
                             " triangles that repeat a corner after welding");
    }
    Triangles kept(static_cast<Eigen::Index>(keep.size()), 3);
    std::vector<int> source(keep.size());
    for (size_t i = 0; i < keep.size(); ++i) {
      kept.row(i) = mesh.triangles.row(keep[i]);
      source[i] = mesh.triangle_source[keep[i]];
    }
    mesh.triangles = std::move(kept);
    mesh.triangle_source = std::move(source);
    mesh = weld(mesh);  // drop vertices that only the removed triangles used
  }
  const MeshValidation check = validate(mesh);
  if (check.triangles == 0) {
    throw Error(Code::InvalidInput, what + " is empty: every triangle is degenerate", "mesh");
  }
  if (!check.closed_manifold()) {
    const bool only_open = check.non_manifold_edges == 0 && check.non_manifold_vertices == 0 &&
                           check.inconsistent_edges == 0;
    throw Error(Code::InvalidInput,
                what + (only_open ? " is open: " : " is not a closed 2-manifold surface: ") +
                    check.problems(),
                "mesh");
  }
  if (check.zero_area_triangles > 0 && diagnostics) {
    diagnostics->push_back(what + ": " + std::to_string(check.zero_area_triangles) +
                           " zero-area triangles kept");
  }
  if (validation) *validation = check;
  if (check.signed_volume < 0) {
    // Every shell is consistently oriented but the whole encloses negative volume:
    // the file is inside out. Turning it is the only reading that makes it a solid.
    for (Eigen::Index t = 0; t < mesh.triangles.rows(); ++t) std::swap(mesh.triangles(t, 1), mesh.triangles(t, 2));
    if (diagnostics) diagnostics->push_back(what + " was inside out; its triangles were flipped");
    if (validation) validation->signed_volume = -check.signed_volume;  // the flip's only effect
  }
  return mesh;
}

}  // namespace genbrep

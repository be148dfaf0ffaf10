// mesh/validate.cpp — counts of everything that makes a mesh unusable as a solid boundary.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
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

// "4 boundary edges (the surface is open; the first at (0, 1, 2))": `what` takes the
// plural; `why`, if any, goes in the parentheses before the position.
void append(std::ostringstream& out, int count, const char* one, const char* many, const char* why,
            const Vec3* at = nullptr) {
  if (count == 0) return;
  if (out.tellp() > 0) out << ", ";
  out << count << ' ' << (count == 1 ? one : many);
  if (*why == 0 && at == nullptr) return;
  out << " (" << why;
  if (at) out << (*why ? "; " : "") << (count == 1 ? "at " : "the first at ") << position(*at);
  out << ')';
}

// The sorted corners of triangle t: the key under which duplicates meet.
std::array<int, 3> corner_set(const Triangles& T, int t) {
  std::array<int, 3> c{T(t, 0), T(t, 1), T(t, 2)};
  std::sort(c.begin(), c.end());
  return c;
}

void count_duplicates(const Triangles& T, MeshValidation* v) {
  std::vector<std::pair<std::array<int, 3>, int>> keys;
  keys.reserve(static_cast<size_t>(T.rows()));
  for (int t = 0; t < T.rows(); ++t) keys.emplace_back(corner_set(T, t), t);
  std::sort(keys.begin(), keys.end());
  for (size_t i = 1; i < keys.size(); ++i) {
    if (keys[i].first != keys[i - 1].first) continue;
    if (v->duplicate_triangles++ == 0) {
      v->duplicate_of[0] = keys[i].second;
      v->duplicate_of[1] = keys[i - 1].second;
    }
  }
}

}  // namespace

std::string position(const Vec3& p) {
  char text[96];
  std::snprintf(text, sizeof text, "(%.6g, %.6g, %.6g)", p.x(), p.y(), p.z());
  return text;
}

std::string MeshValidation::problems() const {
  std::ostringstream out;
  if (vertices == 0 || triangles == 0) return "empty: no triangles";
  append(out, non_finite_vertices, "vertex with NaN or infinite coordinates",
         "vertices with NaN or infinite coordinates", "");
  append(out, repeated_index_triangles, "triangle that repeats a corner",
         "triangles that repeat a corner", "");
  append(out, boundary_edges, "boundary edge", "boundary edges", "the surface is open",
         &boundary_edge_at);
  append(out, non_manifold_edges, "non-manifold edge", "non-manifold edges",
         "three or more triangles", &non_manifold_edge_at);
  append(out, non_manifold_vertices, "non-manifold vertex", "non-manifold vertices", "",
         &non_manifold_vertex_at);
  append(out, inconsistent_edges, "edge with inconsistent orientation",
         "edges with inconsistent orientation", "", &inconsistent_edge_at);
  return out.str();
}

MeshValidation validate(const TriangleMesh& mesh) {
  MeshValidation v;
  const auto& V = mesh.vertices;
  const auto& T = mesh.triangles;
  v.vertices = static_cast<int>(V.rows());
  v.triangles = static_cast<int>(T.rows());
  // The volume is summed about the centre of the bounding box, not the origin: a small part
  // far from the origin (coordinates 1e3, size 1e-2) would otherwise lose its volume, and
  // with it its orientation, to cancellation between terms a billion times larger.
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (Eigen::Index i = 0; i < V.rows(); ++i) {
    if (!V.row(i).allFinite()) {
      ++v.non_finite_vertices;
      continue;
    }
    lo = lo.cwiseMin(V.row(i).transpose());
    hi = hi.cwiseMax(V.row(i).transpose());
  }
  const Vec3 centre = lo.allFinite() && hi.allFinite() ? Vec3(0.5 * (lo + hi)) : Vec3::Zero();
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
    if (cross.allFinite()) v.signed_volume += (pa - centre).dot((pb - centre).cross(pc - centre)) / 6.0;
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
    const Vec3 midpoint = 0.5 * (V.row(edges[i].lo) + V.row(edges[i].hi)).transpose();
    if (count == 1 && v.boundary_edges++ == 0) v.boundary_edge_at = midpoint;
    if (count > 2 && v.non_manifold_edges++ == 0) v.non_manifold_edge_at = midpoint;
    for (size_t k = i + 1; k < j; ++k) shells.unite(edges[i].triangle, edges[k].triangle);
    if (count == 2) {
      const auto& e0 = edges[i];
      const auto& e1 = edges[i + 1];
      if (e0.forward == e1.forward && v.inconsistent_edges++ == 0) v.inconsistent_edge_at = midpoint;
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
    if (j - i > 1 && v.non_manifold_vertices++ == 0)
      v.non_manifold_vertex_at = V.row(vertex_fan[i].first).transpose();
    i = j;
  }
  count_duplicates(T, &v);
  return v;
}

namespace {

// Index range, NaN or infinite coordinates, coordinates beyond kMaxCoordinate.
void check_arrays(const TriangleMesh& input, const std::string& what) {
  if (input.triangles.rows() == 0 || input.vertices.rows() == 0) {
    throw Error(Code::InvalidInput, what + " is empty: it has no triangles", "mesh");
  }
  const Eigen::Index n = input.vertices.rows();
  for (Eigen::Index t = 0; t < input.triangles.rows(); ++t)
    for (int k = 0; k < 3; ++k)
      if (input.triangles(t, k) < 0 || input.triangles(t, k) >= n) {
        throw Error(Code::InvalidInput,
                    what + " has triangle corners outside its " + std::to_string(n) +
                        " vertices (triangle " + std::to_string(t) + " uses vertex " +
                        std::to_string(input.triangles(t, k)) + ")",
                    "mesh");
      }
  int bad = 0, huge = 0;
  Eigen::Index first_bad = -1, first_huge = -1;
  for (Eigen::Index i = 0; i < n; ++i) {
    const auto row = input.vertices.row(i);
    if (!row.allFinite()) {
      if (bad++ == 0) first_bad = i;
    } else if (row.cwiseAbs().maxCoeff() > kMaxCoordinate && huge++ == 0) {
      first_huge = i;
    }
  }
  if (bad > 0) {
    throw Error(Code::InvalidInput,
                what + " has " + std::to_string(bad) + (bad == 1 ? " vertex" : " vertices") +
                    " with NaN or infinite coordinates (first: vertex " + std::to_string(first_bad) + ")",
                "mesh");
  }
  if (huge > 0) {
    char limit[32];
    std::snprintf(limit, sizeof limit, "%g", kMaxCoordinate);
    throw Error(Code::InvalidInput,
                what + " has " + std::to_string(huge) + (huge == 1 ? " vertex" : " vertices") +
                    " with coordinates beyond ±" + limit + " (first: vertex " + std::to_string(first_huge) +
                    " at " + position(input.vertices.row(first_huge)) + "): scale it to smaller units",
                "mesh");
  }
}

// Welds and drops the triangles that welding left with a repeated corner.
TriangleMesh weld_and_drop_repeated(const TriangleMesh& input, const std::string& what,
                                    Diagnostics* diagnostics) {
  TriangleMesh mesh = weld(input);
  std::vector<int> keep;
  for (Eigen::Index t = 0; t < mesh.triangles.rows(); ++t) {
    const auto r = mesh.triangles.row(t);
    if (r(0) != r(1) && r(1) != r(2) && r(2) != r(0)) keep.push_back(static_cast<int>(t));
  }
  if (keep.size() == static_cast<size_t>(mesh.triangles.rows())) return mesh;
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
  return weld(mesh);  // drop vertices that only the removed triangles used
}

// Everything validate() counts that makes the welded mesh no solid boundary.
void check_surface(const TriangleMesh& mesh, const MeshValidation& check, const std::string& what) {
  if (check.triangles == 0) {
    throw Error(Code::InvalidInput, what + " is empty: every triangle is degenerate", "mesh");
  }
  if (check.zero_area_triangles == check.triangles) {
    throw Error(Code::InvalidInput,
                what + " is degenerate: all its " + std::to_string(check.triangles) +
                    " triangles have zero area (its vertices lie on one line)",
                "mesh");
  }
  if (check.duplicate_triangles > 0) {
    const int a = mesh.triangle_source[check.duplicate_of[0]];
    const int b = mesh.triangle_source[check.duplicate_of[1]];
    throw Error(Code::InvalidInput,
                what + " has " + std::to_string(check.duplicate_triangles) + " duplicate " +
                    (check.duplicate_triangles == 1 ? "triangle" : "triangles") + " (face " +
                    std::to_string(std::max(a, b)) + " has the corners of face " +
                    std::to_string(std::min(a, b)) + ", counted from 0)",
                "mesh");
  }
  if (!check.closed_manifold()) {
    const bool only_open = check.non_manifold_edges == 0 && check.non_manifold_vertices == 0 &&
                           check.inconsistent_edges == 0;
    throw Error(Code::InvalidInput,
                what + (only_open ? " is open: " : " is not a closed 2-manifold surface: ") +
                    check.problems(),
                "mesh");
  }
  const Vec3 extent = mesh.vertices.colwise().maxCoeff() - mesh.vertices.colwise().minCoeff();
  if (std::abs(check.signed_volume) <= 1e-12 * extent.norm() * extent.squaredNorm()) {
    throw Error(Code::InvalidInput,
                what + " encloses no volume: it is flat (its bounding box is " +
                    position(extent).substr(1, position(extent).size() - 2) + " across)",
                "mesh");
  }
}

// Triangles that cross: one shell through itself, or two shells through each other.
void check_intersections(const TriangleMesh& mesh, const MeshValidation& check, const std::string& what) {
  const SelfIntersections crossing = self_intersections(mesh);
  if (crossing.pairs == 0) return;
  const int a = crossing.first[0], b = crossing.first[1];
  const Vec3 near = (mesh.vertices.row(mesh.triangles(a, 0)) + mesh.vertices.row(mesh.triangles(a, 1)) +
                     mesh.vertices.row(mesh.triangles(a, 2))) / 3.0;
  const std::string pairs = std::to_string(crossing.pairs) +
                            (crossing.pairs == 1 ? " pair of triangles crosses" : " pairs of triangles cross") +
                            " (the first: faces " + std::to_string(mesh.triangle_source[a]) + " and " +
                            std::to_string(mesh.triangle_source[b]) + ", near " + position(near) + ")";
  const bool shells = check.shells > 1 && !crossing.first_in_one_shell;
  throw Error(Code::InvalidInput,
              what + (shells ? " has " + std::to_string(check.shells) + " shells that overlap: "
                             : std::string(" intersects itself: ")) + pairs,
              "mesh");
}

}  // namespace

TriangleMesh prepare_closed_mesh(const TriangleMesh& input, const std::string& what,
                                 Diagnostics* diagnostics, MeshValidation* validation,
                                 const Context* context) {
  auto step = [context](double fraction) {
    if (context) context->step("mesh", fraction);
  };
  check_arrays(input, what);
  TriangleMesh mesh = weld_and_drop_repeated(input, what, diagnostics);
  step(0.1);
  const MeshValidation check = validate(mesh);
  check_surface(mesh, check, what);
  step(0.2);
  check_intersections(mesh, check, what);
  step(0.45);
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

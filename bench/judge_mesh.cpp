// bench/judge_mesh.cpp — reading, combinatorial checks and CGAL queries for corpus_judge.
#include "judge_mesh.h"

#include <CGAL/IO/OBJ.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/orientation.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>

#include <algorithm>
#include <boost/iterator/function_output_iterator.hpp>
#include <cmath>
#include <functional>
#include <numeric>
#include <stdexcept>

namespace PMP = CGAL::Polygon_mesh_processing;

namespace judge {

namespace {

using Polygons = std::vector<std::vector<std::size_t>>;

// Union-find with path halving; the smaller index becomes the root, so roots do not
// depend on the order of the unions.
struct UnionFind {
  std::vector<int> parent;
  explicit UnionFind(int n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  int find(int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void unite(int a, int b) {
    a = find(a), b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
};

// One triangle's edge, keyed by its sorted end vertices; `forward` when the triangle runs
// it from `lo` to `hi`. Corners are 3 * triangle + k.
struct EdgeUse {
  int lo, hi, triangle;
  bool forward;
  int corner_lo, corner_hi;
};

std::vector<EdgeUse> edge_uses(const Soup& soup) {
  std::vector<EdgeUse> uses;
  uses.reserve(soup.triangles.size() * 3);
  for (int t = 0; t < static_cast<int>(soup.triangles.size()); ++t) {
    const Triangle& tri = soup.triangles[t];
    for (int k = 0; k < 3; ++k) {
      const int a = tri[k], b = tri[(k + 1) % 3];
      const int ca = 3 * t + k, cb = 3 * t + (k + 1) % 3;
      if (a < b)
        uses.push_back({a, b, t, true, ca, cb});
      else
        uses.push_back({b, a, t, false, cb, ca});
    }
  }
  std::sort(uses.begin(), uses.end(), [](const EdgeUse& x, const EdgeUse& y) {
    return std::tie(x.lo, x.hi, x.triangle, x.corner_lo) <
           std::tie(y.lo, y.hi, y.triangle, y.corner_lo);
  });
  return uses;
}

Polygons to_polygons(const Soup& soup) {
  Polygons polygons;
  polygons.reserve(soup.triangles.size());
  for (const Triangle& t : soup.triangles)
    polygons.push_back({std::size_t(t[0]), std::size_t(t[1]), std::size_t(t[2])});
  return polygons;
}

// Thrown by the counting output iterator once `cap` pairs are counted.
struct CapReached {};

}  // namespace

Soup read_soup(const std::string& path) {
  Soup soup;
  Polygons polygons;
  if (!CGAL::IO::read_OBJ(path, soup.points, polygons))
    throw std::runtime_error("cannot read '" + path + "' as OBJ");
  if (polygons.empty()) throw std::runtime_error("'" + path + "' has no face");
  for (const Point& p : soup.points) {
    if (!std::isfinite(p.x()) || !std::isfinite(p.y()) || !std::isfinite(p.z()))
      throw std::runtime_error("'" + path + "' has a vertex with a non-finite coordinate");
  }
  const std::size_t n = soup.points.size();
  soup.polygons = static_cast<int>(polygons.size());
  for (const auto& polygon : polygons) {
    if (polygon.size() < 3)
      throw std::runtime_error("'" + path + "' has a face of fewer than 3 corners");
    for (std::size_t index : polygon) {
      if (index >= n) throw std::runtime_error("'" + path + "' has a face index out of range");
    }
    for (std::size_t k = 1; k + 1 < polygon.size(); ++k) {
      const Triangle t{int(polygon[0]), int(polygon[k]), int(polygon[k + 1])};
      if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2])
        ++soup.repeated_index_triangles;
      else
        soup.triangles.push_back(t);
    }
  }
  return soup;
}

Topology topology(const Soup& soup) {
  Topology top;
  const int triangles = static_cast<int>(soup.triangles.size());
  top.triangles = triangles;
  const std::vector<EdgeUse> uses = edge_uses(soup);
  UnionFind fans(3 * triangles), shells(triangles);
  for (std::size_t i = 0; i < uses.size();) {
    std::size_t j = i;
    while (j < uses.size() && uses[j].lo == uses[i].lo && uses[j].hi == uses[i].hi) ++j;
    const std::size_t count = j - i;
    if (count == 1) ++top.boundary_edges;
    if (count > 2) ++top.non_manifold_edges;
    if (count == 2 && uses[i].forward == uses[i + 1].forward) ++top.inconsistent_edges;
    for (std::size_t k = i + 1; k < j; ++k) {
      fans.unite(uses[i].corner_lo, uses[k].corner_lo);
      fans.unite(uses[i].corner_hi, uses[k].corner_hi);
      shells.unite(uses[i].triangle, uses[k].triangle);
    }
    i = j;
  }
  // A vertex is 2-manifold when all its corners lie in one fan.
  std::vector<int> fan_of(soup.points.size(), -1);
  std::vector<char> several(soup.points.size(), 0);
  for (int c = 0; c < 3 * triangles; ++c) {
    const int v = soup.triangles[c / 3][c % 3];
    const int root = fans.find(c);
    if (fan_of[v] < 0)
      fan_of[v] = root;
    else if (fan_of[v] != root)
      several[v] = 1;
  }
  std::vector<int> used;
  for (int v = 0; v < static_cast<int>(soup.points.size()); ++v) {
    if (fan_of[v] >= 0) used.push_back(v);
    top.non_manifold_vertices += several[v];
  }
  top.vertices = static_cast<int>(used.size());
  std::sort(used.begin(), used.end(), [&](int a, int b) {
    return std::make_pair(soup.points[a], a) < std::make_pair(soup.points[b], b);
  });
  for (std::size_t k = 1; k < used.size(); ++k)
    top.coincident_vertices += soup.points[used[k]] == soup.points[used[k - 1]];
  for (int t = 0; t < triangles; ++t) top.shells += shells.find(t) == t;
  return top;
}

double signed_volume(const Soup& soup) {
  if (soup.points.empty()) return 0;
  const Point& o = soup.points[soup.triangles.empty() ? 0 : soup.triangles[0][0]];
  double six_volume = 0;
  for (const Triangle& t : soup.triangles) {
    const K::Vector_3 a = soup.points[t[0]] - o, b = soup.points[t[1]] - o,
                      c = soup.points[t[2]] - o;
    six_volume += a * CGAL::cross_product(b, c);
  }
  return six_volume / 6;
}

Mesh to_mesh(Soup soup) {
  Polygons polygons = to_polygons(soup);
  if (!PMP::is_polygon_soup_a_polygon_mesh(polygons)) {
    PMP::orient_polygon_soup(soup.points, polygons);
    if (!PMP::is_polygon_soup_a_polygon_mesh(polygons))
      throw std::runtime_error(
          "the triangles form no polygon mesh even once split at non-manifold vertices");
  }
  Mesh mesh;
  PMP::polygon_soup_to_polygon_mesh(soup.points, polygons, mesh);
  return mesh;
}

SelfIntersections self_intersections(const Soup& soup, long cap) {
  SelfIntersections result;
  Mesh mesh;
  try {
    mesh = to_mesh(soup);
  } catch (const std::exception& e) {
    result.note = e.what();
    return result;
  }
  bool first = true;
  auto count = [&](const std::pair<Mesh::Face_index, Mesh::Face_index>& pair) {
    if (pair.first == pair.second) {
      ++result.degenerate_faces;
      return;
    }
    if (first) {
      const Point& p = mesh.point(mesh.target(mesh.halfedge(pair.first)));
      result.first_at = {p.x(), p.y(), p.z()};
      first = false;
    }
    if (++result.pairs >= cap) throw CapReached{};
  };
  try {
    PMP::self_intersections<CGAL::Sequential_tag>(faces(mesh), mesh,
                                                  boost::make_function_output_iterator(count));
  } catch (const CapReached&) {
    result.capped = true;
  }
  result.checked = true;
  return result;
}

Orientation orientation(const Soup& soup) {
  Orientation result;
  Mesh mesh = to_mesh(soup);
  auto volume_id = mesh.add_property_map<Mesh::Face_index, std::size_t>("f:volume", 0).first;
  std::vector<std::size_t> nesting;
  std::vector<bool> outward;
  result.volumes = static_cast<int>(
      PMP::volume_connected_components(mesh, volume_id,
                                       CGAL::parameters::nesting_levels(std::ref(nesting))
                                           .is_cc_outward_oriented(std::ref(outward))));
  for (std::size_t cc = 0; cc < outward.size() && cc < nesting.size(); ++cc) {
    // An outer shell faces outward, a cavity's shell inward.
    result.shells_facing_wrong_way += outward[cc] != (nesting[cc] % 2 == 0);
  }
  result.checked = true;
  result.outward = result.shells_facing_wrong_way == 0;
  return result;
}

Solid::Solid(const Soup& soup) : mesh_(to_mesh(soup)) {
  tree_.rebuild(faces(mesh_).first, faces(mesh_).second, mesh_);
  tree_.accelerate_distance_queries();
  side_ = std::make_unique<Side>(tree_);
}

double Solid::distance(const Point& p) const { return std::sqrt(tree_.squared_distance(p)); }

}  // namespace judge

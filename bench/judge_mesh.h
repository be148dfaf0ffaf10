// bench/judge_mesh.h — meshes as corpus_judge sees them: an OBJ file read as a triangle
// soup, the soup's combinatorial checks (border, non-manifold and inconsistently oriented
// edges, non-manifold vertices), self-intersections, orientation, volume, and for closed
// 2-manifold soups a CGAL Surface_mesh with an AABB tree for distances and an inside test.
// Uses CGAL only, never genbrep's own mesh code: the judge must not share the code it
// judges. Predicates are exact (Epick); distances and volumes are floating point.
#pragma once
#include <CGAL/AABB_face_graph_triangle_primitive.h>
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Side_of_triangle_mesh.h>
#include <CGAL/Surface_mesh.h>

#include <array>
#include <memory>
#include <string>
#include <vector>

namespace judge {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = K::Point_3;
using Mesh = CGAL::Surface_mesh<Point>;
using Primitive = CGAL::AABB_face_graph_triangle_primitive<Mesh>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<K, Primitive>>;
using Side = CGAL::Side_of_triangle_mesh<Mesh, K, CGAL::Default, Tree>;
using Triangle = std::array<int, 3>;

// An OBJ file as CGAL's reader gives it, polygons split into fans of triangles.
// Triangles that repeat a corner index are kept apart: they have no area and no
// orientation, and a mesh builder would refuse them.
struct Soup {
  std::vector<Point> points;
  std::vector<Triangle> triangles;
  int polygons = 0;
  int repeated_index_triangles = 0;
};

// Reads `path`; throws std::runtime_error naming the file when it cannot be read, has no
// face, or has a face index out of range.
Soup read_soup(const std::string& path);

// Counts on the soup's own vertex indices, as any program that opens the file sees them.
struct Topology {
  int vertices = 0;  // referenced by a triangle
  int triangles = 0;
  int boundary_edges = 0;         // edges of one triangle
  int non_manifold_edges = 0;     // edges of three or more triangles
  int non_manifold_vertices = 0;  // vertices whose triangles form several edge-connected fans
  int inconsistent_edges = 0;     // edges of two triangles that run them the same way
  int coincident_vertices = 0;    // distinct indices at a position an earlier index has
  int shells = 0;                 // edge-connected components of triangles
  bool closed() const { return triangles > 0 && boundary_edges == 0; }
  bool manifold() const { return non_manifold_edges == 0 && non_manifold_vertices == 0; }
  bool consistent() const { return inconsistent_edges == 0; }
};
Topology topology(const Soup& soup);

// Signed volume enclosed by the triangles (divergence theorem); meaningful when closed,
// positive when the triangles face outward.
double signed_volume(const Soup& soup);

// Pairs of triangles that intersect other than along a shared edge or corner
// (PMP::self_intersections), counted up to `cap` pairs. Non-manifold soups are first split
// at their non-manifold vertices and edges (PMP::orient_polygon_soup); triangles meeting at
// such a split vertex then count as a pair too.
struct SelfIntersections {
  bool checked = false;
  long pairs = 0;                           // between two distinct triangles
  long degenerate_faces = 0;                // zero-area triangles CGAL reports on their own
  bool capped = false;                      // counting stopped at `cap`
  std::array<double, 3> first_at{0, 0, 0};  // a corner of the first pair's first triangle
  std::string note;                         // why not checked
};
SelfIntersections self_intersections(const Soup& soup, long cap);

// Orientation of a closed, 2-manifold, consistently oriented soup free of
// self-intersections: PMP::volume_connected_components tells, per shell, whether it faces
// outward and how many shells enclose it; a shell enclosed an odd number of times bounds a
// cavity and must face inward.
struct Orientation {
  bool checked = false;
  bool outward = false;
  int volumes = 0;
  int shells_facing_wrong_way = 0;
};
Orientation orientation(const Soup& soup);

// A closed 2-manifold soup as a mesh with its AABB tree: distances to its surface and
// inside tests (exact predicates; a point on the surface is ON_BOUNDARY). Not movable:
// the tree and the inside test point into the mesh.
class Solid {
 public:
  explicit Solid(const Soup& soup);  // throws std::runtime_error for a soup no mesh takes
  Solid(const Solid&) = delete;
  Solid& operator=(const Solid&) = delete;
  CGAL::Bounded_side side(const Point& p) const { return (*side_)(p); }
  double distance(const Point& p) const;
  const Mesh& mesh() const { return mesh_; }

 private:
  Mesh mesh_;
  Tree tree_;
  std::unique_ptr<Side> side_;
};

// A Surface_mesh of a soup that is_polygon_soup_a_polygon_mesh accepts as it is, or once
// PMP::orient_polygon_soup has split it; throws std::runtime_error when neither.
Mesh to_mesh(Soup soup);

}  // namespace judge

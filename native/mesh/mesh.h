// mesh/mesh.h — load, triangulate, weld and validate input meshes (paper §3.1).
// Takes: files (OBJ, PLY, STL, OFF through OpenMesh IO) or arrays. Gives: TriangleMesh
// arrays with provenance (`triangle_source`), a MeshValidation with counts, and the
// halfedge TriMesh for stages that need adjacency.
// Guarantees: prepare_design/prepare_solid either return a closed, 2-manifold,
// consistently and outward-oriented triangle mesh with finite coordinates, or throw
// Error{InvalidInput} naming the object and the problem with counts.
// Complexity: O(n log n) in the number of triangles (sorting edges and vertices).
#pragma once
#include <array>
#include <string>

#include "core/context.h"
#include "core/error.h"
#include "core/types.h"

namespace genbrep {

// Coordinates beyond ±kMaxCoordinate are refused: squared lengths and the exact
// predicates' filters overflow or lose every digit of a small feature long before
// 1e300, and OpenMesh's float readers drop such vertices without a word.
constexpr double kMaxCoordinate = 1e12;

// Reads a polygon soup with OpenMesh's readers, keeping non-manifold faces as they are
// in the file (OpenMesh's own mesh would drop or split them). The file is read once
// before (detail/file_check.h): Error{FileError} when it cannot be opened,
// Error{InvalidInput} naming the line, vertex or face for contents it cannot take.
PolygonSoup read_polygon_file(const std::string& path);

// Splits polygons into triangles; quads along their shorter diagonal, larger polygons as
// a fan from their first corner. triangle_source holds the input polygon index.
// Faces with fewer than 3 corners or out-of-range indices throw Error{InvalidInput}.
TriangleMesh triangulate(const PolygonSoup& soup, const std::string& name);

// Merges vertices whose coordinates are exactly equal (STL and "split normals" exports
// duplicate them), keeps first-occurrence order, drops unreferenced vertices.
TriangleMesh weld(const TriangleMesh& mesh);

struct MeshValidation {
  int vertices = 0;
  int triangles = 0;
  int non_finite_vertices = 0;    // NaN or infinite coordinates
  int repeated_index_triangles = 0;  // a corner used twice: no area at all
  int zero_area_triangles = 0;    // distinct corners, collinear
  int boundary_edges = 0;         // edges with one triangle: the surface is open
  int non_manifold_edges = 0;     // edges with three or more triangles
  int non_manifold_vertices = 0;  // vertices whose triangles form several fans
  int inconsistent_edges = 0;     // manifold edges whose two triangles disagree on orientation
  int duplicate_triangles = 0;    // the corners of an earlier triangle, in any order
  int shells = 0;                 // edge-connected components
  double signed_volume = 0;       // > 0 for an outward-oriented closed surface
  // Where the first of each problem is (an edge's midpoint, a vertex), for messages.
  Vec3 boundary_edge_at = Vec3::Zero();
  Vec3 non_manifold_edge_at = Vec3::Zero();
  Vec3 non_manifold_vertex_at = Vec3::Zero();
  Vec3 inconsistent_edge_at = Vec3::Zero();
  int duplicate_of[2] = {-1, -1};  // the first duplicate triangle and the one it repeats

  bool closed_manifold() const {
    return vertices > 0 && triangles > 0 && non_finite_vertices == 0 &&
           repeated_index_triangles == 0 && boundary_edges == 0 && non_manifold_edges == 0 &&
           non_manifold_vertices == 0 && inconsistent_edges == 0;
  }
  // "12 boundary edges (the surface is open; the first at (0, 1, 2)), 2 non-manifold
  // vertices (the first at ...)" — only the problems, for messages.
  std::string problems() const;
};

MeshValidation validate(const TriangleMesh& mesh);

// "(0.5, 1, -2)": a point as messages print it (6 significant digits).
std::string position(const Vec3& p);

// The checks every input passes before incidence: weld, validate, flip an inside-out
// surface (reported in `diagnostics`), and throw Error{InvalidInput} for anything else:
// no triangles, an index out of range, NaN, infinite or huge (kMaxCoordinate)
// coordinates, every triangle degenerate, duplicate triangles, open or not 2-manifold,
// inconsistently oriented, no volume, or triangles that cross each other.
// `what` names the object in messages, e.g. "keep-in 'boss'". `validation`, if given,
// receives the counts of the returned mesh (so callers need not validate it again).
// `context`, if given, hears ("mesh", 0.1 / 0.2 / 0.45) after welding, validating and the
// intersection test (the design's share of the mesh stage), and may cancel there.
TriangleMesh prepare_closed_mesh(const TriangleMesh& mesh, const std::string& what,
                                 Diagnostics* diagnostics, MeshValidation* validation = nullptr,
                                 const Context* context = nullptr);

// Pairs of triangles of a closed 2-manifold mesh that intersect other than along the
// edges and corners they share (exact predicates, CGAL); zero-area triangles take part in
// no pair, nor do two triangles that both have a corner on one. `pairs` is the count, `first` the pair with the smallest indices and
// `first_in_one_shell` whether its triangles are edge-connected (else two shells overlap).
struct SelfIntersections {
  int pairs = 0;
  std::array<int, 2> first{-1, -1};
  bool first_in_one_shell = true;
};
SelfIntersections self_intersections(const TriangleMesh& mesh);

// Halfedge mesh of a prepared (closed, manifold, oriented) mesh; vertex and face indices
// are the array indices. Throws Error{Internal} if OpenMesh rejects a face.
TriMesh to_trimesh(const TriangleMesh& mesh);

// Bounding-box diagonal, used to derive default lengths.
double bounding_box_diagonal(const Vertices& vertices);

}  // namespace genbrep

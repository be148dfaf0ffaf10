// mesh/mesh.h — load, triangulate, weld and validate input meshes (paper §3.1).
// Takes: files (OBJ, PLY, STL, OFF through OpenMesh IO) or arrays. Gives: TriangleMesh
// arrays with provenance (`triangle_source`), a MeshValidation with counts, and the
// halfedge TriMesh for stages that need adjacency.
// Guarantees: prepare_design/prepare_solid either return a closed, 2-manifold,
// consistently and outward-oriented triangle mesh with finite coordinates, or throw
// Error{InvalidInput} naming the object and the problem with counts.
// Complexity: O(n log n) in the number of triangles (sorting edges and vertices).
#pragma once
#include <string>

#include "core/error.h"
#include "core/types.h"

namespace genbrep {

// Reads a polygon soup with OpenMesh's readers, keeping non-manifold faces as they are
// in the file (OpenMesh's own mesh would drop or split them). Throws Error{FileError}.
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
  int shells = 0;                 // edge-connected components
  double signed_volume = 0;       // > 0 for an outward-oriented closed surface

  bool closed_manifold() const {
    return vertices > 0 && triangles > 0 && non_finite_vertices == 0 &&
           repeated_index_triangles == 0 && boundary_edges == 0 && non_manifold_edges == 0 &&
           non_manifold_vertices == 0 && inconsistent_edges == 0;
  }
  // "12 boundary edges, 2 non-manifold vertices" — only the problems, for messages.
  std::string problems() const;
};

MeshValidation validate(const TriangleMesh& mesh);

// The checks every input passes before incidence: weld, validate, flip an inside-out
// surface (reported in `diagnostics`), and throw Error{InvalidInput} for anything else.
// `what` names the object in messages, e.g. "keep-in 'boss'". `validation`, if given,
// receives the counts of the returned mesh (so callers need not validate it again).
TriangleMesh prepare_closed_mesh(const TriangleMesh& mesh, const std::string& what,
                                 Diagnostics* diagnostics, MeshValidation* validation = nullptr);

// Halfedge mesh of a prepared (closed, manifold, oriented) mesh; vertex and face indices
// are the array indices. Throws Error{Internal} if OpenMesh rejects a face.
TriMesh to_trimesh(const TriangleMesh& mesh);

// Bounding-box diagonal, used to derive default lengths.
double bounding_box_diagonal(const Vertices& vertices);

}  // namespace genbrep

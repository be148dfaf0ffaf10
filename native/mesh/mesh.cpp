// mesh/mesh.cpp — triangulation, welding and conversion to the halfedge mesh.
#include <algorithm>
#include <numeric>

#include "mesh/mesh.h"

namespace genbrep {

TriangleMesh triangulate(const PolygonSoup& soup, const std::string& name) {
  const int n_vertices = static_cast<int>(soup.vertices.rows());
  std::vector<std::array<int, 3>> triangles;
  std::vector<int> source;
  triangles.reserve(soup.indices.size());
  for (int f = 0; f < soup.face_count(); ++f) {
    const int begin = soup.offsets[f], end = soup.offsets[f + 1];
    const int corners = end - begin;
    GENBREP_CHECK(corners >= 3, Code::InvalidInput,
                  name + ": face " + std::to_string(f) + " has " + std::to_string(corners) +
                      " corners; a face needs at least 3");
    for (int i = begin; i < end; ++i) {
      GENBREP_CHECK(soup.indices[i] >= 0 && soup.indices[i] < n_vertices, Code::InvalidInput,
                    name + ": face " + std::to_string(f) + " refers to vertex " +
                        std::to_string(soup.indices[i]) + " of " + std::to_string(n_vertices));
    }
    const int* c = &soup.indices[begin];
    if (corners == 4) {
      // The shorter diagonal gives the better-shaped pair of triangles.
      const double d02 = (soup.vertices.row(c[0]) - soup.vertices.row(c[2])).squaredNorm();
      const double d13 = (soup.vertices.row(c[1]) - soup.vertices.row(c[3])).squaredNorm();
      if (d02 <= d13) {
        triangles.push_back({c[0], c[1], c[2]});
        triangles.push_back({c[0], c[2], c[3]});
      } else {
        triangles.push_back({c[0], c[1], c[3]});
        triangles.push_back({c[1], c[2], c[3]});
      }
      source.insert(source.end(), 2, f);
      continue;
    }
    for (int k = 1; k + 1 < corners; ++k) {
      triangles.push_back({c[0], c[k], c[k + 1]});
      source.push_back(f);
    }
  }
  TriangleMesh mesh;
  mesh.vertices = soup.vertices;
  mesh.triangles.resize(static_cast<Eigen::Index>(triangles.size()), 3);
  for (size_t t = 0; t < triangles.size(); ++t) {
    for (int k = 0; k < 3; ++k) mesh.triangles(t, k) = triangles[t][k];
  }
  mesh.triangle_source = std::move(source);
  return mesh;
}

TriangleMesh weld(const TriangleMesh& mesh) {
  const Eigen::Index n = mesh.vertices.rows();
  std::vector<int> order(static_cast<size_t>(n));
  std::iota(order.begin(), order.end(), 0);
  auto less = [&](int a, int b) {
    for (int k = 0; k < 3; ++k) {
      if (mesh.vertices(a, k) != mesh.vertices(b, k)) return mesh.vertices(a, k) < mesh.vertices(b, k);
    }
    return a < b;
  };
  std::sort(order.begin(), order.end(), less);
  // representative[v] = smallest index with exactly v's coordinates.
  std::vector<int> representative(static_cast<size_t>(n));
  for (size_t i = 0; i < order.size();) {
    size_t j = i;
    while (j < order.size() && mesh.vertices.row(order[j]) == mesh.vertices.row(order[i])) ++j;
    for (size_t k = i; k < j; ++k) representative[order[k]] = order[i];
    i = j;
  }
  // Keep referenced representatives in first-occurrence order of their index.
  std::vector<int> new_index(static_cast<size_t>(n), -1);
  for (Eigen::Index t = 0; t < mesh.triangles.rows(); ++t) {
    for (int k = 0; k < 3; ++k) new_index[representative[mesh.triangles(t, k)]] = 0;
  }
  int count = 0;
  for (Eigen::Index v = 0; v < n; ++v) {
    if (new_index[v] == 0) new_index[v] = count++;
  }
  TriangleMesh out;
  out.vertices.resize(count, 3);
  for (Eigen::Index v = 0; v < n; ++v) {
    if (new_index[v] >= 0 && representative[v] == v) out.vertices.row(new_index[v]) = mesh.vertices.row(v);
  }
  out.triangles.resize(mesh.triangles.rows(), 3);
  for (Eigen::Index t = 0; t < mesh.triangles.rows(); ++t) {
    for (int k = 0; k < 3; ++k) out.triangles(t, k) = new_index[representative[mesh.triangles(t, k)]];
  }
  out.triangle_source = mesh.triangle_source;
  if (out.triangle_source.empty()) {
    out.triangle_source.resize(static_cast<size_t>(mesh.triangles.rows()));
    std::iota(out.triangle_source.begin(), out.triangle_source.end(), 0);
  }
  return out;
}

TriMesh to_trimesh(const TriangleMesh& mesh) {
  TriMesh out;
  out.reserve(mesh.vertices.rows(), 3 * mesh.triangles.rows() / 2, mesh.triangles.rows());
  for (Eigen::Index v = 0; v < mesh.vertices.rows(); ++v) {
    out.add_vertex(TriMesh::Point(mesh.vertices(v, 0), mesh.vertices(v, 1), mesh.vertices(v, 2)));
  }
  for (Eigen::Index t = 0; t < mesh.triangles.rows(); ++t) {
    const auto f = out.add_face(out.vertex_handle(mesh.triangles(t, 0)),
                                out.vertex_handle(mesh.triangles(t, 1)),
                                out.vertex_handle(mesh.triangles(t, 2)));
    GENBREP_CHECK(f.is_valid() && f.idx() == t, Code::Internal,
                  "halfedge mesh rejected triangle " + std::to_string(t) +
                      " of a mesh that passed validation");
  }
  return out;
}

double bounding_box_diagonal(const Vertices& vertices) {
  if (vertices.rows() == 0) return 0;
  return (vertices.colwise().maxCoeff() - vertices.colwise().minCoeff()).norm();
}

}  // namespace genbrep

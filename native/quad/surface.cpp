// quad/surface.cpp — the read-only view of one organic component that the layout is traced on
// (Surface: points, normals, target sizes, the field's directions).
#include <algorithm>
#include <cmath>

#include "quad/detail/surface.h"

namespace genbrep::quad_detail {
Surface::Surface(const TriMesh& m, const Partition& p, const CrossField& f, int c)
    : mesh(m), partition(p), field(f), component(c) {
  const int nv = static_cast<int>(m.n_vertices()), nf = static_cast<int>(m.n_faces());
  point.resize(nv);
  for (int v = 0; v < nv; ++v) point[v] = to_vec(m.point(m.vertex_handle(v)));
  face_normal.assign(nf, Vec3::Zero());
  quads_on_face.assign(nf, 0.0);
  vertex_normal.assign(nv, Vec3::Zero());
  vertex_size.assign(nv, 0.0);
  std::vector<int> count(nv, 0);
  for (int f = 0; f < nf; ++f) {
    int corner[3], k = 0;
    for (auto v : m.fv_range(m.face_handle(f))) corner[k++] = v.idx();
    const Vec3 n = (point[corner[1]] - point[corner[0]]).cross(point[corner[2]] - point[corner[0]]);
    face_normal[f] = n.norm() > 0 ? n.normalized() : Vec3(0, 0, 1);
    if (!in(f)) continue;
    quads_on_face[f] = 0.5 * n.norm() / (field.size_u[f] * field.size_v[f]);
    const double size = 0.5 * (field.size_u[f] + field.size_v[f]);
    for (int v : corner) {
      vertex_normal[v] += n;
      vertex_size[v] += size;
      ++count[v];
    }
  }
  for (int v = 0; v < nv; ++v) {
    if (!count[v]) continue;
    vertices.push_back(v);
    vertex_size[v] /= count[v];
    vertex_normal[v] = vertex_normal[v].norm() > 0 ? vertex_normal[v].normalized() : Vec3(0, 0, 1);
  }
}

int Surface::ccw(int h) const {
  return mesh.opposite_halfedge_handle(mesh.prev_halfedge_handle(mesh.halfedge_handle(h))).idx();
}
double Surface::corner_angle(int h) const {
  const int f = face(h);
  if (f < 0) return 0;
  const int a = from(h), b = to(h);
  const int c = mesh.to_vertex_handle(mesh.next_halfedge_handle(mesh.halfedge_handle(h))).idx();
  const Vec3 u = point[b] - point[a], w = point[c] - point[a];
  return std::atan2(u.cross(w).norm(), u.dot(w));
}
Vec3 Surface::snap(int f, const Vec3& d) const {
  const Vec3 u = field.direction.row(f).transpose();
  const Vec3 v = face_normal[f].cross(u);
  const double a = d.dot(u), b = d.dot(v);
  if (std::abs(a) >= std::abs(b)) return a >= 0 ? u : Vec3(-u);
  return b >= 0 ? v : Vec3(-v);
}
double Surface::size_along(int f, const Vec3& d) const {
  const Vec3 u = field.direction.row(f).transpose();
  const double a = std::abs(d.normalized().dot(u));
  return a >= std::sqrt(0.5) ? field.size_u[f] : field.size_v[f];
}
Vec3 Surface::tangent(int v, const Vec3& d) const {
  const Vec3 t = d - vertex_normal[v] * vertex_normal[v].dot(d);
  return t.norm() > 1e-12 ? t.normalized() : d.normalized();
}

}  // namespace genbrep::quad_detail

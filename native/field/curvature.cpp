// field/curvature.cpp — face frames and the per-face curvature tensor (input to §6.1–6.2).
// The tensor is Rusinkiewicz's per-face estimate ("Estimating curvatures and their
// derivatives on triangle meshes", 3DPVT 2004): the second fundamental form II that best
// maps the three edges of a triangle to the differences of its corners' normals. On the
// faceted output of a level-set solver this is noisy at the grid scale, so it is averaged
// over a few rings (vertex ↔ face, area weighted) as 3×3 world-space tensors and projected
// back into each face's plane, which needs no frame transport.
#include <Eigen/Cholesky>
#include <cmath>

#include "field/detail/field_detail.h"

namespace genbrep::field_detail {
namespace {

Vec3 point(const TriMesh& mesh, OpenMesh::VertexHandle v) {
  const auto& p = mesh.point(v);
  return Vec3(p[0], p[1], p[2]);
}

// Any unit vector perpendicular to n.
Vec3 perpendicular(const Vec3& n) {
  const Vec3 a = std::abs(n.x()) < 0.9 ? Vec3(1, 0, 0) : Vec3(0, 1, 0);
  return n.cross(a).normalized();
}

}  // namespace

double corner_angle(const TriMesh& mesh, OpenMesh::HalfedgeHandle h) {
  const Vec3 p = point(mesh, mesh.from_vertex_handle(h));
  const Vec3 a = point(mesh, mesh.to_vertex_handle(h)) - p;
  const Vec3 b = point(mesh, mesh.from_vertex_handle(mesh.prev_halfedge_handle(h))) - p;
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

FaceFrames face_frames(const TriMesh& mesh) {
  const int nf = static_cast<int>(mesh.n_faces());
  FaceFrames frames;
  frames.normal.resize(nf);
  frames.x.resize(nf);
  frames.y.resize(nf);
  frames.centroid.resize(nf);
  frames.area.resize(nf);
  std::vector<Vec3> raw(nf);  // unnormalised normals (twice the area)
  std::vector<char> degenerate(nf, 0);
  for (int f = 0; f < nf; ++f) {
    const auto h = mesh.halfedge_handle(mesh.face_handle(f));
    const Vec3 p0 = point(mesh, mesh.from_vertex_handle(h));
    const Vec3 p1 = point(mesh, mesh.to_vertex_handle(h));
    const Vec3 p2 = point(mesh, mesh.to_vertex_handle(mesh.next_halfedge_handle(h)));
    raw[f] = (p1 - p0).cross(p2 - p0);
    frames.area[f] = 0.5 * raw[f].norm();
    frames.centroid[f] = (p0 + p1 + p2) / 3.0;
    const double longest =
        std::max({(p1 - p0).squaredNorm(), (p2 - p1).squaredNorm(), (p0 - p2).squaredNorm()});
    // A triangle whose height is below 1e-8 of its longest edge has no reliable normal.
    degenerate[f] = raw[f].norm() <= 1e-8 * longest || longest == 0;
    frames.degenerate += degenerate[f];
  }
  for (int f = 0; f < nf; ++f) {
    const auto fh = mesh.face_handle(f);
    Vec3 n = raw[f];
    if (degenerate[f]) {
      // Sum of the area-weighted normals of the triangles around its corners.
      n.setZero();
      for (auto v : mesh.fv_range(fh))
        for (auto g : mesh.vf_range(v)) n += raw[g.idx()];
      if (n.norm() == 0) n = Vec3(0, 0, 1);
    }
    n.normalize();
    const auto h = mesh.halfedge_handle(fh);
    Vec3 x = point(mesh, mesh.to_vertex_handle(h)) - point(mesh, mesh.from_vertex_handle(h));
    x -= n * n.dot(x);
    x = x.norm() > 1e-300 ? x.normalized() : perpendicular(n);
    frames.normal[f] = n;
    frames.x[f] = x;
    frames.y[f] = n.cross(x);
  }
  return frames;
}

void estimate_curvature(const TriMesh& mesh, const FaceFrames& frames, int smoothing,
                        CrossField* field) {
  const int nf = static_cast<int>(mesh.n_faces());
  const int nv = static_cast<int>(mesh.n_vertices());
  // Angle-weighted vertex normals (Thürmer & Wüthrich): insensitive to how a fan is split.
  std::vector<Vec3> vertex_normal(nv, Vec3::Zero());
  for (int f = 0; f < nf; ++f) {
    for (auto h : mesh.fh_range(mesh.face_handle(f))) {
      vertex_normal[mesh.from_vertex_handle(h).idx()] += corner_angle(mesh, h) * frames.normal[f];
    }
  }
  for (auto& n : vertex_normal) n = n.norm() > 0 ? n.normalized() : Vec3(0, 0, 1);

  // Per-face II by least squares: for each edge e_i (opposite corner i),
  // II·(e·x, e·y) = (Δn·x, Δn·y), Δn the difference of the edge's end normals.
  std::vector<Eigen::Matrix3d> tensor(nf);
  for (int f = 0; f < nf; ++f) {
    const auto h0 = mesh.halfedge_handle(mesh.face_handle(f));
    Eigen::Matrix3d normal_matrix = Eigen::Matrix3d::Zero();
    Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
    auto h = h0;
    for (int i = 0; i < 3; ++i, h = mesh.next_halfedge_handle(h)) {
      const auto a = mesh.from_vertex_handle(h), b = mesh.to_vertex_handle(h);
      const Vec3 e = point(mesh, b) - point(mesh, a);
      const Vec3 dn = vertex_normal[b.idx()] - vertex_normal[a.idx()];
      const double eu = e.dot(frames.x[f]), ev = e.dot(frames.y[f]);
      const Eigen::Vector3d row1(eu, ev, 0), row2(0, eu, ev);
      normal_matrix += row1 * row1.transpose() + row2 * row2.transpose();
      rhs += row1 * dn.dot(frames.x[f]) + row2 * dn.dot(frames.y[f]);
    }
    Eigen::Vector3d abc = Eigen::Vector3d::Zero();
    if (frames.area[f] > 0 &&
        normal_matrix.determinant() > 1e-30 * std::pow(normal_matrix.trace(), 3)) {
      abc = normal_matrix.ldlt().solve(rhs);
    }
    const Vec3& x = frames.x[f];
    const Vec3& y = frames.y[f];
    tensor[f] = abc[0] * x * x.transpose() + abc[1] * (x * y.transpose() + y * x.transpose()) +
                abc[2] * y * y.transpose();
  }

  // Smoothing rounds: vertex tensor = area-weighted mean of its faces; face tensor = mean of
  // its corners, projected into the face plane.
  std::vector<Eigen::Matrix3d> vertex_tensor(nv);
  std::vector<double> vertex_area(nv);
  for (int round = 0; round < smoothing; ++round) {
    std::fill(vertex_tensor.begin(), vertex_tensor.end(), Eigen::Matrix3d::Zero());
    std::fill(vertex_area.begin(), vertex_area.end(), 0.0);
    for (int f = 0; f < nf; ++f) {
      for (auto v : mesh.fv_range(mesh.face_handle(f))) {
        vertex_tensor[v.idx()] += frames.area[f] * tensor[f];
        vertex_area[v.idx()] += frames.area[f];
      }
    }
    for (int v = 0; v < nv; ++v) {
      if (vertex_area[v] > 0) vertex_tensor[v] /= vertex_area[v];
    }
    for (int f = 0; f < nf; ++f) {
      Eigen::Matrix3d mean = Eigen::Matrix3d::Zero();
      for (auto v : mesh.fv_range(mesh.face_handle(f))) mean += vertex_tensor[v.idx()];
      const Eigen::Matrix3d projector =
          Eigen::Matrix3d::Identity() - frames.normal[f] * frames.normal[f].transpose();
      tensor[f] = projector * (mean / 3.0) * projector;
    }
  }

  field->kappa1.resize(nf);
  field->kappa2.resize(nf);
  field->principal1.resize(nf, 3);
  field->principal2.resize(nf, 3);
  for (int f = 0; f < nf; ++f) {
    const Vec3& x = frames.x[f];
    const Vec3& y = frames.y[f];
    const double a = x.dot(tensor[f] * x), b = 0.5 * (x.dot(tensor[f] * y) + y.dot(tensor[f] * x));
    const double c = y.dot(tensor[f] * y);
    const double mean = 0.5 * (a + c), radius = std::hypot(0.5 * (a - c), b);
    field->kappa1[f] = mean + radius;
    field->kappa2[f] = mean - radius;
    const double phi = 0.5 * std::atan2(2 * b, a - c);  // direction of the larger eigenvalue
    const Vec3 d1 = frames.direction(f, phi);
    field->principal1.row(f) = d1.transpose();
    field->principal2.row(f) = frames.normal[f].cross(d1).transpose();
  }
}

}  // namespace genbrep::field_detail

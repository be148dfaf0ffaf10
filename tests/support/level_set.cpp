#include "level_set.h"

#include <array>
#include <cmath>
#include <unordered_map>

namespace genbrep::testing {
namespace {

TriangleMesh to_mesh(const std::vector<Vec3>& vertices, const std::vector<std::array<int, 3>>& triangles) {
  TriangleMesh mesh;
  mesh.vertices.resize(static_cast<Eigen::Index>(vertices.size()), 3);
  for (size_t v = 0; v < vertices.size(); ++v) mesh.vertices.row(v) = vertices[v];
  mesh.triangles.resize(static_cast<Eigen::Index>(triangles.size()), 3);
  for (size_t t = 0; t < triangles.size(); ++t)
    for (int c = 0; c < 3; ++c) mesh.triangles(t, c) = triangles[t][c];
  return mesh;
}

}  // namespace

TriangleMesh extract_level_set(const Field& f, const Vec3& origin, double h,
                               const Eigen::Vector3i& cells) {
  const int nx = cells.x() + 1, ny = cells.y() + 1, nz = cells.z() + 1;
  auto index = [&](int i, int j, int k) { return (static_cast<int64_t>(k) * ny + j) * nx + i; };
  auto point = [&](int64_t g) {
    const int i = static_cast<int>(g % nx), j = static_cast<int>((g / nx) % ny),
              k = static_cast<int>(g / (static_cast<int64_t>(nx) * ny));
    return Vec3(origin + h * Vec3(i, j, k));
  };
  std::vector<double> value(static_cast<size_t>(nx) * ny * nz);
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        double v = f(origin + h * Vec3(i, j, k));
        if (v == 0) v = 1e-12 * h;  // keep the zero set off grid points: stays manifold
        value[index(i, j, k)] = v;
      }
  std::vector<Vec3> vertices;
  std::vector<std::array<int, 3>> triangles;
  std::unordered_map<uint64_t, int> edge_vertex;
  const uint64_t n_points = value.size();
  auto vertex_on = [&](int64_t a, int64_t b) {
    if (a > b) std::swap(a, b);
    const uint64_t key = static_cast<uint64_t>(a) * n_points + static_cast<uint64_t>(b);
    auto it = edge_vertex.find(key);
    if (it != edge_vertex.end()) return it->second;
    const double va = value[a], vb = value[b];
    const Vec3 p = point(a) + (point(b) - point(a)) * (va / (va - vb));
    vertices.push_back(p);
    edge_vertex.emplace(key, static_cast<int>(vertices.size()) - 1);
    return static_cast<int>(vertices.size()) - 1;
  };
  auto emit = [&](int a, int b, int c, const Vec3& outward) {
    const Vec3 n = (vertices[b] - vertices[a]).cross(vertices[c] - vertices[a]);
    if (n.dot(outward) < 0) std::swap(b, c);
    triangles.push_back({a, b, c});
  };
  static const int kAxes[6][2] = {{1, 2}, {1, 4}, {2, 1}, {2, 4}, {4, 1}, {4, 2}};
  for (int k = 0; k + 1 < nz; ++k)
    for (int j = 0; j + 1 < ny; ++j)
      for (int i = 0; i + 1 < nx; ++i) {
        auto corner = [&](int c) { return index(i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1)); };
        for (const auto& axes : kAxes) {
          const int64_t tet[4] = {corner(0), corner(axes[0]), corner(axes[0] | axes[1]), corner(7)};
          std::vector<int64_t> in, out;
          for (int64_t g : tet) (value[g] < 0 ? in : out).push_back(g);
          if (in.empty() || out.empty()) continue;
          Vec3 outward = Vec3::Zero();
          for (int64_t g : out) outward += point(g) / static_cast<double>(out.size());
          for (int64_t g : in) outward -= point(g) / static_cast<double>(in.size());
          if (in.size() == 1 || out.size() == 1) {
            const auto& lone = in.size() == 1 ? in : out;
            const auto& rest = in.size() == 1 ? out : in;
            emit(vertex_on(lone[0], rest[0]), vertex_on(lone[0], rest[1]),
                 vertex_on(lone[0], rest[2]), outward);
          } else {
            const int ac = vertex_on(in[0], out[0]), ad = vertex_on(in[0], out[1]);
            const int bd = vertex_on(in[1], out[1]), bc = vertex_on(in[1], out[0]);
            emit(ac, ad, bd, outward);
            emit(ac, bd, bc, outward);
          }
        }
      }
  return to_mesh(vertices, triangles);
}

double box_sdf(const Vec3& p, const Vec3& lo, const Vec3& hi) {
  const Vec3 center = 0.5 * (lo + hi), half = 0.5 * (hi - lo);
  const Vec3 q = (p - center).cwiseAbs() - half;
  return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
}

double sphere_sdf(const Vec3& p, const Vec3& center, double radius) {
  return (p - center).norm() - radius;
}

double capsule_sdf(const Vec3& p, const Vec3& a, const Vec3& b, double radius) {
  const Vec3 ab = b - a;
  const double t = std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
  return (p - (a + t * ab)).norm() - radius;
}

double torus_sdf(const Vec3& p, const Vec3& center, double major, double minor) {
  const Vec3 q = p - center;
  const double ring = std::hypot(q.x(), q.z()) - major;
  return std::hypot(ring, q.y()) - minor;
}

double arch_sdf(const Vec3& p, const Vec3& center, double major, double minor) {
  return std::max(torus_sdf(p, center, major, minor), center.z() - p.z());
}

TriangleMesh box_mesh(const Vec3& lo, const Vec3& hi, int n) {
  std::vector<Vec3> vertices;
  std::vector<std::array<int, 3>> triangles;
  std::unordered_map<int64_t, int> ids;  // lattice point -> vertex, so faces share edges
  auto vertex = [&](int i, int j, int k) {
    const int64_t key = (static_cast<int64_t>(i) * (n + 1) + j) * (n + 1) + k;
    auto it = ids.find(key);
    if (it != ids.end()) return it->second;
    vertices.push_back(lo + (hi - lo).cwiseProduct(Vec3(i, j, k) / n));
    ids.emplace(key, static_cast<int>(vertices.size()) - 1);
    return static_cast<int>(vertices.size()) - 1;
  };
  // Each face: fixed axis `a` at side s (0 or n); (u, v) axes chosen so u × v points out.
  for (int a = 0; a < 3; ++a)
    for (int s = 0; s <= n; s += n) {
      const int u = (a + 1) % 3, v = (a + 2) % 3;
      for (int x = 0; x < n; ++x)
        for (int y = 0; y < n; ++y) {
          auto at = [&](int px, int py) {
            int c[3];
            c[a] = s;
            c[u] = px;
            c[v] = py;
            return vertex(c[0], c[1], c[2]);
          };
          const int p00 = at(x, y), p10 = at(x + 1, y), p11 = at(x + 1, y + 1), p01 = at(x, y + 1);
          if (s == n) {
            triangles.push_back({p00, p10, p11});
            triangles.push_back({p00, p11, p01});
          } else {
            triangles.push_back({p00, p11, p10});
            triangles.push_back({p00, p01, p11});
          }
        }
    }
  return to_mesh(vertices, triangles);
}

TriangleMesh cylinder_mesh(const Vec3& base, double radius, double height, int segments) {
  TriangleMesh mesh;
  const int n = segments;
  mesh.vertices.resize(2 * n + 2, 3);
  for (int i = 0; i < n; ++i) {
    const double t = 2 * M_PI * i / n;
    const Vec3 ring(radius * std::cos(t), radius * std::sin(t), 0);
    mesh.vertices.row(i) = base + ring;
    mesh.vertices.row(n + i) = base + ring + Vec3(0, 0, height);
  }
  mesh.vertices.row(2 * n) = base;
  mesh.vertices.row(2 * n + 1) = base + Vec3(0, 0, height);
  mesh.triangles.resize(4 * n, 3);
  for (int i = 0; i < n; ++i) {
    const int j = (i + 1) % n;
    mesh.triangles.row(4 * i + 0) << i, j, n + j;
    mesh.triangles.row(4 * i + 1) << i, n + j, n + i;
    mesh.triangles.row(4 * i + 2) << 2 * n, j, i;
    mesh.triangles.row(4 * i + 3) << 2 * n + 1, n + i, n + j;
  }
  return mesh;
}

TriangleMesh merge(const std::vector<TriangleMesh>& meshes) {
  TriangleMesh out;
  Eigen::Index nv = 0, nt = 0;
  for (const auto& m : meshes) {
    nv += m.vertices.rows();
    nt += m.triangles.rows();
  }
  out.vertices.resize(nv, 3);
  out.triangles.resize(nt, 3);
  Eigen::Index v = 0, t = 0;
  for (const auto& m : meshes) {
    out.vertices.middleRows(v, m.vertices.rows()) = m.vertices;
    out.triangles.middleRows(t, m.triangles.rows()) = m.triangles.array() + static_cast<int>(v);
    v += m.vertices.rows();
    t += m.triangles.rows();
  }
  return out;
}

}  // namespace genbrep::testing

#include <cstdio>

namespace genbrep::testing {

void write_obj(const std::string& path, const TriangleMesh& mesh) {
  FILE* file = std::fopen(path.c_str(), "w");
  if (!file) return;
  for (Eigen::Index v = 0; v < mesh.vertices.rows(); ++v) {
    std::fprintf(file, "v %.17g %.17g %.17g\n", mesh.vertices(v, 0), mesh.vertices(v, 1), mesh.vertices(v, 2));
  }
  for (Eigen::Index t = 0; t < mesh.triangles.rows(); ++t) {
    std::fprintf(file, "f %d %d %d\n", mesh.triangles(t, 0) + 1, mesh.triangles(t, 1) + 1, mesh.triangles(t, 2) + 1);
  }
  std::fclose(file);
}

}  // namespace genbrep::testing

// fit/sample.cpp — sampling the limit surface: the watertight tessellation and the
// closest-point projection (fit/fit.h). Uses only LimitSurface's public evaluation.
#include <algorithm>
#include <map>

#include "fit/detail/closest.h"
#include "fit/fit.h"

namespace genbrep {

std::vector<FootPoint> LimitSurface::project(const std::vector<Vec3>& points,
                                             int samples_per_edge) const {
  const int n = std::max(1, samples_per_edge);
  const int quad_total = quad_count();
  // Unshared per-quad grids: a triangle's quad and (u, v) follow from its index.
  const int per_quad = (n + 1) * (n + 1);
  Vertices grid(static_cast<Eigen::Index>(quad_total) * per_quad, 3);
  Triangles triangles(static_cast<Eigen::Index>(quad_total) * 2 * n * n, 3);
  for (int q = 0; q < quad_total; ++q) {
    for (int j = 0; j <= n; ++j) {
      for (int i = 0; i <= n; ++i) {
        grid.row(q * per_quad + j * (n + 1) + i) =
            evaluate(q, double(i) / n, double(j) / n).position.transpose();
      }
    }
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        const int a = q * per_quad + j * (n + 1) + i, b = a + 1, c = b + n + 1, d = a + n + 1;
        const int t = 2 * (q * n * n + j * n + i);
        triangles.row(t) << a, b, c;
        triangles.row(t + 1) << a, c, d;
      }
    }
  }
  const fit_detail::TriangleTree tree(grid, triangles);
  std::vector<FootPoint> feet(points.size());
  for (size_t k = 0; k < points.size(); ++k) {
    const Vec3& p = points[k];
    const fit_detail::TriangleHit hit = tree.closest(p);
    const int t = hit.triangle;
    const int q = t / (2 * n * n);
    const int cell = (t / 2) % (n * n);
    const double i = cell % n, j = cell / n;
    const double b1 = hit.b1, b2 = hit.b2;
    // Corner parameters of the two triangles of cell (i, j): (a,b,c) and (a,c,d).
    double u, v;
    if (t % 2 == 0) {
      u = (i + b1 + b2) / n;
      v = (j + b2) / n;
    } else {
      u = (i + b1) / n;
      v = (j + b1 + b2) / n;
    }
    // Gauss–Newton on |S(u,v) − p|², kept inside the quad, accepting only descent.
    LimitSample sample = evaluate(q, u, v);
    double best = (sample.position - p).squaredNorm();
    for (int iteration = 0; iteration < 8; ++iteration) {
      const Vec3 r = sample.position - p;
      Eigen::Matrix2d normal;
      normal << sample.du.dot(sample.du), sample.du.dot(sample.dv), sample.du.dot(sample.dv),
          sample.dv.dot(sample.dv);
      const Eigen::Vector2d gradient(sample.du.dot(r), sample.dv.dot(r));
      if (!(normal.determinant() > 1e-300)) break;
      Eigen::Vector2d step = -normal.ldlt().solve(gradient);
      bool improved = false;
      for (int halving = 0; halving < 5 && !improved; ++halving, step *= 0.5) {
        const double nu = std::clamp(u + step.x(), 0.0, 1.0);
        const double nv = std::clamp(v + step.y(), 0.0, 1.0);
        const LimitSample trial = evaluate(q, nu, nv);
        const double d2 = (trial.position - p).squaredNorm();
        if (d2 < best) {
          improved = best - d2 > 1e-24 * (1 + best);
          best = d2;
          u = nu;
          v = nv;
          sample = trial;
          if (!improved) break;
        }
      }
      if (!improved) break;
    }
    feet[k] = {q, u, v, sample.position, std::sqrt(best)};
  }
  return feet;
}

TriangleMesh LimitSurface::tessellate(int samples_per_edge) const {
  const int n = std::max(1, samples_per_edge);
  const Quads& cage_quads = quads();
  const int quad_total = quad_count();
  TriangleMesh mesh;
  // Corners: the cage's vertices, evaluated from the first quad that has them.
  std::vector<Vec3> positions(control_point_count(), Vec3::Zero());
  std::vector<char> done(control_point_count(), 0);
  const double corner_u[4] = {0, 1, 1, 0}, corner_v[4] = {0, 0, 1, 1};
  for (int q = 0; q < quad_total; ++q) {
    for (int k = 0; k < 4; ++k) {
      const int c = cage_quads(q, k);
      if (done[c]) continue;
      done[c] = 1;
      positions[c] = evaluate(q, corner_u[k], corner_v[k]).position;
    }
  }
  // Edge samples, n − 1 per edge, in the direction of the edge's first appearance.
  std::map<std::pair<int, int>, int> edge_first;  // (a, b) as first seen → first sample index
  auto edge_uv = [&](int k, double t, double* u, double* v) {
    const double us[4] = {t, 1, 1 - t, 0}, vs[4] = {0, t, 1, 1 - t};
    *u = us[k];
    *v = vs[k];
  };
  std::vector<std::array<int, 4>> quad_edge_start(quad_total);
  std::vector<std::array<char, 4>> quad_edge_reversed(quad_total);
  for (int q = 0; q < quad_total; ++q) {
    for (int k = 0; k < 4; ++k) {
      const int a = cage_quads(q, k), b = cage_quads(q, (k + 1) % 4);
      auto it = edge_first.find({b, a});
      if (it != edge_first.end()) {
        quad_edge_start[q][k] = it->second;
        quad_edge_reversed[q][k] = 1;
        continue;
      }
      it = edge_first.find({a, b});
      if (it != edge_first.end()) {  // same direction twice: non-manifold or flipped quad
        quad_edge_start[q][k] = it->second;
        quad_edge_reversed[q][k] = 0;
        continue;
      }
      const int start = static_cast<int>(positions.size());
      edge_first[{a, b}] = start;
      quad_edge_start[q][k] = start;
      quad_edge_reversed[q][k] = 0;
      for (int i = 1; i < n; ++i) {
        double u, v;
        edge_uv(k, double(i) / n, &u, &v);
        positions.push_back(evaluate(q, u, v).position);
      }
    }
  }
  const int interior_start = static_cast<int>(positions.size());
  for (int q = 0; q < quad_total; ++q) {
    for (int j = 1; j < n; ++j) {
      for (int i = 1; i < n; ++i)
        positions.push_back(evaluate(q, double(i) / n, double(j) / n).position);
    }
  }
  auto vertex_id = [&](int q, int i, int j) {
    if (i == 0 && j == 0) return cage_quads(q, 0);
    if (i == n && j == 0) return cage_quads(q, 1);
    if (i == n && j == n) return cage_quads(q, 2);
    if (i == 0 && j == n) return cage_quads(q, 3);
    int k, along;  // edge k of the quad, sample index from the edge's start corner
    if (j == 0) {
      k = 0;
      along = i;
    } else if (i == n) {
      k = 1;
      along = j;
    } else if (j == n) {
      k = 2;
      along = n - i;
    } else if (i == 0) {
      k = 3;
      along = n - j;
    } else
      return interior_start + q * (n - 1) * (n - 1) + (j - 1) * (n - 1) + (i - 1);
    if (quad_edge_reversed[q][k]) along = n - along;
    return quad_edge_start[q][k] + along - 1;
  };
  mesh.vertices.resize(static_cast<Eigen::Index>(positions.size()), 3);
  for (size_t i = 0; i < positions.size(); ++i) mesh.vertices.row(i) = positions[i].transpose();
  mesh.triangles.resize(static_cast<Eigen::Index>(quad_total) * 2 * n * n, 3);
  mesh.triangle_source.resize(mesh.triangles.rows());
  for (int q = 0; q < quad_total; ++q) {
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        const int a = vertex_id(q, i, j), b = vertex_id(q, i + 1, j),
                  c = vertex_id(q, i + 1, j + 1), d = vertex_id(q, i, j + 1);
        const int t = 2 * (q * n * n + j * n + i);
        mesh.triangles.row(t) << a, b, c;
        mesh.triangles.row(t + 1) << a, c, d;
        mesh.triangle_source[t] = mesh.triangle_source[t + 1] = q;
      }
    }
  }
  return mesh;
}

TriangleMesh tessellate_limit(const QuadCage& cage, int samples_per_edge) {
  return LimitSurface(cage).tessellate(samples_per_edge);
}

}  // namespace genbrep

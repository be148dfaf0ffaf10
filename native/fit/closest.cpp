// fit/closest.cpp — closest-point queries for the fit (see fit/detail/closest.h).
#include "fit/detail/closest.h"

#include <algorithm>
#include <limits>
#include <numeric>

namespace genbrep::fit_detail {

TriangleHit closest_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  // Voronoi regions of the vertices, then edges, then the face.
  TriangleHit hit;
  auto finish = [&](double b1, double b2) {
    hit.b1 = b1;
    hit.b2 = b2;
    hit.point = a + b1 * (b - a) + b2 * (c - a);
    hit.distance2 = (p - hit.point).squaredNorm();
    return hit;
  };
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return finish(0, 0);
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return finish(1, 0);
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double denom = d1 - d3;
    return finish(denom > 0 ? d1 / denom : 0, 0);
  }
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return finish(0, 1);
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double denom = d2 - d6;
    return finish(0, denom > 0 ? d2 / denom : 0);
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double denom = (d4 - d3) + (d5 - d6);
    const double w = denom > 0 ? (d4 - d3) / denom : 0;
    return finish(1 - w, w);
  }
  const double sum = va + vb + vc;
  if (!(sum > 0)) {
    // Degenerate (collinear) triangle: the best of its three edges.
    TriangleHit best = finish(0, 0);
    for (int e = 0; e < 3; ++e) {
      const Vec3& s0 = e == 0 ? a : e == 1 ? b : c;
      const Vec3& s1 = e == 0 ? b : e == 1 ? c : a;
      const Vec3 d = s1 - s0;
      const double len2 = d.squaredNorm();
      const double t = len2 > 0 ? std::clamp((p - s0).dot(d) / len2, 0.0, 1.0) : 0.0;
      const double b1 = e == 0 ? t : e == 1 ? 1 - t : 0;
      const double b2 = e == 0 ? 0 : e == 1 ? t : 1 - t;
      TriangleHit candidate = finish(b1, b2);
      if (candidate.distance2 < best.distance2) best = candidate;
    }
    return best;
  }
  return finish(vb / sum, vc / sum);
}

TriangleTree::TriangleTree(const Vertices& vertices, const Triangles& triangles)
    : vertices_(vertices), triangles_(triangles) {
  const int n = static_cast<int>(triangles.rows());
  if (n == 0) return;
  order_.resize(n);
  std::iota(order_.begin(), order_.end(), 0);
  std::vector<Vec3> centroids(n);
  std::vector<Eigen::AlignedBox3d> boxes(n);
  for (int t = 0; t < n; ++t) {
    const Vec3 a = vertices.row(triangles(t, 0)).transpose(),
               b = vertices.row(triangles(t, 1)).transpose(),
               c = vertices.row(triangles(t, 2)).transpose();
    centroids[t] = (a + b + c) / 3.0;
    boxes[t] = Eigen::AlignedBox3d(a.cwiseMin(b).cwiseMin(c), a.cwiseMax(b).cwiseMax(c));
  }
  nodes_.reserve(2 * (n / 4 + 1));
  build(0, n, centroids, boxes);
}

int TriangleTree::build(int first, int count, const std::vector<Vec3>& centroids,
                        const std::vector<Eigen::AlignedBox3d>& boxes) {
  const int index = static_cast<int>(nodes_.size());
  nodes_.emplace_back();
  Eigen::AlignedBox3d box, centre_box;
  for (int i = first; i < first + count; ++i) {
    box.extend(boxes[order_[i]]);
    centre_box.extend(centroids[order_[i]]);
  }
  nodes_[index].box = box;
  if (count <= 8) {
    nodes_[index].first = first;
    nodes_[index].count = count;
    return index;
  }
  int axis = 0;
  centre_box.sizes().maxCoeff(&axis);
  const int half = count / 2;
  // nth_element with the triangle index as tie-break keeps the split deterministic.
  std::nth_element(order_.begin() + first, order_.begin() + first + half,
                   order_.begin() + first + count, [&](int x, int y) {
                     const double cx = centroids[x][axis], cy = centroids[y][axis];
                     return cx < cy || (cx == cy && x < y);
                   });
  const int left = build(first, half, centroids, boxes);
  const int right = build(first + half, count - half, centroids, boxes);
  nodes_[index].left = left;
  nodes_[index].right = right;
  return index;
}

TriangleHit TriangleTree::closest(const Vec3& p) const {
  TriangleHit best;
  best.distance2 = std::numeric_limits<double>::infinity();
  if (nodes_.empty()) return best;
  // Depth is about log2(n / 8) ≤ 40 for any mesh that fits in memory; each level pushes
  // at most two nodes.
  int stack[128];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& node = nodes_[stack[--top]];
    if (node.box.squaredExteriorDistance(p) > best.distance2) continue;
    if (node.left < 0) {
      for (int i = node.first; i < node.first + node.count; ++i) {
        const int t = order_[i];
        TriangleHit hit = closest_on_triangle(p, vertices_.row(triangles_(t, 0)).transpose(),
                                              vertices_.row(triangles_(t, 1)).transpose(),
                                              vertices_.row(triangles_(t, 2)).transpose());
        if (hit.distance2 < best.distance2 ||
            (hit.distance2 == best.distance2 && t < best.triangle)) {
          hit.triangle = t;
          best = hit;
        }
      }
      continue;
    }
    const double dl = nodes_[node.left].box.squaredExteriorDistance(p);
    const double dr = nodes_[node.right].box.squaredExteriorDistance(p);
    // Push the farther child first so the nearer one is visited first.
    if (dl <= dr) {
      stack[top++] = node.right;
      stack[top++] = node.left;
    } else {
      stack[top++] = node.left;
      stack[top++] = node.right;
    }
  }
  return best;
}

PolylineHit closest_on_polyline(const Vec3& p, const std::vector<Vec3>& polyline, bool closed) {
  PolylineHit best;
  best.distance2 = std::numeric_limits<double>::infinity();
  const int n = static_cast<int>(polyline.size());
  const int segments = closed ? n : n - 1;
  if (n == 1) {
    best.segment = 0;
    best.point = polyline[0];
    best.distance2 = (p - polyline[0]).squaredNorm();
  }
  for (int s = 0; s < segments; ++s) {
    const Vec3& a = polyline[s];
    const Vec3& b = polyline[(s + 1) % n];
    const Vec3 d = b - a;
    const double len2 = d.squaredNorm();
    const double t = len2 > 0 ? std::clamp((p - a).dot(d) / len2, 0.0, 1.0) : 0.0;
    const Vec3 q = a + t * d;
    const double dist2 = (p - q).squaredNorm();
    if (dist2 < best.distance2) best = {s, t, q, dist2};
  }
  return best;
}

}  // namespace genbrep::fit_detail

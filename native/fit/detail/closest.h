// fit/detail/closest.h — closest points on a triangle soup and on polylines, for the fit.
// A static bounding-volume hierarchy (median split on the longest axis of the centroids,
// up to 8 triangles per leaf); queries visit the nearer child first and prune by box
// distance. Deterministic: ties go to the lower triangle index. Degenerate triangles are
// fine (the closest point of a segment or point is returned).
#pragma once
#include <vector>

#include "core/types.h"

namespace genbrep::fit_detail {

struct TriangleHit {
  int triangle = -1;
  double b1 = 0, b2 = 0;  // barycentric weights of corners 1 and 2 (corner 0: 1 − b1 − b2)
  Vec3 point = Vec3::Zero();
  double distance2 = 0;
};

// Closest point of triangle (a, b, c) to p (Ericson, Real-Time Collision Detection §5.1.5).
TriangleHit closest_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c);

class TriangleTree {
 public:
  TriangleTree(const Vertices& vertices, const Triangles& triangles);
  bool empty() const { return nodes_.empty(); }
  TriangleHit closest(const Vec3& p) const;

 private:
  struct Node {
    Eigen::AlignedBox3d box;
    int first = 0, count = 0;  // leaf: triangles order_[first, first + count)
    int left = -1, right = -1;
  };
  int build(int first, int count, const std::vector<Vec3>& centroids,
            const std::vector<Eigen::AlignedBox3d>& boxes);
  const Vertices& vertices_;
  const Triangles& triangles_;
  std::vector<int> order_;
  std::vector<Node> nodes_;
};

// Closest point on the polyline (closed if `closed`): segment index s and t in [0, 1].
struct PolylineHit {
  int segment = -1;
  double t = 0;
  Vec3 point = Vec3::Zero();
  double distance2 = 0;
};
PolylineHit closest_on_polyline(const Vec3& p, const std::vector<Vec3>& polyline, bool closed);

}  // namespace genbrep::fit_detail

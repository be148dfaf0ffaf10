// quad/untangle.cpp — local repair of a filled cage (quad/quad.h step 4): quads that came
// out degenerate or turned over (a re-cornered patch, or nodes merged by a zero-length
// arc, can squeeze a grid cell to nothing) are opened up by smoothing the interior cage
// vertices around them and projecting them back onto the component.
// Only vertices within a few rings of a bad quad move, so the rest of the cage, its
// boundary chains (on the loops) and its irregular vertices stay where the layout put them.
// Complexity: O(rounds · moved vertices · log F) (closest points, locate.cpp).
#include <algorithm>
#include <cmath>
#include <set>

#include "quad/detail/layout.h"

namespace genbrep::quad_detail {
namespace {

constexpr double kPi = 3.14159265358979323846;
// Corners under this are "squeezed" here; the validity bar (measure_cage) is 1°, and the
// margin keeps a repaired quad from sitting just above it.
constexpr double kMinCornerDegrees = 5.0;

}  // namespace

int untangle_cage(const Surface& s, QuadCage& cage, int max_rounds) {
  const ComponentLocator locator(s);
  auto project = [&](const Vec3& p, Vec3* normal) { return locator.closest(p, normal); };
  const int nv = static_cast<int>(cage.vertices.rows());
  const int nq = static_cast<int>(cage.quads.rows());
  std::vector<std::set<int>> neighbours(nv);
  for (int q = 0; q < nq; ++q)
    for (int k = 0; k < 4; ++k) {
      const int a = cage.quads(q, k), b = cage.quads(q, (k + 1) % 4);
      neighbours[a].insert(b), neighbours[b].insert(a);
    }
  std::vector<char> fixed(nv, 0);
  for (const auto& chain : cage.boundary_chains)
    for (int v : chain) fixed[v] = 1;
  auto point = [&](int v) { return Vec3(cage.vertices.row(v).transpose()); };
  auto bad = [&](int q) {
    Vec3 c[4];
    for (int k = 0; k < 4; ++k) c[k] = point(cage.quads(q, k));
    for (int k = 0; k < 4; ++k) {
      const Vec3 a = c[(k + 1) % 4] - c[k], b = c[(k + 3) % 4] - c[k];
      if (a.norm() == 0 || b.norm() == 0) return true;
      if (std::atan2(a.cross(b).norm(), a.dot(b)) * 180 / kPi < kMinCornerDegrees) return true;
    }
    Vec3 normal;
    project(0.25 * (c[0] + c[1] + c[2] + c[3]), &normal);
    return (c[2] - c[0]).cross(c[3] - c[1]).dot(normal) <= 0;
  };
  // Each round smooths the free vertices within 1 + round / 4 rings of a bad quad (the
  // region grows while the repair does not succeed). A vertex moves within its tangent
  // plane and is projected back; a move whose projection lands on a face facing another
  // way (the far side of a thin wall) is refused. The best cage seen is kept.
  auto bad_quads = [&] {
    std::vector<int> list;
    for (int q = 0; q < nq; ++q)
      if (bad(q)) list.push_back(q);
    return list;
  };
  std::vector<int> current = bad_quads();
  Eigen::MatrixX3d best = cage.vertices;
  size_t best_bad = current.size();
  std::set<int> moved_ever;
  for (int round = 0; round < max_rounds && !current.empty(); ++round) {
    std::set<int> region;
    for (int q : current)
      for (int k = 0; k < 4; ++k) region.insert(cage.quads(q, k));
    for (int ring = 0; ring < 1 + round / 4; ++ring) {
      std::set<int> grown = region;
      for (int v : region) grown.insert(neighbours[v].begin(), neighbours[v].end());
      region.swap(grown);
    }
    for (int sweep = 0; sweep < 4; ++sweep)
      for (int v : region) {
        if (fixed[v] || neighbours[v].empty()) continue;
        Vec3 normal;
        const Vec3 at = project(point(v), &normal);
        Vec3 mean = Vec3::Zero();
        for (int w : neighbours[v]) mean += point(w);
        mean /= static_cast<double>(neighbours[v].size());
        Vec3 step = mean - at;
        step -= step.dot(normal) * normal;
        Vec3 landed_normal;
        const Vec3 landed = project(at + step, &landed_normal);
        if (landed_normal.dot(normal) < 0.5) continue;
        cage.vertices.row(v) = landed.transpose();
        moved_ever.insert(v);
      }
    current = bad_quads();
    if (current.size() < best_bad) best_bad = current.size(), best = cage.vertices;
  }
  cage.vertices = best;
  return static_cast<int>(moved_ever.size());
}

}  // namespace genbrep::quad_detail

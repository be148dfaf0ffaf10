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
// After a diagonal collapse the neighbourhood is smoothed until its corners reach this.
constexpr double kShapeCornerDegrees = 30.0;

// The smoothing repair; returns the vertices it moved and leaves the best cage it saw.
std::set<int> smooth_cage(const Surface& s, const ComponentLocator& locator,
                          const DesignNormals& normals, QuadCage& cage, int max_rounds,
                          double min_corner_degrees, std::vector<int>* still_bad) {
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
      if (std::atan2(a.cross(b).norm(), a.dot(b)) * 180 / kPi < min_corner_degrees) return true;
    }
    // Turned over by measure_cage's test, or against the component face under the centroid.
    if (normals.flipped(c)) return true;
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
  *still_bad = bad_quads();
  return moved_ever;
}

}  // namespace

int collapse_diagonals(const Surface& s, const ComponentLocator& locator, QuadCage& cage,
                       const std::vector<int>& bad) {
  const int nv = static_cast<int>(cage.vertices.rows());
  std::vector<char> fixed(nv, 0), touched(nv, 0);
  for (const auto& chain : cage.boundary_chains)
    for (int v : chain) fixed[v] = 1;
  std::vector<std::vector<int>> quads_of(nv);
  for (int q = 0; q < cage.quads.rows(); ++q)
    for (int k = 0; k < 4; ++k) quads_of[cage.quads(q, k)].push_back(q);
  std::vector<int> merged_into(nv, -1);
  std::vector<char> removed(cage.quads.rows(), 0);
  int collapsed = 0;
  for (int q : bad) {
    int best_k = -1;
    double best_length = 1e300;
    for (int k = 0; k < 2; ++k) {
      const int a = cage.quads(q, k), c = cage.quads(q, k + 2);
      if (fixed[a] || fixed[c] || touched[a] || touched[c]) continue;
      bool shared = false;  // another quad holding both ends
      for (int r : quads_of[a])
        if (r != q)
          for (int j = 0; j < 4; ++j) shared |= cage.quads(r, j) == c;
      // The other two corners lose a quad: no interior vertex may drop below 3 quads.
      const int b = cage.quads(q, k + 1), d = cage.quads(q, (k + 3) % 4);
      if (touched[b] || touched[d]) continue;
      if (quads_of[b].size() < (fixed[b] ? 3u : 4u) || quads_of[d].size() < (fixed[d] ? 3u : 4u))
        continue;
      if (shared) continue;
      const double length = (cage.vertices.row(a) - cage.vertices.row(c)).norm();
      if (length < best_length) best_length = length, best_k = k;
    }
    if (best_k < 0) continue;
    const int a = cage.quads(q, best_k), c = cage.quads(q, best_k + 2);
    for (int k = 0; k < 4; ++k) touched[cage.quads(q, k)] = 1;
    Vec3 normal;
    const Vec3 mid = 0.5 * (cage.vertices.row(a) + cage.vertices.row(c)).transpose();
    cage.vertices.row(a) = locator.closest(mid, &normal).transpose();
    merged_into[c] = a;
    removed[q] = 1;
    ++collapsed;
  }
  if (!collapsed) return 0;
  // Compact: drop the removed quads and merged vertices, renumber.
  std::vector<int> new_id(nv, -1);
  int kept = 0;
  for (int v = 0; v < nv; ++v)
    if (merged_into[v] < 0) new_id[v] = kept++;
  auto id = [&](int v) { return new_id[merged_into[v] >= 0 ? merged_into[v] : v]; };
  Vertices vertices(kept, 3);
  for (int v = 0; v < nv; ++v)
    if (new_id[v] >= 0) vertices.row(new_id[v]) = cage.vertices.row(v);
  Quads quads(cage.quads.rows() - collapsed, 4);
  for (int q = 0, r = 0; q < cage.quads.rows(); ++q) {
    if (removed[q]) continue;
    for (int k = 0; k < 4; ++k) quads(r, k) = id(cage.quads(q, k));
    ++r;
  }
  for (auto& chain : cage.boundary_chains)
    for (int& v : chain) v = id(v);
  for (auto& e : cage.crease_edges) e = {id(e[0]), id(e[1])};
  cage.vertices = std::move(vertices);
  cage.quads = std::move(quads);
  return collapsed;
}

int untangle_cage(const Surface& s, QuadCage& cage, int max_rounds, int* collapsed) {
  const ComponentLocator locator(s);
  const DesignNormals normals(s.mesh);
  std::vector<int> bad;
  int moved = static_cast<int>(
      smooth_cage(s, locator, normals, cage, max_rounds, kMinCornerDegrees, &bad).size());
  // A fold that smoothing cannot open (a grid cell turned over inside a regular region):
  // take the quad out by collapsing a diagonal, then smooth again.
  *collapsed = 0;
  for (int attempt = 0; attempt < 4 && !bad.empty(); ++attempt) {
    const int now = collapse_diagonals(s, locator, cage, bad);
    if (!now) break;
    *collapsed += now;
    moved += static_cast<int>(
        smooth_cage(s, locator, normals, cage, max_rounds, kMinCornerDegrees, &bad).size());
  }
  if (*collapsed && bad.empty()) {
    // A collapse leaves thin quads around the merged vertex: open them further while the
    // cage stays valid.
    const Vertices valid = cage.vertices;
    std::vector<int> thin;
    moved += static_cast<int>(
        smooth_cage(s, locator, normals, cage, max_rounds, kShapeCornerDegrees, &thin).size());
    std::vector<int> strict;
    smooth_cage(s, locator, normals, cage, 0, kMinCornerDegrees, &strict);
    if (!strict.empty()) cage.vertices = valid;
  }
  return moved;
}

}  // namespace genbrep::quad_detail

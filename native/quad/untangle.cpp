// quad/untangle.cpp — local repair of a filled cage (quad/quad.h step 4): quads that came
// out degenerate or turned over (a re-cornered patch, or nodes merged by a zero-length
// arc, can squeeze a grid cell to nothing) are opened up by smoothing the interior cage
// vertices around them and projecting them back onto the component.
// Only vertices within a few rings of a bad quad move, so the rest of the cage, its
// boundary chains (on the loops) and its irregular vertices stay where the layout put them.
// Also here: the diagonal collapses of that repair, reused with edge rotations to cancel
// irregular vertices the layout left in pairs (cancel_irregular_pairs), doublet removal
// and evening out.
// Complexity: O(rounds · moved vertices · log F) (closest points, locate.cpp).
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <set>
#include <thread>
#include <vector>

#include "quad/detail/edit.h"

namespace genbrep::quad_detail {

double corner_angle(const Vec3& at, const Vec3& a, const Vec3& b) {
  const Vec3 u = a - at, w = b - at;
  return std::atan2(u.cross(w).norm(), u.dot(w));
}

bool corners_bad(const ComponentLocator& locator, const DesignNormals& normals,
                 const Vec3 (&c)[4], double min_corner_degrees, int* hint) {
  constexpr double kDegrees = 180 / kPi;
  for (int k = 0; k < 4; ++k) {
    if (c[(k + 1) % 4] == c[k] || c[(k + 3) % 4] == c[k]) return true;
    if (corner_angle(c[k], c[(k + 1) % 4], c[(k + 3) % 4]) * kDegrees < min_corner_degrees)
      return true;
  }
  return turned_over(normals, locator, c, hint);
}

// The corners of quad q from the one at v on, counter-clockwise: v, the next, the
// opposite, the previous.
std::array<int, 4> corners_from(const QuadCage& cage, int q, int v) {
  int k = 0;
  while (k < 4 && cage.quads(q, k) != v) ++k;
  return {cage.quads(q, k % 4), cage.quads(q, (k + 1) % 4), cage.quads(q, (k + 2) % 4),
          cage.quads(q, (k + 3) % 4)};
}

// A quad with a corner under `min_corner_degrees`, or turned over by measure_cage's test
// (turned_over). `hint`: the triangle under the centroid when last looked at
// (ComponentLocator::closest; updated), or null.
bool quad_is_bad(const ComponentLocator& locator, const DesignNormals& normals,
                 const QuadCage& cage, int q, double min_corner_degrees, int* hint) {
  Vec3 c[4];
  for (int k = 0; k < 4; ++k) c[k] = cage.vertices.row(cage.quads(q, k)).transpose();
  return corners_bad(locator, normals, c, min_corner_degrees, hint);
}

// The smoothing repair; returns the vertices it moved and leaves the best cage it saw.
std::set<int> smooth_cage(const ComponentLocator& locator, const DesignNormals& normals,
                          QuadCage& cage, int max_rounds, double min_corner_degrees,
                          std::vector<int>* still_bad) {
  // Each vertex's and quad centroid's last triangle (ComponentLocator::closest): the
  // search starts there.
  std::vector<int> hint(cage.vertices.rows(), -1), quad_hint(cage.quads.rows(), -1);
  const int nq = static_cast<int>(cage.quads.rows());
  const CageIncidence incidence(cage);
  const auto& neighbours = incidence.neighbours;
  const auto& fixed = incidence.on_chain;
  const auto& quads_of = incidence.quads_of;
  auto point = [&](int v) { return Vec3(cage.vertices.row(v).transpose()); };
  auto bad = [&](int q) {
    return quad_is_bad(locator, normals, cage, q, min_corner_degrees, &quad_hint[q]);
  };
  // Each round smooths the free vertices within 1 + round / 4 rings of a bad quad (the
  // region grows while the repair does not succeed). A vertex moves within its tangent
  // plane and is projected back; a move whose projection lands on a face facing another
  // way (the far side of a thin wall) is refused. The best cage seen is kept.
  // Only quads around moved vertices are tested again after a round; a repair that has not
  // improved for 8 rounds stops.
  std::vector<char> is_bad(nq, 0);
  for (int q = 0; q < nq; ++q) is_bad[q] = bad(q);
  auto bad_quads = [&] {
    std::vector<int> list;
    for (int q = 0; q < nq; ++q)
      if (is_bad[q]) list.push_back(q);
    return list;
  };
  std::vector<int> current = bad_quads();
  Eigen::MatrixX3d best = cage.vertices;
  std::vector<char> best_is_bad = is_bad;
  size_t best_bad = current.size();
  std::set<int> moved_ever;
  for (int round = 0, stale = 0; round < max_rounds && !current.empty() && stale < 8; ++round) {
    std::set<int> region;
    for (int q : current)
      for (int k = 0; k < 4; ++k) region.insert(cage.quads(q, k));
    for (int ring = 0; ring < 1 + round / 4; ++ring) {
      std::set<int> grown = region;
      for (int v : region) grown.insert(neighbours[v].begin(), neighbours[v].end());
      region.swap(grown);
    }
    std::set<int> moved_now;
    for (int sweep = 0; sweep < 4; ++sweep)
      for (int v : region) {
        if (fixed[v] || neighbours[v].empty()) continue;
        Vec3 normal;
        const Vec3 at = locator.closest(point(v), &normal, &hint[v]);
        Vec3 mean = Vec3::Zero();
        for (int w : neighbours[v]) mean += point(w);
        mean /= static_cast<double>(neighbours[v].size());
        Vec3 step = mean - at;
        step -= step.dot(normal) * normal;
        Vec3 landed_normal;
        int landed_hint = hint[v];
        const Vec3 landed = locator.closest(at + step, &landed_normal, &landed_hint);
        if (landed_normal.dot(normal) < 0.5) continue;
        hint[v] = landed_hint;
        cage.vertices.row(v) = landed.transpose();
        moved_now.insert(v);
      }
    for (int v : moved_now)
      for (int q : quads_of[v]) is_bad[q] = bad(q);
    moved_ever.insert(moved_now.begin(), moved_now.end());
    current = bad_quads();
    ++stale;
    if (current.size() < best_bad)
      best_bad = current.size(), best = cage.vertices, best_is_bad = is_bad, stale = 0;
  }
  cage.vertices = best;
  is_bad = best_is_bad;
  *still_bad = bad_quads();
  return moved_ever;
}




int remove_doublets(QuadCage& cage) {
  int removed_total = 0;
  for (int pass = 0; pass < 8; ++pass) {
    const int nv = static_cast<int>(cage.vertices.rows());
    CageEdit edit(cage);
    const auto& fixed = edit.incidence.on_chain;
    const auto& quads_of = edit.incidence.quads_of;
    auto& touched = edit.touched;
    int now = 0;
    for (int v = 0; v < nv; ++v) {
      if (fixed[v] || quads_of[v].size() != 2) continue;
      const int q1 = quads_of[v][0], q2 = quads_of[v][1];
      const auto a = corners_from(cage, q1, v);  // v, b, x, a
      const auto b = corners_from(cage, q2, v);  // v, a, y, b
      if (b[1] != a[3] || b[3] != a[1] || a[2] == b[2]) continue;
      bool busy = false;
      for (int k = 0; k < 4; ++k) busy |= touched[a[k]] || touched[b[k]];
      if (busy) continue;
      for (int k = 0; k < 4; ++k) touched[a[k]] = touched[b[k]] = 1;
      // The two quads become one: b, x, a, y.
      cage.quads(q1, 0) = a[1], cage.quads(q1, 1) = a[2], cage.quads(q1, 2) = a[3],
                     cage.quads(q1, 3) = b[2];
      edit.removed[q2] = 1;
      edit.merged_into[v] = -2;
      ++now;
    }
    if (!now) break;
    edit.apply(cage);
    removed_total += now;
  }
  return removed_total;
}

int relax_cage(const CageChecks& checks, QuadCage& cage, int sweeps, double step,
               const Dropped& dropped, const std::vector<char>* held) {
  const ComponentLocator& locator = checks.locator;
  const DesignNormals& normals = checks.normals;
  const int nv = static_cast<int>(cage.vertices.rows());
  const CageIncidence incidence(cage);
  const auto& neighbours = incidence.neighbours;
  const auto& fixed = incidence.on_chain;
  const auto& quads_of = incidence.quads_of;
  int moved = 0;
  // Each vertex's and quad centroid's last triangle (ComponentLocator::closest).
  std::vector<int> hint(nv, -1), quad_hint(cage.quads.rows(), -1);
  for (int sweep = 0; sweep < sweeps; ++sweep) {
    dropped.check();
    moved = 0;
    for (int v = 0; v < nv; ++v) {
      if (fixed[v] || neighbours[v].empty() || (held && (*held)[v])) continue;
      const Vec3 old = cage.vertices.row(v).transpose();
      Vec3 normal;
      const Vec3 at = locator.closest(old, &normal, &hint[v]);
      Vec3 mean = Vec3::Zero();
      for (int w : neighbours[v]) mean += cage.vertices.row(w).transpose();
      mean /= static_cast<double>(neighbours[v].size());
      Vec3 d = step * (mean - at);
      d -= d.dot(normal) * normal;
      Vec3 landed_normal;
      int landed_hint = hint[v];
      const Vec3 landed = locator.closest(at + d, &landed_normal, &landed_hint);
      if (landed_normal.dot(normal) < 0.5) continue;
      cage.vertices.row(v) = landed.transpose();
      bool ok = true;
      for (int q : quads_of[v])
        ok = ok && !quad_is_bad(locator, normals, cage, q, kMinCornerDegrees, &quad_hint[q]);
      if (!ok) {
        cage.vertices.row(v) = old.transpose();
      } else {
        hint[v] = landed_hint;
        ++moved;
      }
    }
  }
  return moved;
}



int collapse_diagonals(const ComponentLocator& locator, QuadCage& cage,
                       const std::vector<int>& bad, const std::vector<int>& diagonal,
                       std::vector<int>* done, bool doublets) {
  CageEdit edit(cage);
  const auto& fixed = edit.incidence.on_chain;
  const auto& quads_of = edit.incidence.quads_of;
  auto& touched = edit.touched;
  int collapsed = 0;
  for (size_t i = 0; i < bad.size(); ++i) {
    const int q = bad[i];
    int best_k = -1;
    double best_length = 1e300;
    for (int k = 0; k < 2; ++k) {
      if (!diagonal.empty() && diagonal[i] != k) continue;
      const int a = cage.quads(q, k), c = cage.quads(q, k + 2);
      if ((fixed[a] && fixed[c]) || touched[a] || touched[c]) continue;
      bool shared = false;  // another quad holding both ends
      for (int r : quads_of[a])
        if (r != q)
          for (int j = 0; j < 4; ++j) shared |= cage.quads(r, j) == c;
      // The other two corners lose a quad: no interior vertex may drop below 3 quads
      // (below 2 with `doublets`).
      const int b = cage.quads(q, k + 1), d = cage.quads(q, (k + 3) % 4);
      if (touched[b] || touched[d]) continue;
      const size_t least = doublets ? 3u : 4u;
      if (quads_of[b].size() < (fixed[b] ? 3u : least) || quads_of[d].size() < (fixed[d] ? 3u : least))
        continue;
      if (shared) continue;
      // The link condition: a and c share no edge neighbour but b and d (after this
      // batch's earlier merges), or two edges would become one, held twice the same way.
      auto now = [&](int v) { return edit.merged_into[v] >= 0 ? edit.merged_into[v] : v; };
      std::set<int> around_a;
      for (int x : edit.incidence.neighbours[a]) around_a.insert(now(x));
      bool linked = false;
      for (int x : edit.incidence.neighbours[c]) {
        const int y = now(x);
        linked |= y != now(b) && y != now(d) && y != a && around_a.count(y) > 0;
      }
      if (linked) continue;
      // Nor may two quads round the merged vertex share three corners (one's diagonal the
      // other's edge): the cage would pinch there, every edge still held twice, and the
      // layout choice would fail.
      // Not in the pass that makes doublets on purpose (their two quads share three
      // corners until remove_doublets joins them).
      if (!doublets && pinches(edit, cage, q, a, c, now)) continue;
      // Into a chain vertex only if the interior end touches no other chain vertex (the
      // merged vertex would join two boundary fans).
      if (fixed[a] || fixed[c]) {
        const int inner = fixed[a] ? c : a, outer = fixed[a] ? a : c;
        bool touches = false;
        for (int r : quads_of[inner])
          for (int j = 0; j < 4; ++j)
            touches |= fixed[cage.quads(r, j)] && cage.quads(r, j) != outer;
        if (touches) continue;
      }
      const double length = (cage.vertices.row(a) - cage.vertices.row(c)).norm();
      if (length < best_length) best_length = length, best_k = k;
    }
    if (best_k < 0) continue;
    int a = cage.quads(q, best_k), c = cage.quads(q, best_k + 2);
    for (int k = 0; k < 4; ++k) touched[cage.quads(q, k)] = 1;
    if (fixed[c]) std::swap(a, c);
    if (!fixed[a]) {  // both interior: the midpoint, on the component
      Vec3 normal;
      const Vec3 mid = 0.5 * (cage.vertices.row(a) + cage.vertices.row(c)).transpose();
      cage.vertices.row(a) = locator.closest(mid, &normal).transpose();
    }  // else the interior end merges into the chain vertex, which stays on its loop
    edit.merged_into[c] = a;
    edit.removed[q] = 1;
    if (done) done->push_back(q);
    ++collapsed;
  }
  if (collapsed) edit.apply(cage);
  return collapsed;
}


int open_squeezed(const CageChecks& checks, QuadCage& cage, int max_rounds) {
  std::vector<int> bad;
  smooth_cage(checks.locator, checks.normals, cage, max_rounds, kMinCornerDegrees, &bad);
  return static_cast<int>(bad.size());
}

int untangle_cage(const CageChecks& checks, QuadCage& cage, int max_rounds, int* collapsed,
                  const Dropped& dropped) {
  const ComponentLocator& locator = checks.locator;
  const DesignNormals& normals = checks.normals;
  std::vector<int> bad;
  int moved = static_cast<int>(
      smooth_cage(locator, normals, cage, max_rounds, kMinCornerDegrees, &bad).size());
  // A fold that smoothing cannot open (a grid cell turned over inside a regular region):
  // take the quad out by collapsing a diagonal, then smooth again, while collapses are
  // possible, at most 32 rounds (a large tangle needs many).
  *collapsed = 0;
  for (int attempt = 0; attempt < 32 && !bad.empty(); ++attempt) {
    dropped.check();
    int now = collapse_diagonals(locator, cage, bad);
    // Its other corners have 3 quads each: collapse anyway and join the doublets left.
    if (!now && (now = collapse_diagonals(locator, cage, bad, {}, nullptr, true)))
      remove_doublets(cage);
    if (!now) break;
    *collapsed += now;
    moved += static_cast<int>(
        smooth_cage(locator, normals, cage, max_rounds, kMinCornerDegrees, &bad).size());
  }
  // No pass opening thin quads after the collapses: it leaves others squeezed; the
  // evening out and squaring open them.
  return moved;
}

}  // namespace genbrep::quad_detail

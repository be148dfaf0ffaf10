// quad/cancel.cpp — irregular vertices the layout left in ± pairs cancelled by diagonal
// collapses, edge rotations and vertex splits (cancel_irregular_pairs).
#include <algorithm>
#include <array>
#include <cmath>
#include <set>
#include <vector>

#include "quad/detail/edit.h"

namespace genbrep::quad_detail {

namespace {

// One round of cancel_irregular_pairs on the candidates of the cage as it is.
int cancel_pairs_once(const CageChecks& checks, QuadCage& cage, int max_attempts) {
  const QuadCage original = cage;
  const CageIncidence incidence(original);
  const auto& fixed = incidence.on_chain;
  auto valence = [&](int v) { return static_cast<int>(incidence.quads_of[v].size()); };
  struct Candidate { int gain, quad, k; };
  std::vector<Candidate> candidates;
  for (int q = 0; q < original.quads.rows(); ++q) {
    int c[4];
    bool interior = true;
    for (int k = 0; k < 4; ++k) c[k] = original.quads(q, k), interior &= !fixed[c[k]];
    if (!interior) continue;
    int before = 0;
    for (int v : c) before += valence(v) != 4;
    for (int k = 0; k < 2; ++k) {
      const int merged = valence(c[k]) + valence(c[k + 2]) - 2;
      const int b = valence(c[k + 1]) - 1, d = valence(c[(k + 3) % 4]) - 1;
      if (merged > 5 || b < 3 || d < 3) continue;
      const int gain = before - ((merged != 4) + (b != 4) + (d != 4));
      if (gain > 0) candidates.push_back({gain, q, k});
    }
  }
  std::stable_sort(candidates.begin(), candidates.end(),
                   [](const Candidate& x, const Candidate& y) { return x.gain > y.gain; });
  auto centroid = [](const QuadCage& c, int q) {
    Vec3 m = Vec3::Zero();
    for (int k = 0; k < 4; ++k) m += 0.25 * c.vertices.row(c.quads(q, k)).transpose();
    return m;
  };
  // A collapse whose neighbourhood cannot be opened again is left out and the rest are
  // tried again from the original cage.
  std::vector<char> excluded(original.quads.rows(), 0);
  std::vector<int> squeezed_before;  // quads already under the 5° bar (above measure's 1°)
  smooth_cage(checks.locator, checks.normals, cage, 0, kMinCornerDegrees, &squeezed_before);
  for (int attempt = 0; attempt < max_attempts; ++attempt) {
    cage = original;
    std::vector<int> quads, diagonals, done;
    for (const Candidate& c : candidates)
      if (!excluded[c.quad]) quads.push_back(c.quad), diagonals.push_back(c.k);
    if (quads.empty() ||
        !collapse_diagonals(checks.locator, cage, quads, diagonals, &done))
      break;
    // The merged vertices sit at diagonal midpoints; the caller evens the cage out
    // (relax_cage). Smoothing here, as after an untangling collapse, would open thin quads
    // elsewhere too and can turn others over, so it is only the second try.
    std::vector<int> strict;
    smooth_cage(checks.locator, checks.normals, cage, 0, kMinCornerDegrees, &strict);
    if (strict.size() > squeezed_before.size()) {
      const QuadCage collapsed = cage;
      std::vector<int> thin;
      smooth_cage(checks.locator, checks.normals, cage, 24, kMinCornerDegrees, &thin);
      strict.clear();
      smooth_cage(checks.locator, checks.normals, cage, 0, kMinCornerDegrees, &strict);
      if (strict.size() > squeezed_before.size()) cage = collapsed;
    }
    if (strict.size() <= squeezed_before.size()) return static_cast<int>(done.size());
    for (int q : strict) {
      const Vec3 at = centroid(cage, q);
      int nearest = -1;
      double best = 1e300;
      for (int d : done) {
        const double distance = (centroid(original, d) - at).norm();
        if (distance < best) best = distance, nearest = d;
      }
      if (nearest >= 0) excluded[nearest] = 1;
    }
  }
  cage = original;
  return 0;
}

}  // namespace

int rotate_edges_for_pairs(const CageChecks& checks, QuadCage& cage) {
  const CageIncidence incidence(cage);
  const auto& fixed = incidence.on_chain;
  std::vector<int> valence(cage.vertices.rows());
  for (int v = 0; v < static_cast<int>(valence.size()); ++v)
    valence[v] = static_cast<int>(incidence.quads_of[v].size());
  // The quad holding the directed edge a → b, and where in it (-1 if none).
  auto holding = [&](int a, int b, int* at) {
    for (int q : incidence.quads_of[a])
      for (int k = 0; k < 4; ++k)
        if (cage.quads(q, k) == a && cage.quads(q, (k + 1) % 4) == b) return *at = k, q;
    return -1;
  };
  struct Rotation { int gain, q1, q2; std::array<int, 4> first, second; int u, w, x, y; };
  std::vector<Rotation> rotations;
  for (int u = 0; u < static_cast<int>(valence.size()); ++u)
    for (int w : incidence.neighbours[u]) {
      if (w < u || fixed[u] || fixed[w] || valence[u] < 4 || valence[w] < 4) continue;
      int k1 = 0, k2 = 0;
      const int q1 = holding(u, w, &k1), q2 = holding(w, u, &k2);
      if (q1 < 0 || q2 < 0 || q1 == q2) continue;
      // q1 = (u, w, a, b), q2 = (w, u, c, d): the hexagon u, c, d, w, a, b.
      const int a = cage.quads(q1, (k1 + 2) % 4), b = cage.quads(q1, (k1 + 3) % 4);
      const int c = cage.quads(q2, (k2 + 2) % 4), d = cage.quads(q2, (k2 + 3) % 4);
      const int ring[6] = {u, c, d, w, a, b};
      bool distinct = true;
      for (int i = 0; i < 6; ++i)
        for (int j = i + 1; j < 6; ++j) distinct &= ring[i] != ring[j];
      if (!distinct) continue;
      auto irregular = [&](int v, int change) { return valence[v] + change != 4; };
      const int before = irregular(u, 0) + irregular(w, 0);
      // The new diagonal c–a (quads c, d, w, a and a, b, u, c) or d–b (d, w, a, b and
      // b, u, c, d): u and w lose a quad, its ends gain one.
      for (int r = 0; r < 2; ++r) {
        const int x = r == 0 ? c : d, y = r == 0 ? a : b;
        if (fixed[x] || fixed[y] || incidence.neighbours[x].count(y)) continue;
        const int gain = before + irregular(x, 0) + irregular(y, 0) -
                         (irregular(u, -1) + irregular(w, -1) + irregular(x, 1) + irregular(y, 1));
        if (gain <= 0) continue;
        Rotation rotation{gain, q1, q2, {}, {}, u, w, x, y};
        if (r == 0) rotation.first = {c, d, w, a}, rotation.second = {a, b, u, c};
        else rotation.first = {d, w, a, b}, rotation.second = {b, u, c, d};
        rotations.push_back(rotation);
      }
    }
  std::stable_sort(rotations.begin(), rotations.end(),
                   [](const Rotation& p, const Rotation& q) { return p.gain > q.gain; });
  // One at a time, no two sharing a quad or a changed vertex; a rotation whose new quads
  // come out squeezed or turned over is undone.
  std::vector<char> touched_quad(cage.quads.rows(), 0), touched_vertex(valence.size(), 0);
  int done = 0;
  for (const Rotation& r : rotations) {
    if (touched_quad[r.q1] || touched_quad[r.q2]) continue;
    if (touched_vertex[r.u] || touched_vertex[r.w] || touched_vertex[r.x] || touched_vertex[r.y])
      continue;
    const Eigen::RowVector4i old1 = cage.quads.row(r.q1), old2 = cage.quads.row(r.q2);
    for (int k = 0; k < 4; ++k) cage.quads(r.q1, k) = r.first[k], cage.quads(r.q2, k) = r.second[k];
    if (quad_is_bad(checks.locator, checks.normals, cage, r.q1, kMinCornerDegrees) ||
        quad_is_bad(checks.locator, checks.normals, cage, r.q2, kMinCornerDegrees)) {
      cage.quads.row(r.q1) = old1, cage.quads.row(r.q2) = old2;
      continue;
    }
    touched_quad[r.q1] = touched_quad[r.q2] = 1;
    for (int v : {r.u, r.w, r.x, r.y}) touched_vertex[v] = 1;
    ++done;
  }
  return done;
}

int split_vertices_for_pairs(const CageChecks& checks, QuadCage& cage) {
  const CageIncidence incidence(cage);
  const auto& fixed = incidence.on_chain;
  const int nv = static_cast<int>(cage.vertices.rows());
  auto valence = [&](int v) { return static_cast<int>(incidence.quads_of[v].size()); };
  auto irregular = [&](int v, int change) { return valence(v) + change != 4; };
  // Quad q's corner after and before v.
  auto next_of = [&](int q, int v) {
    const auto c = corners_from(cage, q, v);
    return std::pair<int, int>{c[1], c[3]};
  };
  struct Split { int gain, u, i; std::array<int, 6> fan; std::array<int, 6> ring; };
  std::vector<Split> splits;
  for (int u = 0; u < nv; ++u) {
    if (fixed[u] || valence(u) != 6) continue;
    // The six quads round u in order: quad j spans ring[j] (after u) to ring[j + 1].
    std::array<int, 6> fan{}, ring{};
    fan[0] = incidence.quads_of[u][0];
    bool closed = true;
    for (int j = 0; j < 6 && closed; ++j) {
      const auto [after, before] = next_of(fan[j], u);
      ring[j] = after;
      if (j == 5) {
        closed = before == ring[0];
        break;
      }
      int next = -1;
      for (int q : incidence.quads_of[u])
        if (next_of(q, u).first == before) next = q;
      closed = next >= 0;
      if (closed) fan[j + 1] = next;
    }
    if (!closed || std::set<int>(ring.begin(), ring.end()).size() != 6) continue;
    for (int i = 0; i < 3; ++i) {
      const int p = ring[i], q = ring[i + 3];
      if (fixed[p] || fixed[q] || incidence.neighbours[p].count(q)) continue;
      const int gain = 1 + irregular(p, 0) + irregular(q, 0) - irregular(p, 1) - irregular(q, 1);
      if (gain > 0) splits.push_back({gain, u, i, fan, ring});
    }
  }
  std::stable_sort(splits.begin(), splits.end(),
                   [](const Split& a, const Split& b) { return a.gain > b.gain; });
  std::vector<char> touched(nv, 0);
  int done = 0;
  for (const Split& split : splits) {
    const int u = split.u, i = split.i, p = split.ring[i], q = split.ring[i + 3];
    bool free = !touched[u];
    for (int j = 0; j < 6; ++j) free &= !touched[split.ring[j]];
    if (!free) continue;
    // u keeps quads i .. i + 2; the new vertex w takes the other three; the new quad
    // (p, u, q, w) fills the gap. Each moves a third of the way towards its side.
    const Vec3 at = cage.vertices.row(u).transpose();
    Vec3 side[2] = {Vec3::Zero(), Vec3::Zero()};
    for (int j = 0; j < 6; ++j)
      for (int k = 0; k < 4; ++k)
        side[j >= i && j < i + 3 ? 0 : 1] += cage.vertices.row(cage.quads(split.fan[j], k)).transpose() / 12.0;
    const int w = static_cast<int>(cage.vertices.rows());
    const int added = static_cast<int>(cage.quads.rows());
    cage.vertices.conservativeResize(w + 1, 3);
    cage.quads.conservativeResize(added + 1, 4);
    // Puts the three quads of w's side back on u (or on w).
    auto give_side = [&](int from, int to) {
      for (int j = 0; j < 6; ++j)
        if (!(j >= i && j < i + 3))
          for (int k = 0; k < 4; ++k)
            if (cage.quads(split.fan[j], k) == from) cage.quads(split.fan[j], k) = to;
    };
    Vec3 normal;
    cage.vertices.row(u) = checks.locator.closest(at + (side[0] - at) / 3, &normal).transpose();
    cage.vertices.row(w) = checks.locator.closest(at + (side[1] - at) / 3, &normal).transpose();
    give_side(u, w);
    cage.quads.row(added) << p, u, q, w;
    bool bad = quad_is_bad(checks.locator, checks.normals, cage, added, kMinCornerDegrees);
    for (int j = 0; j < 6 && !bad; ++j)
      bad = quad_is_bad(checks.locator, checks.normals, cage, split.fan[j], kMinCornerDegrees);
    if (bad) {  // undone: u back where it was, w and the new quad gone
      give_side(w, u);
      cage.vertices.row(u) = at.transpose();
      cage.vertices.conservativeResize(w, 3);
      cage.quads.conservativeResize(added, 4);
      continue;
    }
    touched[u] = 1;
    for (int v : split.ring) touched[v] = 1;
    touched.push_back(1);
    ++done;
  }
  return done;
}

int cancel_irregular_pairs(const CageChecks& checks, QuadCage& cage, int max_rounds,
                           const Dropped& dropped) {
  int total = 0;
  for (int round = 0; round < max_rounds; ++round) {
    dropped.check();
    int now = cancel_pairs_once(checks, cage, 4);
    if (!now) now = rotate_edges_for_pairs(checks, cage);
    if (!now) break;
    total += now;
  }
  // Splits move no other vertex and need no smoothing: after the rounds, until none helps.
  for (int round = 0; round < max_rounds; ++round) {
    const int now = split_vertices_for_pairs(checks, cage);
    if (!now) break;
    total += now;
  }
  return total;
}

}  // namespace genbrep::quad_detail

// fit/refine.cpp — pure-quad local refinement by splitting chords (edge rings).
// A chord is the class of cage edges linked by "opposite in a quad". Splitting every edge
// of a chord at its midpoint cuts each quad it crosses into two (or four where two chords
// cross), so the cage stays pure quad and conforming and every new vertex is regular
// (valence 4 inside, 3 on the boundary). Refinement is local across the chord and global
// along it: the T-NURCC of the paper would stop a ring early, which Blender's Catmull–Clark
// cannot show, so this is the refinement a Blender cage can carry.
#include <algorithm>
#include <map>

#include "fit/fit.h"

namespace genbrep {

QuadCage split_chords(const QuadCage& cage, const std::vector<std::array<int, 2>>& edges) {
  const int quads = static_cast<int>(cage.quads.rows());
  // Edge table in order of first appearance (deterministic).
  std::map<std::pair<int, int>, int> edge_id;
  std::vector<std::array<int, 2>> edge_vertices;
  std::vector<std::array<int, 4>> quad_edges(quads);
  std::vector<std::vector<std::pair<int, int>>> edge_quads;  // (quad, local index)
  for (int q = 0; q < quads; ++q) {
    for (int k = 0; k < 4; ++k) {
      const int a = cage.quads(q, k), b = cage.quads(q, (k + 1) % 4);
      const std::pair<int, int> key{std::min(a, b), std::max(a, b)};
      auto it = edge_id.find(key);
      if (it == edge_id.end()) {
        it = edge_id.emplace(key, static_cast<int>(edge_vertices.size())).first;
        edge_vertices.push_back({key.first, key.second});
        edge_quads.emplace_back();
      }
      quad_edges[q][k] = it->second;
      edge_quads[it->second].emplace_back(q, k);
    }
  }
  // Mark the chords through the seed edges.
  std::vector<char> split(edge_vertices.size(), 0);
  std::vector<int> stack;
  for (const auto& [a, b] : edges) {
    const auto it = edge_id.find({std::min(a, b), std::max(a, b)});
    GENBREP_CHECK(
        it != edge_id.end(), Code::Internal,
        "split_chords: " + std::to_string(a) + "-" + std::to_string(b) + " is not a cage edge");
    if (!split[it->second]) {
      split[it->second] = 1;
      stack.push_back(it->second);
    }
  }
  while (!stack.empty()) {
    const int e = stack.back();
    stack.pop_back();
    for (const auto& [q, k] : edge_quads[e]) {
      const int opposite = quad_edges[q][(k + 2) % 4];
      if (!split[opposite]) {
        split[opposite] = 1;
        stack.push_back(opposite);
      }
    }
  }

  QuadCage out = cage;
  std::vector<Vec3> added;
  const int base = static_cast<int>(cage.vertices.rows());
  std::vector<int> midpoint(edge_vertices.size(), -1);
  for (size_t e = 0; e < edge_vertices.size(); ++e) {
    if (!split[e]) continue;
    midpoint[e] = base + static_cast<int>(added.size());
    added.push_back(
        0.5 * (cage.vertices.row(edge_vertices[e][0]) + cage.vertices.row(edge_vertices[e][1]))
                  .transpose());
  }
  std::vector<std::array<int, 4>> new_quads;
  new_quads.reserve(quads * 2);
  for (int q = 0; q < quads; ++q) {
    const int c[4] = {cage.quads(q, 0), cage.quads(q, 1), cage.quads(q, 2), cage.quads(q, 3)};
    int m[4];
    for (int k = 0; k < 4; ++k) m[k] = midpoint[quad_edges[q][k]];
    const bool cut_u = m[0] >= 0;  // edges 0 and 2 split: the quad is cut across u
    const bool cut_v = m[1] >= 0;  // edges 1 and 3 split
    if (!cut_u && !cut_v) {
      new_quads.push_back({c[0], c[1], c[2], c[3]});
    } else if (cut_u && !cut_v) {
      new_quads.push_back({c[0], m[0], m[2], c[3]});
      new_quads.push_back({m[0], c[1], c[2], m[2]});
    } else if (!cut_u && cut_v) {
      new_quads.push_back({c[0], c[1], m[1], m[3]});
      new_quads.push_back({m[3], m[1], c[2], c[3]});
    } else {
      const int f = base + static_cast<int>(added.size());
      Vec3 centre = Vec3::Zero();
      for (int k = 0; k < 4; ++k) centre += 0.25 * cage.vertices.row(c[k]).transpose();
      added.push_back(centre);
      new_quads.push_back({c[0], m[0], f, m[3]});
      new_quads.push_back({m[0], c[1], m[1], f});
      new_quads.push_back({f, m[1], c[2], m[2]});
      new_quads.push_back({m[3], f, m[2], c[3]});
    }
  }
  out.vertices.resize(base + static_cast<Eigen::Index>(added.size()), 3);
  out.vertices.topRows(base) = cage.vertices;
  for (size_t i = 0; i < added.size(); ++i) out.vertices.row(base + i) = added[i].transpose();
  out.quads.resize(static_cast<Eigen::Index>(new_quads.size()), 4);
  for (size_t q = 0; q < new_quads.size(); ++q) {
    for (int k = 0; k < 4; ++k) out.quads(q, k) = new_quads[q][k];
  }
  auto midpoint_of = [&](int a, int b) {
    const auto it = edge_id.find({std::min(a, b), std::max(a, b)});
    return it == edge_id.end() ? -1 : midpoint[it->second];
  };
  for (auto& chain : out.boundary_chains) {
    std::vector<int> refined;
    for (size_t i = 0; i < chain.size(); ++i) {
      refined.push_back(chain[i]);
      const int m = midpoint_of(chain[i], chain[(i + 1) % chain.size()]);
      if (m >= 0) refined.push_back(m);
    }
    chain = std::move(refined);
  }
  out.crease_edges.clear();
  out.crease_values.clear();
  for (size_t i = 0; i < cage.crease_edges.size(); ++i) {
    const auto [a, b] = cage.crease_edges[i];
    const int m = midpoint_of(a, b);
    if (m < 0) {
      out.crease_edges.push_back({a, b});
      out.crease_values.push_back(cage.crease_values[i]);
    } else {
      out.crease_edges.push_back({a, m});
      out.crease_edges.push_back({m, b});
      out.crease_values.push_back(cage.crease_values[i]);
      out.crease_values.push_back(cage.crease_values[i]);
    }
  }
  return out;
}

}  // namespace genbrep

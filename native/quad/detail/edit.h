// quad/detail/edit.h — internals of quad/: what the cage repairs share (untangle.cpp,
// cancel.cpp, place.cpp, square.cpp): quad corners seen from a vertex, the squeezed-quad test,
// smoothing round bad quads, and a batch of quad removals and vertex merges.
#pragma once
#include <algorithm>
#include <array>
#include <set>
#include <vector>

#include "quad/detail/repair.h"

namespace genbrep::quad_detail {

// Corners under this are "squeezed" here; the validity bar (measure_cage) is 1°, and the
// margin keeps a repaired quad from sitting just above it.
constexpr double kMinCornerDegrees = 5.0;

// The corners of quad q from the one at v on, counter-clockwise: v, the next, the
// opposite, the previous.
std::array<int, 4> corners_from(const QuadCage& cage, int q, int v);
// A quad with a corner under `min_corner_degrees`, or turned over by measure_cage's test
// (turned_over). `hint`: the triangle under the centroid when last looked at
// (ComponentLocator::closest; updated), or null.
bool quad_is_bad(const ComponentLocator& locator, const DesignNormals& normals,
                 const QuadCage& cage, int q, double min_corner_degrees, int* hint = nullptr);
// The smoothing repair; returns the vertices it moved and leaves the best cage it saw.
std::set<int> smooth_cage(const ComponentLocator& locator, const DesignNormals& normals,
                          QuadCage& cage, int max_rounds, double min_corner_degrees,
                          std::vector<int>* still_bad);

// One batch of quad removals and vertex merges on a cage; apply() drops the removed quads
// and every vertex v with merged_into[v] ≥ 0 (its corners move to merged_into[v]) or
// merged_into[v] == -2 (no quad left), and renumbers the vertices, chains and creases.
struct CageEdit {
  explicit CageEdit(const QuadCage& cage)
      : incidence(cage),
        touched(cage.vertices.rows(), 0),
        merged_into(cage.vertices.rows(), -1),
        removed(cage.quads.rows(), 0) {}
  CageIncidence incidence;       // of the cage before the batch
  std::vector<char> touched;     // corners of quads this batch already edited
  std::vector<int> merged_into;  // per vertex: -1 kept, ≥ 0 merged into, -2 dropped
  std::vector<char> removed;     // per quad

  void apply(QuadCage& cage) const {
    const int nv = static_cast<int>(cage.vertices.rows());
    std::vector<int> new_id(nv, -1);
    int kept = 0;
    for (int v = 0; v < nv; ++v)
      if (merged_into[v] == -1) new_id[v] = kept++;
    auto id = [&](int v) { return new_id[merged_into[v] >= 0 ? merged_into[v] : v]; };
    Vertices vertices(kept, 3);
    for (int v = 0; v < nv; ++v)
      if (new_id[v] >= 0) vertices.row(new_id[v]) = cage.vertices.row(v);
    Quads quads(static_cast<int>(std::count(removed.begin(), removed.end(), char(0))), 4);
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
  }
};

// Whether merging c into a (collapsing quad q along its diagonal a–c) leaves two quads
// round the merged vertex sharing three corners; `now` maps a vertex to what this batch's
// earlier merges made of it.
template <class Now>
bool pinches(const CageEdit& edit, const QuadCage& cage, int q, int a, int c, Now now) {
  std::vector<std::array<int, 4>> round;
  for (int end : {a, c})
    for (int r : edit.incidence.quads_of[end]) {
      if (r == q) continue;
      std::array<int, 4> corners;
      for (int j = 0; j < 4; ++j) {
        const int y = now(cage.quads(r, j));
        corners[j] = y == c ? a : y;
      }
      round.push_back(corners);
    }
  for (size_t x = 0; x < round.size(); ++x)
    for (size_t y = x + 1; y < round.size(); ++y) {
      int common = 0;
      for (int i : round[x])
        for (int j : round[y]) common += i == j;
      if (common >= 3) return true;
    }
  return false;
}

}  // namespace genbrep::quad_detail

// pipeline/recompose.cpp — what recompose() needs to know about an edited cage: that it is
// a quad mesh that can bound a sheet, its boundary loops, and the solids each loop borders.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <set>

#include "core/numbers.h"
#include "pipeline/pipeline.h"
#include "pull/pull.h"

namespace genbrep {

namespace {

std::string who(const std::string& name) { return "cage '" + name + "'"; }

std::string number(double x) { return format_number(x); }

}  // namespace

QuadCage cage_from_polygons(const PolygonSoup& polygons, const std::string& name) {
  std::map<int, int> by_corners;  // corner count → faces, for faces that are not quads
  for (int f = 0; f < polygons.face_count(); ++f) {
    const int corners = polygons.offsets[f + 1] - polygons.offsets[f];
    if (corners != 4) ++by_corners[corners];
  }
  if (!by_corners.empty()) {
    std::string counts;
    for (const auto& [corners, faces] : by_corners) {
      counts += (counts.empty() ? "" : ", ") + std::to_string(faces) + (faces == 1 ? " face has " : " faces have ") +
                std::to_string(corners) + " corners";
    }
    throw Error(Code::InvalidInput, who(name) + " is not a quad mesh: " + counts);
  }
  QuadCage cage;
  cage.vertices = polygons.vertices;
  cage.quads.resize(polygons.face_count(), 4);
  for (int f = 0; f < polygons.face_count(); ++f) {
    for (int k = 0; k < 4; ++k) cage.quads(f, k) = polygons.indices[polygons.offsets[f] + k];
  }
  return cage;
}

QuadCage with_boundary_chains(const QuadCage& input, const std::string& name) {
  const int n = static_cast<int>(input.vertices.rows());
  GENBREP_CHECK(input.quads.rows() > 0, Code::InvalidInput, who(name) + " has no faces");
  GENBREP_CHECK(input.vertices.allFinite(), Code::InvalidInput, who(name) + " has vertex coordinates that are not finite");
  int repeated = 0;
  for (Eigen::Index q = 0; q < input.quads.rows(); ++q) {
    std::set<int> corners;
    for (int k = 0; k < 4; ++k) {
      const int v = input.quads(q, k);
      GENBREP_CHECK(v >= 0 && v < n, Code::InvalidInput,
                    who(name) + " has a face corner index " + std::to_string(v) + " out of range (" +
                        std::to_string(n) + " vertices)");
      corners.insert(v);
    }
    repeated += corners.size() != 4;
  }
  GENBREP_CHECK(repeated == 0, Code::InvalidInput,
                who(name) + " has " + std::to_string(repeated) + " faces with a repeated corner");
  // Drop vertices no quad uses (Blender keeps loose vertices after deleting faces).
  QuadCage cage = input;
  std::vector<int> index(static_cast<size_t>(n), -1);
  int used = 0;
  for (Eigen::Index q = 0; q < input.quads.rows(); ++q) {
    for (int k = 0; k < 4; ++k) {
      int& i = index[input.quads(q, k)];
      if (i < 0) i = used++;
      cage.quads(q, k) = i;
    }
  }
  cage.vertices.resize(used, 3);
  for (int v = 0; v < n; ++v) {
    if (index[v] >= 0) cage.vertices.row(index[v]) = input.vertices.row(v);
  }
  cage.crease_edges.clear();
  cage.crease_values.clear();
  for (size_t e = 0; e < input.crease_edges.size() && e < input.crease_values.size(); ++e) {
    const auto& [a, b] = input.crease_edges[e];
    if (a < 0 || b < 0 || a >= n || b >= n || index[a] < 0 || index[b] < 0) continue;
    cage.crease_edges.push_back({index[a], index[b]});
    cage.crease_values.push_back(input.crease_values[e]);
  }
  // Halfedges: each directed edge once, each edge in at most two quads of opposite turn.
  std::map<std::pair<int, int>, int> halfedges;
  for (Eigen::Index q = 0; q < cage.quads.rows(); ++q) {
    for (int k = 0; k < 4; ++k) ++halfedges[{cage.quads(q, k), cage.quads(q, (k + 1) % 4)}];
  }
  int bad_edges = 0;
  std::map<int, std::vector<int>> boundary_next;  // tail → heads of boundary halfedges
  for (const auto& [e, count] : halfedges) {
    if (count > 1) ++bad_edges;
    if (halfedges.count({e.second, e.first}) == 0) boundary_next[e.first].push_back(e.second);
  }
  GENBREP_CHECK(bad_edges == 0, Code::InvalidInput,
                who(name) + " is not 2-manifold: " + std::to_string(bad_edges) +
                    " edges are used twice in the same direction (three or more faces, or flipped faces)");
  GENBREP_CHECK(!boundary_next.empty(), Code::InvalidInput,
                who(name) + " is closed: it has no boundary loop that could lie on a solid");
  int pinched = 0;
  for (const auto& [v, heads] : boundary_next) pinched += heads.size() > 1;
  GENBREP_CHECK(pinched == 0, Code::InvalidInput,
                who(name) + " has " + std::to_string(pinched) + " vertices where its boundary touches itself");
  // Boundary loops, in the quads' direction (organic side on the left), smallest vertex first.
  cage.boundary_chains.clear();
  std::set<int> visited;
  for (const auto& [start, heads] : boundary_next) {
    if (visited.count(start)) continue;
    std::vector<int> chain;
    for (int v = start; !visited.count(v); v = boundary_next.at(v)[0]) {
      visited.insert(v);
      chain.push_back(v);
      GENBREP_CHECK(boundary_next.count(v), Code::InvalidInput, who(name) + " has a boundary that does not close");
    }
    GENBREP_CHECK(chain.size() >= 3, Code::InvalidInput, who(name) + " has a boundary loop of fewer than 3 edges");
    cage.boundary_chains.push_back(std::move(chain));
  }
  cage.chain_loop.assign(cage.boundary_chains.size(), -1);
  return cage;
}

std::vector<std::vector<int>> chain_solids_by_proximity(const QuadCage& cage, const SolidSet& solids,
                                                        const std::string& name, int samples_per_edge) {
  GENBREP_CHECK(solids.size() > 0, Code::InvalidInput, "recompose needs the solids the cages end on");
  double edge_sum = 0;
  for (Eigen::Index q = 0; q < cage.quads.rows(); ++q) {
    for (int k = 0; k < 4; ++k) {
      edge_sum += (cage.vertices.row(cage.quads(q, k)) - cage.vertices.row(cage.quads(q, (k + 1) % 4))).norm();
    }
  }
  const double mean_edge = edge_sum / (4.0 * static_cast<double>(cage.quads.rows()));
  const OrganicSheet sheet = cage_sheet(cage, {}, samples_per_edge);
  std::vector<std::vector<int>> out;
  for (size_t l = 0; l < sheet.loops.size(); ++l) {
    std::set<int> nearest;
    double farthest = 0;
    for (int v : sheet.loops[l].vertices) {
      const Vec3 p = sheet.mesh.vertices.row(v).transpose();
      double best = std::numeric_limits<double>::infinity();
      int best_solid = 0;
      for (int j = 0; j < solids.size(); ++j) {
        const double d = std::abs(solids.surface(j).signed_distance(p));
        if (d < best) best = d, best_solid = j;
      }
      nearest.insert(best_solid);
      farthest = std::max(farthest, best);
    }
    GENBREP_CHECK(farthest <= 3 * mean_edge, Code::InvalidInput,
                  who(name) + " is open: its boundary loop " + std::to_string(l) + " (" +
                      std::to_string(cage.boundary_chains[l].size()) + " edges) reaches " + number(farthest) +
                      " from every solid (more than 3 cage edge lengths, " + number(3 * mean_edge) +
                      "); every boundary loop must end on a keep-in, keep-out or seed");
    out.emplace_back(nearest.begin(), nearest.end());
  }
  return out;
}

}  // namespace genbrep

// quad/fill.cpp — the grid filling of every quantized patch (quad/quad.h step 3).
// Arcs are sampled once, by arc length, and every patch that borders an arc uses those
// samples: neighbouring grids share their vertices exactly, so the cage is manifold and
// its boundary chains lie on the loops' polylines. A patch's interior comes from a Tutte
// map (mean-value weights, boundary fixed on the integer rectangle): with a convex
// boundary and positive weights the map is a bijection (Floater 2003), so every grid point
// has exactly one preimage on the surface.
#include <Eigen/IterativeLinearSolvers>
#include <Eigen/Sparse>
#include <algorithm>
#include <cmath>
#include <functional>
#include <map>

#include "quad/detail/patches.h"

namespace genbrep::quad_detail {

namespace {

Vec3 sample_arc(const Surface& s, const Arc& arc, double at) {
  double walked = 0;
  for (size_t i = 1; i < arc.vertices.size(); ++i) {
    const Vec3& a = s.point[arc.vertices[i - 1]];
    const Vec3& b = s.point[arc.vertices[i]];
    const double len = (b - a).norm();
    if (walked + len >= at || i + 1 == arc.vertices.size()) {
      const double t = len > 0 ? std::clamp((at - walked) / len, 0.0, 1.0) : 0.0;
      return a + t * (b - a);
    }
    walked += len;
  }
  return s.point[arc.vertices.front()];
}


// The cage fill_patches builds: points shared along arcs, then each patch's grid.
class Filler {
 public:
  Filler(const Surface& s, const PatchLayout& pl);
  void fill_patch(const Patch& patch, std::vector<int>* quad_patch);

  const Surface& s;
  const PatchLayout& pl;
  std::vector<Vec3> points;
  // Arcs quantized to 0 edges merge their end nodes (quantize.cpp): union-find on nodes.
  std::map<int, int> parent;
  int find(int v) {
    auto it = parent.find(v);
    if (it == parent.end() || it->second == v) return v;
    return it->second = find(it->second);
  }
  std::map<int, int> node_id;
  int node(int vertex) {
    const int v = find(vertex);
    auto it = node_id.find(v);
    if (it != node_id.end()) return it->second;
    points.push_back(s.point[v]);
    return node_id[v] = static_cast<int>(points.size()) - 1;
  }
  // Samples 1..count-1 of every arc, in arc order.
  std::vector<int> arc_base;
  int arc_point(int a, int k) {  // sample k in [0, count] along the arc
    const Arc& arc = pl.arcs[a];
    if (k == 0) return node_id.at(find(arc.vertices.front()));
    if (k == arc.count) return node_id.at(find(arc.vertices.back()));
    return arc_base[a] + k - 1;
  }
  std::vector<std::array<int, 4>> quads;
  // Cage points glued because a collapsed patch (two opposite sides quantized to 0) puts
  // samples of its other two sides on the same grid cell.
  std::vector<int> glue;
  int root(int p) {
    return p < static_cast<int>(glue.size()) && glue[p] != p ? glue[p] = root(glue[p]) : p;
  }
  int collapsed = 0;
  int unlocated = 0;
  // Per mesh vertex, stamped with the patch that set them: its map parameter, and its row
  // among the patch's unknowns.
  std::vector<Eigen::Vector2d> uv;
  std::vector<int> uv_stamp, row_stamp, row_of;
  int stamp = 0;
};

Filler::Filler(const Surface& s, const PatchLayout& pl)
    : s(s),
      pl(pl),
      arc_base(pl.arcs.size()),
      uv(s.mesh.n_vertices()),
      uv_stamp(s.mesh.n_vertices(), 0),
      row_stamp(s.mesh.n_vertices(), 0),
      row_of(s.mesh.n_vertices(), -1) {
  for (const Arc& arc : pl.arcs)
    if (arc.count == 0) {
      const int a = find(arc.vertices.front()), b = find(arc.vertices.back());
      if (a != b) parent[std::max(a, b)] = std::min(a, b);
    }
  for (size_t a = 0; a < pl.arcs.size(); ++a) {
    const Arc& arc = pl.arcs[a];
    node(arc.vertices.front());
    node(arc.vertices.back());
    arc_base[a] = static_cast<int>(points.size());
    for (int k = 1; k < arc.count; ++k)
      points.push_back(sample_arc(s, arc, arc.length * k / arc.count));
  }
}

// One patch: its boundary on the integer rectangle, a Tutte map of its interior, and the
// grid's points lifted back to the surface (or a collapsed sliver: counted, no quads).
void Filler::fill_patch(const Patch& patch, std::vector<int>* quad_patch) {
  int extent[4] = {0, 0, 0, 0};
  for (int side = 0; side < 4; ++side)
    for (auto& t : patch.sides[side]) extent[side] += pl.arcs[t.first].count;
  const int A = extent[0], B = extent[1];
  // Boundary of the rectangle: ids of the cage points and the mesh vertices' parameters.
  const Eigen::Vector2d origin[4] = {{0, 0}, {double(A), 0}, {double(A), double(B)}, {0, double(B)}};
  const Eigen::Vector2d step[4] = {{1, 0}, {0, 1}, {-1, 0}, {0, -1}};
  std::vector<std::vector<int>> grid(A + 1, std::vector<int>(B + 1, -1));
  ++stamp;
  auto set_uv = [&](int v, const Eigen::Vector2d& at) { uv[v] = at, uv_stamp[v] = stamp; };
  auto has_uv = [&](int v) { return uv_stamp[v] == stamp; };
  for (int side = 0; side < 4; ++side) {
    double offset = 0;
    for (auto& [a, reversed] : patch.sides[side]) {
      const Arc& arc = pl.arcs[a];
      std::vector<int> vs = arc.vertices;
      if (reversed) std::reverse(vs.begin(), vs.end());
      double walked = 0;
      for (size_t i = 0; i < vs.size(); ++i) {
        if (i) walked += (s.point[vs[i]] - s.point[vs[i - 1]]).norm();
        const double at = offset + arc.count * (arc.length > 0 ? walked / arc.length : 0.0);
        set_uv(vs[i], origin[side] + at * step[side]);
      }
      for (int k = 0; k <= arc.count; ++k) {
        const Eigen::Vector2d g = origin[side] + (offset + k) * step[side];
        int& cell = grid[int(std::lround(g.x()))][int(std::lround(g.y()))];
        const int id = arc_point(a, reversed ? arc.count - k : k);
        if (cell >= 0 && root(cell) != root(id)) {
          const size_t known = glue.size();
          glue.resize(points.size());
          for (size_t p = known; p < glue.size(); ++p) glue[p] = static_cast<int>(p);
          const int x = root(cell), y = root(id);
          glue[std::max(x, y)] = std::min(x, y);
        }
        cell = id;
      }
      offset += arc.count;
    }
  }
  if (A == 0 || B == 0) {
    ++collapsed;
    return;
  }
  // Tutte map of the interior vertices (mean-value weights), numbered as the patch's
  // faces reach them; the rows are written in vertex order.
  std::vector<int> unknown;
  for (int f : patch.faces)
    for (auto v : s.mesh.fv_range(s.mesh.face_handle(f)))
      if (!has_uv(v.idx()) && row_stamp[v.idx()] != stamp) {
        row_stamp[v.idx()] = stamp, row_of[v.idx()] = static_cast<int>(unknown.size());
        unknown.push_back(v.idx());
      }
  if (!unknown.empty()) {
    const int n = static_cast<int>(unknown.size());
    std::vector<int> in_order = unknown;
    std::sort(in_order.begin(), in_order.end());
    std::vector<Eigen::Triplet<double>> triplets;
    Eigen::MatrixX2d rhs = Eigen::MatrixX2d::Zero(n, 2);
    for (int v : in_order) {
      const int row = row_of[v];
      double diagonal = 0;
      for (auto h : s.mesh.voh_range(s.mesh.vertex_handle(v))) {
        const int w = s.to(h.idx());
        const Vec3 e = s.point[w] - s.point[v];
        // Half-angles at v in the faces on either side of the edge v→w.
        const double alpha = s.corner_angle(h.idx());
        const double beta = s.corner_angle(s.mesh.next_halfedge_handle(
            s.mesh.opposite_halfedge_handle(s.mesh.halfedge_handle(h.idx()))).idx());
        const double weight =
            (std::tan(0.5 * alpha) + std::tan(0.5 * beta)) / std::max(e.norm(), 1e-300);
        diagonal += weight;
        if (row_stamp[w] == stamp) {
          triplets.emplace_back(row, row_of[w], -weight);
        } else {
          GENBREP_CHECK(has_uv(w), Code::StageFailure,
                        "quad: component " + std::to_string(s.component) +
                            ": a patch's interior reaches past its boundary");
          rhs.row(row) += weight * uv[w].transpose();
        }
      }
      triplets.emplace_back(row, row, diagonal);
    }
    Eigen::SparseMatrix<double> matrix(n, n);
    matrix.setFromTriplets(triplets.begin(), triplets.end());
    // Diagonally dominant (an M-matrix): BiCGSTAB with a diagonal preconditioner converges
    // in a few dozen iterations, where a sparse LU's set-up per patch would dominate the fill
    // (thousands of patches of about 100 unknowns); LU if it does not.
    Eigen::MatrixX2d solution(n, 2);
    bool solved = true;
    {
      Eigen::BiCGSTAB<Eigen::SparseMatrix<double>, Eigen::DiagonalPreconditioner<double>> iterative;
      iterative.setTolerance(1e-12);
      iterative.compute(matrix);
      for (int k = 0; k < 2 && solved; ++k) {
        solution.col(k) = iterative.solve(rhs.col(k));
        solved = iterative.info() == Eigen::Success;
      }
    }
    if (!solved) {
      Eigen::SparseLU<Eigen::SparseMatrix<double>> solver;
      solver.compute(matrix);
      GENBREP_CHECK(solver.info() == Eigen::Success, Code::StageFailure,
                    "quad: component " + std::to_string(s.component) +
                        ": the Tutte map of a patch is singular");
      solution = solver.solve(rhs);
    }
    for (int row = 0; row < n; ++row) set_uv(unknown[row], solution.row(row).transpose());
  }
  // Lift the interior grid points: each triangle claims the integer points it contains.
  std::vector<std::vector<double>> quality(A + 1, std::vector<double>(B + 1, -1e300));
  std::vector<std::vector<Vec3>> lifted(A + 1, std::vector<Vec3>(B + 1, Vec3::Zero()));
  for (int f : patch.faces) {
    int c[3], k = 0;
    for (auto v : s.mesh.fv_range(s.mesh.face_handle(f))) c[k++] = v.idx();
    const Eigen::Vector2d p0 = uv[c[0]], p1 = uv[c[1]], p2 = uv[c[2]];
    const double area = (p1 - p0).x() * (p2 - p0).y() - (p1 - p0).y() * (p2 - p0).x();
    if (std::abs(area) < 1e-300) continue;
    const Eigen::Vector2d lo = p0.cwiseMin(p1).cwiseMin(p2), hi = p0.cwiseMax(p1).cwiseMax(p2);
    for (int i = std::max(1, int(std::ceil(lo.x() - 1e-9))); i <= std::min(A - 1, int(std::floor(hi.x() + 1e-9))); ++i)
      for (int j = std::max(1, int(std::ceil(lo.y() - 1e-9))); j <= std::min(B - 1, int(std::floor(hi.y() + 1e-9))); ++j) {
        const Eigen::Vector2d q(i, j);
        auto cross = [](const Eigen::Vector2d& a, const Eigen::Vector2d& b) { return a.x() * b.y() - a.y() * b.x(); };
        const double b0 = cross(p1 - q, p2 - q) / area, b1 = cross(p2 - q, p0 - q) / area;
        const double b2 = 1 - b0 - b1;
        const double worst = std::min({b0, b1, b2});
        if (worst > quality[i][j]) {
          quality[i][j] = worst;
          lifted[i][j] = b0 * s.point[c[0]] + b1 * s.point[c[1]] + b2 * s.point[c[2]];
        }
      }
  }
  for (int i = 1; i < A; ++i)
    for (int j = 1; j < B; ++j) {
      if (quality[i][j] < -1e-6) ++unlocated;
      points.push_back(lifted[i][j]);
      grid[i][j] = static_cast<int>(points.size()) - 1;
    }
  for (int i = 0; i < A; ++i)
    for (int j = 0; j < B; ++j)
      quads.push_back({grid[i][j], grid[i + 1][j], grid[i + 1][j + 1], grid[i][j + 1]});
  if (quad_patch) quad_patch->resize(quads.size(), static_cast<int>(&patch - pl.patches.data()));
}

}  // namespace

QuadCage fill_patches(const Surface& s, const Layout& layout, const PatchLayout& pl,
                      Messages& messages, std::vector<int>* quad_patch) {
  QuadCage cage;
  cage.component = s.component;
  Filler f(s, pl);
  for (const Patch& patch : pl.patches) f.fill_patch(patch, quad_patch);
  std::vector<Vec3>& points = f.points;
  std::vector<std::array<int, 4>>& quads = f.quads;
  const int unlocated = f.unlocated, collapsed = f.collapsed;
  auto root = [&](int p) { return f.root(p); };
  auto arc_point = [&](int a, int k) { return f.arc_point(a, k); };
  if (unlocated)
    messages.warnings.push_back("component " + std::to_string(s.component) + ": " +
                          std::to_string(unlocated) +
                          " grid points fell outside their patch's map (lifted to the nearest)");
  if (collapsed)
    messages.notes.push_back("component " + std::to_string(s.component) + ": " +
                          std::to_string(collapsed) +
                          " sliver patches collapsed (opposite sides quantized to 0)");
  // Compact the glued points.
  std::vector<int> index(points.size(), -1);
  std::vector<Vec3> kept;
  for (size_t p = 0; p < points.size(); ++p)
    if (root(static_cast<int>(p)) == static_cast<int>(p)) index[p] = static_cast<int>(kept.size()), kept.push_back(points[p]);
  auto id = [&](int p) { return index[root(p)]; };
  cage.vertices.resize(static_cast<Eigen::Index>(kept.size()), 3);
  for (size_t i = 0; i < kept.size(); ++i) cage.vertices.row(i) = kept[i].transpose();
  cage.quads.resize(static_cast<Eigen::Index>(quads.size()), 4);
  for (size_t q = 0; q < quads.size(); ++q)
    for (int k = 0; k < 4; ++k) cage.quads(q, k) = id(quads[q][k]);
  for (size_t c = 0; c < layout.curves.size(); ++c) {
    if (!layout.curves[c].closed) continue;
    std::vector<int> chain;
    for (int a : pl.loop_arcs[c])
      for (int k = 0; k < pl.arcs[a].count; ++k) chain.push_back(id(arc_point(a, k)));
    cage.boundary_chains.push_back(chain);
    cage.chain_loop.push_back(layout.curves[c].loop);
  }
  return cage;
}

}  // namespace genbrep::quad_detail

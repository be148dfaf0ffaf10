// pull/cage.cpp — §7.2 on a fitted cage: pull the limit boundary of every chain into its
// solids, fade the move into the quad graph, tessellate the limit surface as the sheet.
#include <Eigen/Sparse>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <tuple>

#include "fit/fit.h"
#include "pull/detail/side.h"
#include "pull/pull.h"

namespace genbrep {

namespace {

// (quad, k) per directed cage edge a→b: the quad whose corner k is a and k+1 is b.
std::map<std::pair<int, int>, std::pair<int, int>> directed_edges(const Quads& quads) {
  std::map<std::pair<int, int>, std::pair<int, int>> out;
  for (Eigen::Index q = 0; q < quads.rows(); ++q) {
    for (int k = 0; k < 4; ++k) out[{quads(q, k), quads(q, (k + 1) % 4)}] = {static_cast<int>(q), k};
  }
  return out;
}

// Quad parameters of the point at fraction t along the quad's edge k (fit/'s convention).
void edge_uv(int k, double t, double* u, double* v) {
  const double us[4] = {t, 1, 1 - t, 0}, vs[4] = {0, t, 1, 1 - t};
  *u = us[k];
  *v = vs[k];
}

// The curve of one chain over all cage control points: the limit points at t = j/n on
// each chain edge and `sub` points on each chord between consecutive ones (the polyline
// the tessellation shows). Weights below 1e-14 (cancelled phantom points) are dropped.
BoundaryCurve chain_curve(const LimitSurface& surface, const std::vector<int>& chain,
                          const std::map<std::pair<int, int>, std::pair<int, int>>& edges, int n, int sub) {
  std::vector<LimitWeights> limit;  // limit samples along the whole chain
  for (size_t i = 0; i < chain.size(); ++i) {
    const auto it = edges.find({chain[i], chain[(i + 1) % chain.size()]});
    GENBREP_CHECK(it != edges.end(), Code::Internal, "a boundary chain edge is not a cage edge");
    for (int j = 0; j < n; ++j) {
      double u, v;
      edge_uv(it->second.second, static_cast<double>(j) / n, &u, &v);
      limit.push_back(surface.weights(it->second.first, u, v));
    }
  }
  BoundaryCurve curve;
  curve.control_count = surface.control_point_count();
  for (size_t s = 0; s < limit.size(); ++s) {
    const LimitWeights& a = limit[s];
    const LimitWeights& b = limit[(s + 1) % limit.size()];
    for (int m = 0; m < sub; ++m) {
      const double t = static_cast<double>(m) / sub;
      std::map<int, double> w;
      for (const auto& [i, x] : a) w[i] += (1 - t) * x;
      for (const auto& [i, x] : b) w[i] += t * x;
      for (const auto& [i, x] : w) {
        if (std::abs(x) < 1e-14) continue;
        curve.controls.push_back(i);
        curve.weights.push_back(x);
      }
      curve.offsets.push_back(static_cast<int>(curve.controls.size()));
    }
  }
  return curve;
}

Vec3 triangle_normal(const TriangleMesh& m, Eigen::Index f) {
  const Vec3 a = m.vertices.row(m.triangles(f, 0)), b = m.vertices.row(m.triangles(f, 1)),
             c = m.vertices.row(m.triangles(f, 2));
  return (b - a).cross(c - a);
}

}  // namespace

OrganicSheet cage_sheet(const QuadCage& cage, const std::vector<std::vector<int>>& chain_solids,
                        int samples_per_edge) {
  const int n = std::max(1, samples_per_edge);
  OrganicSheet sheet;
  sheet.component = cage.component;
  sheet.mesh = tessellate_limit(cage, n);
  // Boundary halfedges of the tessellation (used by one triangle), tail → head.
  std::map<std::pair<int, int>, int> count;
  for (Eigen::Index f = 0; f < sheet.mesh.triangles.rows(); ++f) {
    for (int k = 0; k < 3; ++k) ++count[{sheet.mesh.triangles(f, k), sheet.mesh.triangles(f, (k + 1) % 3)}];
  }
  std::map<int, int> next;
  for (const auto& [e, c] : count) {
    if (count.count({e.second, e.first}) == 0) next[e.first] = e.second;
  }
  // Cage corners come first in the tessellation: a chain's vertex i is tessellation vertex i.
  for (size_t c = 0; c < cage.boundary_chains.size(); ++c) {
    const auto& chain = cage.boundary_chains[c];
    SheetLoop loop;
    loop.solids = c < chain_solids.size() ? chain_solids[c] : std::vector<int>{};
    loop.partition_loop = c < cage.chain_loop.size() ? cage.chain_loop[c] : -1;
    int v = chain.empty() ? -1 : chain[0];
    for (size_t i = 0; i < chain.size(); ++i) {
      GENBREP_CHECK(v == chain[i], Code::Internal,
                    "cage chain " + std::to_string(c) + " does not follow the limit tessellation's boundary");
      for (int j = 0; j < n; ++j) {
        loop.vertices.push_back(v);
        const auto it = next.find(v);
        GENBREP_CHECK(it != next.end(), Code::Internal, "a cage chain vertex is not on the tessellation's boundary");
        v = it->second;
      }
    }
    GENBREP_CHECK(chain.empty() || v == chain[0], Code::Internal, "a cage chain does not close on the tessellation");
    sheet.loops.push_back(std::move(loop));
  }
  return sheet;
}

CageRefinement refine_cage_boundary(const QuadCage& cage,
                                    const std::vector<std::array<int, 2>>& edges,
                                    Eigen::Index max_quads) {
  const auto directed = directed_edges(cage.quads);
  const auto key = [](int a, int b) { return std::make_pair(std::min(a, b), std::max(a, b)); };
  // Walk each strip from its boundary edge; collect the undirected edges it cuts.
  std::map<std::pair<int, int>, int> split;  // undirected edge -> new vertex (filled below)
  CageRefinement out;
  for (const auto& e : edges) {
    auto it = directed.find({e[0], e[1]});
    if (it == directed.end()) it = directed.find({e[1], e[0]});
    GENBREP_CHECK(it != directed.end() && directed.count({it->first.second, it->first.first}) == 0,
                  Code::Internal,
                  "refine_cage_boundary: (" + std::to_string(e[0]) + ", " + std::to_string(e[1]) +
                      ") is not a boundary edge of the cage");
    std::set<std::pair<int, int>> crossed;  // (quad, entry edge parity)
    auto [q, k] = it->second;
    while (crossed.insert({q, k % 2}).second) {
      ++out.strip_quads;
      const int a = cage.quads(q, k), b = cage.quads(q, (k + 1) % 4);
      const int c = cage.quads(q, (k + 2) % 4), d = cage.quads(q, (k + 3) % 4);
      split.emplace(key(a, b), -1);
      split.emplace(key(c, d), -1);
      const auto next = directed.find({d, c});  // the quad across the opposite edge
      if (next == directed.end()) break;        // the strip reached the boundary
      std::tie(q, k) = next->second;
    }
  }
  // New vertices: one per cut edge (in edge order), one per quad cut both ways.
  const int n_old = static_cast<int>(cage.vertices.rows());
  std::vector<Vec3> added;
  for (auto& [e, v] : split) {
    v = n_old + static_cast<int>(added.size());
    added.push_back(0.5 * (cage.vertices.row(e.first) + cage.vertices.row(e.second)).transpose());
  }
  // New quads, each with its old quad and the old parameters of its corners.
  using Param = Eigen::Vector2d;
  const Param unit[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  std::vector<std::array<int, 4>> quads;
  std::vector<int> origin;
  std::vector<std::array<Param, 4>> params;
  for (Eigen::Index q = 0; q < cage.quads.rows(); ++q) {
    int c[4], m[4] = {-1, -1, -1, -1}, mask = 0;
    Param pc[4], pm[4];
    for (int k = 0; k < 4; ++k) {
      c[k] = cage.quads(q, k);
      pc[k] = unit[k];
      pm[k] = 0.5 * (unit[k] + unit[(k + 1) % 4]);
      const auto it = split.find(key(cage.quads(q, k), cage.quads(q, (k + 1) % 4)));
      if (it != split.end()) m[k] = it->second, mask |= 1 << k;
    }
    const auto add = [&](std::array<int, 4> corners, std::array<Param, 4> p) {
      quads.push_back(corners);
      origin.push_back(static_cast<int>(q));
      params.push_back(p);
    };
    if (mask == 0) {
      add({c[0], c[1], c[2], c[3]}, {pc[0], pc[1], pc[2], pc[3]});
    } else if (mask == 0b0101 || mask == 0b1010) {
      const int k = mask == 0b0101 ? 0 : 1, k1 = (k + 1) % 4, k2 = (k + 2) % 4, k3 = (k + 3) % 4;
      add({c[k], m[k], m[k2], c[k3]}, {pc[k], pm[k], pm[k2], pc[k3]});
      add({m[k], c[k1], c[k2], m[k2]}, {pm[k], pc[k1], pc[k2], pm[k2]});
    } else {
      GENBREP_CHECK(mask == 0b1111, Code::Internal,
                    "refine_cage_boundary: a quad is cut on adjacent edges only");
      const int x = n_old + static_cast<int>(added.size());
      Vec3 centre = Vec3::Zero();
      for (int k = 0; k < 4; ++k) centre += 0.25 * cage.vertices.row(c[k]).transpose();
      added.push_back(centre);
      for (int k = 0; k < 4; ++k) {
        const int l = (k + 3) % 4;
        add({c[k], m[k], x, m[l]}, {pc[k], pm[k], Param(0.5, 0.5), pm[l]});
      }
    }
  }
  QuadCage& r = out.cage;
  r = cage;
  r.vertices.resize(n_old + static_cast<Eigen::Index>(added.size()), 3);
  r.vertices.topRows(n_old) = cage.vertices;
  for (size_t i = 0; i < added.size(); ++i)
    r.vertices.row(n_old + static_cast<Eigen::Index>(i)) = added[i].transpose();
  r.quads.resize(static_cast<Eigen::Index>(quads.size()), 4);
  for (size_t q = 0; q < quads.size(); ++q) {
    for (int k = 0; k < 4; ++k) r.quads(static_cast<Eigen::Index>(q), k) = quads[q][k];
  }
  for (size_t ch = 0; ch < cage.boundary_chains.size(); ++ch) {
    const auto& chain = cage.boundary_chains[ch];
    std::vector<int> refined;
    for (size_t i = 0; i < chain.size(); ++i) {
      refined.push_back(chain[i]);
      const auto it = split.find(key(chain[i], chain[(i + 1) % chain.size()]));
      if (it != split.end()) refined.push_back(it->second);
    }
    out.inserted_per_chain.push_back(static_cast<int>(refined.size() - chain.size()));
    r.boundary_chains[ch] = std::move(refined);
  }
  r.crease_edges.clear();
  r.crease_values.clear();
  for (size_t i = 0; i < cage.crease_edges.size(); ++i) {
    const auto [a, b] = cage.crease_edges[i];
    const float value = i < cage.crease_values.size() ? cage.crease_values[i] : 0.0f;
    const auto it = split.find(key(a, b));
    if (it == split.end()) {
      r.crease_edges.push_back({a, b});
      r.crease_values.push_back(value);
    } else {
      r.crease_edges.push_back({a, it->second});
      r.crease_edges.push_back({it->second, b});
      r.crease_values.insert(r.crease_values.end(), 2, value);
    }
  }
  out.over_limit = max_quads >= 0 && r.quads.rows() > max_quads;
  if (added.empty() || out.over_limit) return out;
  // Least-squares positions of the new points: the new limit closest to the old one on the
  // quads whose limit they influence (quads within one vertex ring of a cut quad).
  const int n_new = static_cast<int>(added.size());
  const int n_all = n_old + n_new;
  std::vector<char> near(static_cast<size_t>(n_all), 0);
  for (size_t q = 0; q < quads.size(); ++q) {
    bool cut = false;
    for (int v : quads[q]) cut = cut || v >= n_old;
    if (cut)
      for (int v : quads[q]) near[v] = 1;
  }
  const LimitSurface before(cage);
  LimitSurface after(r);
  const int m = 4;
  // Normal equations, sparse: each sample couples only the new points in its support.
  std::vector<Eigen::Triplet<double>> entries;
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(n_new, 3);
  struct Sample {
    LimitWeights weights;
    Vec3 target;
  };
  std::vector<Sample> samples;
  // Repeated entries are summed into `normal` every few million, not all kept at once.
  Eigen::SparseMatrix<double> normal(n_new, n_new);
  const auto flush = [&] {
    Eigen::SparseMatrix<double> part(n_new, n_new);
    part.setFromTriplets(entries.begin(), entries.end());  // sums repeated entries
    normal += part;
    entries.clear();
  };
  for (size_t q = 0; q < quads.size(); ++q) {
    bool touched = false;
    for (int v : quads[q]) touched = touched || near[v];
    if (!touched) continue;
    for (int i = 0; i <= m; ++i) {
      for (int j = 0; j <= m; ++j) {
        const double u = static_cast<double>(i) / m, v = static_cast<double>(j) / m;
        const auto& p = params[q];
        const Param old =
            (1 - u) * (1 - v) * p[0] + u * (1 - v) * p[1] + u * v * p[2] + (1 - u) * v * p[3];
        Sample s{after.weights(static_cast<int>(q), u, v), Vec3::Zero()};
        for (const auto& [index, w] : before.weights(origin[q], old.x(), old.y())) {
          s.target += w * cage.vertices.row(index).transpose();
        }
        Vec3 fixed = s.target;
        for (const auto& [index, w] : s.weights) {
          if (index < n_old) fixed -= w * cage.vertices.row(index).transpose();
        }
        for (const auto& [a, wa] : s.weights) {
          if (a < n_old) continue;
          rhs.row(a - n_old) += wa * fixed.transpose();
          for (const auto& [b, wb] : s.weights) {
            if (b >= n_old) entries.emplace_back(a - n_old, b - n_old, wa * wb);
          }
        }
        samples.push_back(std::move(s));
      }
    }
    if (entries.size() > (1u << 22)) flush();
  }
  const double lambda = 1e-6;
  for (int i = 0; i < n_new; ++i) {
    entries.emplace_back(i, i, lambda);
    rhs.row(i) += lambda * added[i].transpose();
  }
  flush();
  const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(normal);
  Eigen::MatrixXd solved;
  if (solver.info() == Eigen::Success) solved = solver.solve(rhs);
  const auto change = [&](const Vertices& points) {
    double worst = 0;
    for (const auto& s : samples) {
      Vec3 p = Vec3::Zero();
      for (const auto& [index, w] : s.weights) p += w * points.row(index).transpose();
      worst = std::max(worst, (p - s.target).norm());
    }
    return worst;
  };
  out.midpoint_change = change(r.vertices);
  if (solved.rows() == n_new && solved.allFinite()) {
    Vertices fitted = r.vertices;
    fitted.bottomRows(n_new) = solved;
    out.limit_change = change(fitted);
    if (out.limit_change <= out.midpoint_change) {
      r.vertices = fitted;
      out.least_squares = true;
      return out;
    }
  }
  out.limit_change = out.midpoint_change;  // the solve did not help: keep the midpoints
  return out;
}

namespace {

// One pull of `cage` (no insertion): the §7.2 descent, the fade, the re-pull rounds.
CagePull pull_once(const QuadCage& cage, const std::vector<std::vector<int>>& chain_solids,
                   const SolidSet& solids, double eta, const PullOptions& options,
                   const std::vector<int>& known_sides) {
  GENBREP_CHECK(chain_solids.size() == cage.boundary_chains.size(), Code::Internal,
                "pull_cage needs the solids of every boundary chain");
  const int n = std::max(1, options.cage_samples_per_edge);
  const int n_points = static_cast<int>(cage.vertices.rows());
  LimitSurface surface(cage);
  const auto edges = directed_edges(cage.quads);
  const OrganicSheet original_sheet = cage_sheet(cage, chain_solids, n);
  const auto adjacency = detail::vertex_adjacency(original_sheet.mesh);
  // Per chain: σ, the distance F = σ·D_S and the sampled limit boundary.
  std::vector<int> sides;
  std::vector<SideDistance> distances;
  std::vector<BoundaryCurve> curves;
  for (size_t c = 0; c < cage.boundary_chains.size(); ++c) {
    const SideDistance probe(solids, chain_solids[c], 1);
    sides.push_back(c < known_sides.size()
                        ? known_sides[c]
                        : detail::organic_side(original_sheet, original_sheet.loops[c], adjacency, probe));
    distances.emplace_back(solids, chain_solids[c], sides.back());
    curves.push_back(chain_curve(surface, cage.boundary_chains[c], edges, n, std::max(1, options.samples_per_edge)));
  }
  // The quad graph and its rings from the chains (ring 0: chain vertices and anything the
  // descent moved).
  std::vector<std::vector<int>> neighbours(static_cast<size_t>(n_points));
  for (Eigen::Index q = 0; q < cage.quads.rows(); ++q) {
    for (int k = 0; k < 4; ++k) {
      const int a = cage.quads(q, k), b = cage.quads(q, (k + 1) % 4);
      neighbours[a].push_back(b);
      neighbours[b].push_back(a);
    }
  }
  const Vertices& original = cage.vertices;
  std::vector<Vec3> controls(static_cast<size_t>(n_points));
  for (int i = 0; i < n_points; ++i) controls[i] = original.row(i).transpose();
  CagePull out;
  out.cage = cage;
  out.sheet.eta = eta;
  std::vector<CurvePull> results(curves.size());
  for (int round = 0; round < 3; ++round) {
    for (size_t c = 0; c < curves.size(); ++c) {
      const CurvePull r = pull_curve(curves[c], distances[c], eta, options, &controls);
      if (round == 0) results[c].max_before = r.max_before;
      results[c].iterations += r.iterations;
    }
    // Ring 0 and its displacement; BFS rings over the quad graph.
    std::vector<int> ring(static_cast<size_t>(n_points), -1);
    for (const auto& chain : cage.boundary_chains) {
      for (int v : chain) ring[v] = 0;
    }
    for (int v = 0; v < n_points; ++v) {
      if ((controls[v] - original.row(v).transpose()).squaredNorm() > 0) ring[v] = 0;
    }
    detail::fill_rings(neighbours, &ring);
    // Linear fade over k rings as in pull_sheet; k doubles while a limit triangle folds.
    for (int k = std::max(1, options.cage_blend_rings);; k *= 2) {
      std::vector<Vec3> move(static_cast<size_t>(n_points), Vec3::Zero());
      for (int v = 0; v < n_points; ++v) {
        if (ring[v] == 0) move[v] = controls[v] - original.row(v).transpose();
      }
      detail::fade_over_rings(neighbours, ring, k, &move);
      out.cage.vertices = original;
      for (int v = 0; v < n_points; ++v) out.cage.vertices.row(v) += move[v].transpose();
      surface.set_control_points(out.cage.vertices);
      const TriangleMesh moved = surface.tessellate(n);
      int folded = 0;
      for (Eigen::Index f = 0; f < moved.triangles.rows(); ++f) {
        folded += triangle_normal(original_sheet.mesh, f).dot(triangle_normal(moved, f)) <= 0;
      }
      out.sheet.blend_rings = k;
      out.sheet.folded_triangles = folded;
      if (folded == 0 || 2 * k > options.cage_max_blend_rings) break;
    }
    // The blend may have moved the limit boundary (interior points in its support): check.
    for (int i = 0; i < n_points; ++i) controls[i] = out.cage.vertices.row(i).transpose();
    bool inside = true;
    PullOptions measure = options;
    measure.max_iterations = 0;
    for (size_t c = 0; c < curves.size(); ++c) {
      std::vector<Vec3> copy = controls;
      const CurvePull check = pull_curve(curves[c], distances[c], eta, measure, &copy);
      results[c].converged = check.converged;
      results[c].max_after = check.max_after;
      results[c].stuck_samples = check.stuck_samples;
      inside = inside && check.converged;
    }
    if (inside) break;
  }
  // The pulled cage's sheet and the per-chain results.
  out.sheet.sheet = cage_sheet(out.cage, chain_solids, n);
  for (size_t c = 0; c < curves.size(); ++c) {
    LoopPull lp;
    lp.side = sides[c];
    lp.curve = results[c];
    for (int v : cage.boundary_chains[c]) {
      lp.max_displacement = std::max(lp.max_displacement, (out.cage.vertices.row(v) - original.row(v)).norm());
    }
    for (int s : lp.curve.stuck_samples) {
      Vec3 p = Vec3::Zero();
      for (int k = curves[c].offsets[s]; k < curves[c].offsets[s + 1]; ++k) {
        p += curves[c].weights[k] * controls[curves[c].controls[k]];
      }
      lp.stuck_points.push_back(p);
    }
    out.sheet.loops.push_back(std::move(lp));
  }
  if (out.sheet.folded_triangles > 0) {
    out.sheet.diagnostics.push_back("cage of organic component " + std::to_string(cage.component) + ": " +
                                    std::to_string(out.sheet.folded_triangles) +
                                    " limit triangles fold after the pull even with " +
                                    std::to_string(out.sheet.blend_rings) + " blend rings");
  }
  return out;
}

}  // namespace

CagePull pull_cage(const QuadCage& cage, const std::vector<std::vector<int>>& chain_solids,
                   const SolidSet& solids, double eta, const PullOptions& options,
                   const std::vector<int>& sides) {
  const int n = std::max(1, options.cage_samples_per_edge),
            sub = std::max(1, options.samples_per_edge);
  QuadCage current = cage;
  std::vector<int> inserted(cage.boundary_chains.size(), 0);
  CagePull out = pull_once(current, chain_solids, solids, eta, options, sides);
  const Eigen::Index quad_limit =
      static_cast<Eigen::Index>(
          std::ceil(options.max_insertion_growth * static_cast<double>(cage.quads.rows()))) +
      64;
  int skipped = 0;  // quads of a refinement not made (over quad_limit)
  for (int round = 0; round < options.max_insertions && !out.sheet.converged(); ++round) {
    // The chain edges whose limit segment holds a stuck sample: chain_curve gives each
    // chain edge n limit samples, each followed by `sub` chord samples.
    std::vector<std::array<int, 2>> edges;
    for (size_t c = 0; c < current.boundary_chains.size(); ++c) {
      const auto& chain = current.boundary_chains[c];
      std::set<int> stuck_edges;
      for (int s : out.sheet.loops[c].curve.stuck_samples) stuck_edges.insert(s / sub / n);
      for (int i : stuck_edges) edges.push_back({chain[i], chain[(i + 1) % chain.size()]});
    }
    if (edges.empty()) break;
    CageRefinement refined = refine_cage_boundary(current, edges, quad_limit);
    // Strips cross the whole component: where most of the boundary is stuck (η deeper than
    // the solid is thick, a gap) refinement would multiply the cage without helping.
    if (refined.over_limit) {
      skipped = static_cast<int>(refined.cage.quads.rows());
      break;
    }
    for (size_t c = 0; c < inserted.size(); ++c) inserted[c] += refined.inserted_per_chain[c];
    current = std::move(refined.cage);
    out = pull_once(current, chain_solids, solids, eta, options, sides);
  }
  std::string counts;
  int total = 0;
  for (size_t c = 0; c < inserted.size(); ++c) {
    out.sheet.loops[c].inserted_vertices = inserted[c];
    total += inserted[c];
    if (inserted[c] > 0)
      counts += (counts.empty() ? "" : ", ") + std::string("chain ") + std::to_string(c) + " +" +
                std::to_string(inserted[c]);
  }
  if (skipped > 0) {
    out.sheet.diagnostics.push_back("cage of organic component " + std::to_string(cage.component) +
                                    ": no further boundary vertex insertion: it would give " +
                                    std::to_string(skipped) + " quads, more than " +
                                    std::to_string(quad_limit) + " (the pull stays unconverged)");
  }
  if (total > 0) {
    out.sheet.diagnostics.push_back(
        "cage of organic component " + std::to_string(cage.component) + ": " +
        std::to_string(total) + " boundary vertices inserted where the pull did not converge (" +
        counts + "), pull " + (out.sheet.converged() ? "converged" : "still not converged"));
  }
  return out;
}

}  // namespace genbrep

// fit/fit.cpp — the three fitting strategies of §6.3 (contract in fit/fit.h).
// Every solve is linear: the limit point at fixed parameters is a fixed linear combination
// of control points (LimitSurface::weights), so the L2 problem with the foot-point
// parameters frozen is a sparse least-squares problem; parameter correction (re-projection)
// between solves makes the alternation converge to a local minimum of the true distance.
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <set>

#include "fit/detail/problem.h"

namespace genbrep {

using namespace fit_detail;

const char* strategy_name(FitStrategy strategy) {
  switch (strategy) {
    case FitStrategy::Smooth:
      return "smooth";
    case FitStrategy::Tight:
      return "tight";
    case FitStrategy::BoundaryTight:
      return "boundary_tight";
  }
  return "?";
}

bool parse_strategy(const std::string& name, FitStrategy* strategy) {
  for (FitStrategy s : {FitStrategy::Smooth, FitStrategy::Tight, FitStrategy::BoundaryTight}) {
    if (name == strategy_name(s)) {
      *strategy = s;
      return true;
    }
  }
  return false;
}

namespace {

using Sparse = Eigen::SparseMatrix<double>;

// Rows of the data term: limit weights, target, weight.
struct Rows {
  std::vector<LimitWeights> weights;
  std::vector<Vec3> targets;
  std::vector<double> w;
  void add(LimitWeights weights_, const Vec3& target, double weight) {
    if (!(weight > 0)) return;
    weights.push_back(std::move(weights_));
    targets.push_back(target);
    w.push_back(weight);
  }
};

// Umbrella fairness: one row per free control point, P_i − mean(neighbours), where a
// boundary-chain vertex's neighbours are its chain neighbours (curve fairness, so the
// boundary is not pulled inwards). Scaled by √(μ / n).
// `stiff` (empty or per control point): a factor on the fairness of that point's row.
Sparse fairness_matrix(const QuadCage& cage, const std::vector<char>& free, double mu,
                       const std::vector<double>& stiff) {
  const int n = static_cast<int>(cage.vertices.rows());
  std::vector<std::set<int>> neighbours(n), chain_neighbours(n);
  for (int q = 0; q < cage.quads.rows(); ++q) {
    for (int k = 0; k < 4; ++k) {
      neighbours[cage.quads(q, k)].insert(cage.quads(q, (k + 1) % 4));
      neighbours[cage.quads(q, (k + 1) % 4)].insert(cage.quads(q, k));
    }
  }
  for (const auto& chain : cage.boundary_chains) {
    for (size_t i = 0; i < chain.size(); ++i) {
      chain_neighbours[chain[i]].insert(chain[(i + 1) % chain.size()]);
      chain_neighbours[chain[(i + 1) % chain.size()]].insert(chain[i]);
    }
  }
  const double scale = std::sqrt(mu / std::max(1, n));
  std::vector<Eigen::Triplet<double>> triplets;
  for (int i = 0; i < n; ++i) {
    if (!free[i]) continue;
    const std::set<int>& ring = chain_neighbours[i].empty() ? neighbours[i] : chain_neighbours[i];
    if (ring.empty()) continue;
    const double row = stiff.empty() ? scale : scale * std::sqrt(stiff[i]);
    triplets.emplace_back(i, i, row);
    for (int j : ring) triplets.emplace_back(i, j, -row / ring.size());
  }
  Sparse f(n, n);
  f.setFromTriplets(triplets.begin(), triplets.end());
  return f;
}

// min Σ w |a·P − target|² + |F P|² over the free control points; the others stay. A
// tiny damping towards the current positions keeps unconstrained points in place.
bool solve(const Rows& rows, const Sparse& fairness, const std::vector<char>& free,
           Vertices* control_points, Diagnostics* diagnostics) {
  const int n = static_cast<int>(control_points->rows());
  std::vector<int> free_index(n, -1);
  int unknowns = 0;
  for (int i = 0; i < n; ++i) {
    if (free[i]) free_index[i] = unknowns++;
  }
  if (unknowns == 0) return true;
  std::vector<Eigen::Triplet<double>> triplets;
  Eigen::MatrixXd rhs_rows(rows.w.size(), 3);
  for (size_t r = 0; r < rows.w.size(); ++r) {
    const double s = std::sqrt(rows.w[r]);
    Vec3 target = rows.targets[r];
    for (const auto& [i, w] : rows.weights[r]) {
      if (free_index[i] >= 0) {
        triplets.emplace_back(static_cast<int>(r), free_index[i], s * w);
      } else {
        target -= w * control_points->row(i).transpose();  // fixed points move to the right
      }
    }
    rhs_rows.row(r) = s * target.transpose();
  }
  Sparse a(static_cast<Eigen::Index>(rows.w.size()), unknowns);
  a.setFromTriplets(triplets.begin(), triplets.end());
  // Fairness: split F into free columns and fixed columns the same way.
  std::vector<Eigen::Triplet<double>> f_free;
  Eigen::MatrixXd f_rhs = Eigen::MatrixXd::Zero(n, 3);
  for (int k = 0; k < fairness.outerSize(); ++k) {
    for (Sparse::InnerIterator it(fairness, k); it; ++it) {
      const int col = static_cast<int>(it.col());
      if (free_index[col] >= 0) {
        f_free.emplace_back(static_cast<int>(it.row()), free_index[col], it.value());
      } else {
        f_rhs.row(it.row()) -= it.value() * control_points->row(col);
      }
    }
  }
  Sparse f(n, unknowns);
  f.setFromTriplets(f_free.begin(), f_free.end());
  Sparse normal = Sparse(a.transpose() * a) + Sparse(f.transpose() * f);
  Eigen::MatrixXd rhs = a.transpose() * rhs_rows + f.transpose() * f_rhs;
  const double mean_diagonal = normal.diagonal().sum() / unknowns;
  const double damping = 1e-9 * (mean_diagonal > 0 ? mean_diagonal : 1.0);
  for (int i = 0; i < n; ++i) {
    if (free_index[i] < 0) continue;
    normal.coeffRef(free_index[i], free_index[i]) += damping;
    rhs.row(free_index[i]) += damping * control_points->row(i);
  }
  Eigen::SimplicialLDLT<Sparse> ldlt(normal);
  if (ldlt.info() != Eigen::Success) {
    diagnostics->push_back("least-squares factorisation failed; positions kept");
    return false;
  }
  const Eigen::MatrixXd x = ldlt.solve(rhs);
  if (ldlt.info() != Eigen::Success || !x.allFinite()) {
    diagnostics->push_back("least-squares solve failed; positions kept");
    return false;
  }
  for (int i = 0; i < n; ++i) {
    if (free_index[i] >= 0) control_points->row(i) = x.row(free_index[i]);
  }
  return true;
}

// The data points are the region's vertices (area-weighted) when there are at least
// `min_points` of them. A region about as coarse as the cage (a density raised to the
// design's resolution) leaves quads without data, which the least squares folds (lattice:
// 1.2 region vertices per control point). Such a region is sampled instead at the
// centroids of its triangles split n×n, n the smallest giving at least `min_points`.
Problem make_problem(const TriangleMesh& region, const std::vector<std::vector<Vec3>>& curves,
                     double boundary_weight, long min_points) {
  Problem p(region);
  const int nv = static_cast<int>(region.vertices.rows());
  std::vector<double> area(nv, 0.0);
  std::vector<double> lengths;
  for (int t = 0; t < region.triangles.rows(); ++t) {
    Vec3 c[3];
    for (int k = 0; k < 3; ++k) {
      const int v = region.triangles(t, k);
      GENBREP_CHECK(v >= 0 && v < nv, Code::InvalidInput,
                    "fit region triangle " + std::to_string(t) + " uses vertex " +
                        std::to_string(v) + " of " + std::to_string(nv));
      c[k] = region.vertices.row(v).transpose();
    }
    const double a = 0.5 * (c[1] - c[0]).cross(c[2] - c[0]).norm();
    for (int k = 0; k < 3; ++k) {
      area[region.triangles(t, k)] += a / 3;
      lengths.push_back((c[(k + 1) % 3] - c[k]).norm());
    }
  }
  double total = 0;
  for (double a : area) total += a;
  GENBREP_CHECK(total > 0, Code::InvalidInput, "fit region has no area");
  for (int v = 0; v < nv; ++v) {
    if (area[v] <= 0) continue;
    p.points.push_back(region.vertices.row(v).transpose());
    p.point_weights.push_back(area[v] / total);
  }
  const long triangles = static_cast<long>(region.triangles.rows());
  if (static_cast<long>(p.points.size()) < min_points) {
    long n = 1;
    while (triangles * n * n < min_points) ++n;
    p.points.clear();
    p.point_weights.clear();
    // Sub-triangle centroids in barycentric steps of 1/n: the upright ones at (i + 1/3,
    // j + 1/3)/n, the inverted ones at (i + 2/3, j + 2/3)/n; each stands for 1/n² of the area.
    std::vector<std::array<double, 2>> at;
    for (long i = 0; i < n; ++i) {
      for (long j = 0; i + j < n; ++j) {
        at.push_back({(i + 1.0 / 3) / n, (j + 1.0 / 3) / n});
        if (i + j < n - 1) at.push_back({(i + 2.0 / 3) / n, (j + 2.0 / 3) / n});
      }
    }
    for (long t = 0; t < triangles; ++t) {
      const Vec3 a = region.vertices.row(region.triangles(t, 0)).transpose();
      const Vec3 b = region.vertices.row(region.triangles(t, 1)).transpose();
      const Vec3 c = region.vertices.row(region.triangles(t, 2)).transpose();
      const double weight = 0.5 * (b - a).cross(c - a).norm() / (total * n * n);
      if (!(weight > 0)) continue;
      for (const auto& [x, y] : at) {
        p.points.push_back(a + x * (b - a) + y * (c - a));
        p.point_weights.push_back(weight);
      }
    }
  }
  std::nth_element(lengths.begin(), lengths.begin() + lengths.size() / 2, lengths.end());
  p.median_edge = lengths[lengths.size() / 2];
  p.curves = curves;
  double curve_total = 0;
  for (size_t c = 0; c < curves.size(); ++c) {
    const auto& curve = curves[c];
    GENBREP_CHECK(curve.size() >= 3, Code::InvalidInput,
                  "fit boundary curve " + std::to_string(c) + " has fewer than 3 points");
    for (size_t i = 0; i < curve.size(); ++i) {
      const double half = 0.5 * ((curve[(i + 1) % curve.size()] - curve[i]).norm() +
                                 (curve[i] - curve[(i + curve.size() - 1) % curve.size()]).norm());
      p.curve_points.push_back(curve[i]);
      p.curve_weights.push_back(half);
      p.curve_chain.push_back(static_cast<int>(c));
      curve_total += half;
    }
  }
  for (double& w : p.curve_weights) w *= boundary_weight / std::max(curve_total, 1e-300);
  return p;
}

// The larger of the two one-sided maxima: what the bound δ is checked against.
double two_sided(const Measurement& m) { return std::max(m.max_design_to_limit, m.max_limit_to_design); }

// State of one cage topology during the fit.
struct Fitting {
  QuadCage cage;
  LimitSurface surface;
  std::vector<std::vector<ChainEdge>> chains;
  Measurement measured;
  explicit Fitting(QuadCage c) : cage(std::move(c)), surface(cage), chains(chain_edges(cage)) {}
};

struct Run {
  const Problem& problem;
  const FitOptions& options;
  const Context& ctx;
  FitReport& report;
  std::vector<double> emphasis;  // per design point weight multiplier (Tight's reweighting)
  std::vector<double> stiff;     // per control point fairness multiplier (fold smoothing)

  // Alternates solves over the `free` control points with re-projection; `use_points`
  // and `use_curves` choose the data terms. Leaves f.measured up to date.
  void alternate(Fitting& f, const std::vector<char>& free, bool use_points, bool use_curves,
                 int rounds = 0) {
    if (rounds <= 0) rounds = options.rounds;
    const Sparse fairness = fairness_matrix(
        f.cage, free, options.fairness_weight,
        stiff.size() == static_cast<size_t>(f.cage.vertices.rows()) ? stiff : std::vector<double>());
    for (int round = 0; round < rounds; ++round) {
      ctx.step("fit", std::min(1.0, 0.1 * report.rounds));
      Rows rows;
      if (use_points) {
        for (size_t i = 0; i < problem.points.size(); ++i) {
          const FootPoint& foot = f.measured.feet[i];
          rows.add(f.surface.weights(foot.quad, foot.u, foot.v), problem.points[i],
                   problem.point_weights[i] * emphasis[i]);
        }
      }
      if (use_curves) {
        for (size_t i = 0; i < problem.curve_points.size(); ++i) {
          const FootPoint& foot = f.measured.curve_feet[i].foot;
          rows.add(f.surface.weights(foot.quad, foot.u, foot.v), problem.curve_points[i],
                   problem.curve_weights[i]);
        }
      }
      report.rounds += 1;
      if (!solve(rows, fairness, free, &f.cage.vertices, &report.diagnostics)) break;
      f.surface.set_control_points(f.cage.vertices);
      f.measured = measure(f.surface, f.chains, problem, options);
    }
  }
};

std::vector<std::array<int, 2>> quad_edges_of(const QuadCage& cage, const std::set<int>& quads) {
  std::vector<std::array<int, 2>> edges;
  for (int q : quads) {
    edges.push_back({cage.quads(q, 0), cage.quads(q, 1)});
    edges.push_back({cage.quads(q, 1), cage.quads(q, 2)});
  }
  return edges;
}

// The quads whose limit surface (tessellated with `samples` segments per quad edge) meets
// the limit surface elsewhere, sorted; exact predicates. A tessellation that is not even an
// oriented manifold (a fold along a cage edge) gives every quad.
std::vector<int> folded_quads(const QuadCage& cage, int samples) {
  using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
  using Mesh = CGAL::Surface_mesh<Kernel::Point_3>;
  const TriangleMesh t = tessellate_limit(cage, samples);
  Mesh mesh;
  std::vector<Mesh::Vertex_index> vertex;
  for (Eigen::Index v = 0; v < t.vertices.rows(); ++v)
    vertex.push_back(mesh.add_vertex(Kernel::Point_3(t.vertices(v, 0), t.vertices(v, 1), t.vertices(v, 2))));
  for (Eigen::Index f = 0; f < t.triangles.rows(); ++f)
    if (mesh.add_face(vertex[t.triangles(f, 0)], vertex[t.triangles(f, 1)], vertex[t.triangles(f, 2)]) ==
        Mesh::null_face()) {
      std::vector<int> all(cage.quads.rows());
      for (size_t q = 0; q < all.size(); ++q) all[q] = static_cast<int>(q);
      return all;
    }
  std::vector<std::pair<Mesh::Face_index, Mesh::Face_index>> pairs;
  CGAL::Polygon_mesh_processing::self_intersections(mesh, std::back_inserter(pairs));
  std::set<int> quads;
  for (const auto& [a, b] : pairs) {
    quads.insert(t.triangle_source[static_cast<size_t>(a)]);
    quads.insert(t.triangle_source[static_cast<size_t>(b)]);
  }
  return std::vector<int>(quads.begin(), quads.end());
}

bool limit_intersects_itself(const QuadCage& cage, int samples) {
  return !folded_quads(cage, samples).empty();
}

}  // namespace

Fitted fit_cage(const QuadCage& initial, const TriangleMesh& region,
                const std::vector<std::vector<Vec3>>& boundary_curves, const FitOptions& options,
                const Context& ctx) {
  const auto start = std::chrono::steady_clock::now();
  GENBREP_CHECK(boundary_curves.empty() || boundary_curves.size() == initial.boundary_chains.size(),
                Code::InvalidInput,
                "fit: " + std::to_string(boundary_curves.size()) + " boundary curves for " +
                    std::to_string(initial.boundary_chains.size()) + " cage boundary chains");
  GENBREP_CHECK(options.rounds >= 1, Code::InvalidInput, "fit: rounds must be at least 1");
  const Problem problem =
      make_problem(region, boundary_curves, options.boundary_weight,
                   std::lround(options.points_per_control_point * static_cast<double>(initial.vertices.rows())));
  FitReport report;
  report.component = initial.component;
  report.strategy = options.strategy;
  report.delta = options.delta > 0 ? options.delta : 3 * problem.median_edge;
  const double delta = report.delta;
  Run run{problem, options, ctx, report, std::vector<double>(problem.points.size(), 1.0)};
  const bool has_curves = !problem.curves.empty();

  Fitting f(initial);
  f.measured = measure(f.surface, f.chains, problem, options);
  const std::vector<char> all(f.cage.vertices.rows(), 1);
  auto surface_max = [&] { return two_sided(f.measured); };
  auto refine = [&](const std::vector<std::array<int, 2>>& seeds) {
    if (report.refinements >= options.max_refinements) {
      report.diagnostics.push_back("stopped refining after max_refinements = " +
                                   std::to_string(options.max_refinements));
      return false;
    }
    QuadCage refined = split_chords(f.cage, seeds);
    if (refined.vertices.rows() > options.max_control_points) {
      report.diagnostics.push_back(
          "next refinement would have " + std::to_string(refined.vertices.rows()) +
          " control points > max_control_points = " + std::to_string(options.max_control_points));
      return false;
    }
    f = Fitting(std::move(refined));
    f.measured = measure(f.surface, f.chains, problem, options);
    report.refinements += 1;
    return true;
  };

  if (options.strategy == FitStrategy::Smooth) {
    run.alternate(f, all, true, has_curves);
    report.bound_held = surface_max() <= delta;
  } else if (options.strategy == FitStrategy::Tight) {
    for (;;) {
      run.alternate(f, std::vector<char>(f.cage.vertices.rows(), 1), true, has_curves);
      if (surface_max() <= delta) {
        report.bound_held = true;
        break;
      }
      // Quads where the bound fails, both ways; their two chords are split.
      std::set<int> bad;
      for (size_t i = 0; i < f.measured.feet.size(); ++i) {
        if (f.measured.feet[i].distance > delta) {
          bad.insert(f.measured.feet[i].quad);
          run.emphasis[i] *= 4;  // and the failing samples weigh more in the next solve
        }
      }
      for (int q = 0; q < f.surface.quad_count(); ++q) {
        if (f.measured.quad_limit_to_design[q] > delta) bad.insert(q);
      }
      if (!refine(quad_edges_of(f.cage, bad))) break;
    }
  } else {
    if (has_curves) {
      for (;;) {
        std::vector<char> boundary(f.cage.vertices.rows(), 0);
        for (const auto& chain : f.cage.boundary_chains) {
          for (int v : chain) boundary[v] = 1;
        }
        run.alternate(f, boundary, false, true);
        if (f.measured.max_boundary <= delta) {
          report.bound_held = true;
          break;
        }
        std::vector<std::array<int, 2>> seeds;
        for (size_t c = 0; c < f.chains.size(); ++c) {
          const auto& chain = f.cage.boundary_chains[c];
          for (size_t e = 0; e < f.chains[c].size(); ++e) {
            if (f.measured.chain_edge_distance[c][e] > delta) {
              seeds.push_back({chain[e], chain[(e + 1) % chain.size()]});
            }
          }
        }
        if (!refine(seeds)) break;
      }
      std::vector<char> interior(f.cage.vertices.rows(), 1);
      for (const auto& chain : f.cage.boundary_chains) {
        for (int v : chain) interior[v] = 0;
      }
      run.alternate(f, interior, true, false);
    } else {
      report.diagnostics.push_back("boundary_tight without boundary curves: fitted as smooth");
      run.alternate(f, all, true, false);
      report.bound_held = true;
    }
  }

  // A fit must not fold the surface. Where the fitted limit surface intersects itself and
  // the initial one does not (thin parts wrapped by long quads, where the least squares
  // pulls opposite sides through each other), the control points around the folded quads
  // are held smoother and the fit repeated (fold_smoothing_rounds, fairness ×
  // fold_stiffness each round); if it still folds, the initial cage is kept, reported.
  // The initial cage with its distances, measured only when needed, at most once.
  std::optional<Fitting> initial_fitting;
  auto measured_initial = [&]() -> Fitting& {
    if (!initial_fitting) {
      initial_fitting.emplace(initial);
      initial_fitting->measured = measure(initial_fitting->surface, initial_fitting->chains, problem, options);
    }
    return *initial_fitting;
  };
  std::vector<int> folded;
  if (options.fold_check_samples > 0) folded = folded_quads(f.cage, options.fold_check_samples);
  const bool initial_folds =
      !folded.empty() && limit_intersects_itself(initial, options.fold_check_samples);
  bool undo = !folded.empty() && !initial_folds;
  // Both fold: nothing to go back to; the fit (nearer the region) is kept, and said so.
  if (initial_folds)
    report.diagnostics.push_back(
        "the fitted limit surface intersects itself (" + std::to_string(folded.size()) +
        " quads), and so does the initial cage's: the fit is kept, folded");
  if (undo && options.fold_smoothing_rounds > 0) {
    Fitting unfolded(f.cage);
    unfolded.measured = f.measured;
    std::vector<char> free(f.cage.vertices.rows(), 1);
    if (options.strategy == FitStrategy::BoundaryTight && has_curves)
      for (const auto& chain : f.cage.boundary_chains)
        for (int v : chain) free[v] = 0;
    run.stiff.assign(f.cage.vertices.rows(), 1.0);
    int smoothed_points = 0;
    for (int round = 0, before = static_cast<int>(folded.size());
         !folded.empty() && round < 2 * options.fold_smoothing_rounds; ++round) {
      // Past the rounds asked for, only while the folds keep shrinking.
      if (round >= options.fold_smoothing_rounds && static_cast<int>(folded.size()) >= before) break;
      before = static_cast<int>(folded.size());
      // The folded quads' corners and the corners of the quads within fold_rings of them.
      std::vector<char> ring(f.cage.vertices.rows(), 0);
      for (int q : folded)
        for (int k = 0; k < 4; ++k) ring[f.cage.quads(q, k)] = 1;
      for (int r = 0; r < options.fold_rings; ++r) {
        const std::vector<char> near = ring;
        for (Eigen::Index q = 0; q < f.cage.quads.rows(); ++q) {
          bool touches = false;
          for (int k = 0; k < 4; ++k) touches |= near[f.cage.quads(q, k)] != 0;
          if (touches)
            for (int k = 0; k < 4; ++k) ring[f.cage.quads(q, k)] = 1;
        }
      }
      for (size_t v = 0; v < ring.size(); ++v) {
        if (!ring[v]) continue;
        smoothed_points += run.stiff[v] == 1.0;
        run.stiff[v] *= options.fold_stiffness;
      }
      run.alternate(unfolded, free, true, has_curves && options.strategy != FitStrategy::BoundaryTight,
                    options.fold_smoothing_solves);
      folded = folded_quads(unfolded.cage, options.fold_check_samples);
    }
    run.stiff.clear();
    // Kept only if it stays as near the region as the bound or the initial cage, both ways:
    // holding a fold smoother must not trade it for a surface that strays.
    const auto near_enough = [&] {
      if (two_sided(unfolded.measured) <= delta) return true;
      return two_sided(unfolded.measured) <= two_sided(measured_initial().measured);
    };
    if (folded.empty() && near_enough()) {
      undo = false;
      f = std::move(unfolded);
      report.bound_held = two_sided(f.measured) <= delta;
      report.diagnostics.push_back("the fit folded the limit surface; " +
                                   std::to_string(smoothed_points) +
                                   " control points around the fold were held smoother and it no longer does");
    } else if (folded.empty()) {
      report.diagnostics.push_back("the fit folded the limit surface; held smoother it strays " +
                                   std::to_string(two_sided(unfolded.measured)) + " from the region");
    }
  }
  if (undo) {
    report.diagnostics.push_back(
        "the fitted limit surface intersects itself and the initial one does not: the initial "
        "cage is kept unfitted");
    f = std::move(measured_initial());
    report.refinements = 0;
    report.bound_held = two_sided(f.measured) <= delta;
    report.kept_initial = true;
  }

  const Measurement& m = f.measured;
  report.control_points = static_cast<int>(f.cage.vertices.rows());
  report.quads = static_cast<int>(f.cage.quads.rows());
  report.rms_design_to_limit = m.rms_design_to_limit;
  report.max_design_to_limit = m.max_design_to_limit;
  report.rms_limit_to_design = m.rms_limit_to_design;
  report.max_limit_to_design = m.max_limit_to_design;
  report.max_boundary_distance = m.max_boundary;
  if (options.strategy == FitStrategy::BoundaryTight) {
    report.bound_held = !has_curves || m.max_boundary <= delta;
  }
  if (!report.bound_held && options.strategy != FitStrategy::Smooth) {
    report.diagnostics.push_back("bound δ = " + std::to_string(delta) + " not reached");
  }
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return {std::move(f.cage), std::move(report)};
}

}  // namespace genbrep

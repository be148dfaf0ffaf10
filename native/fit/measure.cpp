// fit/measure.cpp — limit boundary curves of cage chains, projection onto them, and the
// two-sided distance measurements of a fit (fit/detail/problem.h).
#include <algorithm>
#include <cmath>
#include <map>

#include "fit/detail/problem.h"

namespace genbrep::fit_detail {

std::vector<std::vector<ChainEdge>> chain_edges(const QuadCage& cage) {
  // Directed quad edges → (quad, k); a chain edge must have exactly one quad.
  std::map<std::pair<int, int>, std::vector<std::pair<int, int>>> directed;
  for (int q = 0; q < cage.quads.rows(); ++q) {
    for (int k = 0; k < 4; ++k)
      directed[{cage.quads(q, k), cage.quads(q, (k + 1) % 4)}].push_back({q, k});
  }
  std::vector<std::vector<ChainEdge>> out;
  for (size_t c = 0; c < cage.boundary_chains.size(); ++c) {
    const auto& chain = cage.boundary_chains[c];
    GENBREP_CHECK(chain.size() >= 3, Code::InvalidInput,
                  "cage boundary chain " + std::to_string(c) + " has " +
                      std::to_string(chain.size()) + " vertices (a closed chain needs 3)");
    std::vector<ChainEdge> edges;
    for (size_t i = 0; i < chain.size(); ++i) {
      const int a = chain[i], b = chain[(i + 1) % chain.size()];
      const auto forward = directed.find({a, b});
      const auto backward = directed.find({b, a});
      const size_t count = (forward == directed.end() ? 0 : forward->second.size()) +
                           (backward == directed.end() ? 0 : backward->second.size());
      GENBREP_CHECK(count == 1, Code::InvalidInput,
                    "cage boundary chain " + std::to_string(c) + ": " + std::to_string(a) + "-" +
                        std::to_string(b) + " is not a boundary edge of the cage (" +
                        std::to_string(count) + " quads)");
      const bool reversed = forward == directed.end();
      const auto& [q, k] = reversed ? backward->second[0] : forward->second[0];
      edges.push_back({q, k, reversed});
    }
    out.push_back(std::move(edges));
  }
  return out;
}

void chain_parameters(const ChainEdge& e, double t, double* u, double* v, double* du_dt,
                      double* dv_dt) {
  const double s = e.reversed ? 1 - t : t;
  const double us[4] = {s, 1, 1 - s, 0}, vs[4] = {0, s, 1, 1 - s};
  const double dus[4] = {1, 0, -1, 0}, dvs[4] = {0, 1, 0, -1};
  const double sign = e.reversed ? -1 : 1;
  *u = us[e.k];
  *v = vs[e.k];
  if (du_dt) *du_dt = sign * dus[e.k];
  if (dv_dt) *dv_dt = sign * dvs[e.k];
}

namespace {

// The limit curve of one chain as a polyline with `samples` segments per chain edge.
std::vector<Vec3> chain_polyline(const LimitSurface& surface, const std::vector<ChainEdge>& edges,
                                 int samples) {
  std::vector<Vec3> polyline;
  for (const ChainEdge& e : edges) {
    for (int j = 0; j < samples; ++j) {
      double u, v;
      chain_parameters(e, double(j) / samples, &u, &v, nullptr, nullptr);
      polyline.push_back(surface.evaluate(e.quad, u, v).position);
    }
  }
  return polyline;
}

}  // namespace

std::vector<CurveFoot> project_on_chains(const LimitSurface& surface,
                                         const std::vector<std::vector<ChainEdge>>& chains,
                                         const std::vector<Vec3>& points,
                                         const std::vector<int>& point_chain, int samples) {
  samples = std::max(1, samples);
  std::vector<std::vector<Vec3>> polylines;
  for (const auto& edges : chains) polylines.push_back(chain_polyline(surface, edges, samples));
  std::vector<CurveFoot> out(points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    const Vec3& p = points[i];
    const auto& edges = chains[point_chain[i]];
    const PolylineHit hit = closest_on_polyline(p, polylines[point_chain[i]], true);
    const int e = hit.segment / samples;
    double t = (hit.segment % samples + hit.t) / samples;
    // Newton on |C(t) − p|² along the chain edge, accepting only descent.
    double u, v, du, dv;
    chain_parameters(edges[e], t, &u, &v, &du, &dv);
    LimitSample s = surface.evaluate(edges[e].quad, u, v);
    double best = (s.position - p).squaredNorm();
    for (int iteration = 0; iteration < 6; ++iteration) {
      const Vec3 tangent = du * s.du + dv * s.dv;
      const double tt = tangent.squaredNorm();
      if (!(tt > 1e-300)) break;
      const double nt = std::clamp(t - tangent.dot(s.position - p) / tt, 0.0, 1.0);
      double nu, nv;
      chain_parameters(edges[e], nt, &nu, &nv, &du, &dv);
      const LimitSample trial = surface.evaluate(edges[e].quad, nu, nv);
      const double d2 = (trial.position - p).squaredNorm();
      if (!(d2 < best)) break;
      best = d2;
      t = nt;
      u = nu;
      v = nv;
      s = trial;
    }
    out[i] = {e, t, {edges[e].quad, u, v, s.position, std::sqrt(best)}};
  }
  return out;
}

Measurement measure(const LimitSurface& surface, const std::vector<std::vector<ChainEdge>>& chains,
                    const Problem& problem, const FitOptions& options) {
  Measurement m;
  // The projection's start grid is capped (max_projection_triangles), down to 3 segments
  // per edge: a cage of thousands of quads would otherwise rebuild a tree of 10⁵–10⁶
  // triangles every round only to seed the Gauss–Newton steps.
  int samples = std::max(1, options.projection_samples);
  const double quads = surface.quad_count();
  while (samples > 3 && 2.0 * samples * samples * quads > options.max_projection_triangles) --samples;
  m.feet = surface.project(problem.points, samples);
  double sum = 0;
  for (const FootPoint& f : m.feet) {
    sum += f.distance * f.distance;
    m.max_design_to_limit = std::max(m.max_design_to_limit, f.distance);
  }
  m.rms_design_to_limit = m.feet.empty() ? 0 : std::sqrt(sum / m.feet.size());

  const int n = std::max(1, options.measure_samples);
  m.quad_limit_to_design.assign(surface.quad_count(), 0.0);
  sum = 0;
  long count = 0;
  for (int q = 0; q < surface.quad_count(); ++q) {
    for (int j = 0; j <= n; ++j) {
      for (int i = 0; i <= n; ++i) {
        const Vec3 p = surface.evaluate(q, double(i) / n, double(j) / n).position;
        const double d = std::sqrt(problem.tree.closest(p).distance2);
        m.quad_limit_to_design[q] = std::max(m.quad_limit_to_design[q], d);
        sum += d * d;
        ++count;
      }
    }
    m.max_limit_to_design = std::max(m.max_limit_to_design, m.quad_limit_to_design[q]);
  }
  m.rms_limit_to_design = count ? std::sqrt(sum / count) : 0;

  // Boundary, both ways: curve points to the limit curve, limit-curve samples to the curve.
  m.chain_edge_distance.resize(chains.size());
  for (size_t c = 0; c < chains.size(); ++c) m.chain_edge_distance[c].assign(chains[c].size(), 0.0);
  if (!problem.curves.empty()) {
    m.curve_feet = project_on_chains(surface, chains, problem.curve_points, problem.curve_chain,
                                     options.projection_samples);
    for (size_t i = 0; i < m.curve_feet.size(); ++i) {
      double& worst = m.chain_edge_distance[problem.curve_chain[i]][m.curve_feet[i].edge];
      worst = std::max(worst, m.curve_feet[i].foot.distance);
    }
    for (size_t c = 0; c < chains.size(); ++c) {
      for (size_t e = 0; e < chains[c].size(); ++e) {
        for (int j = 0; j <= n; ++j) {
          double u, v;
          chain_parameters(chains[c][e], double(j) / n, &u, &v, nullptr, nullptr);
          const Vec3 p = surface.evaluate(chains[c][e].quad, u, v).position;
          const double d = std::sqrt(closest_on_polyline(p, problem.curves[c], true).distance2);
          m.chain_edge_distance[c][e] = std::max(m.chain_edge_distance[c][e], d);
        }
        m.max_boundary = std::max(m.max_boundary, m.chain_edge_distance[c][e]);
      }
    }
  }
  return m;
}

}  // namespace genbrep::fit_detail

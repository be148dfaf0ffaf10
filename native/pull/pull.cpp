// pull/pull.cpp — stand-in sheets (§7.1), curve descent (§7.2), interior blending.
#include "pull/pull.h"

#include "pull/detail/side.h"

#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>
#include <map>

namespace genbrep {

namespace {

// Tangential Laplacian smoothing of the interior vertices (see organic_sheets).
void smooth_tangentially(TriangleMesh* mesh, int rounds) {
  const int n = static_cast<int>(mesh->vertices.rows());
  std::vector<std::vector<int>> neighbours(static_cast<size_t>(n));
  std::map<std::pair<int, int>, int> edge_faces;
  for (Eigen::Index f = 0; f < mesh->triangles.rows(); ++f) {
    for (int k = 0; k < 3; ++k) {
      const int a = mesh->triangles(f, k), b = mesh->triangles(f, (k + 1) % 3);
      neighbours[a].push_back(b);
      neighbours[b].push_back(a);
      ++edge_faces[{std::min(a, b), std::max(a, b)}];
    }
  }
  std::vector<char> fixed(static_cast<size_t>(n), 0);
  for (const auto& [e, count] : edge_faces) {
    if (count == 1) fixed[e.first] = fixed[e.second] = 1;  // boundary: the loops stay
  }
  for (int round = 0; round < rounds; ++round) {
    std::vector<Vec3> normal(static_cast<size_t>(n), Vec3::Zero());
    for (Eigen::Index f = 0; f < mesh->triangles.rows(); ++f) {
      const Vec3 a = mesh->vertices.row(mesh->triangles(f, 0)), b = mesh->vertices.row(mesh->triangles(f, 1)),
                 c = mesh->vertices.row(mesh->triangles(f, 2));
      for (int k = 0; k < 3; ++k) normal[mesh->triangles(f, k)] += (b - a).cross(c - a);
    }
    Vertices next = mesh->vertices;
    for (int v = 0; v < n; ++v) {
      if (fixed[v] || neighbours[v].empty() || normal[v].norm() == 0) continue;
      Vec3 mean = Vec3::Zero();
      for (int u : neighbours[v]) mean += mesh->vertices.row(u).transpose();
      const Vec3 p = mesh->vertices.row(v).transpose(), nv = normal[v].normalized();
      Vec3 step = 0.5 * (mean / static_cast<double>(neighbours[v].size()) - p);
      step -= step.dot(nv) * nv;
      next.row(v) = (p + step).transpose();
    }
    mesh->vertices = next;
  }
}

}  // namespace

std::vector<OrganicSheet> organic_sheets(const TriangleMesh& design, const Partition& partition,
                                         int tangential_rounds) {
  const int n_faces = static_cast<int>(design.triangles.rows());
  GENBREP_CHECK(static_cast<int>(partition.face_component.size()) == n_faces, Code::Internal,
                "partition and design disagree on the triangle count");
  std::vector<OrganicSheet> sheets(static_cast<size_t>(partition.organic_components));
  std::vector<std::map<int, int>> local(sheets.size());  // design vertex -> sheet vertex
  std::vector<std::vector<Vec3>> points(sheets.size());
  std::vector<std::vector<Eigen::Vector3i>> tris(sheets.size());
  for (int t = 0; t < n_faces; ++t) {
    const int c = partition.face_component[t];
    if (c < 0) continue;
    Eigen::Vector3i tri;
    for (int k = 0; k < 3; ++k) {
      const int v = design.triangles(t, k);
      auto [it, added] = local[c].emplace(v, static_cast<int>(points[c].size()));
      if (added) points[c].push_back(design.vertices.row(v).transpose());
      tri[k] = it->second;
    }
    tris[c].push_back(tri);
    sheets[c].mesh.triangle_source.push_back(t);
  }
  for (size_t c = 0; c < sheets.size(); ++c) {
    auto& s = sheets[c];
    s.component = static_cast<int>(c);
    s.mesh.vertices.resize(static_cast<Eigen::Index>(points[c].size()), 3);
    for (size_t v = 0; v < points[c].size(); ++v) s.mesh.vertices.row(v) = points[c][v].transpose();
    s.mesh.triangles.resize(static_cast<Eigen::Index>(tris[c].size()), 3);
    for (size_t t = 0; t < tris[c].size(); ++t) s.mesh.triangles.row(t) = tris[c][t].transpose();
  }
  for (size_t l = 0; l < partition.loops.size(); ++l) {
    const auto& loop = partition.loops[l];
    SheetLoop out{{}, loop.solids, static_cast<int>(l)};
    for (int v : loop.vertices) out.vertices.push_back(local[loop.component].at(v));
    sheets[loop.component].loops.push_back(std::move(out));
  }
  for (auto& s : sheets) smooth_tangentially(&s.mesh, tangential_rounds);
  return sheets;
}

BoundaryCurve polyline_curve(int n, int samples_per_edge) {
  BoundaryCurve c;
  c.control_count = n;
  const int m = std::max(1, samples_per_edge);
  for (int i = 0; i < n; ++i) {
    for (int k = 0; k < m; ++k) {
      const double t = static_cast<double>(k) / m;
      c.controls.push_back(i);
      c.weights.push_back(1 - t);
      if (k > 0) {
        c.controls.push_back((i + 1) % n);
        c.weights.push_back(t);
      }
      c.offsets.push_back(static_cast<int>(c.controls.size()));
    }
  }
  return c;
}

BoundaryCurve cubic_bspline_curve(int n, int samples_per_span) {
  GENBREP_CHECK(n >= 3, Code::Internal, "a closed B-spline needs 3 control points");
  BoundaryCurve c;
  c.control_count = n;
  const int m = std::max(1, samples_per_span);
  for (int i = 0; i < n; ++i) {
    for (int k = 0; k < m; ++k) {
      const double t = static_cast<double>(k) / m, s = 1 - t;
      // Uniform cubic B-spline basis on span [c_i, c_{i+1}] (the CC boundary limit curve).
      const double w[4] = {s * s * s / 6, (3 * t * t * t - 6 * t * t + 4) / 6,
                           (-3 * t * t * t + 3 * t * t + 3 * t + 1) / 6, t * t * t / 6};
      for (int j = 0; j < 4; ++j) {
        c.controls.push_back(((i + j - 1) % n + n) % n);
        c.weights.push_back(w[j]);
      }
      c.offsets.push_back(static_cast<int>(c.controls.size()));
    }
  }
  return c;
}

SideDistance::SideDistance(const SolidSet& solids, std::vector<int> members, int side)
    : solids_(&solids), members_(std::move(members)), side_(side) {
  GENBREP_CHECK(!members_.empty(), Code::Internal, "a boundary loop borders no solid");
  scale_ = 0;
  for (int j : members_) {
    scale_ = std::max(scale_, (solids.surface(j).max_corner() - solids.surface(j).min_corner()).norm());
  }
}

double SideDistance::value(const Vec3& p, Vec3* gradient) const {
  // The member whose surface is nearest p, and its projection q: one tree query per member.
  int j = members_[0];
  double d = std::numeric_limits<double>::infinity();
  Vec3 q = p;
  for (int m : members_) {
    Vec3 nearest;
    const double dm = solids_->surface(m).signed_distance(p, &nearest);
    if (dm < d) d = dm, j = m, q = nearest;
  }
  const ClosedSurface& s = solids_->surface(j);
  if (gradient) {
    // ∇D = sign(D)·(p − q)/|p − q| with q the projection (the unit normal at q, §7.2).
    const Vec3 diff = p - q;
    if (diff.norm() > 1e-9 * scale_) {
      *gradient = (d < 0 ? -1.0 : 1.0) * diff.normalized();
    } else {
      const double e = 1e-6 * scale_;
      Vec3 g;
      for (int k = 0; k < 3; ++k) {
        const Vec3 step = Vec3::Unit(k) * e;
        g[k] = s.signed_distance(p + step) - s.signed_distance(p - step);
      }
      *gradient = g.norm() > 0 ? g.normalized() : Vec3::UnitZ();
    }
    *gradient *= side_;
  }
  return side_ * d;
}

CurvePull pull_curve(const BoundaryCurve& curve, const SideDistance& distance, double eta,
                     const PullOptions& options, std::vector<Vec3>* controls) {
  GENBREP_CHECK(eta < 0, Code::Internal, "the safety tolerance η must be negative");
  GENBREP_CHECK(static_cast<int>(controls->size()) == curve.control_count, Code::Internal,
                "boundary curve and control points disagree");
  const double target = (1 + options.overshoot) * eta;
  CurvePull out;
  const int n_samples = curve.sample_count();
  // F and ∇F per sample, kept while none of the sample's control points moves: once most
  // of the curve is inside, an iteration queries the distance only where it still moves.
  std::vector<double> value(static_cast<size_t>(n_samples));
  std::vector<Vec3> gradient(static_cast<size_t>(n_samples));
  std::vector<char> stale(static_cast<size_t>(n_samples), 1), moved(controls->size(), 0);
  for (int iteration = 0;; ++iteration) {
    // Best displacement per control point: the largest requested (max over the samples).
    std::vector<Vec3> move(controls->size(), Vec3::Zero());
    double worst = -std::numeric_limits<double>::infinity();
    out.stuck_samples.clear();
    for (int s = 0; s < n_samples; ++s) {
      double norm2 = 0;
      for (int k = curve.offsets[s]; k < curve.offsets[s + 1]; ++k) {
        norm2 += curve.weights[k] * curve.weights[k];
        if (moved[curve.controls[k]]) stale[s] = 1;
      }
      if (stale[s]) {
        Vec3 p = Vec3::Zero();
        for (int k = curve.offsets[s]; k < curve.offsets[s + 1]; ++k)
          p += curve.weights[k] * (*controls)[curve.controls[k]];
        value[s] = distance.value(p, &gradient[s]);
        stale[s] = 0;
      }
      const double f = value[s];
      worst = std::max(worst, f);
      if (f <= eta) continue;
      out.stuck_samples.push_back(s);
      const Vec3 delta = -(f - target) * gradient[s];
      for (int k = curve.offsets[s]; k < curve.offsets[s + 1]; ++k) {
        const Vec3 d = curve.weights[k] / norm2 * delta;
        Vec3& m = move[curve.controls[k]];
        if (d.squaredNorm() > m.squaredNorm()) m = d;
      }
    }
    if (iteration == 0) out.max_before = worst;
    out.max_after = worst;
    out.iterations = iteration;
    if (out.stuck_samples.empty()) {
      out.converged = true;
      return out;
    }
    if (iteration == options.max_iterations) return out;
    for (size_t i = 0; i < controls->size(); ++i) {
      moved[i] = move[i] != Vec3::Zero();
      (*controls)[i] += move[i];
    }
  }
}

bool SheetPull::converged() const {
  return std::all_of(loops.begin(), loops.end(), [](const LoopPull& l) { return l.curve.converged; });
}

void detail::fill_rings(const std::vector<std::vector<int>>& adjacency, std::vector<int>* ring) {
  std::deque<int> queue;
  for (int v = 0; v < static_cast<int>(ring->size()); ++v) {
    if ((*ring)[v] == 0) queue.push_back(v);
  }
  while (!queue.empty()) {
    const int v = queue.front();
    queue.pop_front();
    for (int u : adjacency[v]) {
      if ((*ring)[u] < 0) (*ring)[u] = (*ring)[v] + 1, queue.push_back(u);
    }
  }
}

void detail::fade_over_rings(const std::vector<std::vector<int>>& adjacency,
                             const std::vector<int>& ring, int k, std::vector<Vec3>* move) {
  for (int r = 1; r <= k; ++r) {
    const double factor = (1.0 - r / (k + 1.0)) / (1.0 - (r - 1) / (k + 1.0));
    for (int v = 0; v < static_cast<int>(ring.size()); ++v) {
      if (ring[v] != r) continue;
      Vec3 sum = Vec3::Zero();
      int count = 0;
      for (int u : adjacency[v]) {
        if (ring[u] == r - 1) sum += (*move)[u], ++count;
      }
      (*move)[v] = factor * sum / std::max(1, count);
    }
  }
}

std::vector<std::vector<int>> detail::vertex_adjacency(const TriangleMesh& mesh) {
  std::vector<std::vector<int>> adjacency(static_cast<size_t>(mesh.vertices.rows()));
  for (Eigen::Index f = 0; f < mesh.triangles.rows(); ++f) {
    for (int k = 0; k < 3; ++k) {
      const int a = mesh.triangles(f, k), b = mesh.triangles(f, (k + 1) % 3);
      adjacency[a].push_back(b);
      adjacency[b].push_back(a);
    }
  }
  for (auto& a : adjacency) {
    std::sort(a.begin(), a.end());
    a.erase(std::unique(a.begin(), a.end()), a.end());
  }
  return adjacency;
}

int detail::organic_side(const OrganicSheet& sheet, const SheetLoop& loop,
                         const std::vector<std::vector<int>>& adjacency, const SideDistance& d) {
  std::vector<int> ring(adjacency.size(), -1);
  std::deque<int> queue;
  for (int v : loop.vertices) ring[v] = 0, queue.push_back(v);
  int inside = 0, outside = 0;
  while (!queue.empty()) {
    const int v = queue.front();
    queue.pop_front();
    if (ring[v] >= 2) {
      (d.value(sheet.mesh.vertices.row(v).transpose()) < 0 ? inside : outside) += 1;
    }
    if (ring[v] == 3) continue;
    for (int u : adjacency[v]) {
      if (ring[u] < 0) ring[u] = ring[v] + 1, queue.push_back(u);
    }
  }
  return inside > outside ? -1 : 1;
}

namespace {

Vec3 triangle_normal(const Vertices& v, const Triangles& t, int f) {
  const Vec3 a = v.row(t(f, 0)), b = v.row(t(f, 1)), c = v.row(t(f, 2));
  return (b - a).cross(c - a);
}

}  // namespace

SheetPull pull_sheet(const OrganicSheet& sheet, const SolidSet& solids, double eta,
                     const PullOptions& options) {
  SheetPull out;
  out.sheet = sheet;
  out.eta = eta;
  const Vertices& original = sheet.mesh.vertices;
  const int n = static_cast<int>(original.rows());
  const auto adjacency = detail::vertex_adjacency(sheet.mesh);
  // §7.2 on each loop: the polyline through its vertices, sampled along its edges.
  std::vector<Vec3> displacement(static_cast<size_t>(n), Vec3::Zero());
  std::vector<char> on_boundary(static_cast<size_t>(n), 0);
  for (const auto& loop : sheet.loops) {
    LoopPull lp;
    const SideDistance probe(solids, loop.solids, 1);
    lp.side = detail::organic_side(sheet, loop, adjacency, probe);
    const SideDistance distance(solids, loop.solids, lp.side);
    std::vector<Vec3> controls;
    for (int v : loop.vertices) controls.push_back(original.row(v).transpose());
    const BoundaryCurve curve = polyline_curve(static_cast<int>(controls.size()), options.samples_per_edge);
    lp.curve = pull_curve(curve, distance, eta, options, &controls);
    for (size_t i = 0; i < controls.size(); ++i) {
      const int v = loop.vertices[i];
      displacement[v] = controls[i] - original.row(v).transpose();
      on_boundary[v] = 1;
      lp.max_displacement = std::max(lp.max_displacement, displacement[v].norm());
    }
    for (int s : lp.curve.stuck_samples) {
      Vec3 p = Vec3::Zero();
      for (int k = curve.offsets[s]; k < curve.offsets[s + 1]; ++k) p += curve.weights[k] * controls[curve.controls[k]];
      lp.stuck_points.push_back(p);
    }
    out.loops.push_back(std::move(lp));
  }
  // Ring distance from the boundary, for the blend.
  std::vector<int> ring(static_cast<size_t>(n), -1);
  for (int v = 0; v < n; ++v) {
    if (on_boundary[v]) ring[v] = 0;
  }
  detail::fill_rings(adjacency, &ring);
  // Linear fade over k rings: ring r moves by (1 − r/(k+1)) of its boundary neighbours'
  // mean move, rescaled; k doubles while any triangle turns over.
  for (int k = std::max(1, options.blend_rings);; k *= 2) {
    std::vector<Vec3> move = displacement;
    detail::fade_over_rings(adjacency, ring, k, &move);
    Vertices moved = original;
    for (int v = 0; v < n; ++v) moved.row(v) += move[v].transpose();
    int folded = 0;
    for (Eigen::Index f = 0; f < sheet.mesh.triangles.rows(); ++f) {
      const Vec3 before = triangle_normal(original, sheet.mesh.triangles, static_cast<int>(f));
      const Vec3 after = triangle_normal(moved, sheet.mesh.triangles, static_cast<int>(f));
      folded += before.dot(after) <= 0;
    }
    out.sheet.mesh.vertices = moved;
    out.blend_rings = k;
    out.folded_triangles = folded;
    if (folded == 0 || 2 * k > options.max_blend_rings) break;
  }
  if (out.folded_triangles > 0) {
    out.diagnostics.push_back("organic component " + std::to_string(sheet.component) + ": " +
                              std::to_string(out.folded_triangles) +
                              " triangles fold after the pull even with " +
                              std::to_string(out.blend_rings) + " blend rings");
  }
  return out;
}

}  // namespace genbrep

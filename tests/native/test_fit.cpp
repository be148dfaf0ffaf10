// Tests for fit/: the Catmull–Clark limit evaluator (OpenSubdiv, Blender's settings) and
// the three fitting strategies of paper §6.3 on level-set regions (marching tetrahedra of
// a signed distance on a grid of spacing h, as a generative solver gives them).
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>

#include "fit/fit.h"
#include "level_set.h"

using namespace genbrep;
using namespace genbrep::testing;

namespace {

constexpr double kPi = 3.14159265358979323846;

// Uniform cubic B-spline basis.
std::array<double, 4> bspline(double t) {
  const double s = 1 - t;
  return {s * s * s / 6, (3 * t * t * t - 6 * t * t + 4) / 6,
          (-3 * t * t * t + 3 * t * t + 3 * t + 1) / 6, t * t * t / 6};
}

// An (nx+1)×(ny+1) grid of control points, quads CCW seen from +z, boundary chain around
// the rim (counter-clockwise from +z).
QuadCage grid_cage(int nx, int ny, const std::function<Vec3(int, int)>& position) {
  QuadCage cage;
  auto id = [&](int i, int j) { return j * (nx + 1) + i; };
  cage.vertices.resize((nx + 1) * (ny + 1), 3);
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) cage.vertices.row(id(i, j)) = position(i, j).transpose();
  cage.quads.resize(nx * ny, 4);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i)
      cage.quads.row(j * nx + i) << id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1);
  std::vector<int> rim;
  for (int i = 0; i < nx; ++i) rim.push_back(id(i, 0));
  for (int j = 0; j < ny; ++j) rim.push_back(id(nx, j));
  for (int i = nx; i > 0; --i) rim.push_back(id(i, ny));
  for (int j = ny; j > 0; --j) rim.push_back(id(0, j));
  cage.boundary_chains = {rim};
  cage.chain_loop = {0};
  return cage;
}

// A cylinder tube cage of m×k quads, radius r, z in [z0, z1]; chains: bottom, top rings.
QuadCage tube_cage(int m, int k, double r, double z0, double z1) {
  QuadCage cage;
  auto id = [&](int i, int j) { return j * m + (i % m); };
  cage.vertices.resize(m * (k + 1), 3);
  for (int j = 0; j <= k; ++j)
    for (int i = 0; i < m; ++i) {
      const double a = 2 * kPi * i / m;
      cage.vertices.row(id(i, j)) << r * std::cos(a), r * std::sin(a), z0 + (z1 - z0) * j / k;
    }
  cage.quads.resize(m * k, 4);
  for (int j = 0; j < k; ++j)
    for (int i = 0; i < m; ++i)
      cage.quads.row(j * m + i) << id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1);
  std::vector<int> bottom, top;
  for (int i = 0; i < m; ++i) bottom.push_back(id(i, 0));
  for (int i = m; i > 0; --i) top.push_back(id(i, k));
  cage.boundary_chains = {bottom, top};
  cage.chain_loop = {0, 1};
  return cage;
}

// A cube cage with n×n quads per face, its vertices pushed onto the sphere of radius r.
QuadCage sphere_cage(int n, double r) {
  QuadCage cage;
  std::map<std::array<int, 3>, int> index;
  std::vector<Vec3> points;
  std::vector<std::array<int, 4>> quads;
  auto vertex = [&](std::array<int, 3> g) {
    auto it = index.find(g);
    if (it != index.end()) return it->second;
    const Vec3 p = Vec3(2.0 * g[0] / n - 1, 2.0 * g[1] / n - 1, 2.0 * g[2] / n - 1);
    points.push_back(r * p.normalized());
    index[g] = static_cast<int>(points.size()) - 1;
    return static_cast<int>(points.size()) - 1;
  };
  for (int axis = 0; axis < 3; ++axis) {
    const int b = (axis + 1) % 3, c = (axis + 2) % 3;
    for (int side = 0; side < 2; ++side) {
      for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
          std::array<int, 4> q;
          const int corners[4][2] = {{i, j}, {i + 1, j}, {i + 1, j + 1}, {i, j + 1}};
          for (int k = 0; k < 4; ++k) {
            std::array<int, 3> g;
            g[axis] = side * n;
            g[b] = corners[k][0];
            g[c] = corners[k][1];
            q[k] = vertex(g);
          }
          if (side == 0) std::swap(q[1], q[3]);
          quads.push_back(q);
        }
    }
  }
  cage.vertices.resize(points.size(), 3);
  for (size_t v = 0; v < points.size(); ++v) cage.vertices.row(v) = points[v].transpose();
  cage.quads.resize(quads.size(), 4);
  for (size_t q = 0; q < quads.size(); ++q)
    for (int k = 0; k < 4; ++k) cage.quads(q, k) = quads[q][k];
  return cage;
}

// A quad disk (square grid squeezed onto a disk) lifted onto the sphere of radius r, as
// the cage of the cap z > r·cos(angle).
QuadCage cap_cage(int n, double r, double angle) {
  const double rho = r * std::sin(angle);
  return grid_cage(n, n, [&](int i, int j) {
    const double x = 2.0 * i / n - 1, y = 2.0 * j / n - 1;
    const double px = rho * x * std::sqrt(1 - y * y / 2), py = rho * y * std::sqrt(1 - x * x / 2);
    return Vec3(px, py, std::sqrt(r * r - px * px - py * py));
  });
}

// The triangles of `mesh` whose centroids pass `keep`, compacted.
TriangleMesh select(const TriangleMesh& mesh, const std::function<bool(const Vec3&)>& keep) {
  std::vector<int> kept, remap(mesh.vertices.rows(), -1);
  for (int t = 0; t < mesh.triangles.rows(); ++t) {
    Vec3 c = Vec3::Zero();
    for (int k = 0; k < 3; ++k) c += mesh.vertices.row(mesh.triangles(t, k)).transpose() / 3;
    if (keep(c)) kept.push_back(t);
  }
  TriangleMesh out;
  std::vector<Vec3> vertices;
  out.triangles.resize(kept.size(), 3);
  for (size_t i = 0; i < kept.size(); ++i)
    for (int k = 0; k < 3; ++k) {
      int& v = remap[mesh.triangles(kept[i], k)];
      if (v < 0) {
        v = static_cast<int>(vertices.size());
        vertices.push_back(mesh.vertices.row(mesh.triangles(kept[i], k)).transpose());
      }
      out.triangles(i, k) = v;
    }
  out.vertices.resize(vertices.size(), 3);
  for (size_t v = 0; v < vertices.size(); ++v) out.vertices.row(v) = vertices[v].transpose();
  return out;
}

// Closed boundary loops of an open triangle mesh, as polylines.
std::vector<std::vector<Vec3>> boundary_loops(const TriangleMesh& mesh) {
  std::set<std::pair<int, int>> directed;
  for (int t = 0; t < mesh.triangles.rows(); ++t)
    for (int k = 0; k < 3; ++k)
      directed.insert({mesh.triangles(t, k), mesh.triangles(t, (k + 1) % 3)});
  std::multimap<int, int> next;
  for (const auto& [a, b] : directed)
    if (!directed.count({b, a})) next.emplace(a, b);
  std::vector<std::vector<Vec3>> loops;
  while (!next.empty()) {
    const int start = next.begin()->first;
    std::vector<Vec3> loop;
    int v = start;
    do {
      loop.push_back(mesh.vertices.row(v).transpose());
      const auto it = next.find(v);
      if (it == next.end()) break;
      v = it->second;
      next.erase(it);
    } while (v != start);
    loops.push_back(loop);
  }
  return loops;
}

// The largest boundary loop whose centroid passes `side`.
std::vector<Vec3> largest_loop(const std::vector<std::vector<Vec3>>& loops,
                               const std::function<bool(const Vec3&)>& side) {
  std::vector<Vec3> best;
  for (const auto& loop : loops) {
    Vec3 c = Vec3::Zero();
    for (const Vec3& p : loop) c += p / loop.size();
    if (side(c) && loop.size() > best.size()) best = loop;
  }
  return best;
}

TriangleMesh level_set(const Field& sdf, const Vec3& lo, const Vec3& hi, double h) {
  const Vec3 origin = lo - Vec3(0.37 * h, 0.29 * h, 0.41 * h);
  const Vec3 size = (hi - origin) / h;
  return extract_level_set(
      sdf, origin, h,
      Eigen::Vector3i(int(std::ceil(size.x())) + 1, int(std::ceil(size.y())) + 1,
                      int(std::ceil(size.z())) + 1));
}

// An open tube: a level-set cylinder of radius r cut at |z| < half_height.
struct Fixture {
  TriangleMesh region;
  std::vector<std::vector<Vec3>> curves;
  QuadCage cage;
  double h = 0;
};

Fixture tube_fixture(double h, double half_height, int m, int k) {
  const double r = 1;
  auto sdf = [&](const Vec3& p) {
    return std::max(std::hypot(p.x(), p.y()) - r, std::abs(p.z()) - half_height - 0.5);
  };
  const Vec3 extent(r + 0.1, r + 0.1, half_height + 0.6);
  Fixture f;
  f.h = h;
  f.region = select(level_set(sdf, -extent, extent, h),
                    [&](const Vec3& c) { return std::abs(c.z()) < half_height; });
  const auto loops = boundary_loops(f.region);
  f.curves = {largest_loop(loops, [](const Vec3& c) { return c.z() < 0; }),
              largest_loop(loops, [](const Vec3& c) { return c.z() > 0; })};
  // Start off the surface (radius 0.9) so the fit has to move it.
  f.cage = tube_cage(m, k, 0.9, -half_height, half_height);
  return f;
}

Fixture sphere_fixture(double h, int n) {
  Fixture f;
  f.h = h;
  f.region = level_set([](const Vec3& p) { return sphere_sdf(p, Vec3::Zero(), 1); },
                       Vec3(-1.1, -1.1, -1.1), Vec3(1.1, 1.1, 1.1), h);
  f.cage = sphere_cage(n, 1.0);
  return f;
}

Fixture cap_fixture(double h, int n) {
  const double angle = 50 * kPi / 180;
  Fixture f;
  f.h = h;
  const TriangleMesh sphere =
      level_set([](const Vec3& p) { return sphere_sdf(p, Vec3::Zero(), 1); },
                Vec3(-1.1, -1.1, -1.1), Vec3(1.1, 1.1, 1.1), h);
  f.region = select(sphere, [&](const Vec3& c) { return c.z() > std::cos(angle); });
  f.curves = {largest_loop(boundary_loops(f.region), [](const Vec3&) { return true; })};
  f.cage = cap_cage(n, 1.0, angle);
  return f;
}

Fitted fit(const Fixture& f, FitStrategy strategy, double delta = 0) {
  FitOptions options;
  options.strategy = strategy;
  options.delta = delta > 0 ? delta : 3 * f.h;
  return fit_cage(f.cage, f.region, f.curves, options, Context());
}

void print(const char* name, const Fixture& f, const FitReport& r) {
  std::printf(
      "[fit] %-22s %-14s h=%.4f tris=%ld cps=%d quads=%d  d→l rms %.5f (%.3fh) max %.5f "
      "(%.2fh)  l→d rms %.5f max %.5f (%.2fh)  boundary %.5f (%.2fh)  rounds %d refinements "
      "%d  %.3f s  bound %s\n",
      name, strategy_name(r.strategy), f.h, long(f.region.triangles.rows()), r.control_points,
      r.quads, r.rms_design_to_limit, r.rms_design_to_limit / f.h, r.max_design_to_limit,
      r.max_design_to_limit / f.h, r.rms_limit_to_design, r.max_limit_to_design,
      r.max_limit_to_design / f.h, r.max_boundary_distance, r.max_boundary_distance / f.h, r.rounds,
      r.refinements, r.seconds, r.bound_held ? "held" : "NOT held");
  for (const auto& d : r.diagnostics) std::printf("[fit]   %s\n", d.c_str());
}

}  // namespace

// ---------------------------------------------------------------------------------------
// Limit evaluator

TEST(Limit, RegularQuadIsTheBicubicBSplineOfItsSixteenControlPoints) {
  const QuadCage cage = grid_cage(3, 3, [](int i, int j) {
    return Vec3(i + 0.1 * std::sin(3.0 * j), j + 0.1 * std::cos(2.0 * i), std::sin(i + 2.0 * j));
  });
  const LimitSurface surface(cage);
  const int middle = 4;  // quad (1, 1): all of its 16-point ring is regular
  for (double u : {0.0, 0.2, 0.5, 0.9, 1.0})
    for (double v : {0.0, 0.35, 0.7, 1.0}) {
      const auto bu = bspline(u), bv = bspline(v);
      Vec3 expected = Vec3::Zero();
      for (int b = 0; b < 4; ++b)
        for (int a = 0; a < 4; ++a)
          expected += bu[a] * bv[b] * cage.vertices.row(b * 4 + a).transpose();
      const LimitSample s = surface.evaluate(middle, u, v);
      EXPECT_NEAR((s.position - expected).norm(), 0, 1e-12) << "u " << u << " v " << v;
      // The weights reproduce the point and sum to one.
      Vec3 combined = Vec3::Zero();
      double sum = 0;
      for (const auto& [i, w] : surface.weights(middle, u, v)) {
        combined += w * cage.vertices.row(i).transpose();
        sum += w;
      }
      EXPECT_NEAR((combined - expected).norm(), 0, 1e-12);
      EXPECT_NEAR(sum, 1, 1e-12);
      // Derivatives against central differences.
      const double e = 1e-6;
      const Vec3 du = (surface.evaluate(middle, std::min(1.0, u + e), v).position -
                       surface.evaluate(middle, std::max(0.0, u - e), v).position) /
                      (std::min(1.0, u + e) - std::max(0.0, u - e));
      EXPECT_NEAR((s.du - du).norm(), 0, 1e-6);
    }
}

TEST(Limit, EdgeOnlyBoundaryIsTheCubicBSplineOfTheBoundaryChain) {
  const QuadCage cage = grid_cage(5, 4, [](int i, int j) {
    return Vec3(i + 0.2 * std::sin(1.0 * j), j, 0.5 * std::sin(0.9 * i) * std::cos(1.3 * j));
  });
  const LimitSurface surface(cage);
  const auto& chain = cage.boundary_chains[0];
  const int m = static_cast<int>(chain.size());
  const std::set<int> corners = {0, 5, 29, 24};  // the grid's valence-2 vertices
  // Exact except within 2^-quality of a smooth valence-2 corner, where OpenSubdiv (and so
  // Blender) uses a Gregory end cap: a small, quality-dependent approximation.
  const double isolation = 1.0 / (1 << cage.scheme.quality);
  double worst = 0, worst_near_corner = 0;
  for (int q = 0; q < cage.quads.rows(); ++q)
    for (int k = 0; k < 4; ++k) {
      const int a = cage.quads(q, k), b = cage.quads(q, (k + 1) % 4);
      int i = -1;
      for (int c = 0; c < m; ++c)
        if (chain[c] == a && chain[(c + 1) % m] == b) i = c;
      if (i < 0) continue;
      for (double t : {0.0, 0.05, 0.125, 0.25, 0.5, 0.8, 0.875, 0.95, 1.0}) {
        const auto w = bspline(t);
        Vec3 expected = Vec3::Zero();
        for (int d = 0; d < 4; ++d)
          expected += w[d] * cage.vertices.row(chain[(i - 1 + d + m) % m]).transpose();
        const double us[4] = {t, 1, 1 - t, 0}, vs[4] = {0, t, 1, 1 - t};
        const double error = (surface.evaluate(q, us[k], vs[k]).position - expected).norm();
        const bool near_corner =
            (corners.count(a) && t < isolation) || (corners.count(b) && 1 - t < isolation);
        (near_corner ? worst_near_corner : worst) =
            std::max(near_corner ? worst_near_corner : worst, error);
      }
    }
  std::printf(
      "[fit] EDGE_ONLY boundary vs periodic cubic B-spline of %d chain points: %.3g "
      "(within 1/%d of a smooth corner: %.3g)\n",
      m, worst, 1 << cage.scheme.quality, worst_near_corner);
  EXPECT_LT(worst, 1e-12);
  EXPECT_LT(worst_near_corner, 1e-2);

  // EDGE_AND_CORNER (Blender 'PRESERVE_CORNERS') interpolates the valence-2 corners.
  QuadCage cornered = cage;
  cornered.scheme.boundary_smooth_all = false;
  const LimitSurface sharp(cornered);
  EXPECT_NEAR((sharp.evaluate(0, 0, 0).position - cage.vertices.row(0).transpose()).norm(), 0,
              1e-12);
  EXPECT_GT((surface.evaluate(0, 0, 0).position - cage.vertices.row(0).transpose()).norm(), 1e-3);
}

TEST(Limit, CubeCornerLimitIsTheValenceThreeFormula) {
  // Cube of side 2: the limit of a valence-3 corner (n²v + 4Σe + Σf)/(n(n+5)) = v/2.
  const QuadCage cube = sphere_cage(1, std::sqrt(3.0));
  const LimitSurface surface(cube);
  for (int q = 0; q < cube.quads.rows(); ++q) {
    const double cu[4] = {0, 1, 1, 0}, cv[4] = {0, 0, 1, 1};
    for (int k = 0; k < 4; ++k) {
      const Vec3 v = cube.vertices.row(cube.quads(q, k)).transpose();
      EXPECT_NEAR((surface.evaluate(q, cu[k], cv[k]).position - 0.5 * v).norm(), 0, 1e-12);
    }
  }
}

TEST(Limit, TessellationIsWatertightAndLabelledByQuad) {
  const QuadCage cage = sphere_cage(3, 1.0);
  for (int n : {1, 4}) {
    const TriangleMesh mesh = tessellate_limit(cage, n);
    std::map<std::pair<int, int>, int> directed;
    for (int t = 0; t < mesh.triangles.rows(); ++t)
      for (int k = 0; k < 3; ++k)
        directed[{mesh.triangles(t, k), mesh.triangles(t, (k + 1) % 3)}] += 1;
    for (const auto& [e, count] : directed) {
      ASSERT_EQ(count, 1);
      ASSERT_EQ(directed.count({e.second, e.first}), 1u) << "open edge";
    }
    const long v = mesh.vertices.rows(), f = mesh.triangles.rows(), e = long(directed.size()) / 2;
    EXPECT_EQ(v - e + f, 2);  // a sphere
    EXPECT_EQ(mesh.triangle_source[2 * n * n * 5], 5);
    // Outward: positive signed volume.
    double volume = 0;
    for (int t = 0; t < f; ++t) {
      const Vec3 a = mesh.vertices.row(mesh.triangles(t, 0)),
                 b = mesh.vertices.row(mesh.triangles(t, 1)),
                 c = mesh.vertices.row(mesh.triangles(t, 2));
      volume += a.dot(b.cross(c)) / 6;
    }
    EXPECT_GT(volume, 0);
    EXPECT_EQ(tessellate_limit(cage, n).vertices, mesh.vertices);  // deterministic
  }
}

TEST(Limit, ProjectionFindsTheFootPoint) {
  const QuadCage cage = sphere_cage(3, 1.0);
  const LimitSurface surface(cage);
  std::vector<Vec3> points;
  std::vector<std::array<double, 3>> truth;
  for (int q = 0; q < cage.quads.rows(); q += 5) {
    const double u = 0.13 + 0.07 * (q % 10), v = 0.71 - 0.05 * (q % 7);
    const LimitSample s = surface.evaluate(q, u, v);
    points.push_back(s.position + 0.05 * s.normal());
    truth.push_back({double(q), u, v});
  }
  const auto feet = surface.project(points);
  for (size_t i = 0; i < feet.size(); ++i) {
    EXPECT_EQ(feet[i].quad, int(truth[i][0]));
    EXPECT_NEAR(feet[i].u, truth[i][1], 1e-7);
    EXPECT_NEAR(feet[i].v, truth[i][2], 1e-7);
    EXPECT_NEAR(feet[i].distance, 0.05, 1e-9);
  }
}

TEST(Limit, RejectsBrokenCages) {
  QuadCage cage = grid_cage(2, 2, [](int i, int j) { return Vec3(i, j, 0); });
  cage.quads(0, 2) = 99;
  EXPECT_THROW(LimitSurface{cage}, Error);
  cage = grid_cage(2, 2, [](int i, int j) { return Vec3(i, j, 0); });
  cage.quads(0, 1) = cage.quads(0, 0);
  EXPECT_THROW(LimitSurface{cage}, Error);
}

TEST(Refine, ChordSplitsStayPureQuadAndConforming) {
  const QuadCage cage = tube_cage(8, 4, 1, -1, 1);
  // One quad's two chords: the ring around (8 quads → 16) and the column along (4 → 8).
  const QuadCage refined = split_chords(
      cage, {{cage.quads(9, 0), cage.quads(9, 1)}, {cage.quads(9, 1), cage.quads(9, 2)}});
  EXPECT_EQ(refined.quads.rows(), 32 + 8 + 4 + 1);  // 8 rings · 4: one ring and one column doubled
  EXPECT_EQ(refined.boundary_chains[0].size(), 9u);  // the column reaches both rims
  EXPECT_EQ(refined.boundary_chains[1].size(), 9u);
  const TriangleMesh mesh = tessellate_limit(refined, 2);  // validates chains' topology too
  std::map<std::pair<int, int>, int> edges;
  for (int q = 0; q < refined.quads.rows(); ++q)
    for (int k = 0; k < 4; ++k) edges[{refined.quads(q, k), refined.quads(q, (k + 1) % 4)}] += 1;
  int boundary = 0;
  for (const auto& [e, count] : edges) {
    EXPECT_EQ(count, 1);
    if (!edges.count({e.second, e.first})) ++boundary;
  }
  EXPECT_EQ(boundary, 18);
  EXPECT_GT(mesh.triangles.rows(), 0);
}

// ---------------------------------------------------------------------------------------
// Fitting on level-set regions

TEST(Fit, TubeSmoothTightAndBoundaryTight) {
  const Fixture f = tube_fixture(0.05, 1.0, 16, 8);
  ASSERT_GT(f.curves[0].size(), 20u);
  ASSERT_GT(f.curves[1].size(), 20u);
  const Fitted smooth = fit(f, FitStrategy::Smooth);
  print("tube", f, smooth.report);
  EXPECT_LE(smooth.report.rms_design_to_limit, 0.5 * f.h);

  const Fitted tight = fit(f, FitStrategy::Tight);
  print("tube", f, tight.report);
  EXPECT_TRUE(tight.report.bound_held);
  EXPECT_LE(std::max(tight.report.max_design_to_limit, tight.report.max_limit_to_design), 3 * f.h);

  const Fitted boundary = fit(f, FitStrategy::BoundaryTight);
  print("tube", f, boundary.report);
  EXPECT_TRUE(boundary.report.bound_held);
  EXPECT_LE(boundary.report.max_boundary_distance, 3 * f.h);
  EXPECT_LE(boundary.report.rms_design_to_limit, 0.5 * f.h);
}

TEST(Fit, SphereSmoothAndTight) {
  const Fixture f = sphere_fixture(0.04, 3);
  const Fitted smooth = fit(f, FitStrategy::Smooth);
  print("sphere (cube cage)", f, smooth.report);
  EXPECT_LE(smooth.report.rms_design_to_limit, 0.5 * f.h);
  const Fitted tight = fit(f, FitStrategy::Tight);
  print("sphere (cube cage)", f, tight.report);
  EXPECT_TRUE(tight.report.bound_held);
  EXPECT_LE(std::max(tight.report.max_design_to_limit, tight.report.max_limit_to_design), 3 * f.h);
}

TEST(Fit, TightRefinesUntilASmallBoundHolds) {
  // The 8-point cube cage cannot hold a sphere to h/4: chords are split until it does.
  const Fixture f = sphere_fixture(0.04, 1);
  const Fitted tight = fit(f, FitStrategy::Tight, 0.25 * f.h);
  print("sphere δ=h/4", f, tight.report);
  EXPECT_GE(tight.report.refinements, 1);
  EXPECT_TRUE(tight.report.bound_held);
  EXPECT_LE(std::max(tight.report.max_design_to_limit, tight.report.max_limit_to_design),
            0.25 * f.h);
  EXPECT_GT(tight.cage.quads.rows(), f.cage.quads.rows());
  // And a size limit stops it, reported.
  FitOptions capped;
  capped.strategy = FitStrategy::Tight;
  capped.delta = 0.25 * f.h;
  capped.max_control_points = 12;
  const Fitted stopped = fit_cage(f.cage, f.region, f.curves, capped, Context());
  EXPECT_FALSE(stopped.report.bound_held);
  EXPECT_EQ(stopped.cage.vertices.rows(), f.cage.vertices.rows());
  EXPECT_FALSE(stopped.report.diagnostics.empty());
}

TEST(Fit, CapAllStrategies) {
  const Fixture f = cap_fixture(0.03, 6);
  ASSERT_GT(f.curves[0].size(), 20u);
  const Fitted smooth = fit(f, FitStrategy::Smooth);
  print("cap (disk cage)", f, smooth.report);
  EXPECT_LE(smooth.report.rms_design_to_limit, 0.5 * f.h);
  const Fitted tight = fit(f, FitStrategy::Tight);
  print("cap (disk cage)", f, tight.report);
  EXPECT_LE(std::max(tight.report.max_design_to_limit, tight.report.max_limit_to_design), 3 * f.h);
  const Fitted boundary = fit(f, FitStrategy::BoundaryTight);
  print("cap (disk cage)", f, boundary.report);
  EXPECT_TRUE(boundary.report.bound_held);
  EXPECT_LE(boundary.report.max_boundary_distance, 3 * f.h);
}

TEST(Fit, BoundaryTightSplitsBoundaryChordsUntilTheCurveHolds) {
  // One quad: its boundary limit curve is the B-spline of four points, far from the rim.
  Fixture f = cap_fixture(0.03, 1);
  const Fitted fitted = fit(f, FitStrategy::BoundaryTight, f.h);
  print("cap (one quad) δ=h", f, fitted.report);
  EXPECT_GE(fitted.report.refinements, 1);
  EXPECT_TRUE(fitted.report.bound_held);
  EXPECT_LE(fitted.report.max_boundary_distance, f.h);
  EXPECT_GT(fitted.cage.boundary_chains[0].size(), 4u);
}

// Whether one of the report's diagnostics contains `text`.
bool says(const FitReport& report, const std::string& text) {
  return std::any_of(report.diagnostics.begin(), report.diagnostics.end(),
                     [&](const std::string& d) { return d.find(text) != std::string::npos; });
}

// Independent of fit.cpp: whether the limit surface of a cage, tessellated with 4 segments
// per quad edge, intersects itself (CGAL, exact predicates).
bool limit_folds(const QuadCage& cage) {
  using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
  CGAL::Surface_mesh<Kernel::Point_3> mesh;
  const TriangleMesh t = tessellate_limit(cage, 4);
  std::vector<CGAL::Surface_mesh<Kernel::Point_3>::Vertex_index> v;
  for (Eigen::Index i = 0; i < t.vertices.rows(); ++i)
    v.push_back(mesh.add_vertex(Kernel::Point_3(t.vertices(i, 0), t.vertices(i, 1), t.vertices(i, 2))));
  for (Eigen::Index f = 0; f < t.triangles.rows(); ++f)
    mesh.add_face(v[t.triangles(f, 0)], v[t.triangles(f, 1)], v[t.triangles(f, 2)]);
  return CGAL::Polygon_mesh_processing::does_self_intersect(mesh);
}

// The fold tests fit with little fairness (the default before it was raised to 0.3):
// with the default the fits below do not fold at all.
FitOptions little_fairness() {
  FitOptions options;
  options.fairness_weight = 1e-3;
  return options;
}

// The fit with little fairness and without the fold check: what folds the tubes below.
Fitted unchecked_fit(const Fixture& f) {
  FitOptions options = little_fairness();
  options.fold_check_samples = 0;
  return fit_cage(f.cage, f.region, f.curves, options, Context());
}

// A fit must not fold the surface: the tube's region with its +x half moved 1.5 towards
// −x, through the other half, pulls the cage's +x side through its −x side. The plain
// fit's limit surface then intersects itself; with the check and no smoothing the initial
// cage is kept, unchanged, and the report says so.
Fixture folding_tube() {
  Fixture f = tube_fixture(0.05, 0.8, 16, 4);
  for (Eigen::Index i = 0; i < f.region.vertices.rows(); ++i)
    if (f.region.vertices(i, 0) > 0) f.region.vertices(i, 0) -= 1.5;
  f.curves.clear();
  return f;
}

TEST(Fit, AFitThatFoldsTheSurfaceIsUndone) {
  const Fixture f = folding_tube();
  ASSERT_FALSE(limit_folds(f.cage));
  const Fitted plain = unchecked_fit(f);
  EXPECT_FALSE(plain.report.kept_initial);
  EXPECT_TRUE(limit_folds(plain.cage));
  FitOptions undo = little_fairness();
  undo.fold_smoothing_rounds = 0;
  const Fitted checked = fit_cage(f.cage, f.region, f.curves, undo, Context());
  print("folded tube", f, checked.report);
  EXPECT_TRUE(checked.report.kept_initial);
  EXPECT_FALSE(limit_folds(checked.cage));
  ASSERT_EQ(checked.cage.vertices.rows(), f.cage.vertices.rows());
  EXPECT_EQ((checked.cage.vertices - f.cage.vertices).norm(), 0.0);
  EXPECT_TRUE(says(checked.report, "kept unfitted"));
}

// With fold smoothing (the default) the same fit is repeated with the control points
// around the folded quads held smoother. On this region (half of it pushed through the
// other half) the unfolded surface strays far from the region, so it is not kept either:
// the initial cage comes back, and the report says why.
TEST(Fit, AFoldSmoothedIntoASurfaceThatStraysIsUndoneToo) {
  const Fixture f = folding_tube();
  const Fitted checked = fit_cage(f.cage, f.region, f.curves, little_fairness(), Context());
  print("fold smoothed", f, checked.report);
  EXPECT_TRUE(checked.report.kept_initial);
  EXPECT_FALSE(limit_folds(checked.cage));
  EXPECT_EQ((checked.cage.vertices - f.cage.vertices).norm(), 0.0);
  EXPECT_TRUE(says(checked.report, "held smoother it strays"));
}

// Fold smoothing goes on past the rounds asked for while each round leaves fewer folded
// quads: the tube's region with its +x half pushed towards −x, by 0.5 at the bottom and
// 1 at the top, folds the plain fit (10 quads); one round held smoother leaves 6, a second
// none. Asked for one round, the fit takes two and keeps the unfolded surface (the 8 x 8
// net needed four: 49, 18, 3, 2, 0 folded quads).
TEST(Fit, FoldSmoothingGoesOnWhileTheFoldsShrink) {
  Fixture f = tube_fixture(0.05, 0.8, 16, 4);
  for (Eigen::Index i = 0; i < f.region.vertices.rows(); ++i)
    if (f.region.vertices(i, 0) > 0) f.region.vertices(i, 0) -= 0.5 + 0.5 * (f.region.vertices(i, 2) + 0.8) / 1.6;
  f.curves.clear();
  ASSERT_TRUE(limit_folds(unchecked_fit(f).cage));
  FitOptions options = little_fairness();
  options.fold_smoothing_rounds = 1;
  const Fitted fitted = fit_cage(f.cage, f.region, f.curves, options, Context());
  print("graded fold", f, fitted.report);
  EXPECT_FALSE(fitted.report.kept_initial);
  EXPECT_FALSE(limit_folds(fitted.cage));
  EXPECT_EQ(fitted.report.rounds, options.rounds + 2 * options.fold_smoothing_solves);
  EXPECT_TRUE(says(fitted.report, "no longer does"));
}

// A cage whose own limit surface already intersects itself (the folded tube's plain fit)
// has nothing to be undone to: fitted again, the fit is kept, and the report says that
// both fold rather than saying nothing.
TEST(Fit, AFoldTheInitialCageAlreadyHasIsReported) {
  const Fixture f = folding_tube();
  const Fitted plain = unchecked_fit(f);
  ASSERT_TRUE(limit_folds(plain.cage));
  const Fitted again = fit_cage(plain.cage, f.region, f.curves, little_fairness(), Context());
  EXPECT_FALSE(again.report.kept_initial);
  EXPECT_TRUE(limit_folds(again.cage));
  EXPECT_TRUE(says(again.report, "and so does the initial cage's"));
}

// A region about as coarse as the cage (368 vertices, 386 control points: a density raised
// to the design's resolution, as on lattice) leaves quads without data. Fitted to the
// vertices alone the limit surface strays between them, and with little fairness it folds;
// sampled inside its triangles (the default, 4 points per control point) it does neither.
TEST(Fit, ARegionAsCoarseAsTheCageIsSampledInsideItsTriangles) {
  const Fixture f = sphere_fixture(0.4, 8);
  ASSERT_LT(f.region.vertices.rows(), f.cage.vertices.rows());
  for (double fairness : {1e-3, 1e-6}) {
    FitOptions vertices_only, sampled_options;
    vertices_only.points_per_control_point = 0;
    vertices_only.fold_check_samples = 0;
    vertices_only.fairness_weight = sampled_options.fairness_weight = fairness;
    const Fitted sparse = fit_cage(f.cage, f.region, f.curves, vertices_only, Context());
    print("sphere, vertices only", f, sparse.report);
    const Fitted sampled = fit_cage(f.cage, f.region, f.curves, sampled_options, Context());
    print("sphere, sampled", f, sampled.report);
    EXPECT_FALSE(sampled.report.kept_initial);
    EXPECT_FALSE(limit_folds(sampled.cage));
    EXPECT_LT(sampled.report.max_limit_to_design, 0.1 * f.h);
    EXPECT_LT(sampled.report.max_design_to_limit, 0.1 * f.h);
    EXPECT_LT(sampled.report.max_limit_to_design, 0.25 * sparse.report.max_limit_to_design);
    if (fairness < 1e-4) {
      EXPECT_TRUE(limit_folds(sparse.cage));
    }
  }
}

TEST(Fit, Deterministic) {
  const Fixture f = cap_fixture(0.05, 4);
  for (FitStrategy s : {FitStrategy::Smooth, FitStrategy::Tight, FitStrategy::BoundaryTight}) {
    const Fitted a = fit(f, s), b = fit(f, s);
    EXPECT_EQ(a.cage.vertices, b.cage.vertices) << strategy_name(s);
    EXPECT_EQ(a.cage.quads, b.cage.quads) << strategy_name(s);
  }
}

TEST(Fit, MismatchedBoundaryCurvesAreInvalidInput) {
  const Fixture f = cap_fixture(0.08, 3);
  std::vector<std::vector<Vec3>> two = {f.curves[0], f.curves[0]};
  try {
    fit_cage(f.cage, f.region, two, {}, Context());
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), Code::InvalidInput);
  }
}

TEST(Fit, TwoThousandQuadsToFiftyThousandTriangles) {
  // Timing is printed, not asserted (tests/ style): the issue asks for < 5 s.
  const Fixture f = tube_fixture(0.066, 2.0, 48, 42);
  const Fitted smooth = fit(f, FitStrategy::Smooth);
  print("tube 2k quads", f, smooth.report);
  std::printf("[fit] TIMING %d quads to %ld triangles: %.2f s (smooth, %d rounds)\n",
              smooth.report.quads, long(f.region.triangles.rows()), smooth.report.seconds,
              smooth.report.rounds);
  EXPECT_EQ(smooth.report.quads, 2016);
  EXPECT_LE(smooth.report.rms_design_to_limit, 0.5 * f.h);
}

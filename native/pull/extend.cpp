// pull/extend.cpp — a cage extended into its solids: one row of quads beyond every
// boundary chain, reaching into the chain's solids. Where the design stops short of a
// keep-in, or meets it at an edge or corner, pulling the fitted boundary in moves it by more
// than the quads beside it are wide, and the fade folds the limit surface. A keep-in is
// material anyway, so the surface may run into it: the new row carries the whole move and
// leaves the fitted quads where they are.
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <set>

#include "pull/detail/side.h"
#include "pull/pull.h"

namespace genbrep {

namespace {

// How far out a new vertex may go: 8 local chain edges, or 4 times as far as its chain
// vertex is from the solid (a grazing direction needs more than the distance); beyond that
// a row is not a local extension. Searched in 64 steps.
constexpr double kMaxEdges = 8;
constexpr double kMaxGaps = 4;
constexpr int kSteps = 64;
// How deep the new boundary is placed: this fraction of the local edge inside the solid.
constexpr double kDepth = 0.5;
// Passes of (1, 2, 1) averaging of the directions along the chain.
constexpr int kSmoothingPasses = 3;

// Chain vertex i's outward direction: away from the centroids of its quads, across the
// chain (the chain tangent removed).
Vec3 outward(const QuadCage& cage, const std::vector<std::vector<int>>& vertex_quads,
             const std::vector<int>& chain, size_t i) {
  const int v = chain[i];
  const Vec3 p = cage.vertices.row(v).transpose();
  Vec3 centre = Vec3::Zero();
  for (int q : vertex_quads[v]) {
    for (int k = 0; k < 4; ++k) centre += cage.vertices.row(cage.quads(q, k)).transpose();
  }
  centre /= 4.0 * static_cast<double>(std::max<size_t>(1, vertex_quads[v].size()));
  const size_t m = chain.size();
  Vec3 tangent = cage.vertices.row(chain[(i + 1) % m]).transpose() - cage.vertices.row(chain[(i + m - 1) % m]).transpose();
  if (tangent.norm() > 0) tangent.normalize();
  Vec3 away = p - centre;
  away -= away.dot(tangent) * tangent;
  return away.norm() > 0 ? Vec3(away.normalized()) : Vec3::Zero();
}

// The new row's quads (chain vertex i to ends[i]) as triangles with the quads at the
// chain: does a new one cross another, other than along shared corners and edges? Control
// polygons, exact predicates: a row whose control polygon crosses itself gives a limit
// surface that does too.
bool row_crosses(const std::vector<Vec3>& points, const std::vector<std::array<int, 4>>& quads,
                 const std::vector<int>& chain, const std::vector<Vec3>& ends,
                 const std::map<std::pair<int, int>, int>& directed) {
  using Plain = CGAL::Surface_mesh<CGAL::Exact_predicates_inexact_constructions_kernel::Point_3>;
  Plain mesh;
  std::map<int, Plain::Vertex_index> index;
  auto vertex = [&](int v, const Vec3& p) {
    auto it = index.find(v);
    if (it != index.end()) return it->second;
    return index[v] = mesh.add_vertex(Plain::Point(p.x(), p.y(), p.z()));
  };
  const int first_end = static_cast<int>(points.size());
  const size_t m = chain.size();
  std::set<int> near;
  for (int v : chain) near.insert(v);
  for (size_t q = 0; q < quads.size(); ++q) {
    const auto& quad = quads[q];
    if (!near.count(quad[0]) && !near.count(quad[1]) && !near.count(quad[2]) && !near.count(quad[3])) continue;
    Plain::Vertex_index c[4];
    for (int k = 0; k < 4; ++k) c[k] = vertex(quad[k], points[quad[k]]);
    mesh.add_face(c[0], c[1], c[2]);
    mesh.add_face(c[0], c[2], c[3]);
  }
  const auto first_new = static_cast<Plain::size_type>(mesh.number_of_faces());
  for (size_t i = 0; i < m; ++i) {
    const int a = chain[i], b = chain[(i + 1) % m];
    const int wa = first_end + static_cast<int>(i), wb = first_end + static_cast<int>((i + 1) % m);
    const Plain::Vertex_index pa = vertex(a, points[a]), pb = vertex(b, points[b]);
    const Plain::Vertex_index qa = vertex(wa, ends[i]), qb = vertex(wb, ends[(i + 1) % m]);
    if (directed.count({a, b})) {
      mesh.add_face(pb, pa, qa);
      mesh.add_face(pb, qa, qb);
    } else {
      mesh.add_face(pa, pb, qb);
      mesh.add_face(pa, qb, qa);
    }
  }
  // Crossings among the fitted quads alone are the fit's, not the row's.
  std::vector<std::pair<Plain::Face_index, Plain::Face_index>> pairs;
  CGAL::Polygon_mesh_processing::self_intersections(mesh, std::back_inserter(pairs));
  for (const auto& [f, g] : pairs)
    if (f.idx() >= first_new || g.idx() >= first_new) return true;
  return false;
}

}  // namespace

ExtendedCage extend_cage(const QuadCage& cage, const std::vector<std::vector<int>>& chain_solids,
                         const SolidSet& solids) {
  GENBREP_CHECK(chain_solids.size() == cage.boundary_chains.size(), Code::Internal,
                "extend_cage needs the solids of every boundary chain");
  ExtendedCage out;
  out.cage = cage;
  const int n_points = static_cast<int>(cage.vertices.rows());
  std::vector<std::vector<int>> vertex_quads(static_cast<size_t>(n_points));
  std::map<std::pair<int, int>, int> directed;  // a→b as some quad's corners k, k+1
  for (Eigen::Index q = 0; q < cage.quads.rows(); ++q) {
    for (int k = 0; k < 4; ++k) {
      vertex_quads[cage.quads(q, k)].push_back(static_cast<int>(q));
      directed[{cage.quads(q, k), cage.quads(q, (k + 1) % 4)}] = static_cast<int>(q);
    }
  }
  const OrganicSheet sheet = cage_sheet(cage, chain_solids, 2);
  const auto adjacency = detail::vertex_adjacency(sheet.mesh);
  std::vector<Vec3> points;
  std::vector<std::array<int, 4>> quads;
  for (Eigen::Index v = 0; v < cage.vertices.rows(); ++v) points.push_back(cage.vertices.row(v).transpose());
  for (Eigen::Index q = 0; q < cage.quads.rows(); ++q)
    quads.push_back({cage.quads(q, 0), cage.quads(q, 1), cage.quads(q, 2), cage.quads(q, 3)});
  for (size_t c = 0; c < cage.boundary_chains.size(); ++c) {
    const auto& chain = cage.boundary_chains[c];
    const size_t m = chain.size();
    if (m < 3 || chain_solids[c].empty()) {
      out.problem = "boundary chain " + std::to_string(c) + " borders no solid";
      out.cage = cage;
      return out;
    }
    const SideDistance probe(solids, chain_solids[c], 1);
    out.sides.push_back(detail::organic_side(sheet, sheet.loops[c], adjacency, probe));
    const SideDistance distance(solids, chain_solids[c], out.sides.back());
    // Ways out, tried in turn until every vertex reaches the solid and the row crosses
    // neither itself nor the quads at the chain: across the chain first; where that misses
    // the solid (the chain wraps round a solid's edge, or the design meets it at a grazing
    // angle), half way to the solid's inward normal, then along it. Directions are
    // smoothed along the chain: directions that differ from one vertex to the next cross
    // the row over itself.
    std::vector<double> edge(m);
    std::vector<Vec3> across(m), into(m);
    for (size_t i = 0; i < m; ++i) {
      const Vec3 p = points[chain[i]];
      edge[i] = 0.5 * ((points[chain[(i + 1) % m]] - p).norm() + (points[chain[(i + m - 1) % m]] - p).norm());
      across[i] = outward(cage, vertex_quads, chain, i);
      Vec3 gradient = Vec3::Zero();
      distance.value(p, &gradient);
      into[i] = gradient.norm() > 0 ? Vec3(-gradient.normalized()) : across[i];
      if (across[i].isZero() || edge[i] <= 0) {
        out.problem = "boundary chain " + std::to_string(c) + " has a vertex with no outward direction";
        out.cage = cage;
        return out;
      }
    }
    std::vector<double> reach(m, 0);
    std::vector<Vec3> direction(m);
    // How far along `d` chain vertex i first is deep enough inside (where the solid is
    // thinner than that, its deepest step); false when it never gets inside.
    auto reach_along = [&](size_t i, const Vec3& d, double* r) {
      const Vec3 p = points[chain[i]];
      const double limit = std::max(kMaxEdges * edge[i], kMaxGaps * distance.value(p));
      const double step = limit / kSteps;
      double deepest = 0;
      *r = 0;
      if (!d.allFinite() || d.isZero()) return false;
      for (int k = 1; k <= kSteps; ++k) {
        const double f = distance.value(p + k * step * d);
        if (f < deepest) deepest = f, *r = k * step;
        if (f <= -kDepth * edge[i] || (deepest < 0 && f > deepest)) break;
      }
      return deepest < 0;
    };
    auto blend = [](const Vec3& a, const Vec3& b, double t) {
      return Vec3(((1 - t) * a.normalized() + t * b.normalized()).normalized());
    };
    int short_of = -1;
    std::vector<int> row(m);
    Vec3 across_mean = Vec3::Zero(), into_mean = Vec3::Zero();
    for (size_t i = 0; i < m; ++i) across_mean += across[i], into_mean += into[i];
    bool made = false, crossed = false;
    for (int policy = 0; policy < 7 && !made; ++policy) {
      // 0–2: per vertex, across the chain, half way to the normal, along the normal;
      // 3: per vertex, the first of five steps from across to the normal that reaches;
      // 4–6: one direction for the whole chain (the row a sheared copy of the chain, which
      // a small loop round a thin member needs), as 0–2.
      for (size_t i = 0; i < m; ++i) {
        if (policy < 3) {
          direction[i] = blend(across[i], into[i], 0.5 * policy);
        } else if (policy == 3) {
          direction[i] = into[i];
          double r = 0;
          for (const double t : {0.0, 0.25, 0.5, 0.75}) {
            if (!reach_along(i, blend(across[i], into[i], t), &r)) continue;
            direction[i] = blend(across[i], into[i], t);
            break;
          }
        } else {
          direction[i] = blend(across_mean, into_mean, 0.5 * (policy - 4));
        }
      }
      for (int pass = 0; pass < kSmoothingPasses; ++pass) {
        std::vector<Vec3> smoothed(m);
        for (size_t i = 0; i < m; ++i)
          smoothed[i] = (direction[(i + m - 1) % m] + 2 * direction[i] + direction[(i + 1) % m]).normalized();
        direction = smoothed;
      }
      short_of = -1;
      for (size_t i = 0; i < m && short_of < 0; ++i) {
        if (!reach_along(i, direction[i], &reach[i])) short_of = static_cast<int>(i);
      }
      if (short_of >= 0) continue;
      // The row's width evened along the chain (the larger of each vertex and its
      // neighbours: a jagged row turns its quads over), else each vertex's own, else half
      // way between its own and the first point inside (rays that converge cross later).
      std::vector<Vec3> ends(m);
      bool crosses = true;
      for (int width = 0; width < 3 && crosses; ++width) {
        for (size_t i = 0; i < m; ++i) {
          const double even = std::max({reach[(i + m - 1) % m], reach[i], reach[(i + 1) % m]});
          ends[i] = points[chain[i]] + (width == 0 ? even : width == 1 ? reach[i] : 0.5 * reach[i]) * direction[i];
        }
        crosses = row_crosses(points, quads, chain, ends, directed);
      }
      if (crosses) {
        crossed = true;
        continue;
      }
      for (size_t i = 0; i < m; ++i) {
        row[i] = static_cast<int>(points.size());
        points.push_back(ends[i]);
        out.widest = std::max(out.widest, (ends[i] - points[chain[i]]).norm());
      }
      made = true;
    }
    if (!made) {
      out.problem = "boundary chain " + std::to_string(c) + ": every row of quads tried " +
                    (crossed ? "crosses itself or the quads beside it" : "") + (crossed && short_of >= 0 ? ", or " : "") +
                    (short_of >= 0 ? "misses its solids (within 8 quad widths, or 4 times the distance to them, "
                                     "of vertex " + std::to_string(chain[short_of]) + ")"
                                   : "");
      out.cage = cage;
      return out;
    }
    // The new quads face the same way as the quads they border: the chain edge a→b runs
    // the other way round in the new quad.
    for (size_t i = 0; i < m; ++i) {
      const int a = chain[i], b = chain[(i + 1) % m], wa = row[i], wb = row[(i + 1) % m];
      if (directed.count({a, b}))
        quads.push_back({b, a, wa, wb});
      else
        quads.push_back({a, b, wb, wa});
    }
    out.cage.boundary_chains[c] = row;
  }
  out.cage.vertices.resize(static_cast<Eigen::Index>(points.size()), 3);
  for (size_t v = 0; v < points.size(); ++v) out.cage.vertices.row(static_cast<Eigen::Index>(v)) = points[v].transpose();
  out.cage.quads.resize(static_cast<Eigen::Index>(quads.size()), 4);
  for (size_t q = 0; q < quads.size(); ++q)
    for (int k = 0; k < 4; ++k) out.cage.quads(static_cast<Eigen::Index>(q), k) = quads[q][k];
  out.extended = true;
  return out;
}

}  // namespace genbrep

// quad/measure.cpp — the statistics of a cage (QuadStats) and the tests they rest on: the
// design's normals, turned-over and oversized quads, irregular vertices matched to singularities.
#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <tuple>
#include <vector>

#include "quad/detail/cage.h"

namespace genbrep {
namespace quad_detail {

DesignNormals::DesignNormals(const TriMesh& design) {
  const int nv = static_cast<int>(design.n_vertices());
  point_.resize(nv);
  normal_.assign(nv, Vec3::Zero());
  for (int v = 0; v < nv; ++v) {
    const auto& p = design.point(design.vertex_handle(v));
    point_[v] = Vec3(p[0], p[1], p[2]);
  }
  // Area-weighted vertex normals; then whether a triangle turns more than 30° from them.
  std::vector<std::array<int, 3>> corners(design.n_faces());
  std::vector<Vec3> face_normal(design.n_faces());
  for (auto f : design.faces()) {
    std::array<int, 3>& c = corners[f.idx()];
    int k = 0;
    for (auto v : design.fv_range(f)) c[k++] = v.idx();
    const Vec3 n = (point_[c[1]] - point_[c[0]]).cross(point_[c[2]] - point_[c[0]]);
    face_normal[f.idx()] = n;
    for (int v : c) normal_[v] += n;
  }
  creased_.assign(nv, 0);
  for (size_t f = 0; f < corners.size(); ++f) {
    const Vec3& n = face_normal[f];
    for (int v : corners[f])
      creased_[v] |= n.dot(normal_[v]) < kFaceCheckCosine * n.norm() * normal_[v].norm();
  }
  lo_ = Vec3::Constant(1e300);
  Vec3 hi = Vec3::Constant(-1e300);
  for (const Vec3& p : point_) lo_ = lo_.cwiseMin(p), hi = hi.cwiseMax(p);
  // Cells about 1.5 mean edges wide hold 2–3 vertices where the surface passes (27 cells
  // searched per lookup), but at most
  // 16 per vertex in all (a thin plate's box is mostly empty).
  double edges = 0;
  long counted = 0;
  for (auto e : design.edges()) {
    const auto h = design.halfedge_handle(e, 0);
    edges += (point_[design.to_vertex_handle(h).idx()] - point_[design.from_vertex_handle(h).idx()]).norm();
    ++counted;
  }
  const Vec3 box = (hi - lo_).cwiseMax(Vec3::Constant(1e-12));
  cell_ = counted ? std::max(1.5 * edges / counted, 1e-12) : 1.0;
  cell_ = std::max({cell_, box.maxCoeff() / 1024, std::cbrt(box.prod() / (16.0 * std::max(nv, 1)))});
  for (int a = 0; a < 3; ++a) cells_[a] = nv ? long(std::floor((hi[a] - lo_[a]) / cell_)) + 1 : 0;
  std::vector<long> cell_of(nv);
  first_.assign(cells_[0] * cells_[1] * cells_[2] + 1, 0);
  for (int v = 0; v < nv; ++v) {
    const auto k = key(point_[v]);
    cell_of[v] = (k[2] * cells_[1] + k[1]) * cells_[0] + k[0];
    ++first_[cell_of[v] + 1];
  }
  for (size_t i = 1; i < first_.size(); ++i) first_[i] += first_[i - 1];
  vertex_.resize(nv);
  std::vector<int> next(first_.begin(), first_.end() - 1);
  for (int v = 0; v < nv; ++v) vertex_[next[cell_of[v]]++] = v;
}

std::array<long, 3> DesignNormals::key(const Vec3& p) const {
  const Vec3 r = (p - lo_) / cell_;
  return {long(std::floor(r.x())), long(std::floor(r.y())), long(std::floor(r.z()))};
}

Vec3 DesignNormals::nearest_normal(const Vec3& p) const {
  bool creased = false;
  return nearest_normal(p, &creased);
}

Vec3 DesignNormals::nearest_normal(const Vec3& p, bool* creased) const {
  const int v = nearest_vertex(p);
  *creased = v >= 0 && creased_[v];
  return v < 0 ? Vec3(Vec3::Zero()) : normal_[v];
}

int DesignNormals::nearest_vertex(const Vec3& p) const {
  if (point_.empty()) return -1;
  const auto k = key(p);
  const Vec3 r = (p - lo_) / cell_;  // in cells
  int best = -1;
  double best_d = 1e300;
  auto scan = [&](long x, long y, long z) {
    if (x < 0 || y < 0 || z < 0 || x >= cells_[0] || y >= cells_[1] || z >= cells_[2]) return;
    const long cell = (z * cells_[1] + y) * cells_[0] + x;
    for (int i = first_[cell]; i < first_[cell + 1]; ++i) {
      const int v = vertex_[i];
      const double d = (point_[v] - p).squaredNorm();
      if (d < best_d) best_d = d, best = v;
    }
  };
  // p's own cell first; then the cells around it, one only if it comes nearer p than the
  // best so far, in cubes of doubling radius until the cube holds every point nearer than
  // the best (or 64 cells out).
  scan(k[0], k[1], k[2]);
  for (long radius = 1, inner = 0;; inner = radius, radius *= 2) {
    for (long x = k[0] - radius; x <= k[0] + radius; ++x)
      for (long y = k[1] - radius; y <= k[1] + radius; ++y)
        for (long z = k[2] - radius; z <= k[2] + radius; ++z) {
          const long at[3] = {x, y, z};
          double gap = 0;
          long ring = 0;
          for (int a = 0; a < 3; ++a) {
            const double g = std::max({0.0, double(at[a]) - r[a], r[a] - double(at[a] + 1)});
            gap += g * g;
            ring = std::max(ring, std::abs(at[a] - k[a]));
          }
          if (ring > inner && gap * cell_ * cell_ < best_d) scan(x, y, z);
        }
    if ((best >= 0 && best_d <= radius * radius * cell_ * cell_) || radius >= 64) break;
  }
  return best;
}

int oversized_quads(const CageChecks& checks, const QuadCage& cage, double density,
                    double factor) {
  int oversized = 0;
  for (int q = 0; q < cage.quads.rows(); ++q) {
    Vec3 c[4], centre = Vec3::Zero();
    for (int k = 0; k < 4; ++k) c[k] = cage.vertices.row(cage.quads(q, k)).transpose(), centre += 0.25 * c[k];
    const int v = checks.normals.nearest_vertex(centre);
    if (v < 0 || checks.surface.vertex_size[v] <= 0) continue;
    const double limit = factor * checks.surface.vertex_size[v] / density;
    bool long_edge = false;
    for (int k = 0; k < 4; ++k) long_edge |= (c[(k + 1) % 4] - c[k]).norm() > limit;
    oversized += long_edge;
  }
  return oversized;
}

double singular_reach(const CageChecks& checks, const QuadCage& cage,
                      const CageIncidence& incidence, int v, double density) {
  const Vec3 p = cage.vertices.row(v).transpose();
  const int near = checks.normals.nearest_vertex(p);
  double edges = 0;  // the vertex's mean edge length
  for (int w : incidence.neighbours[v]) edges += (cage.vertices.row(w).transpose() - p).norm();
  if (!incidence.neighbours[v].empty()) edges /= static_cast<double>(incidence.neighbours[v].size());
  return kSingularReach *
         std::max(edges, near >= 0 ? checks.surface.vertex_size[near] / density : 0);
}

void explaining_pairs(const Irregular& irregular, int entry,
                      const std::vector<SingularPoint>& singular, std::vector<Explaining>* pairs) {
  for (size_t i = 0; i < singular.size(); ++i) {
    const double distance = (singular[i].point - irregular.point).norm();
    if (distance <= irregular.reach && singular[i].index * irregular.carries > 0)
      pairs->push_back({distance, entry, static_cast<int>(i)});
  }
}

void match_pairs(std::vector<Explaining>& pairs, const std::vector<Irregular>& irregular,
                 const std::vector<SingularPoint>& singular, std::vector<int>* carries) {
  sort_pairs(pairs, [&](int entry) { return irregular[entry].vertex; });
  carries->resize(irregular.size());
  for (size_t e = 0; e < irregular.size(); ++e) (*carries)[e] = irregular[e].carries;
  match_sorted_pairs(pairs, singular, carries);
}

void match_sorted_pairs(const std::vector<Explaining>& pairs,
                        const std::vector<SingularPoint>& singular, std::vector<int>* carries) {
  thread_local std::vector<int> left;
  left.resize(singular.size());
  for (size_t i = 0; i < singular.size(); ++i) left[i] = std::abs(singular[i].index);
  for (const Explaining& pair : pairs) {
    int& carried = (*carries)[pair.entry];
    const int explained = std::min(std::abs(carried), left[pair.point]);
    left[pair.point] -= explained;
    carried -= carried > 0 ? explained : -explained;
  }
}

std::vector<Irregular> matched_irregulars(const CageChecks& checks, const QuadCage& cage,
                                          const CageIncidence& incidence,
                                          const std::vector<SingularPoint>& singular,
                                          double density, std::vector<int>* left) {
  std::vector<Irregular> irregular;
  for (int v = 0; v < static_cast<int>(cage.vertices.rows()); ++v) {
    const int quads = static_cast<int>(incidence.quads_of[v].size());
    if (incidence.on_chain[v] || quads == 4 || quads == 0) continue;
    irregular.push_back({v, 4 - quads, cage.vertices.row(v).transpose(),
                         singular_reach(checks, cage, incidence, v, density)});
  }
  std::vector<Explaining> pairs;
  for (size_t e = 0; e < irregular.size(); ++e)
    explaining_pairs(irregular[e], static_cast<int>(e), singular, &pairs);
  match_pairs(pairs, irregular, singular, left);
  return irregular;
}

int irregular_off_singularities(const CageChecks& checks, const QuadCage& cage,
                                const std::vector<SingularPoint>& singular, double density) {
  std::vector<int> left;
  matched_irregulars(checks, cage, CageIncidence(cage), singular, density, &left);
  return static_cast<int>(std::count_if(left.begin(), left.end(), [](int q) { return q != 0; }));
}

bool DesignNormals::flipped(const Vec3 (&c)[4]) const {
  const Vec3 across = (c[2] - c[0]).cross(c[3] - c[1]);
  const Vec3 n = nearest_normal(0.25 * (c[0] + c[1] + c[2] + c[3]));
  if (n.squaredNorm() > 0 && across.dot(n) <= 0) return true;
  return spans_thin_part(c, across);
}

bool DesignNormals::spans_thin_part(const Vec3 (&c)[4], const Vec3& across) const {
  const double length = across.norm();
  if (length <= 0) return false;
  for (int k = 0; k < 4; ++k) {
    const Vec3 n = nearest_normal(c[k]);
    if (n.squaredNorm() == 0 || across.dot(n) >= kThinPartCosine * length * n.norm()) return false;
  }
  return true;
}

}  // namespace quad_detail

QuadStats measure_cage(const QuadCage& cage, const TriMesh& design) {
  return quad_detail::measure_cage(cage, quad_detail::DesignNormals(design));
}

bool quad_detail::degenerate_quad(const QuadCage& cage, Eigen::Index q) {
  Vec3 c[4];
  bool degenerate = false;
  for (int k = 0; k < 4; ++k) {
    c[k] = cage.vertices.row(cage.quads(q, k)).transpose();
    for (int j = 0; j < k; ++j) degenerate |= cage.quads(q, k) == cage.quads(q, j);
  }
  for (int k = 0; k < 4; ++k)
    degenerate |= quad_detail::corner_angle(c[k], c[(k + 1) % 4], c[(k + 3) % 4]) * 180 / kPi < 1 ||
                  c[(k + 1) % 4] == c[k] || c[(k + 3) % 4] == c[k];
  return degenerate;
}

namespace {
QuadStats measure(const QuadCage& cage, const quad_detail::DesignNormals& normals,
                  const quad_detail::ComponentLocator* locator) {
  QuadStats stats;
  stats.quads = static_cast<int>(cage.quads.rows());
  stats.vertices = static_cast<int>(cage.vertices.rows());
  std::map<std::pair<int, int>, int> edge_use;
  for (Eigen::Index q = 0; q < cage.quads.rows(); ++q)
    for (int k = 0; k < 4; ++k) {
      const int a = cage.quads(q, k), b = cage.quads(q, (k + 1) % 4);
      ++edge_use[{std::min(a, b), std::max(a, b)}];
    }
  std::vector<int> valence(stats.vertices, 0);
  std::vector<char> boundary(stats.vertices, 0);
  for (const auto& [edge, uses] : edge_use) {
    ++valence[edge.first];
    ++valence[edge.second];
    if (uses == 1) boundary[edge.first] = boundary[edge.second] = 1;
  }
  for (int v = 0; v < stats.vertices; ++v) {
    if (!valence[v]) continue;
    if (boundary[v]) {
      ++stats.boundary_vertices;
      stats.boundary_valence3 += valence[v] == 3;
    } else {
      ++stats.interior_vertices;
      stats.interior_valence4 += valence[v] == 4;
    }
  }
  stats.irregular_vertices = (stats.interior_vertices - stats.interior_valence4) +
                             (stats.boundary_vertices - stats.boundary_valence3);
  double angle_sum = 0;
  int corners = 0;
  for (Eigen::Index q = 0; q < cage.quads.rows(); ++q) {
    Vec3 c[4];
    for (int k = 0; k < 4; ++k) c[k] = cage.vertices.row(cage.quads(q, k)).transpose();
    const bool degenerate = quad_detail::degenerate_quad(cage, q);
    bool skewed = false;
    for (int k = 0; k < 4; ++k) {
      const double angle =
          quad_detail::corner_angle(c[k], c[(k + 1) % 4], c[(k + 3) % 4]) * 180 / kPi;
      const double deviation = std::abs(angle - 90);
      skewed |= deviation > kSkewedDegrees;
      angle_sum += deviation;
      stats.max_angle_deviation_deg = std::max(stats.max_angle_deviation_deg, deviation);
      ++corners;
    }
    stats.degenerate_quads += degenerate;
    stats.skewed_quads += skewed;
    stats.flipped_quads += locator ? quad_detail::turned_over(normals, *locator, c) : normals.flipped(c);
  }
  stats.mean_angle_deviation_deg = corners ? angle_sum / corners : 0;
  return stats;
}
}  // namespace

bool quad_detail::faces_away(const ComponentLocator& locator, const Vec3 (&c)[4], int* hint) {
  int none = -1;
  const Vec3 across = (c[2] - c[0]).cross(c[3] - c[1]);
  const double bound = std::cos(kStandingDegrees * kPi / 180) * across.norm();
  for (const Vec3& normal :
       locator.normals_at(0.25 * (c[0] + c[1] + c[2] + c[3]), hint ? hint : &none))
    if (across.dot(normal) <= bound) return true;
  return false;
}

bool quad_detail::turned_over(const DesignNormals& normals, const ComponentLocator& locator,
                              const Vec3 (&c)[4], int* hint) {
  const Vec3 across = (c[2] - c[0]).cross(c[3] - c[1]);
  bool creased = false;
  const Vec3 design = normals.nearest_normal(0.25 * (c[0] + c[1] + c[2] + c[3]), &creased);
  if (design.squaredNorm() > 0) {
    const double agreement = across.dot(design);
    if (agreement <= 0 || normals.spans_thin_part(c, across)) return true;
    if (agreement >= kFaceCheckCosine * across.norm() * design.norm() && !creased) return false;
  }
  return faces_away(locator, c, hint);
}

QuadStats quad_detail::measure_cage(const QuadCage& cage, const CageChecks& checks) {
  return measure(cage, checks.normals, &checks.locator);
}

QuadStats quad_detail::measure_cage(const QuadCage& cage, const DesignNormals& normals) {
  return measure(cage, normals, nullptr);
}

bool quad_detail::cage_is_manifold(const QuadCage& cage, std::string* why) {
  const int nv = static_cast<int>(cage.vertices.rows());
  std::map<std::pair<int, int>, int> directed;  // → quad
  std::vector<std::vector<int>> quads_of(nv);
  for (int q = 0; q < cage.quads.rows(); ++q)
    for (int k = 0; k < 4; ++k) {
      const int a = cage.quads(q, k), b = cage.quads(q, (k + 1) % 4);
      if (a == b || !directed.insert({{a, b}, q}).second) {
        *why = "edge " + std::to_string(a) + "-" + std::to_string(b) + " is used twice the same way";
        return false;
      }
      quads_of[a].push_back(q);
    }
  for (int v = 0; v < nv; ++v) {
    const auto& around = quads_of[v];
    if (around.empty()) continue;
    // Walk the fan from one quad across the edges at v; it must reach every quad at v.
    std::set<int> reached{around[0]};
    std::vector<int> stack{around[0]};
    while (!stack.empty()) {
      const int q = stack.back();
      stack.pop_back();
      for (int k = 0; k < 4; ++k) {
        if (cage.quads(q, k) != v) continue;
        for (int w : {cage.quads(q, (k + 1) % 4), cage.quads(q, (k + 3) % 4)})
          for (auto key : {std::make_pair(v, w), std::make_pair(w, v)}) {
            auto it = directed.find(key);
            if (it != directed.end() && reached.insert(it->second).second) stack.push_back(it->second);
          }
      }
    }
    if (reached.size() != around.size()) {
      *why = "cage vertex " + std::to_string(v) + " joins two fans of quads";
      return false;
    }
  }
  // Two quads sharing three corners (a doublet: an interior vertex with two quads) or a
  // diagonal: the limit surface folds there.
  for (int q = 0; q < cage.quads.rows(); ++q) {
    std::map<int, int> shared;
    for (int k = 0; k < 4; ++k)
      for (int r : quads_of[cage.quads(q, k)])
        if (r != q) ++shared[r];
    for (const auto& [r, n] : shared) {
      bool diagonal = false;
      if (n == 2)
        for (int k = 0; k < 2; ++k)
          for (int j = 0; j < 2; ++j)
            diagonal |= (cage.quads(q, k) == cage.quads(r, j) && cage.quads(q, k + 2) == cage.quads(r, j + 2)) ||
                        (cage.quads(q, k) == cage.quads(r, j + 2) && cage.quads(q, k + 2) == cage.quads(r, j));
      if (n >= 3 || diagonal) {
        *why = "quads " + std::to_string(q) + " and " + std::to_string(r) + " share " +
               (n >= 3 ? "three corners" : "a diagonal");
        return false;
      }
    }
  }
  return true;
}

std::vector<quad_detail::Irregular> quad_detail::count_off_singularities(
    const quad_detail::CageChecks& checks, const QuadCage& cage,
    const std::vector<quad_detail::SingularPoint>& singular, double density, QuadStats* stats) {
  std::vector<int> left;
  const std::vector<quad_detail::Irregular> irregular = quad_detail::matched_irregulars(
      checks, cage, quad_detail::CageIncidence(cage), singular, density, &left);
  std::vector<quad_detail::Irregular> off;
  stats->off_singularities.clear();
  for (size_t e = 0; e < irregular.size(); ++e)
    if (left[e]) {
      off.push_back(irregular[e]);
      stats->off_singularities.push_back({irregular[e].vertex, 4 - irregular[e].carries, left[e]});
    }
  stats->irregular_off_singularities = static_cast<int>(off.size());
  return off;
}

}  // namespace genbrep

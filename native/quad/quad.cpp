// quad/quad.cpp — extract_cages: layout, quantization and filling per organic component,
// and the cage statistics (quad/quad.h).
#include "quad/quad.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <functional>
#include <map>
#include <optional>
#include <set>
#include <thread>
#include <tuple>

#include "quad/detail/layout.h"

namespace genbrep {
namespace {
constexpr double kPi = 3.14159265358979323846;
}

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
  // Cells about 1.5 mean edges wide hold 2–3 vertices where the surface passes (a 64th
  // of the box held 5 on the 6 x 6 net, 27 cells searched per lookup), but at most
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

namespace {
// A quad with a corner twice, two corners at one point or a corner under 1°
// (QuadStats::degenerate_quads).
bool degenerate_quad(const QuadCage& cage, Eigen::Index q) {
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
    const bool degenerate = degenerate_quad(cage, q);
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

namespace {
void extract_component(const TriMesh& design, const Partition& partition, const CrossField& field,
                       const QuadOptions& options, int c, QuadResult* out);
}  // namespace

QuadResult extract_cages(const TriMesh& design, const Partition& partition,
                         const CrossField& field, const QuadOptions& options,
                         const Context& context) {
  GENBREP_CHECK(partition.face_component.size() == design.n_faces() &&
                    field.direction.rows() == static_cast<Eigen::Index>(design.n_faces()),
                Code::InvalidInput, "quad: the partition or field does not match the design (" +
                    std::to_string(design.n_faces()) + " triangles)");
  GENBREP_CHECK(options.density > 0, Code::InvalidInput, "quad: density must be positive");
  QuadResult result;
  for (int c = 0; c < partition.organic_components; ++c) {
    context.step("quad", double(c) / std::max(1, partition.organic_components));
    try {
      extract_component(design, partition, field, options, c, &result);
    } catch (const Error& e) {
      if (e.code() == Code::Cancelled || e.code() == Code::InvalidInput) throw;
      result.failures.push_back({c, e.what()});
      result.diagnostics.push_back("component " + std::to_string(c) + ": no cage: " + e.what());
    }
  }
  context.step("quad", 1.0);
  return result;
}

namespace {

constexpr double kOversized = 2.5;  // QuadStats::oversized_quads
// Rounds of place_irregulars (windows edited in one round share no vertex, so a cluster
// takes several). 25 nets with arrival_snap: 8 → 233 irregular vertices off singularities,
// 16 → 219, 32 → 219 (converged), the sweep's time 182 → 186 s; genus 64 64 → 65.
constexpr int kPlaceRounds = 16;

bool cage_is_manifold(const QuadCage& cage, std::string* why);

// Per cage vertex: an irregular vertex a singularity of `singular` explains
// (matched_irregulars at `density`).
std::vector<char> explained_vertices(const quad_detail::CageChecks& checks, const QuadCage& cage,
                                     const std::vector<quad_detail::SingularPoint>& singular,
                                     double density) {
  std::vector<int> left;
  std::vector<char> explained(cage.vertices.rows(), 0);
  const std::vector<quad_detail::Irregular> irregular = quad_detail::matched_irregulars(
      checks, cage, quad_detail::CageIncidence(cage), singular, density, &left);
  for (size_t e = 0; e < irregular.size(); ++e) explained[irregular[e].vertex] = !left[e];
  return explained;
}

// How often evened_out holds more vertices and evens out again (holding one moves its
// neighbours, which can move another's match).
constexpr int kHoldRounds = 3;

// A copy of `cage` evened out (relax_cage: 10 sweeps, half steps). With `singular`, an
// irregular vertex a singularity explained before and none explains after (moved past its
// reach, or its singularity matched to a neighbour drawn nearer) is held where it was and
// the copy evened out again from `cage`, up to kHoldRounds times
// (QuadOptions::hold_explained); how many were held goes to *held_count.
QuadCage evened_out(const quad_detail::CageChecks& checks, const QuadCage& cage,
                    const quad_detail::Dropped& dropped,
                    const std::vector<quad_detail::SingularPoint>* singular, double density,
                    int* held_count) {
  *held_count = 0;
  QuadCage relaxed = cage;
  quad_detail::relax_cage(checks, relaxed, 10, 0.5, dropped);
  if (!singular) return relaxed;
  const std::vector<char> before = explained_vertices(checks, cage, *singular, density);
  std::vector<char> held(before.size(), 0);
  for (int round = 0; round < kHoldRounds; ++round) {
    const std::vector<char> after = explained_vertices(checks, relaxed, *singular, density);
    bool more = false;
    for (size_t v = 0; v < held.size(); ++v)
      if (before[v] && !after[v] && !held[v]) held[v] = 1, more = true, ++*held_count;
    if (!more) break;
    relaxed = cage;
    quad_detail::relax_cage(checks, relaxed, 10, 0.5, dropped, &held);
  }
  return relaxed;
}

// The chain vertices of three quads on a smooth stretch of their loop the edits onto
// singularities move off it (QuadOptions::place_chain_vertices; 0 without).
int chain_vertices_left(const QuadCage& cage, const QuadOptions& options) {
  return options.place_chain_vertices ? quad_detail::chain_vertices_to_shed(cage) : 0;
}

// Irregular vertices beside a singularity of `singular` that does not explain them (a −1
// singularity drawn as a 6 and a 3, or a 5 with a 3–5 pair beside it) are moved onto it by
// local edits (place_irregulars, as `options` says: density, draw_pairs_together,
// place_edits, place_climb, place_climb_last, place_rivals, place_chain_vertices,
// settle_rings, settle_sweeps); kept in *cage and *stats if the cage stays valid with fewer
// such vertices (with place_chain_vertices, such vertices and chain vertices of three quads
// where two would do, together).
void place_onto_singularities(const quad_detail::Surface& surface,
                              const quad_detail::CageChecks& checks, QuadCage* cage,
                              QuadStats* stats, quad_detail::Messages* messages,
                              const quad_detail::Dropped& dropped, const QuadOptions& options,
                              const std::vector<quad_detail::SingularPoint>& singular) {
  const double density = options.density;
  QuadCage placed = *cage;
  quad_detail::PlaceSettings settings;
  settings.draw_pairs_together = options.draw_pairs_together;
  settings.max_edits = options.place_edits;
  settings.climb = options.place_climb;
  settings.climb_last = options.place_climb_last;
  settings.rivals = options.place_rivals;
  settings.chain_vertices = options.place_chain_vertices;
  settings.settle_rings = options.settle_rings;
  settings.settle_sweeps = options.settle_sweeps;
  const int windows = quad_detail::place_irregulars(checks, placed, singular, density, kPlaceRounds,
                                                    settings, dropped);
  if (!windows) return;
  const int off = quad_detail::irregular_off_singularities(checks, *cage, singular, density);
  const int left = quad_detail::open_squeezed(checks, placed, 24);
  const QuadStats placed_stats = quad_detail::measure_cage(placed, checks);
  const int placed_off =
      quad_detail::irregular_off_singularities(checks, placed, singular, density);
  const int shed = chain_vertices_left(*cage, options);
  const int placed_shed = chain_vertices_left(placed, options);
  std::string why;
  if (!left && !placed_stats.flipped_quads && !placed_stats.degenerate_quads &&
      placed_off + placed_shed < off + shed && cage_is_manifold(placed, &why)) {
    messages->notes.push_back(
        "component " + std::to_string(surface.component) + ": " + std::to_string(windows) +
        " local edits moved irregular vertices onto the singularities beside them (away from "
        "singularities " +
        std::to_string(off) + " → " + std::to_string(placed_off) +
        (shed || placed_shed ? "; chain vertices of three quads where two would do " +
                                   std::to_string(shed) + " → " + std::to_string(placed_shed)
                             : std::string()) +
        ")");
    const int folded = stats->collapsed_quads;
    *cage = std::move(placed);
    *stats = placed_stats;
    stats->collapsed_quads = folded;
  } else {
    messages->notes.push_back(
        "component " + std::to_string(surface.component) + ": " + std::to_string(windows) +
        " local edits onto singularities not kept (" +
        (left ? std::to_string(left) + " quads left squeezed or turned over"
         : placed_stats.flipped_quads || placed_stats.degenerate_quads
             ? std::to_string(placed_stats.flipped_quads + placed_stats.degenerate_quads) +
                   " quads flipped or degenerate"
         : placed_off + placed_shed >= off + shed
             ? "no fewer irregular vertices away from singularities" +
                   std::string(options.place_chain_vertices
                                   ? " and chain vertices of three quads where two would do"
                                   : "")
             : "not a valid 2-manifold: " + why) +
        ")");
  }
}

// The cage evened out (evened_out, holding what `singular` explains if
// QuadOptions::hold_explained), kept in *cage and *stats if it stays valid and its corners
// come closer to 90°.
void even_out_kept(const quad_detail::Surface& surface, const quad_detail::CageChecks& checks,
                   QuadCage* cage, QuadStats* stats, quad_detail::Messages* messages,
                   const quad_detail::Dropped& dropped, const QuadOptions& options,
                   const std::vector<quad_detail::SingularPoint>* singular) {
  int held = 0;
  QuadCage relaxed = evened_out(checks, *cage, dropped, options.hold_explained ? singular : nullptr,
                                options.density, &held);
  QuadStats relaxed_stats = quad_detail::measure_cage(relaxed, checks);
  if (relaxed_stats.flipped_quads || relaxed_stats.degenerate_quads ||
      relaxed_stats.mean_angle_deviation_deg >= stats->mean_angle_deviation_deg)
    return;
  if (held)
    messages->notes.push_back("component " + std::to_string(surface.component) + ": " +
                              std::to_string(held) +
                              " irregular vertices held where singularities explain them while "
                              "the cage was evened out");
  relaxed_stats.collapsed_quads = stats->collapsed_quads;
  *cage = std::move(relaxed);
  *stats = relaxed_stats;
}

// Measures a filled cage; squeezed or turned-over quads are untangled first, and that is
// reported. A valid cage is then evened out (even_out_kept). With `singular`, irregular
// vertices none of them explains are placed first (place_onto_singularities), and those
// they explain are held in the evening out, which runs QuadOptions::place_passes times;
// the placing runs again before it while some are still unexplained.
QuadStats measure_untangled(const quad_detail::Surface& surface,
                            const quad_detail::CageChecks& checks, QuadCage* cage,
                            quad_detail::Messages* messages, const quad_detail::Dropped& dropped,
                            const QuadOptions& options,
                            const std::vector<quad_detail::SingularPoint>* singular = nullptr) {
  QuadStats stats = quad_detail::measure_cage(*cage, checks);
  if (stats.flipped_quads || stats.degenerate_quads) {
    const int bad = stats.flipped_quads + stats.degenerate_quads;
    int collapsed = 0;
    const int moved = quad_detail::untangle_cage(checks, *cage, 24, &collapsed, dropped);
    stats = quad_detail::measure_cage(*cage, checks);
    stats.collapsed_quads = collapsed;
    messages->warnings.push_back("component " + std::to_string(surface.component) + ": " +
                           std::to_string(bad) + " degenerate or flipped quads after filling; " +
                           std::to_string(moved) + " cage vertices around them smoothed" +
                           (collapsed ? ", " + std::to_string(collapsed) +
                                            " quads that stayed folded collapsed along a diagonal"
                                      : std::string()) +
                           ", " + std::to_string(stats.flipped_quads + stats.degenerate_quads) +
                           " left");
  }
  if (stats.flipped_quads || stats.degenerate_quads) return stats;
  // Irregular vertices the layout left in ± pairs (collapsed slivers, merged nodes) are
  // cancelled by diagonal collapses and edge rotations where the quads allow it; kept if
  // the cage stays valid.
  QuadCage cancelled = *cage;
  if (const int pairs = quad_detail::cancel_irregular_pairs(checks, cancelled, 4, dropped)) {
    const QuadStats cancelled_stats = quad_detail::measure_cage(cancelled, checks);
    std::string why;
    if (!cancelled_stats.flipped_quads && !cancelled_stats.degenerate_quads &&
        cancelled_stats.irregular_vertices < stats.irregular_vertices &&
        cage_is_manifold(cancelled, &why)) {
      messages->notes.push_back("component " + std::to_string(surface.component) + ": " +
                             std::to_string(pairs) +
                             " diagonal collapses, edge rotations or vertex splits cancelled "
                             "irregular vertices in pairs (" + std::to_string(stats.irregular_vertices) + " → " +
                             std::to_string(cancelled_stats.irregular_vertices) + ")");
      const int folded = stats.collapsed_quads;
      *cage = std::move(cancelled);
      stats = cancelled_stats;
      stats.collapsed_quads = folded;
    }
  }
  const int passes = singular ? std::max(1, options.place_passes) : 1;
  for (int pass = 0; pass < passes; ++pass) {
    if (singular &&
        (pass == 0 ||
         quad_detail::irregular_off_singularities(checks, *cage, *singular, options.density) ||
         chain_vertices_left(*cage, options)))
      place_onto_singularities(surface, checks, cage, &stats, messages, dropped, options,
                               *singular);
    even_out_kept(surface, checks, cage, &stats, messages, dropped, options, singular);
  }
  return stats;
}

// A step's warnings go to the result's diagnostics, its notes to its notes.
void add_messages(const quad_detail::Messages& messages, QuadResult* out) {
  out->diagnostics.insert(out->diagnostics.end(), messages.warnings.begin(), messages.warnings.end());
  out->notes.insert(out->notes.end(), messages.notes.begin(), messages.notes.end());
}

// A cage with its corners squared (square_cage: 10 sweeps, on `threads` threads, the same
// result for any number), if it stays valid and its corners come closer to 90°.
struct Squared {
  QuadCage cage;
  double mean_deg = 0, max_deg = 0;  // corner deviation after squaring
  int skewed_quads = 0, oversized_quads = 0, moved = 0;
  double seconds = 0;
};
std::optional<Squared> square_copy(const quad_detail::CageChecks& checks, double density,
                                   int threads, const QuadCage& cage, const QuadStats& stats) {
  const auto start = std::chrono::steady_clock::now();
  Squared out{cage};
  out.moved = quad_detail::square_cage(checks, out.cage, 10, density, threads);
  const QuadStats measured = quad_detail::measure_cage(out.cage, checks);
  if (measured.flipped_quads || measured.degenerate_quads ||
      measured.mean_angle_deviation_deg >= stats.mean_angle_deviation_deg)
    return std::nullopt;
  out.mean_deg = measured.mean_angle_deviation_deg;
  out.max_deg = measured.max_angle_deviation_deg;
  out.skewed_quads = measured.skewed_quads;
  out.oversized_quads = quad_detail::oversized_quads(checks, out.cage, density, kOversized);
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

// The kept cage takes its squared copy (square_copy, or the one its attempt made already),
// reported. Only the kept cage: layout choices are compared as filled and evened out,
// where a distorted layout (a fan of rows over collapsed slivers) still shows in its
// angles; squaring would hide that.
void keep_squared(Squared&& squared, int c, QuadCage* cage, QuadStats* stats,
                  Diagnostics* notes) {
  char text[200];
  std::snprintf(text, sizeof text,
                "component %d: corners squared (%d cage vertices moved in the last sweep, "
                "%.1f s): mean deviation from 90° %.1f° → %.1f°",
                c, squared.moved, squared.seconds, stats->mean_angle_deviation_deg,
                squared.mean_deg);
  notes->push_back(text);
  // Vertices moved, the topology did not: only the angles change.
  stats->mean_angle_deviation_deg = squared.mean_deg;
  stats->max_angle_deviation_deg = squared.max_deg;
  stats->skewed_quads = squared.skewed_quads;
  stats->oversized_quads = squared.oversized_quads;
  stats->seconds += squared.seconds;
  *cage = std::move(squared.cage);
}

void square_kept(const quad_detail::CageChecks& checks, double density, int c, int threads,
                 QuadCage* cage, QuadStats* stats, Diagnostics* notes) {
  if (auto squared = square_copy(checks, density, threads, *cage, *stats))
    keep_squared(std::move(*squared), c, cage, stats, notes);
}

// Whether the cage is an oriented 2-manifold whose limit surface can be built: every
// directed edge once, the quads around every vertex one fan (joined through the edges at
// that vertex), and no two quads sharing three corners or a diagonal. Collapsed sliver
// patches and diagonal collapses can break this; `why` names the first problem.
bool cage_is_manifold(const QuadCage& cage, std::string* why) {
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

std::string same_layout(int c) {
  return "quad: component " + std::to_string(c) + ": the same layout as an earlier choice";
}

// Why a layout choice's attempt failed (its error's message); a cancellation or bad input
// is thrown on, as is anything not a genbrep Error.
std::string attempt_failure(const std::exception_ptr& error) {
  try {
    std::rethrow_exception(error);
  } catch (const Error& e) {
    if (e.code() == Code::Cancelled || e.code() == Code::InvalidInput) throw;
    return e.what();
  }
}

// QuadStats::irregular_off_singularities and off_singularities of `cage`. Returns those
// vertices (matched_irregulars' entries with quarter turns no singularity explains).
std::vector<quad_detail::Irregular> count_off_singularities(
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

// The layout's two fingerprints, set as extract_once reaches them: the traced curves (with
// the options the rest reads) and the quantized patch layout.
struct LayoutKeys {
  std::optional<std::size_t> traced, quantized;
};

// An attempt's work (QuadOptions::work_per_component) when it reached each fingerprint and
// at its end: a choice whose layout the search has already seen is charged only what the
// search one choice at a time would have spent on it, up to the fingerprint that repeats.
struct AttemptWork {
  double traced = 0, quantized = 0, total = 0;
};

// The patches (indices into the layout's patches) that the quads of `cage` left turned
// over or degenerate came from: each such quad's centre is matched to the nearest quad
// centre of `filled`, the cage as fill_patches made it, whose patch `quad_patch` gives.
std::set<int> patches_of_bad_quads(const quad_detail::CageChecks& checks, const QuadCage& cage,
                                   const QuadCage& filled, const std::vector<int>& quad_patch) {
  auto centre = [](const QuadCage& of, int q) {
    Vec3 sum = Vec3::Zero();
    for (int k = 0; k < 4; ++k) sum += of.vertices.row(of.quads(q, k)).transpose();
    return Vec3(0.25 * sum);
  };
  std::vector<Vec3> filled_centres;
  for (int q = 0; q < filled.quads.rows(); ++q) filled_centres.push_back(centre(filled, q));
  std::set<int> patches;
  for (int q = 0; q < cage.quads.rows(); ++q) {
    Vec3 c[4];
    for (int k = 0; k < 4; ++k) c[k] = cage.vertices.row(cage.quads(q, k)).transpose();
    if (!degenerate_quad(cage, q) && !quad_detail::turned_over(checks.normals, checks.locator, c))
      continue;
    const Vec3 at = centre(cage, q);
    int nearest = -1;
    double best = 1e300;
    for (size_t f = 0; f < filled_centres.size(); ++f) {
      const double d = (filled_centres[f] - at).squaredNorm();
      if (d < best) best = d, nearest = static_cast<int>(f);
    }
    if (nearest >= 0) patches.insert(quad_patch[nearest]);  // one entry per filled quad
  }
  return patches;
}

// What every attempt at one component reads, the same for all of them: the (refined)
// surface the layout is traced on, the checks on the unrefined component, the field's
// singularities there, the quads the size field asks for (QuadStats::size_field_quads), and
// the density asked before any raise for dense singularities (QuadStats::squeezed_arcs).
struct ComponentInputs {
  const quad_detail::Surface& surface;
  const quad_detail::CageChecks& checks;
  const std::vector<quad_detail::SingularPoint>& singular;
  double asked;
  double unraised_density;
};

// What one reading of a layout gives: its fingerprints, the cage with its statistics and
// messages, the work spent, and per irregular vertex of the cage no singularity explains
// the spot a second reading prices higher (read_off_nodes_again).
struct Reading {
  LayoutKeys keys;
  QuadCage cage;
  QuadStats stats;
  quad_detail::Messages messages;
  AttemptWork work;
  std::vector<std::pair<Vec3, double>> unexplained;
};

// One attempt at one component: layout, quantization, filling, into *out. Throws
// Error{StageFailure} when the layout cannot be quantized or the filled cage is invalid,
// or when a fingerprint is in `seen` (a layout an earlier choice already had), or once
// `dropped`. Reads only its arguments, so attempts run on several threads at once.
// `costly_nodes`: the layout's Layout::costly_nodes.
void extract_once(const ComponentInputs& in, const QuadOptions& options,
                  const std::set<std::size_t>& seen, const quad_detail::Dropped& dropped,
                  const std::vector<std::pair<Vec3, double>>& costly_nodes, Reading* out) {
  const quad_detail::Surface& surface = in.surface;
  const quad_detail::CageChecks& checks = in.checks;
  const std::vector<quad_detail::SingularPoint>& singular = in.singular;
  LayoutKeys* keys = &out->keys;
  QuadCage* cage = &out->cage;
  QuadStats* stats = &out->stats;
  quad_detail::Messages* messages = &out->messages;
  AttemptWork* work = &out->work;
  const auto start = std::chrono::steady_clock::now();
  const int c = surface.component;
  quad_detail::Layout layout = quad_detail::start_layout(surface);
  layout.costly_nodes = costly_nodes;
  // The work so far: tracing, rounds of building patches, branch-and-bound nodes × arcs
  // of quantization, quads filled (weights: QuadOptions::work_per_component).
  const double triangles = static_cast<double>(surface.mesh.n_faces());
  double branching = 0;
  auto work_so_far = [&] {
    return triangles * (2 + layout.patch_rounds) + 15 * branching +
           850 * static_cast<double>(cage->quads.rows());
  };
  // Also when the attempt fails part way.
  struct Tally {
    std::function<double()> so_far;
    double* total;
    ~Tally() { *total = so_far(); }
  } tally{work_so_far, &work->total};
  quad_detail::trace_separatrices(surface, layout, options, *messages);
  // The rest is deterministic in the traced curves and the options it reads: a choice
  // that traced the same curves as an earlier one with the same options gives its result.
  std::size_t traced = (options.fit_corners ? (options.global_corners ? 3u : 2u) : 1u) * 1000003u +
                       static_cast<std::size_t>(options.max_balance_rounds) * 2u +
                       (options.kink_nodes ? 1u : 0u);
  for (const auto& curve : layout.curves)
    for (int v : curve.vertices) traced = traced * 1000003u + static_cast<std::size_t>(v) + 1;
  keys->traced = traced;
  work->traced = work_so_far();
  GENBREP_CHECK(!seen.count(traced), Code::StageFailure, same_layout(c));
  // A layout whose sides cannot balance (a strip that would need a loop arc at 0 edges)
  // has its unbalanced patches merged with a neighbour, a few rounds at most.
  quad_detail::PatchLayout patches;
  std::string failure;
  bool relaxed = false;
  int merged = 0, straightened = 0, tangle_rounds = 0, tangle_patches = 0;
  std::set<std::pair<int, int>> merged_arcs;  // stretches merge_patch took off, by their ends
  // Each round changes the layout in a few places: only the patches there are read again.
  quad_detail::PatchReading reading;
  // A cage whose untangling leaves quads turned over (one tangle, as measured) has the
  // patches those quads came from merged with a neighbour, and the layout quantized and
  // filled again (QuadOptions::max_tangle_rounds).
  for (int repair = 0;; ++repair) {
    quad_detail::Messages layout_messages;  // of the last round only
    for (int round = 0;; ++round) {
      dropped.check();
      layout_messages = {};
      patches = quad_detail::build_patches(surface, layout, options, layout_messages, &reading);
      const bool quantized = quad_detail::quantize(patches, options, &failure, &relaxed);
      branching += static_cast<double>(patches.quantize_nodes) * static_cast<double>(patches.arcs.size());
      if (quantized) break;
      int now = 0, taken = 0;
      // Cusp readings at an unbalanced patch are taken back first (always: they are
      // readings, not changes to the layout); only where there are none are the patches
      // merged.
      const std::vector<int> unbalanced = quad_detail::unbalanced_patches(patches);
      for (int p : unbalanced) taken += quad_detail::straighten_cusps(layout, patches, p);
      if (!taken && round < options.max_balance_rounds)
        for (int p : unbalanced)
          now += quad_detail::merge_patch(surface, layout, patches, p, &merged_arcs);
      GENBREP_CHECK(now + taken > 0, Code::StageFailure,
                    "quad: component " + std::to_string(c) + ": quantization of " +
                        std::to_string(patches.patches.size()) + " patches: " + failure +
                        (merged ? " (after merging " + std::to_string(merged) +
                                      " unbalanced patches)"
                                : std::string()));
      merged += now;
      straightened += taken;
    }
    if (repair == 0) {
      // Different choices often give the same quantized layout: it is filled only once.
      std::size_t fingerprint = patches.arcs.size();
      for (const auto& arc : patches.arcs)
        for (int value : {arc.vertices.front(), arc.vertices.back(), arc.count})
          fingerprint = fingerprint * 1000003u + static_cast<std::size_t>(value);
      for (const auto& patch : patches.patches)
        for (const auto& side : patch.sides)
          for (const auto& [a, reversed] : side)
            fingerprint = fingerprint * 1000003u + static_cast<std::size_t>(2 * a + reversed);
      keys->quantized = fingerprint;
      work->quantized = work_so_far();
      GENBREP_CHECK(!seen.count(fingerprint), Code::StageFailure, same_layout(c));
    }
    dropped.check();
    quad_detail::Messages filled_messages;  // of this fill only
    std::vector<int> quad_patch;
    *cage = quad_detail::fill_patches(surface, layout, patches, filled_messages, &quad_patch);
    const QuadCage filled = *cage;
    dropped.check();
    if (const int doublets = quad_detail::remove_doublets(*cage))
      filled_messages.notes.push_back("component " + std::to_string(c) + ": " +
                                      std::to_string(doublets) +
                                      " doublets (interior vertices of two quads) removed");
    *stats = measure_untangled(surface, checks, cage, &filled_messages, dropped, options,
                               options.place_irregulars ? &singular : nullptr);
    std::set<int> tangled;  // the patches the quads left turned over came from
    if ((stats->flipped_quads || stats->degenerate_quads) && repair < options.max_tangle_rounds)
      tangled = patches_of_bad_quads(checks, *cage, filled, quad_patch);
    int now = 0;
    for (int p : tangled)
      now += quad_detail::merge_patch(surface, layout, patches, p, &merged_arcs);
    if (!now) {
      messages->append(layout_messages);
      messages->append(filled_messages);
      break;
    }
    ++tangle_rounds;
    tangle_patches += now;
  }
  if (merged)
    messages->notes.push_back("component " + std::to_string(c) + ": " + std::to_string(merged) +
                           " patches whose sides could not balance merged with a neighbour");
  if (straightened)
    messages->notes.push_back("component " + std::to_string(c) + ": " +
                           std::to_string(straightened) +
                           " cusp corners read as quarter turns after all, so that the "
                           "layout's sides balance");
  if (relaxed)
    messages->notes.push_back("component " + std::to_string(c) +
                           ": the layout's sides balance only with some interior arcs at 0 edges");
  if (tangle_rounds)
    messages->notes.push_back("component " + std::to_string(c) + ": " +
                           std::to_string(tangle_patches) +
                           " patches under quads the untangling left turned over merged with a "
                           "neighbour and the layout filled again (" +
                           std::to_string(tangle_rounds) + (tangle_rounds > 1 ? " rounds)" : " round)"));
  stats->oversized_quads = quad_detail::oversized_quads(checks, *cage, options.density, kOversized);
  if (stats->oversized_quads) {
    char text[200];
    std::snprintf(text, sizeof text,
                  "component %d: %d quads have an edge longer than %gx the target edge length "
                  "(quantization squeezed patches whose opposite sides differ)",
                  c, stats->oversized_quads, kOversized);
    messages->warnings.push_back(text);
  }
  stats->patches = static_cast<int>(patches.patches.size());
  stats->squeezed_arcs = quad_detail::squeezed_arcs(patches, in.unraised_density);
  stats->separatrices = layout.separatrices;
  stats->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (layout.dropped_traces)
    messages->notes.push_back("component " + std::to_string(c) + ": " +
                           std::to_string(layout.dropped_traces) + " traces dropped");
  std::string why;
  GENBREP_CHECK(cage_is_manifold(*cage, &why), Code::StageFailure,
                "quad: component " + std::to_string(c) + ": the cage is not a valid 2-manifold: " + why);
  GENBREP_CHECK(stats->flipped_quads == 0 && stats->degenerate_quads == 0, Code::StageFailure,
                "the cage has " + std::to_string(stats->flipped_quads) + " flipped and " +
                    std::to_string(stats->degenerate_quads) + " degenerate quads");
  // The irregular vertices no singularity explains, each priced within off_node_radius ×
  // its reach (in kSingularReach units: local target edges or its own edges) if read again.
  out->unexplained.clear();
  for (const quad_detail::Irregular& x :
       count_off_singularities(checks, *cage, singular, options.density, stats))
    out->unexplained.push_back(
        {x.point, options.off_node_radius * x.reach / quad_detail::kSingularReach});
  stats->size_field_quads = in.asked;
}

// QuadOptions::off_node_price: the layout of `options` traced and read again, the nodes
// near the irregular vertices the first reading left away from singularities (its
// `unexplained`) priced higher; the second cage is kept in *first (cage, stats, messages)
// if better_second_reading says so, and the work of both is counted. A second attempt that
// fails leaves the first as it was.
void read_off_nodes_again(const ComponentInputs& in, const QuadOptions& options,
                          const quad_detail::Dropped& dropped, Reading* first) {
  Reading again;
  std::string failure;
  try {
    extract_once(in, options, {}, dropped, first->unexplained, &again);
  } catch (const Error& e) {
    if (e.code() != Code::StageFailure) throw;
    failure = e.what();
  }
  first->work.total += again.work.total;
  dropped.check();
  QuadStats* stats = &first->stats;
  quad_detail::Messages* messages = &first->messages;
  const int c = in.surface.component, before = stats->irregular_off_singularities;
  const std::string head = "component " + std::to_string(c) + ": the layout read again with " +
                           "the nodes near its " + std::to_string(before) +
                           " irregular vertices away from singularities priced higher";
  if (!failure.empty()) {
    messages->notes.push_back(head + " failed (" + failure + "); the first reading kept");
    return;
  }
  const int after = again.stats.irregular_off_singularities;
  if (!quad_detail::better_second_reading(again.stats, *stats)) {
    messages->notes.push_back(head + ": " + std::to_string(after) +
                              " away from singularities, not better; the first reading kept");
    return;
  }
  again.messages.notes.push_back(head + ": " + std::to_string(before) + " → " +
                                 std::to_string(after) + " away from singularities");
  first->cage = std::move(again.cage);
  *stats = again.stats;
  *messages = std::move(again.messages);
  first->unexplained = std::move(again.unexplained);
}

// How often the component's triangles are split for tracing (QuadOptions::
// trace_edges_per_cage_edge): the mean target size over the mean length of its edges.
int refine_levels(const quad_detail::Surface& s, const QuadOptions& options) {
  if (options.trace_edges_per_cage_edge <= 0) return 0;
  double size = 0, length = 0;
  int edges = 0;
  for (int v : s.vertices) size += s.vertex_size[v];
  size /= std::max<size_t>(1, s.vertices.size()) * options.density;
  for (auto e : s.mesh.edges()) {
    const auto h = s.mesh.halfedge_handle(e, 0);
    if (!s.in(s.face(h.idx())) && !s.in(s.face(h.idx() ^ 1))) continue;
    length += (s.point[s.to(h.idx())] - s.point[s.from(h.idx())]).norm();
    ++edges;
  }
  if (!edges || length <= 0) return 0;
  int levels = 0;
  for (double span = size / (length / edges); span < options.trace_edges_per_cage_edge &&
                                              levels < options.max_refine_levels;
       span *= 2)
    ++levels;
  return levels;
}

// The quads the size field asks for on the component at `density`: Σ area / (size_u ·
// size_v) over its triangles, times density² (QuadStats::size_field_quads).
double size_field_quads(const quad_detail::Surface& s, double density) {
  double quads = 0;
  for (auto f : s.mesh.faces())
    if (s.in(f.idx())) quads += s.face_quads(f.idx());
  return quads * (density * density);
}

// The factor (≥ 1) by which the density must rise for the component's cage to have
// `vertices_per_singular_quarter` vertices per quarter turn of traced singularity index.
double density_raise(const quad_detail::Surface& s, const QuadOptions& options) {
  if (options.vertices_per_singular_quarter <= 0) return 1;
  int quarters = 0;
  for (const Singularity& sing : s.field.singularities)
    if (sing.component == s.component && !sing.on_boundary) quarters += std::abs(sing.index);
  const double quads = size_field_quads(s, options.density);
  const double wanted = options.vertices_per_singular_quarter * quarters;
  return quads > 0 && quads < wanted ? std::sqrt(wanted / quads) : 1.0;
}

// Whether a cage meets issue 5's targets (interior valence 4 ≥ 95%, boundary valence 3
// ≥ 90%, mean corner deviation ≤ 12°).
bool meets_targets(const QuadStats& s) {
  return s.interior_valence4_fraction() >= 0.95 && s.boundary_valence3_fraction() >= 0.90 &&
         s.mean_angle_deviation_deg <= 12.0;
}

// Meets them with a margin (valence 4 ≥ 98%, valence 3 ≥ 95%, ≤ 8°), has no irregular
// vertex away from the field's singularities and follows the size field's density: no
// other layout choice is tried.
bool comfortably_meets_targets(const QuadStats& s) {
  return s.interior_valence4_fraction() >= 0.98 && s.boundary_valence3_fraction() >= 0.95 &&
         s.mean_angle_deviation_deg <= 8.0 && s.irregular_off_singularities == 0 &&
         s.size_field_miss() == 0;
}

}  // namespace

namespace quad_detail {
constexpr double kEvenDensityMiss = 0.1;  // ~10%
// A cage within 0.8–1.2× the quads its size field asks for beats one outside, and of two
// outside the nearer, by more than kEvenDensityMiss in log ratio (issue 5: density
// follows the size field): arches' second component, whose requested layout has 1.25×
// once pairs are drawn together, keeps a choice with 0.92×, and a sphere whose density is
// raised for its singularities the densest of its choices (all under half of what it asks).
// Then fewer squeezed arcs (patch rows gutted to half the edges their length asks for or
// less): on the genus-16 net at h 0.11 a choice with none off had a stub 2-3 quads across
// (its end an arc of 2 edges where the size field asks 4.1), and was kept for its none off
// over one with 2 off and the stub 6 across. Over 48 conversions (bench/quad_judge,
// off_node_count 3) this rule took the kept cages' squeezed arcs 6 → 1 and their irregular
// vertices off singularities 52 → 57 (oversized quads 1423 → 1409, skewed 1357 → 1344).
// Irregular vertices away from singularities count next (issue 5 wants none): none
// against some always wins; otherwise counts within 15% (or 2) of each other are even.
// Then skewed quads (a corner over 45° off square), counts within 20% (or 5) even: the
// 3 x 3 net's requested layout (15 off, 4.8°, 35 skewed, rows crumpled at two junctions)
// against a sparser choice (13 off, 5.2°, 20 skewed; was kept for its 13 alone). Then
// quads over 2.5x the target edge (oversized_quads), counts within 20% (or 5) even: the
// genus-36 net at h 0.125 kept a choice with 63 of them, a strut between two holes given
// half the columns, over one with 28, the two even on every count before and 0.09° apart
// in mean corner deviation. Irregular counts within 5% are even: lattice's requested layout
// had 130 at 9.3° against the joined layout's 131 at 6.8°, and the first one's fit folded.
bool better_cage(const QuadStats& a, const QuadStats& b) {
  return better_cage(a, meets_targets(a), b, meets_targets(b));
}
namespace {
// Whether counts x and y differ by more than `at_least` and `share` of the larger: not even.
bool uneven(int x, int y, double at_least, double share) {
  return std::abs(x - y) > std::max(at_least, share * std::max(x, y));
}
}  // namespace
bool better_cage(const QuadStats& a, bool meets_a, const QuadStats& b, bool meets_b) {
  if (meets_a != meets_b) return meets_a;
  if ((a.collapsed_quads > 0) != (b.collapsed_quads > 0)) return a.collapsed_quads == 0;
  const double miss_a = a.size_field_miss(), miss_b = b.size_field_miss();
  if (meets_a && (miss_a == 0) != (miss_b == 0)) return miss_a == 0;
  if (meets_a && std::abs(miss_a - miss_b) > kEvenDensityMiss) return miss_a < miss_b;
  if (meets_a && a.squeezed_arcs != b.squeezed_arcs) return a.squeezed_arcs < b.squeezed_arcs;
  const int off_a = a.irregular_off_singularities, off_b = b.irregular_off_singularities;
  if (meets_a && off_a != off_b && (std::min(off_a, off_b) == 0 || uneven(off_a, off_b, 1, 0.15)))
    return off_a < off_b;
  if (meets_a && uneven(a.skewed_quads, b.skewed_quads, 5, 0.2))
    return a.skewed_quads < b.skewed_quads;
  if (meets_a && uneven(a.oversized_quads, b.oversized_quads, 5, 0.2))
    return a.oversized_quads < b.oversized_quads;
  if (meets_a && uneven(a.irregular_vertices, b.irregular_vertices, 0, 0.05))
    return a.irregular_vertices < b.irregular_vertices;
  return a.mean_angle_deviation_deg < b.mean_angle_deviation_deg;
}

// A second reading is kept only if it leaves fewer irregular vertices off singularities
// (what it is for) and is the better cage: the genus-36 net at h 0.14 kept one that went
// 4 → 6 off for the one quad the first had collapsed, with a valence 7 and two 3s crowded
// at a hole corner. Over 48 conversions (bench/quad_judge) requiring fewer took 57 → 54
// off singularities, oversized quads 1409 → 1398, skewed 1344 → 1311.
bool better_second_reading(const QuadStats& second, const QuadStats& first) {
  return second.irregular_off_singularities < first.irregular_off_singularities &&
         better_cage(second, first);
}
}  // namespace quad_detail

namespace {

// One component. The layout depends on a few discrete choices (how corners are read,
// whether separatrices join nearly parallel curves, which singularity pairs cancel, which
// singularities the boundary absorbs, whether separatrices cross, whether unbalanced
// patches are merged, what a curve arriving at a singularity records). They are tried in
// turn, each from scratch (a layout equal to an earlier one is not filled again), until a
// cage meets the targets with a margin and has no irregular vertex away from the field's
// singularities (comfortably_meets_targets), or until the work budget after the first cage
// that meets them is spent (QuadOptions::work_after_meeting, min_choices_after_meeting). Kept:
// among the cages meeting the targets, preferably one that needed no quad collapsed (a collapse
// leaves a valence-6 vertex whose pulled limit surface can fold), then the density nearest the
// size field's, then the fewest squeezed arcs, then the fewest irregular
// vertices away from the field's singularities (counts within 15% or 2 even, unless one is none),
// then the fewest skewed quads (within 20% or 5 even), then the fewest quads over 2.5x the
// target edge (the same), then the fewest irregular vertices (counts within 5% of each other
// are even), then the smallest mean corner deviation (better_cage); if none
// meets them, the valid cage with the smallest mean corner deviation. The choice that was used is
// reported when it is not the requested one.
void extract_component(const TriMesh& design, const Partition& partition, const CrossField& field,
                       const QuadOptions& options, int c, QuadResult* out) {
  struct Variant { std::string what; QuadOptions options; };
  std::vector<Variant> variants;
  const std::pair<const char*, std::function<void(QuadOptions&)>> layouts[] = {
      {"", [](QuadOptions&) {}},
      {"singularity pairs within 2x the cancel distance cancelled",
       [](QuadOptions& o) { o.pair_cancel_distance *= 2; }},
      {"separatrices joined to nearly parallel curves",
       [](QuadOptions& o) { o.join_parallel = !o.join_parallel; }},
      {"singularity pairs within 2x the cancel distance cancelled, separatrices joined to "
       "nearly parallel curves",
       [](QuadOptions& o) { o.pair_cancel_distance *= 2, o.join_parallel = !o.join_parallel; }},
      {"separatrices crossing", [](QuadOptions& o) { o.cross_separatrices = !o.cross_separatrices; }},
      {"singularities within 2x the absorb distance left to the boundary",
       [](QuadOptions& o) { o.boundary_absorb_distance *= 2; }},
      {"both distances doubled",
       [](QuadOptions& o) { o.pair_cancel_distance *= 2, o.boundary_absorb_distance *= 2; }},
      {"both distances doubled, separatrices crossing", [](QuadOptions& o) {
         o.pair_cancel_distance *= 2, o.boundary_absorb_distance *= 2;
         o.cross_separatrices = !o.cross_separatrices;
       }}};
  // Merging unbalanced patches is tried only after every choice without it (but joins and
  // the requested layout).
  for (bool balance : {false, true})
    for (const auto& [what, change] : layouts)
      for (int corners : {0, 1, 2}) {  // as asked; all at once or patch by patch; re-read
        QuadOptions o = options;
        change(o);
        if (corners == 1 && !o.fit_corners) continue;
        if (corners == 1) o.global_corners = !o.global_corners;
        if (corners == 2) o.fit_corners = !o.fit_corners;
        const bool flip_corners = corners != 0;
        std::string name = what;
        if (flip_corners) {
          name += name.empty() ? "" : ", ";
          name += corners == 1 ? (o.global_corners ? "corners chosen for all patches at once"
                                                   : "corners fitted patch by patch")
                  : o.fit_corners ? "corners fitted as rectangles"
                                  : "corners re-read one at a time";
        }
        // Joins leave layouts that often balance only once a join is taken back (merging
        // an unbalanced patch drops its shortest arc, the link): they are tried with
        // merging in the first pass already, and not again.
        if (o.join_parallel && balance) continue;
        if (balance) {
          name += name.empty() ? "" : ", ";
          name += "unbalanced patches merged";
        } else if (!o.join_parallel && !(what[0] == '\0' && corners != 2)) {
          // The requested layout (corners chosen either way) merges unbalanced patches too:
          // through Blender, lattice's was one small patch from balancing, and without
          // merging a sparser choice with 22 irregular vertices off singularities was kept
          // (4 with the merge).
          o.max_balance_rounds = 0;
        }
        variants.push_back({name, o});
      }
  // The requested layout with its arrivals recorded the other way (QuadOptions::
  // arrival_chord) comes second, so that it runs beside the requested one and is compared
  // with it on every component (min_choices_after_meeting).
  {
    QuadOptions o = variants[0].options;
    o.arrival_chord = !o.arrival_chord;
    variants.insert(variants.begin() + 1,
                    {o.arrival_chord ? "arrivals recording their chord"
                                     : "arrivals recording the field's direction",
                     o});
  }
  const quad_detail::Surface coarse(design, partition, field, c);
  // Raise the density where singularities are dense (QuadOptions::vertices_per_singular_quarter).
  const double raise = density_raise(coarse, options);
  if (raise > 1) {
    char text[160];
    std::snprintf(text, sizeof text,
                  "component %d: density raised %.2gx so that its singularities are at most "
                  "1 in %.0f cage vertices",
                  c, raise, options.vertices_per_singular_quarter);
    out->notes.push_back(text);
    for (auto& variant : variants) variant.options.density *= raise;
  }
  const double asked = size_field_quads(coarse, variants[0].options.density);
  const auto preparing = std::chrono::steady_clock::now();
  const int levels = refine_levels(coarse, variants[0].options);
  const quad_detail::RefinedDesign refined =
      quad_detail::refine_component(design, partition, field, c, levels);
  const bool finer = refined.mesh.n_faces() > 0;  // else: nothing needed splitting
  std::optional<quad_detail::Surface> refined_surface;
  if (finer) refined_surface.emplace(refined.mesh, refined.partition, refined.field, c);
  const quad_detail::Surface& surface = refined_surface ? *refined_surface : coarse;
  // Checks run on the unrefined component: the same surface, a sixteenth of the triangles.
  const quad_detail::CageChecks checks(coarse);
  int triangles = 0;  // of the (refined) component
  for (auto f : surface.mesh.faces()) triangles += surface.in(f.idx());
  if (finer) {
    char text[200];
    std::snprintf(text, sizeof text,
                  "component %d: refined round its singularities%s for tracing (%d triangles) "
                  "in %.1f s",
                  c, levels > 0 ? (" and " + std::to_string(1 << (2 * levels)) + "x").c_str() : "",
                  triangles,
                  std::chrono::duration<double>(std::chrono::steady_clock::now() - preparing).count());
    out->notes.push_back(text);
  }
  // The component's field singularities (QuadStats).
  std::vector<quad_detail::SingularPoint> singular;
  for (const auto& point : field.singularities)
    if (point.component == c) singular.push_back({coarse.point[point.vertex], point.index});
  std::set<std::size_t> seen_layouts;
  std::string first_failure, requested_failure;
  int best = -1;
  QuadCage best_cage;
  QuadStats best_stats;
  bool best_meets = false, best_squaring_tried = false;
  std::optional<Squared> best_squared;
  // The requested layout's cage, if it was valid (as judged: its angles after squaring).
  std::optional<QuadStats> requested_stats;
  quad_detail::Messages best_messages;
  // Once a cage meets the targets, more choices are tried only within a work budget:
  // choices × the (refined) component's triangles (QuadOptions::work_after_meeting), but
  // at least min_choices_after_meeting, counting only choices that traced a new layout (a
  // repeated one stops after tracing).
  int first_meeting = -1, tried_after_meeting = 0;
  const int choices_after_meeting =
      std::max(options.min_choices_after_meeting,
               static_cast<int>(options.work_after_meeting / std::max(1, triangles)));
  // The work the attempts spent, summed in choice order (QuadOptions::work_per_component).
  double work_spent = 0;
  auto out_of_work = [&](size_t tried) {
    if (tried == 0 || work_spent < options.work_per_component) return false;
    char text[200];
    std::snprintf(text, sizeof text,
                  "component %d: stopped trying layout choices after %.3g units of work "
                  "(work_per_component), %zu of %zu tried",
                  c, work_spent, tried, variants.size());
    out->diagnostics.push_back(text);
    return true;
  };
  // Choices run in batches of `threads` at once (each attempt reads only shared constant
  // data); their results are taken in order, exactly as if they had run one after another:
  // a layout an earlier choice of the same batch already had counts as repeated, and a
  // batch's later results are dropped once the search would have stopped.
  const int threads = std::max(
      1, options.parallel_choices > 0
             ? options.parallel_choices
             : std::min(4, static_cast<int>(std::thread::hardware_concurrency())));
  const ComponentInputs inputs{surface, checks, singular, asked, options.density};
  struct Attempt : Reading {
    std::exception_ptr error;
    // A cage that meets the targets but for its corner angles is squared before it is
    // judged (the targets are the output cage's, and squaring makes it): the copy, if it
    // came closer to 90°. Choices are still compared on the angles before squaring.
    std::optional<Squared> squared;
    bool squaring_tried = false;
    bool dropped = false;  // it ended in an error after it was told to stop
    bool needs_squaring() const {
      QuadStats square = stats;
      square.mean_angle_deviation_deg = 0;
      return !error && !meets_targets(stats) && meets_targets(square);
    }
    QuadStats judged() const {  // what the targets are checked on
      QuadStats judged = stats;
      if (squared) judged.mean_angle_deviation_deg = squared->mean_deg;
      return judged;
    }
  };
  // Choice k's attempt becomes the cage kept so far.
  auto keep = [&](size_t k, Attempt& a, bool meets) {
    best = static_cast<int>(k);
    best_cage = std::move(a.cage);
    best_stats = a.stats;
    best_meets = meets;
    best_squared = std::move(a.squared);
    best_squaring_tried = a.squaring_tried;
    best_messages = std::move(a.messages);
  };
  // Choice k's second reading (read_off_nodes_again), where its first left irregular
  // vertices away from singularities: off_node_share of them, or off_node_count.
  auto wants_second_reading = [&](size_t k, const Attempt& a) {
    const QuadOptions& o = variants[k].options;
    const int off = a.stats.irregular_off_singularities;
    return !a.error && o.off_node_price > 0 && off > 0 &&
           (off >= o.off_node_share * a.stats.irregular_vertices ||
            (o.off_node_count > 0 && off >= o.off_node_count));
  };
  auto read_again = [&](size_t k, Attempt* a, const quad_detail::Dropped& dropped) {
    if (!wants_second_reading(k, *a)) return;
    try {
      read_off_nodes_again(inputs, variants[k].options, dropped, a);
    } catch (...) {
      a->error = std::current_exception();
      a->dropped = dropped.stopped();
    }
  };
  // Choice k's attempt: its first reading, and its second unless `first_only`.
  auto attempt = [&](size_t k, const std::set<std::size_t>& seen, Attempt* a,
                     const quad_detail::Dropped& dropped, bool first_only = false) {
    try {
      extract_once(inputs, variants[k].options, seen, dropped, {}, a);
    } catch (...) {
      a->error = std::current_exception();
      a->dropped = dropped.stopped();
      return;
    }
    if (!first_only) read_again(k, a, dropped);
  };
  // QuadOptions::pair_second_readings: the first batch holds the requested layout and its
  // sibling, however many threads there are (not where the work allows the requested one
  // only: work_per_component 0).
  const bool pair_readings =
      options.pair_second_readings && options.work_per_component > 0 && variants.size() >= 2;
  bool stop = false;
  for (size_t k = 0; k < variants.size() && !stop;) {
    if (out_of_work(k)) break;
    if (first_meeting >= 0 && tried_after_meeting >= choices_after_meeting) break;
    const bool pair = pair_readings && k == 0;
    const size_t batch =
        std::min(variants.size() - k, static_cast<size_t>(pair ? std::max(threads, 2) : threads));
    std::vector<Attempt> attempts(batch);
    // The layouts seen before the batch, as every attempt of it reads them (the search
    // adds to seen_layouts while later attempts still run).
    const std::set<std::size_t> seen_before = seen_layouts;
    // Results are taken as their attempts end, in order; once the search stops, the
    // batch's later attempts are dropped (on the 6 x 6 net the requested layout's sibling
    // ran 1.8 s past it, for a result the search would not look at). Also when a result
    // throws: every worker is told and joined.
    std::atomic<bool> drop{false};
    std::vector<std::thread> workers;
    struct JoinAll {
      std::atomic<bool>& drop;
      std::vector<std::thread>& workers;
      ~JoinAll() {
        drop = true;
        for (auto& worker : workers)
          if (worker.joinable()) worker.join();
      }
    } join_all{drop, workers};
    // On one thread the pair's sibling runs after the requested layout, on this one.
    for (size_t i = 1; i < batch && threads > 1; ++i)
      workers.emplace_back([&, i, first = k, only = pair && i == 1] {
        attempt(first + i, seen_before, &attempts[i], quad_detail::Dropped(&drop), only);
        quad_detail::release_quantize_thread();
      });
    attempt(k, seen_before, &attempts[0], quad_detail::Dropped(), pair);
    if (pair) {
      // The pair's first readings, then their second readings (pair_second_readings).
      if (threads > 1)
        workers[0].join();
      else
        attempt(k + 1, seen_before, &attempts[1], quad_detail::Dropped(), true);
      bool again[2];
      for (int i : {0, 1}) {
        const Attempt &a = attempts[i], &other = attempts[1 - i];
        again[i] = wants_second_reading(k + i, a);
        if (!again[i] || other.error || other.stats.irregular_off_singularities) continue;
        // Beside one that left none: only where, with none left and the corner angles
        // even, it would be kept over that one.
        QuadStats none_left = a.stats;
        none_left.irregular_off_singularities = 0;
        none_left.mean_angle_deviation_deg = other.stats.mean_angle_deviation_deg;
        again[i] = quad_detail::better_cage(none_left, meets_targets(a.stats), other.stats,
                                            meets_targets(other.stats));
        if (!again[i])
          out->notes.push_back(
              "component " + std::to_string(c) + ": " +
              (i == 0 ? "the requested layout" : "the layout with " + variants[k + 1].what) +
              " not read again: " +
              (i == 0 ? "the layout with " + variants[k + 1].what : "the requested one") +
              " left no irregular vertex away from singularities, and would be kept even if "
              "a second reading left none (pair_second_readings)");
      }
      if (again[1] && threads > 1)
        workers[0] = std::thread([&, first = k] {
          read_again(first + 1, &attempts[1], quad_detail::Dropped(&drop));
          quad_detail::release_quantize_thread();
        });
      if (again[0]) read_again(k, &attempts[0], quad_detail::Dropped());
      if (again[1] && threads == 1) read_again(k + 1, &attempts[1], quad_detail::Dropped());
    }
    // The batch's first cage needs squaring before it is judged, and would end the search
    // if it then meets the targets (no choice is tried after meeting): the others are
    // dropped and it is squared on every thread. If it still misses, the others that had
    // ended before the drop are taken as they are, and the next batch starts at the first
    // one that was cut short (the 8 x 8 net ran its second choice, 13 s, twice).
    size_t taken = batch;
    for (size_t i = 0; i < taken && !stop; ++i, ++k) {
      if (i > 0 && ((first_meeting >= 0 && tried_after_meeting >= choices_after_meeting) ||
                    out_of_work(k))) {
        stop = true;
        break;
      }
      if (i > 0 && i - 1 < workers.size() && workers[i - 1].joinable()) workers[i - 1].join();
      Attempt& a = attempts[i];
      // Repeated layouts, as the sequential search sees them, and the work it would spend.
      bool grew = false, repeated = false;
      double work = a.work.total;
      if (a.keys.traced) {
        repeated = seen_layouts.count(*a.keys.traced) > 0;
        if (repeated) work = a.work.traced;
        if (!repeated) grew = seen_layouts.insert(*a.keys.traced).second;
      }
      if (!repeated && a.keys.quantized) {
        repeated = !seen_layouts.insert(*a.keys.quantized).second;
        if (repeated) work = a.work.quantized;
        grew |= !repeated;
      }
      work_spent += work;
      std::string failure;
      if (repeated) {
        failure = same_layout(c);
      } else if (a.error) {
        failure = attempt_failure(a.error);
      }
      if (!failure.empty()) {
        tried_after_meeting += first_meeting >= 0 && grew;
        if (first_failure.empty()) first_failure = failure;
        if (k == 0) requested_failure = failure;
        continue;
      }
      tried_after_meeting += first_meeting >= 0;
      if (a.needs_squaring()) {
        int squaring_threads = i + 1 == batch ? threads : 1;  // the batch's others still run
        if (i == 0 && batch > 1 && first_meeting < 0 && choices_after_meeting == 0) {
          drop = true;
          for (auto& worker : workers)
            if (worker.joinable()) worker.join();
          taken = 1;
          while (taken < batch && !attempts[taken].dropped) ++taken;
          squaring_threads = threads;
        }
        a.squared = square_copy(checks, variants[k].options.density, squaring_threads, a.cage,
                                a.stats);
        a.squaring_tried = true;
      }
      const QuadStats judged = a.judged();
      const bool meets = meets_targets(judged);
      if (k == 0) requested_stats = judged;
      // Collapsed quads mean the layout itself was broken there: such a cage ranks below
      // every collapse-free one (better_cage), but a valid field-aligned cage still beats the
      // fallback (the genus-64 net's: 97.6% valence 4 at 13.9°, against the fallback's 85%).
      if (best < 0 || quad_detail::better_cage(a.stats, meets, best_stats, best_meets))
        keep(k, a, meets);
      if (comfortably_meets_targets(judged) && !judged.collapsed_quads && best == int(k))
        stop = true;
      if (first_meeting < 0 && meets) first_meeting = static_cast<int>(k);
    }
  }
  // Last field-aligned resort before the fallback cage: the requested layout without kink
  // nodes (QuadOptions::kink_nodes). Their corners can leave a layout that no integer counts
  // balance (lattice's requested layout at h 0.125: 266 patches, 14 merged, none balance),
  // and where every choice the component's work allowed failed so, the layout as it is
  // read without them still gives a field-aligned cage. One more attempt, on this thread.
  if (best < 0 && variants[0].options.kink_nodes) {
    Variant plain = variants[0];
    plain.what = "no quarter turn along a curve read as a node";
    plain.options.kink_nodes = false;
    variants.push_back(plain);
    Attempt a;
    attempt(variants.size() - 1, {}, &a, quad_detail::Dropped());
    if (a.error)
      attempt_failure(a.error);  // a failure here leaves the fallback cage
    else
      keep(variants.size() - 1, a, meets_targets(a.judged()));
  }
  if (best >= 0) {
    add_messages(best_messages, out);
    if (best > 0) {
      std::string why = "the requested one failed: " + requested_failure;
      if (requested_stats && !meets_targets(*requested_stats)) {
        char text[240];
        std::snprintf(text, sizeof text,
                      "the requested one missed the targets: %.1f%% interior valence 4, %.1f%% "
                      "boundary valence 3, %.1f° mean corner deviation",
                      100 * requested_stats->interior_valence4_fraction(),
                      100 * requested_stats->boundary_valence3_fraction(),
                      requested_stats->mean_angle_deviation_deg);
        why = text;
      } else if (requested_stats) {
        char text[240];
        std::snprintf(text, sizeof text,
                      "%d irregular vertices (%d away from singularities), %.1f° mean corner "
                      "deviation, %d collapsed quads; the requested one: %d (%d), %.1f°, %d",
                      best_stats.irregular_vertices, best_stats.irregular_off_singularities,
                      best_stats.mean_angle_deviation_deg, best_stats.collapsed_quads,
                      requested_stats->irregular_vertices,
                      requested_stats->irregular_off_singularities,
                      requested_stats->mean_angle_deviation_deg, requested_stats->collapsed_quads);
        why = text;
      }
      out->notes.push_back("component " + std::to_string(c) +
                           ": the cage uses the layout with " + variants[best].what + " (" + why +
                           ")");
    }
    if (best_squared)
      keep_squared(std::move(*best_squared), c, &best_cage, &best_stats, &out->notes);
    else if (!best_squaring_tried)
      square_kept(checks, variants[best].options.density, c, threads, &best_cage, &best_stats,
                  &out->notes);
    // Counted again on the squared cage: squaring moves the vertices round an irregular
    // one, and with them its mean edge, so its reach (48 conversions: one more, the 3 x 3
    // net at h 0.115, a 5 whose reach fell under its singularity's distance).
    count_off_singularities(checks, best_cage, singular, variants[best].options.density,
                            &best_stats);
    if (!meets_targets(best_stats)) {
      char text[240];
      std::snprintf(text, sizeof text,
                    "component %d: no layout choice met the targets; the cage is the best "
                    "field-aligned one (%.1f%% interior valence 4, %.1f%% boundary valence 3, "
                    "%.1f° mean corner deviation, %d quads collapsed along a diagonal)",
                    c, 100 * best_stats.interior_valence4_fraction(),
                    100 * best_stats.boundary_valence3_fraction(),
                    best_stats.mean_angle_deviation_deg, best_stats.collapsed_quads);
      out->diagnostics.push_back(text);
    }
    out->cages.push_back(std::move(best_cage));
    out->stats.push_back(best_stats);
    return;
  }
  // Last resort: the split coarse remesh, valid by construction but not field-aligned.
  // A coarse remesh of a thin part can fold; then it is made finer.
  double size = 0;
  for (int v : surface.vertices) size += surface.vertex_size[v];
  size /= std::max<size_t>(1, surface.vertices.size()) * options.density;
  const auto start = std::chrono::steady_clock::now();
  QuadCage cage;
  QuadStats stats;
  double scale = 0;
  bool valid = false;
  quad_detail::Messages untangled;  // of the rejected tries too: only the last one's is kept
  for (double factor : {2.0, 1.5, 1.0, 0.75}) {
    cage = quad_detail::fallback_cage(coarse, factor * size);
    untangled = {};
    stats = measure_untangled(surface, checks, &cage, &untangled, quad_detail::Dropped(), options);
    scale = factor;
    std::string why;
    valid = !stats.flipped_quads && !stats.degenerate_quads && cage_is_manifold(cage, &why);
    if (valid) break;
  }
  stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  stats.fallback = true;
  GENBREP_CHECK(valid, Code::StageFailure,
                first_failure + " (and " + std::to_string(variants.size() - 1) +
                    " alternative layouts and the fallback cage failed too)");
  char scale_text[16];
  std::snprintf(scale_text, sizeof scale_text, "%.2g", scale);
  out->diagnostics.push_back(
      "component " + std::to_string(c) + ": no field-aligned layout gave a valid cage (" +
      first_failure + "); the cage is the FALLBACK: a coarse remesh (edge " + scale_text +
      " x the target) split into quads, not aligned with the field, "
      "with irregular vertices wherever triangles could not be paired");
  add_messages(untangled, out);
  square_kept(checks, variants[0].options.density / scale, c, threads, &cage, &stats, &out->notes);
  count_off_singularities(checks, cage, singular, variants[0].options.density, &stats);
  out->cages.push_back(std::move(cage));
  stats.size_field_quads = asked;
  out->stats.push_back(stats);
}

}  // namespace

}  // namespace genbrep

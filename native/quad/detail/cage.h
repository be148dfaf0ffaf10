// quad/detail/cage.h — internals of quad/: what a cage is checked against (closest points on the
// component, the design's normals), its measures (measure.cpp) and the matching of its irregular
// vertices to field singularities.
#pragma once
#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <memory>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "core/cage.h"
#include "quad/detail/surface.h"

namespace genbrep::quad_detail {

// Closest points on the component's triangles (locate.cpp), with the normal of the face hit.
class ComponentLocator {
 public:
  explicit ComponentLocator(const Surface& s);
  ~ComponentLocator();
  Vec3 closest(const Vec3& p, Vec3* normal) const;
  // The same, starting the search from triangle *hint (a previous answer near p; -1: none)
  // and leaving the triangle hit there: the same point, found faster.
  Vec3 closest(const Vec3& p, Vec3* normal, int* hint) const;
  // The unit normals of the component's triangles that hold the point closest to p: its
  // triangle's, or where that point lies on an edge or a vertex (a point off a crease)
  // those of every component triangle there, so that the answer does not depend on which
  // of them the search met first (the hint).
  std::vector<Vec3> normals_at(const Vec3& p, int* hint) const;

 private:
  struct Impl;
  const Surface& surface_;
  std::unique_ptr<Impl> impl_;
};

// A quad whose normal is more than 75° from the design's at every corner spans a thin
// part (DesignNormals::spans_thin_part); a quad wrapping a third of a round strut is at
// 60°.
constexpr double kThinPartCosine = 0.26;

// The one test for a turned-over quad, shared by measure_cage and untangle_cage: the quad's
// normal (cross product of its diagonals) against the area-weighted vertex normal of the
// design vertex nearest its centroid (a uniform grid over the design's box, cells about
// 1.5 mean edges wide, vertices bucketed per cell; the nearest found exactly in O(1) cells
// for a point on the surface), and the thin-part test at its corners.
class DesignNormals {
 public:
  explicit DesignNormals(const TriMesh& design);
  int nearest_vertex(const Vec3& p) const;   // -1 if the design has no vertex
  Vec3 nearest_normal(const Vec3& p) const;  // zero if the design has no vertex
  // The same, and whether that vertex sits on a crease: one of its triangles' normals more
  // than acos(kFaceCheckCosine) = 30° from its normal, so that its normal does not stand
  // for the surface round it.
  Vec3 nearest_normal(const Vec3& p, bool* creased) const;
  // Whether a quad faces against the design: its normal ((c2 − c0) × (c3 − c1)) against
  // the design's at the vertex nearest its centre, or it spans a thin part.
  bool flipped(const Vec3 (&corner)[4]) const;
  // Whether the design turns away from the quad at all four corners (its normal there
  // more than acos(kThinPartCosine) from the quad's, `across` unnormalized): a quad cut
  // across a strut, its corners on opposite sides of it.
  bool spans_thin_part(const Vec3 (&corner)[4], const Vec3& across) const;

 private:
  std::vector<Vec3> point_, normal_;
  std::vector<char> creased_;  // per vertex (nearest_normal)
  Vec3 lo_;
  double cell_ = 1;
  std::array<long, 3> cells_{};   // per axis
  std::vector<int> first_;        // per cell (x fastest) and one past the last: into vertex_
  std::vector<int> vertex_;       // the vertices of each cell, ascending
  std::array<long, 3> key(const Vec3& p) const;
};

// Per cage vertex: whether it lies on a boundary chain (never moved or merged away by
// untangle.cpp, not counted by irregular_off_singularities), the quads around it and its
// edge neighbours.
struct CageIncidence {
  explicit CageIncidence(const QuadCage& cage)
      : on_chain(cage.vertices.rows(), 0),
        quads_of(cage.vertices.rows()),
        neighbours(cage.vertices.rows()) {
    for (const auto& chain : cage.boundary_chains)
      for (int v : chain) on_chain[v] = 1;
    for (int q = 0; q < cage.quads.rows(); ++q)
      for (int k = 0; k < 4; ++k) {
        const int a = cage.quads(q, k), b = cage.quads(q, (k + 1) % 4);
        quads_of[a].push_back(q);
        neighbours[a].insert(b), neighbours[b].insert(a);
      }
  }
  std::vector<char> on_chain;
  std::vector<std::vector<int>> quads_of;
  std::vector<std::set<int>> neighbours;
};

// What measuring and repairing a cage test against, built once per component: closest
// points on the component and the design's vertex normals.
struct CageChecks {
  explicit CageChecks(const Surface& s) : surface(s), locator(s), normals(s.mesh) {}
  const Surface& surface;
  ComponentLocator locator;
  DesignNormals normals;
};

// Quads with an edge longer than `factor` × the local target edge length (the component's
// size at the design vertex nearest the quad's centre, divided by `density`): where
// quantization squeezed a patch whose opposite sides differ, its quads stretch across
// (quad.cpp).
int oversized_quads(const CageChecks& checks, const QuadCage& cage, double density,
                    double factor);
// A field singularity: where, and its index in quarter turns (−1: five quads meet there).
struct SingularPoint {
  Vec3 point;
  int index;
};
// How far a singularity explains an irregular vertex, in edges (the vertex's own mean
// edge or the local target edge, the longer): a traced singular node can end up about one
// edge off after the evening out and the merges of quantization, and merged ones (valence
// 6 and 7) further where the cage is coarser than the target.
constexpr double kSingularReach = 2.0;
// Interior vertices of `cage` (not on a boundary chain) of valence ≠ 4 whose quarter turns
// (4 − valence) are not all explained by singularities of `singular` of the same sign
// within kSingularReach edges (the vertex's mean edge, or the local target edge — the
// design's size at the nearest vertex over `density` — if longer). Each singularity
// explains at most |index| quarter turns, nearest
// vertex–singularity pairs first; a valence-3 vertex beside a −1 singularity, or a second
// valence-5 vertex beside one, is not explained. O(irregular × singular).
int irregular_off_singularities(const CageChecks& checks, const QuadCage& cage,
                                const std::vector<SingularPoint>& singular, double density);
// An irregular interior cage vertex as irregular_off_singularities matches it: the quarter
// turns it carries (4 − valence), where it is, and how far a singularity explains it.
struct Irregular {
  int vertex;  // ties between equal distances go by vertex, then singularity
  int carries;
  Vec3 point;
  double reach;
};
// kSingularReach × (the vertex's mean edge, or the local target edge if longer).
double singular_reach(const CageChecks& checks, const QuadCage& cage,
                      const CageIncidence& incidence, int v, double density);
// A singularity of the same sign within reach of an irregular vertex (`entry`: its index
// in the list matched).
struct Explaining {
  double distance;
  int entry, point;
};
// Appends the singularities that can explain `irregular` (entry `entry`) to `pairs`.
void explaining_pairs(const Irregular& irregular, int entry,
                      const std::vector<SingularPoint>& singular, std::vector<Explaining>* pairs);
// The order the matching takes pairs in: nearest first, then by the entry's vertex
// (`vertex`), then by singularity. No two pairs share a key.
inline std::tuple<double, int, int> pair_order(const Explaining& pair, int vertex) {
  return {pair.distance, vertex, pair.point};
}
// Sorts `pairs` by pair_order, `vertex_of(entry)` giving each entry's vertex.
template <class VertexOf>
void sort_pairs(std::vector<Explaining>& pairs, VertexOf vertex_of) {
  std::sort(pairs.begin(), pairs.end(), [&](const Explaining& a, const Explaining& b) {
    return pair_order(a, vertex_of(a.entry)) < pair_order(b, vertex_of(b.entry));
  });
}
// irregular_off_singularities' matching of `pairs` (sorted here by pair_order): nearest
// first, each singularity explaining at most |index| quarter turns. Per entry of
// `irregular`, the quarter turns left unexplained (0: explained), into `carries`.
void match_pairs(std::vector<Explaining>& pairs, const std::vector<Irregular>& irregular,
                 const std::vector<SingularPoint>& singular, std::vector<int>* carries);
// The same with `pairs` already sorted, and `carries` holding, per entry, the quarter turns
// it carries.
void match_sorted_pairs(const std::vector<Explaining>& pairs,
                        const std::vector<SingularPoint>& singular, std::vector<int>* carries);
// The interior irregular vertices of `cage` (`incidence` its CageIncidence) as
// irregular_off_singularities matches them, and per entry in `left` the quarter turns no
// singularity explains.
std::vector<Irregular> matched_irregulars(const CageChecks& checks, const QuadCage& cage,
                                          const CageIncidence& incidence,
                                          const std::vector<SingularPoint>& singular,
                                          double density, std::vector<int>* left);

// measure_cage (quad.h) with the design's normals already built.
QuadStats measure_cage(const QuadCage& cage, const DesignNormals& normals);
// The same with the component: a quad is flipped by turned_over, which also finds one
// that stands on the surface under it. The stage measures with this one.
QuadStats measure_cage(const QuadCage& cage, const CageChecks& checks);
// Whether a quad faces against the component's triangles at the point closest to its
// centre, or stands on them: its normal (the cross product of its diagonals) more than
// kStandingDegrees from theirs (ComponentLocator::normals_at). *hint as in
// ComponentLocator::closest.
constexpr double kStandingDegrees = 80.0;
bool faces_away(const ComponentLocator& locator, const Vec3 (&corner)[4], int* hint = nullptr);
// The one test for a turned-over quad where the component is at hand (measure_cage with
// the checks, and the untangling's, evening out's and squaring's quad_is_bad, so that a
// move they allow never makes a cage the measure rejects): DesignNormals::flipped, and
// unless the quad's normal is within acos(kFaceCheckCosine) = 30° of the nearest design
// vertex's and that vertex is not on a crease, faces_away. (On a crease the vertex's
// normal is the mean of two sides, and a quad folded over it can agree with that mean.
// The design vertex nearest a quad's centre can also lie round a fillet from the surface
// under it, hence the tight 30°.) Looking up every quad's triangle is what this costs.
constexpr double kFaceCheckCosine = 0.866;
bool turned_over(const DesignNormals& normals, const ComponentLocator& locator,
                 const Vec3 (&corner)[4], int* hint = nullptr);


// The angle at `at` between the edges to a and b, in radians (measure_cage, the untangle,
// the squaring).
double corner_angle(const Vec3& at, const Vec3& a, const Vec3& b);
// Whether a quad with corners `c` has a corner under `min_corner_degrees` (or two corners
// at one point), or is turned over (turned_over). *hint as in ComponentLocator::closest.
bool corners_bad(const ComponentLocator& locator, const DesignNormals& normals,
                 const Vec3 (&c)[4], double min_corner_degrees, int* hint = nullptr);

// A quad with a corner twice, two corners at one point or a corner under 1°
// (QuadStats::degenerate_quads).
bool degenerate_quad(const QuadCage& cage, Eigen::Index q);
// Whether the cage is an oriented 2-manifold whose limit surface can be built: every
// directed edge once, the quads around every vertex one fan (joined through the edges at
// that vertex), and no two quads sharing three corners or a diagonal. Collapsed sliver
// patches and diagonal collapses can break this; `why` names the first problem.
bool cage_is_manifold(const QuadCage& cage, std::string* why);
// QuadStats::irregular_off_singularities and off_singularities of `cage`. Returns those
// vertices (matched_irregulars' entries with quarter turns no singularity explains).
std::vector<Irregular> count_off_singularities(const CageChecks& checks, const QuadCage& cage,
                                               const std::vector<SingularPoint>& singular,
                                               double density, QuadStats* stats);

}  // namespace genbrep::quad_detail

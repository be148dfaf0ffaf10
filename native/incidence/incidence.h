// incidence/incidence.h — which input solids each design vertex represents (paper §4.1).
// Takes: the prepared design mesh and the prepared input solids (closed, oriented).
// Gives: per design vertex the sorted set I(V) of solids it is incident with, and which
// seeds it marks as eroded (E_j: the design surface runs through the seed's interior).
// A vertex counts as incident for the partition iff I(V) is non-empty and it marks no
// eroded seed: an eroded seed's surface is organic material's surface, not the seed's.
// Modes: distance (§4.1.3) with tolerance d; grid (§4.1.1) with the solver's voxel grid.
// Solids of the same role that overlap act as their union (§3.1): a vertex near one
// member's boundary but deep inside another member is not incident with the first.
// Complexity: O(|V| · |S| · log |T_S|) queries on per-solid AABB trees (CGAL).
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "core/context.h"
#include "core/error.h"
#include "core/types.h"

namespace genbrep {

// A closed, oriented triangle surface with point queries: nearest point, unsigned and
// signed distance, inside test. The inside test shoots rays with exact predicates, so
// its sign is right next to edges and vertices, where normal-based signs fail.
class ClosedSurface {
 public:
  explicit ClosedSurface(const TriangleMesh& mesh);
  ~ClosedSurface();
  ClosedSurface(ClosedSurface&&) noexcept;
  ClosedSurface& operator=(ClosedSurface&&) noexcept;

  Vec3 nearest_point(const Vec3& p) const;
  double distance(const Vec3& p) const;
  bool inside(const Vec3& p) const;             // points on the surface count as inside
  double signed_distance(const Vec3& p) const;  // <= 0 inside (paper: D(p) <= 0 for p in S)
  // The same, with the nearest point on the surface (nearest_point) from the same query.
  double signed_distance(const Vec3& p, Vec3* nearest) const;
  // Axis-aligned bounds, for cheap rejection before tree queries.
  const Vec3& min_corner() const;
  const Vec3& max_corner() const;
  bool intersects(const ClosedSurface& other) const;  // surfaces cross or one contains the other

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// The input solids with their roles and names, and the union groups of same-role
// solids that overlap.
class SolidSet {
 public:
  // `solids` must be prepared (mesh::prepare_closed_mesh). Notes overlaps in diagnostics.
  SolidSet(std::vector<SolidInput> solids, Diagnostics* diagnostics);
  int size() const { return static_cast<int>(solids_.size()); }
  const SolidInput& input(int solid) const { return solids_[solid]; }
  const ClosedSurface& surface(int solid) const { return surfaces_[solid]; }
  // Solids share a group iff they have the same role and overlap (transitively).
  int union_group(int solid) const { return group_[solid]; }
  // "keep-in 'boss'": how messages name a solid.
  std::string describe(int solid) const;

 private:
  std::vector<SolidInput> solids_;
  std::vector<ClosedSurface> surfaces_;
  std::vector<int> group_;
};

struct IncidenceOptions {
  enum class Mode { Distance, Grid };
  Mode mode = Mode::Distance;
  // d: accuracy of the solver's representation, design units. 0 = derive it from the
  // design (the median edge length of its triangles, about one voxel for level sets).
  double tolerance = 0;
  Vec3 grid_origin = Vec3::Zero();  // grid mode: a grid point of the solver's voxel grid
  double grid_h = 0;                // grid mode: voxel edge length h (> 0)
};

struct Incidence {
  // I(V) for vertex v: solids[offsets[v] .. offsets[v+1]), sorted ascending.
  std::vector<int> offsets{0};
  std::vector<int> solids;
  // Seed whose eroded part E_j vertex v bounds, or -1.
  std::vector<int> eroded_seed;
  double tolerance = 0;        // d actually used (distance mode) or h (grid mode)
  bool tolerance_derived = false;
  std::vector<int> incident_vertices_per_solid;
  Diagnostics diagnostics;

  int vertex_count() const { return static_cast<int>(offsets.size()) - 1; }
  bool incident(int v) const { return offsets[v + 1] > offsets[v] && eroded_seed[v] < 0; }
};

// The median edge length of a mesh: the automatic tolerance.
double median_edge_length(const TriangleMesh& mesh);

Incidence compute_incidence(const TriangleMesh& design, const SolidSet& solids,
                            const IncidenceOptions& options, const Context& context);

// Where the design and its solids disagree: returns one warning per solid, naming it, how
// many points, how far and where, for a keep-in the design does not contain (design
// vertices more than 3 × incidence.tolerance deep inside it, the keep-in away from the
// design touching no design vertex, or, failing those, points of its surface more than
// twice the tolerance outside the design) and for material inside a keep-out (design vertices
// more than 3 × tolerance deep). A keep-in buried in the material is fine, and so is a
// keep-out cutting through a keep-in (a bore through a boss): the keep-out wins there.
// Throws Error{InvalidInput} (stage "incidence") for a keep-in wholly inside a keep-out,
// which no solid can honour. The pipeline calls it right after compute_incidence, whose
// counts it uses.
std::vector<std::string> check_placement(const TriangleMesh& design, const SolidSet& solids,
                                         const Incidence& incidence, const Context& context);

}  // namespace genbrep

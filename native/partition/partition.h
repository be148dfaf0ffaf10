// partition/partition.h — incident and organic regions, components, boundary loops
// (paper §4.2–5.2).
// Takes: the design's halfedge mesh (closed, 2-manifold) and the vertex incidences.
// Gives: per triangle its incident solids I(T) (the union of its vertices' incidences
// when all three are incident, else none), the incident sets C_i, the organic
// components O_i (edge-connected flood fill), and the boundary loops between O and C.
// Guarantees: after the repair of §5.1 (reassigning the incident triangles around
// non-manifold boundary vertices to O, iterated to convergence) every boundary vertex
// has exactly two boundary edges, so every loop is a simple closed vertex cycle. Loops
// run along the organic triangles' orientation: the organic side is on the left.
// partition_faces() starts from triangle labels I(T) instead (a remeshed design whose
// labels were carried through, relax/).
// Complexity: O(|T|) per repair round; rounds are few in practice (§5.1).
#pragma once
#include <vector>

#include "core/context.h"
#include "core/error.h"
#include "core/types.h"
#include "incidence/incidence.h"

namespace genbrep {

struct PartitionOptions {
  // Repair rounds before giving up; the repair converges by construction (in the worst
  // case everything becomes organic), so this only bounds pathological inputs.
  int max_repair_rounds = 1000;
};

struct BoundaryLoop {
  std::vector<int> vertices;  // closed cycle of design vertex indices (last joins first)
  std::vector<int> solids;    // solids of the incident triangles along the loop, sorted
  int component = -1;         // the organic component this loop bounds
};

struct Partition {
  // I(T) for triangle t: face_solids[face_offsets[t] .. face_offsets[t+1]), sorted.
  std::vector<int> face_offsets{0};
  std::vector<int> face_solids;
  std::vector<int> face_solid;      // first incident solid per triangle, -1 = organic
  std::vector<int> face_component;  // organic component per triangle, -1 = incident
  std::vector<std::vector<int>> solid_faces;  // C_i: triangles incident with solid i
  int organic_components = 0;
  std::vector<BoundaryLoop> loops;
  int repair_rounds = 0;            // rounds that changed something
  int repaired_vertices = 0;        // non-manifold boundary vertices resolved
  int reassigned_triangles = 0;     // incident triangles moved to O by the repair
  Diagnostics diagnostics;

  int organic_triangles() const;
};

Partition partition(const TriMesh& design, const Incidence& incidence, int solid_count,
                    const PartitionOptions& options, const Context& context);

// The same from triangle labels instead of vertex incidences: `face_solids[t]` is I(T) for
// triangle t (any order, duplicates allowed; empty = organic). Runs the §5.1 repair,
// components and loops exactly as partition() does after its §4.2 step; stages that
// change the mesh but carry the labels (relax/) use it to retrace the loops.
// Throws Error{Internal} if the sizes disagree or a label is outside [0, solid_count).
Partition partition_faces(const TriMesh& design, std::vector<std::vector<int>> face_solids,
                          int solid_count, const PartitionOptions& options, const Context& context);

}  // namespace genbrep

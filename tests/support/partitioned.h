// tests/support/partitioned.h — a scene carried through the first stages, as stage tests
// downstream of the partition need it: prepared design, its halfedge mesh, partition.
#pragma once
#include "core/types.h"
#include "level_set.h"
#include "partition/partition.h"
#include "scenes.h"

namespace genbrep::testing {

// The mesh is built in the constructor: a default-constructed TriMesh in a test file makes
// GCC emit OpenMesh's property vtables there and warn (-Wmaybe-uninitialized) inside them.
struct Partitioned {
  explicit Partitioned(TriangleMesh prepared);
  TriangleMesh design;
  TriMesh mesh;
  Partition partition;
};

// Scene → prepared design → distance incidence (tolerance h) → partition.
Partitioned partition_scene(const Scene& scene);
// A closed level set of `sdf` with no solids: one organic component, no loops.
Partitioned all_organic(const Field& sdf, const Vec3& lo, const Vec3& hi, double h);
// §5.3 boundary relaxation, as the pipeline runs it before field and quad.
Partitioned relaxed(const Partitioned& partitioned);

}  // namespace genbrep::testing

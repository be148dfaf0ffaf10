#include "partitioned.h"

#include <cstdio>

#include "incidence/incidence.h"
#include "mesh/mesh.h"
#include "relax/relax.h"

namespace genbrep::testing {

Partitioned::Partitioned(TriangleMesh prepared) : design(std::move(prepared)), mesh(to_trimesh(design)) {}

Partitioned partition_scene(const Scene& s) {
  Partitioned r(prepare_closed_mesh(s.design, "design", nullptr));
  std::vector<SolidInput> prepared = s.solids;
  for (auto& solid : prepared) solid.mesh = prepare_closed_mesh(solid.mesh, solid.name, nullptr);
  const SolidSet solids(prepared, nullptr);
  IncidenceOptions options;
  options.tolerance = s.h;
  const Incidence incidence = compute_incidence(r.design, solids, options, Context());
  r.partition = partition(r.mesh, incidence, solids.size(), {}, Context());
  return r;
}

Partitioned all_organic(const Field& sdf, const Vec3& lo, const Vec3& hi, double h) {
  const Vec3 origin = lo - Vec3(0.37 * h, 0.29 * h, 0.41 * h);
  const Vec3 size = (hi - origin) / h;
  const Eigen::Vector3i cells(static_cast<int>(std::ceil(size.x())) + 1,
                              static_cast<int>(std::ceil(size.y())) + 1,
                              static_cast<int>(std::ceil(size.z())) + 1);
  Partitioned r(prepare_closed_mesh(extract_level_set(sdf, origin, h, cells), "design", nullptr));
  Incidence incidence;
  for (Eigen::Index v = 0; v < r.design.vertices.rows(); ++v) {
    incidence.offsets.push_back(0);
    incidence.eroded_seed.push_back(-1);
  }
  r.partition = partition(r.mesh, incidence, 0, {}, Context());
  return r;
}

Partitioned relaxed(const Partitioned& r) {
  const Relaxed x = relax(r.design, r.partition, {}, Context());
  Partitioned out(x.design);
  out.partition = x.partition;
  for (const auto& d : x.diagnostics) std::printf("[relax] warning: %s\n", d.c_str());
  for (const auto& d : x.notes) std::printf("[relax] %s\n", d.c_str());
  return out;
}

}  // namespace genbrep::testing

// Tests for partition/: C ⊔ O, organic components, §5.1 repair, boundary loops.
#include <gtest/gtest.h>

#include <set>

#include "incidence/incidence.h"
#include "level_set.h"
#include "mesh/mesh.h"
#include "partition/partition.h"
#include "scenes.h"

using namespace genbrep;
using namespace genbrep::testing;

namespace {

struct Converted {
  TriangleMesh design;
  Incidence incidence;
  Partition partition;
};

Converted run(const Scene& s, bool grid) {
  Converted r;
  r.design = prepare_closed_mesh(s.design, "design", nullptr);
  std::vector<SolidInput> prepared = s.solids;
  for (auto& solid : prepared) solid.mesh = prepare_closed_mesh(solid.mesh, solid.name, nullptr);
  const SolidSet solids(prepared, nullptr);
  IncidenceOptions options;
  options.tolerance = s.h;
  if (grid) {
    options.mode = IncidenceOptions::Mode::Grid;
    options.grid_origin = s.grid_origin;
    options.grid_h = s.h;
  }
  r.incidence = compute_incidence(r.design, solids, options, Context());
  r.partition = partition(to_trimesh(r.design), r.incidence, solids.size(), {}, Context());
  return r;
}

// Every loop is a closed cycle of distinct vertices, each step an edge of an organic
// triangle running in that triangle's direction (organic side on the left), whose
// other triangle is incident.
void expect_valid_loops(const Converted& r) {
  const TriMesh mesh = to_trimesh(r.design);
  const auto& p = r.partition;
  for (const auto& loop : p.loops) {
    ASSERT_GE(loop.vertices.size(), 3u);
    EXPECT_EQ(std::set<int>(loop.vertices.begin(), loop.vertices.end()).size(), loop.vertices.size());
    for (size_t i = 0; i < loop.vertices.size(); ++i) {
      const auto a = mesh.vertex_handle(loop.vertices[i]);
      const auto b = mesh.vertex_handle(loop.vertices[(i + 1) % loop.vertices.size()]);
      const auto h = mesh.find_halfedge(a, b);
      ASSERT_TRUE(h.is_valid());
      EXPECT_EQ(p.face_component[mesh.face_handle(h).idx()], loop.component);
      EXPECT_GE(p.face_solid[mesh.opposite_face_handle(h).idx()], 0);
    }
    EXPECT_FALSE(loop.solids.empty());
  }
}

}  // namespace

class PartitionScenes : public ::testing::TestWithParam<std::tuple<int, bool>> {};

TEST_P(PartitionScenes, ComponentsAndLoopsAreAsBuilt) {
  const auto [which, grid] = GetParam();
  const double h = 0.05;
  const Scene s = analytic_scene(which, h);
  const Converted r = run(s, grid);
  EXPECT_EQ(r.partition.organic_components, s.expected_components) << s.name;
  EXPECT_EQ(static_cast<int>(r.partition.loops.size()), s.expected_loops) << s.name;
  expect_valid_loops(r);
  // C_i and face_solid agree; every solid is represented.
  for (size_t i = 0; i < r.partition.solid_faces.size(); ++i) {
    EXPECT_FALSE(r.partition.solid_faces[i].empty()) << s.name << " solid " << i;
    for (int f : r.partition.solid_faces[i]) EXPECT_LE(r.partition.face_solid[f], static_cast<int>(i));
  }
}

INSTANTIATE_TEST_SUITE_P(DistanceAndGrid, PartitionScenes,
                         ::testing::Combine(::testing::Range(0, 6), ::testing::Bool()));

TEST(Partition, TubeLoopsEachBorderOneKeepIn) {
  const Converted r = run(tube_scene(0.05), false);
  ASSERT_EQ(r.partition.loops.size(), 2u);
  std::set<std::vector<int>> solids;
  for (const auto& loop : r.partition.loops) solids.insert(loop.solids);
  EXPECT_EQ(solids, (std::set<std::vector<int>>{{0}, {1}}));
}

TEST(Partition, BoltHoleWallIsIncidentWithTheKeepOut) {
  const Converted r = run(bolt_hole_scene(0.05), false);
  EXPECT_GT(r.partition.solid_faces[1].size(), 100u);  // the hole's wall
  // The wall meets the boss's faces at the hole's rims: triangles incident with both.
  int both = 0;
  for (size_t f = 0; f < r.partition.face_solid.size(); ++f) {
    both += r.partition.face_offsets[f + 1] - r.partition.face_offsets[f] == 2;
  }
  EXPECT_GT(both, 0);
}

TEST(Partition, RepairsANonManifoldBoundaryVertex) {
  // A subdivided box; on its top face two organic vertices opposite each other across
  // vertex v make two organic fans that touch only at v.
  const int n = 6;
  const TriangleMesh box = box_mesh(Vec3(0, 0, 0), Vec3(1, 1, 1), n);
  const TriMesh mesh = to_trimesh(box);
  auto find = [&](double x, double y) {
    for (Eigen::Index v = 0; v < box.vertices.rows(); ++v) {
      if ((box.vertices.row(v) - Eigen::RowVector3d(x, y, 1)).norm() < 1e-9) return static_cast<int>(v);
    }
    return -1;
  };
  const double step = 1.0 / n;
  const int v = find(0.5, 0.5);
  // Neighbours of v along its rows: for the top face (axis z) u = x, v = y, diagonals
  // run (x, y) -> (x + 1, y + 1), so (x ± 1, y) are opposite in v's ring.
  const int left = find(0.5 - step, 0.5), right = find(0.5 + step, 0.5);
  ASSERT_GE(v, 0);
  ASSERT_GE(left, 0);
  ASSERT_GE(right, 0);
  Incidence inc;
  for (int i = 0; i < static_cast<int>(box.vertices.rows()); ++i) {
    const bool organic = i == left || i == right;
    if (!organic) inc.solids.push_back(0);
    inc.offsets.push_back(static_cast<int>(inc.solids.size()));
    inc.eroded_seed.push_back(-1);
  }
  const Partition p = partition(mesh, inc, 1, {}, Context());
  EXPECT_EQ(p.repaired_vertices, 1);
  EXPECT_EQ(p.repair_rounds, 1);
  EXPECT_EQ(p.reassigned_triangles, 2);  // the two incident triangles of v's ring
  EXPECT_EQ(p.organic_components, 1);
  ASSERT_EQ(p.loops.size(), 1u);
  EXPECT_EQ(p.organic_triangles(), 14);  // two 6-fans sharing two triangles, plus two
  EXPECT_EQ(p.diagnostics.size(), 1u);
}

TEST(Partition, AllOrganicAndAllIncidentMeshesHaveNoLoops) {
  const TriangleMesh box = box_mesh(Vec3(0, 0, 0), Vec3(1, 1, 1), 2);
  const TriMesh mesh = to_trimesh(box);
  for (bool organic : {true, false}) {
    Incidence inc;
    for (Eigen::Index i = 0; i < box.vertices.rows(); ++i) {
      if (!organic) inc.solids.push_back(0);
      inc.offsets.push_back(static_cast<int>(inc.solids.size()));
      inc.eroded_seed.push_back(-1);
    }
    const Partition p = partition(mesh, inc, 1, {}, Context());
    EXPECT_EQ(p.organic_components, organic ? 1 : 0);
    EXPECT_TRUE(p.loops.empty());
  }
}

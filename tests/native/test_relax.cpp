// Tests for relax/: channel remesh and surface-restricted loop smoothing (paper §5.3) on
// level-set scenes whose partition boundaries zigzag along voxel stairs; and the
// partition_faces entry point the stage uses to retrace loops.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "incidence/incidence.h"
#include "mesh/mesh.h"
#include "partition/partition.h"
#include "relax/relax.h"
#include "scenes.h"

using namespace genbrep;
using namespace genbrep::testing;

namespace {

constexpr double kH = 0.05;

struct Prepared {
  std::string name;
  TriangleMesh design;
  Incidence incidence;
  Partition partition;
  int solid_count = 0;
};

Prepared prepare(const Scene& s) {
  Prepared r;
  r.name = s.name;
  r.design = prepare_closed_mesh(s.design, "design", nullptr);
  std::vector<SolidInput> solids = s.solids;
  for (auto& solid : solids) solid.mesh = prepare_closed_mesh(solid.mesh, solid.name, nullptr);
  const SolidSet set(solids, nullptr);
  IncidenceOptions options;
  options.tolerance = s.h;
  r.incidence = compute_incidence(r.design, set, options, Context());
  r.solid_count = set.size();
  r.partition = partition(to_trimesh(r.design), r.incidence, r.solid_count, {}, Context());
  return r;
}

Scene scene(int which) {
  switch (which) {
    case 0:
      return tube_scene(kH);
    case 1:
      return grown_box_scene(kH);
    case 2:
      return two_arches_scene(kH);
    default:
      return bolt_hole_scene(kH);
  }
}

double segment_distance(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 ab = b - a;
  const double t =
      ab.squaredNorm() > 0 ? std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0) : 0;
  return (p - (a + t * ab)).norm();
}

// Distance from p to the nearest segment of any loop of `partition` on `mesh`.
double distance_to_loops(const Vec3& p, const TriangleMesh& mesh, const Partition& partition) {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& loop : partition.loops) {
    for (size_t i = 0; i < loop.vertices.size(); ++i) {
      const Vec3 a = mesh.vertices.row(loop.vertices[i]);
      const Vec3 b = mesh.vertices.row(loop.vertices[(i + 1) % loop.vertices.size()]);
      best = std::min(best, segment_distance(p, a, b));
    }
  }
  return best;
}

Vec3 triangle_normal(const TriangleMesh& mesh, int t) {
  const Vec3 a = mesh.vertices.row(mesh.triangles(t, 0)),
             b = mesh.vertices.row(mesh.triangles(t, 1)),
             c = mesh.vertices.row(mesh.triangles(t, 2));
  return (b - a).cross(c - a);
}

}  // namespace

class RelaxScenes : public ::testing::TestWithParam<int> {};

TEST_P(RelaxScenes, SmoothsLoopsOnTheDesignSurface) {
  const Prepared p = prepare(scene(GetParam()));
  RelaxOptions options;
  options.tolerance = kH;  // the incidence tolerance, as the pipeline passes it
  const Relaxed r = relax(p.design, p.partition, options, Context());

  std::printf(
      "[%s] %lld -> %lld triangles, channel %d, target %.4f, d %.4f, remeshed %d, "
      "organic area %.4f -> %.4f (%+.2f%%), max displacement %.4f (%.2f d), skipped %d\n",
      p.name.c_str(), static_cast<long long>(p.design.triangles.rows()),
      static_cast<long long>(r.design.triangles.rows()), r.channel_triangles, r.target_edge_length,
      r.tolerance, r.remeshed, r.organic_area_before, r.organic_area_after,
      100 * (r.organic_area_after - r.organic_area_before) / r.organic_area_before,
      r.max_displacement, r.max_displacement / r.tolerance, r.skipped_moves);
  for (const auto& d : r.diagnostics) std::printf("  warning: %s\n", d.c_str());
  for (const auto& d : r.notes) std::printf("  note: %s\n", d.c_str());
  EXPECT_TRUE(r.remeshed) << p.name;

  // Same topology of the partition; a valid closed mesh with provenance.
  const MeshValidation validation = validate(r.design);
  EXPECT_TRUE(validation.closed_manifold()) << p.name << ": " << validation.problems();
  EXPECT_EQ(r.partition.organic_components, p.partition.organic_components) << p.name;
  ASSERT_EQ(r.partition.loops.size(), p.partition.loops.size()) << p.name;
  ASSERT_EQ(r.loops.size(), r.partition.loops.size());
  ASSERT_EQ(r.design.triangle_source.size(), static_cast<size_t>(r.design.triangles.rows()));
  ASSERT_EQ(r.triangle_origin.size(), static_cast<size_t>(r.design.triangles.rows()));

  // Shape: every loop has more even edges and turns less, by a measured factor.
  std::vector<char> matched(p.partition.loops.size(), 0);
  for (size_t i = 0; i < r.loops.size(); ++i) {
    const auto& l = r.loops[i];
    std::printf(
        "  loop %zu (was %d): %d -> %d vertices, edge CV %.3f -> %.3f (x%.2f lower), "
        "turning %.1f -> %.1f deg (x%.2f lower), max turning %.0f -> %.0f deg, moved %.4f\n",
        i, l.original_loop, l.before.vertices, l.after.vertices, l.before.edge_length_cv,
        l.after.edge_length_cv, l.before.edge_length_cv / l.after.edge_length_cv,
        l.before.mean_turning_angle * 180 / M_PI, l.after.mean_turning_angle * 180 / M_PI,
        l.before.mean_turning_angle / l.after.mean_turning_angle,
        l.before.max_turning_angle * 180 / M_PI, l.after.max_turning_angle * 180 / M_PI,
        l.max_displacement);
    ASSERT_GE(l.original_loop, 0);
    matched[l.original_loop] = 1;
    EXPECT_LT(l.after.edge_length_cv, l.before.edge_length_cv) << p.name << " loop " << i;
    EXPECT_GT(l.before.mean_turning_angle, 1.5 * l.after.mean_turning_angle)
        << p.name << " loop " << i;
    // No corner left sharper than a right angle: every interior angle is "flat" (§6.1).
    EXPECT_LT(l.after.max_turning_angle, M_PI / 2) << p.name << " loop " << i;
  }
  EXPECT_EQ(std::count(matched.begin(), matched.end(), 1), static_cast<long>(matched.size()))
      << p.name << ": every original loop has a relaxed one";

  // Every vertex on the original design surface.
  const ClosedSurface surface(p.design);
  const double diagonal = bounding_box_diagonal(p.design.vertices);
  double worst = 0;
  for (Eigen::Index v = 0; v < r.design.vertices.rows(); ++v) {
    worst = std::max(worst, surface.distance(r.design.vertices.row(v)));
  }
  std::printf("  farthest vertex from the design: %.3g (%.3g of the diagonal)\n", worst,
              worst / diagonal);
  EXPECT_LT(worst, 1e-6 * diagonal) << p.name;

  // Loop vertices within d of the original loops (independent brute-force check).
  double moved = 0;
  for (const auto& loop : r.partition.loops) {
    for (int v : loop.vertices) {
      moved = std::max(moved, distance_to_loops(r.design.vertices.row(v), p.design, p.partition));
    }
  }
  EXPECT_LE(moved, options.tolerance * (1 + 1e-9)) << p.name;
  EXPECT_NEAR(moved, r.max_displacement, 1e-9) << p.name;

  // No triangle faces against the design triangle it came from.
  int flipped = 0;
  for (Eigen::Index t = 0; t < r.design.triangles.rows(); ++t) {
    const Vec3 n = triangle_normal(r.design, static_cast<int>(t));
    const Vec3 m = triangle_normal(p.design, r.triangle_origin[t]);
    flipped += n.dot(m) <= 0;
  }
  EXPECT_EQ(flipped, 0) << p.name;

  // The organic region does not shrink (nor grow) by more than a few percent.
  EXPECT_GT(r.organic_area_after, 0.97 * r.organic_area_before) << p.name;
  EXPECT_LT(r.organic_area_after, 1.03 * r.organic_area_before) << p.name;
}

INSTANTIATE_TEST_SUITE_P(LevelSetScenes, RelaxScenes, ::testing::Range(0, 4));

TEST(Relax, IsDeterministic) {
  const Prepared p = prepare(bolt_hole_scene(kH));
  RelaxOptions options;
  options.tolerance = kH;
  const Relaxed a = relax(p.design, p.partition, options, Context());
  const Relaxed b = relax(p.design, p.partition, options, Context());
  ASSERT_EQ(a.design.vertices.rows(), b.design.vertices.rows());
  ASSERT_EQ(a.design.triangles.rows(), b.design.triangles.rows());
  EXPECT_TRUE(a.design.vertices == b.design.vertices);
  EXPECT_TRUE(a.design.triangles == b.design.triangles);
  EXPECT_EQ(a.design.triangle_source, b.design.triangle_source);
  EXPECT_EQ(a.partition.face_solids, b.partition.face_solids);
  EXPECT_EQ(a.partition.face_component, b.partition.face_component);
}

TEST(Relax, WithoutLoopsReturnsTheDesign) {
  const Scene s = tube_scene(kH);
  const TriangleMesh design = prepare_closed_mesh(s.design, "design", nullptr);
  const std::vector<std::vector<int>> organic(static_cast<size_t>(design.triangles.rows()));
  const Partition all_organic = partition_faces(to_trimesh(design), organic, 0, {}, Context());
  const Relaxed r = relax(design, all_organic, {}, Context());
  EXPECT_FALSE(r.remeshed);
  EXPECT_TRUE(r.design.vertices == design.vertices);
  EXPECT_TRUE(r.design.triangles == design.triangles);
  EXPECT_EQ(r.design.triangle_source, design.triangle_source);
  EXPECT_TRUE(r.loops.empty());
}

// partition_faces on the §4.2 triangle labels reproduces partition() exactly.
TEST(PartitionFaces, MatchesPartitionFromIncidences) {
  for (int which = 0; which < 4; ++which) {
    const Prepared p = prepare(scene(which));
    const TriMesh mesh = to_trimesh(p.design);
    std::vector<std::vector<int>> sets(mesh.n_faces());
    for (const auto f : mesh.faces()) {
      std::vector<int> set;
      bool incident = true;
      for (const auto v : mesh.fv_range(f)) {
        incident = incident && p.incidence.incident(v.idx());
        set.insert(set.end(), p.incidence.solids.begin() + p.incidence.offsets[v.idx()],
                   p.incidence.solids.begin() + p.incidence.offsets[v.idx() + 1]);
      }
      if (incident) sets[f.idx()] = set;  // unsorted, with repeats: partition_faces sorts
    }
    const Partition q = partition_faces(mesh, sets, p.solid_count, {}, Context());
    EXPECT_EQ(q.face_offsets, p.partition.face_offsets) << p.name;
    EXPECT_EQ(q.face_solids, p.partition.face_solids) << p.name;
    EXPECT_EQ(q.face_solid, p.partition.face_solid) << p.name;
    EXPECT_EQ(q.face_component, p.partition.face_component) << p.name;
    EXPECT_EQ(q.solid_faces, p.partition.solid_faces) << p.name;
    EXPECT_EQ(q.organic_components, p.partition.organic_components) << p.name;
    EXPECT_EQ(q.repaired_vertices, p.partition.repaired_vertices) << p.name;
    EXPECT_EQ(q.reassigned_triangles, p.partition.reassigned_triangles) << p.name;
    ASSERT_EQ(q.loops.size(), p.partition.loops.size()) << p.name;
    for (size_t i = 0; i < q.loops.size(); ++i) {
      EXPECT_EQ(q.loops[i].vertices, p.partition.loops[i].vertices) << p.name;
      EXPECT_EQ(q.loops[i].solids, p.partition.loops[i].solids) << p.name;
      EXPECT_EQ(q.loops[i].component, p.partition.loops[i].component) << p.name;
    }
  }
}

TEST(PartitionFaces, RejectsLabelsOutOfRange) {
  const TriMesh mesh = to_trimesh(prepare_closed_mesh(tube_scene(kH).design, "design", nullptr));
  std::vector<std::vector<int>> sets(mesh.n_faces());
  sets[0] = {3};
  EXPECT_THROW(partition_faces(mesh, sets, 2, {}, Context()), Error);
  sets.pop_back();
  sets[0].clear();
  EXPECT_THROW(partition_faces(mesh, sets, 2, {}, Context()), Error);
}

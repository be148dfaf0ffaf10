// Tests for incidence/: point queries on solids, union groups, distance and grid modes.
#include <gtest/gtest.h>

#include "incidence/incidence.h"
#include "level_set.h"
#include "mesh/mesh.h"
#include "scenes.h"

using namespace genbrep;
using namespace genbrep::testing;

namespace {

SolidSet make_solids(std::vector<SolidInput> solids, Diagnostics* notes = nullptr) {
  for (auto& s : solids) s.mesh = prepare_closed_mesh(s.mesh, s.name, notes);
  return SolidSet(std::move(solids), notes);
}

int count_incident(const Incidence& inc, int solid) {
  int n = 0;
  for (int v = 0; v < inc.vertex_count(); ++v)
    for (int i = inc.offsets[v]; i < inc.offsets[v + 1]; ++i) n += inc.solids[i] == solid;
  return n;
}

}  // namespace

TEST(ClosedSurface, SignedDistanceIsRightAtFacesEdgesAndCorners) {
  const ClosedSurface box(box_mesh(Vec3(0, 0, 0), Vec3(1, 1, 1), 2));
  EXPECT_NEAR(box.signed_distance(Vec3(0.5, 0.5, 0.5)), -0.5, 1e-12);
  EXPECT_NEAR(box.signed_distance(Vec3(0.5, 0.5, 1.25)), 0.25, 1e-12);
  // Just outside an edge and a corner, where the nearest triangle's normal is ambiguous.
  EXPECT_NEAR(box.signed_distance(Vec3(1.001, 1.001, 0.5)), std::sqrt(2e-6), 1e-9);
  EXPECT_NEAR(box.signed_distance(Vec3(1.001, 1.001, 1.001)), std::sqrt(3e-6), 1e-9);
  // Just inside the same edge and corner.
  EXPECT_NEAR(box.signed_distance(Vec3(0.999, 0.999, 0.5)), -0.001, 1e-9);
  EXPECT_NEAR(box.signed_distance(Vec3(0.999, 0.999, 0.999)), -0.001, 1e-9);
  EXPECT_TRUE(box.inside(Vec3(1, 0.5, 0.5)));  // on the surface counts as inside
  EXPECT_TRUE((box.nearest_point(Vec3(2, 0.5, 0.5)) - Vec3(1, 0.5, 0.5)).norm() < 1e-12);
}

TEST(SolidSet, OverlappingSolidsOfOneRoleFormAUnion) {
  Diagnostics notes;
  const SolidSet solids = make_solids({{"a", Role::KeepIn, box_mesh(Vec3(0, 0, 0), Vec3(2, 1, 1))},
                                       {"b", Role::KeepIn, box_mesh(Vec3(1, 0, 0), Vec3(3, 1, 1))},
                                       {"c", Role::KeepOut, box_mesh(Vec3(1, 0, 0), Vec3(3, 1, 1))},
                                       {"d", Role::KeepIn, box_mesh(Vec3(5, 0, 0), Vec3(6, 1, 1))}},
                                      &notes);
  EXPECT_EQ(solids.union_group(0), solids.union_group(1));
  EXPECT_NE(solids.union_group(1), solids.union_group(2));  // different role: no union
  EXPECT_NE(solids.union_group(0), solids.union_group(3));  // disjoint
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_EQ(notes[0], "keep-in 'a' and keep-in 'b' overlap and are treated as their union");

  // A design vertex on b's left face, deep inside a: that face is interior to the union.
  TriangleMesh design = box_mesh(Vec3(-0.1, 0.2, 0.2), Vec3(1.0, 0.8, 0.8));
  IncidenceOptions options;
  options.tolerance = 0.05;
  const Incidence inc = compute_incidence(design, solids, options, Context());
  int on_b = 0;
  for (int v = 0; v < inc.vertex_count(); ++v) {
    if (design.vertices(v, 0) == 1.0) {
      for (int i = inc.offsets[v]; i < inc.offsets[v + 1]; ++i) on_b += inc.solids[i] == 1;
    }
  }
  EXPECT_EQ(on_b, 0);
}

TEST(Incidence, DistanceModeMarksVerticesNearTheSolidAndDerivesD) {
  const Scene s = grown_box_scene(0.05);
  const SolidSet solids = make_solids(s.solids);
  const Incidence inc = compute_incidence(s.design, solids, IncidenceOptions{}, Context());
  EXPECT_TRUE(inc.tolerance_derived);
  EXPECT_GT(inc.tolerance, 0.3 * s.h);
  EXPECT_LT(inc.tolerance, 1.5 * s.h);
  const ClosedSurface box(solids.input(0).mesh);
  int checked = 0;
  for (int v = 0; v < inc.vertex_count(); ++v) {
    const Vec3 p = s.design.vertices.row(v);
    const double D = box.signed_distance(p);
    EXPECT_EQ(inc.incident(v), D <= inc.tolerance) << "vertex " << v << " at D = " << D;
    ++checked;
  }
  EXPECT_EQ(checked, s.design.vertices.rows());
  // The blob's top is far from the box: organic.
  EXPECT_GT(inc.vertex_count() - count_incident(inc, 0), 100);
}

TEST(Incidence, ErodedSeedVerticesAreMarkedInBothModes) {
  const Scene s = eroded_seed_scene(0.05);
  const SolidSet solids = make_solids(s.solids);
  IncidenceOptions distance;
  distance.tolerance = s.h;
  IncidenceOptions grid;
  grid.mode = IncidenceOptions::Mode::Grid;
  grid.grid_origin = s.grid_origin;
  grid.grid_h = s.h;
  for (const auto& options : {distance, grid}) {
    // Distance mode marks vertices on the bite itself; grid mode any vertex whose cell
    // has a corner in the bite, so up to a cell diagonal away from it.
    const double reach = options.mode == IncidenceOptions::Mode::Grid ? std::sqrt(3.0) * s.h : 0.2 * s.h;
    const Incidence inc = compute_incidence(s.design, solids, options, Context());
    int eroded = 0, eroded_far_from_bite = 0;
    for (int v = 0; v < inc.vertex_count(); ++v) {
      if (inc.eroded_seed[v] != 0) continue;
      ++eroded;
      // Eroded vertices lie on the bite: the sphere of radius 0.9 around (1, 1, 1).
      const double r = (Vec3(s.design.vertices.row(v)) - Vec3(1, 1, 1)).norm();
      eroded_far_from_bite += std::abs(r - 0.9) > reach;
    }
    EXPECT_GT(eroded, 50);
    EXPECT_EQ(eroded_far_from_bite, 0);
  }
}

TEST(Incidence, GridModeAgreesWithDistanceModeAwayFromTheJunction) {
  const Scene s = two_arches_scene(0.06);
  const SolidSet solids = make_solids(s.solids);
  IncidenceOptions grid;
  grid.mode = IncidenceOptions::Mode::Grid;
  grid.grid_origin = s.grid_origin;
  grid.grid_h = s.h;
  IncidenceOptions distance;
  distance.tolerance = s.h;
  const Incidence a = compute_incidence(s.design, solids, grid, Context());
  const Incidence b = compute_incidence(s.design, solids, distance, Context());
  int disagree = 0;
  for (int v = 0; v < a.vertex_count(); ++v) disagree += a.incident(v) != b.incident(v);
  // Both modes decide the same for all but a thin band of vertices at the junctions.
  EXPECT_LT(disagree, a.vertex_count() / 20) << disagree << " of " << a.vertex_count();
  for (int j = 0; j < solids.size(); ++j) EXPECT_GT(a.incident_vertices_per_solid[j], 100);
}

TEST(Incidence, RejectsABadGrid) {
  const Scene s = grown_box_scene(0.1);
  const SolidSet solids = make_solids(s.solids);
  IncidenceOptions grid;
  grid.mode = IncidenceOptions::Mode::Grid;
  grid.grid_h = 0;
  EXPECT_THROW(compute_incidence(s.design, solids, grid, Context()), Error);
}

TEST(Incidence, ProgressCanCancel) {
  const Scene s = grown_box_scene(0.1);
  const SolidSet solids = make_solids(s.solids);
  Context cancel([](const std::string&, double) { return false; });
  try {
    compute_incidence(s.design, solids, IncidenceOptions{}, cancel);
    FAIL() << "not cancelled";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), Code::Cancelled);
  }
}

// Where the design disagrees with its solids, each solid is named in a warning; a keep-in
// on the design's surface or buried in it is fine; a keep-in inside a keep-out is an error.
TEST(Placement, NamesSolidsThatContradictTheirRoles) {
  const TriangleMesh design = prepare_closed_mesh(box_mesh(Vec3(-1, -1, -1), Vec3(1, 1, 1), 10), "d", nullptr);
  IncidenceOptions options;
  options.tolerance = 0.05;
  // The first warning, the error, or "no warning".
  auto placement = [&](std::vector<SolidInput> inputs) {
    const SolidSet solids = make_solids(std::move(inputs));
    const Incidence inc = compute_incidence(design, solids, options, Context());
    try {
      const auto warnings = check_placement(design, solids, inc, Context());
      return warnings.empty() ? std::string("no warning") : warnings.front();
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), Code::InvalidInput);
      return "error: " + std::string(e.what());
    }
  };
  const SolidInput pad{"pad", Role::KeepIn, box_mesh(Vec3(0.6, -0.3, -0.3), Vec3(1, 0.3, 0.3))};
  const SolidInput buried{"core", Role::KeepIn, box_mesh(Vec3(-0.2, -0.2, -0.2), Vec3(0.2, 0.2, 0.2))};
  EXPECT_EQ(placement({pad, buried}), "no warning");
  const std::string sticking_out = placement({{"pad", Role::KeepIn, box_mesh(Vec3(0.5, -0.6, -0.6), Vec3(2, 0.6, 0.6))}});
  EXPECT_EQ(sticking_out.rfind("keep-in 'pad' is not inside the design: 25 design vertices", 0), 0u) << sticking_out;
  // Sticking out by 0.13 (more than 2d, less than 3d): found on the keep-in's own surface.
  const std::string just_out = placement({{"pad", Role::KeepIn, box_mesh(Vec3(0.6, -0.3, -0.3), Vec3(1.13, 0.3, 0.3))}});
  EXPECT_EQ(just_out.rfind("keep-in 'pad' is not inside the design: ", 0), 0u) << just_out;
  EXPECT_NE(just_out.find("points of its surface lie up to 0.13 outside it"), std::string::npos) << just_out;
  const std::string far = placement({{"pad", Role::KeepIn, box_mesh(Vec3(10, 10, 10), Vec3(11, 11, 11))}});
  EXPECT_EQ(far.rfind("keep-in 'pad' is outside the design: it is 15.6 from it", 0), 0u) << far;
  const std::string material =
      placement({pad, {"bore", Role::KeepOut, box_mesh(Vec3(-2, -0.5, -0.5), Vec3(-0.5, 0.5, 0.5))}});
  EXPECT_EQ(material.rfind("keep-out 'bore' has material inside it: 9 design vertices", 0), 0u) << material;
  // A keep-out drilling through the keep-in wins there; one holding all of it is an error.
  EXPECT_EQ(placement({pad, {"bore", Role::KeepOut, box_mesh(Vec3(0.8, -0.1, -0.1), Vec3(1.5, 0.1, 0.1))}}),
            "no warning");
  const std::string inside = placement({pad, {"bore", Role::KeepOut, box_mesh(Vec3(0.4, -0.5, -0.5), Vec3(1.5, 0.5, 0.5))}});
  EXPECT_EQ(inside.rfind("error: keep-in 'pad' lies inside keep-out 'bore': all its 8 vertices", 0), 0u) << inside;
}

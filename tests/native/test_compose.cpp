// Tests for pull/ and compose/ (paper §7–8): every check here is done by code other than
// the code that built the result — mesh::validate, CGAL's self-intersection test and
// Side_of_triangle_mesh, AABB distances to the original solids.
#include <CGAL/AABB_face_graph_triangle_primitive.h>
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Side_of_triangle_mesh.h>
#include <CGAL/Surface_mesh.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <nlohmann/json.hpp>
#include <random>
#include <set>

#include "compose/compose.h"
#include "compose/detail/exact.h"
#include "corpus_design.h"
#include "fixtures.h"
#include "incidence/incidence.h"
#include "level_set.h"
#include "mesh/mesh.h"
#include "partition/partition.h"
#include "pipeline/pipeline.h"
#include "pull/pull.h"
#include "scenes.h"
#include "solid_meshes.h"

using namespace genbrep;
using namespace genbrep::testing;

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Mesh = CGAL::Surface_mesh<K::Point_3>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<K, CGAL::AABB_face_graph_triangle_primitive<Mesh>>>;
using SideOf = CGAL::Side_of_triangle_mesh<Mesh, K>;

Mesh to_cgal(const TriangleMesh& m) {
  Mesh out;
  for (Eigen::Index v = 0; v < m.vertices.rows(); ++v) out.add_vertex(K::Point_3(m.vertices(v, 0), m.vertices(v, 1), m.vertices(v, 2)));
  for (Eigen::Index t = 0; t < m.triangles.rows(); ++t) {
    out.add_face(Mesh::Vertex_index(m.triangles(t, 0)), Mesh::Vertex_index(m.triangles(t, 1)),
                 Mesh::Vertex_index(m.triangles(t, 2)));
  }
  return out;
}
K::Point_3 point(const Vertices& v, Eigen::Index i) { return K::Point_3(v(i, 0), v(i, 1), v(i, 2)); }

struct Converted {
  std::string name;
  TriangleMesh design;
  std::vector<SolidInput> solids;
  Partition partition;
  Composed composed;
};

// Through compose() as the pipeline runs it, with distance incidence and the organic
// regions as the surfaces; `floor`: with the design, so the design Boolean can take over.
Converted convert(const std::string& name, const TriangleMesh& design, const std::vector<SolidInput>& inputs, double d,
                  bool floor = false) {
  Converted r;
  r.name = name;
  r.design = prepare_closed_mesh(design, "design", nullptr);
  for (const auto& s : inputs) r.solids.push_back({s.name, s.role, prepare_closed_mesh(s.mesh, s.name, nullptr)});
  const SolidSet solids(r.solids, nullptr);
  IncidenceOptions options;
  options.tolerance = d;
  const Incidence incidence = compute_incidence(r.design, solids, options, Context());
  r.partition = partition(to_trimesh(r.design), incidence, solids.size(), {}, Context());
  r.composed = compose(organic_sheets(r.design, r.partition), solids, {}, Context(), floor ? &r.design : nullptr);
  return r;
}

std::string joined(const Diagnostics& d) {
  std::string s;
  for (const auto& line : d) s += "\n  " + line;
  return s;
}

// The acceptance checks, each measured independently of compose/. `check_volume`:
// the composed volume is within 2% of the design's (not where keep-ins add material).
void expect_valid(const Converted& r, bool check_volume = true) {
  const auto& c = r.composed;
  ASSERT_GT(c.mesh.triangles.rows(), 0) << r.name << joined(c.report.diagnostics);
  const MeshValidation v = validate(c.mesh);
  EXPECT_TRUE(v.closed_manifold()) << r.name << ": " << v.problems();
  EXPECT_GT(v.signed_volume, 0) << r.name;
  const Mesh composed = to_cgal(c.mesh);
  const bool self_intersecting = CGAL::Polygon_mesh_processing::does_self_intersect(composed);
  EXPECT_FALSE(self_intersecting) << r.name;
  const SideOf side(composed);
  const double scale = bounding_box_diagonal(r.design.vertices), tol = 1e-9 * scale;
  int keep_in_vertices = 0, keep_out_samples = 0, vertices_in_keep_out = 0;
  double max_solid_face_distance = 0;
  std::mt19937 random(7);
  for (size_t s = 0; s < r.solids.size(); ++s) {
    const auto& solid = r.solids[s];
    const Mesh m = to_cgal(solid.mesh);
    const Tree tree(faces(m).first, faces(m).second, m);
    if (solid.role == Role::KeepIn) {  // every keep-in vertex inside or on G, but in a keep-out
      for (Eigen::Index v = 0; v < solid.mesh.vertices.rows(); ++v, ++keep_in_vertices) {
        const auto q = point(solid.mesh.vertices, v);
        bool in_keep_out = false;
        for (const auto& other : r.solids) {
          if (other.role != Role::KeepOut || in_keep_out) continue;
          const Mesh o = to_cgal(other.mesh);
          const Tree other_tree(faces(o).first, faces(o).second, o);
          in_keep_out = SideOf(o)(q) != CGAL::ON_UNBOUNDED_SIDE || other_tree.squared_distance(q) <= tol * tol;
        }
        if (!in_keep_out) {
          EXPECT_NE(side(q), CGAL::ON_UNBOUNDED_SIDE) << r.name << " " << solid.name;
        }
      }
    }
    if (solid.role == Role::KeepOut) {  // sampled keep-out interior points are outside G
      const SideOf in_solid(m);
      const Vec3 lo = solid.mesh.vertices.colwise().minCoeff(), hi = solid.mesh.vertices.colwise().maxCoeff();
      std::uniform_real_distribution<double> u(0, 1);
      for (int i = 0; i < 4000; ++i) {
        const Vec3 p = lo + (hi - lo).cwiseProduct(Vec3(u(random), u(random), u(random)));
        const K::Point_3 q(p.x(), p.y(), p.z());
        if (in_solid(q) != CGAL::ON_BOUNDED_SIDE || tree.squared_distance(q) < 1e-12) continue;
        ++keep_out_samples;
        EXPECT_EQ(side(q), CGAL::ON_UNBOUNDED_SIDE) << r.name << " " << solid.name;
      }
      for (Eigen::Index v = 0; v < c.mesh.vertices.rows(); ++v) {
        const auto q = point(c.mesh.vertices, v);
        vertices_in_keep_out += in_solid(q) == CGAL::ON_BOUNDED_SIDE && std::sqrt(tree.squared_distance(q)) > tol;
      }
    }
    // Faces sourced from this solid lie on its original triangles, grown as compose grows
    // them (by 1e-6 to 2e-6 of the scene, at most 5 times that at sharp corners).
    for (Eigen::Index f = 0; f < c.mesh.triangles.rows(); ++f) {
      if (c.mesh.triangle_source[f] != static_cast<int>(s)) continue;
      for (int k = 0; k < 3; ++k) {
        const double d = std::sqrt(tree.squared_distance(point(c.mesh.vertices, c.mesh.triangles(f, k))));
        max_solid_face_distance = std::max(max_solid_face_distance, d);
      }
    }
  }
  EXPECT_EQ(vertices_in_keep_out, 0) << r.name;
  double scene = scale;
  for (const auto& solid : r.solids) scene = std::max(scene, bounding_box_diagonal(solid.mesh.vertices));
  EXPECT_LE(max_solid_face_distance, 1e-5 * scene) << r.name;
  const double design_volume = validate(r.design).signed_volume;
  const double volume_error = std::abs(v.signed_volume - design_volume) / design_volume;
  if (check_volume) {
    EXPECT_LT(volume_error, 0.02) << r.name;
  }
  int solid_faces = 0;
  for (int s : c.mesh.triangle_source) solid_faces += s >= 0;
  double max_eta = 0;
  for (const auto& contact : c.contacts) max_eta = std::min(max_eta, contact.eta);
  std::printf("[compose] %-12s V=%d F=%d (solid %d, organic %d) closed_manifold=%d self_int=%d "
              "volume=%.5f design=%.5f err=%.3f%% genus=%d shells=%d cells=%d+%d "
              "keep-in vertices=%d keep-out samples=%d composed-in-keep-out=%d "
              "max solid-face distance=%.2e eta=%.2e contact %.2fs boolean %.2fs\n",
              r.name.c_str(), v.vertices, v.triangles, solid_faces, v.triangles - solid_faces,
              v.closed_manifold(), self_intersecting, v.signed_volume, design_volume, 100 * volume_error,
              c.report.genus, v.shells, c.report.organic_cells, c.report.solid_cells, keep_in_vertices,
              keep_out_samples, vertices_in_keep_out, max_solid_face_distance, max_eta,
              c.report.seconds_contact, c.report.seconds_boolean);
  // The report agrees with the independent measurement.
  EXPECT_TRUE(c.report.ok) << r.name << joined(c.report.diagnostics);
  EXPECT_EQ(c.report.self_intersecting, self_intersecting);
}

Converted convert_scene(const Scene& s) { return convert(s.name, s.design, s.solids, s.h); }

}  // namespace

class ComposeScenes : public ::testing::TestWithParam<int> {};

TEST_P(ComposeScenes, ComposedSolidIsWatertightAndRespectsTheSolids) {
  const double h = 0.05;
  const int which = GetParam();
  const Scene s = analytic_scene(which, h);
  const Converted r = convert_scene(s);
  expect_valid(r);
  // Contact curves match the loops one to one and lie on ∂S as the Booleans take it (the
  // solids grown by at most 1e-5 of the scene), the pulled boundary inside.
  const SolidSet solids(r.solids, nullptr);
  double scene = bounding_box_diagonal(r.design.vertices);
  for (const auto& solid : r.solids) scene = std::max(scene, bounding_box_diagonal(solid.mesh.vertices));
  for (const auto& contact : r.composed.contacts) {
    ASSERT_TRUE(contact.established) << s.name << joined(contact.diagnostics);
    std::vector<int> per_loop(contact.pulled.loops.size(), 0);
    for (const auto& curve : contact.curves) {
      ASSERT_GE(curve.loop, 0);
      ++per_loop[curve.loop];
      for (const Vec3& p : curve.points) {
        double d = std::numeric_limits<double>::infinity();
        for (int j : contact.pulled.loops[curve.loop].solids) d = std::min(d, solids.surface(j).distance(p));
        EXPECT_LT(d, 1e-5 * scene) << s.name;
      }
    }
    for (int n : per_loop) EXPECT_EQ(n, 1) << s.name;
    for (double after : contact.max_distance_after) EXPECT_LE(after, contact.eta) << s.name;
  }
}

INSTANTIATE_TEST_SUITE_P(Scenes, ComposeScenes, ::testing::Range(0, 6));

TEST(Compose, SeedBiteIsSubtractiveAndGrownBlobAdditive) {
  const Converted bite = convert_scene(eroded_seed_scene(0.05));
  ASSERT_EQ(bite.composed.contacts.size(), 1u);
  EXPECT_FALSE(bite.composed.contacts[0].additive);
  const Converted grown = convert_scene(grown_box_scene(0.05));
  ASSERT_EQ(grown.composed.contacts.size(), 1u);
  EXPECT_TRUE(grown.composed.contacts[0].additive);
  EXPECT_EQ(grown.composed.report.genus, 0);
}

// The stand-in (unrelaxed organic triangles) with distance incidence, d derived.
class ComposeFixtures : public ::testing::TestWithParam<std::string> {};

TEST_P(ComposeFixtures, ComposedSolidIsWatertightAndRespectsTheSolids) {
  const FixtureFiles f = load_fixture(GetParam());
  expect_valid(convert(GetParam(), f.design, f.solids, 0));
}

INSTANTIATE_TEST_SUITE_P(Fixtures, ComposeFixtures, ::testing::Values("arches", "lattice", "seed"));
// Known failures of this path (docs/compose_method.md): distance incidence without
// relaxation gives loops whose pulled raw level-set sheet intersects itself (§9.1
// "organic surface defects"): on "components" near a block, on "boss" at the rim of the
// boss (12 pairs at η₀; η doubling does not help and ends where the pull cannot reach η).
// The fixtures as Blender converts them (grid incidence, relaxed) are ComposeFixturePipelines.
// Run with --gtest_also_run_disabled_tests.
INSTANTIATE_TEST_SUITE_P(DISABLED_KnownFailures, ComposeFixtures, ::testing::Values("components", "boss"));

// The whole pipeline as scripts/blender_convert.py runs it on the .blend: grid incidence
// with the voxel grid make_fixtures.py records on the design (origin GRID_OFFSET · h,
// GRID_OFFSET = (0.37, 0.29, 0.41)), relaxation, cages where quad/fit succeed and the
// stand-in where they do not. "boss": the keep-out bolt fills the keep-in boss's bore,
// their faces 1e-16 apart.
struct FixtureGrid {
  const char* name;
  double h;
};

void PrintTo(const FixtureGrid& grid, std::ostream* os) { *os << grid.name << " h=" << grid.h; }

// The worst ratio of a quad's longest edge to its shortest, over the cage.
double worst_edge_ratio(const QuadCage& cage) {
  double worst = 1;
  for (Eigen::Index q = 0; q < cage.quads.rows(); ++q) {
    double shortest = 1e300, longest = 0;
    for (int k = 0; k < 4; ++k) {
      const double length =
          (cage.vertices.row(cage.quads(q, k)) - cage.vertices.row(cage.quads(q, (k + 1) % 4))).norm();
      shortest = std::min(shortest, length);
      longest = std::max(longest, length);
    }
    worst = std::max(worst, longest / shortest);
  }
  return worst;
}

class ComposeFixturePipelines : public ::testing::TestWithParam<FixtureGrid> {};

TEST_P(ComposeFixturePipelines, ComposedSolidIsWatertightAndRespectsTheSolids) {
  const FixtureGrid grid = GetParam();
  const FixtureFiles f = load_fixture(grid.name);
  Inputs inputs{{"design", f.design}, f.solids};
  Options options;
  options.incidence.mode = IncidenceOptions::Mode::Grid;
  options.incidence.grid_h = grid.h;
  options.incidence.grid_origin = Vec3(0.37, 0.29, 0.41) * grid.h;
  const Result result = genbrep::convert(inputs, options, Context());
  Converted r;
  r.name = std::string(grid.name) + " (pipeline)";
  r.design = result.design;
  r.solids = result.solids;
  r.partition = result.relaxed.partition;
  r.composed = result.composed;
  ASSERT_FALSE(r.composed.contacts.empty()) << r.name << joined(r.composed.report.diagnostics);
  expect_valid(r);
  std::string surfaces;
  for (const auto& contact : r.composed.contacts) surfaces += " " + contact.surface;
  std::printf("[compose] %-20s surfaces:%s\n", r.name.c_str(), surfaces.c_str());
  // Issue 5's targets on every cage of the level-set fixtures, each a field-aligned layout.
  EXPECT_TRUE(result.quads.failures.empty()) << r.name;
  for (size_t c = 0; c < result.quads.stats.size(); ++c) {
    const QuadStats& s = result.quads.stats[c];
    EXPECT_FALSE(s.fallback) << r.name << " cage " << c;
    EXPECT_GE(s.interior_valence4_fraction(), 0.95) << r.name << " cage " << c;
    EXPECT_GE(s.boundary_valence3_fraction(), 0.90) << r.name << " cage " << c;
    EXPECT_LE(s.mean_angle_deviation_deg, 12.0) << r.name << " cage " << c;
    EXPECT_EQ(s.flipped_quads, 0) << r.name << " cage " << c;
    EXPECT_EQ(s.degenerate_quads, 0) << r.name << " cage " << c;
    // Irregular vertices only at the field's singularities (within one target edge), but
    // on lattice, whose 96 singularities leave 5 farther (boss had 2 until the layout
    // choice that both cancels close pairs and joins parallel curves was tried).
    std::printf("[compose] %-20s cage %zu: %d irregular vertices, %d away from singularities\n",
                r.name.c_str(), c, s.irregular_vertices, s.irregular_off_singularities);
    EXPECT_LE(s.irregular_off_singularities, std::string(grid.name) == "lattice" ? 5 : 0)
        << r.name << " cage " << c;
  }
  // Every component composes from its fitted cage: none falls back to its design region,
  // and no fit was undone (lattice's first fit folds; the fold is smoothed away).
  for (const auto& contact : r.composed.contacts) EXPECT_EQ(contact.surface, "cage") << r.name;
  for (const auto& fitted : result.fitted)
    EXPECT_FALSE(fitted.report.kept_initial) << r.name << joined(fitted.report.diagnostics);
  // The fit keeps the rows where the quad stage put them: no fitted cage has a quad much
  // longer for its width than the extracted cage's worst. (With the fit's fairness at
  // 10⁻³ the rows bunched where the surface turns tightly: arches' second cage 3.2 -> 8.8,
  // components' fourth 2.3 -> 4.3.)
  ASSERT_EQ(result.fitted.size(), result.quads.cages.size());
  for (size_t c = 0; c < result.fitted.size(); ++c) {
    const double extracted = worst_edge_ratio(result.quads.cages[c]);
    const double fitted = worst_edge_ratio(result.fitted[c].cage);
    std::printf("[compose] %-20s cage %zu: worst edge ratio %.2f extracted, %.2f fitted\n", r.name.c_str(), c,
                extracted, fitted);
    EXPECT_LE(fitted, 1.5 * extracted) << r.name << " cage " << c;
  }
}

INSTANTIATE_TEST_SUITE_P(Fixtures, ComposeFixturePipelines,
                         ::testing::Values(FixtureGrid{"arches", 0.125}, FixtureGrid{"boss", 0.1},
                                           FixtureGrid{"components", 0.1}, FixtureGrid{"lattice", 0.125},
                                           FixtureGrid{"seed", 0.1}),
                         [](const ::testing::TestParamInfo<FixtureGrid>& info) { return std::string(info.param.name); });

// §9.1: a keep-in and a keep-out 0.003 apart (h = 0.05), an organic dome across both.
// Without the design the gap is reported by name; with it, a solid is always made: from
// the dome's design region when the contact holds, else from its part of the design solid
// (the design less the keep-ins), the fallback naming the gap.
TEST(Compose, TinyGapGivesASolidAndNamesTheGap) {
  const Scene s = gap_dome_scene(0.05, 0.003);
  const TriangleMesh& design = s.design;
  const std::vector<SolidInput>& solids = s.solids;
  const double h = s.h;
  const Converted r = convert("tiny_gap", design, solids, h, true);
  const std::string diagnostics = joined(r.composed.report.diagnostics);
  std::printf("[compose] tiny_gap: floor=%d%s\n", r.composed.report.floor, diagnostics.c_str());
  expect_valid(r);
  ASSERT_EQ(r.composed.contacts.size(), 1u);
  const auto& contact = r.composed.contacts[0];
  EXPECT_FALSE(r.composed.report.floor);
  if (contact.surface != "design region") {
    EXPECT_EQ(contact.surface, "design solid");
    EXPECT_NE(contact.fallback.find("crosses a gap of 0.003 between keep-in 'boss' and keep-out 'bolt'"),
              std::string::npos)
        << contact.fallback;
    ASSERT_EQ(fallbacks(r.composed).size(), 1u);
  } else {
    EXPECT_EQ(contact.surface, "design region");
    EXPECT_TRUE(fallbacks(r.composed).empty());
  }
  const Converted bare = convert("tiny_gap without the design", design, solids, h);
  if (!bare.composed.report.ok) {
    EXPECT_NE(joined(bare.composed.report.diagnostics)
                  .find("crosses a gap of 0.003 between keep-in 'boss' and keep-out 'bolt'"),
              std::string::npos)
        << joined(bare.composed.report.diagnostics);
  }
}

// One component without a working tier (§9.1's gap dome) beside one that composes (a tube
// between two keep-ins, 6 units away): the dome takes its part of the design solid (the
// design less the keep-ins), the tube keeps its own cell, and the solid is valid; the
// whole design is not the floor.
TEST(Compose, AComponentWithoutAWorkingTierTakesItsPartOfTheDesignAndTheOthersKeepTheirCells) {
  const Scene dome = gap_dome_scene(0.05, 0.003);
  Scene tube = tube_scene(0.05);
  const Vec3 away(0, 6, 0);
  tube.design.vertices.rowwise() += away.transpose();
  for (auto& solid : tube.solids) solid.mesh.vertices.rowwise() += away.transpose();
  std::vector<SolidInput> solids = dome.solids;
  solids.insert(solids.end(), tube.solids.begin(), tube.solids.end());
  const Converted r = convert("gap dome and tube", merge({dome.design, tube.design}), solids, 0.05, true);
  std::printf("[compose] gap dome and tube: floor=%d%s\n", r.composed.report.floor,
              joined(r.composed.report.diagnostics).c_str());
  expect_valid(r, false);
  EXPECT_FALSE(r.composed.report.floor);
  ASSERT_EQ(r.composed.contacts.size(), 2u);
  int from_design = 0, own = 0;
  for (const auto& contact : r.composed.contacts) {
    const double y = contact.pulled.mesh.vertices.rows() > 0 ? contact.pulled.mesh.vertices.col(1).mean() : 0;
    if (contact.surface == "design solid") {
      ++from_design;
      EXPECT_NE(contact.fallback.find("crosses a gap of 0.003"), std::string::npos) << contact.fallback;
    } else {
      ++own;
      EXPECT_EQ(contact.surface, "design region");
      EXPECT_TRUE(contact.fallback.empty()) << contact.fallback;
      EXPECT_GT(y, 3);  // the tube
    }
  }
  EXPECT_EQ(from_design, 1);
  EXPECT_EQ(own, 1);
  ASSERT_EQ(fallbacks(r.composed).size(), 1u);
  // Every face is the design's, a solid's or the tube's: its organic faces near the tube.
  int tube_faces = 0;
  for (Eigen::Index f = 0; f < r.composed.mesh.triangles.rows(); ++f)
    tube_faces += r.composed.mesh.vertices(r.composed.mesh.triangles(f, 0), 1) > 3 &&
                  r.composed.mesh.triangle_source[static_cast<size_t>(f)] < 0;
  EXPECT_GT(tube_faces, 0);
  EXPECT_EQ(validate(r.composed.mesh).shells, 2);
}

TEST(Pull, CubicBsplineCurveReproducesItsControlPolygonAverages) {
  // At t = 0 the uniform cubic B-spline is (c_{i-1} + 4 c_i + c_{i+1}) / 6.
  const BoundaryCurve curve = cubic_bspline_curve(5, 4);
  ASSERT_EQ(curve.sample_count(), 20);
  double sum = 0;
  for (int k = curve.offsets[4]; k < curve.offsets[5]; ++k) {
    sum += curve.weights[k];
    if (curve.controls[k] == 1) {
      EXPECT_NEAR(curve.weights[k], 4.0 / 6, 1e-15);
    }
  }
  EXPECT_NEAR(sum, 1, 1e-15);
}

// ---- §7.2 local refinement: boundary vertex insertion on cages ----

namespace {

// A k×k planar grid cage over [-s, s]² at z = 0, quads counter-clockwise seen from +z, one
// chain counter-clockwise around it (organic side on the left).
QuadCage grid_cage(int k, double s) {
  QuadCage cage;
  cage.component = 0;
  const auto id = [k](int i, int j) { return j * (k + 1) + i; };
  cage.vertices.resize((k + 1) * (k + 1), 3);
  for (int j = 0; j <= k; ++j) {
    for (int i = 0; i <= k; ++i)
      cage.vertices.row(id(i, j)) = Vec3(-s + 2 * s * i / k, -s + 2 * s * j / k, 0).transpose();
  }
  cage.quads.resize(k * k, 4);
  for (int j = 0; j < k; ++j) {
    for (int i = 0; i < k; ++i)
      cage.quads.row(j * k + i) << id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1);
  }
  std::vector<int> chain;
  for (int i = 0; i < k; ++i) chain.push_back(id(i, 0));
  for (int j = 0; j < k; ++j) chain.push_back(id(k, j));
  for (int i = k; i > 0; --i) chain.push_back(id(i, k));
  for (int j = k; j > 0; --j) chain.push_back(id(0, j));
  cage.boundary_chains = {chain};
  cage.chain_loop = {0};
  return cage;
}

// A tube of m quads around (radius 1, axis z) and r rings of quads along z ∈ [0, r]: two
// chains, bottom and top, quads facing outward.
QuadCage tube_cage(int m, int r) {
  QuadCage cage;
  cage.component = 0;
  const auto id = [m](int a, int l) { return l * m + (a % m); };
  cage.vertices.resize(m * (r + 1), 3);
  for (int l = 0; l <= r; ++l) {
    for (int a = 0; a < m; ++a) {
      const double t = 2 * M_PI * a / m;
      cage.vertices.row(id(a, l)) = Vec3(std::cos(t), std::sin(t), l).transpose();
    }
  }
  cage.quads.resize(m * r, 4);
  for (int l = 0; l < r; ++l) {
    for (int a = 0; a < m; ++a)
      cage.quads.row(l * m + a) << id(a, l), id(a + 1, l), id(a + 1, l + 1), id(a, l + 1);
  }
  std::vector<int> bottom, top;
  for (int a = 0; a < m; ++a) bottom.push_back(id(a, 0));
  for (int a = m; a > 0; --a) top.push_back(id(a, r));
  cage.boundary_chains = {bottom, top};
  cage.chain_loop = {0, 1};
  return cage;
}

// Problems of a cage as a pure-quad, manifold, consistently oriented mesh without
// T-junctions whose boundary is exactly its chains (empty: none). Independent of pull/.
std::string cage_problems(const QuadCage& cage) {
  std::string out;
  const int n = static_cast<int>(cage.vertices.rows());
  std::map<std::pair<int, int>, int> directed;
  std::vector<int> used(static_cast<size_t>(n), 0);
  for (Eigen::Index q = 0; q < cage.quads.rows(); ++q) {
    std::set<int> corners;
    for (int k = 0; k < 4; ++k) {
      const int a = cage.quads(q, k), b = cage.quads(q, (k + 1) % 4);
      if (a < 0 || a >= n) return "quad " + std::to_string(q) + " has an index out of range";
      corners.insert(a);
      ++used[a];
      if (++directed[{a, b}] > 1) out += " directed edge used twice (orientation or manifoldness);";
    }
    if (corners.size() != 4) out += " quad " + std::to_string(q) + " repeats a corner;";
  }
  for (int v = 0; v < n; ++v)
    if (!used[v]) out += " vertex " + std::to_string(v) + " unused;";
  std::set<std::pair<int, int>> boundary, chains;
  for (const auto& [e, count] : directed)
    if (!directed.count({e.second, e.first})) boundary.insert(e);
  for (const auto& chain : cage.boundary_chains) {
    for (size_t i = 0; i < chain.size(); ++i) {
      if (!chains.insert({chain[i], chain[(i + 1) % chain.size()]}).second)
        out += " a chain edge repeats;";
    }
  }
  if (boundary != chains) {
    out += " boundary edges (" + std::to_string(boundary.size()) + ") are not the chain edges (" +
           std::to_string(chains.size()) + "): a T-junction or a wrong chain;";
  }
  return out;
}

// `sub` contains `whole`'s elements in the same cyclic order, starting at the same vertex.
bool is_subsequence(const std::vector<int>& whole, const std::vector<int>& sub) {
  size_t i = 0;
  for (int v : sub)
    if (i < whole.size() && whole[i] == v) ++i;
  return i == whole.size() && !sub.empty() && sub[0] == whole[0];
}

}  // namespace

TEST(BoundaryInsertion, StripSplitAcrossATubeReachesBothChains) {
  const QuadCage cage = tube_cage(6, 3);
  ASSERT_EQ(cage_problems(cage), "");
  const CageRefinement r =
      refine_cage_boundary(cage, {{cage.boundary_chains[0][2], cage.boundary_chains[0][3]}});
  EXPECT_EQ(cage_problems(r.cage), "");
  EXPECT_EQ(r.strip_quads, 3);
  EXPECT_EQ(r.cage.quads.rows(), cage.quads.rows() + 3);        // grown by the strip length
  EXPECT_EQ(r.cage.vertices.rows(), cage.vertices.rows() + 4);  // one per cut edge
  ASSERT_EQ(r.inserted_per_chain, (std::vector<int>{1, 1}));
  for (size_t c = 0; c < 2; ++c) {
    ASSERT_EQ(r.cage.boundary_chains[c].size(), cage.boundary_chains[c].size() + 1);
    EXPECT_TRUE(is_subsequence(cage.boundary_chains[c], r.cage.boundary_chains[c]));
  }
  // The new bottom vertex sits between old chain vertices 2 and 3.
  EXPECT_EQ(r.cage.boundary_chains[0][2], cage.boundary_chains[0][2]);
  EXPECT_GE(r.cage.boundary_chains[0][3], cage.vertices.rows());
  EXPECT_EQ(r.cage.boundary_chains[0][4], cage.boundary_chains[0][3]);
  // Every quad faces outward (the tube's radial direction).
  for (Eigen::Index q = 0; q < r.cage.quads.rows(); ++q) {
    const Vec3 a = r.cage.vertices.row(r.cage.quads(q, 0)),
               b = r.cage.vertices.row(r.cage.quads(q, 1)),
               c = r.cage.vertices.row(r.cage.quads(q, 2));
    const Vec3 centre = 0.5 * (a + c);
    EXPECT_GT((b - a).cross(c - a).dot(Vec3(centre.x(), centre.y(), 0)), 0) << "quad " << q;
  }
  // The chains still follow the limit tessellation's boundary (cage_sheet checks it).
  EXPECT_NO_THROW(cage_sheet(r.cage, {{0}, {0}}, 4));
  // The least-squares positions change the limit less than the midpoints would.
  EXPECT_LE(r.limit_change, r.midpoint_change);
  std::printf("[refine] tube 6x3: max limit change %.3g (%s kept), %.3g with midpoints\n",
              r.limit_change, r.least_squares ? "least squares" : "midpoints", r.midpoint_change);
}

TEST(BoundaryInsertion, CrossingStripsCutAQuadInFourAndCreasesSplit) {
  QuadCage cage = grid_cage(3, 1.0);
  ASSERT_EQ(cage_problems(cage), "");
  const auto& chain =
      cage.boundary_chains[0];  // 12 vertices: bottom 0..2, right 3..5, top 6..8, left 9..11
  cage.crease_edges = {{chain[1], chain[2]}, {chain[3], chain[4]}};
  cage.crease_values = {1.0f, 0.5f};
  // The middle bottom edge (strip goes up) and the middle left edge (strip goes right):
  // they cross in the centre quad.
  const CageRefinement r =
      refine_cage_boundary(cage, {{chain[1], chain[2]}, {chain[10], chain[11]}});
  EXPECT_EQ(cage_problems(r.cage), "");
  EXPECT_EQ(r.strip_quads, 6);
  EXPECT_EQ(r.cage.quads.rows(), 16);     // 9 + 3 + 3 + 1 (the crossing quad is cut in four)
  EXPECT_EQ(r.cage.vertices.rows(), 25);  // 16 + 8 cut edges + 1 centre
  ASSERT_EQ(r.inserted_per_chain, (std::vector<int>{4}));  // each strip enters and leaves the chain
  EXPECT_TRUE(is_subsequence(chain, r.cage.boundary_chains[0]));
  for (Eigen::Index q = 0; q < r.cage.quads.rows(); ++q) {
    const Vec3 a = r.cage.vertices.row(r.cage.quads(q, 0)),
               b = r.cage.vertices.row(r.cage.quads(q, 1)),
               c = r.cage.vertices.row(r.cage.quads(q, 2));
    EXPECT_GT((b - a).cross(c - a).z(), 0) << "quad " << q;
  }
  // The split crease is two creased edges with its value; the other one is unchanged.
  const int m = r.cage.boundary_chains[0][2];
  EXPECT_GE(m, 16);
  using E = std::array<int, 2>;
  EXPECT_EQ(r.cage.crease_edges,
            (std::vector<E>{{chain[1], m}, {m, chain[2]}, {chain[3], chain[4]}}));
  EXPECT_EQ(r.cage.crease_values, (std::vector<float>{1.0f, 1.0f, 0.5f}));
  EXPECT_NO_THROW(cage_sheet(r.cage, {{0}}, 4));
  EXPECT_LE(r.limit_change, r.midpoint_change);
  std::printf(
      "[refine] grid 3x3, crossing strips: max limit change %.3g (%s kept), %.3g with midpoints\n",
      r.limit_change, r.least_squares ? "least squares" : "midpoints", r.midpoint_change);
  // Over a quad limit the refinement is only counted: the same topology, its new points
  // at the midpoints (here the least squares moved them).
  ASSERT_TRUE(r.least_squares);
  const CageRefinement over = refine_cage_boundary(cage, {{chain[1], chain[2]}, {chain[10], chain[11]}}, 15);
  EXPECT_TRUE(over.over_limit);
  EXPECT_FALSE(over.least_squares);
  EXPECT_EQ(over.cage.quads, r.cage.quads);
  EXPECT_EQ(over.inserted_per_chain, r.inserted_per_chain);
  EXPECT_EQ(over.cage.vertices.topRows(16), cage.vertices);
  EXPECT_NE(over.cage.vertices.bottomRows(9), r.cage.vertices.bottomRows(9));
  const CageRefinement within = refine_cage_boundary(cage, {{chain[1], chain[2]}, {chain[10], chain[11]}}, 16);
  EXPECT_FALSE(within.over_limit);
  EXPECT_EQ(within.cage.vertices, r.cage.vertices);
  // A planar cage stays planar; an interior edge is refused.
  EXPECT_LT(r.cage.vertices.col(2).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_THROW(refine_cage_boundary(cage, {{5, 6}}), Error);
}

// A membrane spanning a square window frame (four keep-in bars, inner half-width 1, outer
// 1 + w): its rim must lie in the bars. The limit boundary of a coarse cage is a rounded
// curve that cuts the frame's corners into the window; only finer boundary spacing near
// the corners lets it turn inside the bars.
TEST(BoundaryInsertion, PullConvergesOnlyWithInsertion) {
  const double w = 0.04, t = 0.2;
  std::vector<SolidInput> inputs;
  const double a = 1.0, b = 1.0 + w;
  const std::pair<Vec3, Vec3> bars[4] = {{Vec3(a, -b, -t), Vec3(b, b, t)},
                                         {Vec3(-b, -b, -t), Vec3(-a, b, t)},
                                         {Vec3(-b, a, -t), Vec3(b, b, t)},
                                         {Vec3(-b, -b, -t), Vec3(b, -a, t)}};
  for (int i = 0; i < 4; ++i) {
    inputs.push_back(
        {"bar" + std::to_string(i), Role::KeepIn,
         prepare_closed_mesh(box_mesh(bars[i].first, bars[i].second), "bar", nullptr)});
  }
  const SolidSet solids(inputs, nullptr);
  const QuadCage cage = grid_cage(2, 1.0 + w / 2);
  const std::vector<std::vector<int>> chain_solids = {{0, 1, 2, 3}};
  const double eta = -1e-3;
  PullOptions without;
  without.max_insertions = 0;
  const CagePull coarse = pull_cage(cage, chain_solids, solids, eta, without);
  ASSERT_EQ(coarse.sheet.loops.size(), 1u);
  EXPECT_FALSE(coarse.sheet.loops[0].curve.converged);
  EXPECT_EQ(coarse.sheet.loops[0].inserted_vertices, 0);
  EXPECT_EQ(coarse.cage.quads, cage.quads);
  const CagePull refined = pull_cage(cage, chain_solids, solids, eta, PullOptions{});
  ASSERT_EQ(refined.sheet.loops.size(), 1u);
  const LoopPull& loop = refined.sheet.loops[0];
  EXPECT_TRUE(loop.curve.converged)
      << "max F after " << loop.curve.max_after << joined(refined.sheet.diagnostics);
  EXPECT_GT(loop.inserted_vertices, 0);
  EXPECT_EQ(cage_problems(refined.cage), "");
  EXPECT_EQ(static_cast<int>(refined.cage.boundary_chains[0].size()),
            static_cast<int>(cage.boundary_chains[0].size()) + loop.inserted_vertices);
  EXPECT_TRUE(is_subsequence(cage.boundary_chains[0], refined.cage.boundary_chains[0]));
  // Independently of pull_curve: every vertex of the pulled limit tessellation's boundary
  // loop lies inside a bar, at least |η| deep.
  const auto deepest_worst = [&](int n) {
    const OrganicSheet sheet = cage_sheet(refined.cage, chain_solids, n);
    double worst = -1;
    for (int v : sheet.loops[0].vertices) {
      const Vec3 p = sheet.mesh.vertices.row(v);
      double d = std::numeric_limits<double>::infinity();
      for (const auto& [lo, hi] : bars) d = std::min(d, box_sdf(p, lo, hi));
      worst = std::max(worst, d);
    }
    return worst;
  };
  const double worst = deepest_worst(4);  // the tessellation compose uses
  EXPECT_LE(worst, eta * (1 - 1e-9));
  EXPECT_LT(deepest_worst(16), 0);  // and the limit curve between its samples
  std::printf(
      "[refine] frame w=%.2f: without insertion max F %.3g (converged %d); with: %d vertices "
      "inserted, "
      "%d quads, max F %.3g, tessellation boundary max D %.3g\n",
      w, coarse.sheet.loops[0].curve.max_after, coarse.sheet.loops[0].curve.converged,
      loop.inserted_vertices, static_cast<int>(refined.cage.quads.rows()), loop.curve.max_after,
      worst);
  ASSERT_FALSE(refined.sheet.diagnostics.empty());
  EXPECT_NE(refined.sheet.diagnostics.back().find("boundary vertices inserted"), std::string::npos);
}

// ---- A cage extended into its solids (the tier below the fitted cage) ----

namespace {

// A tube cage (radius 1, z ∈ [0, 4]) whose bottom ring stops 0.6 short of a keep-in foot and
// whose top ring lies 0.1 inside a keep-in head.
struct ShortTube {
  QuadCage cage = tube_cage(12, 4);
  std::vector<SolidInput> inputs{
      {"foot", Role::KeepIn, prepare_closed_mesh(box_mesh(Vec3(-2, -2, -1.6), Vec3(2, 2, -0.6)), "foot", nullptr)},
      {"head", Role::KeepIn, prepare_closed_mesh(box_mesh(Vec3(-2, -2, 3.9), Vec3(2, 2, 5)), "head", nullptr)}};
  std::vector<std::vector<int>> chain_solids{{0}, {1}};
};

}  // namespace

TEST(ExtendedCage, ARowOfQuadsReachesIntoEachChainsSolidAndTheFittedQuadsStay) {
  const ShortTube t;
  const SolidSet solids(t.inputs, nullptr);
  const ExtendedCage e = extend_cage(t.cage, t.chain_solids, solids);
  ASSERT_TRUE(e.extended) << e.problem;
  EXPECT_EQ(cage_problems(e.cage), "");
  EXPECT_EQ(e.cage.quads.rows(), t.cage.quads.rows() + 24);  // one row of 12 per chain
  EXPECT_EQ(e.cage.quads.topRows(t.cage.quads.rows()), t.cage.quads);
  EXPECT_EQ(e.cage.vertices.topRows(t.cage.vertices.rows()), t.cage.vertices);
  EXPECT_EQ(e.sides, (std::vector<int>{1, 1}));
  // Independently of pull/: every new chain vertex is inside its own box, and no further
  // out than the 8 chain edges the extension allows.
  const double chain_edge = 2 * std::sin(M_PI / 12);
  for (size_t c = 0; c < 2; ++c) {
    ASSERT_EQ(e.cage.boundary_chains[c].size(), t.cage.boundary_chains[c].size());
    for (size_t i = 0; i < e.cage.boundary_chains[c].size(); ++i) {
      const Vec3 p = e.cage.vertices.row(e.cage.boundary_chains[c][i]).transpose();
      const Vec3 from = t.cage.vertices.row(t.cage.boundary_chains[c][i]).transpose();
      if (c == 0) EXPECT_LT(p.z(), -0.6) << "bottom chain vertex " << i << " at " << p.transpose();
      if (c == 1) EXPECT_GT(p.z(), 3.9) << "top chain vertex " << i << " at " << p.transpose();
      EXPECT_LE((p - from).norm(), 8 * chain_edge + 1e-9);
    }
  }
}

TEST(ExtendedCage, ACageShortOfItsKeepInComposesFromItsOwnQuads) {
  const ShortTube t;
  const SolidSet solids(t.inputs, nullptr);
  OrganicSurface surface;
  surface.sheet.component = 0;
  surface.cage = t.cage;
  surface.chain_solids = t.chain_solids;
  const Composed composed = compose({surface}, solids, {}, Context());
  ASSERT_TRUE(composed.report.ok) << joined(composed.report.diagnostics);
  ASSERT_EQ(composed.contacts.size(), 1u);
  const ComponentContact& contact = composed.contacts[0];
  EXPECT_TRUE(contact.surface == "cage" || contact.surface == "extended cage") << contact.surface;
  if (contact.surface == "extended cage") EXPECT_FALSE(contact.fallback.empty());
  const MeshValidation v = validate(composed.mesh);
  EXPECT_TRUE(v.closed_manifold());
  EXPECT_FALSE(composed.report.self_intersecting);
  // The boxes, and the tube between them (limit radius about 0.95 over 4.5 units of
  // length: about 12.9) at least over 3.8 units.
  const double boxes = 16 * 1.0 + 16 * 1.1;
  EXPECT_GT(v.signed_volume, boxes + 0.8 * M_PI * 3.8) << v.signed_volume;
}

// ---- Composition from fitted cages (pipeline) and recompose from edited cages ----

namespace {

// The design is the converted one (recompose has none): volume compares against it.
Converted from_result(const std::string& name, const Result& result, const TriangleMesh& design) {
  Converted r;
  r.name = name;
  r.design = design;
  r.solids = result.solids;
  r.composed = result.composed;
  return r;
}

Inputs scene_inputs(const Scene& s) {
  Inputs in;
  in.design = {s.name, s.design};
  in.solids = s.solids;
  return in;
}

// Outward unit normal of the cage at vertex v (sum of its quads' corner normals).
Vec3 cage_normal(const QuadCage& cage, int v) {
  Vec3 n = Vec3::Zero();
  for (Eigen::Index q = 0; q < cage.quads.rows(); ++q) {
    for (int k = 0; k < 4; ++k) {
      if (cage.quads(q, k) != v) continue;
      const Vec3 p = cage.vertices.row(v), a = cage.vertices.row(cage.quads(q, (k + 1) % 4)),
                 b = cage.vertices.row(cage.quads(q, (k + 3) % 4));
      n += (a - p).cross(b - p);
    }
  }
  return n.normalized();
}

// The interior control point farthest from every solid (the middle of an organic span).
int farthest_interior_point(const QuadCage& cage, const SolidSet& solids) {
  std::vector<char> boundary(static_cast<size_t>(cage.vertices.rows()), 0);
  for (const auto& chain : cage.boundary_chains) for (int v : chain) boundary[v] = 1;
  int best = -1;
  double best_d = -1;
  for (int v = 0; v < cage.vertices.rows(); ++v) {
    if (boundary[v]) continue;
    double d = std::numeric_limits<double>::infinity();
    for (int j = 0; j < solids.size(); ++j) d = std::min(d, solids.surface(j).distance(cage.vertices.row(v).transpose()));
    if (d > best_d) best_d = d, best = v;
  }
  return best;
}

}  // namespace

class ComposeFromCages : public ::testing::TestWithParam<int> {};

TEST_P(ComposeFromCages, PulledCagesComposeAWatertightSolid) {
  const Scene s = GetParam() == 0 ? tube_scene(0.05) : two_arches_scene(0.05);
  const Result result = convert(scene_inputs(s), Options{}, Context());
  ASSERT_FALSE(result.fitted.empty()) << s.name;
  expect_valid(from_result(s.name + "/cages", result, result.design));
  const auto report = nlohmann::json::parse(result.report_json);
  for (const auto& contact : result.composed.contacts) {
    bool fitted = false;
    for (const auto& f : result.fitted) fitted = fitted || f.cage.component == contact.component;
    EXPECT_EQ(contact.surface, fitted ? "cage" : "design region") << s.name << joined(contact.diagnostics);
    EXPECT_TRUE(contact.established) << s.name << joined(contact.diagnostics);
    for (double after : contact.max_distance_after) EXPECT_LE(after, contact.eta) << s.name;
    std::printf("[cages] %s component %d: %s, eta=%.3g (%d doublings), %d curves, max F before %.3g after %.3g\n",
                s.name.c_str(), contact.component, contact.surface.c_str(), contact.eta, contact.doublings,
                static_cast<int>(contact.curves.size()),
                *std::max_element(contact.max_distance_before.begin(), contact.max_distance_before.end()),
                *std::max_element(contact.max_distance_after.begin(), contact.max_distance_after.end()));
  }
  // final_cages hands on the pulled cages: same topology as the fitted ones.
  const auto cages = final_cages(result);
  ASSERT_EQ(cages.size(), result.fitted.size());
  for (size_t i = 0; i < cages.size(); ++i) EXPECT_EQ(cages[i].quads, result.fitted[i].cage.quads);
  for (const auto& c : report["composed"]["contacts"]) EXPECT_TRUE(c.contains("surface"));
}

INSTANTIATE_TEST_SUITE_P(Scenes, ComposeFromCages, ::testing::Values(0, 1));

TEST(Recompose, EditedCageChangesTheVolumeTheExpectedWay) {
  const Scene s = tube_scene(0.05);
  const Result converted = convert(scene_inputs(s), Options{}, Context());
  std::vector<QuadCage> cages = final_cages(converted);
  ASSERT_EQ(cages.size(), 1u);
  const Result same = recompose(s.solids, cages, Options{}, Context());
  expect_valid(from_result("tube/recomposed", same, converted.design));
  // Move the middle control point outward by h / 2: an additive surface gains volume.
  const SolidSet solids(converted.solids, nullptr);
  const int v = farthest_interior_point(cages[0], solids);
  ASSERT_GE(v, 0);
  cages[0].vertices.row(v) += 0.5 * s.h * cage_normal(cages[0], v).transpose();
  const Result edited = recompose(s.solids, cages, Options{}, Context());
  expect_valid(from_result("tube/edited", edited, converted.design));
  ASSERT_EQ(edited.composed.contacts.size(), 1u);
  EXPECT_EQ(edited.composed.contacts[0].surface, "cage");
  EXPECT_TRUE(edited.composed.contacts[0].additive);
  std::printf("[recompose] tube: convert %.5f, recomposed %.5f, control point %d moved out by %.3f: %.5f\n",
              converted.composed.report.volume, same.composed.report.volume, v, 0.5 * s.h,
              edited.composed.report.volume);
  EXPECT_NEAR(same.composed.report.volume, converted.composed.report.volume, 1e-3 * converted.composed.report.volume);
  EXPECT_GT(edited.composed.report.volume, same.composed.report.volume);
}

TEST(Recompose, OpenOrNonQuadCagesAreNamed) {
  const Scene s = tube_scene(0.05);
  const Result converted = convert(scene_inputs(s), Options{}, Context());
  const std::vector<QuadCage> cages = final_cages(converted);
  ASSERT_EQ(cages.size(), 1u);
  // Non-quad: a cage read from polygons with a pentagon and two triangles.
  PolygonSoup soup;
  soup.vertices = Vertices::Random(6, 3);
  for (const std::vector<int>& face : {std::vector<int>{0, 1, 2, 3, 4}, {0, 1, 5}, {1, 2, 5}, {2, 3, 4, 5}}) {
    soup.indices.insert(soup.indices.end(), face.begin(), face.end());
    soup.offsets.push_back(static_cast<int>(soup.indices.size()));
  }
  try {
    cage_from_polygons(soup, "component 2");
    FAIL() << "non-quad cage accepted";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), "cage 'component 2' is not a quad mesh: 2 faces have 3 corners, 1 face has 5 corners");
  }
  // Open: delete the quad farthest from the solids: its hole is a boundary loop on no solid.
  const SolidSet solids(converted.solids, nullptr);
  QuadCage holed = cages[0];
  const int v = farthest_interior_point(holed, solids);
  Eigen::Index drop = -1;
  for (Eigen::Index q = 0; q < holed.quads.rows() && drop < 0; ++q) {
    for (int k = 0; k < 4; ++k) drop = holed.quads(q, k) == v ? q : drop;
  }
  Quads kept(holed.quads.rows() - 1, 4);
  for (Eigen::Index q = 0, r = 0; q < holed.quads.rows(); ++q) if (q != drop) kept.row(r++) = holed.quads.row(q);
  holed.quads = kept;
  try {
    recompose(s.solids, {holed}, Options{}, Context());
    FAIL() << "open cage accepted";
  } catch (const Error& e) {
    std::printf("[recompose] %s\n", e.what());
    EXPECT_EQ(std::string(e.what()).rfind("cage 'component 0' is open: its boundary loop", 0), 0u) << e.what();
  }
}

// A cage compose cannot pull (here one quad given twice: not 2-manifold) does not fail
// the composition: that component is composed from its design region, and the report
// says why.
TEST(Compose, UnusableCageFallsBackToTheDesignRegion) {
  const Scene s = tube_scene(0.05);
  const Result result = convert(scene_inputs(s), Options{}, Context());
  ASSERT_EQ(result.fitted.size(), 1u);
  std::vector<OrganicSurface> surfaces;
  for (auto& sheet : organic_sheets(result.relaxed.design, result.relaxed.partition))
    surfaces.push_back({std::move(sheet), std::nullopt, {}});
  QuadCage broken = result.fitted[0].cage;
  Quads quads(broken.quads.rows() + 1, 4);
  quads.topRows(broken.quads.rows()) = broken.quads;
  quads.row(broken.quads.rows()) = broken.quads.row(broken.quads.rows() / 2);
  broken.quads = quads;
  OrganicSurface& surface = surfaces.at(static_cast<size_t>(broken.component));
  surface.cage = broken;
  for (int loop : broken.chain_loop)
    surface.chain_solids.push_back(result.relaxed.partition.loops[loop].solids);
  const SolidSet solids(result.solids, nullptr);
  const Composed composed = compose(surfaces, solids, ComposeOptions{}, Context());
  ASSERT_EQ(composed.contacts.size(), 1u);
  EXPECT_TRUE(composed.contacts[0].established) << joined(composed.contacts[0].diagnostics);
  EXPECT_EQ(composed.contacts[0].surface, "design region");
  EXPECT_TRUE(composed.report.ok) << joined(composed.report.diagnostics);
  bool named = false;
  for (const auto& d : composed.report.diagnostics)
    named = named || d.find("its cage could not be pulled") != std::string::npos;
  EXPECT_TRUE(named) << joined(composed.report.diagnostics);
  Converted r;
  r.name = "tube/broken cage";
  r.design = result.design;
  r.solids = result.solids;
  r.composed = composed;
  expect_valid(r);
}

// A part of the design that touches no solid is a closed organic shell: part of the
// solid, as its best tier (not a fallback). Two arches, only the first one's feet given
// as keep-ins: the second arch and its feet are one closed shell.
TEST(Compose, ClosedOrganicShellIsPartOfTheSolid) {
  Scene s = two_arches_scene(0.1);
  s.solids.resize(2);  // foot0 and foot1: the arch at y = -1.5
  const Result result = convert(scene_inputs(s), Options{}, Context());
  Converted r = from_result("two arches, one without solids", result, result.design);
  expect_valid(r);
  ASSERT_EQ(result.composed.contacts.size(), 2u) << joined(result.composed.report.diagnostics);
  int shells = 0;
  for (const auto& contact : result.composed.contacts) shells += contact.surface == "closed shell";
  EXPECT_EQ(shells, 1) << joined(result.composed.report.diagnostics);
  EXPECT_FALSE(result.composed.report.floor);
  EXPECT_EQ(exit_status(result), fallbacks(result.composed).empty() ? 0 : 3);
}

// A solver result that stops short of its keep-in (the keep-in is material anyway): the
// keep-in is 3 voxels larger than the design's block on every side but the top. Whatever
// tier composes it, the solid is valid and holds the whole keep-in.
TEST(Compose, DesignShortOfItsKeepInStillGivesASolidHoldingIt) {
  const double h = 0.05;
  const Vec3 lo(-1, -0.6, -0.5), hi(0, 0.6, 0.5), margin(0.15, 0.15, 0.15);
  auto f = [&](const Vec3& p) {
    return std::min(box_sdf(p, lo, hi), capsule_sdf(p, Vec3(-0.5, 0, 0.4), Vec3(0.8, 0, 1.0), 0.25));
  };
  const Vec3 origin(-1.4 - 0.37 * h, -1.0 - 0.29 * h, -0.9 - 0.41 * h);
  const TriangleMesh design = extract_level_set(f, origin, h, Eigen::Vector3i(56, 40, 50));
  const std::vector<SolidInput> solids{{"block", Role::KeepIn, box_mesh(lo - margin, Vec3(hi.x(), hi.y(), hi.z()) + Vec3(0.15, 0.15, -0.1))}};
  const Converted r = convert("short of keep-in", design, solids, h, true);
  std::printf("[compose] short of keep-in: floor=%d%s\n", r.composed.report.floor,
              joined(r.composed.report.diagnostics).c_str());
  expect_valid(r, false);
  EXPECT_TRUE(r.composed.report.ok);
}

// Near-coincident solids on a tilted axis: a keep-out bolt in the bore of a keep-in boss,
// their walls apart by ε × the scene (0 = the same vertices), with an organic strut from
// the boss to a keep-in block. Every ε gives a solid without self-intersections.
class NearCoincidentBore : public ::testing::TestWithParam<double> {};

TEST_P(NearCoincidentBore, GivesASolidWithoutSelfIntersections) {
  const double h = 0.06, epsilon = GetParam();
  const Vec3 axis = Vec3(0.3, 0.2, 1).normalized(), base(0, 0, -0.4);
  const double inner = 0.3, outer = 0.6, length = 0.8;
  auto tube = [&](const Vec3& p) {
    const double t = (p - base).dot(axis);
    const double r = ((p - base) - t * axis).norm();
    return std::max({r - outer, inner - r, -t, t - length});
  };
  const Vec3 block_lo(1.2, -0.4, -0.4), block_hi(1.8, 0.4, 0.4);
  auto f = [&](const Vec3& p) {
    const double material = std::min({tube(p), box_sdf(p, block_lo, block_hi),
                                      capsule_sdf(p, base + 0.4 * axis, Vec3(1.5, 0, 0), 0.2)});
    const double t = (p - base).dot(axis);
    return std::max(material, inner - ((p - base) - t * axis).norm());  // the bore stays open
  };
  const Vec3 origin(-1.0 - 0.37 * h, -1.0 - 0.29 * h, -0.8 - 0.41 * h);
  const TriangleMesh design = extract_level_set(f, origin, h, Eigen::Vector3i(50, 34, 34));
  const double scene = bounding_box_diagonal(design.vertices);
  const int segments = 48;
  const std::vector<SolidInput> solids{
      {"boss", Role::KeepIn, tube_mesh(base, axis, 0, length, inner, outer, segments)},
      {"bolt", Role::KeepOut, tube_mesh(base, axis, -0.3, length + 0.3, 0, inner + epsilon * scene, segments)},
      {"block", Role::KeepIn, box_mesh(block_lo, block_hi)}};
  const Converted r = convert("near-coincident bore", design, solids, h, true);
  std::printf("[compose] near-coincident bore eps=%g: floor=%d%s\n", epsilon, r.composed.report.floor,
              joined(r.composed.report.diagnostics).c_str());
  expect_valid(r, false);
  EXPECT_TRUE(r.composed.report.ok);
}

INSTANTIATE_TEST_SUITE_P(Epsilons, NearCoincidentBore, ::testing::Values(0.0, 1e-12, 1e-9, 1e-6, 1e-3));

// Near coincidence in the design Boolean (generated seed 2: a plate's hole and a keep-out
// bore whose walls agree to 4e-16 on a tilted axis): (design ∪ keep-ins) \ keep-outs,
// exact, rounded to doubles with the short edges collapsed, crosses itself; with each
// solid grown by its own 1-2e-6 of the scene first (detail::grown, as compose does), the
// walls cross by that much, it rounds without a crossing and bounds the same volume to
// within the growth.
TEST(Compose, GrowingTheSolidsLetsTheDesignBooleanRoundWithoutCrossings) {
  using detail::ExactMesh;
  const GeneratedCase c = generate_case(2);
  const double scene = bounding_box_diagonal(c.design.vertices);
  auto design_boolean = [&](double grow) {
    ExactMesh g = detail::to_exact(c.design);
    for (const Role role : {Role::KeepIn, Role::KeepOut})
      for (size_t s = 0; s < c.solids.size(); ++s) {
        const GeneratedSolid& solid = c.solids[s];
        if (solid.role != role) continue;
        const double by = grow * (1.0 + static_cast<double>(s) / static_cast<double>(c.solids.size()));
        ExactMesh operand = detail::to_exact(grow > 0 ? detail::grown(solid.mesh, by) : solid.mesh), out;
        EXPECT_EQ(detail::make_usable(&operand, true), "") << solid.name;
        EXPECT_TRUE(detail::exact_boolean(g, operand, role == Role::KeepIn, &out)) << solid.name;
        g = std::move(out);
      }
    return g;
  };
  auto rounded = [&](const ExactMesh& g) { return detail::round_to_doubles(g, 1e-10 * scene).mesh; };
  auto crossings = [&](const TriangleMesh& m) {
    std::vector<std::pair<detail::InexactMesh::Face_index, detail::InexactMesh::Face_index>> pairs;
    CGAL::Polygon_mesh_processing::self_intersections(detail::to_inexact(m), std::back_inserter(pairs));
    return pairs.size();
  };
  const TriangleMesh plain = rounded(design_boolean(0));
  ASSERT_GT(crossings(plain), 0u);
  const TriangleMesh grown = rounded(design_boolean(1e-6 * scene));
  std::printf("[compose] seed 2 design Boolean: %zu crossing pairs; with the solids grown: %zu\n",
              crossings(plain), crossings(grown));
  EXPECT_EQ(crossings(grown), 0u);
  const MeshValidation before = validate(plain), after = validate(grown);
  EXPECT_EQ(after.boundary_edges, 0);
  EXPECT_EQ(after.non_manifold_edges, 0);
  EXPECT_NEAR(after.signed_volume, before.signed_volume, 1e-4 * std::abs(before.signed_volume));
}

// The corefinement orders its output by where its boxes lie in memory; exact_boolean
// returns the solid in one canonical order (vertices lexicographic, faces by corners), so
// the same Boolean after different allocations is the same mesh.
TEST(Compose, AnExactBooleanIsTheSameMeshWhateverWasAllocatedBefore) {
  const detail::ExactMesh a = detail::to_exact(box_mesh(Vec3(0, 0, 0), Vec3(1, 1, 1), 3));
  const detail::ExactMesh b = detail::to_exact(
      oriented_box_mesh(Vec3(1, 0.5, 0.5), Vec3(0.4, 0.3, 0.35), Eigen::AngleAxisd(0.3, Vec3(1, 2, 3).normalized()).toRotationMatrix()));
  auto listed = [](const detail::ExactMesh& m) {
    std::vector<std::array<double, 3>> points;
    for (const auto v : m.vertices())
      points.push_back({CGAL::to_double(m.point(v).x()), CGAL::to_double(m.point(v).y()), CGAL::to_double(m.point(v).z())});
    std::vector<std::array<int, 3>> faces;
    for (const auto f : m.faces()) {
      std::array<int, 3> c{};
      int k = 0;
      for (const auto v : CGAL::vertices_around_face(m.halfedge(f), m)) c[static_cast<size_t>(k++)] = static_cast<int>(v.idx());
      faces.push_back(c);
    }
    return std::make_pair(points, faces);
  };
  detail::ExactMesh first, second;
  ASSERT_TRUE(detail::exact_boolean(a, b, false, &first));
  std::vector<std::vector<char>> clutter;
  for (int i = 1; i <= 64; ++i) clutter.emplace_back(static_cast<size_t>(i * 4093));
  ASSERT_TRUE(detail::exact_boolean(detail::ExactMesh(a), detail::ExactMesh(b), false, &second));
  const auto x = listed(first), y = listed(second);
  EXPECT_GT(x.second.size(), 108u);  // cut by the tilted box
  EXPECT_EQ(x, y);
  EXPECT_TRUE(std::is_sorted(x.first.begin(), x.first.end()));
  EXPECT_TRUE(std::is_sorted(x.second.begin(), x.second.end()));
}

// A grown solid: every face moves outward by at least the growth and no vertex by more
// than 5 times it; a box grows into the box larger by it on every side, and a tube's bore
// narrows.
TEST(Compose, AGrownSolidMovesEveryFaceOutwardByAtLeastTheGrowth) {
  const double delta = 1e-3;
  const std::vector<TriangleMesh> solids{
      box_mesh(Vec3(0, 0, 0), Vec3(1, 1, 1), 3),
      tube_mesh(Vec3(0.2, -0.1, 0.3), Vec3(1, 2, 3).normalized(), 0, 1.5, 0.4, 0.7, 48),
      generate_case(2).solids.front().mesh};
  for (const TriangleMesh& solid : solids) {
    const TriangleMesh g = detail::grown(solid, delta);
    ASSERT_EQ(g.vertices.rows(), solid.vertices.rows());
    ASSERT_EQ(g.triangles, solid.triangles);
    for (Eigen::Index t = 0; t < solid.triangles.rows(); ++t) {
      const Vec3 a = solid.vertices.row(solid.triangles(t, 0)), b = solid.vertices.row(solid.triangles(t, 1)),
                 c = solid.vertices.row(solid.triangles(t, 2));
      const Vec3 n = (b - a).cross(c - a).normalized();
      for (int k = 0; k < 3; ++k) {
        const Vec3 move = (g.vertices.row(solid.triangles(t, k)) - solid.vertices.row(solid.triangles(t, k))).transpose();
        EXPECT_GE(move.dot(n), delta * (1 - 1e-9)) << "triangle " << t;
        EXPECT_LE(move.norm(), 5 * delta * (1 + 1e-9));
      }
    }
    EXPECT_GT(validate(g).signed_volume, validate(solid).signed_volume);
  }
  const TriangleMesh box = detail::grown(solids[0], delta);
  EXPECT_NEAR(validate(box).signed_volume, std::pow(1 + 2 * delta, 3), 1e-12);
  EXPECT_NEAR(box.vertices.minCoeff(), -delta, 1e-15);
  EXPECT_NEAR(box.vertices.maxCoeff(), 1 + delta, 1e-15);
}

// CGAL's corefinement requires operands without self-intersections; a keep-out that
// crosses itself (two overlapping boxes as one mesh, past the mesh stage's checks) is
// refused with its name before any corefinement, and compose says so instead of crashing.
TEST(Compose, OperandThatBreaksCgalPreconditionsIsRefusedByName) {
  const Scene s = grown_box_scene(0.1);
  std::vector<SolidInput> solids = s.solids;
  solids.push_back({"crossed", Role::KeepOut,
                    merge({box_mesh(Vec3(2, 2, 2), Vec3(3, 3, 3)), box_mesh(Vec3(2.5, 2.5, 2.5), Vec3(3.5, 3.5, 3.5))})});
  const TriangleMesh design = prepare_closed_mesh(s.design, "design", nullptr);
  const SolidSet set(solids, nullptr);
  IncidenceOptions options;
  options.tolerance = s.h;
  const Incidence incidence = compute_incidence(design, set, options, Context());
  const Partition p = partition(to_trimesh(design), incidence, set.size(), {}, Context());
  const Composed composed = compose(organic_sheets(design, p), set, {}, Context(), &design);
  const std::string diagnostics = joined(composed.report.diagnostics);
  EXPECT_FALSE(composed.report.ok);
  EXPECT_EQ(composed.mesh.triangles.rows(), 0);
  EXPECT_NE(diagnostics.find("keep-out 'crossed' intersects itself"), std::string::npos) << diagnostics;
}

// Zero-area triangles pass the mesh stage but are self-intersections to CGAL: a keep-in
// whose top face is split through a point on an edge composes all the same.
TEST(Compose, ZeroAreaTrianglesInASolidAreRepairedBeforeCorefinement) {
  const Scene s = grown_box_scene(0.1);
  std::vector<SolidInput> solids = s.solids;
  ASSERT_EQ(solids.size(), 1u);
  TriangleMesh& box = solids[0].mesh;
  // Split triangle 0 at the midpoint m of its edge (a, b); the neighbour across that edge
  // stays as it is, and the zero-area triangle (m, a, b) closes the seam between them.
  const int a = box.triangles(0, 0), b = box.triangles(0, 1), c = box.triangles(0, 2);
  const Vec3 mid = 0.5 * (box.vertices.row(a) + box.vertices.row(b)).transpose();
  const int m = static_cast<int>(box.vertices.rows());
  box.vertices.conservativeResize(m + 1, 3);
  box.vertices.row(m) = mid.transpose();
  const Eigen::Index n = box.triangles.rows();
  box.triangles.conservativeResize(n + 2, 3);
  box.triangles.row(0) << a, m, c;
  box.triangles.row(n) << m, b, c;
  box.triangles.row(n + 1) << m, a, b;
  box.triangle_source.clear();
  const Converted r = convert("zero-area keep-in", s.design, solids, s.h, true);
  std::printf("[compose] zero-area keep-in: floor=%d%s\n", r.composed.report.floor,
              joined(r.composed.report.diagnostics).c_str());
  expect_valid(r);
}

// A design with no solids at all is one closed organic shell per part, composed from its
// cage (warned about: it is rarely what was meant), not an empty composition.
TEST(Compose, DesignWithoutSolidsIsComposedFromItsCage) {
  const Scene s = grown_box_scene(0.1);
  Inputs inputs{{s.name, s.design}, {}};
  Options options;
  options.incidence.tolerance = s.h;
  const Result result = convert(inputs, options, Context());
  Converted r = from_result("no solids", result, result.design);
  expect_valid(r);
  ASSERT_EQ(result.composed.contacts.size(), 1u) << joined(result.composed.report.diagnostics);
  EXPECT_EQ(result.composed.contacts[0].surface, "closed shell");
  EXPECT_EQ(result.fitted.size(), 1u);
  EXPECT_EQ(exit_status(result), 0);
  bool warned = false;
  for (const auto& d : result.diagnostics) warned = warned || d.find("has no solids") != std::string::npos;
  EXPECT_TRUE(warned) << joined(result.diagnostics);
}

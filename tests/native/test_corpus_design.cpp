// The corpus generator: a pure function of its seed, and what it draws is valid input of
// the kinds it says it draws.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "corpus_design.h"
#include "mesh/mesh.h"
#include "solid_meshes.h"

using namespace genbrep;
using namespace genbrep::testing;

namespace {

// Volumes are measured about the mesh's own centre: a case moved 1e5 sizes from the origin
// would otherwise lose the volume's sign to rounding.
void expect_closed_outward(TriangleMesh mesh, const std::string& what) {
  mesh.vertices.rowwise() -= mesh.vertices.colwise().mean();
  const MeshValidation v = validate(mesh);
  EXPECT_EQ(v.boundary_edges, 0) << what;
  EXPECT_EQ(v.non_manifold_edges, 0) << what;
  EXPECT_EQ(v.non_manifold_vertices, 0) << what;
  EXPECT_EQ(v.inconsistent_edges, 0) << what;
  EXPECT_GT(v.signed_volume, 0) << what;
}

// Sum of the genera of a closed mesh's shells, from its Euler characteristic.
int total_genus(const TriangleMesh& mesh) {
  const MeshValidation v = validate(mesh);
  const long faces = mesh.triangles.rows(), edges = 3 * faces / 2;
  const long euler = mesh.vertices.rows() - edges + faces;
  return static_cast<int>((2 * v.shells - euler) / 2);
}

}  // namespace

TEST(SolidMeshes, TubesCylindersAndPlatesAreClosedAndOutward) {
  const Eigen::Matrix3d tilt = Eigen::AngleAxisd(0.3, Vec3(1, 2, 0).normalized()).toRotationMatrix();
  const TriangleMesh tube = tube_mesh(Vec3(1, 2, 3), Vec3(0.1, 0.2, 1), -2, 2, 1, 1.5, 48);
  expect_closed_outward(tube, "tube");
  const double expected = 3.14159265358979 * (1.5 * 1.5 - 1) * 4;
  EXPECT_NEAR(validate(tube).signed_volume, expected, 0.01 * expected);
  expect_closed_outward(tube_mesh(Vec3::Zero(), Vec3(1, 0, 0), 0, 3, 0, 2, 64), "cylinder");
  const TriangleMesh plate =
      plate_with_holes_mesh(Vec3::Zero(), Vec3(6, 3, 1), tilt, {{-3, 0, 1}, {3, 0.5, 1.2}}, 48);
  expect_closed_outward(plate, "plate");
  EXPECT_EQ(total_genus(plate), 2);
}

TEST(CorpusDesign, TheSameSeedGivesTheSameCase) {
  const GeneratedCase a = generate_case(17), b = generate_case(17), c = generate_case(18);
  EXPECT_EQ(a.meta_json, b.meta_json);
  ASSERT_EQ(a.design.vertices.rows(), b.design.vertices.rows());
  EXPECT_TRUE((a.design.vertices.array() == b.design.vertices.array()).all());
  EXPECT_TRUE((a.design.triangles.array() == b.design.triangles.array()).all());
  ASSERT_EQ(a.solids.size(), b.solids.size());
  for (size_t s = 0; s < a.solids.size(); ++s)
    EXPECT_TRUE((a.solids[s].mesh.vertices.array() == b.solids[s].mesh.vertices.array()).all());
  EXPECT_NE(a.meta_json, c.meta_json);
}

TEST(CorpusDesign, EverySeedGivesClosedOrientedDesignsAndSolids) {
  for (uint64_t seed = 1; seed <= 12; ++seed) {
    const GeneratedCase g = generate_case(seed);
    const std::string at = "seed " + std::to_string(seed);
    expect_closed_outward(g.design, at + " design");
    for (const auto& s : g.solids) expect_closed_outward(s.mesh, at + " " + s.file);
    const auto meta = nlohmann::json::parse(g.meta_json);
    EXPECT_GE(meta["keep_in"].size(), 1u) << at;
    EXPECT_GT(meta["tolerance"].get<double>(), 0) << at;
    EXPECT_GT(meta["voxel"].get<double>(), 0) << at;
  }
}

TEST(CorpusDesign, AVariationChangesOnlyWhatItSays) {
  const GeneratedCase base = generate_case(5, {"none", "smoothed", "no"});
  const GeneratedCase scaled = generate_case(5, {"scale", "smoothed", "no"});
  const GeneratedCase nudged = generate_case(5, {"nudge", "smoothed", "no"});
  const double factor = nlohmann::json::parse(scaled.meta_json)["drawn"]["scale"].get<double>();
  ASSERT_EQ(base.design.vertices.rows(), scaled.design.vertices.rows());
  EXPECT_LT((scaled.design.vertices - factor * base.design.vertices).cwiseAbs().maxCoeff(),
            1e-12 * factor * base.design.vertices.cwiseAbs().maxCoeff());
  EXPECT_TRUE((nudged.design.vertices.array() == base.design.vertices.array()).all());
  const Vec3 shift = (nudged.solids[0].mesh.vertices.row(0) - base.solids[0].mesh.vertices.row(0)).transpose();
  EXPECT_GT(shift.norm(), 0);
  EXPECT_LE(shift.norm(), 0.5 * nlohmann::json::parse(base.meta_json)["voxel"].get<double>() * (1 + 1e-9));
}

TEST(CorpusDesign, TheLatticeIsOneComponentOfHighGenus) {
  const GeneratedCase g = generate_case(3, {"none", "smoothed", "yes"});
  const auto lattice = nlohmann::json::parse(g.meta_json)["drawn"]["lattice"];
  const int genus = lattice["genus"].get<int>();
  EXPECT_GE(genus, 20);
  EXPECT_LE(genus, 100);
  // The lattice's tubes are thick enough to survive extraction: the design carries its genus.
  EXPECT_GE(total_genus(g.design), genus);
}

TEST(CorpusDesign, BossBoresMeetTheBossWallWithinAThousandthOfAVoxel) {
  int bosses = 0;
  for (uint64_t seed = 1; seed <= 30; ++seed) {
    const auto meta = nlohmann::json::parse(generate_case(seed, {"none", "smoothed", "no"}).meta_json);
    for (const auto& k : meta["drawn"]["keep_ins"]) {
      if (k["kind"] != "boss") continue;
      ++bosses;
      const double offset = std::abs(k["bore_offset_h"].get<double>());
      EXPECT_TRUE(offset == 0 || (offset >= 1e-9 && offset <= 1e-3)) << offset;
      const auto axis = k["axis"];
      EXPECT_LT(std::abs(axis[2].get<double>()), 1 - 1e-6) << "a boss axis is tilted";
    }
  }
  EXPECT_GT(bosses, 3);
}

// Tests for mesh/: file reading, triangulation, welding, validation and preparation.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "level_set.h"
#include "mesh/mesh.h"

using namespace genbrep;
using genbrep::testing::box_mesh;
using genbrep::testing::merge;

namespace {

std::string write_temp(const std::string& name, const std::string& text) {
  const auto path = std::filesystem::temp_directory_path() / ("genbrep_test_" + name);
  std::ofstream(path) << text;
  return path.string();
}

const char* kCubeObj =
    "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
    "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n";

}  // namespace

TEST(MeshIo, ReadsObjQuadsAndTriangulatesThem) {
  const TriangleMesh m = triangulate(read_polygon_file(write_temp("cube.obj", kCubeObj)), "cube");
  EXPECT_EQ(m.vertices.rows(), 8);
  EXPECT_EQ(m.triangles.rows(), 12);
  EXPECT_EQ(m.triangle_source[0], 0);
  EXPECT_EQ(m.triangle_source[11], 5);
  const MeshValidation v = validate(m);
  EXPECT_TRUE(v.closed_manifold()) << v.problems();
  EXPECT_NEAR(v.signed_volume, 1.0, 1e-12);
}

TEST(MeshIo, ReadsOffAndAsciiStlAndPly) {
  const std::string off = write_temp("tet.off",
                                     "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n"
                                     "3 0 2 1\n3 0 1 3\n3 1 2 3\n3 0 3 2\n");
  EXPECT_TRUE(validate(triangulate(read_polygon_file(off), "tet")).closed_manifold());
  std::string stl = "solid t\n";
  const double p[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  const int f[4][3] = {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {0, 3, 2}};
  for (const auto& t : f) {
    stl += "facet normal 0 0 0\nouter loop\n";
    for (int c : t) {
      stl += "vertex " + std::to_string(p[c][0]) + " " + std::to_string(p[c][1]) + " " +
             std::to_string(p[c][2]) + "\n";
    }
    stl += "endloop\nendfacet\n";
  }
  stl += "endsolid t\n";
  const TriangleMesh from_stl = weld(triangulate(read_polygon_file(write_temp("tet.stl", stl)), "tet"));
  EXPECT_EQ(from_stl.vertices.rows(), 4);
  EXPECT_TRUE(validate(from_stl).closed_manifold());
  const std::string ply = write_temp("tet.ply",
                                     "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\n"
                                     "property float y\nproperty float z\nelement face 4\n"
                                     "property list uchar int vertex_indices\nend_header\n"
                                     "0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 1 2 3\n3 0 3 2\n");
  EXPECT_EQ(triangulate(read_polygon_file(ply), "tet").triangles.rows(), 4);
}

TEST(MeshIo, TextCoordinatesAreReadAsDoubles) {
  // OpenMesh's readers hand coordinates on as floats; a solid written with 17 digits must
  // come back exactly (1/3 and 0.1 are not floats). Binary STL holds floats anyway.
  const double x = 1.0 / 3, y = 0.1, z = -1234.5678901234567;
  char v0[128];
  std::snprintf(v0, sizeof v0, "%.17g %.17g %.17g", x, y, z);
  const std::string p(v0);
  const std::string obj = write_temp("exact.obj", "# a comment\nv " + p + "\nvt 0.5 0.5\nv 1 0 0\n"
                                                  "vn 0 0 1\nv 0 1 0\nf 1/1 2/1 3/1\n");
  const std::string off = write_temp("exact.off", "OFF\n3 1 0\n" + p +
                                                      "\n1 0 0\n0 1 0\n3 0 1 2\n");
  const std::string ply = write_temp(
      "exact.ply",
      "ply\nformat ascii 1.0\ncomment written by a test\nelement vertex 3\nproperty double z\n"
      "property double x\nproperty double y\nelement face 1\n"
      "property list uchar int vertex_indices\nend_header\n" +
          [&] {
            char row[128];
            std::snprintf(row, sizeof row, "%.17g %.17g %.17g", z, x, y);
            return std::string(row);
          }() +
          "\n0 1 0\n0 0 1\n3 0 1 2\n");
  for (const std::string& path : {obj, off, ply}) {
    const PolygonSoup soup = read_polygon_file(path);
    ASSERT_EQ(soup.vertices.rows(), 3) << path;
    EXPECT_EQ(soup.vertices(0, 0), x) << path;
    EXPECT_EQ(soup.vertices(0, 1), y) << path;
    EXPECT_EQ(soup.vertices(0, 2), z) << path;
    EXPECT_EQ(soup.vertices(1, 0), 1.0) << path;
    EXPECT_EQ(soup.vertices(2, 1), 1.0) << path;
    EXPECT_EQ(soup.offsets.back(), 3) << path;
  }
}

// Comments in an OFF file (a line of its own after the header or the counts, or after a
// vertex) are not data: OpenMesh's reader took them for some and read a tetrahedron as
// "face 0 has 0 corners" or as unreadable coordinates.
TEST(MeshIo, OffCommentsAreNotData) {
  const std::string body = "0 0 0\n1 0 0 # the second\n0 1 0\n0 0 1\n"
                           "3 0 2 1\n3 0 1 3\n3 1 2 3\n# last face\n3 0 3 2\n";
  for (const std::string& text : {"OFF\n# a tetrahedron\n4 4 0\n" + body,
                                  "OFF # with a comment\n4 4 0\n# vertices\n" + body}) {
    const PolygonSoup soup = read_polygon_file(write_temp("commented.off", text));
    ASSERT_EQ(soup.vertices.rows(), 4) << text;
    ASSERT_EQ(soup.offsets.size(), 5u) << text;
    EXPECT_EQ(soup.offsets.back(), 12) << text;
    EXPECT_EQ(soup.vertices(1, 0), 1.0) << text;
    EXPECT_EQ(soup.vertices(3, 2), 1.0) << text;
    EXPECT_EQ(std::count(soup.indices.begin(), soup.indices.end(), -1), 0) << text;
    EXPECT_EQ(soup.indices[9], 0) << text;  // the last face, after its comment: 0 3 2
    EXPECT_EQ(soup.indices[10], 3) << text;
  }
}

TEST(MeshIo, MissingAndUnreadableFilesThrowFileError) {
  try {
    read_polygon_file("/nonexistent/genbrep/design.obj");
    FAIL() << "no error for a missing file";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), Code::FileError);
    EXPECT_NE(std::string(e.what()).find("design.obj"), std::string::npos);
  }
  EXPECT_THROW(read_polygon_file(write_temp("junk.xyz", "not a mesh")), Error);
}

TEST(MeshIo, KeepsNonManifoldFacesAsTheFileStatesThem) {
  // Three triangles on one edge: OpenMesh's own mesh would split the third off.
  const std::string obj = write_temp("fin.obj",
                                     "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\n"
                                     "f 1 2 3\nf 2 1 4\nf 1 2 5\n");
  const TriangleMesh m = triangulate(read_polygon_file(obj), "fin");
  EXPECT_EQ(m.vertices.rows(), 5);
  EXPECT_EQ(validate(m).non_manifold_edges, 1);
}

TEST(MeshTriangulate, RejectsOutOfRangeIndices) {
  PolygonSoup soup;
  soup.vertices = Vertices::Zero(3, 3);
  soup.indices = {0, 1, 7};
  soup.offsets = {0, 3};
  EXPECT_THROW(triangulate(soup, "bad"), Error);
}

TEST(MeshWeld, MergesExactDuplicatesAndKeepsOrder) {
  TriangleMesh box = box_mesh(Vec3(0, 0, 0), Vec3(1, 1, 1));
  // Unshare every corner: 36 vertices, as an STL file would hold them.
  TriangleMesh soup;
  soup.vertices.resize(3 * box.triangles.rows(), 3);
  soup.triangles.resize(box.triangles.rows(), 3);
  for (Eigen::Index t = 0; t < box.triangles.rows(); ++t)
    for (int c = 0; c < 3; ++c) {
      soup.vertices.row(3 * t + c) = box.vertices.row(box.triangles(t, c));
      soup.triangles(t, c) = static_cast<int>(3 * t + c);
    }
  EXPECT_EQ(validate(soup).boundary_edges, 36);
  const TriangleMesh welded = weld(soup);
  EXPECT_EQ(welded.vertices.rows(), 8);
  EXPECT_TRUE(validate(welded).closed_manifold());
  EXPECT_EQ(welded.vertices.row(0), soup.vertices.row(0));
}

TEST(MeshValidate, CountsEachProblem) {
  const TriangleMesh box = box_mesh(Vec3(0, 0, 0), Vec3(1, 1, 1));
  EXPECT_TRUE(validate(box).closed_manifold());
  EXPECT_EQ(validate(box).shells, 1);

  TriangleMesh open = box;
  open.triangles.conservativeResize(11, 3);
  EXPECT_EQ(validate(open).boundary_edges, 3);

  TriangleMesh flipped = box;
  std::swap(flipped.triangles(0, 1), flipped.triangles(0, 2));
  EXPECT_EQ(validate(flipped).inconsistent_edges, 3);

  TriangleMesh two = merge({box, box_mesh(Vec3(2, 0, 0), Vec3(3, 1, 1))});
  EXPECT_EQ(validate(two).shells, 2);
  EXPECT_TRUE(validate(two).closed_manifold());

  // Two boxes sharing only the corner (1,1,1): one non-manifold vertex once welded.
  TriangleMesh pinched = weld(merge({box, box_mesh(Vec3(1, 1, 1), Vec3(2, 2, 2))}));
  EXPECT_EQ(validate(pinched).non_manifold_vertices, 1);
  EXPECT_EQ(validate(pinched).non_manifold_edges, 0);

  TriangleMesh nan = box;
  nan.vertices(3, 1) = std::nan("");
  EXPECT_EQ(validate(nan).non_finite_vertices, 1);

  TriangleMesh repeated = box;
  repeated.triangles(0, 2) = repeated.triangles(0, 0);
  EXPECT_EQ(validate(repeated).repeated_index_triangles, 1);
}

TEST(MeshPrepare, ErrorsNameTheObjectAndTheProblem) {
  const TriangleMesh box = box_mesh(Vec3(0, 0, 0), Vec3(1, 1, 1));
  auto message = [](const TriangleMesh& m) {
    try {
      prepare_closed_mesh(m, "keep-in 'boss'", nullptr);
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), Code::InvalidInput);
      return std::string(e.what());
    }
    return std::string("no error");
  };
  TriangleMesh open = box;
  open.triangles.conservativeResize(10, 3);
  EXPECT_EQ(message(open),
            "keep-in 'boss' is open: 4 boundary edges (the surface is open; the first at (0, 0.5, 1))");
  EXPECT_EQ(message(TriangleMesh{}), "keep-in 'boss' is empty: it has no triangles");
  TriangleMesh nan = box;
  nan.vertices(2, 0) = std::nan("");
  EXPECT_NE(message(nan).find("1 vertex with NaN"), std::string::npos);
}

TEST(MeshPrepare, FlipsAnInsideOutSurfaceAndSaysSo) {
  TriangleMesh box = box_mesh(Vec3(0, 0, 0), Vec3(2, 1, 1));
  for (Eigen::Index t = 0; t < box.triangles.rows(); ++t) std::swap(box.triangles(t, 1), box.triangles(t, 2));
  Diagnostics notes;
  const TriangleMesh fixed = prepare_closed_mesh(box, "seed 's'", &notes);
  EXPECT_NEAR(validate(fixed).signed_volume, 2.0, 1e-12);
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_NE(notes[0].find("inside out"), std::string::npos);
}

TEST(MeshPrepare, KeepsTheOrientationOfASmallPartFarFromTheOrigin) {
  // 4 x 3 x 2 hundredths at (648, -679, 1430): summed about the origin, the volume's terms
  // are 1e9 times the part's and their rounding decides its sign.
  const Vec3 lo(648.3042692949556, -678.9031069998529, 1430.39051634928);
  const TriangleMesh box = box_mesh(lo, lo + Vec3(0.04, 0.03, 0.02), 24);
  Diagnostics notes;
  const TriangleMesh kept = prepare_closed_mesh(box, "design 'far'", &notes);
  EXPECT_TRUE(notes.empty()) << notes.front();
  EXPECT_EQ(kept.triangles, box.triangles);
  EXPECT_NEAR(validate(kept).signed_volume, 0.04 * 0.03 * 0.02, 1e-12);
}

TEST(MeshHalfedge, ConvertsWithSameIndices) {
  const TriangleMesh box = box_mesh(Vec3(0, 0, 0), Vec3(1, 1, 1), 3);
  const TriMesh mesh = to_trimesh(box);
  EXPECT_EQ(mesh.n_faces(), static_cast<size_t>(box.triangles.rows()));
  EXPECT_EQ(mesh.n_vertices(), static_cast<size_t>(box.vertices.rows()));
  // Euler characteristic of a sphere-like closed surface.
  EXPECT_EQ(static_cast<int>(mesh.n_vertices() - mesh.n_edges() + mesh.n_faces()), 2);
}

TEST(MeshPrepare, ReportsTheValidationOfWhatItReturns) {
  TriangleMesh box = box_mesh(Vec3(0, 0, 0), Vec3(2, 1, 1), 2);
  for (Eigen::Index t = 0; t < box.triangles.rows(); ++t) std::swap(box.triangles(t, 1), box.triangles(t, 2));
  MeshValidation reported;
  const TriangleMesh prepared = prepare_closed_mesh(box, "seed 's'", nullptr, &reported);
  const MeshValidation fresh = validate(prepared);
  EXPECT_EQ(reported.triangles, fresh.triangles);
  EXPECT_EQ(reported.shells, fresh.shells);
  EXPECT_EQ(reported.boundary_edges, fresh.boundary_edges);
  EXPECT_DOUBLE_EQ(reported.signed_volume, fresh.signed_volume);
  EXPECT_NEAR(reported.signed_volume, 2.0, 1e-12);
}

namespace {

// The message read_polygon_file throws for `text` written as `name`, or "no error".
std::string read_error(const std::string& name, const std::string& text) {
  try {
    read_polygon_file(write_temp(name, text));
  } catch (const Error& e) {
    EXPECT_EQ(e.stage(), "mesh");
    return e.what();
  }
  return "no error";
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

}  // namespace

// The first reading names what OpenMesh would skip or misread, with its line or number.
TEST(MeshFileCheck, NamesBrokenTextFilesWithTheirLine) {
  const std::string tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
  EXPECT_TRUE(contains(read_error("range.obj", tri + "f 1 2 7\n"),
                       "line 4: face 1 uses vertex 7 but the file has 3 vertices"));
  EXPECT_TRUE(contains(read_error("zero.obj", tri + "f 0 1 2\n"), "uses vertex 0; OBJ numbers"));
  EXPECT_TRUE(contains(read_error("back.obj", tri + "f -1 -2 -4\n"), "counts back past the first"));
  EXPECT_TRUE(contains(read_error("nan.obj", "v nan 0 0\n"), "line 1: vertex 1 has a NaN coordinate"));
  EXPECT_TRUE(contains(read_error("inf.obj", "v 0 1e999 0\n"), "an infinite coordinate ('1e999')"));
  EXPECT_TRUE(contains(read_error("huge.obj", "v 0 1e300 0\n"), "a coordinate of 1e+300, beyond"));
  EXPECT_TRUE(contains(read_error("short.obj", "v 0 1\n"), "has 2 coordinates; a vertex needs 3"));
  EXPECT_TRUE(contains(read_error("bin.obj", std::string("v 0 0 0\n\x01\x02", 10)), "byte 8 is 0x01"));
  EXPECT_TRUE(contains(read_error("empty.obj", ""), "is empty (0 bytes)"));
  EXPECT_TRUE(contains(read_error("head.off", "OFX\n"), "does not start with OFF"));
  EXPECT_TRUE(contains(read_error("cut.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n"), "the data ends after 2 vertices"));
  EXPECT_TRUE(contains(read_error("idx.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n"),
                       "face 0 uses vertex 3 but the file has 3 vertices"));
  EXPECT_TRUE(contains(read_error("head.ply", "plx\n"), "does not start with 'ply'"));
  EXPECT_TRUE(contains(read_error("nohead.ply", "ply\nformat ascii 1.0\n"), "has no end_header"));
}

TEST(MeshFileCheck, NamesTruncatedBinaryFiles) {
  std::string stl(80, ' ');
  const uint32_t count = 4;
  stl.append(reinterpret_cast<const char*>(&count), 4);
  stl.append(50 * 3 + 20, '\0');
  EXPECT_TRUE(contains(read_error("cut.stl", stl), "is truncated: it does not start with 'solid', and as "
                                                   "binary STL its header announces 4 triangles (284 bytes)"));
  const std::string ply = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
                          "property float y\nproperty float z\nend_header\n" + std::string(30, '\0');
  EXPECT_TRUE(contains(read_error("cut.ply", ply), "the data ends in vertex 2"));
  EXPECT_THROW(read_polygon_file(std::filesystem::temp_directory_path().string()), Error);
}

TEST(MeshPrepare, NamesDuplicatesIntersectionsAndFlatSurfaces) {
  auto message = [](const TriangleMesh& m) {
    try {
      prepare_closed_mesh(m, "design 'd'", nullptr);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const TriangleMesh box = box_mesh(Vec3(0, 0, 0), Vec3(1, 1, 1), 3);
  TriangleMesh twice = box;
  twice.triangles.conservativeResize(box.triangles.rows() + 1, 3);
  twice.triangles.row(box.triangles.rows()) = box.triangles.row(2);
  twice.triangle_source.clear();
  EXPECT_TRUE(contains(message(twice), "has 1 duplicate triangle (face " + std::to_string(box.triangles.rows()) +
                                           " has the corners of face 2"));
  const TriangleMesh overlapping = merge({box, box_mesh(Vec3(0.55, 0.55, 0.55), Vec3(2, 2, 2), 3)});
  EXPECT_TRUE(contains(message(overlapping), "has 2 shells that overlap:"));
  TriangleMesh huge = box;
  huge.vertices *= 1e13;
  EXPECT_TRUE(contains(message(huge), "coordinates beyond ±1e+12"));
  TriangleMesh flat = box;
  flat.vertices.col(2).setZero();
  EXPECT_NE(message(flat), "no error");
  EXPECT_EQ(self_intersections(box).pairs, 0);
}

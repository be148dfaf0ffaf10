// Tests for pipeline/ and the command line: stage order, report, outputs, errors.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "level_set.h"
#include "pipeline/pipeline.h"
#include "scenes.h"

using namespace genbrep;
using namespace genbrep::testing;
namespace fs = std::filesystem;

namespace {

Inputs inputs_of(const Scene& s) {
  Inputs in;
  in.design = {s.name, s.design};
  in.solids = s.solids;
  return in;
}

fs::path temp_dir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("genbrep_cli_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

struct CliRun {
  int exit_code;
  std::string err;
};

CliRun run_cli(const std::string& args, const fs::path& dir) {
  const fs::path err = dir / "stderr.txt";
  const std::string command = std::string(GENBREP_CLI) + " " + args + " > " + (dir / "stdout.txt").string() +
                              " 2> " + err.string();
  const int status = std::system(command.c_str());
  std::stringstream text;
  text << std::ifstream(err).rdbuf();
  return {WEXITSTATUS(status), text.str()};
}

// Writes the scene's design and solids as OBJ files; returns the CLI's input flags.
std::string write_scene(const Scene& s, const fs::path& dir) {
  std::string flags = "--design " + (dir / (s.name + ".obj")).string();
  write_obj((dir / (s.name + ".obj")).string(), s.design);
  for (const auto& solid : s.solids) {
    const fs::path path = dir / (solid.name + ".obj");
    write_obj(path.string(), solid.mesh);
    flags += std::string(solid.role == Role::KeepIn ? " --keep-in " : solid.role == Role::KeepOut ? " --keep-out " : " --seed ") + path.string();
  }
  return flags;
}

}  // namespace

TEST(Pipeline, TwoArchesGiveTwoComponentsAndFourLoops) {
  const Scene s = two_arches_scene(0.05);
  const Result r = convert(inputs_of(s), Options{}, Context());
  const auto report = nlohmann::json::parse(r.report_json);
  EXPECT_EQ(report["counts"]["organic_components"], 2);
  EXPECT_EQ(report["counts"]["boundary_loops"], 4);
  EXPECT_EQ(report["stages_run"], stage_names());
  // Each arch is an annulus (χ = 0): its field's indices sum to zero.
  ASSERT_EQ(report["field"]["components"].size(), 2u);
  for (const auto& c : report["field"]["components"]) EXPECT_EQ(c["index_sum_quarter_turns"], 0);
  EXPECT_TRUE(report["tolerance"]["derived"].get<bool>());
  EXPECT_EQ(report["counts"]["incident_triangles_per_solid"].size(), 4u);
  for (const auto& n : report["counts"]["incident_triangles_per_solid"]) EXPECT_GT(n.get<int>(), 100);
  EXPECT_EQ(report["counts"]["organic_triangles"].get<int>() + report["counts"]["incident_triangles"].get<int>(),
            report["counts"]["triangles"].get<int>());
  for (const auto& stage : stage_names()) EXPECT_TRUE(report["stages"].contains(stage)) << stage;
  // How the stages worked is in the notes; the warnings (diagnostics) hold only what falls
  // short of what was asked, so a clean run has none.
  const auto mentions = [](const nlohmann::json& lines, const std::string& text) {
    return std::count_if(lines.begin(), lines.end(), [&](const nlohmann::json& line) {
      return line.get<std::string>().find(text) != std::string::npos;
    });
  };
  EXPECT_EQ(mentions(report["notes"], "field: 2 components"), 1) << report["notes"];
  EXPECT_EQ(mentions(report["notes"], "corners squared"), 2) << report["notes"];
  EXPECT_EQ(mentions(report["diagnostics"], "field:"), 0) << report["diagnostics"];
  EXPECT_EQ(mentions(report["diagnostics"], "quad:"), 0) << report["diagnostics"];
  // Relax's repaired folds are notes too: this clean scene has no warning at all.
  EXPECT_EQ(mentions(report["notes"], "channel remesh: unfolded"), 1) << report["notes"];
  EXPECT_TRUE(report["diagnostics"].empty()) << report["diagnostics"];
}

// report.json says where each cage's irregular vertices that no field singularity explains
// are, and the quarter turns left at each: none on the two arches (every irregular vertex
// explained); a listed vertex (as the quad stage lists them) is written at its cage
// position.
TEST(Pipeline, TheReportSaysWhereTheIrregularVerticesOffSingularitiesAre) {
  const Scene s = two_arches_scene(0.05);
  Options options;
  options.until = "quad";
  Result r = convert(inputs_of(s), options, Context());
  const auto report = nlohmann::json::parse(r.report_json);
  ASSERT_EQ(report["cages"].size(), 2u);
  for (const auto& cage : report["cages"]) {
    EXPECT_EQ(cage["irregular_vertices_off_singularities"], 0);
    EXPECT_TRUE(cage["irregular_vertices_off_singularities_at"].empty());
  }
  ASSERT_EQ(r.quads.cages.size(), 2u);
  const int v = static_cast<int>(r.quads.cages[1].vertices.rows()) / 2;
  r.quads.stats[1].irregular_off_singularities = 1;
  r.quads.stats[1].off_singularities = {{v, 5, -1}};
  const auto listed = nlohmann::json::parse(make_report(inputs_of(s), options, r));
  const auto& at = listed["cages"][1]["irregular_vertices_off_singularities_at"];
  ASSERT_EQ(at.size(), 1u);
  EXPECT_EQ(at[0]["quarter_turns"], -1);
  EXPECT_EQ(at[0]["valence"], 5);
  for (int k = 0; k < 3; ++k)
    EXPECT_DOUBLE_EQ(at[0]["position"][k].get<double>(), r.quads.cages[1].vertices(v, k));
  EXPECT_TRUE(listed["cages"][0]["irregular_vertices_off_singularities_at"].empty());
}

TEST(Pipeline, SameInputGivesSameOutput) {
  const Scene s = bolt_hole_scene(0.06);
  const Result a = convert(inputs_of(s), Options{}, Context());
  const Result b = convert(inputs_of(s), Options{}, Context());
  EXPECT_EQ(a.partition.face_solid, b.partition.face_solid);
  EXPECT_EQ(a.partition.face_component, b.partition.face_component);
  ASSERT_EQ(a.partition.loops.size(), b.partition.loops.size());
  for (size_t i = 0; i < a.partition.loops.size(); ++i) EXPECT_EQ(a.partition.loops[i].vertices, b.partition.loops[i].vertices);
  // Down to the last coordinate and in the same order: the cages handed on and the
  // composed solid (whose corefinement orders its output by where its points were
  // allocated: compose sorts it). The third run tries its layout choices one at a time,
  // the others as many at once as the machine has threads (at most 4); no stage decides
  // anything by the clock.
  Options one_at_a_time;
  one_at_a_time.quad.parallel_choices = 1;
  const Result c = convert(inputs_of(s), one_at_a_time, Context());
  for (const Result* r : {&b, &c}) {
    const std::vector<QuadCage> cages_a = final_cages(a), cages_r = final_cages(*r);
    ASSERT_EQ(cages_a.size(), cages_r.size());
    ASSERT_FALSE(cages_a.empty());
    for (size_t i = 0; i < cages_a.size(); ++i) {
      EXPECT_EQ(cages_a[i].quads, cages_r[i].quads) << "cage " << i;
      EXPECT_EQ(cages_a[i].vertices, cages_r[i].vertices) << "cage " << i;
      EXPECT_EQ(cages_a[i].boundary_chains, cages_r[i].boundary_chains) << "cage " << i;
    }
    EXPECT_TRUE(a.composed.report.ok);
    EXPECT_EQ(a.composed.mesh.vertices, r->composed.mesh.vertices);
    EXPECT_EQ(a.composed.mesh.triangles, r->composed.mesh.triangles);
  }
}

TEST(Pipeline, UntilStopsAfterTheNamedStageAndRejectsUnknownStages) {
  const Scene s = grown_box_scene(0.1);
  Options options;
  options.until = "incidence";
  const Result r = convert(inputs_of(s), options, Context());
  EXPECT_EQ(r.stages_run, (std::vector<std::string>{"mesh", "incidence"}));
  EXPECT_TRUE(r.partition.face_solid.empty());
  options.until = "teleport";
  EXPECT_THROW(convert(inputs_of(s), options, Context()), Error);
}

TEST(Pipeline, ErrorsCarryTheStageName) {
  Scene s = grown_box_scene(0.1);
  s.solids[0].mesh.triangles.conservativeResize(11, 3);
  try {
    convert(inputs_of(s), Options{}, Context());
    FAIL() << "open keep-in accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.stage(), "mesh");
    EXPECT_EQ(std::string(e.what()),
              "keep-in 'base' is open: 3 boundary edges (the surface is open; the first at (-1, 0, 0))");
  }
}

TEST(Cli, ConvertsTwoArchesAndWritesReportAndPartition) {
  const fs::path dir = temp_dir("arches");
  const Scene s = two_arches_scene(0.06);
  const CliRun run = run_cli("convert " + write_scene(s, dir) + " --out " + (dir / "out").string(), dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  std::ifstream report_file(dir / "out" / "report.json");
  const auto report = nlohmann::json::parse(report_file);
  EXPECT_EQ(report["counts"]["organic_components"], 2);
  EXPECT_EQ(report["counts"]["boundary_loops"], 4);
  EXPECT_EQ(report["inputs"]["solids"].size(), 4u);
  // partition.ply: header plus binary body of the announced size.
  std::ifstream ply(dir / "out" / "partition.ply", std::ios::binary);
  std::string line, header;
  int vertices = 0, faces = 0;
  while (std::getline(ply, line) && line != "end_header") {
    std::sscanf(line.c_str(), "element vertex %d", &vertices);
    std::sscanf(line.c_str(), "element face %d", &faces);
  }
  EXPECT_EQ(faces, report["counts"]["triangles"].get<int>());
  const auto body = fs::file_size(dir / "out" / "partition.ply") - static_cast<size_t>(ply.tellg());
  EXPECT_EQ(body, static_cast<size_t>(vertices) * 24 + static_cast<size_t>(faces) * (1 + 12 + 8));
}

// Each of the report's warnings is one "genbrep: warning:" line on standard error; notes
// are not. The two arches with a keep-out far from the design warn (it touches no design
// vertex); the two arches alone, a clean run, print no warning.
TEST(Cli, WarningsGoToStandardErrorAndNotesDoNot) {
  const fs::path dir = temp_dir("warnings");
  const Scene arches = two_arches_scene(0.06);
  write_obj((dir / "far.obj").string(), box_mesh(Vec3(50, 50, 50), Vec3(51, 51, 51)));
  const CliRun run = run_cli("convert " + write_scene(arches, dir) + " --keep-out " +
                                 (dir / "far.obj").string() + " --until quad --out " +
                                 (dir / "out").string(),
                             dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto report = nlohmann::json::parse(std::ifstream(dir / "out" / "report.json"));
  ASSERT_FALSE(report["diagnostics"].empty());
  ASSERT_FALSE(report["notes"].empty());
  std::string expected;
  for (const auto& warning : report["diagnostics"])
    expected += "genbrep: warning: " + warning.get<std::string>() + "\n";
  EXPECT_EQ(run.err, expected);
  EXPECT_NE(run.err.find("'far' touches no design vertex"), std::string::npos) << run.err;
  const fs::path clean = temp_dir("no_warnings");
  const CliRun alone = run_cli("convert " + write_scene(arches, clean) + " --until quad --out " +
                                   (clean / "out").string(),
                               clean);
  ASSERT_EQ(alone.exit_code, 0) << alone.err;
  EXPECT_EQ(alone.err, "");
}

TEST(Cli, GridModeFromTheCommandLine) {
  const fs::path dir = temp_dir("grid");
  const Scene s = tube_scene(0.06);
  std::ostringstream grid;
  grid.precision(17);
  grid << s.grid_origin.x() << "," << s.grid_origin.y() << "," << s.grid_origin.z() << "," << s.h;
  const CliRun run = run_cli("convert " + write_scene(s, dir) + " --grid " + grid.str() + " --out " + (dir / "out").string(), dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  std::ifstream report_file(dir / "out" / "report.json");
  const auto report = nlohmann::json::parse(report_file);
  EXPECT_EQ(report["tolerance"]["mode"], "grid");
  EXPECT_EQ(report["counts"]["boundary_loops"], 2);
}

TEST(Cli, BadInputGivesOneClearLineAndNonZeroExit) {
  const fs::path dir = temp_dir("bad");
  const Scene s = grown_box_scene(0.1);
  write_obj((dir / "design.obj").string(), s.design);
  TriangleMesh open = s.solids[0].mesh;
  open.triangles.conservativeResize(10, 3);
  write_obj((dir / "boss.obj").string(), open);
  write_obj((dir / "base.obj").string(), s.solids[0].mesh);
  std::ofstream(dir / "empty.obj") << "# nothing\n";
  std::ofstream(dir / "nan.obj") << "v nan 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 1 4 3\n";
  const std::string design = " --design " + (dir / "design.obj").string();
  const std::string out = " --out " + (dir / "out").string();
  const struct {
    std::string args;
    std::string expected;
  } cases[] = {
      {"convert --design " + (dir / "missing.obj").string() + out, "missing.obj': no such file"},
      {"convert --design " + (dir / "empty.obj").string() + out, "design 'empty' is empty"},
      {"convert --design " + (dir / "nan.obj").string() + out, "nan.obj' line 1: vertex 1 has a NaN coordinate"},
      {"convert" + design + " --keep-in " + (dir / "boss.obj").string() + out,
       "keep-in 'boss' is open: 4 boundary edges"},
      {"convert" + design + " --keep-in " + (dir / "base.obj").string() + " --tolerance -1" + out,
       "tolerance must be positive"},
      {"convert" + design, "--out is required"},
  };
  for (const auto& c : cases) {
    const CliRun run = run_cli(c.args, dir);
    EXPECT_NE(run.exit_code, 0) << c.args;
    EXPECT_NE(run.exit_code, 4) << "internal error for " << c.args << ": " << run.err;
    EXPECT_NE(run.err.find(c.expected), std::string::npos) << run.err;
    EXPECT_EQ(run.err.rfind("genbrep: ", 0), 0u) << run.err;
  }
}

TEST(Cli, ComposeRecomposesFromTheCagesConvertWrote) {
  const fs::path dir = temp_dir("compose");
  const Scene s = tube_scene(0.06);
  const std::string scene = write_scene(s, dir);
  const CliRun converted = run_cli("convert " + scene + " --out " + (dir / "out").string(), dir);
  ASSERT_EQ(converted.exit_code, 0) << converted.err;
  ASSERT_TRUE(fs::exists(dir / "out" / "cage_000.obj"));
  const std::string solids = scene.substr(scene.find(" --", 1));  // the solid flags
  const CliRun composed = run_cli("compose --cages " + (dir / "out" / "cage_000.obj").string() + solids +
                                      " --out " + (dir / "again").string(), dir);
  ASSERT_EQ(composed.exit_code, 0) << composed.err;
  ASSERT_TRUE(fs::exists(dir / "again" / "composed.obj"));
  ASSERT_TRUE(fs::exists(dir / "again" / "composed.ply"));
  const auto first = nlohmann::json::parse(std::ifstream(dir / "out" / "report.json"));
  const auto second = nlohmann::json::parse(std::ifstream(dir / "again" / "report.json"));
  EXPECT_TRUE(second["composed"]["ok"].get<bool>()) << second["diagnostics"];
  EXPECT_EQ(second["composed"]["contacts"][0]["surface"], "cage");
  EXPECT_EQ(second["inputs"]["cages"][0]["name"], "cage_000");
  EXPECT_NEAR(second["composed"]["volume"].get<double>(), first["composed"]["volume"].get<double>(),
              1e-3 * first["composed"]["volume"].get<double>());
  // A cage that is not a quad mesh is named in one line.
  std::ofstream(dir / "tri.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
  const CliRun bad = run_cli("compose --cages " + (dir / "tri.obj").string() + solids + " --out " + (dir / "bad").string(), dir);
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.err.find("cage 'tri' is not a quad mesh: 1 face has 3 corners"), std::string::npos) << bad.err;
}

// Exit status 3: a solid was written, but a component fell back below its best tier. An
// organic dome across a keep-in and a keep-out 0.003 apart (§9.1's gap): its boundary
// cannot be pulled across the gap, so its part of the design solid composes it, and
// standard error says which component fell back and why, one line each.
TEST(Cli, FallbackWritesTheSolidAndExitsThree) {
  const Scene s = gap_dome_scene(0.05, 0.003);
  const fs::path dir = temp_dir("fallback");
  const CliRun run = run_cli("convert " + write_scene(s, dir) + " --tolerance 0.05 --out " + (dir / "out").string(), dir);
  const auto report = nlohmann::json::parse(std::ifstream(dir / "out" / "report.json"));
  const auto& composed = report["composed"];
  ASSERT_TRUE(composed["ok"].get<bool>()) << run.err;
  EXPECT_TRUE(fs::exists(dir / "out" / "composed.obj"));
  const auto& lines = composed["fallbacks"];
  ASSERT_FALSE(lines.empty()) << run.err;
  EXPECT_EQ(run.exit_code, 3) << run.err;
  for (const auto& line : lines)
    EXPECT_NE(run.err.find("genbrep: fallback: " + line.get<std::string>()), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("crosses a gap of 0.003 between keep-in 'boss' and keep-out 'bolt'"), std::string::npos)
      << run.err;
}

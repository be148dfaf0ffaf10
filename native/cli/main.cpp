// cli/main.cpp — `genbrep convert`: files in, report.json and partition.ply out;
// `genbrep compose`: edited cages and the solids in, the recomposed solid out.
// Thin: parses arguments, reads files, calls pipeline::convert, writes outputs. Bad input
// exits non-zero with one line naming the file and the problem; it never crashes.
// Exit status: 0 made as asked; 3 a solid was written but some component fell back to a
// lower tier (one "genbrep: fallback: …" line each on standard error); 1 nothing could be
// written (bad input, or no valid solid); 2 usage; 4 internal error (a bug: report it).
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "pipeline/output.h"
#include "pipeline/pipeline.h"

namespace fs = std::filesystem;
using namespace genbrep;

namespace {

const char* kUsage =
    "usage: genbrep convert --design FILE [--keep-in FILE]... [--keep-out FILE]...\n"
    "                       [--seed FILE]... [--tolerance D | --grid OX,OY,OZ,H]\n"
    "                       [--until STAGE] [--target-edge-length L] [--density S]\n"
    "                       [--fitting smooth|tight|boundary_tight] [--field-obj] --out DIR\n"
    "       genbrep compose --cages FILE [--cages FILE]... [--keep-in FILE]...\n"
    "                       [--keep-out FILE]... [--seed FILE]... --out DIR\n"
    "       genbrep --version\n"
    "Reads OBJ, PLY, STL or OFF. Writes DIR/report.json, DIR/partition.ply, DIR/relaxed.ply\n"
    "(the design after boundary relaxation, same face properties) and, with\n"
    "--field-obj, DIR/field.obj (a cross per organic triangle, singularities as points).\n"
    "compose: quad cages (e.g. cage_000.obj from convert, edited) are pulled into the\n"
    "solids their boundary loops lie on and composed: DIR/composed.obj, composed.ply,\n"
    "report.json.\n"
    "Exit status: 0 everything made as asked; 3 a solid was written but some component\n"
    "fell back to a lower tier (listed on standard error); 1 nothing could be written;\n"
    "2 usage error; 4 internal error.\n";

struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

TriangleMesh read_mesh(const std::string& path) {
  return triangulate(read_polygon_file(path), "'" + path + "'");
}

// --keep-in, --keep-out and --seed name a solid file of that role.
bool solid_flag(const std::string& flag, Role* role) {
  if (flag == "--keep-in") *role = Role::KeepIn;
  else if (flag == "--keep-out") *role = Role::KeepOut;
  else if (flag == "--seed") *role = Role::Seed;
  else return false;
  return true;
}

// A solid named after its file's stem, as messages and the report name it.
SolidInput read_solid(const std::string& path, Role role) {
  return {fs::path(path).stem().string(), role, read_mesh(path)};
}

double parse_number(const std::string& text, const std::string& flag) {
  try {
    size_t used = 0;
    const double value = std::stod(text, &used);
    if (used == text.size()) return value;
  } catch (const std::exception&) {
  }
  throw UsageError(flag + " expects a number, got '" + text + "'");
}

struct Command {
  Inputs inputs;
  Options options;
  fs::path out;
  bool field_obj = false;
};

Command parse(int argc, char** argv) {
  Command cmd;
  bool have_design = false, have_tolerance = false, have_grid = false;
  for (int i = 2; i < argc; ++i) {
    const std::string flag = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw UsageError(flag + " needs a value");
      return argv[++i];
    };
    if (flag == "--design") {
      const std::string path = value();
      cmd.inputs.design = {fs::path(path).stem().string(), read_mesh(path)};
      have_design = true;
    } else if (Role role; solid_flag(flag, &role)) {
      cmd.inputs.solids.push_back(read_solid(value(), role));
    } else if (flag == "--tolerance") {
      cmd.options.incidence.tolerance = parse_number(value(), flag);
      have_tolerance = true;
    } else if (flag == "--grid") {
      std::stringstream parts(value());
      std::string part;
      std::vector<double> numbers;
      while (std::getline(parts, part, ',')) numbers.push_back(parse_number(part, flag));
      if (numbers.size() != 4) throw UsageError("--grid expects OX,OY,OZ,H");
      cmd.options.incidence.mode = IncidenceOptions::Mode::Grid;
      cmd.options.incidence.grid_origin = Vec3(numbers[0], numbers[1], numbers[2]);
      cmd.options.incidence.grid_h = numbers[3];
      have_grid = true;
    } else if (flag == "--target-edge-length") {
      cmd.options.field.target_edge_length = parse_number(value(), flag);
    } else if (flag == "--density") {
      cmd.options.field.density = parse_number(value(), flag);
    } else if (flag == "--fitting") {
      if (!parse_strategy(value(), &cmd.options.fit.strategy)) {
        throw UsageError("--fitting expects smooth, tight or boundary_tight");
      }
    } else if (flag == "--field-obj") {
      cmd.field_obj = true;
    } else if (flag == "--until") {
      cmd.options.until = value();
    } else if (flag == "--out") {
      cmd.out = value();
    } else {
      throw UsageError("unknown option '" + flag + "'");
    }
  }
  if (!have_design) throw UsageError("--design is required");
  if (cmd.out.empty()) throw UsageError("--out is required");
  if (have_tolerance && have_grid) throw UsageError("give --tolerance or --grid, not both");
  return cmd;
}

// The report's warnings ('diagnostics'), one line each on standard error, so a batch run
// shows them without opening report.json; its notes (how the stages worked) stay there.
void print_warnings(const std::string& report_json) {
  const auto report = nlohmann::json::parse(report_json);
  for (const auto& warning : report.value("diagnostics", nlohmann::json::array()))
    std::cerr << "genbrep: warning: " << warning.get<std::string>() << '\n';
}

// Exit 1 without a solid: one error line with compose's last word on why.
void print_not_composed(const Result& result) {
  const auto& diagnostics = result.composed.report.diagnostics;
  std::cerr << "genbrep: error in compose: no valid solid could be composed"
            << (diagnostics.empty() ? std::string() : ": " + diagnostics.back()) << '\n';
}

int run_convert(int argc, char** argv) {
  Command cmd = parse(argc, argv);
  const Result result = convert(cmd.inputs, cmd.options, Context());
  std::error_code ec;
  fs::create_directories(cmd.out, ec);
  if (ec) throw Error(Code::FileError, "cannot create '" + cmd.out.string() + "': " + ec.message());
  write_text_file((cmd.out / "report.json").string(), result.report_json);
  print_warnings(result.report_json);
  std::cout << "wrote " << (cmd.out / "report.json").string();
  if (ran(result, "partition")) {
    write_partition_ply((cmd.out / "partition.ply").string(), result.design, result.partition);
    std::cout << " and " << (cmd.out / "partition.ply").string() << " ("
              << result.partition.organic_components << " organic components, "
              << result.partition.loops.size() << " boundary loops)";
  }
  std::cout << '\n';
  if (ran(result, "relax")) {
    write_partition_ply((cmd.out / "relaxed.ply").string(), result.relaxed.design, result.relaxed.partition);
    std::cout << "wrote " << (cmd.out / "relaxed.ply").string() << '\n';
  }
  for (const QuadCage& cage : final_cages(result)) {
    char name[32];
    std::snprintf(name, sizeof(name), "cage_%03d.obj", cage.component);
    write_cage_obj((cmd.out / name).string(), cage);
    std::cout << "wrote " << (cmd.out / name).string() << " (" << cage.quads.rows() << " quads)\n";
  }
  if (ran(result, "compose")) {
    if (result.composed.report.ok) {
      write_composed((cmd.out / "composed.obj").string(), (cmd.out / "composed.ply").string(), result.composed.mesh);
      std::cout << "wrote " << (cmd.out / "composed.obj").string() << " and composed.ply ("
                << result.composed.mesh.triangles.rows() << " triangles, closed and 2-manifold)\n";
    } else {
      std::cout << "not composed: see the diagnostics in report.json\n";
      print_not_composed(result);
    }
    for (const auto& line : fallbacks(result.composed)) std::cerr << "genbrep: fallback: " << line << '\n';
  }
  if (cmd.field_obj) {
    if (!ran(result, "field")) throw UsageError("--field-obj needs the field stage (check --until)");
    write_field_obj((cmd.out / "field.obj").string(), to_trimesh(result.relaxed.design), result.field);
    std::cout << "wrote " << (cmd.out / "field.obj").string() << " (" << result.field.singularities.size()
              << " singularities)\n";
  }
  return exit_status(result);
}

// genbrep compose: recompose(solids, cages) from files; cage names are the file stems.
int run_compose(int argc, char** argv) {
  std::vector<SolidInput> solids;
  std::vector<QuadCage> cages;
  std::vector<std::string> names;
  fs::path out;
  for (int i = 2; i < argc; ++i) {
    const std::string flag = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw UsageError(flag + " needs a value");
      return argv[++i];
    };
    if (flag == "--cages") {
      const std::string path = value();
      names.push_back(fs::path(path).stem().string());
      cages.push_back(cage_from_polygons(read_polygon_file(path), names.back()));
    } else if (Role role; solid_flag(flag, &role)) {
      solids.push_back(read_solid(value(), role));
    } else if (flag == "--out") {
      out = value();
    } else {
      throw UsageError("unknown option '" + flag + "' for compose");
    }
  }
  if (cages.empty()) throw UsageError("compose needs at least one --cages FILE");
  if (solids.empty()) throw UsageError("compose needs the solids (--keep-in, --keep-out, --seed)");
  if (out.empty()) throw UsageError("--out is required");
  const Result result = recompose(solids, cages, Options{}, Context(), names);
  std::error_code ec;
  fs::create_directories(out, ec);
  if (ec) throw Error(Code::FileError, "cannot create '" + out.string() + "': " + ec.message());
  write_text_file((out / "report.json").string(), result.report_json);
  print_warnings(result.report_json);
  std::cout << "wrote " << (out / "report.json").string() << '\n';
  if (!result.composed.report.ok) {
    std::cout << "not composed: see the diagnostics in report.json\n";
    print_not_composed(result);
    return 1;
  }
  write_composed((out / "composed.obj").string(), (out / "composed.ply").string(), result.composed.mesh);
  std::cout << "wrote " << (out / "composed.obj").string() << " and composed.ply ("
            << result.composed.mesh.triangles.rows() << " triangles, closed and 2-manifold)\n";
  for (const auto& line : fallbacks(result.composed)) std::cerr << "genbrep: fallback: " << line << '\n';
  return exit_status(result);
}

}  // namespace

int main(int argc, char** argv) {
  const std::string command = argc > 1 ? argv[1] : "";
  try {
    if (command == "--version") {
      std::cout << "genbrep " << kVersion << '\n';
      return 0;
    }
    if (command == "--help" || command == "-h") {
      std::cout << kUsage;
      return 0;
    }
    if (command == "convert") return run_convert(argc, argv);
    if (command == "compose") return run_compose(argc, argv);
    throw UsageError(command.empty() ? "no command given" : "unknown command '" + command + "'");
  } catch (const UsageError& e) {
    std::cerr << "genbrep: " << e.what() << '\n' << kUsage;
    return 2;
  } catch (const Error& e) {
    std::cerr << "genbrep: error" << (e.stage().empty() ? "" : " in " + e.stage()) << ": "
              << e.what() << '\n';
    return e.code() == Code::Internal ? 4 : 1;
  } catch (const std::exception& e) {
    std::cerr << "genbrep: internal error: " << e.what() << '\n';
    return 4;
  }
}

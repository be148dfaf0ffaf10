// tests/support/fixtures.cpp — see fixtures.h.
#include "fixtures.h"

#include <algorithm>
#include <filesystem>

#include "mesh/mesh.h"

namespace genbrep::testing {

FixtureFiles load_fixture(const std::string& name) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::path(__FILE__).parent_path() / "../../blend_fixtures/obj" / name;
  auto load = [&](const fs::path& file) {
    return triangulate(read_polygon_file(file.string()), file.stem().string());
  };
  FixtureFiles out;
  std::vector<fs::path> files(fs::directory_iterator(dir), fs::directory_iterator{});
  std::sort(files.begin(), files.end());
  for (const auto& file : files) {
    const std::string stem = file.stem().string();
    for (const auto& [suffix, role] :
         {std::pair{"_keep_in", Role::KeepIn}, {"_keep_out", Role::KeepOut}, {"_seed", Role::Seed}}) {
      const std::string tail(suffix);
      if (stem.size() > tail.size() &&
          stem.compare(stem.size() - tail.size(), tail.size(), tail) == 0) {
        out.solids.push_back({stem.substr(0, stem.size() - tail.size()), role, load(file)});
      }
    }
  }
  out.design = load(dir / "design_design.obj");
  return out;
}

}  // namespace genbrep::testing

// make_scenes DIR [h] [net N | gap G] — writes the analytic level-set scenes of scenes.h
// (or only the net of N × N cells, or only the gap dome with gap G) as OBJ files,
// DIR/<scene>/design.obj and DIR/<scene>/<solid>_<role>.obj, plus DIR/<scene>/grid.txt
// ("ox oy oz h") and expected.txt ("components loops"). Used by the Python tests.
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <string>
#include <vector>

#include "level_set.h"
#include "scenes.h"

using namespace genbrep;
using namespace genbrep::testing;

int main(int argc, char** argv) {
  if (argc < 2) {
    std::cerr << "usage: make_scenes DIR [h]\n";
    return 2;
  }
  const double h = argc > 2 ? std::stod(argv[2]) : 0.06;
  std::vector<Scene> scenes;
  if (argc > 4 && std::string(argv[3]) == "net") {
    scenes.push_back(net_scene(h, std::stoi(argv[4])));
  } else if (argc > 4 && std::string(argv[3]) == "gap") {
    scenes.push_back(gap_dome_scene(h, std::stod(argv[4])));
  } else {
    for (Scene s : {grown_box_scene(h), tube_scene(h), two_arches_scene(h), eroded_seed_scene(h),
                    bolt_hole_scene(h)})
      scenes.push_back(std::move(s));
  }
  for (const Scene& s : scenes) {
    const auto dir = std::filesystem::path(argv[1]) / s.name;
    std::filesystem::create_directories(dir);
    write_obj((dir / "design.obj").string(), s.design);
    for (const auto& solid : s.solids) {
      write_obj((dir / (solid.name + "_" + role_name(solid.role) + ".obj")).string(), solid.mesh);
    }
    std::ofstream(dir / "grid.txt") << std::setprecision(17) << s.grid_origin.x() << ' ' << s.grid_origin.y()
                                    << ' ' << s.grid_origin.z() << ' ' << s.h << '\n';
    std::ofstream(dir / "expected.txt") << s.expected_components << ' ' << s.expected_loops << '\n';
  }
  return 0;
}

// tests/support/fixtures.h — the Blender fixtures' OBJ exports (blend_fixtures/obj/<name>/),
// roles from the file names (<solid>_keep_in.obj, _keep_out, _seed; design_design.obj).
#pragma once
#include <string>
#include <vector>

#include "core/types.h"

namespace genbrep::testing {

struct FixtureFiles {
  TriangleMesh design;
  std::vector<SolidInput> solids;  // sorted by file name
};

FixtureFiles load_fixture(const std::string& name);

}  // namespace genbrep::testing

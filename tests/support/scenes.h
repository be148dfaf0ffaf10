// tests/support/scenes.h — level-set designs with exact input solids whose partition is
// known in advance. Each design is extracted on a grid of spacing h from origin
// `grid_origin`, as a level-set solver would output it.
#pragma once
#include <string>
#include <vector>

#include "core/types.h"

namespace genbrep::testing {

struct Scene {
  std::string name;
  TriangleMesh design;
  std::vector<SolidInput> solids;
  Vec3 grid_origin;
  double h = 0;
  int expected_components = 0;
  int expected_loops = 0;
};

// Organic blob grown on the top face of one keep-in box: 1 component, 1 loop.
Scene grown_box_scene(double h);
// A tube joining two keep-in boxes: 1 component, 2 loops.
Scene tube_scene(double h);
// Two disjoint arches, each joining two keep-in boxes: 2 components, 4 loops.
Scene two_arches_scene(double h);
// A seed box with a spherical bite eroded from one corner: 1 component, 1 loop.
Scene eroded_seed_scene(double h);
// §9.1's gap: a keep-in box 'boss' and a keep-out box 'bolt' `gap` apart along x, an
// organic dome across both (cut where it enters the bolt): 1 component, 1 loop that
// borders both; its boundary cannot be pulled across the gap.
Scene gap_dome_scene(double h, double gap);
// A keep-in boss with organic material and a keep-out bolt hole through both.
Scene bolt_hole_scene(double h);
// A row of n arches joining n + 1 keep-in boxes at their feet (size scales with n).
Scene arch_row_scene(double h, int n);
// A flat net of n × n square cells (capsule struts of radius 0.2 along x and y, 1 apart)
// whose n + 1 x-struts run into a keep-in bar at each end: 1 component of genus n², with
// 2(n + 1) loops (a generative lattice of high genus).
Scene net_scene(double h, int n);
// The analytic scenes by number, for parameterised tests: 0 grown_box, 1 tube,
// 2 two_arches, 3 eroded_seed, 4 bolt_hole, 5 (or more) arch_row of 3.
Scene analytic_scene(int which, double h);

}  // namespace genbrep::testing

#include "scenes.h"

#include <algorithm>

#include "level_set.h"

namespace genbrep::testing {
namespace {

// Grid covering [lo, hi] with spacing h, origin offset so no solid face sits on a grid
// plane by accident (a solver's grid knows nothing of the solids).
Scene extract(const std::string& name, const Field& f, const Vec3& lo, const Vec3& hi, double h) {
  Scene s;
  s.name = name;
  s.h = h;
  s.grid_origin = lo - Vec3(0.37 * h, 0.29 * h, 0.41 * h);
  const Vec3 size = (hi - s.grid_origin) / h;
  const Eigen::Vector3i cells(static_cast<int>(std::ceil(size.x())) + 1,
                              static_cast<int>(std::ceil(size.y())) + 1,
                              static_cast<int>(std::ceil(size.z())) + 1);
  s.design = extract_level_set(f, s.grid_origin, h, cells);
  return s;
}

SolidInput solid(const std::string& name, Role role, TriangleMesh mesh) {
  return SolidInput{name, role, std::move(mesh)};
}

}  // namespace

Scene grown_box_scene(double h) {
  const Vec3 lo(-1, -1, -1), hi(1, 1, 0);
  const Vec3 center(0, 0, 0.3);
  auto f = [&](const Vec3& p) { return std::min(box_sdf(p, lo, hi), sphere_sdf(p, center, 0.6)); };
  Scene s = extract("grown_box", f, Vec3(-1.3, -1.3, -1.3), Vec3(1.3, 1.3, 1.2), h);
  s.solids.push_back(solid("base", Role::KeepIn, box_mesh(lo, hi)));
  s.expected_components = 1;
  s.expected_loops = 1;
  return s;
}

Scene tube_scene(double h) {
  const Vec3 lo0(-2, -0.5, -0.5), hi0(-1, 0.5, 0.5), lo1(1, -0.5, -0.5), hi1(2, 0.5, 0.5);
  auto f = [&](const Vec3& p) {
    return std::min({box_sdf(p, lo0, hi0), box_sdf(p, lo1, hi1),
                     capsule_sdf(p, Vec3(-1.3, 0, 0), Vec3(1.3, 0, 0), 0.25)});
  };
  Scene s = extract("tube", f, Vec3(-2.3, -0.8, -0.8), Vec3(2.3, 0.8, 0.8), h);
  s.solids.push_back(solid("left", Role::KeepIn, box_mesh(lo0, hi0)));
  s.solids.push_back(solid("right", Role::KeepIn, box_mesh(lo1, hi1)));
  s.expected_components = 1;
  s.expected_loops = 2;
  return s;
}

Scene arch_row_scene(double h, int n) {
  // Feet 4 apart and 2 wide; arches of radius 1.45 land 1.1 apart on a shared foot, so
  // neighbouring arches stay separate organic components.
  const double spacing = 4.0, radius = 1.45;
  std::vector<std::pair<Vec3, Vec3>> boxes;
  for (int i = 0; i <= n; ++i) {
    const double x = i * spacing;
    boxes.push_back({Vec3(x - 1.0, -0.6, -1.0), Vec3(x + 1.0, 0.6, 0.3)});
  }
  auto f = [boxes, n, spacing, radius](const Vec3& p) {
    double d = 1e9;
    for (const auto& b : boxes) d = std::min(d, box_sdf(p, b.first, b.second));
    for (int i = 0; i < n; ++i) d = std::min(d, arch_sdf(p, Vec3((i + 0.5) * spacing, 0, 0), radius, 0.35));
    return d;
  };
  Scene s = extract("arch_row", f, Vec3(-1.3, -0.9, -1.3), Vec3(n * spacing + 1.3, 0.9, 2.2), h);
  for (int i = 0; i <= n; ++i) {
    s.solids.push_back(solid("foot" + std::to_string(i), Role::KeepIn, box_mesh(boxes[i].first, boxes[i].second)));
  }
  s.expected_components = n;
  s.expected_loops = 2 * n;
  return s;
}

Scene net_scene(double h, int n) {
  const double radius = 0.2, reach = 0.9;  // x-struts run `reach` past the outer y-struts
  const Vec3 lo0(-reach - 0.5, -0.5, -0.5), hi0(-reach + 0.3, n + 0.5, 0.5);
  const Vec3 lo1(n + reach - 0.3, -0.5, -0.5), hi1(n + reach + 0.5, n + 0.5, 0.5);
  auto f = [=](const Vec3& p) {
    double d = std::min(box_sdf(p, lo0, hi0), box_sdf(p, lo1, hi1));
    for (int i = 0; i <= n; ++i) {
      d = std::min(d, capsule_sdf(p, Vec3(-reach, i, 0), Vec3(n + reach, i, 0), radius));
      d = std::min(d, capsule_sdf(p, Vec3(i, 0, 0), Vec3(i, n, 0), radius));
    }
    return d;
  };
  Scene s = extract("net", f, lo0 - Vec3(0.3, 0.3, 0.3), hi1 + Vec3(0.3, 0.3, 0.3), h);
  s.solids.push_back(solid("left", Role::KeepIn, box_mesh(lo0, hi0)));
  s.solids.push_back(solid("right", Role::KeepIn, box_mesh(lo1, hi1)));
  s.expected_components = 1;
  s.expected_loops = 2 * (n + 1);
  return s;
}

Scene two_arches_scene(double h) {
  std::vector<std::pair<Vec3, Vec3>> boxes;
  for (double y : {-1.5, 1.5})
    for (double x : {-2.0, 2.0}) boxes.push_back({Vec3(x - 0.6, y - 0.6, -1.0), Vec3(x + 0.6, y + 0.6, 0.3)});
  auto f = [&](const Vec3& p) {
    double d = 1e9;
    for (const auto& b : boxes) d = std::min(d, box_sdf(p, b.first, b.second));
    for (double y : {-1.5, 1.5}) d = std::min(d, arch_sdf(p, Vec3(0, y, 0), 2.0, 0.35));
    return d;
  };
  Scene s = extract("two_arches", f, Vec3(-2.9, -2.4, -1.3), Vec3(2.9, 2.4, 2.7), h);
  for (size_t i = 0; i < boxes.size(); ++i) {
    s.solids.push_back(solid("foot" + std::to_string(i), Role::KeepIn, box_mesh(boxes[i].first, boxes[i].second)));
  }
  s.expected_components = 2;
  s.expected_loops = 4;
  return s;
}

Scene eroded_seed_scene(double h) {
  const Vec3 lo(-1, -1, -1), hi(1, 1, 1);
  auto f = [&](const Vec3& p) { return std::max(box_sdf(p, lo, hi), -sphere_sdf(p, hi, 0.9)); };
  Scene s = extract("eroded_seed", f, Vec3(-1.3, -1.3, -1.3), Vec3(1.3, 1.3, 1.3), h);
  s.solids.push_back(solid("stock", Role::Seed, box_mesh(lo, hi)));
  s.expected_components = 1;
  s.expected_loops = 1;
  return s;
}

Scene gap_dome_scene(double h, double gap) {
  const Vec3 k_lo(-1, -0.6, -0.5), k_hi(0, 0.6, 0.5), l_lo(gap, -0.6, -0.5), l_hi(1, 0.6, 0.5);
  auto f = [&](const Vec3& p) {
    return std::max(std::min(box_sdf(p, k_lo, k_hi), sphere_sdf(p, Vec3(0, 0, 0.5), 0.45)), -box_sdf(p, l_lo, l_hi));
  };
  Scene s = extract("gap_dome", f, Vec3(-1.3, -0.9, -0.8), Vec3(1.1, 0.9, 1.1), h);
  s.solids.push_back(solid("boss", Role::KeepIn, box_mesh(k_lo, k_hi)));
  s.solids.push_back(solid("bolt", Role::KeepOut, box_mesh(l_lo, l_hi)));
  s.expected_components = 1;
  s.expected_loops = 1;
  return s;
}

Scene bolt_hole_scene(double h) {
  const Vec3 lo(-1, -1, -0.5), hi(1, 1, 0.5);
  const Vec3 axis_base(0, 0, -1.0);
  const double radius = 0.35;
  auto hole = [&](const Vec3& p) {  // infinite-enough cylinder along z, inside [-1, 1.5]
    const double radial = std::hypot(p.x(), p.y()) - radius;
    const double axial = std::max(axis_base.z() - p.z(), p.z() - 1.5);
    return std::max(radial, axial);
  };
  auto f = [&](const Vec3& p) {
    const double material = std::min(box_sdf(p, lo, hi), capsule_sdf(p, Vec3(0.9, 0, 0), Vec3(2.2, 0, 0), 0.3));
    return std::max(material, -hole(p));
  };
  Scene s = extract("bolt_hole", f, Vec3(-1.3, -1.3, -0.8), Vec3(2.6, 1.3, 0.8), h);
  s.solids.push_back(solid("boss", Role::KeepIn, box_mesh(lo, hi)));
  s.solids.push_back(solid("bolt", Role::KeepOut, cylinder_mesh(axis_base, radius, 2.5, 48)));
  s.expected_components = 1;
  s.expected_loops = 1;
  return s;
}

Scene analytic_scene(int which, double h) {
  return which == 0   ? grown_box_scene(h)
         : which == 1 ? tube_scene(h)
         : which == 2 ? two_arches_scene(h)
         : which == 3 ? eroded_seed_scene(h)
         : which == 4 ? bolt_hole_scene(h)
                      : arch_row_scene(h, 3);
}

}  // namespace genbrep::testing

// core/numbers.h — small helpers every stage writes the same way: π, a point of any 3-vector
// type as a Vec3, and a number as text for messages.
#pragma once
#include <cstdio>
#include <string>

#include "core/types.h"

namespace genbrep {

constexpr double kPi = 3.14159265358979323846;

// Any point type with p[0], p[1], p[2] (OpenMesh::Vec3d, CGAL's inexact Point_3) as a Vec3.
template <class Point>
Vec3 to_vec(const Point& p) {
  return Vec3(p[0], p[1], p[2]);
}

// `x` with `digits` significant digits (printf's %g), for messages and reports.
inline std::string format_number(double x, int digits = 3) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.*g", digits, x);
  return buffer;
}

}  // namespace genbrep

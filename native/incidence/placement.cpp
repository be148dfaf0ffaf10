// incidence/placement.cpp — solids placed against their roles (DESIGN.md, "The job"):
// a keep-in the design does not contain, material inside a keep-out, a keep-in inside a
// keep-out, a keep-in nowhere near the design. Depths count only beyond
// kClearly · d: within that the solver's resolution explains them, and incidence notes
// the deeper-than-d ones as warnings.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "incidence/incidence.h"
#include "mesh/mesh.h"

namespace genbrep {
namespace {

// Depths beyond 3d are not the solver's rounding (δ = 3h bounds the §6.3 fit the same way).
constexpr double kClearly = 3.0;

std::string length(double x) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3g", x);
  return text;
}

struct Intrusion {
  int count = 0;
  double deepest = 0;
  Vec3 first = Vec3::Zero();
  void add(const Vec3& p, double depth) {
    if (count++ == 0) first = p;
    deepest = std::max(deepest, depth);
  }
  // "12 design vertices lie up to 0.5 deep inside it (the first at (0, 1, 2))".
  std::string text(const std::string& points, const std::string& container) const {
    return std::to_string(count) + " " + points + (count == 1 ? " lies" : " lie") + " up to " + length(deepest) +
           " deep inside " + container + " (" +
           (count == 1 ? "at " : "the first at ") + position(first) + ")";
  }
};

// How deep p lies inside s beyond `depth`, or 0.
double depth_beyond(const ClosedSurface& s, const Vec3& p, double depth) {
  if ((p.array() < s.min_corner().array()).any() || (p.array() > s.max_corner().array()).any()) return 0;
  const double dist = s.distance(p);
  return dist > depth && s.inside(p) ? dist : 0;
}

// Whether p lies inside a keep-out or within `margin` of one: a keep-out cutting through a
// keep-in (a bolt bore through a boss) wins there, so the design's surface may run there.
bool at_keep_out(const SolidSet& solids, const Vec3& p, double margin) {
  for (int k = 0; k < solids.size(); ++k) {
    if (solids.input(k).role != Role::KeepOut) continue;
    const ClosedSurface& s = solids.surface(k);
    if ((p.array() < s.min_corner().array() - margin).any() || (p.array() > s.max_corner().array() + margin).any())
      continue;
    if (s.distance(p) <= margin || s.inside(p)) return true;
  }
  return false;
}

// Design vertices deep inside a keep-in (the design does not contain it there) where no
// keep-out cuts it, or deep inside a keep-out (material inside it).
void check_design_vertices(const TriangleMesh& design, const SolidSet& solids, double d,
                           const Context& context) {
  const int n = static_cast<int>(design.vertices.rows());
  for (int j = 0; j < solids.size(); ++j) {
    const Role role = solids.input(j).role;
    if (role == Role::Seed) continue;
    Intrusion intrusion;
    for (int v = 0; v < n; ++v) {
      if ((v & 0x3fff) == 0) context.step("incidence", 1.0);  // counted: checks only
      const Vec3 p = design.vertices.row(v);
      const double depth = depth_beyond(solids.surface(j), p, kClearly * d);
      if (depth > 0 && (role == Role::KeepOut || !at_keep_out(solids, p, kClearly * d))) intrusion.add(p, depth);
    }
    if (intrusion.count == 0) continue;
    throw Error(Code::InvalidInput,
                role == Role::KeepIn
                    ? solids.describe(j) + " is not inside the design: " + intrusion.text(intrusion.count == 1 ? "design vertex" : "design vertices", "it") +
                          "; the design must contain every keep-in"
                    : solids.describe(j) + " has material inside it: " + intrusion.text(intrusion.count == 1 ? "design vertex" : "design vertices", "it") +
                          "; a keep-out must stay empty",
                "incidence");
  }
}

// A keep-in wholly inside a keep-out: none of it can be material. A keep-out that only
// cuts through a keep-in (a bore through a boss) is the usual way to drill it, and wins.
void check_keep_in_keep_out(const SolidSet& solids, double d) {
  for (int i = 0; i < solids.size(); ++i) {
    if (solids.input(i).role != Role::KeepIn) continue;
    const Vertices& points = solids.input(i).mesh.vertices;
    for (int j = 0; j < solids.size(); ++j) {
      if (solids.input(j).role != Role::KeepOut) continue;
      Intrusion intrusion;
      bool inside_all = true;
      for (Eigen::Index v = 0; v < points.rows() && inside_all; ++v) {
        const Vec3 p = points.row(v);
        inside_all = solids.surface(j).inside(p);
        const double depth = inside_all ? solids.surface(j).distance(p) : 0;
        if (depth > kClearly * d) intrusion.add(p, depth);
      }
      if (!inside_all || intrusion.count == 0) continue;
      throw Error(Code::InvalidInput,
                  solids.describe(i) + " lies inside " + solids.describe(j) + ": all its " +
                      std::to_string(points.rows()) + " vertices are in it, up to " + length(intrusion.deepest) +
                      " deep; material cannot be both required and forbidden there",
                  "incidence");
    }
  }
}

}  // namespace

void check_placement(const TriangleMesh& design, const SolidSet& solids, const Incidence& incidence,
                     const Context& context) {
  const double d = incidence.tolerance;
  check_keep_in_keep_out(solids, d);
  check_design_vertices(design, solids, d, context);
  for (int j = 0; j < solids.size(); ++j) {
    if (solids.input(j).role != Role::KeepIn || incidence.incident_vertices_per_solid[j] > 0) continue;
    // A keep-in no design vertex is near: buried in the material (valid), or away from it.
    const ClosedSurface surface(design);
    const Vertices& points = solids.input(j).mesh.vertices;
    if (surface.inside(Vec3(points.row(0).transpose()))) continue;
    double nearest = std::numeric_limits<double>::infinity();
    for (Eigen::Index v = 0; v < points.rows(); ++v)
      nearest = std::min(nearest, surface.distance(Vec3(points.row(v).transpose())));
    throw Error(Code::InvalidInput,
                solids.describe(j) + " is outside the design: it is " + length(nearest) +
                    " from it at its nearest, and no design vertex lies within d = " + length(d) +
                    " of it; the design must contain every keep-in",
                "incidence");
  }
}

}  // namespace genbrep

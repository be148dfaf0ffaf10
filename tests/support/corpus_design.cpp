#include "corpus_design.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <numeric>
#include <stdexcept>

#include "level_set.h"
#include "solid_meshes.h"

namespace genbrep::testing {
namespace {

using json = nlohmann::ordered_json;
using Sdf = std::function<double(const Vec3&)>;
using Rotation = Eigen::Matrix3d;
constexpr double kPi = 3.14159265358979323846;
// World size of one voxel before any scale variation: scenes of a few units, as the fixtures.
constexpr double kVoxel = 0.1;
// Facet sag of round solids, in voxels: well under the tolerance, as a CAD export's.
constexpr double kSag = 0.01;

// splitmix64: a fixed, portable stream (std distributions differ between libraries).
struct Rng {
  uint64_t state;
  uint64_t next() {
    uint64_t z = (state += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
  }
  double uniform(double lo = 0, double hi = 1) { return lo + (hi - lo) * (next() >> 11) * 0x1.0p-53; }
  int integer(int lo, int hi) { return lo + static_cast<int>(next() % static_cast<uint64_t>(hi - lo + 1)); }
  bool chance(double p) { return uniform() < p; }
  Vec3 unit() {
    const double z = uniform(-1, 1), a = uniform(0, 2 * kPi), r = std::sqrt(1 - z * z);
    return {r * std::cos(a), r * std::sin(a), z};
  }
  Rotation rotation() {  // uniform over SO(3) (Shoemake)
    const double u1 = uniform(), u2 = uniform(0, 2 * kPi), u3 = uniform(0, 2 * kPi);
    const Eigen::Quaterniond q(std::sqrt(u1) * std::cos(u3), std::sqrt(1 - u1) * std::sin(u2),
                               std::sqrt(1 - u1) * std::cos(u2), std::sqrt(u1) * std::sin(u3));
    return q.normalized().toRotationMatrix();
  }
  // A frame whose third axis is tilted 1°–30° off z: never axis-aligned.
  Rotation tilted() {
    const double tilt = uniform(1, 30) * kPi / 180, azimuth = uniform(0, 2 * kPi);
    return (Eigen::AngleAxisd(azimuth, Vec3::UnitZ()) * Eigen::AngleAxisd(tilt, Vec3::UnitX())).toRotationMatrix();
  }
};

double smooth_min(double a, double b, double k) {
  if (k <= 0) return std::min(a, b);
  const double t = std::max(k - std::abs(a - b), 0.0) / k;
  return std::min(a, b) - t * t * k * 0.25;
}

// Signed distance of a capped cylinder (radius `outer`, hollow inside `inner` > 0) of half
// length hz about the local z axis, at a point q in its local frame.
double cylinder_sdf(const Vec3& q, double inner, double outer, double hz) {
  const double radial = std::hypot(q.x(), q.y());
  const double dr = inner > 0 ? std::max(radial - outer, inner - radial) : radial - outer;
  const double dz = std::abs(q.z()) - hz;
  return std::hypot(std::max(dr, 0.0), std::max(dz, 0.0)) + std::min(std::max(dr, dz), 0.0);
}

// Distance from p to triangle abc (closest point by regions, Ericson §5.1.5).
double triangle_distance(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return ap.norm();
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return bp.norm();
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return (p - (a + ab * (d1 / (d1 - d3)))).norm();
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return cp.norm();
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return (p - (a + ac * (d2 / (d2 - d6)))).norm();
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0)
    return (p - (b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6))))).norm();
  const double denom = 1 / (va + vb + vc);
  return (p - (a + ab * (vb * denom) + ac * (vc * denom))).norm();
}

json to_json(const Vec3& v) { return json::array({v.x(), v.y(), v.z()}); }

// A keep-in or seed that members attach to: a box-like (box, plate, seed block) or
// round (cylinder, tube, boss, disk) body in its own frame.
struct Anchor {
  std::string name;
  bool round = false;
  Vec3 center;
  Rotation frame = Rotation::Identity();
  Vec3 half;  // box: half extents; round: (outer radius, inner radius, half length)
  double bound = 0;  // radius of a sphere around `center` holding it
};

// A point on the anchor's surface: on a face, an edge or a corner (round bodies: on the
// wall, on a rim, or on a rim as well).
Vec3 attach_point(const Anchor& a, const std::string& where, Rng& rng) {
  Vec3 q;
  if (a.round) {
    const double angle = rng.uniform(0, 2 * kPi), r = a.half.x(), hz = a.half.z();
    const double z = where == "face" ? rng.uniform(-0.6, 0.6) * hz : (rng.chance(0.5) ? hz : -hz);
    q = Vec3(r * std::cos(angle), r * std::sin(angle), z);
  } else {
    const int axis = rng.integer(0, 2);
    for (int k = 0; k < 3; ++k) {
      const bool fixed = where == "corner" || (where == "edge" ? k != axis : k == axis);
      q[k] = fixed ? (rng.chance(0.5) ? a.half[k] : -a.half[k]) : rng.uniform(-0.7, 0.7) * a.half[k];
    }
  }
  return a.center + a.frame * q;
}

std::string draw_attach(Rng& rng) {
  const double u = rng.uniform();
  return u < 0.5 ? "face" : u < 0.8 ? "edge" : "corner";
}

// Everything drawn, in voxel units, before extraction and variation.
struct Drawing {
  std::vector<Sdf> material;  // keep-ins, eroded seeds, organic members
  // Per material entry: half the thickness of a keep-in (the most a shrunk extraction may
  // take off it), 0 for the rest.
  std::vector<double> keep_in_half;
  std::vector<Sdf> removed;   // keep-outs (the design is void there)
  std::vector<GeneratedSolid> solids;
  std::vector<Anchor> anchors;
  Eigen::AlignedBox3d extent;
  json keep_ins = json::array(), keep_outs = json::array(), members = json::array(), seeds = json::array();
  json lattice = nullptr;
  bool free_shell = false;

  void add_solid(Role role, const std::string& name, TriangleMesh mesh) {
    int index = 0;
    for (const auto& s : solids) index += s.role == role;
    solids.push_back({std::string(role_name(role)) + "_" + std::to_string(index) + ".obj", name, role, std::move(mesh)});
  }
  void add_material(Sdf f, double keep_in_half_thickness = 0) {
    material.push_back(std::move(f));
    keep_in_half.push_back(keep_in_half_thickness);
  }
  void cover(const Vec3& center, double radius) {
    extent.extend(center - Vec3::Constant(radius));
    extent.extend(center + Vec3::Constant(radius));
  }
  bool free_at(const Vec3& center, double radius, double gap) const {
    for (const auto& a : anchors)
      if ((a.center - center).norm() < a.bound + radius + gap) return false;
    return true;
  }
};

void add_keep_out_cylinder(Drawing& d, const std::string& name, const Vec3& center, const Rotation& frame,
                           double radius, double hz) {
  d.removed.push_back([=](const Vec3& p) { return cylinder_sdf(frame.transpose() * (p - center), 0, radius, hz); });
  d.add_solid(Role::KeepOut, name,
              tube_mesh(center, frame.col(2), -hz, hz, 0, radius, circle_segments(radius, kSag)));
}

// One keep-in primitive at `center`; returns its anchor.
Anchor draw_keep_in(Drawing& d, Rng& rng, const Vec3& center, int index) {
  const double u = rng.uniform();
  const std::string kind = u < 0.25 ? "box" : u < 0.45 ? "plate" : u < 0.6 ? "cylinder" : u < 0.75 ? "tube" : "boss";
  Anchor a;
  a.name = kind + "_" + std::to_string(index);
  a.center = center;
  json entry = {{"name", a.name}, {"kind", kind}, {"center", to_json(center)}};
  if (kind == "box" || kind == "plate") {
    a.frame = rng.chance(0.5) ? rng.rotation() : Rotation::Identity();
    a.half = kind == "box" ? Vec3(rng.uniform(2, 5), rng.uniform(2, 5), rng.uniform(2, 5))
                           : Vec3(rng.uniform(6, 10), rng.uniform(3.5, 6), rng.uniform(1, 2));
    std::vector<PlateHole> holes;
    if (kind == "plate") {
      const int n = rng.integer(1, 3);
      for (int i = 0; i < n; ++i) {
        const double r = rng.uniform(1, 2.2);
        holes.push_back({a.half.x() * (2.0 * (i + 0.5) / n - 1), rng.uniform(-0.3, 0.3) * (a.half.y() - r), r});
      }
    }
    const Vec3 c = center, h = a.half;
    const Rotation f = a.frame;
    d.add_material(
        [=](const Vec3& p) {
          const Vec3 q = f.transpose() * (p - c);
          double s = box_sdf(q, -h, h);
          for (const auto& hole : holes) s = std::max(s, hole.radius - std::hypot(q.x() - hole.u, q.y() - hole.v));
          return s;
        },
        h.minCoeff());
    const int segments = holes.empty() ? 0 : circle_segments(holes.front().radius, kSag);
    d.add_solid(Role::KeepIn, a.name,
                holes.empty() ? oriented_box_mesh(c, h, f) : plate_with_holes_mesh(c, h, f, holes, segments));
    entry["half_extents"] = to_json(h);
    entry["tilted"] = !f.isIdentity();
    entry["holes"] = holes.size();
    // Half of the plates' holes are bolt bores: keep-outs whose wall is the hole's wall.
    if (!holes.empty() && rng.chance(0.5)) {
      for (const auto& hole : holes)
        add_keep_out_cylinder(d, "bore_" + a.name, c + f * Vec3(hole.u, hole.v, 0), f, hole.radius, h.z() + 1.5);
      entry["bores"] = "coincident with the holes";
    }
    a.bound = h.norm();
    d.keep_ins.push_back(entry);
    return a;
  }
  a.round = true;
  a.frame = kind == "boss" ? rng.tilted() : rng.chance(0.5) ? rng.rotation() : Rotation::Identity();
  const double outer = rng.uniform(2.5, 5), hz = rng.uniform(2, 4.5);
  const double inner = kind == "cylinder" ? 0 : outer - rng.uniform(1, 2);
  a.half = Vec3(outer, inner, hz);
  const int segments = circle_segments(outer, kSag);
  const Rotation f = a.frame;
  d.add_material([=](const Vec3& p) { return cylinder_sdf(f.transpose() * (p - center), inner, outer, hz); },
                 std::min(inner > 0 ? 0.5 * (outer - inner) : outer, hz));
  d.add_solid(Role::KeepIn, a.name, tube_mesh(center, f.col(2), -hz, hz, inner, outer, segments));
  entry["outer_radius"] = outer;
  entry["inner_radius"] = inner;
  entry["half_length"] = hz;
  entry["axis"] = to_json(f.col(2));
  if (kind == "boss") {
    // The bore's wall is the boss's inner wall: exactly, or off by 1e-9 h to 1e-3 h either way.
    const double offset = rng.chance(1.0 / 3) ? 0.0
                          : (rng.chance(0.5) ? 1 : -1) * std::pow(10.0, rng.uniform(-9, -3));
    const double bore = inner + offset;
    d.removed.push_back([=](const Vec3& p) { return cylinder_sdf(f.transpose() * (p - center), 0, bore, hz + 1.5); });
    d.add_solid(Role::KeepOut, "bore_" + a.name, tube_mesh(center, f.col(2), -hz - 1.5, hz + 1.5, 0, bore, segments));
    entry["bore_offset_h"] = offset;
  }
  a.bound = std::hypot(outer, hz);
  d.keep_ins.push_back(entry);
  return a;
}

// A keep-out box beside the middle of segment a–b of radius r, `gap` voxels off its surface.
void add_grazing_keep_out(Drawing& d, Rng& rng, const Vec3& a, const Vec3& b, double r, int index) {
  const Vec3 along = (b - a).normalized();
  Vec3 side = along.cross(rng.unit());
  if (side.norm() < 1e-3) return;
  side.normalize();
  const double gap = rng.uniform(0.5, 2);
  const Vec3 half(rng.uniform(1.5, 3), rng.uniform(1.5, 3), rng.uniform(2, 4));  // side, along, third
  const Vec3 center = 0.5 * (a + b) + side * (r + gap + half.x());
  const double bound = half.norm();
  if (!d.free_at(center, bound, 1.0)) return;
  Rotation frame;
  frame << side, along, side.cross(along);
  d.removed.push_back([=](const Vec3& p) { return box_sdf(frame.transpose() * (p - center), -half, half); });
  d.add_solid(Role::KeepOut, "grazed_" + std::to_string(index), oriented_box_mesh(center, half, frame));
  d.keep_outs.push_back({{"kind", "grazed box"}, {"gap_h", gap}, {"center", to_json(center)}});
  d.cover(center, bound);
}

void add_capsule(Drawing& d, const Vec3& a, const Vec3& b, double r) {
  d.add_material([=](const Vec3& p) { return capsule_sdf(p, a, b, r); });
  d.cover(a, r);
  d.cover(b, r);
}

// Organic members joining anchor i to anchor j (and a third, for trees and webs).
void draw_member(Drawing& d, Rng& rng, int i, int j, int k) {
  const Anchor &ai = d.anchors[i], &aj = d.anchors[j];
  const std::string wi = draw_attach(rng), wj = draw_attach(rng);
  const Vec3 pi = attach_point(ai, wi, rng), pj = attach_point(aj, wj, rng);
  const double u = rng.uniform();
  json entry = {{"from", ai.name}, {"to", aj.name}, {"attach", {wi, wj}}};
  if (u < 0.55 || k < 0) {  // a strut, straight or bent once
    const double r = rng.uniform(0.5, 3);
    Vec3 mid = 0.5 * (pi + pj);
    if (rng.chance(0.5)) mid += rng.unit() * rng.uniform(0, 0.3) * (pj - pi).norm();
    add_capsule(d, pi, mid, r);
    add_capsule(d, mid, pj, r);
    entry["kind"] = "strut";
    entry["thickness_h"] = 2 * r;
    if (rng.chance(0.4)) add_grazing_keep_out(d, rng, pi, mid, r, static_cast<int>(d.members.size()));
  } else if (u < 0.8) {  // a tree: a junction with a branch to each of three anchors
    const std::string wk = draw_attach(rng);
    const Vec3 pk = attach_point(d.anchors[k], wk, rng);
    const Vec3 junction = (pi + pj + pk) / 3 + rng.unit() * rng.uniform(0, 3);
    const double r = rng.uniform(0.75, 2.5);
    for (const Vec3& p : {pi, pj, pk}) add_capsule(d, junction, p, r * rng.uniform(0.7, 1.0));
    entry["kind"] = "tree";
    entry["to"] = {aj.name, d.anchors[k].name};
    entry["attach"].push_back(wk);
    entry["thickness_h"] = 2 * r;
  } else {  // a thin web spanning two attachments and a point off their line
    const Vec3 apex = 0.5 * (pi + pj) + rng.unit() * rng.uniform(0.25, 0.5) * (pj - pi).norm();
    const double t = rng.uniform(0.5, 3);
    d.add_material([=](const Vec3& p) { return triangle_distance(p, pi, pj, apex) - t; });
    for (const Vec3& p : {pi, pj, apex}) d.cover(p, t);
    entry["kind"] = "web";
    entry["thickness_h"] = 2 * t;
  }
  d.members.push_back(entry);
}

// A seed block, or a seed disk round a keep-in hub, eroded by pockets and through-holes.
void draw_seed(Drawing& d, Rng& rng, const Vec3& center, int index) {
  Anchor a;
  a.center = center;
  std::vector<Sdf> pockets;
  json entry;
  Sdf stock;
  TriangleMesh mesh;
  const bool disk = rng.chance(0.5);
  if (disk) {
    const double radius = rng.uniform(7, 11), hz = rng.uniform(1.5, 3), hub = rng.uniform(2, 3);
    a.round = true;
    a.frame = rng.chance(0.5) ? rng.rotation() : Rotation::Identity();
    a.half = Vec3(radius, 0, hz);
    const Rotation f = a.frame;
    stock = [=](const Vec3& p) { return cylinder_sdf(f.transpose() * (p - center), 0, radius, hz); };
    mesh = tube_mesh(center, f.col(2), -hz, hz, 0, radius, circle_segments(radius, kSag));
    const double hub_hz = hz + rng.uniform(1, 2);
    d.add_material([=](const Vec3& p) { return cylinder_sdf(f.transpose() * (p - center), 0, hub, hub_hz); }, hub);
    d.add_solid(Role::KeepIn, "hub_" + std::to_string(index),
                tube_mesh(center, f.col(2), -hub_hz, hub_hz, 0, hub, circle_segments(hub, kSag)));
    const int n = rng.integer(2, 5);
    int reaching = 0;
    for (int i = 0; i < n; ++i) {
      const double pr = rng.uniform(2, 4), angle = rng.uniform(0, 2 * kPi);
      const bool reach = rng.chance(0.3);
      reaching += reach;
      const double at = reach ? hub + 0.7 * pr : rng.uniform(hub + pr + 1, radius);
      const Vec3 c1 = center + f * Vec3(at * std::cos(angle), at * std::sin(angle), (rng.chance(0.5) ? 1 : -1) * hz);
      const Vec3 c2 = c1 + f * Vec3(rng.uniform(-2, 2), rng.uniform(-2, 2), 0);
      pockets.push_back([=](const Vec3& p) { return smooth_min(sphere_sdf(p, c1, pr), sphere_sdf(p, c2, 0.8 * pr), 1.5); });
    }
    entry = {{"kind", "disk round a keep-in hub"}, {"radius", radius}, {"pockets", n}, {"pockets_reaching_hub", reaching}};
  } else {
    a.frame = rng.chance(0.5) ? rng.rotation() : Rotation::Identity();
    a.half = Vec3(rng.uniform(6, 10), rng.uniform(5, 8), rng.uniform(2, 4));
    const Rotation f = a.frame;
    const Vec3 h = a.half;
    stock = [=](const Vec3& p) { return box_sdf(f.transpose() * (p - center), -h, h); };
    mesh = oriented_box_mesh(center, h, f);
    const int n = rng.integer(1, 4);
    for (int i = 0; i < n; ++i) {
      const double pr = rng.uniform(2, 5);
      const Vec3 c1 = center + f * Vec3(rng.uniform(-1, 1) * h.x(), rng.uniform(-1, 1) * h.y(), h.z());
      const Vec3 c2 = c1 + rng.unit() * rng.uniform(1, 3);
      pockets.push_back([=](const Vec3& p) { return smooth_min(sphere_sdf(p, c1, pr), sphere_sdf(p, c2, 0.7 * pr), 1.5); });
    }
    entry = {{"kind", "block"}, {"half_extents", to_json(h)}, {"pockets", n}};
  }
  const int holes = rng.integer(0, 2);
  for (int i = 0; i < holes; ++i) {
    const double r = rng.uniform(1.5, 3);
    const Vec3 at = center + a.frame * Vec3(rng.uniform(-0.5, 0.5) * a.half.x(), rng.uniform(-0.5, 0.5) * a.half.x(), 0);
    const Rotation f = a.frame;
    const double through = a.half.z() + 2;
    pockets.push_back([=](const Vec3& p) { return cylinder_sdf(f.transpose() * (p - at), 0, r, through); });
  }
  entry["through_holes"] = holes;
  d.add_material([=](const Vec3& p) {
    double s = stock(p);
    for (const auto& pocket : pockets) s = std::max(s, -pocket(p));
    return s;
  });
  a.name = "seed_" + std::to_string(index);
  a.bound = a.round ? std::hypot(a.half.x(), a.half.z()) : a.half.norm();
  d.add_solid(Role::Seed, a.name, std::move(mesh));
  d.anchors.push_back(a);
  d.seeds.push_back(entry);
  d.cover(center, a.bound);
}

// A lattice of struts on a jittered nx × ny × nz grid of nodes, beside the other parts,
// with keep-in pads on its outer nodes: one organic component of genus 20–100.
void draw_lattice(Drawing& d, Rng& rng, const Vec3& corner) {
  int nx, ny, nz, genus;
  do {
    nz = rng.integer(1, 2);
    nx = nz == 1 ? rng.integer(5, 10) : rng.integer(3, 6);
    ny = nz == 1 ? rng.integer(5, 10) : rng.integer(3, 6);
    const int edges = (nx - 1) * ny * nz + nx * (ny - 1) * nz + nx * ny * (nz - 1);
    genus = edges - nx * ny * nz + 1;
  } while (genus < 20 || genus > 100);
  const double spacing = rng.uniform(5.5, 7), r = rng.uniform(0.8, 1.3);
  std::vector<Vec3> node(static_cast<size_t>(nx * ny * nz));
  auto at = [&](int i, int j, int k) -> Vec3& { return node[static_cast<size_t>((k * ny + j) * nx + i)]; };
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) at(i, j, k) = corner + spacing * Vec3(i, j, k) + rng.unit() * rng.uniform(0, 1);
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        if (i + 1 < nx) add_capsule(d, at(i, j, k), at(i + 1, j, k), r);
        if (j + 1 < ny) add_capsule(d, at(i, j, k), at(i, j + 1, k), r);
        if (k + 1 < nz) add_capsule(d, at(i, j, k), at(i, j, k + 1), r);
      }
  // Pads on the four corners of the bottom layer and on a few other outer nodes, each on a
  // short stub pointing out of the lattice.
  std::vector<std::pair<int, int>> outer = {{0, 0}, {nx - 1, 0}, {0, ny - 1}, {nx - 1, ny - 1}};
  const int extra = rng.integer(1, 4);
  for (int e = 0; e < extra; ++e) outer.push_back(rng.chance(0.5) ? std::make_pair(rng.integer(1, nx - 2), 0)
                                                                   : std::make_pair(0, rng.integer(1, ny - 2)));
  int pads = 0;
  for (size_t e = 0; e < outer.size(); ++e) {
    const auto [i, j] = outer[e];
    if (std::find(outer.begin(), outer.begin() + static_cast<long>(e), outer[e]) != outer.begin() + static_cast<long>(e))
      continue;
    const Vec3 out = Vec3(i == 0 ? -1 : i == nx - 1 ? 1 : 0, j == 0 ? -1 : j == ny - 1 ? 1 : 0, 0).normalized();
    const Vec3 half = Vec3::Constant(rng.uniform(1.5, 2.2));
    const Vec3 center = at(i, j, 0) + out * (spacing * 0.45 + half.x());
    add_capsule(d, at(i, j, 0), center, r);
    d.add_material([=](const Vec3& p) { return box_sdf(p - center, -half, half); }, half.x());
    d.add_solid(Role::KeepIn, "pad_" + std::to_string(pads++), oriented_box_mesh(center, half, Rotation::Identity()));
    d.cover(center, half.norm());
  }
  d.lattice = {{"nodes", {nx, ny, nz}}, {"genus", genus}, {"spacing_h", spacing}, {"thickness_h", 2 * r}, {"pads", pads}};
}

// Keep-ins, seeds, members joining them (a random spanning tree and a few more), and now
// and then a lattice and a closed shell touching no solid.
Drawing draw(Rng& rng, bool lattice) {
  Drawing d;
  const Vec3 domain(rng.uniform(32, 46), rng.uniform(32, 46), rng.uniform(20, 28));
  const int keep_ins = rng.integer(2, 5), seeds = rng.chance(0.5) ? 1 : 0;
  for (int i = 0; i < keep_ins + seeds; ++i) {
    const bool seed = i >= keep_ins;
    const double need = seed ? 12 : 7;
    for (int attempt = 0; attempt < 200; ++attempt) {
      const Vec3 center = Vec3(rng.uniform(need, domain.x() - need), rng.uniform(need, domain.y() - need),
                               rng.uniform(std::min(need, domain.z() / 2), std::max(domain.z() - need, domain.z() / 2)));
      if (!d.free_at(center, need, 2)) continue;
      if (seed) {
        draw_seed(d, rng, center, i - keep_ins);
      } else {
        d.anchors.push_back(draw_keep_in(d, rng, center, i));
        d.cover(center, d.anchors.back().bound);
      }
      break;
    }
  }
  const int n = static_cast<int>(d.anchors.size());
  auto third = [n](int i, int j) {  // an anchor other than i and j, or -1
    for (int t = 1; t < n; ++t)
      if ((j + t) % n != i && (j + t) % n != j) return (j + t) % n;
    return -1;
  };
  for (int i = 1; i < n; ++i) {
    const int parent = rng.integer(0, i - 1);
    draw_member(d, rng, parent, i, third(parent, i));
  }
  const int more = rng.integer(0, 2);
  for (int m = 0; m < more && n > 1; ++m) {
    const int i = rng.integer(0, n - 1), j = (i + rng.integer(1, n - 1)) % n;
    draw_member(d, rng, i, j, third(i, j));
  }
  if (lattice) draw_lattice(d, rng, Vec3(domain.x() + 14, 4, domain.z() / 3));
  if (rng.chance(0.1)) {  // a closed organic shell: two blended balls that touch nothing
    const Vec3 c = d.extent.max() + Vec3(10, 0, -6), c2 = c + rng.unit() * 3;
    const double r = rng.uniform(2, 4);
    d.add_material([=](const Vec3& p) { return smooth_min(sphere_sdf(p, c, r), sphere_sdf(p, c2, 0.8 * r), 1.5); });
    d.cover(c, r + 4);
    d.free_shell = true;
  }
  return d;
}

void transform(TriangleMesh& mesh, double scale, const Rotation& rotation, const Vec3& offset) {
  for (Eigen::Index v = 0; v < mesh.vertices.rows(); ++v)
    mesh.vertices.row(v) = (scale * (rotation * Vec3(mesh.vertices.row(v).transpose())) + offset).transpose();
}

std::string pick(const std::string& forced, const std::vector<std::string>& choices, const std::vector<double>& weights,
                 Rng& rng) {
  if (forced != "random") {
    if (std::find(choices.begin(), choices.end(), forced) == choices.end())
      throw std::invalid_argument("unknown choice '" + forced + "'");
    return forced;
  }
  double u = rng.uniform() * std::accumulate(weights.begin(), weights.end(), 0.0);
  for (size_t i = 0; i < choices.size(); ++i)
    if ((u -= weights[i]) < 0) return choices[i];
  return choices.back();
}

}  // namespace

GeneratedCase generate_case(uint64_t seed, const GenerateOptions& options) {
  // Separate streams: the base design does not depend on the variation drawn.
  Rng design_rng{seed * 0x2545f4914f6cdd1dULL + 1}, variation_rng{seed * 0x9e3779b97f4a7c15ULL + 7};
  const bool lattice = options.lattice == "random" ? design_rng.chance(0.2) : options.lattice == "yes";
  Drawing d = draw(design_rng, lattice);
  const std::string extraction = pick(options.extraction, {"smoothed", "staircase", "shrunk"}, {2, 1, 1}, design_rng);
  const double shrink = extraction == "shrunk" ? design_rng.uniform(0.25, 2) : 0;
  const double blend = extraction == "smoothed" ? 1.5 : 0;
  // Shrunk: each keep-in loses up to `shrink` off its surface (at most half its thickness),
  // so the design falls short of it as a filtered density leaves it; the rest is unchanged.
  std::vector<double> inset;
  for (double half : d.keep_in_half) inset.push_back(std::min(shrink, 0.5 * half));
  auto field = [&](const Vec3& p) {
    double f = 1e9;
    for (size_t m = 0; m < d.material.size(); ++m) f = smooth_min(f, d.material[m](p) + inset[m], blend);
    for (const auto& r : d.removed) f = std::max(f, -r(p));
    if (extraction == "staircase") return f < 0 ? -1.0 : 1.0;  // thresholded density
    return f;
  };
  // A solver's grid knows nothing of the solids: its origin sits at a random fraction.
  const Vec3 origin = d.extent.min() - Vec3::Constant(3) -
                      Vec3(design_rng.uniform(), design_rng.uniform(), design_rng.uniform());
  const Vec3 size = (d.extent.max() + Vec3::Constant(3) - origin);
  const Eigen::Vector3i cells(static_cast<int>(std::ceil(size.x())), static_cast<int>(std::ceil(size.y())),
                              static_cast<int>(std::ceil(size.z())));
  GeneratedCase out;
  out.design = extract_level_set(field, origin, 1.0, cells);

  // The variation: what a user would not expect to change the result.
  std::vector<std::string> variations;
  if (options.variation == "random") {
    const std::vector<std::string> kinds = {"scale", "rotate", "move", "nudge", "tolerance"};
    if (!variation_rng.chance(0.35)) {
      variations.push_back(kinds[variation_rng.integer(0, 4)]);
      if (variation_rng.chance(0.25)) {
        const std::string second = kinds[variation_rng.integer(0, 4)];
        if (second != variations[0]) variations.push_back(second);
      }
    }
  } else if (options.variation != "none") {
    pick(options.variation, {"scale", "rotate", "move", "nudge", "tolerance"}, {1, 1, 1, 1, 1}, variation_rng);
    variations.push_back(options.variation);
  }
  auto has = [&](const char* v) { return std::find(variations.begin(), variations.end(), v) != variations.end(); };
  const double scale = kVoxel * (has("scale") ? std::pow(10.0, variation_rng.uniform(-3, 3)) : 1.0);
  const Rotation rotation = has("rotate") ? variation_rng.rotation() : Rotation::Identity();
  const double span = (d.extent.max() - d.extent.min()).norm();
  const Vec3 offset = has("move") ? Vec3(variation_rng.unit() * span * scale * std::pow(10.0, variation_rng.uniform(2, 5)))
                                  : Vec3::Zero();
  const Vec3 nudge = has("nudge") ? Vec3(variation_rng.unit() * variation_rng.uniform(0, 0.5)) : Vec3::Zero();
  const double tolerance_h = has("tolerance") ? variation_rng.uniform(0.5, 3) : 1.0;

  transform(out.design, scale, rotation, offset);
  json files_in = json::array(), files_out = json::array(), files_seed = json::array(), names = json::object();
  for (GeneratedSolid& s : d.solids) {
    for (Eigen::Index v = 0; v < s.mesh.vertices.rows(); ++v) s.mesh.vertices.row(v) += nudge.transpose();
    transform(s.mesh, scale, rotation, offset);
    (s.role == Role::KeepIn ? files_in : s.role == Role::KeepOut ? files_out : files_seed).push_back(s.file);
    names[s.file] = s.name;
    out.solids.push_back(std::move(s));
  }
  json meta;
  meta["generator"] = "generate_design";
  meta["generator_seed"] = seed;
  meta["voxel"] = scale;
  meta["tolerance"] = tolerance_h * scale;
  if (rotation.isIdentity()) {
    meta["grid"] = {{"origin", to_json(scale * origin + offset)}, {"h", scale}};
  }
  meta["keep_in"] = files_in;
  meta["keep_out"] = files_out;
  meta["seed"] = files_seed;
  meta["names"] = names;
  json drawn;
  drawn["extraction"] = extraction;
  if (extraction == "shrunk") drawn["shrink_h"] = shrink;
  drawn["variation"] = variations;
  if (has("scale")) drawn["scale"] = scale / kVoxel;
  if (has("rotate")) drawn["rotation"] = {to_json(rotation.row(0)), to_json(rotation.row(1)), to_json(rotation.row(2))};
  if (has("move")) drawn["offset"] = to_json(offset);
  if (has("nudge")) drawn["nudge_h"] = to_json(nudge);
  drawn["tolerance_h"] = tolerance_h;
  drawn["keep_ins"] = d.keep_ins;
  drawn["keep_outs"] = d.keep_outs;
  drawn["members"] = d.members;
  drawn["seeds"] = d.seeds;
  drawn["lattice"] = d.lattice;
  drawn["closed_shell_touching_no_solid"] = d.free_shell;
  drawn["design_triangles"] = out.design.triangles.rows();
  meta["drawn"] = drawn;
  out.meta_json = meta.dump(1) + "\n";
  return out;
}

void write_case(const std::string& dir, const GeneratedCase& generated) {
  std::filesystem::create_directories(dir);
  write_obj(dir + "/design.obj", generated.design);
  for (const auto& s : generated.solids) write_obj(dir + "/" + s.file, s.mesh);
  FILE* file = std::fopen((dir + "/meta.json").c_str(), "w");
  if (!file) throw std::runtime_error("cannot write '" + dir + "/meta.json'");
  std::fputs(generated.meta_json.c_str(), file);
  std::fclose(file);
}

}  // namespace genbrep::testing

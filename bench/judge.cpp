// bench/judge.cpp — corpus_judge: an independent verdict on one corpus case and, given a
// conversion's output folder, on its composed mesh. Prints one JSON object on stdout.
//   corpus_judge --case DIR [--result OUTDIR] [--samples N] [--cap N]
// The case folder holds design.obj, meta.json (keep_in, keep_out, seed: file lists;
// names; tolerance d; voxel h) and the solids' OBJ files.
// Inputs: the design and every solid closed, 2-manifold, the design free of
// self-intersections; the case is "consistent" when every keep-in lies in the design up to
// d (points on and inside the keep-in, outside the design farther than d, count against it)
// and no keep-out holds material deeper than d (design surface points, and keep-out
// interior points inside the design, deeper than d in the keep-out count against it).
// Result: OUTDIR/composed.obj closed, 2-manifold, consistently and outward oriented, free
// of self-intersections; points inside each keep-in (surface points pushed in by
// eps = 1e-3 d, interior points) inside the composed mesh; points inside each keep-out
// deeper than eps, and composed vertices deeper than eps, outside it. Inside tests run only
// on closed, 2-manifold meshes; otherwise those checks say "not checked".
// Uses CGAL (judge_mesh.h), never genbrep's compose or pull code. Sampling is
// deterministic: a fixed seed, uniforms made from std::mt19937_64's raw bits.
// Exit status: 0 when a verdict is printed (whatever it says), 2 for bad arguments.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>
#include <random>

#include "judge_mesh.h"

namespace fs = std::filesystem;
using json = nlohmann::ordered_json;
using namespace judge;

namespace {

constexpr std::uint64_t kSeed = 20190701;      // any fixed value: runs must repeat exactly
constexpr double kEpsilonOfTolerance = 1e-3;   // eps = this × d: "inside" means deeper than eps
constexpr int kAttemptsPerInteriorPoint = 50;  // rejection sampling gives up after this many

// The message of the exception being handled; call only inside a catch block.
std::string current_message() {
  try {
    throw;
  } catch (const std::exception& e) {
    return e.what();
  } catch (...) {
    return "an exception of unknown type";
  }
}

json position(const Point& p) { return json::array({p.x(), p.y(), p.z()}); }

// Uniform doubles in [0, 1) from the top 53 bits of the engine's output, so the sequence
// is the same with every standard library.
class Random {
 public:
  explicit Random(std::uint64_t seed) : engine_(seed) {}
  double uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }

 private:
  std::mt19937_64 engine_;
};

struct SurfacePoint {
  Point p;
  K::Vector_3 outward;  // unit normal of its triangle, turned to face out of the volume
};

// Area-weighted points on the soup's triangles. `sign` is +1 when the triangles face
// outward (positive volume), -1 when they face inward.
std::vector<SurfacePoint> surface_points(const Soup& soup, int count, double sign, Random& random) {
  std::vector<double> cumulative;
  double total = 0;
  for (const Triangle& t : soup.triangles) {
    total += std::sqrt(CGAL::squared_area(soup.points[t[0]], soup.points[t[1]], soup.points[t[2]]));
    cumulative.push_back(total);
  }
  std::vector<SurfacePoint> points;
  if (total <= 0) return points;
  for (int i = 0; i < count; ++i) {
    const double u = random.uniform() * total;
    const std::size_t k = std::min<std::size_t>(
        std::upper_bound(cumulative.begin(), cumulative.end(), u) - cumulative.begin(),
        cumulative.size() - 1);
    const Triangle& t = soup.triangles[k];
    const Point &a = soup.points[t[0]], &b = soup.points[t[1]], &c = soup.points[t[2]];
    const double r = std::sqrt(random.uniform()), s = random.uniform();
    const Point p = CGAL::barycenter(a, 1 - r, b, r * (1 - s), c, r * s);
    K::Vector_3 n = CGAL::cross_product(b - a, c - a);
    const double length = std::sqrt(n.squared_length());
    if (length > 0) n = n * (sign / length);
    points.push_back({p, n});
  }
  return points;
}

// Uniform points inside a closed solid by rejection from its bounding box.
std::vector<Point> interior_points(const Soup& soup, const Solid& solid, int count,
                                   Random& random) {
  const CGAL::Bbox_3 box = CGAL::bbox_3(soup.points.begin(), soup.points.end());
  std::vector<Point> points;
  for (long attempt = 0;
       attempt < long(count) * kAttemptsPerInteriorPoint && int(points.size()) < count; ++attempt) {
    const Point p(box.xmin() + random.uniform() * (box.xmax() - box.xmin()),
                  box.ymin() + random.uniform() * (box.ymax() - box.ymin()),
                  box.zmin() + random.uniform() * (box.zmax() - box.zmin()));
    if (solid.side(p) == CGAL::ON_BOUNDED_SIDE) points.push_back(p);
  }
  return points;
}

// One input mesh: its soup, counts and, when closed and 2-manifold, its queries.
struct Input {
  std::string file, name, role;
  Soup soup;
  Topology top;
  double volume = 0;
  std::unique_ptr<Solid> solid;  // null unless closed and 2-manifold
  std::string error;

  double sign() const { return volume < 0 ? -1.0 : 1.0; }
};

std::unique_ptr<Input> load(const fs::path& path, const std::string& name,
                            const std::string& role) {
  auto input = std::make_unique<Input>();
  input->file = path.filename().string();
  input->name = name;
  input->role = role;
  try {
    input->soup = read_soup(path.string());
    input->top = topology(input->soup);
    input->volume = signed_volume(input->soup);
    if (input->top.closed() && input->top.manifold())
      input->solid = std::make_unique<Solid>(input->soup);
  } catch (...) {
    input->error = current_message();
  }
  return input;
}

json topology_json(const Topology& top) {
  return {{"vertices", top.vertices},
          {"triangles", top.triangles},
          {"closed", top.closed()},
          {"boundary_edges", top.boundary_edges},
          {"manifold", top.manifold()},
          {"non_manifold_edges", top.non_manifold_edges},
          {"non_manifold_vertices", top.non_manifold_vertices},
          {"inconsistent_edges", top.inconsistent_edges},
          {"coincident_vertices", top.coincident_vertices},
          {"shells", top.shells}};
}

json input_json(const Input& input) {
  json out = {{"file", input.file}, {"name", input.name}, {"role", input.role}};
  if (!input.error.empty()) {
    out["error"] = input.error;
    return out;
  }
  out.update(topology_json(input.top));
  out["volume"] = input.volume;
  return out;
}

json self_intersections_json(const SelfIntersections& s) {
  if (!s.checked) return {{"checked", false}, {"note", s.note}};
  json out = {{"checked", true},
              {"pairs", s.pairs},
              {"capped", s.capped},
              {"degenerate_faces", s.degenerate_faces}};
  if (s.pairs > 0) out["first_at"] = s.first_at;
  return out;
}

// Running worst of a set of violations: how many, how far at most, and where.
struct Worst {
  long count = 0;
  double max = 0;
  std::optional<Point> at;
  void add(const Point& p, double distance) {
    ++count;
    if (!at || distance > max) max = distance, at = p;
  }
  void fill(json& out, const char* count_key, const char* max_key) const {
    out[count_key] = count;
    out[max_key] = max;
    if (at) out["at"] = position(*at);
  }
};

struct Case {
  fs::path dir;
  double tolerance = 0, voxel = 0;
  int samples = 10000;
  long cap = 100000;
  std::unique_ptr<Input> design;
  std::vector<std::unique_ptr<Input>> keep_ins, keep_outs, seeds;
};

void load_case(Case& c, json& out) {
  std::ifstream file(c.dir / "meta.json");
  if (!file) throw std::runtime_error("no meta.json in '" + c.dir.string() + "'");
  const json meta = json::parse(file);
  c.tolerance = meta.at("tolerance").get<double>();
  c.voxel = meta.value("voxel", 0.0);
  const json names = meta.value("names", json::object());
  auto solids = [&](const char* key, const char* role, std::vector<std::unique_ptr<Input>>& into) {
    for (const auto& f : meta.value(key, json::array())) {
      const std::string file_name = f.get<std::string>();
      into.push_back(load(c.dir / file_name,
                          names.value(file_name, fs::path(file_name).stem().string()), role));
    }
  };
  c.design = load(c.dir / "design.obj", "design", "design");
  solids("keep_in", "keep-in", c.keep_ins);
  solids("keep_out", "keep-out", c.keep_outs);
  solids("seed", "seed", c.seeds);
  out["tolerance"] = c.tolerance;
  out["voxel"] = c.voxel;
}

json inputs_json(const Case& c) {
  json design = input_json(*c.design);
  if (c.design->error.empty())
    design["self_intersections"] =
        self_intersections_json(self_intersections(c.design->soup, c.cap));
  json solids = json::array();
  for (const auto* group : {&c.keep_ins, &c.keep_outs, &c.seeds})
    for (const auto& s : *group) solids.push_back(input_json(*s));
  return {{"design", design}, {"solids", solids}};
}

// Keep-ins inside the design and keep-outs free of material, both up to the tolerance d.
json consistency_json(const Case& c, const json& inputs) {
  json reasons = json::array(), unchecked = json::array();
  const Input& design = *c.design;
  if (!design.solid) unchecked.push_back("design is not a closed 2-manifold mesh");
  const json& design_si = inputs["design"].value("self_intersections", json::object());
  if (design_si.value("pairs", 0) > 0) unchecked.push_back("design self-intersects");
  for (const auto* group : {&c.keep_ins, &c.keep_outs})
    for (const auto& s : *group)
      if (!s->solid)
        unchecked.push_back(s->role + " '" + s->name + "' is not a closed 2-manifold mesh");
  if (!design.solid)
    return {{"verdict", "not checked"}, {"reasons", reasons}, {"not_checked", unchecked}};
  Random random(kSeed);
  for (const auto& k : c.keep_ins) {
    if (!k->solid) continue;
    Worst outside;
    auto test = [&](const Point& p) {
      if (design.solid->side(p) != CGAL::ON_UNBOUNDED_SIDE) return;
      const double d = design.solid->distance(p);
      if (d > c.tolerance) outside.add(p, d);
    };
    for (const auto& s : surface_points(k->soup, c.samples, k->sign(), random)) test(s.p);
    for (const auto& p : interior_points(k->soup, *k->solid, c.samples, random)) test(p);
    if (outside.count == 0) continue;
    json reason = {{"kind", "keep-in outside the design"}, {"solid", k->file}, {"name", k->name}};
    outside.fill(reason, "points", "max_distance");
    reasons.push_back(reason);
  }
  const auto design_surface = surface_points(design.soup, c.samples, design.sign(), random);
  for (const auto& l : c.keep_outs) {
    if (!l->solid) continue;
    Worst material;
    for (const auto& s : design_surface) {
      if (l->solid->side(s.p) != CGAL::ON_BOUNDED_SIDE) continue;
      const double depth = l->solid->distance(s.p);
      if (depth > c.tolerance) material.add(s.p, depth);
    }
    for (const auto& p : interior_points(l->soup, *l->solid, c.samples, random)) {
      if (design.solid->side(p) != CGAL::ON_BOUNDED_SIDE) continue;
      const double depth = l->solid->distance(p);
      if (depth > c.tolerance) material.add(p, depth);
    }
    if (material.count == 0) continue;
    json reason = {{"kind", "material inside a keep-out"}, {"solid", l->file}, {"name", l->name}};
    material.fill(reason, "points", "max_depth");
    reasons.push_back(reason);
  }
  const char* verdict = !reasons.empty()    ? "inconsistent"
                        : unchecked.empty() ? "consistent"
                                            : "not checked";
  return {{"verdict", verdict}, {"reasons", reasons}, {"not_checked", unchecked}};
}

// Points inside a closed solid: surface points pushed inward by `push` (those that stay
// inside; at a concave edge a push can leave), then interior points.
std::vector<Point> inner_points(const Input& input, int count, double push, Random& random) {
  std::vector<Point> points;
  for (const auto& s : surface_points(input.soup, count, input.sign(), random)) {
    const Point p = s.p - push * s.outward;
    if (input.solid->side(p) == CGAL::ON_BOUNDED_SIDE) points.push_back(p);
  }
  for (const auto& p : interior_points(input.soup, *input.solid, count, random))
    points.push_back(p);
  return points;
}

// Points inside each keep-in must be inside the composed mesh, but where a keep-out
// overlaps the keep-in, or lies within eps of the point: keep-outs are removed last
// (§8.1), so those points are empty by rule (a generated bore 1e-3 h wider than its boss's
// hole cuts the boss's wall), and within eps of a keep-out either answer is in tolerance.
json keep_ins_json(const Case& c, const Solid& composed, double eps, Random& random,
                   bool& all_inside) {
  json out = json::array();
  for (const auto& k : c.keep_ins) {
    json entry = {{"solid", k->file}, {"name", k->name}};
    if (!k->solid) {
      entry["checked"] = false;
      out.push_back(entry), all_inside = false;
      continue;
    }
    const std::vector<Point> points = inner_points(*k, c.samples, eps, random);
    Worst outside;
    long beyond_tolerance = 0;
    for (const auto& p : points) {
      if (composed.side(p) != CGAL::ON_UNBOUNDED_SIDE) continue;
      const bool in_keep_out = std::any_of(c.keep_outs.begin(), c.keep_outs.end(), [&](const auto& l) {
        return l->solid && (l->solid->side(p) != CGAL::ON_UNBOUNDED_SIDE || l->solid->distance(p) <= eps);
      });
      if (in_keep_out) continue;
      const double depth = composed.distance(p);
      outside.add(p, depth);
      beyond_tolerance += depth > c.tolerance;
    }
    entry["checked"] = true;
    entry["points"] = points.size();
    outside.fill(entry, "outside", "max_depth_outside");
    entry["outside_beyond_tolerance"] = beyond_tolerance;
    all_inside = all_inside && outside.count == 0;
    out.push_back(entry);
  }
  return out;
}

// Points deeper than eps inside each keep-out, and composed vertices, must be outside the
// composed mesh; the depth reported is how deep into the keep-out the material reaches.
json keep_outs_json(const Case& c, const Solid& composed, const Soup& composed_soup, double eps,
                    Random& random, bool& all_empty) {
  json out = json::array();
  for (const auto& l : c.keep_outs) {
    json entry = {{"solid", l->file}, {"name", l->name}};
    if (!l->solid) {
      entry["checked"] = false;
      out.push_back(entry), all_empty = false;
      continue;
    }
    Worst material, vertices;
    long tested = 0;
    for (const auto& p : inner_points(*l, c.samples, 2 * eps, random)) {
      const double depth = l->solid->distance(p);
      if (depth <= eps) continue;
      ++tested;
      if (composed.side(p) == CGAL::ON_BOUNDED_SIDE) material.add(p, depth);
    }
    for (const Point& v : composed_soup.points) {
      if (l->solid->side(v) != CGAL::ON_BOUNDED_SIDE) continue;
      const double depth = l->solid->distance(v);
      if (depth > eps) vertices.add(v, depth);
    }
    entry["checked"] = true;
    entry["points"] = tested;
    material.fill(entry, "material_points", "max_depth");
    entry["vertices_inside"] = vertices.count;
    entry["vertices_max_depth"] = vertices.max;
    if (vertices.at) entry["vertex_at"] = position(*vertices.at);
    all_empty = all_empty && material.count == 0 && vertices.count == 0;
    out.push_back(entry);
  }
  return out;
}

json result_json(const Case& c, const fs::path& result_dir) {
  json out = {{"folder", result_dir.string()}};
  const fs::path path = result_dir / "composed.obj";
  out["present"] = fs::exists(path);
  if (!out["present"]) {
    out["watertight"] = false;
    return out;
  }
  const Soup soup = read_soup(path.string());
  const Topology top = topology(soup);
  out["polygons"] = soup.polygons;
  out["repeated_index_triangles"] = soup.repeated_index_triangles;
  out.update(topology_json(top));
  const SelfIntersections si = self_intersections(soup, c.cap);
  out["self_intersections"] = self_intersections_json(si);
  const bool clean = si.checked && si.pairs == 0;
  const double volume = signed_volume(soup);
  out["volume"] = volume;
  if (c.design->error.empty() && c.design->volume != 0)
    out["volume_vs_design"] = volume / c.design->volume;
  bool outward = false;
  if (top.closed() && top.manifold() && top.consistent() && clean) {
    const Orientation o = orientation(soup);
    outward = o.outward && volume > 0;
    out["orientation"] = {{"checked", true},
                          {"outward", outward},
                          {"volumes", o.volumes},
                          {"shells_facing_wrong_way", o.shells_facing_wrong_way}};
  } else {
    out["orientation"] = {
        {"checked", false}, {"consistent", top.consistent()}, {"positive_volume", volume > 0}};
  }
  bool keep_ins_inside = false, keep_outs_empty = false;
  if (top.closed() && top.manifold()) {
    const Solid composed(soup);
    const double eps = kEpsilonOfTolerance * c.tolerance;
    Random random(kSeed + 1);
    keep_ins_inside = keep_outs_empty = true;
    out["eps"] = eps;
    // Side_of_triangle_mesh counts ray crossings: where shells overlap, the parity is wrong.
    if (!clean)
      out["classification_note"] = "the mesh self-intersects: inside tests are unreliable there";
    out["keep_ins"] = keep_ins_json(c, composed, eps, random, keep_ins_inside);
    out["keep_outs"] = keep_outs_json(c, composed, soup, eps, random, keep_outs_empty);
    out["keep_ins_inside"] = keep_ins_inside;
    out["keep_outs_empty"] = keep_outs_empty;
  } else {
    out["keep_ins_inside"] = "not checked";
    out["keep_outs_empty"] = "not checked";
  }
  out["watertight"] = top.closed() && top.manifold() && top.consistent() && outward && clean &&
                      !si.capped && keep_ins_inside && keep_outs_empty;
  return out;
}

int usage(const std::string& message) {
  std::cerr << "corpus_judge: " << message
            << "\nusage: corpus_judge --case DIR [--result OUTDIR] [--samples N] [--cap N]\n";
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  Case c;
  std::optional<fs::path> result_dir;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (i + 1 >= argc) return usage("missing value after " + arg);
    if (arg == "--case")
      c.dir = argv[++i];
    else if (arg == "--result")
      result_dir = argv[++i];
    else if (arg == "--samples")
      c.samples = std::max(1, std::atoi(argv[++i]));
    else if (arg == "--cap")
      c.cap = std::max(1L, std::atol(argv[++i]));
    else
      return usage("unknown argument " + arg);
  }
  if (c.dir.empty()) return usage("--case DIR is required");
  const auto start = std::chrono::steady_clock::now();
  json out = {{"case", c.dir.string()}, {"samples", c.samples}};
  json errors = json::array();
  try {
    load_case(c, out);
    const json inputs = inputs_json(c);
    out["inputs"] = inputs;
    out["consistency"] = consistency_json(c, inputs);
  } catch (...) {
    errors.push_back("inputs: " + current_message());
  }
  if (result_dir) {
    try {
      if (!c.design) throw std::runtime_error("the case's inputs could not be read");
      out["result"] = result_json(c, *result_dir);
    } catch (...) {
      errors.push_back("result: " + current_message());
      out["result"] = {{"folder", result_dir->string()},
                       {"present", fs::exists(*result_dir / "composed.obj")},
                       {"watertight", false}};
    }
  }
  out["errors"] = errors;
  out["seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::cout << out.dump(2) << '\n';
  return 0;
}

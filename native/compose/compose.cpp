// compose/compose.cpp — §8.2's classification as exact Booleans, provenance, report.
#include "compose/compose.h"

#include <CGAL/AABB_face_graph_triangle_primitive.h>
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/boost/graph/Face_filtered_graph.h>
#include <CGAL/boost/graph/copy_face_graph.h>
#include <CGAL/Polygon_mesh_processing/corefinement.h>
#include <CGAL/Polygon_mesh_processing/orientation.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <functional>
#include <limits>
#include <memory>

#include "core/numbers.h"
#include "compose/detail/establish.h"
#include "compose/detail/exact.h"
#include "mesh/mesh.h"

namespace genbrep {
namespace {

namespace PMP = CGAL::Polygon_mesh_processing;
using detail::ExactMesh;
using Inexact = CGAL::Exact_predicates_inexact_constructions_kernel;
using detail::InexactMesh;
using detail::to_inexact;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Inexact, CGAL::AABB_face_graph_triangle_primitive<InexactMesh>>>;

constexpr const char* kStage = "compose";


// The running Boolean G. `empty` until the first operand: ∅ ∪ X = X, ∅ \ X = ∅. Every
// operand is checked against CGAL's preconditions first (operand.cpp), unless `checked`
// says it already was; G itself is the output of a corefinement, checked by
// exact_boolean. `why` says what failed.
struct Accumulator {
  ExactMesh mesh;
  bool empty = true;
  std::string why;
  bool apply(ExactMesh operand, bool unite, const std::string& what, bool checked = false) {
    const std::string unusable = checked ? std::string() : detail::make_usable(&operand, true);
    if (!unusable.empty()) {
      why = what + " " + unusable;
      return false;
    }
    if (empty) {
      if (unite) mesh = std::move(operand), empty = false;
      return true;
    }
    ExactMesh out;
    if (!detail::exact_boolean(mesh, operand, unite, &out)) {
      why = std::string(unite ? "uniting " : "subtracting ") + what + " gives a non-manifold result";
      return false;
    }
    mesh = std::move(out);
    if (mesh.is_empty()) empty = true;
    return true;
  }
};

// Each solid enters the Booleans grown by its own amount, between 1 and 2 times this
// (× the scene's size): surfaces that coincide or nearly coincide (a keep-out bore in its
// keep-in boss, the design's flat base on a keep-in's face, two flush keep-ins) then lie
// that far apart or cross by that much, instead of being cut into slivers thinner than a
// double can hold, which no rounding keeps from folding (docs/compose_method.md).
constexpr double kGrow = 1e-6;

// The solids as the Booleans take them: solid s of n grown by kGrow × scale × (1 + s/n)
// (detail::grown), or as given where growing it would make it unusable. `moved`: the
// farthest any vertex moved.
SolidSet grown_solids(const SolidSet& solids, double scale, double* moved) {
  *moved = 0;
  std::vector<SolidInput> grown;
  const int n = solids.size();
  for (int s = 0; s < n; ++s) {
    SolidInput solid = solids.input(s);
    TriangleMesh moved_mesh = detail::grown(solid.mesh, kGrow * scale * (1.0 + static_cast<double>(s) / n));
    detail::ExactMesh check = detail::to_exact(moved_mesh);
    if (detail::make_usable(&check, true).empty()) {
      *moved = std::max(*moved, (moved_mesh.vertices - solid.mesh.vertices).rowwise().norm().maxCoeff());
      solid.mesh = std::move(moved_mesh);
    }
    grown.push_back(std::move(solid));
  }
  Diagnostics unused;  // overlaps were noted for the solids as given
  return SolidSet(std::move(grown), &unused);
}

void note_grown(double moved, ComposeReport* report) {
  if (moved == 0) return;
  report->notes.push_back("solid faces lie up to " + format_number(moved, 2) +
                          " outside the input solids: each solid was grown by its own 1-2 x " +
                          format_number(kGrow, 2) + " of the scene's size before the Booleans, so that nearly "
                          "coincident surfaces are cut cleanly");
}

// Per face: the first solid whose triangles hold all three corners (to 1e-9 relative,
// the rounding of intersection vertices), else the nearest trimmed organic sheet.
std::vector<int> face_sources(const TriangleMesh& mesh, const SolidSet& solids,
                              const std::vector<detail::OrganicCell>& cells, double scale) {
  std::vector<InexactMesh> meshes;
  std::vector<std::unique_ptr<Tree>> trees;
  for (int s = 0; s < solids.size(); ++s) meshes.push_back(to_inexact(solids.input(s).mesh));
  for (const auto& c : cells) meshes.push_back(to_inexact(detail::to_double(c.trimmed)));
  for (const auto& m : meshes) {
    trees.push_back(std::make_unique<Tree>(faces(m).first, faces(m).second, m));
    trees.back()->accelerate_distance_queries();
  }
  const double tolerance = 1e-9 * scale;
  std::vector<int> source(static_cast<size_t>(mesh.triangles.rows()), std::numeric_limits<int>::min());
  for (Eigen::Index f = 0; f < mesh.triangles.rows(); ++f) {
    auto point = [&](int k) {
      const auto v = mesh.vertices.row(mesh.triangles(f, k));
      return Inexact::Point_3(v(0), v(1), v(2));
    };
    const auto centroid = CGAL::centroid(point(0), point(1), point(2));
    for (int s = 0; s < solids.size() && source[f] == std::numeric_limits<int>::min(); ++s) {
      bool on = trees[s]->squared_distance(centroid) <= tolerance * tolerance;
      for (int k = 0; k < 3 && on; ++k) on = trees[s]->squared_distance(point(k)) <= tolerance * tolerance;
      if (on) source[f] = s;
    }
    if (source[f] != std::numeric_limits<int>::min()) continue;
    double best = std::numeric_limits<double>::infinity();
    for (size_t c = 0; c < cells.size(); ++c) {
      const double d = CGAL::to_double(trees[solids.size() + c]->squared_distance(centroid));
      if (d < best) best = d, source[f] = organic_source(cells[c].component);
    }
  }
  return source;
}

void measure(const TriangleMesh& mesh, ComposeReport* report) {
  const MeshValidation v = validate(mesh);
  report->vertices = v.vertices;
  report->triangles = v.triangles;
  report->boundary_edges = v.boundary_edges;
  report->non_manifold_edges = v.non_manifold_edges;
  report->non_manifold_vertices = v.non_manifold_vertices;
  report->inconsistent_edges = v.inconsistent_edges;
  report->volume = v.signed_volume;
  report->shells = v.shells;
  const InexactMesh m = to_inexact(mesh);
  report->self_intersecting = v.triangles > 0 && PMP::does_self_intersect(m);
  // Euler: χ = V − E + F = Σ (2 − 2 g_i) over closed shells.
  const long euler = static_cast<long>(m.number_of_vertices()) - static_cast<long>(m.number_of_edges()) +
                     static_cast<long>(m.number_of_faces());
  report->genus = static_cast<int>((2L * v.shells - euler) / 2);
  report->ok = v.closed_manifold() && !report->self_intersecting && v.signed_volume > 0;
}

std::string number(double x) { return format_number(x, 2); }

std::string point_text(const Vec3& p) {
  char buffer[96];
  std::snprintf(buffer, sizeof buffer, "(%.4g, %.4g, %.4g)", p.x(), p.y(), p.z());
  return buffer;
}

// Which solids the collapsed slivers lie on (within 1e-9 × scale), for the report.
std::string near_coincidence(const detail::Rounded& rounded, const SolidSet& solids, double scale) {
  std::string names;
  for (int s = 0; s < solids.size(); ++s) {
    const bool near = std::any_of(rounded.where.begin(), rounded.where.end(),
                                  [&](const Vec3& p) { return solids.surface(s).distance(p) <= 1e-9 * scale; });
    if (near) names += (names.empty() ? "" : ", ") + solids.describe(s);
  }
  std::string text = "rounding to doubles: collapsed " + std::to_string(rounded.collapsed) +
                     " edges up to " + number(rounded.longest) + " long (slivers where operands nearly coincide";
  if (!names.empty()) text += ": " + names;
  text += rounded.where.empty() ? ")" : ", e.g. at " + point_text(rounded.where.front()) + ")";
  if (rounded.blocked > 0) text += "; " + std::to_string(rounded.blocked) + " left, collapsing them would pinch the surface";
  return text;
}

// Where the returned mesh intersects itself, by face source, for the report.
std::string intersecting_pairs(const TriangleMesh& mesh, const SolidSet& solids) {
  const InexactMesh m = to_inexact(mesh);
  std::vector<std::pair<InexactMesh::Face_index, InexactMesh::Face_index>> pairs;
  PMP::self_intersections(m, std::back_inserter(pairs));
  auto source = [&](InexactMesh::Face_index f) {
    const int s = mesh.triangle_source[static_cast<size_t>(f)];
    return s >= 0 ? solids.describe(s) : "organic component " + std::to_string(-1 - s);
  };
  std::string text = "the composed mesh intersects itself: " + std::to_string(pairs.size()) + " triangle pairs";
  if (!pairs.empty()) {
    const auto [f, g] = pairs.front();
    const Vec3 at = mesh.vertices.row(mesh.triangles(static_cast<Eigen::Index>(f), 0)).transpose();
    text += ", e.g. " + source(f) + " against " + source(g) + " at " + point_text(at);
  }
  return text;
}

// The corefinement's vertex and face order depends on where its points were allocated, so
// the same input gave the same solid in a different order from run to run (and a
// different composed.obj). Vertices are put in lexicographic order (ties keep their
// order), each triangle starts at its smallest vertex (orientation kept) and triangles are
// sorted: the same solid is then the same arrays.
TriangleMesh canonical_order(const TriangleMesh& mesh) {
  const Eigen::Index nv = mesh.vertices.rows(), nt = mesh.triangles.rows();
  std::vector<int> order(static_cast<size_t>(nv));
  for (Eigen::Index v = 0; v < nv; ++v) order[static_cast<size_t>(v)] = static_cast<int>(v);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    for (int k = 0; k < 3; ++k)
      if (mesh.vertices(a, k) != mesh.vertices(b, k)) return mesh.vertices(a, k) < mesh.vertices(b, k);
    return false;
  });
  TriangleMesh out;
  out.vertices.resize(nv, 3);
  std::vector<int> renamed(static_cast<size_t>(nv));
  for (size_t i = 0; i < order.size(); ++i) {
    out.vertices.row(static_cast<Eigen::Index>(i)) = mesh.vertices.row(order[i]);
    renamed[static_cast<size_t>(order[i])] = static_cast<int>(i);
  }
  std::vector<std::array<int, 3>> triangles(static_cast<size_t>(nt));
  for (Eigen::Index t = 0; t < nt; ++t) {
    std::array<int, 3> c{renamed[mesh.triangles(t, 0)], renamed[mesh.triangles(t, 1)],
                         renamed[mesh.triangles(t, 2)]};
    std::rotate(c.begin(), std::min_element(c.begin(), c.end()), c.end());
    triangles[static_cast<size_t>(t)] = c;
  }
  std::sort(triangles.begin(), triangles.end());
  out.triangles.resize(nt, 3);
  for (Eigen::Index t = 0; t < nt; ++t)
    for (int k = 0; k < 3; ++k) out.triangles(t, k) = triangles[static_cast<size_t>(t)][k];
  return out;
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// §8.2 as Booleans: G = (((P \ bites) ∪ additive Q) ∪ K) \ L. False with the reason in
// g->why when an operand breaks a precondition or a Boolean is not manifold.
bool classify(const std::vector<detail::OrganicCell>& cells, const SolidSet& solids, const Context& context,
              ComposeReport* report, Accumulator* g) {
  bool ok = true;
  auto solid_pass = [&](Role role, bool unite) {
    for (int s = 0; s < solids.size() && ok; ++s) {
      if (solids.input(s).role != role) continue;
      ++report->solid_cells;
      ok = g->apply(detail::to_exact(solids.input(s).mesh), unite, solids.describe(s));
      context.step(kStage, 0.5 + 0.4 * s / std::max(1, solids.size()));
    }
  };
  auto cell_pass = [&](bool additive) {
    for (const auto& c : cells) {
      if (c.additive != additive || !ok) continue;
      ++report->organic_cells;
      ExactMesh operand = c.closed;
      if (!additive) PMP::reverse_face_orientations(operand);  // the bite as a solid
      ok = g->apply(operand, additive, "organic component " + std::to_string(c.component), c.usable);
    }
  };
  solid_pass(Role::Seed, true);
  cell_pass(false);
  cell_pass(true);
  solid_pass(Role::KeepIn, true);
  solid_pass(Role::KeepOut, false);
  if (ok && g->empty) g->why = "the composition is empty";
  return ok && !g->empty;
}

// The floor: G = (D ∪ K) \ L, the design with the keep-ins added and the keep-outs
// removed, exactly. Seeds are not added: where the design lies on a seed it holds the
// seed's material, and what it leaves out of a seed was eroded.
bool design_boolean(const TriangleMesh& design, const SolidSet& solids, const Context& context,
                    Accumulator* g) {
  if (!g->apply(detail::to_exact(design), true, "the design")) return false;
  for (const Role role : {Role::KeepIn, Role::KeepOut}) {
    for (int s = 0; s < solids.size(); ++s) {
      if (solids.input(s).role != role) continue;
      if (!g->apply(detail::to_exact(solids.input(s).mesh), role == Role::KeepIn, solids.describe(s))) return false;
      context.step(kStage, 0.9);
    }
  }
  if (g->empty) g->why = "the design Boolean is empty";
  return !g->empty;
}

// The exact G rounded to doubles without new crossings (round.cpp), ordered, with face
// sources, measured into out->report.
void finish(const ExactMesh& exact, const SolidSet& solids, const std::vector<detail::OrganicCell>& cells,
            double scale, Composed* out) {
  auto& report = out->report;
  const detail::Rounded rounded = detail::round_robustly(exact, scale);
  out->mesh = canonical_order(rounded.mesh);
  out->mesh.triangle_source = face_sources(out->mesh, solids, cells, scale);
  report.solid_faces = report.organic_faces = 0;
  for (int s : out->mesh.triangle_source) (s >= 0 ? report.solid_faces : report.organic_faces) += 1;
  measure(out->mesh, &report);
  if (rounded.collapsed > 0 || rounded.blocked > 0) report.diagnostics.push_back(near_coincidence(rounded, solids, scale));
  if (rounded.repaired)
    report.notes.push_back(std::string("rounding to doubles crossed slivers over their neighbours; the crossing "
                                       "faces were removed and the holes refilled locally") +
                           (report.self_intersecting ? ", still crossing" : ", now free of crossings"));
  else if (rounded.refined > 0)
    report.notes.push_back("rounding to doubles crossed slivers over their neighbours; autorefined " +
                           std::to_string(rounded.refined) + (rounded.refined == 1 ? " time" : " times") +
                           (report.self_intersecting ? ", still crossing" : ", now free of crossings"));
  if (report.self_intersecting) report.diagnostics.push_back(intersecting_pairs(out->mesh, solids));
}

// The design's own material outside the keep-ins (grown, as the Booleans take them):
// D \ K exactly, split into volumes (closed, outward). Each piece borders the keep-ins on
// their grown faces exactly, as the organic cells' caps do. Empty with `why` set when a
// Boolean fails.
std::vector<ExactMesh> design_pieces(const TriangleMesh& design, const SolidSet& grown, std::string* why) {
  Accumulator g;
  bool ok = g.apply(detail::to_exact(design), true, "the design");
  for (int s = 0; s < grown.size() && ok; ++s) {
    if (grown.input(s).role != Role::KeepIn) continue;
    ok = g.apply(detail::to_exact(grown.input(s).mesh), false, grown.describe(s));
  }
  if (!ok || g.empty) {
    *why = ok ? "the design lies inside the keep-ins" : g.why;
    return {};
  }
  auto volume = g.mesh.add_property_map<ExactMesh::Face_index, std::size_t>("f:volume", 0).first;
  const std::size_t n = PMP::volume_connected_components(g.mesh, volume);
  std::vector<ExactMesh> pieces(n);
  for (std::size_t k = 0; k < n; ++k)
    CGAL::copy_face_graph(CGAL::Face_filtered_graph<ExactMesh>(g.mesh, k, volume), pieces[k]);
  return pieces;
}

// Which pieces each sheet's vertices lie on: per sheet, the pieces nearest to at least a
// tenth of its vertices (a design region is within the tolerance of the design's surface,
// and its material is the piece behind that surface).
std::vector<std::vector<int>> pieces_of(const std::vector<ExactMesh>& pieces,
                                        const std::vector<const OrganicSheet*>& sheets) {
  std::vector<InexactMesh> meshes;
  std::vector<std::unique_ptr<Tree>> trees;
  for (const auto& piece : pieces) {
    meshes.push_back(to_inexact(detail::to_double(piece)));
  }
  for (const auto& m : meshes) {
    trees.push_back(std::make_unique<Tree>(faces(m).first, faces(m).second, m));
    trees.back()->accelerate_distance_queries();
  }
  std::vector<std::vector<int>> out;
  for (const OrganicSheet* sheet : sheets) {
    std::vector<int> votes(pieces.size(), 0);
    const Eigen::Index nv = sheet ? sheet->mesh.vertices.rows() : 0;
    for (Eigen::Index v = 0; v < nv; ++v) {
      const Inexact::Point_3 p(sheet->mesh.vertices(v, 0), sheet->mesh.vertices(v, 1), sheet->mesh.vertices(v, 2));
      double best = std::numeric_limits<double>::infinity();
      int nearest = -1;
      for (size_t k = 0; k < trees.size(); ++k) {
        const double d = CGAL::to_double(trees[k]->squared_distance(p));
        if (d < best) best = d, nearest = static_cast<int>(k);
      }
      if (nearest >= 0) ++votes[static_cast<size_t>(nearest)];
    }
    std::vector<int> mine;
    for (size_t k = 0; k < votes.size(); ++k)
      if (votes[k] > 0 && 10 * votes[k] >= nv) mine.push_back(static_cast<int>(k));
    out.push_back(mine);
  }
  return out;
}

// `contact` took a lower tier because of `why` (the higher tier's diagnostics): its
// fallback reason is `reason` with the first of them and `tail`; its diagnostics start with
// "organic component N: <reason>, composed from <what>" and `why`, indented.
void fell_back(ComponentContact* contact, const Diagnostics& why, const std::string& reason, const std::string& tail,
               const std::string& what) {
  contact->fallback = reason + (why.empty() ? std::string() : " (" + why.front() + ")") + tail;
  Diagnostics lines{"organic component " + std::to_string(contact->component) + ": " + reason +
                    ", composed from " + what};
  for (const auto& w : why) lines.push_back("  cage: " + w);
  contact->diagnostics.insert(contact->diagnostics.begin(), lines.begin(), lines.end());
}

// Composes the components that have a cell from it, and every other component from its
// part of the design solid (design_pieces): the pieces its design region lies on; a
// component with a cell that shares a piece with one without gives its cell up for it.
// False (out->contacts and report untouched but for diagnostics) where that cannot be done
// or composed: a component without a cell borders a seed (its bite would be lost) or has
// no design region, a bite would have to give its cell up, or the Booleans or the
// rounding fail.
bool by_component(const TriangleMesh& design, const std::vector<OrganicSurface>& surfaces,
                  const SolidSet& grown, const std::vector<size_t>& contact_surface,
                  const std::vector<int>& contact_cell, const std::vector<detail::OrganicCell>& cells,
                  double growth, double scale, const Context& context, Composed* out) {
  const size_t n = contact_surface.size();
  std::vector<char> from_design(n, 0);
  for (size_t c = 0; c < n; ++c) {
    if (contact_cell[c] >= 0) continue;
    const OrganicSheet& sheet = surfaces[contact_surface[c]].sheet;
    if (sheet.mesh.triangles.rows() == 0) return false;
    for (const auto& loop : sheet.loops)
      for (int s : loop.solids)
        if (grown.input(s).role == Role::Seed) return false;
    from_design[c] = 1;
  }
  std::string why;
  const std::vector<ExactMesh> pieces = design_pieces(design, grown, &why);
  if (pieces.empty()) {
    out->report.diagnostics.push_back("the design solid (the design less the keep-ins) cannot be composed: " + why);
    return false;
  }
  std::vector<const OrganicSheet*> sheets;
  for (size_t c = 0; c < n; ++c) {
    const OrganicSheet& sheet = surfaces[contact_surface[c]].sheet;
    sheets.push_back(sheet.mesh.triangles.rows() > 0 ? &sheet : nullptr);
  }
  const std::vector<std::vector<int>> near = pieces_of(pieces, sheets);
  std::vector<char> taken(pieces.size(), 0);
  for (bool changed = true; changed;) {
    changed = false;
    for (size_t c = 0; c < n; ++c) {
      if (from_design[c]) {
        if (near[c].empty()) return false;
        for (int k : near[c]) changed = changed || !taken[static_cast<size_t>(k)], taken[static_cast<size_t>(k)] = 1;
      } else if (std::any_of(near[c].begin(), near[c].end(), [&](int k) { return taken[static_cast<size_t>(k)]; })) {
        if (!cells[static_cast<size_t>(contact_cell[c])].additive) return false;
        from_design[c] = 1, changed = true;
      }
    }
  }
  // The operands: the kept cells and the pieces; for face sources, the kept cells and the
  // design regions of the others.
  std::vector<detail::OrganicCell> operands, sources;
  std::string names;
  for (size_t c = 0; c < n; ++c) {
    if (!from_design[c]) {
      operands.push_back(cells[static_cast<size_t>(contact_cell[c])]);
      sources.push_back(cells[static_cast<size_t>(contact_cell[c])]);
      continue;
    }
    detail::OrganicCell region;
    region.component = out->contacts[c].component;
    region.trimmed = detail::to_exact(surfaces[contact_surface[c]].sheet.mesh);
    sources.push_back(std::move(region));
    names += (names.empty() ? "" : ", ") + std::to_string(out->contacts[c].component);
  }
  for (size_t k = 0; k < pieces.size(); ++k) {
    if (!taken[k]) continue;
    detail::OrganicCell piece;
    piece.closed = pieces[k];
    piece.additive = true;
    piece.usable = true;  // a volume of an exact Boolean's result: closed, outward, not crossing
    piece.volume = detail::signed_volume(piece.closed);
    operands.push_back(std::move(piece));
  }
  auto& report = out->report;
  const ComposeReport before = report;
  Accumulator g;
  if (!classify(operands, grown, context, &report, &g)) {
    report = before;
    report.diagnostics.push_back("composing the organic components without a working tier from their part of "
                                 "the design solid: " + g.why);
    return false;
  }
  finish(g.mesh, grown, sources, scale, out);
  if (!report.ok) {
    report = before;
    report.diagnostics.push_back("composing the organic components without a working tier from their part of "
                                 "the design solid: " +
                                 std::string(report.self_intersecting ? "the composed mesh intersects itself"
                                                                      : "the composed mesh is not closed"));
    return false;
  }
  note_grown(growth, &report);
  for (size_t c = 0; c < n; ++c) {
    if (!from_design[c]) continue;
    ComponentContact& contact = out->contacts[c];
    if (contact_cell[c] >= 0) {
      contact.fallback = "its part of the design solid is shared with an organic component no tier composed";
    } else {
      contact.fallback = contact.diagnostics.empty() ? "no tier composed it" : contact.diagnostics.back();
    }
    contact.surface = "design solid";
  }
  report.diagnostics.push_back("organic component" + std::string(names.find(',') == std::string::npos ? " " : "s ") +
                               names + ": composed from their part of the design solid (the design less the "
                               "keep-ins), the other components from their own cells");
  return true;
}

}  // namespace

std::vector<std::string> fallbacks(const Composed& composed) {
  std::vector<std::string> lines;
  if (!composed.report.ok) return lines;  // nothing was composed: the diagnostics say why
  for (const auto& c : composed.contacts) {
    if (c.fallback.empty()) continue;
    lines.push_back("organic component " + std::to_string(c.component) + ": composed from the " + c.surface +
                    ": " + c.fallback);
  }
  return lines;
}

Composed compose(const std::vector<OrganicSheet>& sheets, const SolidSet& solids,
                 const ComposeOptions& options, const Context& context, const TriangleMesh* design) {
  std::vector<OrganicSurface> surfaces;
  for (const auto& sheet : sheets) surfaces.push_back({sheet, std::nullopt, {}});
  return compose(surfaces, solids, options, context, design);
}

Composed compose(const std::vector<OrganicSurface>& surfaces, const SolidSet& solids,
                 const ComposeOptions& options, const Context& context, const TriangleMesh* design) {
  Composed out;
  auto& report = out.report;
  double scale = 0;
  for (int s = 0; s < solids.size(); ++s) {
    scale = std::max(scale, bounding_box_diagonal(solids.input(s).mesh.vertices));
  }
  for (const auto& surface : surfaces) {
    if (surface.sheet.mesh.vertices.rows() > 0) scale = std::max(scale, bounding_box_diagonal(surface.sheet.mesh.vertices));
    if (surface.cage) scale = std::max(scale, bounding_box_diagonal(surface.cage->vertices));
  }
  if (design) scale = std::max(scale, bounding_box_diagonal(design->vertices));
  double growth = 0;
  const SolidSet grown = grown_solids(solids, scale, &growth);
  // §7: contact per component, from its cage when it has one, else (or when the cage cannot
  // be pulled) from its design region; cut at the grown solids the Booleans take, so that
  // the caps cut out of ∂S lie exactly on their faces. An Error from a tier (other than a
  // cancel) is that tier failing, with its message as the reason.
  auto start = std::chrono::steady_clock::now();
  std::vector<detail::OrganicCell> cells;
  std::vector<size_t> contact_surface;  // per contact: its index in `surfaces`
  std::vector<int> contact_cell;        // per contact: its index in `cells`, or -1 (no tier)
  std::string failed;  // the first component no tier could compose, and why
  auto attempt = [&](const std::function<ComponentContact(detail::OrganicCell*)>& tier, int component,
                     const char* what, detail::OrganicCell* cell) {
    try {
      return tier(cell);
    } catch (const Error& e) {
      if (e.code() == Code::Cancelled) throw;
      ComponentContact contact;
      contact.component = component;
      contact.diagnostics.push_back("organic component " + std::to_string(component) + ": its " + what +
                                    " cannot be composed: " + e.what());
      *cell = detail::OrganicCell();
      return contact;
    }
  };
  for (size_t i = 0; i < surfaces.size(); ++i) {
    context.step(kStage, 0.5 * i / std::max<size_t>(1, surfaces.size()));
    const OrganicSurface& surface = surfaces[i];
    const int component = surface.sheet.component;
    const bool has_sheet = surface.sheet.mesh.triangles.rows() > 0;
    if (!surface.cage && !has_sheet) continue;
    detail::OrganicCell cell;
    ComponentContact contact;
    auto region = [&](detail::OrganicCell* c) { return detail::establish(surface.sheet, solids, grown, options, c); };
    if (surface.cage) {
      contact = attempt(
          [&](detail::OrganicCell* c) {
            return detail::establish_cage(*surface.cage, surface.chain_solids, solids, grown, options, c);
          },
          component, "cage", &cell);
      // Tier 2: the cage extended into its solids by one row of quads, where pulling the
      // fitted boundary in folds or stops short.
      if (!contact.established) {
        Diagnostics why = contact.diagnostics;
        ComponentContact extended = attempt(
            [&](detail::OrganicCell* c) {
              const ExtendedCage e = extend_cage(*surface.cage, surface.chain_solids, solids);
              if (!e.extended) {
                ComponentContact none;
                none.component = component;
                none.diagnostics.push_back("organic component " + std::to_string(component) +
                                           ": its cage cannot be extended into the solids: " + e.problem);
                return none;
              }
              ComponentContact r =
                  detail::establish_cage(e.cage, surface.chain_solids, solids, grown, options, c, e.sides);
              r.surface = "extended cage";
              return r;
            },
            component, "extended cage", &cell);
        if (extended.established) {
          fell_back(&extended, why, "its cage as fitted could not be pulled into the solids",
                    "; extended into them by a row of quads", "the cage extended into them");
          contact = std::move(extended);
        } else {
          for (const auto& d : extended.diagnostics) contact.diagnostics.push_back(d);
        }
      }
      if (!contact.established && has_sheet) {
        Diagnostics why = contact.diagnostics;
        contact = attempt(region, component, "design region", &cell);
        fell_back(&contact, why, "its cage could not be pulled into the solids", "", "the design region instead");
      }
    } else {
      contact = attempt(region, component, "design region", &cell);
    }
    contact_surface.push_back(i);
    contact_cell.push_back(contact.established ? static_cast<int>(cells.size()) : -1);
    if (contact.established) {
      cells.push_back(std::move(cell));
    } else if (failed.empty()) {
      failed = "organic component " + std::to_string(component) + " could not be composed" +
               (contact.diagnostics.empty() ? std::string() : " (" + contact.diagnostics.back() + ")");
    }
    out.contacts.push_back(std::move(contact));
    for (const auto& d : out.contacts.back().diagnostics) report.diagnostics.push_back(d);
  }
  report.seconds_contact = seconds_since(start);
  start = std::chrono::steady_clock::now();
  if (failed.empty()) {
    Accumulator g;
    if (classify(cells, grown, context, &report, &g)) {
      // Rule 4: a cell bounded by organic faces of both orientations (two organic cells
      // that overlap, or an organic surface running through a keep-in) is inside; say so.
      for (size_t a = 0; a < cells.size(); ++a) {
        for (size_t b = a + 1; b < cells.size(); ++b) {
          ExactMesh x = cells[a].closed, y = cells[b].closed;
          if (PMP::do_intersect(x, y)) {
            report.diagnostics.push_back("organic components " + std::to_string(cells[a].component) + " and " +
                                         std::to_string(cells[b].component) +
                                         " overlap: cells seen from both orientations are classified "
                                         "inside (§8.2 rule 4); the input is invalid there");
          }
        }
      }
      report.seconds_boolean = seconds_since(start);
      finish(g.mesh, grown, cells, scale, &out);
      if (report.ok) {
        note_grown(growth, &report);
        return out;
      }
      failed = report.self_intersecting ? "the composed mesh intersects itself after rounding to doubles"
                                        : "the composed mesh is not a closed 2-manifold bounding a volume";
    } else {
      failed = g.why;
    }
  }
  // Components no tier composed take their part of the design solid and the others keep
  // their cells (by_component); only where that fails does every component fall to the floor.
  if (!failed.empty() && design &&
      by_component(*design, surfaces, grown, contact_surface, contact_cell, cells, growth, scale, context, &out)) {
    report.seconds_boolean = seconds_since(start);
    return out;
  }
  report.diagnostics.push_back("the organic components cannot all be composed: " + failed);
  if (!design) return out;
  // The floor: the whole design as an exact Boolean with the solids, grown as for the tiers
  // above; where that cannot be composed (a grown solid running into a feature of the
  // design finer than the growth), again with the solids as given.
  // Faces off the solids are attributed to the nearest component's design region.
  cells.clear();
  for (const auto& surface : surfaces) {
    if (surface.sheet.mesh.triangles.rows() == 0) continue;
    cells.emplace_back();
    cells.back().component = surface.sheet.component;
    cells.back().trimmed = detail::to_exact(surface.sheet.mesh);
  }
  const size_t diagnostics_before = report.diagnostics.size(), notes_before = report.notes.size();
  bool composed = false;
  std::string why[2];  // why each attempt could not compose: grown, as given
  for (int attempt = 0; attempt < 2; ++attempt) {
    const SolidSet& operands = attempt == 0 ? grown : solids;
    Accumulator g;
    if (!design_boolean(*design, operands, context, &g)) {
      why[attempt] = g.why;
      continue;
    }
    if (composed) {
      // The first result could not be composed: its words give way to this one's.
      report.diagnostics.resize(diagnostics_before);
      report.notes.resize(notes_before);
      report.notes.push_back("the design Boolean with the solids grown could not be composed; composed "
                             "again with the solids as given");
    }
    finish(g.mesh, operands, cells, scale, &out);
    composed = true;
    if (report.ok && attempt == 0) note_grown(growth, &report);
    if (report.ok) break;
  }
  report.seconds_boolean = seconds_since(start);
  if (composed && !report.ok && !why[1].empty())
    report.diagnostics.push_back("with the solids as given, the design Boolean cannot be composed: " + why[1]);
  if (!composed) {
    report.ok = false;
    report.diagnostics.push_back("the design Boolean (the design with the keep-ins added and the keep-outs "
                                 "removed) cannot be composed either: " + why[0] +
                                 (why[1] != why[0] ? "; with the solids as given: " + why[1] : std::string()));
    return out;
  }
  report.floor = true;
  report.organic_cells = 0;
  report.solid_cells = 0;
  for (auto& contact : out.contacts) {
    contact.fallback = contact.established ? failed : (contact.diagnostics.empty() ? failed : contact.diagnostics.back());
    contact.surface = "design Boolean";
  }
  report.diagnostics.push_back("composed as the design Boolean (the design with the keep-ins added and the "
                               "keep-outs removed), because " + failed);
  return out;
}

}  // namespace genbrep

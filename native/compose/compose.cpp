// compose/compose.cpp — §8.2's classification as exact Booleans, provenance, report.
#include "compose/compose.h"

#include <CGAL/AABB_face_graph_triangle_primitive.h>
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/corefinement.h>
#include <CGAL/Polygon_mesh_processing/orientation.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <limits>

#include "compose/detail/establish.h"
#include "compose/detail/exact.h"
#include "mesh/mesh.h"

namespace genbrep {
namespace {

namespace PMP = CGAL::Polygon_mesh_processing;
using detail::ExactMesh;
using Inexact = CGAL::Exact_predicates_inexact_constructions_kernel;
using InexactMesh = CGAL::Surface_mesh<Inexact::Point_3>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Inexact, CGAL::AABB_face_graph_triangle_primitive<InexactMesh>>>;

constexpr const char* kStage = "compose";

InexactMesh to_inexact(const TriangleMesh& mesh) {
  InexactMesh out;
  for (Eigen::Index v = 0; v < mesh.vertices.rows(); ++v) {
    out.add_vertex(Inexact::Point_3(mesh.vertices(v, 0), mesh.vertices(v, 1), mesh.vertices(v, 2)));
  }
  for (Eigen::Index t = 0; t < mesh.triangles.rows(); ++t) {
    out.add_face(InexactMesh::Vertex_index(static_cast<unsigned>(mesh.triangles(t, 0))),
                 InexactMesh::Vertex_index(static_cast<unsigned>(mesh.triangles(t, 1))),
                 InexactMesh::Vertex_index(static_cast<unsigned>(mesh.triangles(t, 2))));
  }
  return out;
}

// The running Boolean G. `empty` until the first operand: ∅ ∪ X = X, ∅ \ X = ∅.
struct Accumulator {
  ExactMesh mesh;
  bool empty = true;
  Diagnostics* diagnostics;

  bool apply(const ExactMesh& operand, bool unite, const std::string& what) {
    if (empty) {
      if (unite) mesh = operand, empty = false;
      return true;
    }
    ExactMesh a = mesh, b = operand, out;
    const bool ok = unite ? PMP::corefine_and_compute_union(a, b, out)
                          : PMP::corefine_and_compute_difference(a, b, out);
    if (!ok) {
      diagnostics->push_back(std::string(unite ? "uniting " : "subtracting ") + what +
                             " gives a non-manifold result");
      return false;
    }
    mesh = std::move(out);
    if (mesh.is_empty()) empty = true;
    return true;
  }
};

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

std::string number(double x) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.2g", x);
  return buffer;
}

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

}  // namespace

Composed compose(const std::vector<OrganicSheet>& sheets, const SolidSet& solids,
                 const ComposeOptions& options, const Context& context) {
  std::vector<OrganicSurface> surfaces;
  for (const auto& sheet : sheets) surfaces.push_back({sheet, std::nullopt, {}});
  return compose(surfaces, solids, options, context);
}

Composed compose(const std::vector<OrganicSurface>& surfaces, const SolidSet& solids,
                 const ComposeOptions& options, const Context& context) {
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
  // §7: contact per component, from its cage when it has one.
  auto start = std::chrono::steady_clock::now();
  std::vector<detail::OrganicCell> cells;
  bool contact_ok = true;
  for (size_t i = 0; i < surfaces.size(); ++i) {
    context.step(kStage, 0.5 * i / std::max<size_t>(1, surfaces.size()));
    const OrganicSurface& surface = surfaces[i];
    const bool has_sheet = surface.sheet.mesh.triangles.rows() > 0;
    if (!surface.cage && !has_sheet) continue;
    detail::OrganicCell cell;
    ComponentContact contact;
    if (surface.cage) {
      try {
        contact = detail::establish_cage(*surface.cage, surface.chain_solids, solids, options, &cell);
      } catch (const Error& e) {
        // A cage edited into something the pull cannot use (e.g. not 2-manifold) is
        // reported like a pull that does not converge; the design region stands in.
        if (e.code() == Code::Cancelled) throw;
        contact = ComponentContact();
        contact.component = surface.sheet.component;
        contact.diagnostics.push_back("organic component " + std::to_string(surface.sheet.component) +
                                      ": its cage cannot be pulled: " + e.what());
        cell = detail::OrganicCell();
      }
      if (!contact.established && has_sheet) {
        Diagnostics why = contact.diagnostics;
        contact = detail::establish(surface.sheet, solids, options, &cell);
        contact.diagnostics.insert(contact.diagnostics.begin(),
                                   "organic component " + std::to_string(surface.sheet.component) +
                                       ": its cage could not be pulled into the solids, composed from "
                                       "the design region instead");
        for (size_t k = 0; k < why.size(); ++k) {
          contact.diagnostics.insert(contact.diagnostics.begin() + 1 + static_cast<long>(k), "  cage: " + why[k]);
        }
      }
    } else {
      contact = detail::establish(surface.sheet, solids, options, &cell);
    }
    out.contacts.push_back(std::move(contact));
    const auto& added = out.contacts.back();
    for (const auto& d : added.diagnostics) report.diagnostics.push_back(d);
    if (added.established) {
      cells.push_back(std::move(cell));
    } else if (surface.cage ? !surface.cage->boundary_chains.empty() : !surface.sheet.loops.empty()) {
      contact_ok = false;
    }
  }
  report.seconds_contact = seconds_since(start);
  if (!contact_ok) return out;  // a named diagnostic says which component and why
  // §8.2 as Booleans: G = (((P \ bites) ∪ additive Q) ∪ K) \ L.
  start = std::chrono::steady_clock::now();
  Accumulator g{{}, true, &report.diagnostics};
  bool ok = true;
  auto solid_pass = [&](Role role, bool unite) {
    for (int s = 0; s < solids.size() && ok; ++s) {
      if (solids.input(s).role != role) continue;
      ++report.solid_cells;
      ok = g.apply(detail::to_exact(solids.input(s).mesh), unite, solids.describe(s));
      context.step(kStage, 0.5 + 0.5 * s / std::max(1, solids.size()));
    }
  };
  auto cell_pass = [&](bool additive) {
    for (const auto& c : cells) {
      if (c.additive != additive || !ok) continue;
      ++report.organic_cells;
      ExactMesh operand = c.closed;
      if (!additive) PMP::reverse_face_orientations(operand);  // the bite as a solid
      ok = g.apply(operand, additive, "organic component " + std::to_string(c.component));
    }
  };
  solid_pass(Role::Seed, true);
  cell_pass(false);
  cell_pass(true);
  solid_pass(Role::KeepIn, true);
  solid_pass(Role::KeepOut, false);
  // Rule 4: a cell bounded by organic faces of both orientations (two organic cells that
  // overlap, or an organic surface running through a keep-in) is inside; say so.
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
  if (!ok || g.empty) {
    if (g.empty) report.diagnostics.push_back("the composition is empty");
    return out;
  }
  // Edges below 1e-10 × the scene come from operands that nearly coincide; collapsed
  // before rounding (round.cpp), 10× below the 1e-9 to which faces are matched to solids.
  detail::Rounded rounded = detail::round_to_doubles(std::move(g.mesh), 1e-10 * scale);
  out.mesh = canonical_order(rounded.mesh);
  if (rounded.collapsed > 0 || rounded.blocked > 0) report.diagnostics.push_back(near_coincidence(rounded, solids, scale));
  out.mesh.triangle_source = face_sources(out.mesh, solids, cells, scale);
  for (int s : out.mesh.triangle_source) (s >= 0 ? report.solid_faces : report.organic_faces) += 1;
  measure(out.mesh, &report);
  if (report.self_intersecting) report.diagnostics.push_back(intersecting_pairs(out.mesh, solids));
  return out;
}

}  // namespace genbrep

// compose/establish.cpp — §7.3: pull with η doubling until C ≅ ∂O; §9.1 gap naming.
#include <cmath>
#include <cstdio>
#include <limits>
#include <set>

#include "core/numbers.h"
#include "compose/compose.h"
#include "compose/detail/establish.h"
#include "compose/detail/exact.h"
#include "mesh/mesh.h"

namespace genbrep {
namespace {

std::string number(double x) { return format_number(x); }

// The local width of the gap between solids a and b near p: alternating projections
// converge to a pair of mutually nearest points.
double local_gap(const SolidSet& solids, int a, int b, const Vec3& p) {
  Vec3 qa = solids.surface(a).nearest_point(p), qb = solids.surface(b).nearest_point(qa);
  for (int i = 0; i < 16; ++i) {
    qa = solids.surface(a).nearest_point(qb);
    qb = solids.surface(b).nearest_point(qa);
  }
  if (solids.surface(b).inside(qa) || solids.surface(a).inside(qb)) return 0;  // they overlap
  return (qa - qb).norm();
}

// §9.1: names the narrowest gap between two of a loop's solids near the given points;
// empty when there is none.
std::string find_gap(const OrganicSheet& sheet, const SheetLoop& loop, const SolidSet& solids,
                     const std::vector<Vec3>& points) {
  double best = std::numeric_limits<double>::infinity();
  int best_a = -1, best_b = -1;
  for (size_t i = 0; i < loop.solids.size(); ++i) {
    for (size_t j = i + 1; j < loop.solids.size(); ++j) {
      const int a = loop.solids[i], b = loop.solids[j];
      for (const Vec3& p : points) {
        const double g = local_gap(solids, a, b, p);
        if (g > 0 && g < best) best = g, best_a = a, best_b = b;
      }
    }
  }
  if (best_a >= 0) {
    return "the organic boundary of component " + std::to_string(sheet.component) +
           " crosses a gap of " + number(best) + " between " + solids.describe(best_a) + " and " +
           solids.describe(best_b);
  }
  return {};
}

// The gap if there is one, else where the boundary stays outside.
std::string explain(const OrganicSheet& sheet, const SheetLoop& loop, const SolidSet& solids,
                    const std::vector<Vec3>& points, double max_after, double eta) {
  const std::string gap = find_gap(sheet, loop, solids, points);
  if (!gap.empty()) return gap;
  const std::string who = "the organic boundary of component " + std::to_string(sheet.component);
  std::string names;
  for (int s : loop.solids) names += (names.empty() ? "" : ", ") + solids.describe(s);
  // F > 0: outside S; η < F ≤ 0: inside, but not as deep as η asks (a doubled η deeper
  // than the solid is thick).
  return who + " cannot be pulled inside " + names + " (stays " +
         (max_after > 0 ? number(max_after) + " outside)" : "at depth " + number(-max_after) + " < |η| = " + number(-eta) + ")");
}

// A component with no boundary on a solid (a part of the design touching none) is its own
// closed cell: material when it encloses positive volume, else a void.
ComponentContact closed_shell(const OrganicSheet& sheet, detail::OrganicCell* cell) {
  ComponentContact out;
  out.component = sheet.component;
  out.surface = "closed shell";
  out.pulled = sheet;
  const std::string who = "organic component " + std::to_string(sheet.component);
  const detail::ExactMesh closed = detail::to_exact(sheet.mesh);
  const std::string unusable = detail::unusable_operand(closed, true);
  if (!unusable.empty()) {
    out.diagnostics.push_back(who + " is a closed organic shell, but its surface " + unusable);
    return out;
  }
  cell->component = sheet.component;
  cell->closed = closed;
  cell->trimmed = closed;
  cell->volume = detail::signed_volume(closed);
  cell->additive = cell->volume > 0;
  cell->usable = cell->additive;  // checked as it is; a void is checked turned inside out
  out.established = true;
  out.additive = cell->additive;
  out.cell_volume = cell->volume;
  out.diagnostics.push_back(who + " touches no solid: composed as a closed organic shell");
  return out;
}

}  // namespace

ComponentContact detail::establish(const OrganicSheet& sheet, const SolidSet& solids, const SolidSet& cut_solids,
                                   const ComposeOptions& options, OrganicCell* cell) {
  return establish_with(
      sheet, [&](double eta) { return pull_sheet(sheet, solids, eta, options.pull); }, solids, cut_solids, options,
      cell);
}

ComponentContact detail::establish_cage(const QuadCage& cage, const std::vector<std::vector<int>>& chain_solids,
                                        const SolidSet& solids, const SolidSet& cut_solids,
                                        const ComposeOptions& options, OrganicCell* cell,
                                        const std::vector<int>& sides) {
  QuadCage last;
  const OrganicSheet sheet = cage_sheet(cage, chain_solids, options.pull.cage_samples_per_edge);
  ComponentContact out = establish_with(
      sheet,
      [&](double eta) {
        CagePull pulled = pull_cage(cage, chain_solids, solids, eta, options.pull, sides);
        last = std::move(pulled.cage);
        return std::move(pulled.sheet);
      },
      solids, cut_solids, options, cell);
  if (out.surface != "closed shell") out.surface = "cage";
  out.cage = last.vertices.rows() > 0 ? std::move(last) : cage;
  return out;
}

ComponentContact detail::establish_with(const OrganicSheet& sheet, const SheetPuller& pull_at,
                                        const SolidSet& solids, const SolidSet& cut_solids,
                                        const ComposeOptions& options, OrganicCell* cell) {
  ComponentContact out;
  out.component = sheet.component;
  std::set<int> members;
  for (const auto& loop : sheet.loops) members.insert(loop.solids.begin(), loop.solids.end());
  if (sheet.loops.empty()) return closed_shell(sheet, cell);
  if (members.empty()) {
    out.diagnostics.push_back("organic component " + std::to_string(sheet.component) +
                              ": its boundary loops border no solid");
    return out;
  }
  std::vector<SolidInput> inputs;
  for (int s = 0; s < cut_solids.size(); ++s) inputs.push_back(cut_solids.input(s));
  const ExactMesh solid = solid_union(inputs, std::vector<int>(members.begin(), members.end()));
  double eta = options.initial_eta;
  if (eta >= 0) {
    eta = -1e-4 * bounding_box_diagonal(sheet.mesh.vertices);
  }
  std::string first_problem, last_problem;
  for (int doubling = 0; doubling <= options.max_doublings; ++doubling, eta *= 2) {
    SheetPull pull = pull_at(eta);
    out.eta = eta;
    out.doublings = doubling;
    out.pulled = pull.sheet;
    out.max_distance_before.clear();
    out.max_distance_after.clear();
    for (const auto& l : pull.loops) {
      out.max_distance_before.push_back(l.curve.max_before);
      out.max_distance_after.push_back(l.curve.max_after);
    }
    if (!pull.converged()) {
      // Doubling η cannot help a boundary that cannot get inside (§9.1): name the cause.
      if (doubling > 0) {  // the doublings were for a contact problem: say which
        out.diagnostics.push_back("organic component " + std::to_string(sheet.component) +
                                  ": no contact curve homeomorphic to the boundary up to η = " + number(out.eta / 2) +
                                  " (at η₀: " + first_problem + "; at the last η: " + last_problem +
                                  "), and the pull cannot reach η = " + number(out.eta));
      }
      for (size_t l = 0; l < pull.loops.size(); ++l) {
        if (pull.loops[l].curve.converged) continue;
        out.diagnostics.push_back(explain(sheet, sheet.loops[l], solids, pull.loops[l].stuck_points,
                                          pull.loops[l].curve.max_after, eta));
      }
      for (const auto& d : pull.diagnostics)
        out.diagnostics.push_back(d);  // e.g. inserted vertices
      return out;
    }
    const ContactCut cut = cut_at_contact(pull.sheet, solid);
    if (first_problem.empty()) first_problem = cut.problem;
    last_problem = cut.problem;
    if (!cut.homeomorphic || !cut.has_cell) continue;  // §7.3: η → 2η
    out.established = true;
    out.additive = cut.cell.additive;
    out.cell_volume = cut.cell.volume;
    for (size_t c = 0; c < cut.curves.size(); ++c) out.curves.push_back({cut.curve_loop[c], cut.curves[c]});
    for (const auto& d : pull.diagnostics) out.diagnostics.push_back(d);
    *cell = cut.cell;
    return out;
  }
  // Not homeomorphic at any η: near which solids? Use every boundary vertex as a probe.
  out.diagnostics.push_back("organic component " + std::to_string(sheet.component) +
                            ": no contact curve homeomorphic to the boundary up to η = " +
                            number(out.eta) + " (at η₀: " + first_problem + "; at the last η: " + last_problem + ")");
  for (const auto& loop : sheet.loops) {
    std::vector<Vec3> points;
    for (int v : loop.vertices) points.push_back(sheet.mesh.vertices.row(v).transpose());
    const std::string gap = find_gap(sheet, loop, solids, points);
    if (!gap.empty()) out.diagnostics.push_back(gap);
  }
  return out;
}

ComponentContact establish_contact(const OrganicSheet& sheet, const SolidSet& solids,
                                   const ComposeOptions& options) {
  detail::OrganicCell cell;
  return detail::establish(sheet, solids, solids, options, &cell);
}

ComponentContact establish_cage_contact(const QuadCage& cage, const std::vector<std::vector<int>>& chain_solids,
                                        const SolidSet& solids, const ComposeOptions& options) {
  detail::OrganicCell cell;
  return detail::establish_cage(cage, chain_solids, solids, solids, options, &cell);
}

}  // namespace genbrep

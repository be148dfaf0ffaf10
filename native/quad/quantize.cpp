// quad/quantize.cpp — exact quantization of the patch layout (quad/quad.h step 2): the
// integer count of cage edges on every arc, so that the two pairs of opposite sides of
// every patch have equal sums (the integer-grid condition of §6 for a patch layout).
// Formulation: a small integer program, solved by GLPK's branch-and-cut. Every arc is an
// integer variable n ≥ lower (1, or 0 for short interior arcs); every patch gives two
// equalities Σ(side 0) = Σ(side 2), Σ(side 1) = Σ(side 3). The cost is separable and convex,
// (n − t)² / max(t, 1) with t = length / target size, written as a piecewise-linear
// function of integer segment variables with increasing slopes: exact at the integers
// within 4 of the rounded target, its chords over segments of doubling width farther out.
// The counts are sums of their segments (no count column or row of their own).
// Why not a min-cost flow: around singularities a T-mesh has side cycles of odd twist
// (Lyon et al. 2021), where an arc enters both of its constraints with the same sign; the
// constraint matrix is then that of a bidirected graph, not a network, and rounding or
// local search can leave it infeasible. The integer program has no such case. Its LP relaxation is half-integral and the
// constraints are homogeneous, so an integer solution exists whenever a real one does
// (twice a half-integral solution), and branch-and-cut finds the nearest.
// Complexity: arcs · segments columns (segments ≈ 8 + 2 log t); a few hundred arcs solve in
// milliseconds, thousands can take long to prove optimal. The search stops once its
// solution is provably within QuadOptions::quantize_gap of the optimum, which depends on
// the problem only, so the counts are the same on every run; a time limit
// (QuadOptions::quantize_seconds) stays as a last resort and keeps the best solution
// found — only then does the result depend on the machine.
#include <glpk.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <memory>
#include <string>

#include "quad/detail/patches.h"

namespace genbrep::quad_detail {

namespace {

struct ProblemDeleter {
  void operator()(glp_prob* p) const { glp_delete_prob(p); }
};

// Per arc: on how many patch sides it lies (1: a loop arc, with a patch on one side only).
std::vector<int> sides_per_arc(const PatchLayout& layout) {
  std::vector<int> sides_of(layout.arcs.size(), 0);
  for (const Patch& patch : layout.patches)
    for (const auto& side : patch.sides)
      for (auto& [a, reversed] : side) ++sides_of[a];
  return sides_of;
}

// Whether the patch has a side on a loop (an arc on one patch side only).
bool on_loop(const Patch& patch, const std::vector<int>& sides_of) {
  for (const auto& side : patch.sides)
    for (auto& [a, reversed] : side)
      if (sides_of[a] == 1) return true;
  return false;
}

// The patches' two equalities Σ(side k) − Σ(side k + 2) = 0 as arc → coefficient, summed
// (an arc on both opposite sides of one patch cancels there); rows that cancel entirely
// are left out.
struct SideRow {
  int patch;
  std::map<int, int> coefficients;
};
std::vector<SideRow> side_rows(const PatchLayout& layout) {
  std::vector<SideRow> rows;
  for (size_t p = 0; p < layout.patches.size(); ++p)
    for (int pair = 0; pair < 2; ++pair) {
      SideRow row{static_cast<int>(p), {}};
      for (int side : {pair, pair + 2})
        for (auto& [a, reversed] : layout.patches[p].sides[side])
          row.coefficients[a] += side < 2 ? 1 : -1;
      auto& c = row.coefficients;
      for (auto it = c.begin(); it != c.end();) it = it->second ? std::next(it) : c.erase(it);
      if (!c.empty()) rows.push_back(std::move(row));
    }
  return rows;
}

// The integer program of one solve: a variable per class of arcs that must be equal, its
// count written as segment columns around a base, and the rows over them.
class CountProgram {
 public:
  CountProgram(PatchLayout& layout, const QuadOptions& options, const std::vector<SideRow>& rows)
      : layout(layout), options(options), rows(rows), arcs(static_cast<int>(layout.arcs.size())),
        problem(glp_create_prob()), lp(problem.get()), parent(arcs), segments(arcs), base(arcs, 0) {
    glp_set_obj_dir(lp, GLP_MIN);
    for (int a = 0; a < arcs; ++a) parent[a] = a;
  }
  void merge_equal_arcs();
  void add_count_columns(const std::vector<int>& lower);
  void add_side_rows();
  void add_width_rows();
  void add_loop_rows(const std::vector<int>& lower, const std::vector<int>& sides_of);
  bool solve(std::string* failure);

 private:
  int find(int a) { return parent[a] == a ? a : parent[a] = find(parent[a]); }
  std::map<int, int> by_class(const std::map<int, int>& coefficients) {
    std::map<int, int> out;
    for (auto& [a, c] : coefficients) out[find(a)] += c;
    for (auto it = out.begin(); it != out.end();) it = it->second ? std::next(it) : out.erase(it);
    return out;
  }
  // Σ c·n over the given arcs as a row over segment columns; returns Σ c·b (to move right).
  double add_counts(int row, const std::map<int, int>& coefficients) {
    double constant = 0;
    for (auto& [v, c] : by_class(coefficients)) {
      constant += c * base[v];
      for (const Segment& g : segments[v]) ia.push_back(row), ja.push_back(g.column), ar.push_back(c * g.sign);
    }
    return constant;
  }

  PatchLayout& layout;
  const QuadOptions& options;
  const std::vector<SideRow>& rows;
  const int arcs;
  std::unique_ptr<glp_prob, ProblemDeleter> problem;
  glp_prob* lp;
  // Arcs that must be equal (a row n_a − n_b = 0: two opposite sides of one arc each, the
  // usual case along a strip of patches) are one variable, the strip's count: union-find
  // over such rows, repeated while merging turns more rows into such pairs.
  std::vector<int> parent;
  struct Segment { int column; double sign; };
  std::vector<std::vector<Segment>> segments;  // per variable
  std::vector<int> base;                       // per variable
  std::vector<int> ia{0}, ja{0};
  std::vector<double> ar{0};
};

void CountProgram::merge_equal_arcs() {
  for (bool merged = true; merged;) {
    merged = false;
    for (const SideRow& row : rows) {
      const std::map<int, int> c = by_class(row.coefficients);
      if (c.size() == 2 && c.begin()->second == -std::next(c.begin())->second) {
        parent[find(std::next(c.begin())->first)] = find(c.begin()->first);
        merged = true;
      }
    }
  }
}

void CountProgram::add_count_columns(const std::vector<int>& lower) {
  // Per variable (a class of equal arcs), its count n = b + Σ up − Σ down around the
  // integer b that minimises the members' summed cost, in integer segments priced at the
  // cost's increments: unit segments within kExact of b, then segments doubling in width
  // (priced at the cost's chord, above the convex cost in between), so that a long arc
  // needs few columns. The counts are substituted into the rows: no column or row per count.
  constexpr int kExact = 4;
  std::vector<std::vector<int>> members(arcs);
  for (int a = 0; a < arcs; ++a) members[find(a)].push_back(a);
  auto target = [&](int a) { return std::max(layout.arcs[a].target * options.density, 1e-3); };
  for (int v = 0; v < arcs; ++v) {
    if (members[v].empty()) continue;
    int low = 0;
    double weights = 0, weighted = 0, longest = 0;
    for (int a : members[v]) {
      const double t = target(a);
      low = std::max(low, lower[a]);
      weights += 1 / std::max(t, 1.0), weighted += t / std::max(t, 1.0);
      longest = std::max(longest, t);
    }
    auto cost = [&](int n) {
      double sum = 0;
      for (int a : members[v]) {
        const double t = target(a);
        sum += (n - t) * (n - t) / std::max(t, 1.0);
      }
      return sum;
    };
    base[v] = std::max(low, static_cast<int>(std::lround(weighted / weights)));
    const int upper = std::max(2 * base[v], static_cast<int>(std::ceil(longest))) + 8;
    auto add_segments = [&](int to, double sign) {
      for (int n = base[v], width = 1; n != to;) {
        const int step = std::min(width, std::abs(to - n));
        const int next = n + (to > n ? step : -step);
        const int column = glp_add_cols(lp, 1);
        glp_set_col_kind(lp, column, GLP_IV);
        glp_set_col_bnds(lp, column, GLP_DB, 0, step);
        glp_set_obj_coef(lp, column, (cost(next) - cost(n)) / step);
        segments[v].push_back({column, sign});
        if (std::abs(next - base[v]) >= kExact) width *= 2;
        n = next;
      }
    };
    add_segments(upper, 1.0);
    add_segments(low, -1.0);
  }
}

void CountProgram::add_side_rows() {
  for (const SideRow& side_row : rows) {
    if (by_class(side_row.coefficients).empty()) continue;  // holds by the merging
    const int row = glp_add_rows(lp, 1);
    const double constant = add_counts(row, side_row.coefficients);
    glp_set_row_bnds(lp, row, GLP_FX, -constant, -constant);
  }
}

void CountProgram::add_width_rows() {
  // A patch at least one cage edge wide across a pair of sides should keep a row of quads
  // there even when those sides are short arcs (their targets say nothing about the
  // patch's width in between): Σ(side) + s ≥ 1, the slack s ∈ [0, 1] priced at the
  // patch's width w = quads / length (the cost of an arc of target w at 0 edges).
  for (const Patch& patch : layout.patches)
    for (int pair = 0; pair < 2; ++pair) {
      const double across = 0.5 * options.density *
                            (side_target(layout.arcs, patch, pair) +
                             side_target(layout.arcs, patch, pair + 2));
      const double along = 0.5 * options.density *
                           (side_target(layout.arcs, patch, 1 - pair) +
                            side_target(layout.arcs, patch, 3 - pair));
      const double width = patch.quads * options.density * options.density / std::max(along, 1.0);
      if (width < 1 || across >= 1) continue;
      const int row = glp_add_rows(lp, 1);
      std::map<int, int> coefficient;
      for (auto& [a, reversed] : patch.sides[pair]) ++coefficient[a];
      const double constant = add_counts(row, coefficient);
      glp_set_row_bnds(lp, row, GLP_LO, 1 - constant, 0);
      const int slack = glp_add_cols(lp, 1);
      glp_set_col_bnds(lp, slack, GLP_DB, 0, 1);
      glp_set_obj_coef(lp, slack, width);
      ia.push_back(row), ja.push_back(slack), ar.push_back(1.0);
    }
}

void CountProgram::add_loop_rows(const std::vector<int>& lower, const std::vector<int>& sides_of) {
  // A patch on a loop keeps at least one cage edge on each side that could vanish (every
  // arc of it free to be 0): its collapse would glue the loop's chain onto the patch's
  // other sides. Rows Σ(side) ≥ 1, so one solve finds the nearest counts.
  for (const Patch& patch : layout.patches) {
    if (!on_loop(patch, sides_of)) continue;
    for (const auto& side : patch.sides) {
      bool may_vanish = !side.empty();
      std::map<int, int> coefficient;
      for (auto& [a, reversed] : side) may_vanish &= lower[a] == 0, ++coefficient[a];
      if (!may_vanish) continue;
      const int row = glp_add_rows(lp, 1);
      const double constant = add_counts(row, coefficient);
      glp_set_row_bnds(lp, row, GLP_LO, 1 - constant, 0);
    }
  }
}

bool CountProgram::solve(std::string* failure) {
  glp_load_matrix(lp, static_cast<int>(ia.size()) - 1, ia.data(), ja.data(), ar.data());
  glp_iocp parameters;
  glp_init_iocp(&parameters);
  parameters.msg_lev = GLP_MSG_OFF;
  parameters.presolve = GLP_ON;
  parameters.tm_lim = static_cast<int>(1000 * std::max(options.quantize_seconds, 1.0));
  parameters.mip_gap = options.quantize_gap;
  // The branch-and-bound nodes created so far, read whenever GLPK selects the next one.
  int nodes = 0;
  parameters.cb_info = &nodes;
  parameters.cb_func = [](glp_tree* tree, void* info) {
    if (glp_ios_reason(tree) != GLP_ISELECT) return;
    int active = 0, current = 0, total = 0;
    glp_ios_tree_size(tree, &active, &current, &total);
    *static_cast<int*>(info) = total;
  };
  const int code = glp_intopt(lp, &parameters);
  layout.quantize_nodes += std::max(nodes, 1);
  const int status = glp_mip_status(lp);
  const bool stopped_with_solution = code == GLP_EMIPGAP || code == GLP_ETMLIM;
  if ((code != 0 && !stopped_with_solution) || (status != GLP_OPT && status != GLP_FEAS)) {
    *failure = code == GLP_ENOPFS || status == GLP_NOFEAS
                   ? "no integer counts make opposite sides equal (" + std::to_string(rows.size()) +
                         " side constraints)"
                   : "the integer program stopped without a solution (GLPK code " +
                         std::to_string(code) + ")";
    return false;
  }
  layout.quantize_cost = glp_mip_obj_val(lp);
  for (int a = 0; a < arcs; ++a) {
    const int v = find(a);
    double n = base[v];
    for (const Segment& g : segments[v]) n += g.sign * glp_mip_col_val(lp, g.column);
    layout.arcs[a].count = static_cast<int>(std::lround(n));
  }
  return true;
}

// One exact solve with per-arc lower bounds (0 or 1).
bool solve(PatchLayout& layout, const QuadOptions& options, const std::vector<int>& lower,
           const std::vector<int>& sides_of, std::string* failure) {
  const std::vector<SideRow> rows = side_rows(layout);
  glp_term_out(GLP_OFF);
  CountProgram program(layout, options, rows);
  program.merge_equal_arcs();
  program.add_count_columns(lower);
  program.add_side_rows();
  program.add_width_rows();
  program.add_loop_rows(lower, sides_of);
  return program.solve(failure);
}

}  // namespace

std::vector<int> unbalanced_patches(const PatchLayout& layout) {
  const int arcs = static_cast<int>(layout.arcs.size());
  const std::vector<int> sides_of = sides_per_arc(layout);
  const std::vector<SideRow> rows = side_rows(layout);
  glp_term_out(GLP_OFF);
  std::unique_ptr<glp_prob, ProblemDeleter> problem(glp_create_prob());
  glp_prob* lp = problem.get();
  glp_set_obj_dir(lp, GLP_MIN);
  glp_add_cols(lp, arcs);
  for (int a = 0; a < arcs; ++a) glp_set_col_bnds(lp, a + 1, GLP_LO, sides_of[a] == 1 ? 1 : 0, 0);
  std::vector<int> ia{0}, ja{0};
  std::vector<double> ar{0};
  for (const SideRow& row : rows) {
    const int r = glp_add_rows(lp, 1);
    glp_set_row_bnds(lp, r, GLP_FX, 0, 0);
    for (auto& [a, c] : row.coefficients) ia.push_back(r), ja.push_back(a + 1), ar.push_back(c);
    // s⁺ − s⁻, priced 1, or a quarter at a cusp patch: a cusp reading is the cheapest
    // thing to take back (straighten_cusps), so the imbalance lands there when it can.
    const int slack = glp_add_cols(lp, 2);
    const double price = layout.patches[row.patch].cusps.empty() ? 1.0 : 0.25;
    for (int k = 0; k < 2; ++k) {
      glp_set_col_bnds(lp, slack + k, GLP_LO, 0, 0);
      glp_set_obj_coef(lp, slack + k, price);
      ia.push_back(r), ja.push_back(slack + k), ar.push_back(k ? -1.0 : 1.0);
    }
  }
  // A patch on a loop keeps an edge on every side of interior arcs (solve's rows):
  // Σ(side) + s ≥ 1, the slack priced 1, so that a layout only those rows unbalance names
  // a patch to merge.
  std::vector<std::pair<int, int>> loop_slack;  // (slack column, patch)
  for (size_t p = 0; p < layout.patches.size(); ++p) {
    const Patch& patch = layout.patches[p];
    if (!on_loop(patch, sides_of)) continue;
    for (const auto& side : patch.sides) {
      bool interior = !side.empty();
      for (auto& [a, reversed] : side) interior &= sides_of[a] != 1;
      if (!interior) continue;
      const int r = glp_add_rows(lp, 1);
      glp_set_row_bnds(lp, r, GLP_LO, 1, 0);
      for (auto& [a, reversed] : side) ia.push_back(r), ja.push_back(a + 1), ar.push_back(1.0);
      const int slack = glp_add_cols(lp, 1);
      glp_set_col_bnds(lp, slack, GLP_LO, 0, 0);
      glp_set_obj_coef(lp, slack, 1.0);
      ia.push_back(r), ja.push_back(slack), ar.push_back(1.0);
      loop_slack.push_back({slack, static_cast<int>(p)});
    }
  }
  glp_load_matrix(lp, static_cast<int>(ia.size()) - 1, ia.data(), ja.data(), ar.data());
  glp_smcp parameters;
  glp_init_smcp(&parameters);
  parameters.msg_lev = GLP_MSG_OFF;
  std::vector<int> out;
  if (glp_simplex(lp, &parameters) != 0 || glp_get_status(lp) != GLP_OPT) return out;
  for (size_t r = 0; r < rows.size(); ++r) {
    const int slack = arcs + 2 * static_cast<int>(r) + 1;
    if (glp_get_col_prim(lp, slack) + glp_get_col_prim(lp, slack + 1) > 1e-9)
      out.push_back(rows[r].patch);
  }
  for (auto& [slack, p] : loop_slack)
    if (glp_get_col_prim(lp, slack) > 1e-9) out.push_back(p);
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

// Interior arcs shorter than one target edge (sliver arcs between nearby T-junctions and
// nodes) may get 0 edges: their end nodes then merge in the cage (zero-length arcs as in
// Campen et al. 2015, QGP), and a patch whose two opposite sides both get 0 collapses onto
// its other pair (fill.cpp glues them). Loop arcs keep ≥ 1 so every chain stays on its
// loop, and a patch that touches a loop keeps ≥ 1 edge on every side (solve's rows).
// A layout whose separatrices end on curves they already crossed (a helix around a hole:
// going round, each side is longer than the last by a T-junction's offset) has no solution
// with those bounds; then every interior arc may get 0 (reported by the caller as
// collapsed patches), which the cost keeps to the fewest and shortest arcs.
bool quantize(PatchLayout& layout, const QuadOptions& options, std::string* failure,
              bool* relaxed) {
  const int arcs = static_cast<int>(layout.arcs.size());
  const std::vector<int> sides_of = sides_per_arc(layout);
  *relaxed = false;
  layout.quantize_nodes = 0;
  std::vector<int> lower(arcs, 1);
  for (int a = 0; a < arcs; ++a)
    if (sides_of[a] == 2 && layout.arcs[a].target * options.density < 1.0) lower[a] = 0;
  if (solve(layout, options, lower, sides_of, failure)) return true;
  *relaxed = true;
  for (int a = 0; a < arcs; ++a)
    if (sides_of[a] == 2) lower[a] = 0;
  return solve(layout, options, lower, sides_of, failure);
}

int squeezed_arcs(const PatchLayout& layout, double density) {
  int squeezed = 0;
  for (const Arc& arc : layout.arcs) {
    const double asked = arc.target * density;
    squeezed += asked >= kSqueezedTarget && arc.count <= kSqueezedShare * asked;
  }
  return squeezed;
}

void release_quantize_thread() { glp_free_env(); }

}  // namespace genbrep::quad_detail

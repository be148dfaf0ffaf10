// pipeline/report.cpp — report.json: inputs, tolerance, seconds per stage, counts, notes.
#include <nlohmann/json.hpp>

#include "pipeline/pipeline.h"

namespace genbrep {

namespace {

using json = nlohmann::ordered_json;

// The "composed" section: checks measured on the composed mesh, and per component which
// surface was composed (its tier: "cage", the pulled fitted cage; "extended cage", the cage
// extended into its solids by a row of quads and pulled; "design region"; "closed
// shell"; "design solid", its part of the design less the keep-ins; "design Boolean", the
// floor) and, below its best tier, why ("fallback").
json composed_json(const Result& result) {
  const ComposeReport& c = result.composed.report;
  json contacts = json::array();
  for (const auto& contact : result.composed.contacts) {
    json entry = {{"component", contact.component},
                  {"surface", contact.surface},
                  {"established", contact.established},
                  {"eta", contact.eta},
                  {"doublings", contact.doublings},
                  {"additive", contact.additive},
                  {"contact_curves", contact.curves.size()},
                  {"max_distance_before", contact.max_distance_before},
                  {"max_distance_after", contact.max_distance_after}};
    if (!contact.fallback.empty()) entry["fallback"] = contact.fallback;
    if (contact.surface == "cage" || contact.surface == "extended cage") {
      entry["control_points"] = contact.cage.vertices.rows();
      entry["quads"] = contact.cage.quads.rows();
    }
    contacts.push_back(entry);
  }
  const double design_volume = result.design_validation.signed_volume;
  json out = {{"ok", c.ok},
              {"vertices", c.vertices},
              {"triangles", c.triangles},
              {"boundary_edges", c.boundary_edges},
              {"non_manifold_edges", c.non_manifold_edges},
              {"non_manifold_vertices", c.non_manifold_vertices},
              {"inconsistent_edges", c.inconsistent_edges},
              {"self_intersecting", c.self_intersecting},
              {"volume", c.volume}};
  if (design_volume != 0) out["volume_vs_design"] = c.volume / design_volume;
  out["shells"] = c.shells;
  out["genus"] = c.genus;
  out["organic_cells"] = c.organic_cells;
  out["solid_cells"] = c.solid_cells;
  out["floor"] = c.floor;
  out["fallbacks"] = fallbacks(result.composed);
  out["contacts"] = contacts;
  return out;
}

json compose_diagnostics(const Result& result) {
  // compose() already copies every contact's diagnostics into its report's, in order.
  json diagnostics = json::array();
  for (const auto& d : result.composed.report.diagnostics) diagnostics.push_back("compose: " + d);
  return diagnostics;
}

}  // namespace

std::string make_recompose_report(const std::vector<SolidInput>& solids,
                                  const std::vector<std::string>& cage_names, const Result& result) {
  json report;
  report["genbrep_version"] = kVersion;
  report["command"] = "recompose";
  report["stages_run"] = result.stages_run;
  json inputs = json::array();
  for (const auto& s : solids) {
    inputs.push_back({{"name", s.name}, {"role", role_name(s.role)}, {"triangles", s.mesh.triangles.rows()}});
  }
  json cages = json::array();
  for (size_t i = 0; i < result.fitted.size(); ++i) {
    const QuadCage& cage = result.fitted[i].cage;
    cages.push_back({{"name", i < cage_names.size() ? cage_names[i] : ""},
                     {"component", cage.component},
                     {"control_points", cage.vertices.rows()},
                     {"quads", cage.quads.rows()},
                     {"boundary_loops", cage.boundary_chains.size()}});
  }
  report["inputs"] = {{"solids", inputs}, {"cages", cages}};
  json seconds = json::object();
  for (const auto& t : result.timings) seconds[t.stage] = t.seconds;
  report["stages"] = seconds;
  if (ran(result, "compose")) report["composed"] = composed_json(result);
  json diagnostics = result.diagnostics;
  for (const auto& d : compose_diagnostics(result)) diagnostics.push_back(d);
  report["diagnostics"] = diagnostics;
  return report.dump(2);
}

std::string make_report(const Inputs& inputs, const Options& options, const Result& result) {
  json report;
  report["genbrep_version"] = kVersion;
  report["stages_run"] = result.stages_run;

  json design;
  design["name"] = inputs.design.name;
  design["input_vertices"] = inputs.design.mesh.vertices.rows();
  design["input_triangles"] = inputs.design.mesh.triangles.rows();
  design["vertices"] = result.design_validation.vertices;
  design["triangles"] = result.design_validation.triangles;
  design["shells"] = result.design_validation.shells;
  design["volume"] = result.design_validation.signed_volume;
  json solids = json::array();
  for (size_t i = 0; i < inputs.solids.size(); ++i) {
    json s;
    s["name"] = inputs.solids[i].name;
    s["role"] = role_name(inputs.solids[i].role);
    s["triangles"] = inputs.solids[i].mesh.triangles.rows();
    solids.push_back(s);
  }
  report["inputs"] = {{"design", design}, {"solids", solids}};

  const bool grid = options.incidence.mode == IncidenceOptions::Mode::Grid;
  json tolerance;
  tolerance["mode"] = grid ? "grid" : "distance";
  tolerance["value"] = result.incidence.tolerance;
  tolerance["derived"] = result.incidence.tolerance_derived;
  if (grid) {
    const Vec3& o = options.incidence.grid_origin;
    tolerance["grid_origin"] = {o.x(), o.y(), o.z()};
    tolerance["grid_h"] = options.incidence.grid_h;
  }
  report["tolerance"] = tolerance;

  json seconds = json::object();
  double total = 0;
  for (const auto& t : result.timings) {
    seconds[t.stage] = t.seconds;
    total += t.seconds;
  }
  report["stages"] = seconds;
  report["seconds_total"] = total;

  const Partition& p = result.partition;
  json counts;
  counts["triangles"] = result.design_validation.triangles;
  const bool partitioned = !p.face_solid.empty();
  if (partitioned) {
    json per_solid = json::array();
    for (const auto& faces : p.solid_faces) per_solid.push_back(faces.size());
    counts["incident_triangles"] = result.design_validation.triangles - p.organic_triangles();
    counts["incident_triangles_per_solid"] = per_solid;
    counts["organic_triangles"] = p.organic_triangles();
    counts["organic_components"] = p.organic_components;
    counts["boundary_loops"] = p.loops.size();
    counts["repaired_vertices"] = p.repaired_vertices;
    counts["repair_rounds"] = p.repair_rounds;
    counts["reassigned_triangles"] = p.reassigned_triangles;
  }
  if (!result.incidence.incident_vertices_per_solid.empty()) {
    counts["incident_vertices_per_solid"] = result.incidence.incident_vertices_per_solid;
  }
  report["counts"] = counts;
  if (partitioned) {
    json loops = json::array();
    for (const auto& loop : p.loops) {
      loops.push_back({{"vertices", loop.vertices.size()},
                       {"solids", loop.solids},
                       {"component", loop.component}});
    }
    report["loops"] = loops;
  }
  if (ran(result, "relax")) {
    const Relaxed& r = result.relaxed;
    json relax;
    relax["tolerance"] = r.tolerance;
    relax["target_edge_length"] = r.target_edge_length;
    relax["max_displacement"] = r.max_displacement;
    relax["triangles"] = r.design.triangles.rows();
    relax["channel_triangles"] = r.channel_triangles;
    relax["remeshed"] = r.remeshed;
    relax["skipped_moves"] = r.skipped_moves;
    relax["organic_area_before"] = r.organic_area_before;
    relax["organic_area_after"] = r.organic_area_after;
    json loops = json::array();
    for (const auto& loop : r.loops) {
      loops.push_back({{"original_loop", loop.original_loop},
                       {"edge_length_cv_before", loop.before.edge_length_cv},
                       {"edge_length_cv_after", loop.after.edge_length_cv},
                       {"mean_turning_degrees_before", loop.before.mean_turning_angle * 180 / M_PI},
                       {"mean_turning_degrees_after", loop.after.mean_turning_angle * 180 / M_PI},
                       {"max_displacement", loop.max_displacement}});
    }
    relax["loops"] = loops;
    report["relax"] = relax;
  }
  if (ran(result, "field")) {
    const CrossField& f = result.field;
    json field;
    field["target_edge_length"] = f.target_edge_length;
    field["min_edge_length"] = f.min_edge_length;
    field["tolerance_epsilon"] = f.tolerance;
    field["kappa_max"] = f.kappa_max;
    json components = json::array();
    for (int c = 0; c < result.relaxed.partition.organic_components; ++c) {
      int positive = 0, negative = 0, on_boundary = 0;
      for (const auto& s : f.singularities) {
        if (s.component != c) continue;
        positive += s.index > 0;
        negative += s.index < 0;
        on_boundary += s.on_boundary;
      }
      components.push_back({{"component", c},
                            {"singularities_positive", positive},
                            {"singularities_negative", negative},
                            {"singularities_on_boundary", on_boundary},
                            {"index_sum_quarter_turns", f.index_sum(c)}});
    }
    field["components"] = components;
    report["field"] = field;
  }
  if (ran(result, "quad")) {
    json cages = json::array();
    for (size_t i = 0; i < result.quads.cages.size(); ++i) {
      const QuadStats& s = result.quads.stats[i];
      const QuadCage& quad_cage = result.quads.cages[i];
      json off = json::array();  // where they are, their valence, the quarter turns left
      for (const auto& [v, valence, turns] : s.off_singularities)
        off.push_back(
            {{"position",
              {quad_cage.vertices(v, 0), quad_cage.vertices(v, 1), quad_cage.vertices(v, 2)}},
             {"valence", valence},
             {"quarter_turns", turns}});
      json cage = {{"component", quad_cage.component},
                   {"quads", s.quads},
                   {"quad_fraction", 1.0},
                   {"interior_valence4_fraction", s.interior_valence4_fraction()},
                   {"boundary_valence3_fraction", s.boundary_valence3_fraction()},
                   {"irregular_vertices", s.irregular_vertices},
                   {"irregular_vertices_off_singularities", s.irregular_off_singularities},
                   {"irregular_vertices_off_singularities_at", off},
                   {"mean_angle_deviation_degrees", s.mean_angle_deviation_deg},
                   {"max_angle_deviation_degrees", s.max_angle_deviation_deg},
                   {"skewed_quads", s.skewed_quads},
                   {"flipped_quads", s.flipped_quads},
                   {"collapsed_quads", s.collapsed_quads},
                   {"oversized_quads", s.oversized_quads},
                   {"squeezed_arcs", s.squeezed_arcs},
                   {"size_field_quads", s.size_field_quads},
                   {"patches", s.patches},
                   {"method", s.fallback ? "fallback: split coarse remesh, not field-aligned" : "field-aligned patch layout"},
                   {"seconds", s.seconds}};
      if (i < result.fitted.size()) {
        const FitReport& f = result.fitted[i].report;
        cage["fit"] = {{"strategy", strategy_name(f.strategy)},
                       {"control_points", f.control_points},
                       {"delta", f.delta},
                       {"rms_design_to_limit", f.rms_design_to_limit},
                       {"max_design_to_limit", f.max_design_to_limit},
                       {"rms_limit_to_design", f.rms_limit_to_design},
                       {"max_limit_to_design", f.max_limit_to_design},
                       {"max_boundary_distance", f.max_boundary_distance},
                       {"rounds", f.rounds},
                       {"refinements", f.refinements},
                       {"bound_held", f.bound_held},
                       {"kept_initial", f.kept_initial},
                       {"seconds", f.seconds}};
      }
      cages.push_back(cage);
    }
    json failures = json::array();
    for (const auto& f : result.quads.failures) failures.push_back({{"component", f.component}, {"reason", f.reason}});
    report["cages"] = cages;
    report["cage_failures"] = failures;
  }
  if (ran(result, "compose")) report["composed"] = composed_json(result);
  json diagnostics = result.diagnostics;
  for (const auto& d : result.incidence.diagnostics) diagnostics.push_back(d);
  for (const auto& d : p.diagnostics) diagnostics.push_back(d);
  for (const auto& d : result.relaxed.diagnostics) diagnostics.push_back(d);
  for (const auto& d : result.field.diagnostics) diagnostics.push_back(d);
  for (const auto& d : result.quads.diagnostics) diagnostics.push_back("quad: " + d);
  for (const auto& d : compose_diagnostics(result)) diagnostics.push_back(d);
  for (const auto& f : result.fitted) {
    for (const auto& d : f.report.diagnostics) diagnostics.push_back("fit: " + d);
  }
  report["diagnostics"] = diagnostics;
  // How the stages did their work, apart from the warnings above: nothing to act on.
  json notes = json::array();
  for (const auto& d : result.relaxed.notes) notes.push_back(d);
  for (const auto& d : result.field.notes) notes.push_back(d);
  for (const auto& d : result.quads.notes) notes.push_back("quad: " + d);
  for (const auto& d : result.composed.report.notes) notes.push_back("compose: " + d);
  report["notes"] = notes;
  return report.dump(2);
}

}  // namespace genbrep

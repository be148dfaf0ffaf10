// pipeline/pipeline.cpp — stage order, timings, error attribution.
#include "pipeline/pipeline.h"

#include <algorithm>
#include <chrono>

namespace genbrep {

const char* const kVersion = "0.1.0";

const std::vector<std::string>& stage_names() {
  static const std::vector<std::string> names{"mesh", "incidence", "partition", "relax", "field", "quad", "fit", "compose"};
  return names;
}

namespace {

// Runs one stage: times it, records it, and attaches the stage name to its errors.
std::vector<SolidInput> prepare_solids(const std::vector<SolidInput>& inputs, Diagnostics* diagnostics) {
  std::vector<SolidInput> out;
  for (const auto& solid : inputs) {
    SolidInput prepared = solid;
    prepared.mesh = prepare_closed_mesh(solid.mesh, describe(solid), diagnostics);
    out.push_back(std::move(prepared));
  }
  return out;
}

template <typename Fn>
void run_stage(const std::string& stage, Result* result, const Context& context, Fn&& fn) {
  const auto start = std::chrono::steady_clock::now();
  context.step(stage, 0.0);
  try {
    fn();
  } catch (const Error& e) {
    throw e.with_stage(stage);
  } catch (const std::bad_alloc&) {
    throw Error(Code::StageFailure, "out of memory", stage);
  } catch (const std::exception& e) {
    throw Error(Code::Internal, std::string("unexpected failure: ") + e.what(), stage);
  }
  const std::chrono::duration<double> seconds = std::chrono::steady_clock::now() - start;
  result->timings.push_back({stage, seconds.count()});
  result->stages_run.push_back(stage);
}

}  // namespace

int exit_status(const Result& result) {
  if (!ran(result, "compose")) return 0;
  if (!result.composed.report.ok) return 1;
  return fallbacks(result.composed).empty() ? 0 : 3;
}

std::vector<QuadCage> final_cages(const Result& result) {
  if (!ran(result, "fit") && !ran(result, "compose")) return result.quads.cages;
  std::vector<QuadCage> cages;
  for (const auto& f : result.fitted) {
    cages.push_back(f.cage);
    for (const auto& contact : result.composed.contacts) {
      if (contact.component == f.cage.component && (contact.surface == "cage" || contact.surface == "extended cage") &&
          contact.established) {
        cages.back() = contact.cage;
      }
    }
  }
  return cages;
}

TriangleMesh component_region(const TriangleMesh& design, const Partition& partition, int component) {
  std::vector<int> index(static_cast<size_t>(design.vertices.rows()), -1);
  std::vector<int> faces;
  for (size_t f = 0; f < partition.face_component.size(); ++f) {
    if (partition.face_component[f] == component) faces.push_back(static_cast<int>(f));
  }
  TriangleMesh region;
  region.triangles.resize(static_cast<Eigen::Index>(faces.size()), 3);
  int count = 0;
  for (size_t i = 0; i < faces.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      int& v = index[design.triangles(faces[i], k)];
      if (v < 0) v = count++;
      region.triangles(static_cast<Eigen::Index>(i), k) = v;
    }
    region.triangle_source.push_back(faces[i]);
  }
  region.vertices.resize(count, 3);
  for (size_t v = 0; v < index.size(); ++v) {
    if (index[v] >= 0) region.vertices.row(index[v]) = design.vertices.row(static_cast<Eigen::Index>(v));
  }
  return region;
}

std::vector<std::vector<Vec3>> chain_curves(const TriangleMesh& design, const Partition& partition,
                                            const QuadCage& cage) {
  std::vector<std::vector<Vec3>> curves;
  for (int loop : cage.chain_loop) {
    std::vector<Vec3> curve;
    for (int v : partition.loops[loop].vertices) curve.push_back(design.vertices.row(v));
    curves.push_back(std::move(curve));
  }
  return curves;
}

bool ran(const Result& result, const std::string& stage) {
  return std::find(result.stages_run.begin(), result.stages_run.end(), stage) != result.stages_run.end();
}

Result convert(const Inputs& inputs, const Options& options, const Context& context) {
  const auto& names = stage_names();
  const std::string until = options.until.empty() ? names.back() : options.until;
  const auto last = std::find(names.begin(), names.end(), until);
  GENBREP_CHECK(last != names.end(), Code::InvalidInput,
                "unknown stage '" + until + "'; stages are " + [&] {
                  std::string list;
                  for (const auto& n : names) list += (list.empty() ? "" : ", ") + n;
                  return list;
                }());
  auto wanted = [&](const char* stage) {
    return std::find(names.begin(), last + 1, stage) != last + 1;
  };

  Result result;
  std::unique_ptr<SolidSet> solids;
  run_stage("mesh", &result, context, [&] {
    const std::string design = "design '" + inputs.design.name + "'";
    result.design = prepare_closed_mesh(inputs.design.mesh, design, &result.diagnostics,
                                        &result.design_validation, &context);
    // Without solids every triangle is organic: the design is one closed organic shell
    // per part, composed from its cage. Say so, since it is rarely what was meant.
    if (inputs.solids.empty())
      result.diagnostics.push_back(design + " has no solids (keep-in, keep-out or seed): every part of it "
                                   "is organic and composed from its cage as a closed shell");
    context.step("mesh", 0.5);
    result.solids = prepare_solids(inputs.solids, &result.diagnostics);
  });
  if (wanted("incidence")) {
    run_stage("incidence", &result, context, [&] {
      solids = std::make_unique<SolidSet>(result.solids, &result.diagnostics);
      result.incidence = compute_incidence(result.design, *solids, options.incidence, context);
      for (auto& warning : check_placement(result.design, *solids, result.incidence, context))
        result.incidence.diagnostics.push_back(std::move(warning));
    });
  }
  std::unique_ptr<TriMesh> mesh;
  if (wanted("partition")) {
    run_stage("partition", &result, context, [&] {
      mesh = std::make_unique<TriMesh>(to_trimesh(result.design));
      result.partition = partition(*mesh, result.incidence, solids->size(), options.partition, context);
    });
  }
  if (wanted("relax")) {
    run_stage("relax", &result, context, [&] {
      RelaxOptions relax_options = options.relax;
      if (relax_options.tolerance <= 0) relax_options.tolerance = result.incidence.tolerance;
      result.relaxed = relax(result.design, result.partition, relax_options, context);
      mesh = std::make_unique<TriMesh>(to_trimesh(result.relaxed.design));
    });
  }
  if (wanted("field")) {
    run_stage("field", &result, context, [&] {
      result.field = compute_field(*mesh, result.relaxed.partition, options.field, context);
    });
  }
  if (wanted("quad")) {
    run_stage("quad", &result, context, [&] {
      result.quads = extract_cages(*mesh, result.relaxed.partition, result.field, options.quad, context);
    });
  }
  if (wanted("fit")) {
    run_stage("fit", &result, context, [&] {
      FitOptions fit_options = options.fit;
      if (fit_options.delta <= 0 && options.incidence.mode == IncidenceOptions::Mode::Grid) {
        fit_options.delta = 3 * options.incidence.grid_h;  // δ = 3h for level sets (§6.3)
      }
      // A cage the fit cannot take (e.g. a boundary chain too short to be a closed curve)
      // becomes a quad failure with the reason: its component is composed without a cage.
      for (size_t i = 0; i < result.quads.cages.size();) {
        const QuadCage& cage = result.quads.cages[i];
        try {
          const TriangleMesh region = component_region(result.relaxed.design, result.relaxed.partition, cage.component);
          result.fitted.push_back(fit_cage(cage, region, chain_curves(result.relaxed.design, result.relaxed.partition, cage),
                                           fit_options, context));
          ++i;
        } catch (const Error& e) {
          if (e.code() == Code::Cancelled) throw;
          result.quads.failures.push_back({cage.component, std::string("the fit cannot take its cage: ") + e.what()});
          result.quads.diagnostics.push_back("component " + std::to_string(cage.component) +
                                             ": no cage: the fit cannot take it: " + e.what());
          result.quads.cages.erase(result.quads.cages.begin() + static_cast<long>(i));
          if (i < result.quads.stats.size()) result.quads.stats.erase(result.quads.stats.begin() + static_cast<long>(i));
        }
      }
    });
  }
  if (wanted("compose")) {
    run_stage("compose", &result, context, [&] {
      // Per component: its pulled fitted cage, the design region as stand-in and fallback.
      std::vector<OrganicSurface> surfaces;
      for (auto& sheet : organic_sheets(result.relaxed.design, result.relaxed.partition)) {
        surfaces.push_back({std::move(sheet), std::nullopt, {}});
      }
      for (const Fitted& f : result.fitted) {
        OrganicSurface& surface = surfaces.at(static_cast<size_t>(f.cage.component));
        surface.cage = f.cage;
        for (int loop : f.cage.chain_loop) surface.chain_solids.push_back(result.relaxed.partition.loops[loop].solids);
      }
      result.composed = compose(surfaces, *solids, options.compose, context, &result.design);
      // A component the quad stage gave no cage was composed below its best tier too.
      for (auto& contact : result.composed.contacts) {
        const OrganicSurface& surface = surfaces.at(static_cast<size_t>(contact.component));
        if (!surface.cage && contact.fallback.empty() && contact.surface == "design region")
          contact.fallback = "the quad stage gave it no cage (see the quad diagnostics)";
      }
    });
  }
  result.report_json = make_report(inputs, options, result);
  return result;
}

Result recompose(const std::vector<SolidInput>& solids, const std::vector<QuadCage>& cages,
                 const Options& options, const Context& context, const std::vector<std::string>& cage_names) {
  Result result;
  std::vector<std::string> names;
  for (size_t i = 0; i < cages.size(); ++i) {
    names.push_back(i < cage_names.size() ? cage_names[i]
                                          : "component " + std::to_string(cages[i].component >= 0 ? cages[i].component
                                                                                                   : static_cast<int>(i)));
  }
  run_stage("mesh", &result, context, [&] {
    GENBREP_CHECK(!cages.empty(), Code::InvalidInput, "recompose needs at least one cage");
    result.solids = prepare_solids(solids, &result.diagnostics);
    for (size_t i = 0; i < cages.size(); ++i) {
      Fitted f;
      f.cage = with_boundary_chains(cages[i], names[i]);
      f.cage.component = static_cast<int>(i);
      f.report.component = static_cast<int>(i);
      result.fitted.push_back(std::move(f));
    }
  });
  run_stage("compose", &result, context, [&] {
    const SolidSet set(result.solids, &result.diagnostics);
    std::vector<OrganicSurface> surfaces;
    for (size_t i = 0; i < cages.size(); ++i) {
      OrganicSurface surface;
      surface.sheet.component = static_cast<int>(i);
      surface.cage = result.fitted[i].cage;
      surface.chain_solids = chain_solids_by_proximity(*surface.cage, set, names[i],
                                                       options.compose.pull.cage_samples_per_edge);
      surfaces.push_back(std::move(surface));
    }
    result.composed = compose(surfaces, set, options.compose, context);
  });
  result.report_json = make_recompose_report(solids, names, result);
  return result;
}

}  // namespace genbrep

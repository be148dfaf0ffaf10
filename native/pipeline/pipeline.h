// pipeline/pipeline.h — the only place that knows the stage order (DESIGN.md).
// Takes: the design mesh and the input solids as arrays with names and roles, options,
// and a Context for progress and cancel. Gives: every stage's result, seconds per stage,
// and report.json text. Runs stages up to and including `options.until`.
// Throws Error (with the failing stage's name) for bad input or a failed stage.
#pragma once
#include <string>
#include <vector>

#include "core/context.h"
#include "core/error.h"
#include "core/types.h"
#include "field/field.h"
#include "incidence/incidence.h"
#include "mesh/mesh.h"
#include "partition/partition.h"
#include "relax/relax.h"

namespace genbrep {

extern const char* const kVersion;

// Stages that exist, in order. `Options::until` takes one of these.
const std::vector<std::string>& stage_names();

struct Options {
  IncidenceOptions incidence;
  PartitionOptions partition;
  RelaxOptions relax;  // tolerance 0 = the incidence tolerance d
  FieldOptions field;
  std::string until;  // last stage to run; empty = all
};

struct Inputs {
  NamedMesh design;
  std::vector<SolidInput> solids;
};

struct StageTiming {
  std::string stage;
  double seconds = 0;
};

struct Result {
  TriangleMesh design;             // welded, validated, outward-oriented
  MeshValidation design_validation;
  std::vector<SolidInput> solids;  // prepared solids, same order as the inputs
  Incidence incidence;
  Partition partition;             // of `design`
  Relaxed relaxed;                 // §5.3: the design and partition the later stages use
  CrossField field;                // per triangle of relaxed.design
  std::vector<std::string> stages_run;
  std::vector<StageTiming> timings;
  Diagnostics diagnostics;         // the mesh stage's notes (welds, flips)
  std::string report_json;
};

Result convert(const Inputs& inputs, const Options& options, const Context& context);

// Whether `stage` ran in the conversion that gave `result`.
bool ran(const Result& result, const std::string& stage);

// report.json of a result (also stored in Result::report_json).
std::string make_report(const Inputs& inputs, const Options& options, const Result& result);

}  // namespace genbrep

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
#include "compose/compose.h"
#include "core/types.h"
#include "field/field.h"
#include "fit/fit.h"
#include "incidence/incidence.h"
#include "mesh/mesh.h"
#include "partition/partition.h"
#include "quad/quad.h"
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
  QuadOptions quad;
  FitOptions fit;     // delta 0 = 3h with grid incidence (§6.3), else fit's own default
  ComposeOptions compose;
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
  QuadResult quads;                // §6: a cage per organic component that could be meshed
  std::vector<Fitted> fitted;      // §6.3: the fitted cages, same order as quads.cages
  // §7–8: the watertight solid. A component with a fitted cage is composed from the pulled
  // cage's limit surface (contacts[i].surface == "cage", contacts[i].cage the pulled cage);
  // the others, and a cage that cannot be pulled, from the relaxed design's organic region
  // ("design region"). After recompose(): the input cages are in `fitted` (reports empty).
  Composed composed;
  std::vector<std::string> stages_run;
  std::vector<StageTiming> timings;
  Diagnostics diagnostics;         // the mesh stage's notes (welds, flips)
  std::string report_json;
};

Result convert(const Inputs& inputs, const Options& options, const Context& context);

// The cages to hand on: after compose the pulled cage of every component composed from
// its cage (the fitted one where it fell back to the design region), else fitted if fit
// ran, else the extracted ones.
std::vector<QuadCage> final_cages(const Result& result);

// ---- Recompose from edited cages (issue 7 item 5) ----
// Runs mesh preparation of the solids, then per cage: checks it, finds its boundary loops
// from its quads (edges used by one quad, followed in the quads' direction), gives every
// loop the solids nearest its limit boundary (for each limit sample the solid with the
// smallest |signed distance|; the loop borders every solid that is nearest to one of its
// samples), pulls and composes (§7–8) exactly as convert() does. cages[i] becomes organic
// component i, named cage_names[i] (default "component <cage.component or i>"). Its
// boundary_chains and chain_loop are ignored (recomputed; chain_loop = -1); vertices no
// quad uses are dropped. Throws Error{InvalidInput} naming the cage: not 2-manifold, a
// quad with a repeated corner, no boundary, or a boundary loop farther than
// 3 × its mean edge length from every solid (open: a hole, not a loop on a solid).
Result recompose(const std::vector<SolidInput>& solids, const std::vector<QuadCage>& cages,
                 const Options& options, const Context& context,
                 const std::vector<std::string>& cage_names = {});

// A polygon mesh (OBJ of a cage, the binding's faces array) as a QuadCage; throws
// Error{InvalidInput} "cage 'C' is not a quad mesh: 3 faces have 5 corners".
QuadCage cage_from_polygons(const PolygonSoup& polygons, const std::string& name);

// The checks and boundary loops of recompose() for one cage (see there).
QuadCage with_boundary_chains(const QuadCage& cage, const std::string& name);
std::vector<std::vector<int>> chain_solids_by_proximity(const QuadCage& cage, const SolidSet& solids,
                                                        const std::string& name, int samples_per_edge);

// The organic triangles of one component as an open mesh, and its boundary loops as
// polylines in the order of `cage.chain_loop` (what fit_cage takes).
TriangleMesh component_region(const TriangleMesh& design, const Partition& partition, int component);
std::vector<std::vector<Vec3>> chain_curves(const TriangleMesh& design, const Partition& partition,
                                            const QuadCage& cage);

// The exit status of a conversion or recomposition, the same for the command line, the
// Python module and the Blender batch script: 0 when everything asked for was made as asked;
// 3 when a solid was made but some component fell back below its best tier (each one in
// fallbacks(result.composed)); 1 when compose ran and no valid solid could be made.
// (2 is a usage error and 4 an internal error, both the command line's own.)
int exit_status(const Result& result);

// Whether `stage` ran in the conversion that gave `result`.
bool ran(const Result& result, const std::string& stage);

// report.json of a result (also stored in Result::report_json).
std::string make_report(const Inputs& inputs, const Options& options, const Result& result);
std::string make_recompose_report(const std::vector<SolidInput>& solids,
                                  const std::vector<std::string>& cage_names, const Result& result);

}  // namespace genbrep

// python/fit_bindings.cpp — the fit stage on numpy arrays, for tests and the add-on:
// limit_points (the limit surface of a cage exactly as Blender's Subdivision Surface
// modifier shows it, tessellated) and fit_cage (one cage fitted to one region).
// Thin: converts arrays, releases the GIL for the native work, converts back. A
// genbrep::Error becomes genbrep_native.ConversionError with .code and .stage.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "fit/fit.h"
#include "python/arrays.h"

namespace py = pybind11;
using namespace genbrep;
using genbrep::python::matrix_to_array;
using genbrep::python::to_indices;
using genbrep::python::to_vertices;

namespace {

// Fit errors without a stage of their own are reported as the fit stage's.
template <typename Fn>
auto guarded(Fn&& fn) {
  return python::guarded([&] {
    try {
      return fn();
    } catch (const Error& e) {
      throw e.with_stage("fit");
    }
  });
}

bool parse_boundary_smooth(const std::string& name) {
  if (name == "ALL") return true;
  if (name == "PRESERVE_CORNERS") return false;
  throw Error(Code::InvalidInput,
              "boundary_smooth must be 'ALL' or 'PRESERVE_CORNERS', not '" + name + "'");
}

// Cage from arrays: vertices, quads, optional creases ((k,2) vertex pairs, (k,) values).
QuadCage to_cage(const py::object& vertices, const py::object& quads,
                 const std::string& boundary_smooth, int quality, const py::object& crease_edges,
                 const py::object& crease_values) {
  QuadCage cage;
  cage.vertices = to_vertices(vertices, "cage vertices");
  cage.quads = to_indices<4>(quads, "cage quads");
  cage.scheme.boundary_smooth_all = parse_boundary_smooth(boundary_smooth);
  if (quality < 1 || quality > 10) throw Error(Code::InvalidInput, "quality must be in 1..10");
  cage.scheme.quality = quality;
  if (!crease_edges.is_none()) {
    const auto edges = to_indices<2>(crease_edges, "crease edges");
    const auto values =
        py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(crease_values);
    if (!values || values.ndim() != 1 || values.shape(0) != edges.rows()) {
      throw Error(Code::InvalidInput, "crease values must be a float array, one per crease edge");
    }
    for (Eigen::Index i = 0; i < edges.rows(); ++i) {
      cage.crease_edges.push_back({edges(i, 0), edges(i, 1)});
      cage.crease_values.push_back(values.data()[i]);
    }
  }
  return cage;
}

FitStrategy parse_strategy(const std::string& name) {
  for (FitStrategy s : {FitStrategy::Smooth, FitStrategy::Tight, FitStrategy::BoundaryTight}) {
    if (name == strategy_name(s)) return s;
  }
  throw Error(Code::InvalidInput,
              "strategy must be smooth, tight or boundary_tight, not '" + name + "'");
}

py::dict report_to_dict(const FitReport& r) {
  py::dict d;
  d["strategy"] = strategy_name(r.strategy);
  d["control_points"] = r.control_points;
  d["quads"] = r.quads;
  d["delta"] = r.delta;
  d["rms_design_to_limit"] = r.rms_design_to_limit;
  d["max_design_to_limit"] = r.max_design_to_limit;
  d["rms_limit_to_design"] = r.rms_limit_to_design;
  d["max_limit_to_design"] = r.max_limit_to_design;
  d["max_boundary_distance"] = r.max_boundary_distance;
  d["rounds"] = r.rounds;
  d["refinements"] = r.refinements;
  d["seconds"] = r.seconds;
  d["bound_held"] = r.bound_held;
  d["kept_initial"] = r.kept_initial;
  d["diagnostics"] = r.diagnostics;
  return d;
}

}  // namespace

void bind_fit(py::module_& m) {
  m.def(
      "limit_points",
      [](const py::object& vertices, const py::object& quads, int samples_per_edge,
         const std::string& boundary_smooth, int quality, const py::object& crease_edges,
         const py::object& crease_values) {
        return guarded([&] {
          const QuadCage cage =
              to_cage(vertices, quads, boundary_smooth, quality, crease_edges, crease_values);
          if (samples_per_edge < 1 || samples_per_edge > 1024) {
            throw Error(Code::InvalidInput, "samples_per_edge must be in 1..1024");
          }
          TriangleMesh mesh;
          {
            py::gil_scoped_release release;
            mesh = tessellate_limit(cage, samples_per_edge);
          }
          return py::make_tuple(matrix_to_array(mesh.vertices), matrix_to_array(mesh.triangles));
        });
      },
      py::arg("vertices"), py::arg("quads"), py::arg("samples_per_edge"),
      py::arg("boundary_smooth") = "ALL", py::arg("quality") = 3,
      py::arg("crease_edges") = py::none(), py::arg("crease_values") = py::none(),
      "limit_points(vertices (n,3) float64, quads (k,4) int, samples_per_edge, "
      "boundary_smooth='ALL',\n"
      "             quality=3, crease_edges=None (c,2), crease_values=None (c,) in [0,1])\n"
      "-> (vertices (N,3) float64, faces (M,3) int32)\n\n"
      "The Catmull–Clark limit surface of the cage as Blender's Subdivision Surface modifier\n"
      "evaluates it (use_limit_surface on, the given boundary_smooth and quality, creases as\n"
      "Blender edge creases), sampled at u, v = i/n, j/n on every quad (Blender level L shows\n"
      "n = 2^L) and triangulated watertight; cage vertices' limit points come first.");

  m.def(
      "fit_cage",
      [](const py::object& vertices, const py::object& quads,
         const std::vector<std::vector<int>>& chains, const py::object& region_vertices,
         const py::object& region_faces, const std::vector<py::object>& boundary_curves,
         const std::string& strategy, double delta, int rounds, double fairness_weight,
         int max_control_points) {
        return guarded([&] {
          QuadCage cage = to_cage(vertices, quads, "ALL", 3, py::none(), py::none());
          cage.boundary_chains = chains;
          cage.chain_loop.resize(chains.size());
          for (size_t i = 0; i < chains.size(); ++i) cage.chain_loop[i] = static_cast<int>(i);
          TriangleMesh region;
          region.vertices = to_vertices(region_vertices, "region vertices");
          region.triangles = to_indices<3>(region_faces, "region faces");
          std::vector<std::vector<Vec3>> curves;
          for (const auto& curve : boundary_curves) {
            const Vertices c = to_vertices(curve, "boundary curve");
            curves.emplace_back();
            for (Eigen::Index i = 0; i < c.rows(); ++i)
              curves.back().push_back(c.row(i).transpose());
          }
          FitOptions options;
          options.strategy = parse_strategy(strategy);
          options.delta = delta;
          options.rounds = rounds;
          options.fairness_weight = fairness_weight;
          options.max_control_points = max_control_points;
          Fitted fitted;
          {
            py::gil_scoped_release release;
            fitted = fit_cage(cage, region, curves, options, Context());
          }
          py::dict out;
          out["vertices"] = matrix_to_array(fitted.cage.vertices);
          out["quads"] = matrix_to_array(fitted.cage.quads);
          out["boundary_chains"] = fitted.cage.boundary_chains;
          out["report"] = report_to_dict(fitted.report);
          return out;
        });
      },
      py::arg("vertices"), py::arg("quads"), py::arg("boundary_chains"), py::arg("region_vertices"),
      py::arg("region_faces"), py::arg("boundary_curves"), py::arg("strategy") = "smooth",
      py::arg("delta") = 0.0, py::arg("rounds") = 4, py::arg("fairness_weight") = 0.3,
      py::arg("max_control_points") = 20000,
      "fit_cage(vertices, quads, boundary_chains, region_vertices, region_faces, boundary_curves,\n"
      "         strategy='smooth', delta=0, rounds=4, fairness_weight=0.3, "
      "max_control_points=20000)\n"
      "-> dict(vertices, quads, boundary_chains, report)\n\n"
      "Fits one cage (boundary 'ALL', quality 3) to one region; boundary_curves[i] (closed\n"
      "polylines, (n,3)) belongs to boundary_chains[i]. Strategies: smooth, tight, "
      "boundary_tight.");
}

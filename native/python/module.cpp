// python/module.cpp — genbrep_native: the pipeline on numpy arrays.
// Thin: converts arrays and dicts to Inputs/Options, releases the GIL for the native
// work, converts the Result back. Errors become genbrep_native.ConversionError (with
// .code and .stage); a progress callback returning False raises CancelledError.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "mesh/mesh.h"
#include "python/arrays.h"
#include "pipeline/pipeline.h"

namespace py = pybind11;
using namespace genbrep;
using namespace genbrep::python;

namespace {

PyObject* g_conversion_error = nullptr;
PyObject* g_cancelled_error = nullptr;

TriangleMesh to_mesh(const py::dict& d, const std::string& what) {
  if (!d.contains("vertices") || !d.contains("faces")) {
    throw Error(Code::InvalidInput, what + ": needs 'vertices' and 'faces'");
  }
  TriangleMesh mesh;
  mesh.vertices = to_vertices(d["vertices"], what + ": vertices");
  mesh.triangles = to_indices<3>(d["faces"], what + ": faces");
  return mesh;
}

py::dict partition_dict(const Partition& partition) {
  py::dict p;
  p["face_solid"] = vector_to_array(partition.face_solid);
  p["face_component"] = vector_to_array(partition.face_component);
  p["organic_components"] = partition.organic_components;
  py::list loops;
  for (const auto& loop : partition.loops) {
    py::dict l;
    l["vertices"] = vector_to_array(loop.vertices);
    l["solids"] = loop.solids;
    l["component"] = loop.component;
    loops.append(l);
  }
  p["loops"] = loops;
  return p;
}

Options to_options(const py::object& obj) {
  Options options;
  if (obj.is_none()) return options;
  const py::dict d = obj.cast<py::dict>();
  for (const auto& item : d) {
    const std::string key = py::str(item.first);
    const py::handle value = item.second;
    if (key == "tolerance") {
      options.incidence.tolerance = value.is_none() ? 0.0 : value.cast<double>();
    } else if (key == "incidence") {
      const std::string mode = value.cast<std::string>();
      if (mode == "grid") options.incidence.mode = IncidenceOptions::Mode::Grid;
      else if (mode == "distance") options.incidence.mode = IncidenceOptions::Mode::Distance;
      else throw Error(Code::InvalidInput, "option incidence must be 'distance' or 'grid', got '" + mode + "'");
    } else if (key == "grid_origin") {
      const auto o = value.cast<std::vector<double>>();
      if (o.size() != 3) throw Error(Code::InvalidInput, "option grid_origin needs three numbers");
      options.incidence.grid_origin = Vec3(o[0], o[1], o[2]);
    } else if (key == "grid_h") {
      options.incidence.grid_h = value.cast<double>();
    } else if (key == "target_edge_length") {
      options.field.target_edge_length = value.is_none() ? 0.0 : value.cast<double>();
    } else if (key == "size_scale") {
      options.field.density = value.cast<double>();
      if (!(options.field.density > 0)) throw Error(Code::InvalidInput, "option size_scale must be positive");
    } else if (key == "fitting") {
      const std::string name = value.cast<std::string>();
      if (!parse_strategy(name, &options.fit.strategy)) {
        throw Error(Code::InvalidInput, "option fitting must be smooth, tight or boundary_tight, got '" + name + "'");
      }
    } else if (key == "until") {
      options.until = value.is_none() ? "" : value.cast<std::string>();
    } else {
      throw Error(Code::InvalidInput, "unknown option '" + key + "'");
    }
  }
  return options;
}

SolidInput to_solid(const py::handle& obj, size_t i) {
  const py::dict s = obj.cast<py::dict>();
  SolidInput solid;
  solid.name = s.contains("name") ? py::str(s["name"]).cast<std::string>() : "solid " + std::to_string(i);
  const std::string role = s.contains("role") ? py::str(s["role"]).cast<std::string>() : "";
  if (!parse_role(role, &solid.role)) {
    throw Error(Code::InvalidInput, "solid '" + solid.name + "' has role '" + role +
                                        "'; roles are keep_in, keep_out, seed");
  }
  solid.mesh = to_mesh(s, "solid '" + solid.name + "'");
  return solid;
}

// The cage vertices of `cage`'s component that are irregular where no field singularity
// explains it (QuadStats::off_singularities). Fitting and pulling keep the quad stage's
// vertices first, in order (split_chords, pull), so its indices hold in the final cage.
std::vector<int> off_singularity_vertices(const Result& result, const QuadCage& cage) {
  std::vector<int> out;
  for (size_t i = 0; i < result.quads.cages.size() && i < result.quads.stats.size(); ++i) {
    if (result.quads.cages[i].component != cage.component) continue;
    for (const auto& off : result.quads.stats[i].off_singularities)
      if (off.vertex < cage.vertices.rows()) out.push_back(off.vertex);
  }
  return out;
}

// The cages to hand on (final_cages: pulled where compose used them) as dicts.
py::list cages_list(const Result& result) {
  py::list cages;
  for (const QuadCage& cage : final_cages(result)) {
    py::dict c;
    c["name"] = "component " + std::to_string(cage.component);
    c["component"] = cage.component;
    c["vertices"] = matrix_to_array(cage.vertices);
    c["faces"] = matrix_to_array(cage.quads);
    std::vector<int> pairs;
    for (const auto& e : cage.crease_edges) pairs.insert(pairs.end(), e.begin(), e.end());
    py::array_t<int32_t> crease_edges({static_cast<py::ssize_t>(cage.crease_edges.size()), py::ssize_t(2)});
    std::copy(pairs.begin(), pairs.end(), crease_edges.mutable_data());
    c["crease_edges"] = crease_edges;
    c["crease_values"] = py::array_t<float>(static_cast<py::ssize_t>(cage.crease_values.size()), cage.crease_values.data());
    py::dict scheme;
    scheme["boundary_smooth"] = cage.scheme.boundary_smooth_all ? "ALL" : "PRESERVE_CORNERS";
    scheme["use_limit_surface"] = cage.scheme.use_limit_surface;
    scheme["quality"] = cage.scheme.quality;
    scheme["levels"] = cage.scheme.levels;
    c["subdivision"] = scheme;
    c["irregular_off_singularities"] = vector_to_array(off_singularity_vertices(result, cage));
    cages.append(c);
  }
  return cages;
}

py::object composed_dict(const Result& result) {
  if (!ran(result, "compose") || !result.composed.report.ok) return py::none();
  py::dict composed;
  composed["vertices"] = matrix_to_array(result.composed.mesh.vertices);
  composed["faces"] = matrix_to_array(result.composed.mesh.triangles);
  composed["face_source"] = vector_to_array(result.composed.mesh.triangle_source);
  return std::move(composed);
}

// The progress callback as a native ProgressCallback: it runs on this thread with the GIL
// re-acquired just for the call; a Python exception inside it cancels the run and is
// kept in *failure to be re-raised afterwards.
ProgressCallback progress_callback(const py::object& progress, std::string* failure) {
  if (progress.is_none()) return {};
  return [progress, failure](const std::string& stage, double fraction) {
    py::gil_scoped_acquire acquire;
    try {
      const py::object r = progress(stage, fraction);
      return r.is_none() || r.cast<bool>();
    } catch (py::error_already_set& e) {
      *failure = e.what();
      return false;
    }
  };
}

// Runs native work with the GIL released and progress going to `progress`. A Python
// exception inside the callback cancels the run and is re-raised as the reason.
template <typename Work>
Result run_released(const py::object& progress, Work&& work) {
  std::string callback_failure;
  const ProgressCallback callback = progress_callback(progress, &callback_failure);
  try {
    py::gil_scoped_release release;
    return work(Context(callback));
  } catch (const Error& e) {
    if (callback_failure.empty()) throw;
    throw Error(Code::InvalidInput, "the progress callback raised: " + callback_failure, e.stage());
  }
}

py::dict convert_py(const py::dict& design, const py::list& solids, const py::object& options_obj,
                    const py::object& progress) {
  Inputs inputs;
  inputs.design.name = design.contains("name") ? py::str(design["name"]).cast<std::string>() : "design";
  inputs.design.mesh = to_mesh(design, "design '" + inputs.design.name + "'");
  for (size_t i = 0; i < solids.size(); ++i) {
    inputs.solids.push_back(to_solid(solids[i], i));
  }
  const Options options = to_options(options_obj);

  const Result result = run_released(progress, [&](const Context& context) {
    return convert(inputs, options, context);
  });
  py::dict out;
  out["report"] = py::module_::import("json").attr("loads")(result.report_json);
  out["status"] = exit_status(result);
  out["fallbacks"] = fallbacks(result.composed);
  py::dict d;
  d["vertices"] = matrix_to_array(result.design.vertices);
  d["faces"] = matrix_to_array(result.design.triangles);
  d["face_source"] = vector_to_array(result.design.triangle_source);
  out["design"] = d;
  if (ran(result, "partition")) {
    out["partition"] = partition_dict(result.partition);
  } else {
    out["partition"] = py::none();
  }
  if (ran(result, "relax")) {
    const Relaxed& r = result.relaxed;
    py::dict relaxed;
    relaxed["vertices"] = matrix_to_array(r.design.vertices);
    relaxed["faces"] = matrix_to_array(r.design.triangles);
    relaxed["face_source"] = vector_to_array(r.design.triangle_source);
    relaxed["partition"] = partition_dict(r.partition);
    out["relaxed"] = relaxed;
  } else {
    out["relaxed"] = py::none();
  }
  if (ran(result, "field")) {
    const CrossField& f = result.field;
    py::dict field;
    field["direction"] = matrix_to_array(f.direction);
    field["size_u"] = py::array_t<double>(f.size_u.size(), f.size_u.data());
    field["size_v"] = py::array_t<double>(f.size_v.size(), f.size_v.data());
    std::vector<int> vertices, index, component;
    for (const auto& s : f.singularities) {
      vertices.push_back(s.vertex);
      index.push_back(s.index);
      component.push_back(s.component);
    }
    field["singular_vertices"] = vector_to_array(vertices);
    field["singular_index"] = vector_to_array(index);
    field["singular_component"] = vector_to_array(component);
    out["field"] = field;
  } else {
    out["field"] = py::none();
  }
  out["cages"] = cages_list(result);
  out["composed"] = composed_dict(result);
  return out;
}

// A cage dict {name, vertices (n,3), faces (k,4), crease_edges (m,2), crease_values (m)}.
QuadCage to_cage(const py::handle& obj, size_t i, std::string* name) {
  const py::dict d = obj.cast<py::dict>();
  *name = d.contains("name") ? py::str(d["name"]).cast<std::string>() : "cage " + std::to_string(i);
  const std::string what = "cage '" + *name + "'";
  if (!d.contains("vertices") || !d.contains("faces")) throw Error(Code::InvalidInput, what + ": needs 'vertices' and 'faces'");
  PolygonSoup soup;
  soup.vertices = to_vertices(d["vertices"], what + ": vertices");
  auto faces = py::array_t<int64_t, py::array::c_style | py::array::forcecast>::ensure(d["faces"]);
  if (!faces || faces.ndim() != 2) throw Error(Code::InvalidInput, what + ": faces must be a K×4 integer array");
  const py::ssize_t corners = faces.shape(1);
  for (py::ssize_t f = 0; f < faces.shape(0); ++f) {
    for (py::ssize_t k = 0; k < corners; ++k) {
      const int64_t v = faces.at(f, k);
      if (v < 0 || v > INT32_MAX) throw Error(Code::InvalidInput, what + ": face index " + std::to_string(v) + " is out of range");
      soup.indices.push_back(static_cast<int>(v));
    }
    soup.offsets.push_back(static_cast<int>(soup.indices.size()));
  }
  QuadCage cage = cage_from_polygons(soup, *name);
  if (d.contains("crease_edges") && !d["crease_edges"].is_none()) {
    auto edges = py::array_t<int64_t, py::array::c_style | py::array::forcecast>::ensure(d["crease_edges"]);
    auto values = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(
        d.contains("crease_values") ? py::object(d["crease_values"]) : py::object(py::list()));
    if (!edges || !values || (edges.size() > 0 && (edges.ndim() != 2 || edges.shape(1) != 2)) ||
        values.size() * 2 != edges.size()) {
      throw Error(Code::InvalidInput, what + ": crease_edges must be M×2 with M crease_values");
    }
    for (py::ssize_t e = 0; e < values.size(); ++e) {
      cage.crease_edges.push_back({static_cast<int>(edges.data()[2 * e]), static_cast<int>(edges.data()[2 * e + 1])});
      cage.crease_values.push_back(values.data()[e]);
    }
  }
  return cage;
}

py::dict recompose_py(const py::list& solid_list, const py::list& cage_list, const py::object& options_obj,
                      const py::object& progress) {
  std::vector<SolidInput> solids;
  for (size_t i = 0; i < solid_list.size(); ++i) solids.push_back(to_solid(solid_list[i], i));
  std::vector<QuadCage> cages;
  std::vector<std::string> names(cage_list.size());
  for (size_t i = 0; i < cage_list.size(); ++i) cages.push_back(to_cage(cage_list[i], i, &names[i]));
  const Options options = to_options(options_obj);
  const Result result = run_released(progress, [&](const Context& context) {
    return recompose(solids, cages, options, context, names);
  });
  py::dict out;
  out["report"] = py::module_::import("json").attr("loads")(result.report_json);
  out["status"] = exit_status(result);
  out["fallbacks"] = fallbacks(result.composed);
  py::list cages_out = cages_list(result);
  for (size_t i = 0; i < cages_out.size() && i < names.size(); ++i) cages_out[i]["name"] = names[i];
  out["cages"] = cages_out;
  out["composed"] = composed_dict(result);
  return out;
}

}  // namespace

namespace genbrep::python {

void set_python_error(const Error& e) {
  PyObject* type = e.code() == Code::Cancelled ? g_cancelled_error : g_conversion_error;
  py::object instance = py::reinterpret_steal<py::object>(PyObject_CallFunction(type, "s", e.what()));
  if (!instance) throw py::error_already_set();
  instance.attr("code") = code_name(e.code());
  instance.attr("stage") = e.stage();
  PyErr_SetObject(type, instance.ptr());
}

}  // namespace genbrep::python

void bind_fit(py::module_& m);  // fit_bindings.cpp: limit_points, fit_cage

PYBIND11_MODULE(genbrep_native, m) {
  m.doc() = "genbrep native core: generative design to editable cages and a watertight solid";
  m.attr("__version__") = kVersion;
  g_conversion_error = PyErr_NewExceptionWithDoc(
      "genbrep_native.ConversionError",
      "A conversion failed: bad input or a stage that could not recover. Attributes: code, stage.",
      PyExc_RuntimeError, nullptr);
  g_cancelled_error = PyErr_NewExceptionWithDoc("genbrep_native.CancelledError",
                                                "The progress callback cancelled the conversion.",
                                                g_conversion_error, nullptr);
  m.attr("ConversionError") = py::handle(g_conversion_error);
  m.attr("CancelledError") = py::handle(g_cancelled_error);
  m.attr("STAGES") = py::tuple(py::cast(stage_names()));
  bind_fit(m);
  // Option keys convert() accepts, so callers can send only what this build understands.
  m.attr("OPTION_KEYS") = py::make_tuple("tolerance", "incidence", "grid_origin", "grid_h", "until",
                                         "target_edge_length", "size_scale", "fitting");

  m.def(
      "convert",
      [](const py::dict& design, const py::list& solids, const py::object& options,
         const py::object& progress) {
        return guarded([&] { return convert_py(design, solids, options, progress); });
      },
      py::arg("design"), py::arg("solids") = py::list(), py::arg("options") = py::none(),
      py::arg("progress") = py::none(),
      "convert(design, solids=[], options=None, progress=None) -> dict\n\n"
      "design: dict(name, vertices float64 N×3, faces int M×3); solids: list of dict(name,\n"
      "role in keep_in/keep_out/seed, vertices, faces); options: dict(tolerance, incidence,\n"
      "grid_origin, grid_h, until); progress(stage, fraction) -> bool, False cancels.\n"
      "The result's 'status' is the command line's exit status (0 made as asked, 3 a solid\n"
      "with fallbacks, listed one per line in 'fallbacks', 1 no solid).");

  m.def(
      "recompose",
      [](const py::list& solids, const py::list& cages, const py::object& options, const py::object& progress) {
        return guarded([&] { return recompose_py(solids, cages, options, progress); });
      },
      py::arg("solids"), py::arg("cages"), py::arg("options") = py::none(), py::arg("progress") = py::none(),
      "recompose(solids, cages, options=None, progress=None) -> dict(report, composed, cages)\n\n"
      "Re-composes after cage edits: cages is a list of dict(name, vertices float64 n×3, faces\n"
      "int k×4, crease_edges m×2 optional, crease_values m optional); each cage's boundary\n"
      "loops are found from its quads and given the solids nearest to them, then pulled and\n"
      "composed. 'cages' returns the pulled cages in convert()'s format.");

  m.def(
      "read_mesh",
      [](const std::string& path) {
        return guarded([&] {
          const TriangleMesh mesh = triangulate(read_polygon_file(path), "'" + path + "'");
          return py::make_tuple(matrix_to_array(mesh.vertices), matrix_to_array(mesh.triangles));
        });
      },
      py::arg("path"), "read_mesh(path) -> (vertices N×3 float64, faces M×3 int32); OBJ/PLY/STL/OFF");

  m.def(
      "validate_mesh",
      [](const py::object& vertices, const py::object& faces) {
        return guarded([&] {
          TriangleMesh mesh;
          mesh.vertices = to_vertices(vertices, "mesh: vertices");
          mesh.triangles = to_indices<3>(faces, "mesh: faces");
          const MeshValidation v = validate(mesh);
          py::dict d;
          d["vertices"] = v.vertices;
          d["triangles"] = v.triangles;
          d["non_finite_vertices"] = v.non_finite_vertices;
          d["repeated_index_triangles"] = v.repeated_index_triangles;
          d["zero_area_triangles"] = v.zero_area_triangles;
          d["boundary_edges"] = v.boundary_edges;
          d["non_manifold_edges"] = v.non_manifold_edges;
          d["non_manifold_vertices"] = v.non_manifold_vertices;
          d["inconsistent_edges"] = v.inconsistent_edges;
          d["duplicate_triangles"] = v.duplicate_triangles;
          d["shells"] = v.shells;
          d["signed_volume"] = v.signed_volume;
          d["closed_manifold"] = v.closed_manifold();
          return d;
        });
      },
      py::arg("vertices"), py::arg("faces"), "validate_mesh(vertices, faces) -> dict of counts");
}

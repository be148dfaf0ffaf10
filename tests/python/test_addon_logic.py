"""The add-on's bpy-free modules, with plain pytest: /usr/bin/python3 -m pytest tests/python."""

import json
import os
import sys
import threading
import types

import numpy as np
import pytest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "addon"))

from genbrep import checks, job, native, options, report, results  # noqa: E402


def test_package_imports_without_bpy():
    assert "bpy" not in sys.modules


# options ------------------------------------------------------------------------------------

def test_defaults_use_distance_without_a_design_grid():
    opts, notes = options.native_options(options.Settings(), "part")
    assert opts == {"incidence": "distance"}
    assert notes == ["not used by this genbrep_native build: fitting, size_scale"]


def test_auto_incidence_uses_the_design_grid():
    grid = ((0.1, 0.2, 0.3), 0.5)
    opts, notes = options.native_options(options.Settings(), "part", design_grid=grid)
    assert opts == {"incidence": "grid", "grid_origin": (0.1, 0.2, 0.3), "grid_h": 0.5}
    assert "h = 0.5" in notes[0]


def test_grid_settings_override_the_design_grid():
    settings = options.Settings(incidence="grid", grid_h=0.2, grid_origin=(1, 2, 3))
    opts, _ = options.native_options(settings, "part", design_grid=((0, 0, 0), 0.5))
    assert (opts["grid_h"], opts["grid_origin"]) == (0.2, (1.0, 2.0, 3.0))


def test_grid_without_voxel_size_names_the_design():
    with pytest.raises(options.OptionError, match="'part'.*genbrep_grid_h"):
        options.native_options(options.Settings(incidence="grid"), "part")


def test_tolerance_until_and_pipeline_keys():
    settings = options.Settings(tolerance=0.05, until="incidence", density="edge_length",
                                target_edge_length=2.0, fitting="tight")
    opts, notes = options.native_options(
        settings, "part", stages=("mesh", "incidence"),
        option_keys=frozenset({"fitting", "target_edge_length", "size_scale"}))
    assert opts == {"tolerance": 0.05, "incidence": "distance", "until": "incidence",
                    "fitting": "tight", "target_edge_length": 2.0}
    assert notes == []


def test_stage_missing_from_the_build_is_an_error():
    with pytest.raises(options.OptionError, match="stage 'fit' is not in this.*mesh, incidence"):
        options.native_options(options.Settings(until="fit"), "part", stages=("mesh", "incidence"))


def test_stages_run():
    assert options.stages_run(("mesh", "incidence", "partition"), {"until": "incidence"}) == (
        "mesh", "incidence")
    assert options.stages_run(("mesh", "incidence"), {}) == ("mesh", "incidence")


@pytest.mark.parametrize("settings, match", [
    (options.Settings(tolerance=-1.0), "Tolerance must be >= 0"),
    (options.Settings(size_scale=0.0), "Size field scale must be > 0"),
    (options.Settings(grid_h=float("nan")), "Voxel size"),
    (options.Settings(fitting="loose"), "unknown fitting 'loose'"),
])
def test_bad_settings_are_named(settings, match):
    with pytest.raises(options.OptionError, match=match):
        options.native_options(settings, "part")


def test_settings_from_property_values():
    values = {"tolerance_auto": True, "tolerance": 0.3, "incidence": "GRID", "grid_h": 0.1,
              "grid_origin": (1, 2, 3), "density": "EDGE_LENGTH", "target_edge_length": 0.5,
              "size_scale": 2.0, "fitting": "BOUNDARY_TIGHT", "until": "ALL"}
    settings = options.settings_from_values(values)
    assert settings == options.Settings(tolerance=0.0, incidence="grid", grid_origin=(1, 2, 3),
                                        grid_h=0.1, density="edge_length",
                                        target_edge_length=0.5, size_scale=2.0,
                                        fitting="boundary_tight", until="all")


@pytest.mark.parametrize("properties, expected", [
    ({"genbrep_grid_h": 0.1, "genbrep_grid_origin": [1, 2, 3]}, ((1.0, 2.0, 3.0), 0.1)),
    ({"genbrep_grid_h": 0.1}, ((0.0, 0.0, 0.0), 0.1)),
    ({}, None),
    ({"genbrep_grid_h": -1.0}, None),
    ({"genbrep_grid_h": "x"}, None),
])
def test_grid_from_properties(properties, expected):
    assert options.grid_from_properties(properties) == expected


# checks -------------------------------------------------------------------------------------

def test_failure_line_is_the_command_lines():
    assert checks.failure_line("design 'part' is open: 3 boundary edges", "mesh") == (
        "error in mesh: design 'part' is open: 3 boundary edges")
    assert checks.failure_line("internal error in genbrep_native: boom") == (
        "internal error in genbrep_native: boom")
    solids = [dict(name="b", role="SEED", vertices=np.zeros((0, 3)), faces=np.zeros((0, 3)))]
    assert checks.native_solids(solids)[0]["role"] == "seed"


@pytest.mark.parametrize("names, requested, active, expected", [
    (["a"], None, None, "a"),
    (["a", "b"], None, "b", "b"),
    (["a", "b"], "a", "b", "a"),
])
def test_choose_design(names, requested, active, expected):
    assert checks.choose_design(names, requested, active) == expected


@pytest.mark.parametrize("names, requested, match", [
    ([], None, "no object has the role Design"),
    (["a", "b"], None, "2 objects have the role Design"),
    (["a"], "c", "'c' does not have the role Design"),
])
def test_choose_design_errors(names, requested, match):
    with pytest.raises(checks.InputError, match=match):
        checks.choose_design(names, requested, None)


def test_role_counts():
    assert checks.role_counts(["DESIGN", "KEEP_IN", "KEEP_IN"]) == {
        "NONE": 0, "DESIGN": 1, "KEEP_IN": 2, "KEEP_OUT": 0, "SEED": 0}


# job ----------------------------------------------------------------------------------------

class ConversionError(Exception):
    pass


class CancelledError(ConversionError):
    pass


def _fake_native(convert):
    return types.SimpleNamespace(convert=convert, ConversionError=ConversionError,
                                 CancelledError=CancelledError)


def _stepping_convert(steps=("mesh", "incidence", "partition"), gate=None):
    def convert(design, solids, options, progress):
        for stage in steps:
            for fraction in (0.0, 0.5, 1.0):
                if gate is not None:
                    gate.wait()
                if progress(stage, fraction) is False:
                    raise CancelledError("cancelled")
        return {"design": design, "report": {}}
    return convert


def test_job_runs_and_reports_progress():
    seen = []
    run = job.ConversionJob(_fake_native(_stepping_convert()), {"name": "d"}, [], {},
                            on_progress=lambda s, f: seen.append((s, f)))
    assert run.run() == job.DONE
    assert run.result["design"] == {"name": "d"}
    assert seen[0] == ("mesh", 0.0) and seen[-1] == ("partition", 1.0)
    assert run.snapshot() == job.Snapshot(job.DONE, "partition", 1.0)


def test_job_cancel_from_progress():
    run = job.ConversionJob(_fake_native(_stepping_convert()), {}, [], {})
    run.on_progress = lambda stage, fraction: stage == "incidence" and run.cancel()
    assert run.run() == job.CANCELLED
    assert run.result is None and run.snapshot().stage == "incidence"


def test_job_cancel_before_start():
    run = job.ConversionJob(_fake_native(_stepping_convert()), {}, [], {})
    run.cancel()
    assert run.run() == job.CANCELLED


def test_job_cancel_after_the_last_check_drops_the_result():
    def convert(design, solids, options, progress):
        run.cancel()
        return {"report": {}}
    run = job.ConversionJob(_fake_native(convert), {}, [], {})
    assert run.run() == job.CANCELLED and run.result is None


def test_threaded_job_keeps_the_caller_free_and_cancels():
    gate = threading.Event()
    run = job.ConversionJob(_fake_native(_stepping_convert(gate=gate)), {}, [], {})
    run.start()
    assert run.state == job.RUNNING  # blocked on the gate, yet start() returned
    run.cancel()
    gate.set()
    assert run.wait(timeout=10)
    assert run.state == job.CANCELLED


def test_job_conversion_error_keeps_code_and_stage():
    def convert(design, solids, options, progress):
        error = ConversionError("keep-in 'pad' is open: 3 boundary edges")
        error.code, error.stage = "invalid_input", "mesh"
        raise error
    run = job.ConversionJob(_fake_native(convert), {}, [], {})
    assert run.run() == job.FAILED
    assert (run.error, run.error_code, run.error_stage) == (
        "keep-in 'pad' is open: 3 boundary edges", "invalid_input", "mesh")


def test_job_unexpected_error_is_caught_with_traceback():
    def convert(design, solids, options, progress):
        raise ZeroDivisionError("boom")
    run = job.ConversionJob(_fake_native(convert), {}, [], {})
    assert run.run() == job.FAILED
    assert run.error == "internal error in genbrep_native: ZeroDivisionError: boom"
    assert "Traceback" in run.details


# report -------------------------------------------------------------------------------------

STAGES = ("mesh", "incidence", "partition")


def test_progress_text_and_fraction():
    assert report.progress_text("incidence", 0.5, STAGES) == \
        "genbrep: incidence 50% (stage 2 of 3)"
    assert report.progress_text("", 0.0, STAGES) == "genbrep: starting"
    assert report.progress_text("relax", 0.25, STAGES) == "genbrep: relax 25%"
    assert report.overall_fraction("incidence", 0.5, STAGES) == pytest.approx(0.5)


def test_progress_printer_prints_stage_starts_and_quarters():
    lines = []
    printer = report.ProgressPrinter(STAGES, lines.append)
    for stage in ("mesh", "incidence"):
        for fraction in np.linspace(0, 1, 11):
            printer(stage, float(fraction))
    assert len(lines) == 10  # 0, 30, 50, 80, 100 % for each stage
    assert lines[0] == "genbrep: mesh 0% (stage 1 of 3)"


REPORT = {"stages": {"mesh": 0.25, "partition": 0.5}, "seconds_total": 0.75,
          "counts": {"triangles": 100, "per_solid": [1, 2]},
          "tolerance": {"mode": "grid", "value": 0.1}, "genbrep_version": "0.1.0",
          "inputs": {"nested": "skipped"}, "diagnostics": ["loop 3 repaired"],
          "notes": ["quad: component 0: corners squared"]}


def test_report_lines():
    assert report.report_lines(REPORT, ["a note"]) == [
        "time: 0.75 s", "  mesh: 0.250 s", "  partition: 0.500 s", "counts:",
        "  triangles: 100", "  per_solid: 1, 2", "tolerance: mode grid, value 0.1",
        "genbrep_version: 0.1.0", "note: a note", "note: quad: component 0: corners squared",
        "warning: loop 3 repaired"]


CAGES = [{"component": 0, "quads": 3903, "interior_valence4_fraction": 0.978,
          "boundary_valence3_fraction": 1.0, "irregular_vertices": 84,
          "irregular_vertices_off_singularities": 0, "irregular_vertices_off_singularities_at": [],
          "mean_angle_deviation_degrees": 3.69, "method": "field-aligned patch layout",
          "fit": {"rms_design_to_limit": 0.0032, "max_design_to_limit": 0.015}},
         {"component": 2, "quads": 120, "interior_valence4_fraction": 0.5,
          "boundary_valence3_fraction": 0.9, "irregular_vertices": 30,
          "irregular_vertices_off_singularities": 5,
          "irregular_vertices_off_singularities_at": [
              {"position": [float(k), 0.5, -0.25], "valence": 5 if k % 2 else 3,
               "quarter_turns": -1 if k % 2 else 1}
              for k in range(5)],
          "mean_angle_deviation_degrees": 20.0,
          "method": "fallback: split coarse remesh, not field-aligned"}]


def test_cage_lines_say_how_regular_each_cage_is_and_where_it_is_not():
    lines = report.cage_lines({"cages": CAGES,
                               "cage_failures": [{"component": 1, "reason": "too thin"}]})
    assert lines == [
        "cages:",
        "  cage 0 (component 0): 3903 quads, corners 3.7° off square on average",
        "    valence 4 inside 97.8%, 3 on the boundary 100.0%; 84 irregular, 0 away from "
        "singularities",
        "    fit: design to limit surface rms 0.0032, max 0.015",
        "  cage 1 (component 2): 120 quads FALLBACK, not field-aligned, corners 20.0° off "
        "square on average",
        "    valence 4 inside 50.0%, 3 on the boundary 90.0%; 30 irregular, 5 away from "
        "singularities",
        "    away from singularities (valence, quarter turns unexplained): (0, 0.5, -0.25) "
        "valence 3, +1; (1, 0.5, -0.25) valence 5, -1; (2, 0.5, -0.25) valence 3, +1; "
        "(3, 0.5, -0.25) valence 5, -1; ... (5 in all)",
        "    (the cage's vertex group 'genbrep irregular off singularities' selects them in "
        "Edit Mode)",
        "  component 1: no cage (too thin)"]
    assert report.cage_lines(REPORT) == []
    assert "cages:" in report.report_lines(dict(REPORT, cages=CAGES))


def test_notes_are_not_warnings():
    assert report.warning_count(REPORT) == 1
    assert report.warning_count(dict(REPORT, diagnostics=[])) == 0
    summary = report.result_summary("part", {"report": dict(REPORT, diagnostics=[])})
    assert "warning" not in summary


def test_report_json_round_trip_with_numpy_values():
    data = dict(REPORT, counts={"per_solid": np.array([1, 2])})
    text = report.to_json(data, ["a note"])
    assert "note: a note" in report.lines_from_json(text)
    assert "  per_solid: 1, 2" in report.lines_from_json(text)
    # The add-on's notes go before the stages' notes, which are kept (a stored report
    # says how the cage was made, as the CLI's report.json does).
    assert json.loads(text)["notes"] == ["a note", "quad: component 0: corners squared"]
    assert "note: quad: component 0: corners squared" in report.lines_from_json(text)
    assert json.loads(report.to_json(data))["notes"] == ["quad: component 0: corners squared"]
    assert report.lines_from_json("not json") == []


def test_format_value_shortens_long_lists():
    assert report.format_value(list(range(10)), max_items=3) == "0, 1, 2, ... (10 in all)"


def test_result_summary():
    result = {"report": REPORT,
              "partition": {"face_component": np.array([-1, 0, 1, 1]), "loops": [{}, {}]},
              "cages": [{}], "composed": None}
    assert report.result_summary("part", result) == (
        "Converted 'part' in 0.75 s: 2 organic components, 2 boundary loops, 1 cage, "
        "not composed; 1 warning (see the genbrep panel)")


# results ------------------------------------------------------------------------------------

def test_names():
    assert results.collection_name("part") == "genbrep part"
    assert results.cage_name("part", {"name": "arm"}, 0) == "part cage arm"
    assert results.cage_name("part", {}, 2) == "part cage 2"


def test_face_colours_by_solid_and_component():
    colours = results.face_colours([0, 1, -1, -1, -1], [-1, -1, 0, 0, 1],
                                   ["keep_in", "keep_out"])
    assert colours.shape == (5, 4) and colours.dtype == np.float32
    np.testing.assert_array_equal(colours[2], colours[3])
    assert len({tuple(c) for c in colours.tolist()}) == 4
    assert colours[1][0] > colours[1][2]  # keep-out reddish
    assert colours[0][2] > colours[0][0]  # keep-in bluish


def test_edge_indices():
    edges = np.array([[0, 1], [1, 2], [2, 0], [5, 3]])
    np.testing.assert_array_equal(results.edge_indices(edges, [[1, 0], [3, 5], [0, 3]]),
                                  [0, 3, -1])
    assert len(results.edge_indices(np.zeros((0, 2)), [[0, 1]])) == 1


def test_loop_edges_close_each_cycle():
    edges, owner = results.loop_edges([{"vertices": [4, 5, 6]}, {"vertices": [1]},
                                       {"vertices": [7, 8]}])
    np.testing.assert_array_equal(edges, [[4, 5], [5, 6], [6, 4], [7, 8], [8, 7]])
    np.testing.assert_array_equal(owner, [0, 0, 0, 2, 2])


def test_subdivision_settings_are_explicit():
    settings = results.subdivision_settings({"boundary_smooth": "preserve_corners",
                                             "use_limit_surface": False, "quality": 2,
                                             "levels": 1})
    assert settings["boundary_smooth"] == "PRESERVE_CORNERS"
    assert (settings["levels"], settings["quality"], settings["use_limit_surface"]) == (1, 2, False)
    assert settings["use_creases"] is True
    with pytest.raises(ValueError, match="boundary_smooth 'SHARP'"):
        results.subdivision_settings({"boundary_smooth": "SHARP"})


# native -------------------------------------------------------------------------------------

def test_native_status_explains_what_is_missing(monkeypatch):
    monkeypatch.setattr(native, "_loaded", True)
    monkeypatch.setattr(native, "_module", None)
    ok, lines = native.status()
    assert not ok
    assert lines[0] == "genbrep_native is missing: conversion is disabled."
    assert f"Python {sys.version_info.major}.{sys.version_info.minor}" in lines[1]
    assert native.required_suffix() in lines[2]


def test_native_stages_and_option_keys_of_a_module():
    module = types.SimpleNamespace(STAGES=("mesh",), OPTION_KEYS=("fitting",))
    assert native.stages(module) == ("mesh",)
    assert native.option_keys(module) == frozenset({"fitting"})
    assert native.option_keys(types.SimpleNamespace()) is None


def test_field_crosses_lie_in_each_face_and_are_perpendicular():
    vertices = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    faces = np.array([[0, 1, 2], [0, 1, 3], [0, 2, 3]])
    direction = np.array([[1, 0, 0], [0, 0, 1], [0, 1, 0]], float)
    organic = np.array([True, True, False])
    points, edges = results.field_crosses(vertices, faces, direction, organic)
    assert points.shape == (8, 3) and edges.shape == (4, 2)
    arms = points[edges[:, 1]] - points[edges[:, 0]]
    normals = np.array([[0, 0, 1], [0, 1, 0]], float).repeat(2, axis=0)
    assert np.allclose(np.sum(arms * normals, axis=1), 0)          # in the face plane
    assert np.allclose(np.sum(arms[0::2] * arms[1::2], axis=1), 0)  # arms perpendicular
    assert np.allclose(arms[0] / np.linalg.norm(arms[0]), [1, 0, 0])


def test_cage_input_keeps_quads_and_creased_edges_and_names_bad_cages():
    vertices = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [2, 0, 0], [2, 1, 0]], float)
    cage = checks.cage_input("c", vertices, [4, 4], [0, 1, 2, 3, 1, 4, 5, 2],
                             [[0, 1], [1, 2], [4, 5]], [0.0, 1.0, 0.5])
    assert cage["faces"].shape == (2, 4)
    assert cage["crease_edges"].tolist() == [[1, 2], [4, 5]]
    assert cage["crease_values"].tolist() == [1.0, 0.5]
    with pytest.raises(checks.InputError, match="cage 'c' is not a quad mesh: 1 faces"):
        checks.cage_input("c", vertices, [4, 3], [0, 1, 2, 3, 1, 4, 5], [], [])
    with pytest.raises(checks.InputError, match="cage 'c' has no faces"):
        checks.cage_input("c", vertices, [], [], [], [])

"""Convert on fixtures: the result collection, re-runs, cancelling, undo, input errors."""

import json

import bmesh
import bpy
import numpy as np
import pytest

from conftest import needs_native, scene_state
from genbrep import bridge, job, native, operators, results

pytestmark = needs_native

COLLECTION = results.collection_name("design")


def _convert(**settings):
    return bpy.ops.genbrep.convert("INVOKE_DEFAULT", **settings)


def _face_ints(mesh, name):
    values = np.empty(len(mesh.polygons), dtype=np.int32)
    mesh.attributes[name].data.foreach_get("value", values)
    return values


def test_convert_writes_partition_collection(open_fixture):
    open_fixture("components")
    assert _convert() == {"FINISHED"}
    collection = bpy.data.collections[COLLECTION]
    assert collection.name in bpy.context.scene.collection.children
    report = json.loads(collection[results.REPORT_PROPERTY])
    cage_names = sorted(o.name for o in collection.objects if " cage " in o.name)
    net_names = sorted(o.name for o in collection.objects if " control net " in o.name)
    names = sorted(o.name for o in collection.objects
                   if " cage " not in o.name and " control net " not in o.name)
    assert names == ["design boundary loops", "design composed", "design cross field",
                     "design partition", "design singularities"]
    assert report["composed"]["ok"]
    assert len(collection.objects["design composed"].data.polygons) == report["composed"]["triangles"]
    # The stored report keeps the stages' notes (how the cages were made) after the
    # add-on's own, as the CLI's report.json has them.
    assert report["notes"][0].startswith("grid incidence with the voxel size recorded")
    assert any(note.startswith("quad: component ") for note in report["notes"])
    # One cage object per cage the pipeline made, shown through its Subdivision Surface.
    assert len(cage_names) == len(report["cages"]) == len(net_names)
    assert [o.name for o in bridge.cage_objects(collection)] == cage_names
    for name in cage_names:
        cage = collection.objects[name]
        assert all(len(p.vertices) == 4 for p in cage.data.polygons)
        modifier = cage.modifiers[0]
        assert modifier.type == "SUBSURF" and modifier.use_limit_surface
        assert modifier.boundary_smooth == "ALL"

    mesh = collection.objects["design partition"].data
    solid = _face_ints(mesh, results.PARTITION_SOLID_ATTRIBUTE)
    component = _face_ints(mesh, results.PARTITION_COMPONENT_ATTRIBUTE)
    assert set(np.unique(solid)) == {-1, 0, 1, 2, 3}  # organic and the four blocks
    assert set(np.unique(component[solid == -1])) == {0, 1, 2, 3}  # one per tube
    assert np.all(component[solid >= 0] == -1)
    assert mesh.color_attributes[results.PARTITION_COLOR_ATTRIBUTE].domain == "CORNER"
    assert sorted(m.name for m in mesh.materials) == [
        *(f"genbrep component {c}" for c in range(4)),
        *(f"genbrep keep-in {s}" for s in range(4))]  # the four blocks
    assert report["counts"]["organic_components"] == 4

    # The cross field: a two-edge cross per organic face, hidden until the user shows it;
    # singular vertices with their indices, which sum to 4χ = 0 per tube (annuli).
    crosses = collection.objects["design cross field"]
    assert len(crosses.data.edges) == 2 * int(np.sum(solid == -1))
    assert crosses.hide_get() and crosses.hide_render
    points = collection.objects["design singularities"].data
    index = np.empty(len(points.vertices), dtype=np.int32)
    points.attributes["genbrep_index"].data.foreach_get("value", index)
    assert index.sum() == 0 and set(np.unique(index)) <= {-1, 1}
    assert [c["index_sum_quarter_turns"] for c in report["field"]["components"]] == [0, 0, 0, 0]


def test_convert_shows_the_composed_solid_and_cages_and_hides_the_inputs(open_fixture):
    open_fixture("seed")
    scene = bpy.context.scene
    inputs = [o for o in scene.objects if o.genbrep.role != "NONE"]
    assert len(inputs) == 3 and not any(o.hide_get() for o in inputs)
    assert _convert() == {"FINISHED"}
    collection = bpy.data.collections[COLLECTION]
    composed = collection.objects["design composed"]
    cages = bridge.cage_objects(collection)
    assert cages and not composed.hide_get()
    nets = [o for o in collection.objects if o.parent in cages]
    assert len(nets) == len(cages)
    for cage in cages:
        assert not cage.hide_get() and cage.display_type != "WIRE"
        net = next(o for o in nets if o.parent == cage)
        assert net.data == cage.data and net.display_type == "WIRE" and not net.hide_get()
    assert collection.objects["design partition"].hide_get()
    # The inputs are hidden in the viewport, unchanged otherwise; the toggle shows them.
    assert all(o.hide_get() and not o.hide_render for o in inputs)
    scene.genbrep_settings.show_inputs = True
    assert not any(o.hide_get() for o in inputs)
    scene.genbrep_settings.show_inputs = False
    assert all(o.hide_get() for o in inputs)
    default = bpy.data.materials.new("default").diffuse_color
    for obj in [composed, *cages, collection.objects["design partition"]]:
        for material in obj.data.materials:
            assert not np.allclose(material.diffuse_color, default), material.name


def test_rerun_replaces_results(open_fixture):
    open_fixture("boss")
    assert _convert() == {"FINISHED"}
    first = {kind: len(getattr(bpy.data, kind)) for kind in ("objects", "meshes", "collections")}
    assert _convert() == {"FINISHED"}
    second = {kind: len(getattr(bpy.data, kind)) for kind in ("objects", "meshes", "collections")}
    assert first == second
    assert not [name for name in bpy.data.objects.keys() if name.endswith(".001")]


def test_cancel_leaves_scene_unchanged(open_fixture):
    open_fixture("seed")
    before = scene_state()
    outcome = operators.convert_now(bpy.context, bpy.context.scene.genbrep_settings,
                                    on_progress=lambda run, stage, fraction: run.cancel())
    assert outcome.status == "CANCELLED" and "scene unchanged" in outcome.message
    assert scene_state() == before


def test_cancel_of_threaded_job_drops_its_result(open_fixture):
    open_fixture("arches")
    before = scene_state()
    prepared = operators.prepare(bpy.context, bpy.context.scene.genbrep_settings)
    prepared.job.start()
    prepared.job.cancel()
    assert prepared.job.wait(timeout=30)
    assert prepared.job.state == job.CANCELLED
    assert operators.finish(prepared).status == "CANCELLED"
    assert scene_state() == before


def test_undo_removes_results(open_fixture):
    open_fixture("boss")
    bpy.ops.ed.undo_push(message="before convert")
    assert _convert() == {"FINISHED"}
    if not bpy.ops.ed.undo.poll():
        pytest.skip("ed.undo cannot run under blender -b (no undo stack without a window); "
                    "test_modal.py checks undo in a windowed Blender")
    bpy.ops.ed.undo()
    assert COLLECTION not in bpy.data.collections


def test_convert_is_one_undo_step():
    assert "UNDO" in operators.GENBREP_OT_convert.bl_options


def test_stop_after_incidence(open_fixture):
    open_fixture("boss")
    assert _convert(until="INCIDENCE") == {"FINISHED"}
    assert "design partition" in bpy.data.collections[COLLECTION].objects


def test_stage_missing_from_build_is_reported(open_fixture):
    open_fixture("boss")
    missing = [s for s in ("compose", "fit") if s not in native.stages()]
    if not missing:
        pytest.skip("this build runs every stage")
    with pytest.raises(RuntimeError, match=f"stage '{missing[0]}' is not in this"):
        _convert(until=missing[0].upper())
    assert COLLECTION not in bpy.data.collections


def test_open_keep_in_is_named(open_fixture):
    open_fixture("boss")
    mesh = bpy.data.objects["mount"].data
    bm = bmesh.new()
    bm.from_mesh(mesh)
    bm.faces.ensure_lookup_table()
    bmesh.ops.delete(bm, geom=[bm.faces[0]], context="FACES_ONLY")
    bm.to_mesh(mesh)
    bm.free()
    with pytest.raises(RuntimeError, match=r"error in mesh: keep-in 'mount' is open: \d+ boundary edges"):
        _convert()


def test_no_design_is_reported(open_fixture):
    open_fixture("boss")
    bpy.data.objects["design"].genbrep.role = "NONE"
    with pytest.raises(RuntimeError, match="no object has the role Design"):
        _convert()


def test_grid_incidence_uses_design_grid(open_fixture):
    open_fixture("boss")
    assert bpy.ops.genbrep.use_design_grid() == {"FINISHED"}
    settings = bpy.context.scene.genbrep_settings
    assert settings.incidence == "GRID" and settings.grid_h == pytest.approx(0.1)
    assert _convert() == {"FINISHED"}

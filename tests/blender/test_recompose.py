"""Recompose: edit a cage with Blender's own data API, recompose, and the composed solid follows."""
import json

import bpy
import numpy as np
import pytest

from genbrep import native, operators, results

COLLECTION = "genbrep design"


@pytest.fixture
def recompose_module():
    module = native.load()
    if module is None or not hasattr(module, "recompose"):
        pytest.fail("genbrep_native has no recompose(): rebuild the module (scripts/setup)")
    return module


def _composed_volume(collection):
    mesh = collection.objects["design composed"].data
    co = np.empty(len(mesh.vertices) * 3)
    mesh.vertices.foreach_get("co", co)
    tri = np.empty(len(mesh.polygons) * 3, dtype=np.int64)
    mesh.polygons.foreach_get("vertices", tri)
    p = co.reshape(-1, 3)[tri.reshape(-1, 3)]
    return np.einsum("ij,ij->i", p[:, 0], np.cross(p[:, 1], p[:, 2])).sum() / 6


def test_recompose_follows_an_edited_cage(open_fixture, recompose_module):
    open_fixture("seed")
    assert bpy.ops.genbrep.convert() == {"FINISHED"}
    collection = bpy.data.collections[COLLECTION]
    before = _composed_volume(collection)
    cages = [o for o in collection.objects if " cage " in o.name]
    assert cages
    # Push the interior control points of the largest cage outward along their normals.
    cage = max(cages, key=lambda o: len(o.data.vertices))
    mesh = cage.data
    boundary = {v for e in mesh.edges if e.is_loose is False for v in e.vertices
                if sum(1 for p in mesh.polygons if e.key in p.edge_keys) == 1}
    size = max(cage.dimensions)
    for v in mesh.vertices:
        if v.index not in boundary:
            v.co += v.normal * 0.02 * size
    mesh.update()
    assert bpy.ops.genbrep.recompose() == {"FINISHED"}
    # The pulled cage has a new mesh, and its control net draws that one.
    assert [o for o in collection.objects if o.parent == cage][0].data == cage.data
    after = _composed_volume(collection)
    assert after > before  # material added where the cage was pushed out
    report = json.loads(collection[results.REPORT_PROPERTY])
    assert report["composed"]["ok"]


def test_recompose_names_a_cage_that_is_no_longer_quads(open_fixture, recompose_module):
    open_fixture("seed")
    assert bpy.ops.genbrep.convert() == {"FINISHED"}
    collection = bpy.data.collections[COLLECTION]
    cage = next(o for o in collection.objects if " cage " in o.name)
    bpy.context.view_layer.objects.active = cage
    bpy.ops.object.mode_set(mode="EDIT")
    bpy.ops.mesh.select_all(action="SELECT")
    bpy.ops.mesh.quads_convert_to_tris()
    bpy.ops.object.mode_set(mode="OBJECT")
    outcome = operators.recompose_now(bpy.context)
    assert outcome.status == "CANCELLED"
    assert f"cage '{cage.name}' is not a quad mesh" in outcome.message

"""Roles: set from the panel operator, counted, saved in the .blend; fixtures agree with
the script that makes them."""

import os

import bpy
import numpy as np
import pytest

from conftest import FIXTURES, fixture_path
from genbrep import bridge, props

SCENES = ("arches", "boss", "seed", "components", "lattice")


def _add_cube(name, location):
    bpy.ops.mesh.primitive_cube_add(location=location)
    bpy.context.active_object.name = name
    return bpy.context.active_object


def test_set_role_applies_to_selected_objects_and_skips_non_geometry(empty_scene):
    a, b = _add_cube("a", (0, 0, 0)), _add_cube("b", (3, 0, 0))
    bpy.ops.object.light_add()
    for obj in (a, b, bpy.context.active_object):
        obj.select_set(True)
    assert bpy.ops.genbrep.set_role(role="KEEP_OUT") == {"FINISHED"}
    assert props.role_of(a) == props.role_of(b) == "KEEP_OUT"
    assert props.role_of(bpy.context.active_object) == "NONE"
    assert [o.name for o in props.objects_with_role(empty_scene, "KEEP_OUT")] == ["a", "b"]


def test_roles_survive_save_and_reload(empty_scene, tmp_path):
    _add_cube("part", (0, 0, 0)).genbrep.role = "DESIGN"
    _add_cube("pad", (2, 0, 0)).genbrep.role = "KEEP_IN"
    _add_cube("bore", (4, 0, 0)).genbrep.role = "KEEP_OUT"
    _add_cube("stock", (6, 0, 0)).genbrep.role = "SEED"
    empty_scene.genbrep_settings.fitting = "TIGHT"
    path = str(tmp_path / "roles.blend")
    bpy.ops.wm.save_as_mainfile(filepath=path)
    bpy.ops.wm.read_homefile(use_factory_startup=True, use_empty=True)
    bpy.ops.wm.open_mainfile(filepath=path)
    roles = {o.name: o.genbrep.role for o in bpy.data.objects}
    assert roles == {"part": "DESIGN", "pad": "KEEP_IN", "bore": "KEEP_OUT", "stock": "SEED"}
    assert bpy.context.scene.genbrep_settings.fitting == "TIGHT"


@pytest.mark.parametrize("scene", SCENES)
def test_fixture_matches_its_script(open_fixture, scene):
    """The committed .blend holds the solids make_fixtures.py defines, with their roles."""
    import sys
    sys.path.insert(0, FIXTURES)
    import make_fixtures
    spec = make_fixtures.SCENES[scene]()
    open_fixture(scene)
    depsgraph = bpy.context.evaluated_depsgraph_get()
    for name, role, (vertices, triangles) in spec["solids"]:
        obj = bpy.data.objects[name]
        assert obj.genbrep.role == role
        read_vertices, read_triangles = bridge.read_triangles(obj, depsgraph)
        np.testing.assert_allclose(read_vertices, vertices, atol=1e-5)
        np.testing.assert_array_equal(read_triangles, triangles)
    designs = props.objects_with_role(bpy.context.scene, "DESIGN")
    assert [d.name for d in designs] == ["design"]
    origin, h = bridge.design_grid(designs[0])
    assert h == pytest.approx(spec["h"])
    np.testing.assert_allclose(origin, np.array(make_fixtures.GRID_OFFSET) * spec["h"])
    obj_dir = os.path.join(FIXTURES, "obj", scene)
    expected = {f"{n}_{r.lower()}.obj" for n, r, _ in spec["solids"]} | {"design_design.obj"}
    assert set(os.listdir(obj_dir)) == expected


def _read_obj(path):
    """Vertices (float64) and 0-based triangles of a fixture OBJ."""
    vertices, triangles = [], []
    with open(path) as lines:
        for line in lines:
            words = line.split()
            if words and words[0] == "v":
                vertices.append([float(w) for w in words[1:4]])
            elif words and words[0] == "f":
                triangles.append([int(w) - 1 for w in words[1:4]])
    return np.array(vertices), np.array(triangles, dtype=np.int32)


@pytest.mark.parametrize("scene", SCENES)
def test_fixture_obj_files_hold_what_the_addon_reads(open_fixture, scene):
    """The command line converts exactly the design and solids the add-on passes: the OBJ
    files' coordinates equal bridge.read_triangles' float64 values to the bit (written with
    9 digits they were up to 1e-9 off, and lattice's quad stage kept another layout)."""
    open_fixture(scene)
    depsgraph = bpy.context.evaluated_depsgraph_get()
    for obj in bpy.context.scene.objects:
        if obj.type != "MESH" or props.role_of(obj) == "NONE":
            continue
        path = os.path.join(FIXTURES, "obj", scene, f"{obj.name}_{props.role_of(obj).lower()}.obj")
        vertices, triangles = _read_obj(path)
        read_vertices, read_triangles = bridge.read_triangles(obj, depsgraph)
        np.testing.assert_array_equal(vertices, read_vertices, err_msg=path)
        np.testing.assert_array_equal(triangles, read_triangles, err_msg=path)


def test_fixture_files_are_small():
    for scene in SCENES:
        assert os.path.getsize(fixture_path(scene)) < 1_000_000, scene

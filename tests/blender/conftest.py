"""pytest inside `blender -b`: puts the add-on and the native module on sys.path, registers
the add-on once, and opens fixture scenes. Run with tests/blender/run.py.

Set GENBREP_REQUIRE_NATIVE=1 to fail, not skip, when genbrep_native does not load."""

import os
import sys

import bpy
import numpy as np
import pytest

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
FIXTURES = os.path.join(ROOT, "blend_fixtures")
for path in (os.path.join(ROOT, "addon"), os.path.join(ROOT, "build", "python")):
    if path not in sys.path:
        sys.path.insert(0, path)

import genbrep  # noqa: E402
from genbrep import native  # noqa: E402

if not hasattr(bpy.types.Object, "genbrep"):
    genbrep.register()

# Tests that need the compiled module skip without it, unless GENBREP_REQUIRE_NATIVE=1
# (for CI, where a missing module is a failure).
if native.load() is None and os.environ.get("GENBREP_REQUIRE_NATIVE") == "1":
    raise RuntimeError(f"genbrep_native does not load: {native.load_error()}")
needs_native = pytest.mark.skipif(native.load() is None,
                                  reason="genbrep_native not built (run scripts/setup)")


def fixture_path(name):
    return os.path.join(FIXTURES, f"{name}.blend")


@pytest.fixture
def open_fixture():
    """open_fixture('boss') loads blend_fixtures/boss.blend and returns its scene."""
    def load(name):
        bpy.ops.wm.open_mainfile(filepath=fixture_path(name))
        return bpy.context.scene
    return load


@pytest.fixture
def empty_scene():
    bpy.ops.wm.read_homefile(use_factory_startup=True, use_empty=True)
    return bpy.context.scene


def scene_state():
    """Names of everything a conversion could add, to compare before and after."""
    return {kind: sorted(getattr(bpy.data, kind).keys())
            for kind in ("objects", "meshes", "collections", "materials")}


def mesh_object(name, vertices, faces, role):
    """A mesh object from triangle arrays, linked to the scene, with its genbrep role."""
    mesh = bpy.data.meshes.new(name)
    faces = np.asarray(faces, np.int32)
    mesh.vertices.add(len(vertices))
    mesh.vertices.foreach_set("co", np.asarray(vertices, np.float32).ravel())
    mesh.loops.add(3 * len(faces))
    mesh.loops.foreach_set("vertex_index", faces.ravel())
    mesh.polygons.add(len(faces))
    mesh.polygons.foreach_set("loop_start", np.arange(0, 3 * len(faces), 3, dtype=np.int32))
    mesh.polygons.foreach_set("loop_total", np.full(len(faces), 3, np.int32))
    mesh.update(calc_edges=True)
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    obj.genbrep.role = role
    return obj

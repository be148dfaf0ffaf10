"""scripts/blender_convert.py as a user runs it: a separate `blender -b` process."""

import os
import subprocess

import bmesh
import bpy

from conftest import ROOT, fixture_path, mesh_object, needs_native

pytestmark = needs_native

SCRIPT = os.path.join(ROOT, "scripts", "blender_convert.py")


def _batch(blend, *args):
    command = [bpy.app.binary_path, "-b", "--factory-startup", blend, "--python-exit-code", "1",
               "-P", SCRIPT, "--", *args]
    env = dict(os.environ, GENBREP_NATIVE_PATH=os.path.join(ROOT, "build", "python"))
    return subprocess.run(command, capture_output=True, text=True, env=env, timeout=300)


def test_batch_writes_converted_blend(tmp_path):
    out = tmp_path / "result.blend"
    run = _batch(fixture_path("arches"), "--out", str(out), "--report", str(tmp_path / "r.json"))
    assert run.returncode == 0, run.stdout + run.stderr
    assert out.exists() and (tmp_path / "r.json").exists()
    bpy.ops.wm.open_mainfile(filepath=str(out))
    assert "design partition" in bpy.data.collections["genbrep design"].objects


def test_batch_fails_on_open_keep_in(empty_scene, tmp_path):
    bpy.ops.mesh.primitive_ico_sphere_add(radius=2)
    bpy.context.active_object.genbrep.role = "DESIGN"
    bpy.ops.mesh.primitive_cube_add(size=1)
    keep_in = bpy.context.active_object
    keep_in.name = "open pad"
    keep_in.genbrep.role = "KEEP_IN"
    bm = bmesh.new()
    bm.from_mesh(keep_in.data)
    bm.faces.ensure_lookup_table()
    bmesh.ops.delete(bm, geom=[bm.faces[0]], context="FACES_ONLY")
    bm.to_mesh(keep_in.data)
    bm.free()
    broken = str(tmp_path / "broken.blend")
    bpy.ops.wm.save_as_mainfile(filepath=broken)
    out = tmp_path / "result.blend"
    run = _batch(broken, "--out", str(out))
    assert run.returncode == 1, run.stdout + run.stderr
    assert "genbrep: error in mesh: keep-in 'open pad' is open: 4 boundary edges" in run.stderr
    assert not out.exists()


def test_batch_rejects_bad_arguments():
    run = _batch(fixture_path("boss"), "--until", "nowhere")
    assert run.returncode == 2
    assert "invalid choice" in run.stderr


def test_batch_exits_three_on_a_fallback(empty_scene, tmp_path):
    """A dome across a keep-in and a keep-out 0.003 apart (make_scenes' gap dome): the solid
    is written from a lower tier, the script exits 3 and names each fallback."""
    import genbrep_native
    subprocess.run([os.path.join(ROOT, "build", "bin", "make_scenes"), str(tmp_path), "0.05", "gap",
                    "0.003"], check=True)
    folder = tmp_path / "gap_dome"
    mesh_object("dome", *genbrep_native.read_mesh(str(folder / "design.obj")), "DESIGN")
    mesh_object("boss", *genbrep_native.read_mesh(str(folder / "boss_keep_in.obj")), "KEEP_IN")
    mesh_object("bolt", *genbrep_native.read_mesh(str(folder / "bolt_keep_out.obj")), "KEEP_OUT")
    scene = str(tmp_path / "gap.blend")
    bpy.ops.wm.save_as_mainfile(filepath=scene)
    out = tmp_path / "result.blend"
    run = _batch(scene, "--out", str(out), "--tolerance", "0.05")
    assert run.returncode == 3, run.stdout + run.stderr
    assert out.exists()
    fallbacks = [line for line in run.stderr.splitlines() if line.startswith("genbrep: fallback: 'dome' ")]
    assert fallbacks and all("organic component 0: composed from the" in line for line in fallbacks), run.stderr

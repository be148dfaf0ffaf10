"""The add-on zip from scripts/package_addon installs into a clean Blender and loads the
native module it carries."""

import os
import subprocess
import sys

import bpy

from conftest import ROOT, needs_native

pytestmark = needs_native

PROBE = """
import sys, bpy
bpy.ops.preferences.addon_install(filepath=sys.argv[-1])
bpy.ops.preferences.addon_enable(module="genbrep")
from genbrep import native
ok, lines = native.status()
print("STATUS", ok, native.load().__file__)
bpy.ops.mesh.primitive_cube_add()
assert bpy.ops.genbrep.set_role(role="KEEP_IN") == {"FINISHED"}
"""


def test_zip_installs_and_loads_its_native_module(tmp_path):
    archive = tmp_path / "genbrep-addon.zip"
    subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "package_addon"), "--out",
                    str(archive)], check=True, capture_output=True)
    env = dict(os.environ, BLENDER_USER_SCRIPTS=str(tmp_path / "scripts"),
               BLENDER_USER_CONFIG=str(tmp_path / "config"))
    env.pop("GENBREP_NATIVE_PATH", None)
    run = subprocess.run([bpy.app.binary_path, "-b", "--factory-startup", "--python-exit-code",
                          "1", "--python-expr", PROBE, "--", str(archive)],
                         capture_output=True, text=True, env=env, timeout=120)
    assert run.returncode == 0, run.stdout + run.stderr
    installed = str(tmp_path / "scripts" / "addons" / "genbrep")
    assert f"STATUS True {installed}" in run.stdout

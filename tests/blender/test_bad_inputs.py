"""The bad-input corpus (tests/bad_inputs/cases.py) through Blender: objects made from each
case's geometry, converted by scripts/blender_convert.py (run in this Blender, as its
main() runs under `blender -b -P`) and by the operator as the panel calls it. Each must
print or report the line the command line prints, exit as it does, and leave the scene as
it was.
"""

import os
import runpy
import sys

import bpy
import numpy as np
import pytest

from conftest import ROOT, mesh_object, needs_native, scene_state

pytestmark = needs_native

sys.path.insert(0, os.path.join(ROOT, "tests", "bad_inputs"))
import cases as corpus  # noqa: E402

SCRIPT = os.path.join(ROOT, "scripts", "blender_convert.py")
ROLES = {"keep_in": "KEEP_IN", "keep_out": "KEEP_OUT", "seed": "SEED"}




def _scene(case, tmp_path):
    """An empty scene holding the case's design and solids as objects with their roles."""
    bpy.ops.wm.read_homefile(use_factory_startup=True, use_empty=True)
    import genbrep_native
    corpus.prepare(case, str(tmp_path))
    design, solids = corpus.inputs(case, str(tmp_path), genbrep_native.read_mesh)
    mesh_object(design["name"], design["vertices"], design["faces"], "DESIGN")
    for solid in solids:
        mesh_object(solid["name"], solid["vertices"], solid["faces"], ROLES[solid["role"]])
    bpy.context.scene.genbrep_settings.tolerance_auto = False
    bpy.context.scene.genbrep_settings.tolerance = corpus.TOLERANCE
    return design["name"]


def _batch(capsys, *args):
    """scripts/blender_convert.py's main() with these arguments: (exit status, output).
    Errors go to stderr, the report's warnings to stdout: both, as a user sees them."""
    argv = sys.argv
    sys.argv = [argv[0], "--", *args]
    try:
        runpy.run_path(SCRIPT, run_name="__main__")
        status = 0
    except SystemExit as exit_:
        status = exit_.code or 0
    finally:
        sys.argv = argv
    captured = capsys.readouterr()
    return status, captured.out + captured.err


def _cases():
    return [pytest.param(c, id=c.name) for c in corpus.cases() if c.kind in ("mesh", "arrays")]


@pytest.mark.parametrize("case", _cases())
def test_batch_script_prints_the_line(case, tmp_path, capsys):
    _scene(case, tmp_path)
    before = scene_state()
    status, output = _batch(capsys, "--until", "incidence", "--tolerance", str(corpus.TOLERANCE))
    assert status == case.exit, output
    assert case.line() in output.splitlines(), output
    if case.exit != 0:
        assert scene_state() == before


@pytest.mark.parametrize("case", _cases())
def test_operator_reports_the_line(case, tmp_path):
    name = _scene(case, tmp_path)
    before = scene_state()
    if case.exit == 0:
        assert bpy.ops.genbrep.convert(design=name, until="INCIDENCE") == {"FINISHED"}
        return
    with pytest.raises(RuntimeError) as error:
        bpy.ops.genbrep.convert(design=name, until="INCIDENCE")
    assert str(error.value).strip() == "Error: " + case.line().removeprefix("genbrep: ")
    assert scene_state() == before

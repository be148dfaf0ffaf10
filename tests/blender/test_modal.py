"""The interactive path (worker thread, modal timer, Esc, undo) needs a window: it runs in a
separate Blender under a virtual X server (xvfb-run), and is skipped where there is none."""

import os
import shutil
import subprocess

import bpy
import pytest

from conftest import fixture_path, needs_native

pytestmark = [needs_native,
              pytest.mark.skipif(shutil.which("xvfb-run") is None,
                                 reason="xvfb-run not installed (apt-get install xvfb)")]

SESSION = os.path.join(os.path.dirname(os.path.abspath(__file__)), "modal_session.py")


def test_modal_convert_undo_and_esc():
    command = ["xvfb-run", "-a", "-s", "-screen 0 1280x800x24", bpy.app.binary_path,
               "--factory-startup", "--enable-event-simulate", fixture_path("boss"),
               "-P", SESSION]
    run = subprocess.run(command, capture_output=True, text=True, timeout=180)
    checks = dict(line.split(" ", 2)[1:] for line in run.stdout.splitlines()
                  if line.startswith("MODAL "))
    # colour_type: Convert makes the Solid view show the partition and cage colours.
    assert checks == {"invoke": "['RUNNING_MODAL']", "converted": "True",
                      "colour_type": "MATERIAL", "after_undo": "False",
                      "invoke_again": "['RUNNING_MODAL']", "after_esc": "False",
                      "running_jobs": "0"}, run.stdout + run.stderr

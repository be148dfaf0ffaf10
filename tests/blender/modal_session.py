"""Drives the Convert operator's interactive (modal) path in a Blender with a window.

Run by test_modal.py as
    xvfb-run blender --factory-startup --enable-event-simulate scene.blend -P modal_session.py
Prints 'MODAL <check> <value>' lines and quits. Timers run the steps, as a user would click:
convert (modal, worker thread) in a view that colours by object, undo, convert again and
press Esc at once.
"""

import os
import sys

import bpy

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "addon"))
import genbrep  # noqa: E402

genbrep.register()
from genbrep import operators  # noqa: E402

COLLECTION = "genbrep design"
_state = {"step": 0, "waited": 0.0}
POLL = 0.25      # seconds between checks while the worker runs
PATIENCE = 120   # seconds to wait for the first conversion before giving up


def _context():
    window = bpy.context.window_manager.windows[0]
    area = next(a for a in window.screen.areas if a.type == "VIEW_3D")
    region = next(r for r in area.regions if r.type == "WINDOW")
    return window, dict(window=window, area=area, region=region, screen=window.screen)


def _say(check, value):
    print(f"MODAL {check} {value}", flush=True)


def step():
    window, override = _context()
    index = _state["step"]
    _state["step"] += 1
    if index == 0:
        override["area"].spaces.active.shading.color_type = "OBJECT"
        bpy.ops.ed.undo_push(message="before convert")
        with bpy.context.temp_override(**override):
            _say("invoke", sorted(bpy.ops.genbrep.convert("INVOKE_DEFAULT")))
        return POLL
    if index == 1:
        # Wait for the worker: the modal timer writes the results when it is done.
        if operators._running and _state["waited"] < PATIENCE:
            _state["step"] = 1
            _state["waited"] += POLL
            return POLL
        _say("converted", COLLECTION in bpy.data.collections)
        _say("colour_type", override["area"].spaces.active.shading.color_type)
        with bpy.context.temp_override(**override):
            bpy.ops.ed.undo()
        _say("after_undo", COLLECTION in bpy.data.collections)
        return 0.5
    if index == 2:
        with bpy.context.temp_override(**override):
            _say("invoke_again", sorted(bpy.ops.genbrep.convert("INVOKE_DEFAULT")))
        window.event_simulate(type="ESC", value="PRESS")
        return 1.0
    _say("after_esc", COLLECTION in bpy.data.collections)
    _say("running_jobs", len(operators._running))
    bpy.ops.wm.quit_blender()
    return None


bpy.app.timers.register(step, first_interval=1.0)

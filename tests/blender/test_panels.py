"""Panel draw code, run against a recording stand-in for UILayout (panels do not draw under
blender -b): every property and operator it names must exist."""

import bpy
import pytest

from conftest import needs_native
from genbrep import panels


class RecordingLayout:
    """Accepts what UILayout accepts, checks names, and records labels."""

    def __init__(self, labels):
        self.labels = labels

    def __getattr__(self, name):  # sub-layouts: row, column, box, grid_flow, ...
        if name in ("row", "column", "box", "grid_flow", "split"):
            return lambda *args, **kwargs: RecordingLayout(self.labels)
        raise AttributeError(name)

    def __setattr__(self, name, value):  # enabled, scale_y, use_property_split, ...
        object.__setattr__(self, name, value)

    def label(self, text="", **kwargs):
        self.labels.append(text)

    def prop(self, data, name, **kwargs):
        assert name in data.bl_rna.properties, f"{data} has no property {name}"

    def operator(self, idname, **kwargs):
        module, name = idname.split(".")
        assert name in dir(getattr(bpy.ops, module)), f"no operator {idname}"
        return type("OperatorProperties", (), {})()


def _draw(panel_class):
    labels = []
    panel = type("PanelStandIn", (), {"layout": RecordingLayout(labels)})()
    if hasattr(panel_class, "poll") and not panel_class.poll(bpy.context):
        return None
    panel_class.draw(panel, bpy.context)
    return labels


@pytest.mark.parametrize("panel_class", panels.CLASSES)
def test_panels_draw_on_a_fixture(open_fixture, panel_class):
    open_fixture("boss")
    bpy.context.view_layer.objects.active = bpy.data.objects["design"]
    _draw(panel_class)


def test_role_counts_are_listed(open_fixture):
    open_fixture("boss")
    labels = _draw(panels.GENBREP_PT_main)
    assert "Keep-in: 2  boss, mount" in labels and "Keep-out: 1  bolt" in labels


@needs_native
def test_report_panel_shows_the_report(open_fixture):
    open_fixture("boss")
    assert bpy.ops.genbrep.convert() == {"FINISHED"}
    labels = _draw(panels.GENBREP_PT_report)
    assert labels and labels[0].startswith("time:")

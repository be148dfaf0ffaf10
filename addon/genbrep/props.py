"""Blender properties: the role of each object, the conversion settings, what is shown.

Object.genbrep.role is saved in the .blend. The settings exist twice with the same names:
on the scene (Scene.genbrep_settings, edited in the panel) and on the convert operator (its
redo panel); `SettingsMixin` declares them once for both. The scene's group also holds
show_inputs, the panel's toggle for the objects with a role.
"""

import bpy

from . import options

ROLE_ITEMS = [
    ("NONE", "None", "Not part of the conversion"),
    ("DESIGN", "Design", "The generative design mesh M to convert"),
    ("KEEP_IN", "Keep-in", "Must be material: lies wholly inside the design"),
    ("KEEP_OUT", "Keep-out", "Must be void: no material inside it"),
    ("SEED", "Seed", "Starting material the solver may have eroded"),
]

# Object types whose evaluated mesh can be read (Object.to_mesh).
CONVERTIBLE_TYPES = {"MESH", "CURVE", "SURFACE", "FONT", "META"}

_STAGE_ITEMS = [("ALL", "All", "Run every stage this build has")] + [
    (s.upper(), s.capitalize(), f"Stop after the {s} stage") for s in options.PIPELINE_STAGES]

SETTING_NAMES = ("tolerance_auto", "tolerance", "incidence", "grid_origin", "grid_h", "density",
                 "target_edge_length", "size_scale", "fitting", "until")


class GENBREP_PG_object(bpy.types.PropertyGroup):
    role: bpy.props.EnumProperty(
        name="Role", items=ROLE_ITEMS, default="NONE",
        description="What this object is in the generative setup")


class SettingsMixin:
    """Conversion settings (names as in options.Settings)."""
    tolerance_auto: bpy.props.BoolProperty(
        name="Automatic Tolerance", default=True,
        description="Derive the incidence distance from the design (voxel size or bounding box)")
    tolerance: bpy.props.FloatProperty(
        name="Tolerance", default=0.0, min=0.0, subtype="DISTANCE", unit="LENGTH", precision=4,
        description="Incidence distance d: design vertices this close to a solid lie on it")
    incidence: bpy.props.EnumProperty(
        name="Incidence", default="AUTO", items=[
            ("AUTO", "Auto", "Grid when the design records its voxel grid, else distance"),
            ("DISTANCE", "Distance", "Vertices within the tolerance of a solid lie on it"),
            ("GRID", "Grid", "Level-set grid incidence (paper §4.1.1): origin and voxel size"),
        ])
    grid_origin: bpy.props.FloatVectorProperty(
        name="Grid Origin", size=3, default=(0.0, 0.0, 0.0), subtype="TRANSLATION",
        unit="LENGTH", description="A point of the solver's voxel grid, world space")
    grid_h: bpy.props.FloatProperty(
        name="Voxel Size", default=0.0, min=0.0, subtype="DISTANCE", unit="LENGTH", precision=4,
        description="Voxel edge length h of the solver's grid; 0 = the one recorded on the "
                    "design (custom property genbrep_grid_h)")
    density: bpy.props.EnumProperty(
        name="Cage Density", default="SIZE_SCALE", items=[
            ("SIZE_SCALE", "Size Field", "Quad size from curvature, times a scale"),
            ("EDGE_LENGTH", "Edge Length", "A target cage edge length"),
        ])
    target_edge_length: bpy.props.FloatProperty(
        name="Edge Length", default=0.0, min=0.0, subtype="DISTANCE", unit="LENGTH",
        description="Target cage edge length; 0 = automatic")
    size_scale: bpy.props.FloatProperty(
        name="Size Scale", default=1.0, min=0.01, soft_max=10.0,
        description="Multiplies the curvature size field: larger = coarser cages")
    fitting: bpy.props.EnumProperty(
        name="Fitting", default="BOUNDARY_TIGHT", items=[
            ("SMOOTH", "Smooth", "Least squares: simplest cages, no deviation bound (§6.3-1)"),
            ("TIGHT", "Tight", "Bound the deviation everywhere (§6.3-2)"),
            ("BOUNDARY_TIGHT", "Boundary Tight",
             "Bound the deviation on the region boundary, least squares inside (§6.3-3)"),
        ])
    until: bpy.props.EnumProperty(
        name="Stop After", default="ALL", items=_STAGE_ITEMS,
        description="Last pipeline stage to run")


def _show_inputs_changed(settings, _context):
    show_inputs(settings.id_data, settings.show_inputs)


class GENBREP_PG_settings(SettingsMixin, bpy.types.PropertyGroup):
    show_inputs: bpy.props.BoolProperty(
        name="Show Inputs", default=True, update=_show_inputs_changed,
        description="Show the design and the solids in the viewport (Convert hides them "
                    "once it has composed a solid)")


def setting_values(owner):
    """{name: value} of the settings on a scene property group or the convert operator."""
    return {name: getattr(owner, name) for name in SETTING_NAMES}


def copy_settings(source, target):
    for name in SETTING_NAMES:
        setattr(target, name, getattr(source, name))


def role_of(obj):
    return obj.genbrep.role if obj is not None and obj.type in CONVERTIBLE_TYPES else "NONE"


def objects_with_role(scene, role):
    """Objects of the scene with the role, sorted by name (the solid order of a run)."""
    return sorted((o for o in scene.objects if role_of(o) == role), key=lambda o: o.name)


def show_inputs(scene, shown):
    """Show or hide the scene's objects with a role, in the viewport only (hide_set, in
    every view layer of the scene that has them); nothing else about them changes."""
    for obj in scene.objects:
        if role_of(obj) == "NONE":
            continue
        for view_layer in scene.view_layers:
            try:
                obj.hide_set(not shown, view_layer=view_layer)
            except RuntimeError:  # not in this view layer (its collection is excluded)
                pass


CLASSES = (GENBREP_PG_object, GENBREP_PG_settings)


def register():
    for cls in CLASSES:
        bpy.utils.register_class(cls)
    bpy.types.Object.genbrep = bpy.props.PointerProperty(type=GENBREP_PG_object)
    bpy.types.Scene.genbrep_settings = bpy.props.PointerProperty(type=GENBREP_PG_settings)


def unregister():
    del bpy.types.Scene.genbrep_settings
    del bpy.types.Object.genbrep
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)

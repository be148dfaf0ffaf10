"""Conversion settings: names, defaults, checking, and the options dict for the native module.

No bpy here. The panel and the operator hold the same settings as Blender properties;
`settings_from_values` turns their values into a `Settings`, and `native_options` checks
them against what the loaded module can do and builds the dict `genbrep_native.convert`
takes.
"""

import math
from dataclasses import dataclass

# Pipeline stages in order (DESIGN.md). A native build may run only a prefix of them.
PIPELINE_STAGES = ("mesh", "incidence", "partition", "relax", "field", "param", "quad", "fit",
                   "pull", "compose")

# Incidence: 'auto' = grid when the design records its voxel grid, else distance (paper §4.1).
INCIDENCE_MODES = ("auto", "distance", "grid")
# Cage density: target edge length (design units) or a scale on the curvature size field (§6.2).
DENSITY_MODES = ("size_scale", "edge_length")
# Fitting strategies of paper §6.3: (1) L2 smooth, (2) L∞ tight, (3) tight on the boundary only.
FITTING_STRATEGIES = ("smooth", "tight", "boundary_tight")

# Option keys every native build takes (the module contract); the others are sent only to
# builds that list them in genbrep_native.OPTION_KEYS.
CORE_OPTION_KEYS = frozenset({"tolerance", "incidence", "grid_origin", "grid_h", "until"})
PIPELINE_OPTION_KEYS = frozenset({"fitting", "target_edge_length", "size_scale"})

# Custom properties on a design object recording the voxel grid it was extracted from.
GRID_H_PROPERTY = "genbrep_grid_h"
GRID_ORIGIN_PROPERTY = "genbrep_grid_origin"


class OptionError(ValueError):
    """A setting the user has to change; str() says which and how."""


@dataclass
class Settings:
    """User settings of one conversion. Lengths are in the design's units."""
    tolerance: float = 0.0          # incidence distance d; 0 = automatic
    incidence: str = "auto"
    grid_origin: tuple = (0.0, 0.0, 0.0)
    grid_h: float = 0.0             # voxel size; 0 = the one the design records
    density: str = "size_scale"
    target_edge_length: float = 0.0  # 0 = automatic
    size_scale: float = 1.0
    fitting: str = "boundary_tight"
    until: str = "all"              # last stage to run, or 'all'


def settings_from_values(values):
    """Settings from a mapping of property values (enum identifiers in any case)."""
    settings = Settings()
    for name in ("incidence", "density", "fitting", "until"):
        if name in values:
            setattr(settings, name, str(values[name]).lower())
    for name in ("tolerance", "grid_h", "target_edge_length", "size_scale"):
        if name in values:
            setattr(settings, name, float(values[name]))
    if values.get("tolerance_auto", False):
        settings.tolerance = 0.0
    if "grid_origin" in values:
        settings.grid_origin = tuple(float(c) for c in values["grid_origin"])
    return settings


def grid_from_properties(properties):
    """(origin, h) recorded on a design object's custom properties, or None."""
    try:
        h = float(properties.get(GRID_H_PROPERTY, 0.0))
        origin = tuple(float(c) for c in properties.get(GRID_ORIGIN_PROPERTY, (0.0, 0.0, 0.0)))
    except (TypeError, ValueError):
        return None
    if not (h > 0.0 and math.isfinite(h)) or len(origin) != 3:
        return None
    return origin, h


def _check_length(name, value, allow_zero=True):
    if not math.isfinite(value) or value < 0.0 or (value == 0.0 and not allow_zero):
        raise OptionError(f"{name} must be {'>= 0' if allow_zero else '> 0'}, got {value:g}")


def native_options(settings, design_name, design_grid=None, stages=PIPELINE_STAGES,
                   option_keys=None):
    """(options dict for genbrep_native.convert, notes for the report).

    design_grid: (origin, h) recorded on the design, or None. stages: the stages the loaded
    module runs. option_keys: keys it accepts beyond the core ones (None = core only).
    Raises OptionError naming the setting and what to do.
    """
    notes = []
    _check_length("Tolerance", settings.tolerance)
    _check_length("Voxel size", settings.grid_h)
    _check_length("Target edge length", settings.target_edge_length)
    _check_length("Size field scale", settings.size_scale, allow_zero=False)
    for name, value, allowed in (("incidence", settings.incidence, INCIDENCE_MODES),
                                 ("density", settings.density, DENSITY_MODES),
                                 ("fitting", settings.fitting, FITTING_STRATEGIES)):
        if value not in allowed:
            raise OptionError(f"unknown {name} '{value}': use one of {', '.join(allowed)}")

    options = {}
    if settings.tolerance > 0.0:
        options["tolerance"] = settings.tolerance

    mode = settings.incidence
    if mode == "auto":
        mode = "grid" if design_grid is not None else "distance"
    options["incidence"] = mode
    if mode == "grid":
        if settings.grid_h > 0.0:
            origin, h = tuple(settings.grid_origin), settings.grid_h
        elif design_grid is not None:
            origin, h = design_grid
            notes.append(f"grid incidence with the voxel size recorded on '{design_name}': "
                         f"h = {h:g}")
        else:
            raise OptionError(
                f"grid incidence needs a voxel size: set Voxel Size, or record it on "
                f"'{design_name}' as custom property {GRID_H_PROPERTY}")
        options["grid_origin"] = tuple(float(c) for c in origin)
        options["grid_h"] = float(h)

    if settings.until != "all":
        if settings.until not in stages:
            raise OptionError(
                f"stage '{settings.until}' is not in this genbrep_native build "
                f"(it runs: {', '.join(stages) or 'nothing'}); choose an earlier stage")
        options["until"] = settings.until

    pipeline = {"fitting": settings.fitting}
    if settings.density == "edge_length":
        pipeline["target_edge_length"] = settings.target_edge_length
    else:
        pipeline["size_scale"] = settings.size_scale
    accepted = option_keys or frozenset()
    for key, value in pipeline.items():
        if key in accepted:
            options[key] = value
    ignored = sorted(k for k in pipeline if k not in accepted)
    if ignored:
        notes.append("not used by this genbrep_native build: " + ", ".join(ignored))
    return options, notes


def stages_run(stages, options):
    """The stages a run with these native options goes through, in order."""
    until = options.get("until")
    return tuple(stages[:stages.index(until) + 1]) if until in stages else tuple(stages)

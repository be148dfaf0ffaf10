"""Checks on the conversion input before it goes native. No bpy here.

Roles are the identifiers of the object property (props.py); the native module takes the
solid roles in lower case. Every message names the object and the problem and says what
to do, so the operator can show it as it is. The meshes themselves are checked natively
(genbrep_native names every broken input), not here.
"""

import numpy as np

ROLES = ("NONE", "DESIGN", "KEEP_IN", "KEEP_OUT", "SEED")
ROLE_LABELS = {"NONE": "None", "DESIGN": "Design", "KEEP_IN": "Keep-in",
               "KEEP_OUT": "Keep-out", "SEED": "Seed"}
SOLID_ROLES = ("KEEP_IN", "KEEP_OUT", "SEED")
NATIVE_ROLE = {"KEEP_IN": "keep_in", "KEEP_OUT": "keep_out", "SEED": "seed"}


class InputError(ValueError):
    """Input the user has to fix before converting; str() names the object and the problem."""


def role_counts(roles):
    """{role: count} over an iterable of role identifiers, every role present."""
    counts = dict.fromkeys(ROLES, 0)
    for role in roles:
        counts[role] = counts.get(role, 0) + 1
    return counts


def choose_design(design_names, requested=None, active=None):
    """Name of the design to convert: the requested one, else the active one, else the only one."""
    if requested:
        if requested not in design_names:
            raise InputError(f"'{requested}' does not have the role Design: give it the role "
                             f"in the genbrep panel, or pick one of: {', '.join(design_names)}")
        return requested
    if not design_names:
        raise InputError("no object has the role Design: select the generative design mesh "
                         "and set its role to Design in the genbrep panel")
    if active in design_names:
        return active
    if len(design_names) > 1:
        raise InputError(f"{len(design_names)} objects have the role Design "
                         f"({', '.join(design_names)}): make the one to convert active")
    return design_names[0]


def failure_line(message, stage=None):
    """A native error as the command line prints it, less its 'genbrep: ' prefix:
    "error in mesh: design 'part' is open: ...", so every front end shows the same line."""
    return f"error in {stage}: {message}" if stage else str(message)


def native_solids(solids):
    """The solids as genbrep_native.convert takes them (lower-case roles)."""
    return [dict(name=s["name"], role=NATIVE_ROLE[s["role"]], vertices=s["vertices"],
                 faces=s["faces"]) for s in solids]


def cage_input(name, vertices, polygon_sizes, corner_indices, crease_pairs, crease_values):
    """The native recompose() dict of one edited cage; raises InputError naming the cage.

    vertices (N, 3) world space; polygon_sizes (K,) corners per polygon; corner_indices the
    polygons' vertex indices, concatenated. Only creased edges (value > 0) are passed on.
    """
    vertices = np.asarray(vertices, dtype=np.float64).reshape(-1, 3)
    sizes = np.asarray(polygon_sizes, dtype=np.int64).ravel()
    if len(sizes) == 0:
        raise InputError(f"cage '{name}' has no faces: undo the edit or convert again")
    bad = int(np.count_nonzero(sizes != 4))
    if bad:
        raise InputError(f"cage '{name}' is not a quad mesh: {bad} faces do not have 4 corners "
                         f"(a Catmull–Clark cage must stay all quads)")
    if not np.isfinite(vertices).all():
        raise InputError(f"cage '{name}' has vertices with NaN or infinite coordinates")
    values = np.asarray(crease_values, dtype=np.float32).ravel()
    pairs = np.asarray(crease_pairs, dtype=np.int32).reshape(-1, 2)
    keep = values > 0
    return dict(name=name, vertices=vertices,
                faces=np.asarray(corner_indices, dtype=np.int32).reshape(-1, 4),
                crease_edges=pairs[keep], crease_values=values[keep])

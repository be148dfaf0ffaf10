"""Bookkeeping for the objects a conversion writes: names, colours, edge lookups. No bpy here.

Everything a run writes lives in the collection `collection_name(design)`; a re-run
replaces that collection's content, so results never pile up.
"""

import colorsys

import numpy as np

PARTITION_SOLID_ATTRIBUTE = "genbrep_solid"          # int per face: solid index, -1 organic
PARTITION_COMPONENT_ATTRIBUTE = "genbrep_component"  # int per face: component, -1 incident
PARTITION_COLOR_ATTRIBUTE = "genbrep_partition"      # colour per face corner
SOURCE_ATTRIBUTE = "genbrep_source"                  # int per face: input triangle index
# vertex group per cage: its irregular vertices no field singularity explains
OFF_SINGULARITIES_GROUP = "genbrep irregular off singularities"
REPORT_PROPERTY = "genbrep_report"                   # JSON report on the result collection
DESIGN_PROPERTY = "genbrep_design"                   # design name on the result collection
COMPONENT_PROPERTY = "genbrep_component"             # organic component on each cage object

ORGANIC_GREY = (0.8, 0.8, 0.8, 1.0)
_GOLDEN = 0.618033988749895


def collection_name(design_name):
    return f"genbrep {design_name}"


def partition_name(design_name):
    return f"{design_name} partition"


def loops_name(design_name):
    return f"{design_name} boundary loops"


def cage_name(design_name, cage, index):
    return f"{design_name} cage {cage.get('name') or index}"


def control_net_name(design_name, cage, index):
    """The wire object drawing a cage's control net (no ' cage ' in it: not a cage)."""
    return f"{design_name} control net {cage.get('name') or index}"


def component_material_name(component):
    return f"genbrep component {component}"


def composed_name(design_name):
    return f"{design_name} composed"


def _hue_colour(index, hue0, saturation, value):
    r, g, b = colorsys.hsv_to_rgb((hue0 + index * _GOLDEN) % 1.0, saturation, value)
    return (r, g, b, 1.0)


def solid_colour(index, role):
    """Strong colour per solid: keep-ins around blue, keep-outs around red, seeds around yellow."""
    base = {"keep_in": 0.6, "keep_out": 0.0, "seed": 0.15}.get(role, 0.75)
    r, g, b = colorsys.hsv_to_rgb((base + 0.07 * ((index * 3) % 5 - 2)) % 1.0, 0.85, 0.85)
    return (r, g, b, 1.0)


def component_colour(component):
    """Light, well-separated colour per organic component."""
    return _hue_colour(component, 0.1, 0.4, 0.95)


def partition_materials(face_solid, face_component, solid_roles):
    """The partition's materials: per face the index of its material (M,) int32, and the
    materials as (name, RGBA): one per solid, one per organic component (the material its
    cage uses too), grey for the rest; only materials some face uses, in that order. A
    name gives its colour, so designs in one file can share the materials.

    solid_roles: the native role ('keep_in', ...) of each solid index.
    """
    face_solid = np.asarray(face_solid, dtype=np.int64)
    face_component = np.asarray(face_component, dtype=np.int64)
    organic = face_solid < 0
    groups = [(f"genbrep {role.replace('_', '-')} {index}", solid_colour(index, role),
               face_solid == index) for index, role in enumerate(solid_roles)]
    groups += [(component_material_name(c), component_colour(c), organic & (face_component == c))
               for c in np.unique(face_component[organic & (face_component >= 0)]).tolist()]
    face_material = np.full(len(face_solid), -1, dtype=np.int32)
    materials = []
    for name, colour, faces in groups:
        if faces.any():
            face_material[faces] = len(materials)
            materials.append((name, colour))
    if np.any(face_material < 0):
        face_material[face_material < 0] = len(materials)
        materials.append(("genbrep organic", ORGANIC_GREY))
    return face_material, materials


def source_materials(face_source, solid_roles):
    """partition_materials for a mesh whose faces carry their source (solid index ≥ 0, or
    organic component c as -1 - c, as the composed solid's do): the same colours."""
    face_source = np.asarray(face_source, dtype=np.int64)
    return partition_materials(np.where(face_source >= 0, face_source, -1),
                               np.where(face_source < 0, -1 - face_source, -1), solid_roles)


def face_colours(face_solid, face_component, solid_roles):
    """(M, 4) float32 RGBA: incident faces by solid, organic faces by component, the
    colours of partition_materials."""
    face_material, materials = partition_materials(face_solid, face_component, solid_roles)
    palette = np.array([colour for _, colour in materials] or [ORGANIC_GREY], dtype=np.float32)
    return palette[face_material]


def edge_indices(mesh_edges, pairs):
    """Index into mesh_edges (E, 2) of each vertex pair in pairs (e, 2), -1 where absent.

    Order inside a pair does not matter. Vectorised: sorts once, then binary searches.
    """
    mesh_edges = np.sort(np.asarray(mesh_edges, dtype=np.int64).reshape(-1, 2), axis=1)
    pairs = np.sort(np.asarray(pairs, dtype=np.int64).reshape(-1, 2), axis=1)
    if len(mesh_edges) == 0 or len(pairs) == 0:
        return np.full(len(pairs), -1, dtype=np.int64)
    base = int(max(mesh_edges.max(), pairs.max())) + 1
    keys = mesh_edges[:, 0] * base + mesh_edges[:, 1]
    order = np.argsort(keys, kind="stable")
    sorted_keys = keys[order]
    wanted = pairs[:, 0] * base + pairs[:, 1]
    at = np.clip(np.searchsorted(sorted_keys, wanted), 0, len(sorted_keys) - 1)
    found = sorted_keys[at] == wanted
    return np.where(found, order[at], -1)


def loop_edges(loops):
    """(E, 2) int32 edges of closed vertex cycles, and (E,) int32 loop index of each edge."""
    edges, owner = [], []
    for index, loop in enumerate(loops):
        cycle = np.asarray(loop.get("vertices", ()), dtype=np.int32).reshape(-1)
        if len(cycle) < 2:
            continue
        edges.append(np.stack([cycle, np.roll(cycle, -1)], axis=1))
        owner.append(np.full(len(cycle), index, dtype=np.int32))
    if not edges:
        return np.zeros((0, 2), dtype=np.int32), np.zeros(0, dtype=np.int32)
    return np.concatenate(edges), np.concatenate(owner)


def subdivision_settings(subdivision):
    """Subdivision Surface settings from a cage's 'subdivision' dict, every one explicit.

    Missing keys get Blender's defaults (which match OpenSubdiv's Catmull-Clark with
    boundary interpolation 'edge only'); the fitter should always send them all.
    """
    subdivision = subdivision or {}
    boundary = str(subdivision.get("boundary_smooth", "ALL")).upper()
    if boundary not in ("ALL", "PRESERVE_CORNERS"):
        raise ValueError(f"unknown boundary_smooth '{boundary}' from genbrep_native")
    levels = int(subdivision.get("levels", 2))
    return {
        "levels": levels,
        "render_levels": levels,
        "quality": int(subdivision.get("quality", 3)),
        "use_limit_surface": bool(subdivision.get("use_limit_surface", True)),
        "boundary_smooth": boundary,
        "use_creases": True,
        "uv_smooth": "PRESERVE_BOUNDARIES",
    }


def field_name(design_name):
    return f"{design_name} cross field"


def singularities_name(design_name):
    return f"{design_name} singularities"


def field_crosses(vertices, faces, direction, organic, arm=0.35):
    """A cross of two edges at the centre of every organic face, to show the cross field.

    vertices (N, 3), faces (M, 3), direction (M, 3) unit field direction per face,
    organic (M,) bool. Each arm is `arm` times the face's mean edge length, one along the
    direction and one along normal × direction. Returns (4K, 3) float64 points and (2K, 2)
    int32 edges for the K organic faces.
    """
    vertices = np.asarray(vertices, dtype=np.float64).reshape(-1, 3)
    faces = np.asarray(faces, dtype=np.int64).reshape(-1, 3)[organic]
    u = np.asarray(direction, dtype=np.float64).reshape(-1, 3)[organic]
    corners = vertices[faces]                                   # (K, 3, 3)
    centre = corners.mean(axis=1)
    normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    normal /= np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-300)
    v = np.cross(normal, u)
    size = arm * np.linalg.norm(corners - np.roll(corners, 1, axis=1), axis=2).mean(axis=1)
    size = size[:, None]
    points = np.stack([centre - size * u, centre + size * u, centre - size * v, centre + size * v], axis=1)
    count = len(faces)
    base = 4 * np.arange(count, dtype=np.int32)[:, None]
    edges = np.concatenate([base + [0, 1], base + [2, 3]], axis=1).reshape(-1, 2)
    return points.reshape(-1, 3), edges.astype(np.int32)

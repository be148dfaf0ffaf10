"""Build the fixture scenes: level-set-style generative designs made from exact solids.

Run from the repository root:

    blender -b --factory-startup --python-exit-code 1 -P blend_fixtures/make_fixtures.py

Each scene is made the way a level-set solver makes its output (paper §4.1.1): the exact
input solids (keep-ins, keep-outs, seeds) plus organic material (tubes swept along
curves) are united, the keep-outs and the solver's erosions are subtracted, and the
result is voxel-remeshed at a known voxel size h (Remesh modifier, mode VOXEL, whose grid
points are the design object's location plus integer multiples of h). h and the grid
origin are recorded on the design object (custom properties genbrep_grid_h,
genbrep_grid_origin) so grid incidence can be used.

Writes blend_fixtures/<scene>.blend with roles set through the add-on's properties, and
blend_fixtures/obj/<scene>/<object>_<role>.obj (world space, triangles) for the command
line. Prints, for each design, its triangle count and whether it is closed and manifold
without coincident vertices; exits non-zero if one is not or has over MAX_TRIANGLES.
"""

import math
import os
import sys

import bmesh
import bpy
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(os.path.dirname(HERE), "addon"))

import genbrep  # noqa: E402  (after the sys.path change)

MAX_TRIANGLES = 30000
GRID_OFFSET = (0.37, 0.29, 0.41)  # grid origin of every design, in voxels


# exact solids, as triangle meshes (vertices N×3 float64, triangles M×3 int32, outward) -------

def box(center, size):
    c, s = np.asarray(center, float), np.asarray(size, float) / 2
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    triangles = [(a, b, c_) for a, b, c_, d in quads] + [(a, c_, d) for a, b, c_, d in quads]
    return c + corners * s, np.array(triangles, np.int32)


def _frames(points):
    """Rotation-minimising normal/binormal along a polyline (double reflection)."""
    tangents = np.gradient(points, axis=0)
    tangents /= np.linalg.norm(tangents, axis=1)[:, None]
    helper = np.array([0.0, 0.0, 1.0]) if abs(tangents[0][2]) < 0.9 else np.array([1.0, 0, 0])
    normal = np.cross(tangents[0], helper)
    normal /= np.linalg.norm(normal)
    normals = [normal]
    for i in range(1, len(points)):
        v1 = points[i] - points[i - 1]
        n_l = normals[-1] - 2 * np.dot(v1, normals[-1]) / np.dot(v1, v1) * v1
        t_l = tangents[i - 1] - 2 * np.dot(v1, tangents[i - 1]) / np.dot(v1, v1) * v1
        v2 = tangents[i] - t_l
        n = n_l - 2 * np.dot(v2, n_l) / max(np.dot(v2, v2), 1e-30) * v2
        normals.append(n / np.linalg.norm(n))
    normals = np.array(normals)
    return normals, np.cross(tangents, normals)


def tube(points, radii, segments=24):
    """Closed tube swept along a polyline, radius per point, flat end caps."""
    points = np.asarray(points, float)
    radii = np.broadcast_to(np.asarray(radii, float), (len(points),))
    normals, binormals = _frames(points)
    angles = np.linspace(0, 2 * math.pi, segments, endpoint=False)
    ring = np.cos(angles)[None, :, None] * normals[:, None] + \
        np.sin(angles)[None, :, None] * binormals[:, None]
    vertices = (points[:, None] + radii[:, None, None] * ring).reshape(-1, 3)
    n, s = len(points), segments
    triangles = []
    for i in range(n - 1):
        for j in range(s):
            a, b = i * s + j, i * s + (j + 1) % s
            c, d = a + s, b + s
            triangles += [(a, b, c), (b, d, c)]
    start, end = len(vertices), len(vertices) + 1
    vertices = np.vstack([vertices, points[0], points[-1]])
    for j in range(s):
        triangles.append((start, (j + 1) % s, j))
        triangles.append((end, (n - 1) * s + j, (n - 1) * s + (j + 1) % s))
    return vertices, np.array(triangles, np.int32)


def cylinder(center, radius, height, segments=48):
    """Closed Z-axis cylinder."""
    c = np.asarray(center, float)
    return tube([c - (0, 0, height / 2), c + (0, 0, height / 2)], radius, segments)


def ring(center, outer, inner, height, segments=48):
    """Closed Z-axis annulus (a boss with a bore)."""
    angles = np.linspace(0, 2 * math.pi, segments, endpoint=False)
    circle = np.stack([np.cos(angles), np.sin(angles), np.zeros(segments)], axis=1)
    c, half = np.asarray(center, float), np.array([0, 0, height / 2])
    layers = [c - half + outer * circle, c + half + outer * circle,
              c - half + inner * circle, c + half + inner * circle]
    vertices = np.vstack(layers)
    ob, ot, ib, it = (k * segments for k in range(4))
    triangles = []
    for j in range(segments):
        k = (j + 1) % segments
        for a, b, c_, d in ((ob + j, ob + k, ot + k, ot + j),   # outer wall, outward
                            (it + j, it + k, ib + k, ib + j),   # inner wall, toward the axis
                            (ot + j, ot + k, it + k, it + j),   # top
                            (ib + j, ib + k, ob + k, ob + j)):  # bottom
            triangles += [(a, b, c_), (a, c_, d)]
    return vertices, np.array(triangles, np.int32)


def arch(start, end, height, samples=40):
    """Points of a half-sine arch from start to end rising by height."""
    t = np.linspace(0.0, 1.0, samples)[:, None]
    start, end = np.asarray(start, float), np.asarray(end, float)
    return start + t * (end - start) + np.sin(math.pi * t) * np.array([0, 0, height])


def line(start, end, samples=12):
    t = np.linspace(0.0, 1.0, samples)[:, None]
    return np.asarray(start, float) + t * (np.asarray(end, float) - np.asarray(start, float))


# the scenes ------------------------------------------------------------------------------
# Each scene: voxel size h; solids (name, role, mesh); organic material and erosions
# (meshes only used to build the design).

def scene_arches():
    solids = [("pad_a1", "KEEP_IN", box((-4, -2.5, 0), (2, 1.6, 1))),
              ("pad_a2", "KEEP_IN", box((4, -2.5, 0), (2, 1.6, 1))),
              ("pad_b1", "KEEP_IN", box((-4, 2.5, 0), (2, 1.6, 1))),
              ("pad_b2", "KEEP_IN", box((4, 2.5, 0), (2, 1.6, 1)))]
    organic = [tube(arch((-4, -2.5, 0), (4, -2.5, 0), 3.5), np.linspace(0.55, 0.55, 40)),
               tube(arch((-4, 2.5, 0), (4, 2.5, 0), 2.5),
                    0.4 + 0.25 * np.abs(np.linspace(-1, 1, 40)))]
    return dict(h=0.125, solids=solids, organic=organic, erosions=[])


def scene_boss():
    solids = [("boss", "KEEP_IN", ring((0, 0, 0), 1.3, 0.55, 1.0)),
              ("mount", "KEEP_IN", box((6, 0, 0), (1.6, 2.4, 1.0))),
              ("bolt", "KEEP_OUT", cylinder((0, 0, 0), 0.55, 3.0))]
    organic = [tube(line((0.9, 0, 0), (6, 0, 0)), np.linspace(0.45, 0.35, 12)),
               tube(arch((0.6, 0.6, 0), (6, 0.8, 0), 1.5), 0.3)]
    return dict(h=0.1, solids=solids, organic=organic, erosions=[])


def scene_seed():
    solids = [("plate", "SEED", box((0, 0, 0), (6, 4, 0.8))),
              ("lug", "KEEP_IN", box((0, 0, 3.5), (1.5, 1.5, 1.0)))]
    organic = [tube(line((0, 0, 0), (0, 0, 3.5)), np.linspace(0.7, 0.45, 12))]
    erosions = [cylinder((3.2, 2.2, 0), 1.8, 2.0), tube(line((-2, 0, -1), (-2, 0, 1)), 0.8)]
    return dict(h=0.1, solids=solids, organic=organic, erosions=erosions)


def scene_components():
    corners = [(-3, -3, 0), (3, -3, 0), (3, 3, 0), (-3, 3, 0)]
    solids = [(f"block_{i}", "KEEP_IN", box(c, (1.4, 1.4, 1.4))) for i, c in enumerate(corners)]
    organic = [tube(line(corners[0], corners[1]), 0.45),
               tube(arch(corners[1], corners[2], 1.5), 0.4),
               tube(line(corners[2], corners[3]), 0.5 - 0.15 * np.sin(np.linspace(0, math.pi, 12))),
               tube(arch(corners[3], corners[0], -1.2), 0.35)]
    return dict(h=0.1, solids=solids, organic=organic, erosions=[])


def scene_lattice():
    solids = [("base", "KEEP_IN", box((0, 0, 0), (5, 5, 0.5))),
              ("top", "KEEP_IN", box((0, 0, 4), (5, 5, 0.5)))]
    organic = []
    posts = [(x, y) for x in (-1.8, 0, 1.8) for y in (-1.8, 0, 1.8)]
    for x, y in posts:
        organic.append(tube(line((x, y, 0), (x, y, 4)), 0.25, segments=16))
    for x in (-1.8, 0, 1.8):
        organic.append(tube(line((x, -1.8, 2), (x, 1.8, 2)), 0.22, segments=16))
        organic.append(tube(line((-1.8, x, 2), (1.8, x, 2)), 0.22, segments=16))
    return dict(h=0.125, solids=solids, organic=organic, erosions=[])


SCENES = {"arches": scene_arches, "boss": scene_boss, "seed": scene_seed,
          "components": scene_components, "lattice": scene_lattice}


# Blender side ----------------------------------------------------------------------------

def _join(meshes):
    vertices, triangles, offset = [], [], 0
    for v, t in meshes:
        vertices.append(v)
        triangles.append(t + offset)
        offset += len(v)
    return np.vstack(vertices), np.vstack(triangles)


def _object(name, mesh_arrays, collection):
    from genbrep import bridge
    obj = bpy.data.objects.new(name, bridge.new_mesh(name, *mesh_arrays))
    collection.objects.link(obj)
    return obj


def _exact_solver():
    """The exact Boolean solver of this Blender version (names change across versions)."""
    items = [i.identifier for i in bpy.types.BooleanModifier.bl_rna.properties["solver"].enum_items]
    return "EXACT" if "EXACT" in items else items[-1]


def _apply_modifiers(obj):
    """Replace obj's mesh by its evaluated mesh, as triangles, then drop the modifiers.

    obj may be translated (not rotated or scaled): the mesh stays in its local space.
    """
    from genbrep import bridge
    depsgraph = bpy.context.evaluated_depsgraph_get()
    vertices, triangles = bridge.read_triangles(obj, depsgraph)
    vertices = vertices - np.array(obj.location)
    old = obj.data
    obj.modifiers.clear()
    obj.data = bridge.new_mesh(old.name, vertices, triangles)
    bpy.data.meshes.remove(old)


def _remesh(obj, h):
    modifier = obj.modifiers.new("voxel remesh", "REMESH")
    modifier.mode = "VOXEL"
    modifier.voxel_size = h
    modifier.adaptivity = 0.0
    _apply_modifiers(obj)


def build_design(spec, collection):
    """The level-set-style design: (solids ∪ organic − keep-outs − erosions) remeshed at h.

    The voxel grid's points are the design object's location plus integer multiples of h
    (the remesh works in object space). The location is an odd fraction of h so that no
    flat solid face lies exactly on a grid plane: there the mesher makes zero-length edges.
    """
    h = spec["h"]
    origin = np.array(GRID_OFFSET) * h
    additive = [m for _, role, m in spec["solids"] if role in ("KEEP_IN", "SEED")]
    vertices, triangles = _join(additive + spec["organic"])
    design = _object("design", (vertices - origin, triangles), collection)
    design.location = origin
    _remesh(design, h / 2)  # the union, fine enough that the final remesh sets the accuracy
    cutters = [m for _, role, m in spec["solids"] if role == "KEEP_OUT"] + spec["erosions"]
    for index, cutter in enumerate(cutters):
        cutter_obj = _object(f"cutter {index}", cutter, collection)
        modifier = design.modifiers.new("cut", "BOOLEAN")
        modifier.operation, modifier.object = "DIFFERENCE", cutter_obj
        modifier.solver = _exact_solver()
        _apply_modifiers(design)
        bpy.data.objects.remove(cutter_obj)
    _remesh(design, h)
    design["genbrep_grid_h"] = h
    design["genbrep_grid_origin"] = tuple(float(c) for c in origin)
    design.genbrep.role = "DESIGN"
    return design


def mesh_defects(obj):
    """{defect: count}: boundary and non-manifold edges and vertices (bmesh), and vertices
    sharing a position with another one (the mesher's zero-length edges)."""
    bm = bmesh.new()
    bm.from_mesh(obj.data)
    defects = {"boundary edges": sum(1 for e in bm.edges if e.is_boundary),
               "non-manifold edges": sum(1 for e in bm.edges if not e.is_manifold),
               "non-manifold vertices": sum(1 for v in bm.verts if not v.is_manifold)}
    bm.free()
    co = np.empty(len(obj.data.vertices) * 3, np.float32)
    obj.data.vertices.foreach_get("co", co)
    defects["coincident vertices"] = len(co) // 3 - len(np.unique(co.reshape(-1, 3), axis=0))
    return defects


def write_obj(path, vertices, triangles):
    """Plain OBJ: 'v x y z' lines and 1-based 'f a b c' lines.

    17 digits: the world-space float64 vertices round-trip exactly, so the command line
    converts the very design the add-on passes (with 9 digits lattice's design moved by
    1e-9 and the quad stage kept another layout)."""
    with open(path, "w") as out:
        out.write("# genbrep fixture, world space\n")
        np.savetxt(out, vertices, fmt="v %.17g %.17g %.17g")
        np.savetxt(out, triangles + 1, fmt="f %d %d %d")


def export_objs(scene_name, objects):
    from genbrep import bridge
    folder = os.path.join(HERE, "obj", scene_name)
    os.makedirs(folder, exist_ok=True)
    for old in os.listdir(folder):
        if old.endswith(".obj"):
            os.remove(os.path.join(folder, old))
    depsgraph = bpy.context.evaluated_depsgraph_get()
    for obj in objects:
        vertices, triangles = bridge.read_triangles(obj, depsgraph)
        write_obj(os.path.join(folder, f"{obj.name}_{obj.genbrep.role.lower()}.obj"),
                  vertices, triangles)


def make_scene(scene_name, spec):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.name = scene_name
    collection = scene.collection
    design = build_design(spec, collection)
    solids = []
    for name, role, arrays in spec["solids"]:
        obj = _object(name, arrays, collection)
        obj.genbrep.role = role
        obj.display_type = "WIRE"
        solids.append(obj)
    defects = mesh_defects(design)
    triangles = len(design.data.polygons)
    clean = not any(defects.values())
    print(f"{scene_name}: design {triangles} triangles, h = {spec['h']}, "
          + ", ".join(f"{count} {name}" for name, count in defects.items())
          + (": closed manifold" if clean else ": BROKEN"))
    path = os.path.join(HERE, f"{scene_name}.blend")
    if os.path.exists(path):
        os.remove(path)  # else Blender keeps the old file as a .blend1 backup
    bpy.ops.wm.save_as_mainfile(filepath=path, compress=True)
    export_objs(scene_name, [design] + solids)
    print(f"  wrote {os.path.relpath(path)} ({os.path.getsize(path) // 1024} KiB)")
    return clean and triangles <= MAX_TRIANGLES


def main():
    genbrep.register()
    wanted = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else list(SCENES)
    failed = [name for name in wanted if not make_scene(name, SCENES[name]())]
    if failed:
        print(f"broken or too large: {', '.join(failed)}", file=sys.stderr)
        sys.exit(1)


if __name__ == "__main__":
    main()

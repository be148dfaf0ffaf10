"""Side by side of genbrep's cage and Blender's QuadriFlow remesh of the same organic region.

    blender -b blend_fixtures/seed.blend --python-exit-code 1 -P scripts/blender_convert.py \
        -- --until fit --out /tmp/qf/seed_fit.blend
    blender -b /tmp/qf/seed_fit.blend --factory-startup -P docs/compare_quadriflow.py -- \
        --components 0 1 --tag seed --out-dir docs [--json /tmp/qf/seed_compare.json]

The .blend must hold a converted design (collection "genbrep <design>" with the
"<design> partition" object and its "<design> cage component <c>" objects). Converted
`--until fit`, the cages are the fitted ones; after compose they are the pulled ones, whose
boundary is moved into the solids on purpose (docs/compose_method.md). For each
component c:
  1. the region: faces of the partition with genbrep_component == c, as an open mesh;
  2. QuadriFlow on the region, target_faces = our cage's quad count so densities match;
  3. the same measurement (measure_quads) on our cage and on the remesh, plus boundary
     conformity of the mesh and of its Catmull-Clark limit against the region's loops;
  4. one PNG of two panels (ours left, QuadriFlow right, same camera): surface, edges as
     dark bars, irregular vertices as red balls, the region's boundary loops as a blue tube.
Figures go to stdout as JSON (and to --json). QuadriFlow failures are recorded, not hidden.
"""

import argparse
import json
import math
import os
import sys
import tempfile

import bmesh
import bpy
import numpy as np
from mathutils import Matrix, Vector

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from render_result import cycles_png, frame, light  # noqa: E402  (render settings the docs share)
from mathutils.bvhtree import BVHTree


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    parser = argparse.ArgumentParser(prog="compare_quadriflow.py")
    parser.add_argument("--components", type=int, nargs="+", required=True)
    parser.add_argument("--tag", help="name part of the PNGs, quadriflow_<tag>_c<c>.png; "
                                      "default: the .blend's name")
    parser.add_argument("--out-dir", default="docs")
    parser.add_argument("--json", help="also write the figures here")
    parser.add_argument("--samples", type=int, default=16)
    parser.add_argument("--width", type=int, default=800, help="of one panel")
    parser.add_argument("--height", type=int, default=600)
    parser.add_argument("--view", type=float, nargs=3,
                        help="direction from the region to the camera; default: along the "
                             "region's mean normal, tilted toward (1, -1.5, 1.1)")
    parser.add_argument("--seeds", type=int, nargs="+", default=[0],
                        help="QuadriFlow seeds to run (each with and without boundary preservation)")
    parser.add_argument("--variants", action="store_true",
                        help="also run QuadriFlow with preserve sharp, smooth normals, mesh "
                             "symmetry, and half and double the target faces")
    parser.add_argument("--no-render", action="store_true")
    return parser.parse_args(argv)


# ---------------------------------------------------------------- measurement

def measure_quads(bm):
    """The figures of native/quad/quad.cpp measure_cage, on any polygon mesh.

    Valence counts edges, so a regular boundary vertex has 3 (one edge into the interior)
    and an open corner 2; irregular = interior ≠ 4 plus boundary ≠ 3, as in our report.
    The angle deviation is the mean |corner angle − 90°| over quad corners only.
    """
    faces = list(bm.faces)
    quads = [f for f in faces if len(f.verts) == 4]
    interior = boundary = interior4 = boundary3 = 0
    irregular = []
    for v in bm.verts:
        if not v.link_faces:
            continue
        valence = len(v.link_edges)
        if any(len(e.link_faces) == 1 for e in v.link_edges):
            boundary += 1
            boundary3 += valence == 3
            regular = valence == 3
        else:
            interior += 1
            interior4 += valence == 4
            regular = valence == 4
        if not regular:
            irregular.append(v.co.copy())
    deviations = []
    for f in quads:
        c = [v.co for v in f.verts]
        for k in range(4):
            a, b = c[(k + 1) % 4] - c[k], c[(k + 3) % 4] - c[k]
            angle = math.degrees(math.atan2(a.cross(b).length, a.dot(b)))
            deviations.append(abs(angle - 90))
    return {
        "faces": len(faces),
        "quads": len(quads),
        "quad_fraction": len(quads) / len(faces) if faces else 0.0,
        "vertices": interior + boundary,
        "interior_valence4_fraction": interior4 / interior if interior else 1.0,
        "boundary_valence3_fraction": boundary3 / boundary if boundary else 1.0,
        "irregular_vertices": len(irregular),
        "irregular_interior": interior - interior4,
        "irregular_boundary": boundary - boundary3,
        "mean_angle_deviation_degrees": float(np.mean(deviations)) if deviations else 0.0,
        "nonmanifold_edges": sum(len(e.link_faces) > 2 for e in bm.edges),
        "irregular_points": irregular,
    }


def boundary_loops(bm):
    """Closed boundary polylines (lists of points), one per loop of edges with one face.

    Walks from vertex to vertex along unused boundary edges; a vertex where two loops touch
    just continues on another unused edge, so the loop count stays the number of cycles.
    """
    edges = [e for e in bm.edges if len(e.link_faces) == 1]
    unused = set(e.index for e in edges)
    by_vertex = {}
    for e in edges:
        for v in e.verts:
            by_vertex.setdefault(v.index, []).append(e)
    loops = []
    for start in edges:
        if start.index not in unused:
            continue
        unused.discard(start.index)
        first, current = start.verts[0], start.verts[1]
        points = [first.co.copy(), current.co.copy()]
        while current != first:
            step = next((e for e in by_vertex[current.index] if e.index in unused), None)
            if step is None:  # open chain: cannot happen on a mesh, keep what we walked
                break
            unused.discard(step.index)
            current = step.other_vert(current)
            points.append(current.co.copy())
        loops.append(points[:-1] if current == first else points)
    return loops


def sample_polylines(loops, spacing):
    """Points along the closed polylines, no farther apart than `spacing`."""
    samples = []
    for points in loops:
        for a, b in zip(points, points[1:] + points[:1]):
            n = max(1, math.ceil((b - a).length / spacing))
            samples.extend(a.lerp(b, t / n) for t in range(n))
    return np.array([tuple(p) for p in samples], dtype=np.float64)


def loop_length(loops):
    return sum((b - a).length for points in loops for a, b in zip(points, points[1:] + points[:1]))


def segments_of(loops):
    a = np.array([tuple(p) for points in loops for p in points], dtype=np.float64)
    b = np.array([tuple(p) for points in loops for p in points[1:] + points[:1]], dtype=np.float64)
    return a, b


def distance_to_segments(points, seg_a, seg_b):
    """Distance from each point to the nearest of the segments (brute force, chunked)."""
    d = seg_b - seg_a
    length2 = np.maximum((d * d).sum(1), 1e-300)
    out = np.empty(len(points))
    for start in range(0, len(points), 512):
        p = points[start:start + 512, None, :]
        t = np.clip(((p - seg_a) * d).sum(2) / length2, 0, 1)
        closest = seg_a + t[..., None] * d
        out[start:start + 512] = np.sqrt(((p - closest) ** 2).sum(2)).min(1)
    return out


def boundary_conformity(region_loops, mesh_loops, spacing):
    """Both one-sided distances between the two sets of boundary polylines, and the loop counts.

    region→mesh says whether every bit of the region's boundary is matched; mesh→region
    whether the remesh's boundary strays. Their max is the Hausdorff distance of the curves.
    """
    lengths = {"region_boundary_length": loop_length(region_loops),
               "mesh_boundary_length": loop_length(mesh_loops)}
    if not mesh_loops:
        return dict(lengths, region_loops=len(region_loops), mesh_loops=0, same_loop_count=False)
    to_mesh = distance_to_segments(sample_polylines(region_loops, spacing), *segments_of(mesh_loops))
    to_region = distance_to_segments(sample_polylines(mesh_loops, spacing), *segments_of(region_loops))
    vertices = np.array([tuple(p) for points in mesh_loops for p in points], dtype=np.float64)
    corners = distance_to_segments(vertices, *segments_of(region_loops))
    return {
        **lengths,
        "region_loops": len(region_loops),
        "mesh_loops": len(mesh_loops),
        "same_loop_count": len(region_loops) == len(mesh_loops),
        "region_to_mesh_max": float(to_mesh.max()), "region_to_mesh_mean": float(to_mesh.mean()),
        "mesh_to_region_max": float(to_region.max()), "mesh_to_region_mean": float(to_region.mean()),
        "hausdorff": float(max(to_mesh.max(), to_region.max())),
        # The mesh's boundary vertices alone: separates vertices that left the boundary
        # from chords cutting across a curved loop.
        "mesh_vertices_to_region_max": float(corners.max()),
    }


def faces_off_region(bm, region_bvh, distance):
    """Faces whose centre is farther than `distance` from the region: caps over openings."""
    return sum((region_bvh.find_nearest(f.calc_center_median())[0]
                - f.calc_center_median()).length > distance for f in bm.faces)


def surface_distance(bm_from, bvh_to):
    """Vertex-to-surface distance, max and mean: a coarse check that the surface is kept."""
    d = np.array([(bvh_to.find_nearest(v.co)[0] - v.co).length for v in bm_from.verts
                  if v.link_faces])
    return {"max": float(d.max()), "mean": float(d.mean())}


def limit_bmesh(obj, levels=3):
    """bmesh of obj's mesh under Catmull-Clark with limit positions (what a cage stands for).

    Any modifiers of obj are replaced by one SUBSURF like the add-on's (boundary smooth ALL,
    use_limit_surface), so QuadriFlow's mesh, read as a cage, is subdivided the same way.
    """
    probe = bpy.data.objects.new(obj.name + " limit probe", obj.data)
    bpy.context.scene.collection.objects.link(probe)
    modifier = probe.modifiers.new("limit", "SUBSURF")
    modifier.levels = modifier.render_levels = levels
    modifier.boundary_smooth, modifier.use_limit_surface = "ALL", True
    evaluated = probe.evaluated_get(bpy.context.evaluated_depsgraph_get())
    bm = bmesh.new()
    bm.from_mesh(evaluated.to_mesh())
    bm.transform(obj.matrix_world)
    evaluated.to_mesh_clear()
    bpy.data.objects.remove(probe)
    return bm


def bmesh_of(obj):
    bm = bmesh.new()
    bm.from_mesh(obj.data)
    bm.transform(obj.matrix_world)
    bm.verts.ensure_lookup_table()
    return bm


# ---------------------------------------------------------------- region and QuadriFlow

def extract_region(partition, component):
    """New object: the partition faces labelled `component`, loose edges and vertices
    dropped (edges between two faces of other components would otherwise stay as wires,
    and QuadriFlow refuses a mesh with them)."""
    labels = np.zeros(len(partition.data.polygons), dtype=np.int32)
    partition.data.attributes["genbrep_component"].data.foreach_get("value", labels)
    bm = bmesh_of(partition)
    bm.faces.ensure_lookup_table()
    bmesh.ops.delete(bm, geom=[bm.faces[i] for i in np.flatnonzero(labels != component)],
                     context="FACES_ONLY")
    bmesh.ops.delete(bm, geom=[e for e in bm.edges if not e.link_faces], context="EDGES_FACES")
    bmesh.ops.delete(bm, geom=[v for v in bm.verts if not v.link_faces], context="VERTS")
    mesh = bpy.data.meshes.new(f"region {component}")
    bm.to_mesh(mesh)
    bm.free()
    region = bpy.data.objects.new(mesh.name, mesh)
    bpy.context.scene.collection.objects.link(region)
    return region


# Blender 3.4's defaults, except symmetry (see compare()); passed in full on every call.
QUADRIFLOW_DEFAULTS = {"use_preserve_boundary": False, "use_preserve_sharp": False,
                       "smooth_normals": False, "use_mesh_symmetry": False,
                       "preserve_paint_mask": False, "mode": "FACES", "seed": 0}


def run_quadriflow(region, target_faces, **options):
    """QuadriFlow on a copy of region; returns (object or None, what happened).

    The operator reports failures through the window manager, not through its return value
    (it returns FINISHED either way: on a non-manifold fan it leaves the mesh as it was and
    prints a warning), so stdout is captured at the file-descriptor level
    for its message and the mesh is compared before/after to tell success from failure.
    """
    remesh = bpy.data.objects.new(f"quadriflow {region.name}", region.data.copy())
    bpy.context.scene.collection.objects.link(remesh)
    bpy.ops.object.select_all(action="DESELECT")
    remesh.select_set(True)
    bpy.context.view_layer.objects.active = remesh
    before = (len(remesh.data.vertices), len(remesh.data.polygons))
    sys.stdout.flush()
    saved = os.dup(1)
    with tempfile.TemporaryFile(mode="w+") as captured:
        os.dup2(captured.fileno(), 1)
        try:
            result = bpy.ops.object.quadriflow_remesh(target_faces=target_faces, **options)
            error = None
        except RuntimeError as exc:
            result, error = None, str(exc)
        finally:
            sys.stdout.flush()
            os.dup2(saved, 1)
            os.close(saved)
        captured.seek(0)
        messages = [line.strip() for line in captured if "uadri" in line or "rror" in line]
    after = (len(remesh.data.vertices), len(remesh.data.polygons))
    changed = after != before or any(len(p.vertices) != 3 for p in remesh.data.polygons)
    outcome = {"options": dict(options, target_faces=target_faces),
               "operator_result": sorted(result) if result else None,
               "exception": error, "messages": messages, "changed_mesh": changed}
    if not changed:
        bpy.data.objects.remove(remesh)
        return None, outcome
    return remesh, outcome


# ---------------------------------------------------------------- rendering

def material(name, color, roughness=0.6):
    m = bpy.data.materials.new(name)
    m.use_nodes = True
    bsdf = m.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = color
    bsdf.inputs["Roughness"].default_value = roughness
    return m


def with_material(obj, mat):
    obj.data.materials.clear()
    obj.data.materials.append(mat)
    return obj


def link(obj):
    bpy.context.scene.collection.objects.link(obj)
    return obj


def wire_object(source, thickness, mat):
    """The edges of source's own mesh as bars (Wireframe modifier on an unsubdivided copy)."""
    wire = link(bpy.data.objects.new(source.name + " wire", source.data.copy()))
    modifier = wire.modifiers.new("wire", "WIREFRAME")
    modifier.thickness, modifier.use_even_offset = thickness, False
    return with_material(wire, mat)


def balls(name, points, radius, mat):
    bm = bmesh.new()
    for p in points:
        bmesh.ops.create_icosphere(bm, subdivisions=2, radius=radius,
                                   matrix=Matrix.Translation(p))
    mesh = bpy.data.meshes.new(name)
    bm.to_mesh(mesh)
    bm.free()
    for polygon in mesh.polygons:
        polygon.use_smooth = True
    return with_material(link(bpy.data.objects.new(name, mesh)), mat)


def loop_tube(name, loops, radius, mat):
    curve = bpy.data.curves.new(name, "CURVE")
    curve.dimensions, curve.bevel_depth, curve.bevel_resolution = "3D", radius, 2
    for points in loops:
        spline = curve.splines.new("POLY")
        spline.points.add(len(points) - 1)
        spline.points.foreach_set("co", [c for p in points for c in (*p, 1.0)])
        spline.use_cyclic_u = True
    return with_material(link(bpy.data.objects.new(name, curve)), mat)


def setup_scene(args):
    scene = bpy.context.scene
    cycles_png(scene, args.samples, args.width, args.height)
    scene.render.image_settings.color_mode = "RGB"
    # The panel title is stamped into the image so a PNG says which method it shows.
    scene.render.use_stamp = True
    for flag in ("date", "time", "render_time", "frame", "frame_range", "memory", "hostname",
                 "camera", "lens", "scene", "marker", "filename", "sequencer_strip"):
        setattr(scene.render, "use_stamp_" + flag, False)
    scene.render.use_stamp_note = True
    scene.render.stamp_font_size = 20
    light(scene)
    return scene


def view_direction(bm):
    """The region's area-weighted mean normal, tilted a little so the shape reads in depth.

    A tube or a closed-around sheet has a mean normal near zero; it gets the oblique default.
    """
    oblique = Vector((1.0, -1.5, 1.1)).normalized()
    mean = sum((f.normal * f.calc_area() for f in bm.faces), Vector())
    if mean.length < 0.3 * sum(f.calc_area() for f in bm.faces):
        return oblique
    return mean.normalized() + 0.4 * oblique


def render_panels(scene, panels, out):
    """Renders each (title, objects) panel alone and writes them side by side into out."""
    strips = []
    for index, (title, objects) in enumerate(panels):
        for obj in scene.objects:
            if obj.type in {"MESH", "CURVE"}:
                obj.hide_render = obj not in objects
        scene.render.stamp_note_text = title
        scene.render.filepath = os.path.join(tempfile.gettempdir(), f"qf_panel{index}.png")
        bpy.ops.render.render(write_still=True)
        image = bpy.data.images.load(scene.render.filepath)
        width, height = image.size
        strips.append(np.array(image.pixels[:], dtype=np.float32).reshape(height, width, 4))
        bpy.data.images.remove(image)
    gap = np.ones((strips[0].shape[0], 6, 4), dtype=np.float32)  # white bar between panels
    joined = np.concatenate([strips[0], gap] + strips[1:], axis=1)
    result = bpy.data.images.new("panels", joined.shape[1], joined.shape[0], alpha=True)
    result.pixels.foreach_set(joined.ravel())
    result.save_render(out, scene=scene)  # with the scene's PNG settings: RGB, compressed


# ---------------------------------------------------------------- main

def compare(args, scene, design_objects, component, mats):
    """Region, QuadriFlow runs, figures of both and (unless --no-render) the PNG of one
    component; returns the figures as a dict (JSON-ready)."""
    partition = next(o for o in design_objects if o.name.endswith(" partition"))
    cage = next(o for o in design_objects if o.name.endswith(f" cage component {component}"))
    region = extract_region(partition, component)
    region_bm = bmesh_of(region)
    region_loops = boundary_loops(region_bm)
    size = max(region.dimensions)
    spacing = size / 2000  # sampling step of the boundary curves: far below any gap we report
    region_bvh = BVHTree.FromBMesh(region_bm)

    cage_bm = bmesh_of(cage)
    target = len(cage.data.polygons)

    def describe(obj, bm):
        stats = measure_quads(bm)
        points = stats.pop("irregular_points")
        limit = limit_bmesh(obj)
        stats["boundary"] = boundary_conformity(region_loops, boundary_loops(bm), spacing)
        stats["limit_boundary"] = boundary_conformity(region_loops, boundary_loops(limit), spacing)
        stats["faces_off_region"] = faces_off_region(bm, region_bvh, 0.02 * size)
        stats["limit_to_region_surface"] = surface_distance(limit, region_bvh)
        stats["region_to_limit_surface"] = surface_distance(region_bm, BVHTree.FromBMesh(limit))
        limit.free()
        return stats, points

    figures = {"component": component, "region_faces": len(region_bm.faces),
               "region_size": size, "ours": None, "quadriflow": []}
    figures["ours"], cage_points = describe(cage, cage_bm)
    # With and without boundary preservation, to see what the option does; --variants adds
    # the other options and half / double density. Every option is passed on every call:
    # from Python the operator otherwise reuses the previous call's values. Symmetry stays
    # off by default: it applies the mesh's own mirror settings, which the region does not set.
    # The first run that changes the mesh is the one rendered.
    runs = [({"use_preserve_boundary": p, "seed": s}, 1.0) for p in (True, False)
            for s in args.seeds]
    if args.variants:
        runs += [({"use_preserve_boundary": True, option: True}, 1.0)
                 for option in ("use_preserve_sharp", "smooth_normals", "use_mesh_symmetry")]
        runs += [({"use_preserve_boundary": True}, scale) for scale in (0.5, 2.0)]
    remesh = remesh_points = None
    for variant, scale in runs:
        options = dict(QUADRIFLOW_DEFAULTS, **variant)
        result, outcome = run_quadriflow(region, round(target * scale), **options)
        if result is not None:
            outcome["figures"], points = describe(result, bmesh_of(result))
            if remesh is None:
                remesh, remesh_points = result, points
                remesh_title = (f"QuadriFlow, preserve boundary "
                                f"{'on' if options['use_preserve_boundary'] else 'off'} "
                                f"({len(result.data.polygons)} quads, as is)")
            else:
                bpy.data.objects.remove(result)
        figures["quadriflow"].append(outcome)

    if not args.no_render:
        out = os.path.join(args.out_dir, f"quadriflow_{args.tag}_c{component}.png")
        limit = link(bpy.data.objects.new(cage.name + " surface", cage.data.copy()))
        limit.modifiers.new("subsurf", "SUBSURF").render_levels = 3
        limit.data.polygons.foreach_set("use_smooth", [True] * len(limit.data.polygons))
        with_material(limit, mats["surface"])
        tube = loop_tube(f"loops {component}", region_loops, 0.004 * size, mats["loop"])
        ours = [limit, wire_object(cage, 0.004 * size, mats["wire"]), tube,
                balls("irregular ours", cage_points, 0.012 * size, mats["irregular"])]
        panels = [(f"genbrep cage ({len(cage.data.polygons)} quads, over its limit surface)", ours)]
        if remesh is not None:
            with_material(remesh, mats["surface"])
            panels.append((remesh_title,
                           [remesh, wire_object(remesh, 0.004 * size, mats["wire"]), tube,
                            balls("irregular qf", remesh_points, 0.012 * size,
                                  mats["irregular"])]))
        # One camera for both panels, a little farther than render_result's crop.
        frame(scene, [region], args.view or view_direction(region_bm), margin=1.05,
              camera=scene.camera)
        render_panels(scene, panels, out)
        figures["png"] = out
    return figures


def main():
    args = parse_args()
    args.tag = args.tag or bpy.path.display_name_from_filepath(bpy.data.filepath)
    design_objects = [o for c in bpy.context.scene.collection.children
                      if c.name.startswith("genbrep ") for o in c.all_objects]
    if not any(o.name.endswith(" partition") for o in design_objects):
        print("compare_quadriflow.py: no genbrep partition in this file: convert it first",
              file=sys.stderr)
        sys.exit(1)
    scene = setup_scene(args)
    for obj in scene.objects:
        obj.hide_render = True
    mats = {"surface": material("surface", (0.75, 0.72, 0.66, 1)),
            "wire": material("wire", (0.03, 0.03, 0.05, 1)),
            "loop": material("loop", (0.05, 0.25, 0.9, 1)),
            "irregular": material("irregular", (0.9, 0.05, 0.03, 1), roughness=0.3)}
    results = [compare(args, scene, design_objects, c, mats) for c in args.components]
    text = json.dumps({"file": bpy.data.filepath, "results": results}, indent=1)
    print(text)
    if args.json:
        with open(args.json, "w") as f:
            f.write(text)


if __name__ == "__main__":
    main()

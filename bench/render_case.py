"""Render corpus cases to one PNG (Cycles on the CPU): each case's design in grey with its
keep-ins blue, keep-outs red and seeds yellow drawn see-through; with --result, the
composed mesh of that case's conversion beside it.

    blender -b --factory-startup --python-exit-code 1 -P bench/render_case.py -- \
        --out cases.png CASE_DIR... [--result OUT_DIR] [--samples 16] [--size 480]

Several cases are laid out in a row, each scaled to the same size, so a generated design
and a real bracket can be compared at a glance.
"""

import argparse
import json
import math
import pathlib
import sys

import bpy
from mathutils import Vector

COLOURS = {"design": (0.75, 0.74, 0.70, 1), "keep_in": (0.15, 0.35, 0.95, 1),
           "keep_out": (0.95, 0.15, 0.12, 1), "seed": (0.95, 0.80, 0.10, 1),
           "composed": (0.55, 0.75, 0.60, 1)}


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    parser = argparse.ArgumentParser(prog="render_case.py")
    parser.add_argument("cases", nargs="+", help="case folders (meta.json, design.obj, solids)")
    parser.add_argument("--out", required=True)
    parser.add_argument("--result", help="conversion output folder of a single case (composed.obj)")
    parser.add_argument("--samples", type=int, default=16)
    parser.add_argument("--size", type=int, default=480, help="pixels per panel, square")
    return parser.parse_args(argv)


def material(role):
    mat = bpy.data.materials.new(role)
    mat.use_nodes = True
    bsdf = mat.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = COLOURS[role]
    if role in ("keep_in", "keep_out", "seed"):
        bsdf.inputs["Alpha"].default_value = 0.45
        mat.blend_method = "BLEND"
    return mat


def load_obj(path, role):
    """A mesh object from a v/f OBJ file (plain reader: the importer differs across versions)."""
    vertices, faces = [], []
    for line in open(path):
        parts = line.split()
        if parts and parts[0] == "v":
            vertices.append(tuple(float(x) for x in parts[1:4]))
        elif parts and parts[0] == "f":
            faces.append(tuple(int(p.split("/")[0]) - 1 for p in parts[1:]))
    mesh = bpy.data.meshes.new(pathlib.Path(path).stem)
    mesh.from_pydata(vertices, [], faces)
    obj = bpy.data.objects.new(mesh.name, mesh)
    obj.data.materials.append(material(role))
    bpy.context.scene.collection.objects.link(obj)
    return obj


def case_objects(case):
    meta = json.loads((case / "meta.json").read_text())
    objects = [load_obj(case / "design.obj", "design")]
    for role, key in (("keep_in", "keep_in"), ("keep_out", "keep_out"), ("seed", "seed")):
        objects += [load_obj(case / name, role) for name in meta.get(key, [])]
    return objects


VIEW = Vector((1.0, -1.6, 1.1)).normalized()  # from the scene towards the camera
ROTATION = (-VIEW).to_track_quat("-Z", "Y")


def fit_into_slot(objects, slot, slots):
    """Scales the objects to a unit-radius bounding sphere centred on the slot-th place of a
    row that runs across the picture."""
    at = (ROTATION @ Vector((1, 0, 0))) * 2.2 * (slot - (slots - 1) / 2)
    corners = [o.matrix_world @ Vector(c) for o in objects for c in o.bound_box]
    lo = Vector(min(c[i] for c in corners) for i in range(3))
    hi = Vector(max(c[i] for c in corners) for i in range(3))
    centre, radius = (lo + hi) / 2, max((hi - lo).length / 2, 1e-30)
    for o in objects:
        for v in o.data.vertices:
            v.co = (v.co - centre) / radius + at


def main():
    args = parse_args()
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    panels = [case_objects(pathlib.Path(c)) for c in args.cases]
    if args.result:
        panels.append([load_obj(pathlib.Path(args.result) / "composed.obj", "composed")])
    for slot, objects in enumerate(panels):
        fit_into_slot(objects, slot, len(panels))
    camera = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
    camera.data.type = "ORTHO"
    camera.data.ortho_scale = 2.2 * len(panels)
    camera.location = VIEW * 10
    camera.rotation_euler = ROTATION.to_euler()
    scene.collection.objects.link(camera)
    scene.camera = camera
    sun = bpy.data.objects.new("sun", bpy.data.lights.new("sun", "SUN"))
    sun.data.energy = 2.5
    sun.rotation_euler = (math.radians(40), math.radians(10), math.radians(30))
    scene.collection.objects.link(sun)
    world = bpy.data.worlds.new("world")
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.25, 0.25, 0.27, 1)
    scene.world = world
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = args.samples
    scene.cycles.use_denoising = False
    scene.render.resolution_x = args.size * len(panels)
    scene.render.resolution_y = args.size
    scene.render.filepath = args.out
    bpy.ops.render.render(write_still=True)


main()

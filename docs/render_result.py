"""Render the genbrep results of a .blend to a PNG (Cycles on the CPU), for the docs.

    blender -b converted.blend --python-exit-code 1 -P docs/render_result.py -- \
        --out docs/partition_boss.png [--samples 32] [--width 960] [--height 540]

Renders what the result collections ("genbrep <design>") show: the partition colours, and
the cages and composed mesh once the pipeline makes them; everything else is hidden from
the render. Adds a camera framing the results, a sun and a light grey world.
"""

import argparse
import math
import sys

import bpy
from mathutils import Vector


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    parser = argparse.ArgumentParser(prog="render_result.py")
    parser.add_argument("--out", required=True, help="PNG to write")
    parser.add_argument("--samples", type=int, default=32)
    parser.add_argument("--width", type=int, default=960)
    parser.add_argument("--height", type=int, default=540)
    parser.add_argument("--view", type=float, nargs=3, default=(1.0, -1.5, 1.1),
                        help="direction from the results to the camera")
    parser.add_argument("--panels", action="store_true",
                        help="one image of three panels side by side: partition colours, "
                             "cages (limit surface with the control cage drawn), composed solid")
    return parser.parse_args(argv)


def result_objects(scene):
    collections = [c for c in scene.collection.children if c.name.startswith("genbrep ")]
    return [o for c in collections for o in c.all_objects if not o.hide_render]


def frame(scene, objects, direction, margin=0.75, camera=None):
    """Camera looking along -direction at the objects' bounding sphere. `margin` scales the
    distance at which the sphere just fits (0.75 crops it to fill the frame); `camera` is
    moved if given, else a new one is made."""
    corners = [o.matrix_world @ Vector(c) for o in objects for c in o.bound_box]
    low = Vector(tuple(min(c[i] for c in corners) for i in range(3)))
    high = Vector(tuple(max(c[i] for c in corners) for i in range(3)))
    center, radius = (low + high) / 2, (high - low).length / 2
    if camera is None:
        camera = bpy.data.objects.new("render camera", bpy.data.cameras.new("render camera"))
        scene.collection.objects.link(camera)
    aspect = scene.render.resolution_y / scene.render.resolution_x
    half_fov = math.atan(camera.data.sensor_width / 2 * aspect / camera.data.lens)
    direction = Vector(direction).normalized()
    camera.location = center + direction * (radius / math.sin(half_fov) * margin)
    camera.rotation_euler = (-direction).to_track_quat("-Z", "Y").to_euler()
    camera.data.clip_end = radius * 20
    scene.camera = camera


def light(scene):
    sun = bpy.data.objects.new("render sun", bpy.data.lights.new("render sun", "SUN"))
    sun.data.energy = 3.0
    sun.rotation_euler = (math.radians(40), math.radians(10), math.radians(30))
    scene.collection.objects.link(sun)
    world = scene.world or bpy.data.worlds.new("render world")
    scene.world = world
    world.use_nodes = True
    background = world.node_tree.nodes.get("Background")
    background.inputs["Color"].default_value = (0.8, 0.82, 0.85, 1.0)
    background.inputs["Strength"].default_value = 0.7


def cycles_png(scene, samples, width, height):
    """Cycles on the CPU, no denoiser, a PNG of width × height, colours as written."""
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = samples
    scene.cycles.use_denoising = False  # this Blender build has no OpenImageDenoise
    scene.render.resolution_x, scene.render.resolution_y = width, height
    scene.render.resolution_percentage = 100
    scene.render.image_settings.file_format = "PNG"
    scene.render.image_settings.compression = 100
    scene.view_settings.view_transform = "Standard"  # keep the partition colours as written


def main():
    args = parse_args()
    scene = bpy.context.scene
    shown = result_objects(scene)
    if not shown:
        print("render_result.py: no genbrep results in this file: convert it first",
              file=sys.stderr)
        sys.exit(1)
    for obj in scene.objects:
        if obj not in shown:
            obj.hide_render = True
    cycles_png(scene, args.samples, args.width, args.height)
    scene.render.filepath = bpy.path.abspath(args.out)
    frame(scene, shown, args.view)
    light(scene)
    if args.panels:
        render_panels(scene, result_panels(scene), args.out)
    else:
        bpy.ops.render.render(write_still=True)
    print(f"render_result.py: wrote {args.out}")


def result_panels(scene):
    """Objects of each panel: partition (with loops), cages (with their wire), composed."""
    objects = [o for c in scene.collection.children if c.name.startswith("genbrep ")
               for o in c.all_objects]
    partition = [o for o in objects if o.name.endswith((" partition", " boundary loops"))]
    cages = [o for o in objects if " cage " in o.name]
    wires = []
    for cage in cages:  # the control cage as thin dark bars over its limit surface
        wire = bpy.data.objects.new(cage.name + " wire", cage.data)
        wire.matrix_world = cage.matrix_world
        modifier = wire.modifiers.new("wire", "WIREFRAME")
        modifier.thickness = 0.004 * max(cage.dimensions)
        material = bpy.data.materials.new("render cage wire")
        material.diffuse_color = (0.05, 0.05, 0.08, 1.0)
        material.use_nodes = True
        material.node_tree.nodes["Principled BSDF"].inputs["Base Color"].default_value = (0.03, 0.03, 0.05, 1)
        wire.data = cage.data.copy()
        wire.data.materials.clear()
        wire.data.materials.append(material)
        cage.users_collection[0].objects.link(wire)
        wires.append(wire)
    composed = [o for o in objects if o.name.endswith(" composed")]
    return [p for p in (partition, cages + wires, composed) if p]


def render_panels(scene, panels, out):
    """Renders each panel alone and writes them side by side into `out`."""
    import numpy as np
    everything = {o for panel in panels for o in panel}
    strips = []
    for index, panel in enumerate(panels):
        for obj in everything:
            obj.hide_render = obj not in panel
        scene.render.filepath = bpy.path.abspath(out) + f".panel{index}.png"
        bpy.ops.render.render(write_still=True)
        image = bpy.data.images.load(scene.render.filepath)
        width, height = image.size
        strips.append(np.array(image.pixels[:], dtype=np.float32).reshape(height, width, 4))
    joined = np.concatenate(strips, axis=1)
    result = bpy.data.images.new("panels", joined.shape[1], joined.shape[0], alpha=True)
    result.pixels.foreach_set(joined.ravel())
    result.filepath_raw = bpy.path.abspath(out)
    result.file_format = "PNG"
    result.save()


if __name__ == "__main__":
    main()

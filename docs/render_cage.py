# docs/render_cage.py — a cage OBJ (genbrep convert's cage_NNN.obj) as a shaded surface with
# its edges drawn, seen from direction (dx, dy, dz) at `dist` from the point (cx, cy, cz);
# Cycles on the CPU, no denoising.
# blender -b --factory-startup -P docs/render_cage.py -- cage.obj out.png cx cy cz dx dy dz dist [markers]
# markers (optional): a text file of lines "x y z r g b", each drawn as a small sphere of
# that colour (e.g. irregular vertices, red where no singularity explains them).
import bpy, sys, math
from mathutils import Vector
argv = sys.argv[sys.argv.index("--") + 1:]
path, out = argv[0], argv[1]
c = Vector([float(x) for x in argv[2:5]]); d = Vector([float(x) for x in argv[5:8]]); dist = float(argv[8])
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.wm.obj_import(filepath=path, forward_axis="Y", up_axis="Z")
obj = bpy.context.selected_objects[0]
mat = bpy.data.materials.new("m"); mat.use_nodes = True
mat.node_tree.nodes["Principled BSDF"].inputs["Base Color"].default_value = (0.8, 0.75, 0.6, 1)
obj.data.materials.append(mat)
wire = obj.copy(); wire.data = obj.data.copy(); bpy.context.collection.objects.link(wire)
m = wire.modifiers.new("w", "WIREFRAME"); m.thickness = 0.008; m.use_replace = True
wm = bpy.data.materials.new("w"); wm.use_nodes = True
wm.node_tree.nodes["Principled BSDF"].inputs["Base Color"].default_value = (0.05, 0.05, 0.1, 1)
wire.data.materials.clear(); wire.data.materials.append(wm)
if len(argv) > 9:
    for line in open(argv[9]):
        x, y, z, r, g, b = (float(t) for t in line.split())
        bpy.ops.mesh.primitive_uv_sphere_add(radius=0.018, location=(x, y, z))
        dot = bpy.context.active_object
        dm = bpy.data.materials.new("dot"); dm.use_nodes = True
        dm.node_tree.nodes["Principled BSDF"].inputs["Base Color"].default_value = (r, g, b, 1)
        dot.data.materials.append(dm)
cam = bpy.data.objects.new("cam", bpy.data.cameras.new("cam")); bpy.context.collection.objects.link(cam)
cam.location = c + d.normalized() * dist
cam.rotation_euler = (c - cam.location).to_track_quat("-Z", "Y").to_euler()
bpy.context.scene.camera = cam
sun = bpy.data.objects.new("sun", bpy.data.lights.new("sun", "SUN")); bpy.context.collection.objects.link(sun)
sun.rotation_euler = cam.rotation_euler; sun.data.energy = 3
world = bpy.data.worlds.new("w"); bpy.context.scene.world = world; world.use_nodes = True
world.node_tree.nodes["Background"].inputs[1].default_value = 0.6
s = bpy.context.scene; s.render.engine = "CYCLES"; s.cycles.device = "CPU"; s.cycles.samples = 16
s.cycles.use_denoising = False; s.render.resolution_x = 960; s.render.resolution_y = 640
s.render.filepath = out
bpy.ops.render.render(write_still=True)

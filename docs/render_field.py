"""Render a cross field written by `genbrep convert --field-obj`: partition.ply plus field.obj.

    blender -b --factory-startup --python-exit-code 1 -P docs/render_field.py -- OUT_DIR PNG
"""
import bpy, sys, math
argv = sys.argv[sys.argv.index("--") + 1:]
folder, out = argv[0], argv[1]
bpy.ops.wm.read_factory_settings(use_empty=True)
import os
ply = folder + ("/relaxed.ply" if os.path.exists(folder + "/relaxed.ply") else "/partition.ply")
bpy.ops.import_mesh.ply(filepath=ply)
part = bpy.context.selected_objects[0]
bpy.ops.import_scene.obj(filepath=folder + "/field.obj", split_mode="OFF", axis_forward="Y", axis_up="Z")
field = bpy.context.selected_objects[0]
bpy.context.view_layer.objects.active = field
bpy.ops.object.convert(target="CURVE")
field.data.bevel_depth = 0.006
mat = bpy.data.materials.new("f"); mat.diffuse_color = (0.05, 0.05, 0.6, 1); mat.use_nodes = True
mat.node_tree.nodes["Principled BSDF"].inputs["Base Color"].default_value = (0.02, 0.05, 0.7, 1)
field.data.materials.append(mat)
m2 = bpy.data.materials.new("p"); m2.use_nodes = True
m2.node_tree.nodes["Principled BSDF"].inputs["Base Color"].default_value = (0.9, 0.85, 0.7, 1)
part.data.materials.append(m2)
scene = bpy.context.scene
cam = bpy.data.cameras.new("c"); co = bpy.data.objects.new("c", cam); scene.collection.objects.link(co)
co.location = (0.0, -13.0, 7.5); co.rotation_euler = (math.radians(65), 0, 0)
sun = bpy.data.lights.new("s", "SUN"); so = bpy.data.objects.new("s", sun); scene.collection.objects.link(so)
so.rotation_euler = (math.radians(40), math.radians(20), 0); sun.energy = 3
scene.camera = co
scene.render.engine = "CYCLES"; scene.cycles.samples = 16; scene.cycles.use_denoising = False
scene.render.resolution_x, scene.render.resolution_y = 1100, 700
scene.world = bpy.data.worlds.new("w"); scene.world.color = (0.8, 0.8, 0.8)
scene.render.filepath = out
bpy.ops.render.render(write_still=True)

"""genbrep: generative design -> editable cages, exact solid surfaces and a watertight mesh.

The bpy-free modules (native, options, checks, job, report, results) import without
Blender, so plain pytest covers them; the Blender modules (props, bridge, operators,
panels) are imported only by register().
"""

bl_info = {
    "name": "genbrep",
    "author": "genbrep contributors",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "View3D > Sidebar > genbrep",
    "description": "Convert a generative design mesh into editable Catmull-Clark cages, the "
                   "exact input solids and one watertight mesh (Marinov et al. 2019)",
    "category": "Object",
}


def register():
    from . import operators, panels, props
    props.register()
    operators.register()
    panels.register()


def unregister():
    from . import operators, panels, props
    panels.unregister()
    operators.unregister()
    props.unregister()

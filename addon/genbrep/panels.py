"""The genbrep tab in the 3D View sidebar: roles, settings, convert, report."""

import bpy

from . import checks, job, native, operators, props, report, results


def _design_name(context):
    try:
        return operators.target_design(context)
    except checks.InputError:
        return None


class GENBREP_PT_main(bpy.types.Panel):
    bl_label = "genbrep"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "genbrep"

    def draw(self, context):
        layout = self.layout
        ok, lines = native.status()
        if not ok:
            box = layout.box()
            for index, line in enumerate(lines):
                box.label(text=line, icon="ERROR" if index == 0 else "BLANK1")

        obj = context.active_object
        if obj is not None and obj.type in props.CONVERTIBLE_TYPES:
            layout.prop(obj.genbrep, "role", text=obj.name)

        layout.label(text="Set role of selected:")
        grid = layout.grid_flow(columns=3, align=True)
        for identifier, label, _ in props.ROLE_ITEMS:
            grid.operator(operators.GENBREP_OT_set_role.bl_idname, text=label).role = identifier

        col = layout.column(align=True)
        for role in ("DESIGN",) + checks.SOLID_ROLES:
            members = props.objects_with_role(context.scene, role)
            names = ", ".join(o.name for o in members[:4]) + (" ..." if len(members) > 4 else "")
            col.label(text=f"{checks.ROLE_LABELS[role]}: {len(members)}  {names}")


class GENBREP_PT_settings(bpy.types.Panel):
    bl_label = "Settings"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "genbrep"
    bl_parent_id = "GENBREP_PT_main"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        settings = context.scene.genbrep_settings
        layout.prop(settings, "tolerance_auto")
        row = layout.row()
        row.enabled = not settings.tolerance_auto
        row.prop(settings, "tolerance")
        layout.prop(settings, "incidence")
        if settings.incidence != "DISTANCE":
            col = layout.column()
            col.prop(settings, "grid_h")
            col.prop(settings, "grid_origin")
            col.operator(operators.GENBREP_OT_use_design_grid.bl_idname)
        layout.prop(settings, "density")
        if settings.density == "EDGE_LENGTH":
            layout.prop(settings, "target_edge_length")
        else:
            layout.prop(settings, "size_scale")
        layout.prop(settings, "fitting")
        layout.prop(settings, "until")


class GENBREP_PT_convert(bpy.types.Panel):
    bl_label = "Convert"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "genbrep"
    bl_parent_id = "GENBREP_PT_main"

    def draw(self, context):
        layout = self.layout
        name = _design_name(context)
        run = operators.running_job(name) if name else None
        if run is not None:
            snapshot = run.snapshot()
            if snapshot.state == job.RUNNING:
                layout.label(text=report.progress_text(snapshot.stage, snapshot.fraction,
                                                       native.stages()), icon="TIME")
                layout.label(text="Esc cancels")
                return
        row = layout.row()
        row.scale_y = 1.4
        row.operator(operators.GENBREP_OT_convert.bl_idname,
                     text=f"Convert '{name}'" if name else "Convert", icon="PLAY")
        row = layout.row(align=True)
        row.operator(operators.GENBREP_OT_recompose.bl_idname, icon="FILE_REFRESH")
        row.operator(operators.GENBREP_OT_clear_results.bl_idname, icon="TRASH")
        layout.prop(context.scene.genbrep_settings, "show_inputs")
        if name is None:
            layout.label(text="Give one object the role Design", icon="INFO")


class GENBREP_PT_report(bpy.types.Panel):
    bl_label = "Report"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "genbrep"
    bl_parent_id = "GENBREP_PT_main"

    @classmethod
    def poll(cls, context):
        name = _design_name(context)
        return name is not None and results.collection_name(name) in bpy.data.collections

    def draw(self, context):
        collection = bpy.data.collections[results.collection_name(_design_name(context))]
        col = self.layout.column(align=True)
        for line in report.lines_from_json(collection.get(results.REPORT_PROPERTY, "")):
            col.label(text=line, icon="ERROR" if line.startswith("warning") else "NONE")


CLASSES = (GENBREP_PT_main, GENBREP_PT_settings, GENBREP_PT_convert, GENBREP_PT_report)


def register():
    for cls in CLASSES:
        bpy.utils.register_class(cls)


def unregister():
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)

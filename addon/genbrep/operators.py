"""Operators: set roles, convert (modal job with progress and Esc, or synchronous), clear.

Operators stay thin: `prepare` validates and gathers arrays, a `job.ConversionJob` runs
the native call, `finish` writes the results on the main thread. Interactive runs use a
worker thread and a modal timer; under `blender -b`, from scripts and from the redo panel
the same steps run synchronously and print progress to the console.
"""

import traceback
from dataclasses import dataclass, field

import bpy

from . import bridge, checks, job, native, options, props, report, results

# Jobs of running modal conversions, by design name (one at a time per design).
_running = {}


@dataclass
class Prepared:
    """Everything a run needs besides the main thread: made by `prepare`."""
    scene_name: str
    design_name: str
    solid_roles: list
    job: job.ConversionJob
    stages: tuple
    notes: list = field(default_factory=list)


@dataclass
class Outcome:
    """How a run ended, as an operator return value and a report."""
    status: str   # 'FINISHED' or 'CANCELLED'
    level: str    # 'INFO', 'WARNING' or 'ERROR'
    message: str


def running_job(design_name):
    return _running.get(design_name)


def designs(scene):
    return [o.name for o in props.objects_with_role(scene, "DESIGN")]


def target_design(context, requested=""):
    """Name of the design a convert would use; raises checks.InputError."""
    active = context.active_object.name if context.active_object else None
    return checks.choose_design(designs(context.scene), requested or None, active)


def prepare(context, settings_owner, requested_design=""):
    """Validate and gather the input; raises checks.InputError or options.OptionError."""
    module = native.load()
    if module is None:
        raise checks.InputError(" ".join(native.status()[1]))
    scene = context.scene
    design_name = target_design(context, requested_design)
    if design_name in _running:
        raise checks.InputError(f"'{design_name}' is already being converted: wait for it to "
                                f"finish or press Esc to cancel it")
    design_obj = scene.objects[design_name]
    settings = options.settings_from_values(props.setting_values(settings_owner))
    native_options, notes = options.native_options(
        settings, design_name, bridge.design_grid(design_obj), native.stages(module),
        native.option_keys(module))

    # The meshes are checked natively, so that the panel, the batch script and the command
    # line name a broken input in the same words.
    design, solids = bridge.gather_input(scene, context.evaluated_depsgraph_get(), design_obj)

    stages = options.stages_run(native.stages(module), native_options)
    run = job.ConversionJob(module, design, checks.native_solids(solids), native_options)
    return Prepared(scene.name, design_name, [checks.NATIVE_ROLE[s["role"]] for s in solids],
                    run, stages, notes)


def finish(prepared):
    """Write the results of a finished job (main thread only); the run's Outcome."""
    name, run = prepared.design_name, prepared.job
    if run.state == job.CANCELLED:
        return Outcome("CANCELLED", "INFO", f"Cancelled converting '{name}': scene unchanged")
    if run.state == job.FAILED:
        if run.details:
            print(run.details)
        return Outcome("CANCELLED", "ERROR", checks.failure_line(run.error, run.error_stage))
    scene = bpy.data.scenes.get(prepared.scene_name)
    if scene is None:
        return Outcome("CANCELLED", "ERROR", f"Scene '{prepared.scene_name}' was deleted "
                                              f"while converting '{name}': nothing written")
    result = run.result
    run_report = result.get("report") or {}
    try:
        bridge.write_results(scene, name, prepared.solid_roles, result,
                             report.to_json(run_report, prepared.notes))
    except (KeyError, TypeError, ValueError, RuntimeError) as exc:
        traceback.print_exc()
        return Outcome("CANCELLED", "ERROR", f"Writing the results of '{name}' failed "
                                              f"({type(exc).__name__}: {exc}): see the console")
    if not bpy.app.background:  # no one looks at the views of a background Blender
        bridge.show_material_colours(w.screen for w in bpy.context.window_manager.windows)
    for line in report.report_lines(run_report, prepared.notes):
        print("genbrep:", line)
    summary = report.result_summary(name, result)
    return Outcome("FINISHED", "WARNING" if report.warning_count(run_report) else "INFO", summary)


def convert_now(context, settings_owner, requested_design="", on_progress=None):
    """Whole conversion in the calling thread, printing progress; returns an Outcome.

    on_progress(job, stage, fraction) runs after each progress print (tests use it to cancel).
    """
    try:
        prepared = prepare(context, settings_owner, requested_design)
    except (checks.InputError, options.OptionError) as exc:
        return Outcome("CANCELLED", "ERROR", str(exc))
    printer = report.ProgressPrinter(prepared.stages, lambda line: print(line, flush=True))

    def progress(stage, fraction):
        printer(stage, fraction)
        if on_progress is not None:
            on_progress(prepared.job, stage, fraction)
    prepared.job.on_progress = progress
    prepared.job.run()
    return finish(prepared)


class GENBREP_OT_set_role(bpy.types.Operator):
    """Set the genbrep role of all selected objects"""
    bl_idname = "genbrep.set_role"
    bl_label = "Set Role"
    bl_options = {"REGISTER", "UNDO"}

    role: bpy.props.EnumProperty(name="Role", items=props.ROLE_ITEMS)

    @classmethod
    def poll(cls, context):
        if not context.selected_objects:
            cls.poll_message_set("Select the objects to give a role")
            return False
        return True

    def execute(self, context):
        chosen = [o for o in context.selected_objects if o.type in props.CONVERTIBLE_TYPES]
        skipped = [o.name for o in context.selected_objects if o not in chosen]
        for obj in chosen:
            obj.genbrep.role = self.role
        label = checks.ROLE_LABELS[self.role]
        message = f"Role {label} set on {len(chosen)} object{'s' if len(chosen) != 1 else ''}"
        if skipped:
            self.report({"WARNING"}, message + f"; skipped {', '.join(skipped)}: no surface")
        else:
            self.report({"INFO"}, message)
        return {"FINISHED"} if chosen else {"CANCELLED"}


class GENBREP_OT_convert(props.SettingsMixin, bpy.types.Operator):
    """Convert the design into cages, exact solid surfaces and a watertight mesh"""
    bl_idname = "genbrep.convert"
    bl_label = "Convert"
    bl_options = {"REGISTER", "UNDO"}

    design: bpy.props.StringProperty(
        name="Design", options={"SKIP_SAVE"},
        description="Design object to convert; empty = the active or only design")

    _timer = None
    _prepared = None

    @classmethod
    def poll(cls, context):
        if native.load() is None:
            cls.poll_message_set("genbrep_native is missing: see the genbrep panel")
            return False
        return True

    def _settings_from_scene(self, context):
        """Settings not set on the operator itself come from the panel (scene)."""
        scene_settings = context.scene.genbrep_settings
        for name in props.SETTING_NAMES:
            if not self.properties.is_property_set(name):
                setattr(self, name, getattr(scene_settings, name))

    def _report(self, outcome):
        self.report({outcome.level}, outcome.message)
        return {outcome.status}

    def execute(self, context):
        self._settings_from_scene(context)
        return self._report(convert_now(context, self, self.design))

    def invoke(self, context, event):
        if bpy.app.background:
            return self.execute(context)
        self._settings_from_scene(context)
        try:
            self._prepared = prepare(context, self, self.design)
        except (checks.InputError, options.OptionError) as exc:
            self.report({"ERROR"}, str(exc))
            return {"CANCELLED"}
        _running[self._prepared.design_name] = self._prepared.job
        self._prepared.job.start()
        wm = context.window_manager
        self._timer = wm.event_timer_add(0.1, window=context.window)
        wm.modal_handler_add(self)
        context.workspace.status_text_set(f"genbrep: converting '{self._prepared.design_name}'"
                                          f" (Esc to cancel)")
        return {"RUNNING_MODAL"}

    def modal(self, context, event):
        run = self._prepared.job
        if event.type == "ESC" and event.value == "PRESS":
            run.cancel()  # the worker stops at its next progress check; its result is dropped
            self._end(context)
            return self._report(Outcome("CANCELLED", "INFO", f"Cancelled converting "
                                        f"'{self._prepared.design_name}': scene unchanged"))
        if event.type != "TIMER":
            return {"PASS_THROUGH"}
        snapshot = run.snapshot()
        if snapshot.state == job.RUNNING:
            context.workspace.status_text_set(
                report.progress_text(snapshot.stage, snapshot.fraction, self._prepared.stages)
                + "  (Esc to cancel)")
            _redraw_panels(context)
            return {"RUNNING_MODAL"}
        self._end(context)
        return self._report(finish(self._prepared))

    def cancel(self, context):
        """Blender ends the modal run itself (a file is loaded, the window closes)."""
        self._prepared.job.cancel()
        self._end(context)

    def _end(self, context):
        if self._timer is not None:
            context.window_manager.event_timer_remove(self._timer)
            self._timer = None
        if context.workspace is not None:
            context.workspace.status_text_set(None)
        _running.pop(self._prepared.design_name, None)
        _redraw_panels(context)


def _redraw_panels(context):
    for area in context.screen.areas if context.screen else ():
        if area.type == "VIEW_3D":
            area.tag_redraw()


class GENBREP_OT_clear_results(bpy.types.Operator):
    """Delete the result collection of the design and show the inputs again"""
    bl_idname = "genbrep.clear_results"
    bl_label = "Clear Results"
    bl_options = {"REGISTER", "UNDO"}

    design: bpy.props.StringProperty(name="Design", options={"SKIP_SAVE"})

    def execute(self, context):
        try:
            name = target_design(context, self.design)
        except checks.InputError as exc:
            self.report({"ERROR"}, str(exc))
            return {"CANCELLED"}
        if not bridge.remove_results(name):
            self.report({"INFO"}, f"'{name}' has no results to clear")
            return {"CANCELLED"}
        context.scene.genbrep_settings.show_inputs = True
        self.report({"INFO"}, f"Deleted collection '{results.collection_name(name)}'")
        return {"FINISHED"}


class GENBREP_OT_use_design_grid(bpy.types.Operator):
    """Use the voxel grid recorded on the design for grid incidence"""
    bl_idname = "genbrep.use_design_grid"
    bl_label = "Use Design Grid"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        try:
            name = target_design(context)
        except checks.InputError as exc:
            self.report({"ERROR"}, str(exc))
            return {"CANCELLED"}
        grid = bridge.design_grid(context.scene.objects[name])
        if grid is None:
            self.report({"ERROR"}, f"'{name}' records no voxel grid (custom properties "
                                   f"{options.GRID_H_PROPERTY}, {options.GRID_ORIGIN_PROPERTY})")
            return {"CANCELLED"}
        settings = context.scene.genbrep_settings
        settings.incidence = "GRID"
        settings.grid_origin, settings.grid_h = grid
        self.report({"INFO"}, f"Grid incidence with h = {grid[1]:g} from '{name}'")
        return {"FINISHED"}


def recompose_now(context, requested_design=""):
    """Pull and compose again from the cages the user edited; returns an Outcome."""
    module = native.load()
    if module is None or not hasattr(module, "recompose"):
        return Outcome("CANCELLED", "ERROR", "Recompose needs a genbrep_native build with "
                                             "recompose(): " + " ".join(native.status()[1]))
    scene = context.scene
    try:
        design_name = target_design(context, requested_design)
        collection = bridge.result_collection_existing(design_name)
        if collection is None:
            raise checks.InputError(f"'{design_name}' has no results to recompose: convert it first")
        cage_objects = bridge.cage_objects(collection)
        if not cage_objects:
            raise checks.InputError(f"'{design_name}' has no cages to recompose from: its "
                                    f"conversion made none (see the report)")
        cages = [bridge.read_cage(obj) for obj in cage_objects]
        _, solids = bridge.gather_input(scene, context.evaluated_depsgraph_get(),
                                        scene.objects[design_name])
    except checks.InputError as exc:
        return Outcome("CANCELLED", "ERROR", str(exc))
    printer = report.ProgressPrinter(("mesh", "compose"), lambda line: print(line, flush=True))
    try:
        result = module.recompose(checks.native_solids(solids), cages, {}, printer)
    except module.ConversionError as exc:
        return Outcome("CANCELLED", "ERROR", f"Recomposing '{design_name}' failed: {exc}")
    run_report = result.get("report") or {}
    solid_roles = [checks.NATIVE_ROLE[s["role"]] for s in solids]
    composed = bridge.write_recomposed(scene, design_name, solid_roles, cage_objects, result,
                                       report.to_json(run_report, []))
    if composed is None:
        return Outcome("FINISHED", "WARNING", f"Recomposed '{design_name}' from "
                       f"{len(cages)} cages, but no watertight solid: see the report")
    return Outcome("FINISHED", "INFO", f"Recomposed '{design_name}' from {len(cages)} cages: "
                   f"{len(composed.data.polygons)} triangles, closed")


class GENBREP_OT_recompose(bpy.types.Operator):
    """Pull and compose again from the cages as edited: the composed solid follows the cages"""
    bl_idname = "genbrep.recompose"
    bl_label = "Recompose"
    bl_options = {"REGISTER", "UNDO"}

    design: bpy.props.StringProperty(name="Design", default="",
                                     description="Design to recompose; empty = the active one")

    def execute(self, context):
        outcome = recompose_now(context, self.design)
        self.report({outcome.level}, outcome.message)
        return {outcome.status}


CLASSES = (GENBREP_OT_set_role, GENBREP_OT_convert, GENBREP_OT_clear_results,
           GENBREP_OT_use_design_grid, GENBREP_OT_recompose)


def register():
    for cls in CLASSES:
        bpy.utils.register_class(cls)


def unregister():
    for job_ in _running.values():
        job_.cancel()
    _running.clear()
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)

"""Text for progress, results and reports. No bpy here.

The native report is a dict (DESIGN.md "Reports"): seconds per stage under 'stages',
'counts', 'tolerance', 'diagnostics' (warnings: where the result falls short of what was
asked), 'notes' (how the stages did their work), maybe more. Formatting tolerates
missing keys and stages it does not know, so it keeps working as the pipeline grows.
"""

import json

from . import results


def overall_fraction(stage, fraction, stages):
    """Progress of the whole run in [0, 1] from the current stage and its fraction."""
    if stage not in stages:
        return 0.0
    fraction = min(max(float(fraction), 0.0), 1.0)
    return (stages.index(stage) + fraction) / len(stages)


def progress_text(stage, fraction, stages):
    """'genbrep: partition 40% (stage 3 of 3)' for the status bar and the console."""
    if not stage:
        return "genbrep: starting"
    if stage not in stages:
        return f"genbrep: {stage} {fraction:.0%}"
    return (f"genbrep: {stage} {min(max(fraction, 0.0), 1.0):.0%} "
            f"(stage {stages.index(stage) + 1} of {len(stages)})")


class ProgressPrinter:
    """Prints progress lines without flooding: on a new stage and every `step` of a stage."""

    def __init__(self, stages, write=print, step=0.25):
        self._stages, self._write, self._step = tuple(stages), write, step
        self._stage, self._next = None, 0.0

    def __call__(self, stage, fraction):
        if stage != self._stage:
            self._stage, self._next = stage, 0.0
        if fraction >= self._next:
            self._write(progress_text(stage, fraction, self._stages))
            self._next = (int(fraction / self._step) + 1) * self._step


def format_value(value, max_items=8):
    """Short text of a report value: numbers to 4 digits, lists and dicts inline."""
    if isinstance(value, bool) or value is None:
        return str(value)
    if isinstance(value, float):
        return f"{value:.4g}"
    if isinstance(value, dict):
        return ", ".join(f"{k} {format_value(v, max_items)}" for k, v in value.items())
    if isinstance(value, (list, tuple)):
        shown = ", ".join(format_value(v, max_items) for v in value[:max_items])
        return shown + (f", ... ({len(value)} in all)" if len(value) > max_items else "")
    return str(value)


def stage_seconds(report):
    """[(stage, seconds)] from report['stages'] (a dict, or a list of pairs/dicts)."""
    stages = report.get("stages") or {}
    if isinstance(stages, dict):
        return [(str(k), float(v)) for k, v in stages.items()]
    pairs = []
    for item in stages:
        if isinstance(item, dict):
            pairs.append((str(item.get("name", "?")), float(item.get("seconds", 0.0))))
        else:
            pairs.append((str(item[0]), float(item[1])))
    return pairs


def cage_lines(report, max_points=4):
    """Per cage of the report: its quads and how regular they are, where its irregular
    vertices that no field singularity explains are, its fit; and the components that got
    no cage, with why."""
    lines = []
    for index, cage in enumerate(report.get("cages") or ()):
        fallback = str(cage.get("method", "")).startswith("fallback")
        lines.append(
            f"  cage {index} (component {cage.get('component', index)}): "
            f"{cage.get('quads', 0)} quads{' FALLBACK, not field-aligned' if fallback else ''}, "
            f"corners {cage.get('mean_angle_deviation_degrees', 0.0):.1f}° off square on average")
        lines.append(
            f"    valence 4 inside {100 * cage.get('interior_valence4_fraction', 1.0):.1f}%, "
            f"3 on the boundary {100 * cage.get('boundary_valence3_fraction', 1.0):.1f}%; "
            f"{cage.get('irregular_vertices', 0)} irregular, "
            f"{cage.get('irregular_vertices_off_singularities', 0)} away from singularities")
        off = cage.get("irregular_vertices_off_singularities_at") or ()
        if off:
            shown = "; ".join(
                "({:.4g}, {:.4g}, {:.4g}) valence {}, {:+d}".format(
                    *point["position"], point.get("valence", "?"), point["quarter_turns"])
                for point in off[:max_points])
            more = f"; ... ({len(off)} in all)" if len(off) > max_points else ""
            lines.append(f"    away from singularities (valence, quarter turns unexplained): "
                         f"{shown}{more}")
            lines.append(f"    (the cage's vertex group '{results.OFF_SINGULARITIES_GROUP}' "
                         f"selects them in Edit Mode)")
        fit = cage.get("fit")
        if fit:
            lines.append(f"    fit: design to limit surface rms {fit.get('rms_design_to_limit', 0.0):.4g}, "
                         f"max {fit.get('max_design_to_limit', 0.0):.4g}")
    for failure in report.get("cage_failures") or ():
        lines.append(f"  component {failure.get('component')}: no cage ({failure.get('reason')})")
    return ["cages:"] + lines if lines else []


def report_lines(report, notes=()):
    """Report as short lines for the panel and the console, warnings last."""
    report = report or {}
    lines = []
    timings = stage_seconds(report)
    if timings:
        total = report.get("seconds_total", sum(s for _, s in timings))
        lines.append(f"time: {float(total):.2f} s")
        lines.extend(f"  {name}: {seconds:.3f} s" for name, seconds in timings)
    counts = report.get("counts") or {}
    if counts:
        lines.append("counts:")
        lines.extend(f"  {key}: {format_value(value)}" for key, value in counts.items())
    if report.get("tolerance") is not None:
        lines.append(f"tolerance: {format_value(report['tolerance'])}")
    lines.extend(cage_lines(report))
    shown = {"stages", "counts", "tolerance", "diagnostics", "notes", "seconds_total"}
    for key, value in report.items():
        if key not in shown and isinstance(value, (int, float, str, bool)):
            lines.append(f"{key}: {format_value(value)}")
    lines.extend(f"note: {note}" for note in notes)
    lines.extend(f"note: {note}" for note in report.get("notes") or ())
    lines.extend(f"warning: fallback: {f}" for f in fallbacks(report))
    lines.extend(f"warning: {d}" for d in report.get("diagnostics") or ())
    return lines


def fallbacks(report):
    """Components composed below their best tier, one line each with the reason."""
    return list(((report or {}).get("composed") or {}).get("fallbacks") or ())


def warning_count(report):
    """The report's warnings; its notes do not count."""
    return len((report or {}).get("diagnostics") or ())


def result_summary(design_name, result):
    """One line saying what a conversion produced."""
    partition = result.get("partition") or {}
    components = partition.get("face_component")
    n_components = int(max(components)) + 1 if components is not None and len(components) else 0
    parts = [f"{n_components} organic component{'s' if n_components != 1 else ''}"]
    loops = partition.get("loops")
    if loops is not None:
        parts.append(f"{len(loops)} boundary loop{'s' if len(loops) != 1 else ''}")
    cages = result.get("cages") or []
    parts.append(f"{len(cages)} cage{'s' if len(cages) != 1 else ''}")
    composed = ((result.get("report") or {}).get("composed") or {})
    if not result.get("composed"):
        parts.append("not composed")
    elif composed.get("floor"):
        parts.append("composed as the design Boolean (no cage in the solid)")
    else:
        n_fallbacks = len(fallbacks(result.get("report")))
        parts.append("composed" + (f", {n_fallbacks} component{'s' if n_fallbacks != 1 else ''} "
                                   f"from a fallback" if n_fallbacks else ""))
    seconds = sum(s for _, s in stage_seconds(result.get("report") or {}))
    warnings = warning_count(result.get("report"))
    text = f"Converted '{design_name}' in {seconds:.2f} s: " + ", ".join(parts)
    if warnings:
        text += f"; {warnings} warning{'s' if warnings != 1 else ''} (see the genbrep panel)"
    return text


def to_json(report, notes=()):
    """The report as JSON (numpy scalars made plain), for storing in a custom property.

    `notes` (the add-on's own) come first in 'notes', before the stages' notes."""
    def plain(value):
        if isinstance(value, dict):
            return {str(k): plain(v) for k, v in value.items()}
        if isinstance(value, (list, tuple)):
            return [plain(v) for v in value]
        if hasattr(value, "tolist"):
            return value.tolist()
        return value
    data = plain(dict(report or {}))
    if notes:
        data["notes"] = list(notes) + list(data.get("notes") or ())
    return json.dumps(data, sort_keys=True)


def lines_from_json(text):
    """report_lines of a report stored with to_json; [] for empty or unreadable text."""
    try:
        data = json.loads(text) if text else {}
    except ValueError:
        return []
    notes = data.pop("notes", ()) if isinstance(data, dict) else ()
    return report_lines(data, notes) if isinstance(data, dict) else []

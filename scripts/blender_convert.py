"""Batch conversion: convert every design in a .blend with the genbrep add-on, headless.

    blender -b scene.blend --python-exit-code 1 -P scripts/blender_convert.py -- \
        [--out result.blend] [--design NAME ...] [--report report.json] [options]

Runs the add-on's Convert operator (synchronously, printing progress) on each object with
the role Design, or on the ones named with --design. Settings not given here come from
the scene's genbrep panel settings. Writes --out only when every design converted.

Exit status, as the command line's: 0 all converted as asked; 3 all gave a solid but some
component fell back below its best tier (one "genbrep: fallback:" line each on standard
error); 1 a design failed or gave no solid (the message names the object and the problem;
--out is not written); 2 bad arguments or genbrep_native missing.

Which add-on: the one in this checkout (../addon) when present, else an installed one.
"""

import argparse
import json
import os
import sys

import bpy

STAGES = ("mesh", "incidence", "partition", "relax", "field", "param", "quad", "fit", "pull",
          "compose")


def parse_args(argv):
    parser = argparse.ArgumentParser(
        prog="blender -b scene.blend --python-exit-code 1 -P scripts/blender_convert.py --",
        description="Convert every genbrep design of the open .blend.")
    parser.add_argument("--out", help="write the converted scene to this .blend")
    parser.add_argument("--design", action="append", default=[],
                        help="convert only this design object (repeatable)")
    parser.add_argument("--report", help="write the reports of all designs as JSON here")
    parser.add_argument("--tolerance", type=float,
                        help="incidence distance d in scene units; 0 = automatic")
    parser.add_argument("--incidence", choices=("auto", "distance", "grid"))
    parser.add_argument("--grid-h", type=float, help="voxel size h for grid incidence")
    parser.add_argument("--grid-origin", type=float, nargs=3, metavar=("X", "Y", "Z"))
    parser.add_argument("--edge-length", type=float,
                        help="cage density as a target edge length (0 = automatic)")
    parser.add_argument("--size-scale", type=float,
                        help="cage density as a scale on the curvature size field")
    parser.add_argument("--fitting", choices=("smooth", "tight", "boundary_tight"))
    parser.add_argument("--until", choices=STAGES, help="stop after this stage")
    args = parser.parse_args(argv)
    if args.edge_length is not None and args.size_scale is not None:
        parser.error("give --edge-length or --size-scale, not both")
    return args


def operator_settings(args):
    """Keyword arguments for bpy.ops.genbrep.convert from the given options only."""
    settings = {}
    if args.tolerance is not None:
        settings.update(tolerance_auto=args.tolerance == 0.0, tolerance=args.tolerance)
    if args.incidence:
        settings["incidence"] = args.incidence.upper()
    if args.grid_h is not None:
        settings["grid_h"] = args.grid_h
    if args.grid_origin is not None:
        settings["grid_origin"] = args.grid_origin
    if args.edge_length is not None:
        settings.update(density="EDGE_LENGTH", target_edge_length=args.edge_length)
    if args.size_scale is not None:
        settings.update(density="SIZE_SCALE", size_scale=args.size_scale)
    if args.fitting:
        settings["fitting"] = args.fitting.upper()
    if args.until:
        settings["until"] = args.until.upper()
    return settings


def load_addon():
    """The genbrep package, registered: this checkout's add-on first, else an installed one."""
    checkout = os.path.join(os.path.dirname(os.path.abspath(__file__)), os.pardir, "addon")
    if "genbrep" not in sys.modules and os.path.isdir(os.path.join(checkout, "genbrep")):
        sys.path.insert(0, os.path.normpath(checkout))
    if not hasattr(bpy.types.Object, "genbrep"):
        try:
            import genbrep
        except ImportError:
            import addon_utils
            if addon_utils.enable("genbrep", default_set=False) is None:
                raise SystemExit("blender_convert.py: the genbrep add-on is neither in this "
                                 "checkout nor installed") from None
        else:
            genbrep.register()
    return sys.modules["genbrep"]


def main():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    try:
        args = parse_args(argv)
    except SystemExit as exc:
        sys.exit(2 if exc.code else 0)
    load_addon()
    from genbrep import native, props, results

    ok, lines = native.status()
    if not ok:
        print("blender_convert.py: " + " ".join(lines), file=sys.stderr)
        print(f"  import errors: {native.load_error()}", file=sys.stderr)
        sys.exit(2)

    scene = bpy.context.scene
    names = args.design or [o.name for o in props.objects_with_role(scene, "DESIGN")]
    if not names:
        print(f"blender_convert.py: no object in '{bpy.data.filepath}' has the genbrep role "
              f"Design: set one in the genbrep panel", file=sys.stderr)
        sys.exit(1)

    settings = operator_settings(args)
    failed, reports = [], {}
    for name in names:
        print(f"genbrep: converting '{name}'", flush=True)
        try:
            bpy.ops.genbrep.convert(design=name, **settings)
        except RuntimeError as exc:  # the operator reported an error
            # The operator's line is the command line's without "genbrep: "; print it whole.
            message = str(exc).removeprefix("Error: ").strip()
            print(f"genbrep: {message}", file=sys.stderr, flush=True)
            failed.append(name)
            continue
        collection = bpy.data.collections[results.collection_name(name)]
        reports[name] = json.loads(collection.get(results.REPORT_PROPERTY, "{}"))

    if args.report:
        os.makedirs(os.path.dirname(os.path.abspath(args.report)), exist_ok=True)
        with open(bpy.path.abspath(args.report), "w") as out:
            json.dump(reports, out, indent=2, sort_keys=True)
    # The command line's exit status: 1 when a design gave no solid, 3 when a solid was
    # made but some component fell back below its best tier (each listed), else 0.
    for name, run_report in reports.items():
        composed = run_report.get("composed")
        if composed is not None and not composed.get("ok"):
            print(f"genbrep: '{name}' was converted but not composed: see its report",
                  file=sys.stderr, flush=True)
            failed.append(name)
        for line in (composed or {}).get("fallbacks") or ():
            print(f"genbrep: fallback: '{name}' {line}", file=sys.stderr, flush=True)
    fell_back = any((r.get("composed") or {}).get("fallbacks") for r in reports.values())
    if failed:
        print(f"genbrep: {len(failed)} of {len(names)} designs failed ({', '.join(failed)}); "
              f"{'nothing written' if args.out else 'no output requested'}", file=sys.stderr)
        sys.exit(1)
    if args.out:
        path = os.path.abspath(bpy.path.abspath(args.out))
        os.makedirs(os.path.dirname(path), exist_ok=True)
        bpy.ops.wm.save_as_mainfile(filepath=path, check_existing=False, compress=True)
        print(f"genbrep: wrote {path}")
    if fell_back:
        sys.exit(3)


if __name__ == "__main__":
    main()

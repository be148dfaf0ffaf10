"""Finding and loading the compiled module `genbrep_native`. No bpy here.

Where the module is looked for, in order:

1. inside this package (the installed add-on zip puts the .so next to this file);
2. on sys.path, after adding the folders in the environment variable GENBREP_NATIVE_PATH
   (os.pathsep-separated) and, in a source checkout, <repo>/build/python.

When nothing loads, the add-on still registers: `status()` then explains what is missing
and which Python version and platform a matching build must target.
"""

import glob
import importlib
import os
import platform
import sys
import sysconfig

MODULE_NAME = "genbrep_native"

_module = None
_load_error = None
_loaded = False


def _candidate_paths():
    paths = [p for p in os.environ.get("GENBREP_NATIVE_PATH", "").split(os.pathsep) if p]
    checkout_build = os.path.normpath(
        os.path.join(os.path.dirname(__file__), os.pardir, os.pardir, "build", "python"))
    if os.path.isdir(checkout_build):
        paths.append(checkout_build)
    return paths


def load():
    """The native module, or None when it cannot be imported (see `status()`)."""
    global _module, _load_error, _loaded
    if _loaded:
        return _module
    _loaded = True
    errors = []
    try:
        _module = importlib.import_module("." + MODULE_NAME, __package__)
        return _module
    except ImportError as exc:
        errors.append(f"in the add-on folder: {exc}")
    for path in _candidate_paths():
        if path not in sys.path:
            sys.path.append(path)
    try:
        _module = importlib.import_module(MODULE_NAME)
    except ImportError as exc:
        errors.append(f"on sys.path: {exc}")
        _load_error = "; ".join(errors)
    return _module


def required_suffix():
    """File-name suffix a module needs to load here, e.g. '.cpython-311-x86_64-linux-gnu.so'."""
    return sysconfig.get_config_var("EXT_SUFFIX") or ".so"


def present_builds():
    """File names of genbrep_native builds shipped in the add-on folder (any Python version)."""
    here = os.path.dirname(__file__)
    found = glob.glob(os.path.join(here, MODULE_NAME + "*.so")) + glob.glob(
        os.path.join(here, MODULE_NAME + "*.pyd"))
    return sorted(os.path.basename(p) for p in found)


def status():
    """(ok, lines): whether the module loaded, and short lines for the panel."""
    module = load()
    if module is not None:
        where = os.path.dirname(getattr(module, "__file__", "") or "")
        return True, [f"{MODULE_NAME} loaded", where]
    python = f"Python {sys.version_info.major}.{sys.version_info.minor}"
    lines = [
        f"{MODULE_NAME} is missing: conversion is disabled.",
        f"Blender runs {python} on {sys.platform} {platform.machine()}:",
        f"install the add-on zip built for it ({MODULE_NAME}{required_suffix()}).",
    ]
    builds = present_builds()
    if builds:
        lines.append("Found only: " + ", ".join(builds))
    return False, lines


def load_error():
    """The import errors collected by `load()`, or None."""
    load()
    return _load_error


def stages(module=None):
    """Stage names the loaded module runs, in order (empty without a module)."""
    module = module if module is not None else load()
    return tuple(getattr(module, "STAGES", ())) if module is not None else ()


def option_keys(module=None):
    """Option keys the module declares via OPTION_KEYS, or None when it declares none."""
    module = module if module is not None else load()
    keys = getattr(module, "OPTION_KEYS", None) if module is not None else None
    return frozenset(keys) if keys is not None else None

"""The bad-input corpus (tests/bad_inputs/cases.py) through the command line and the module.

Every case must give its one line and exit status from `genbrep convert`, and the same
message as a ConversionError (with its code and stage) from genbrep_native: read_mesh for
broken files, convert for broken geometry. tests/blender/test_bad_inputs.py runs the same
cases through Blender.
"""
import os
import subprocess
import sys
import tempfile

import pytest

from conftest import BUILD, ROOT

sys.path.insert(0, str(ROOT / "tests" / "bad_inputs"))
import cases as corpus  # noqa: E402

CLI = str(BUILD / "bin" / "genbrep")
NOBODY = 65534


def _drop_root():
    """Runs a child as nobody: root reads every file, so 'unreadable' needs another user."""
    if os.geteuid() == 0:
        os.setgid(NOBODY)
        os.setuid(NOBODY)


@pytest.fixture
def folder():
    # Not pytest's tmp_path: its parents are closed to the user 'unreadable' runs as.
    with tempfile.TemporaryDirectory(prefix="genbrep_bad_") as path:
        os.chmod(path, 0o755)
        yield path


def _cases(*kinds):
    return [pytest.param(c, id=c.name) for c in corpus.cases() if c.kind in kinds]


def test_corpus_has_every_kind_the_issue_lists():
    names = {c.name for c in corpus.cases()}
    assert len(names) == len(corpus.cases()) >= 25


@pytest.mark.parametrize("case", _cases("file", "mesh"))
def test_command_line_prints_the_line(case, folder):
    corpus.prepare(case, folder)
    run = subprocess.run([CLI, *case.cli_args()], cwd=folder, capture_output=True, text=True,
                         timeout=120, preexec_fn=_drop_root if case.name == "unreadable" else None)
    lines = run.stderr.splitlines()
    assert run.returncode == case.exit, run.stderr
    assert case.line() in lines, run.stderr
    if case.exit != 0:
        assert lines == [case.line()], "one line, and only one"


@pytest.mark.parametrize("case", _cases("file"))
def test_read_mesh_raises_the_message(case, folder, native):
    corpus.prepare(case, folder)
    path = os.path.join(folder, case.design)
    if case.name == "unreadable" and os.geteuid() == 0:
        code = ("import sys, genbrep_native as g\ntry:\n g.read_mesh(sys.argv[1])\n"
                "except g.ConversionError as e:\n print(e.code, e.stage, e, sep='|')\n")
        run = subprocess.run([sys.executable, "-c", code, path], capture_output=True, text=True,
                             env=dict(os.environ, PYTHONPATH=str(BUILD / "python")),
                             preexec_fn=_drop_root, timeout=60)
        expected = case.message.replace("'design.obj'", f"'{path}'")
        assert run.stdout.strip() == f"{case.code}|{case.stage}|{expected}", run.stderr
        return
    with pytest.raises(native.ConversionError) as error:
        native.read_mesh(path)
    assert str(error.value) == case.message.replace(f"'{case.design}'", f"'{path}'")
    assert (error.value.code, error.value.stage) == (case.code, case.stage)


@pytest.mark.parametrize("case", _cases("mesh", "arrays"))
def test_convert_raises_the_message(case, folder, native):
    corpus.prepare(case, folder)
    design, solids = corpus.inputs(case, folder, native.read_mesh)
    options = {"tolerance": corpus.TOLERANCE, "until": "incidence"}
    if case.exit == 0:
        report = native.convert(design, solids, options)["report"]
        assert case.message in report["diagnostics"]
        return
    with pytest.raises(native.ConversionError) as error:
        native.convert(design, solids, options)
    assert str(error.value) == case.message
    assert (error.value.code, error.value.stage) == (case.code, case.stage)


FOUND = ROOT / "tests" / "bad_inputs" / "found"


@pytest.mark.parametrize("case_json", [pytest.param(p, id=p.parent.name)
                                       for p in sorted(FOUND.glob("*/case.json"))])
def test_inputs_the_fuzzer_found_get_an_answer(case_json, folder):
    """Each input bench/fuzz kept (it crashed, hung or tripped a sanitizer once) now gets a
    result or one error line, in the normal build; bench/fuzz checks the sanitizer build."""
    import json
    import shutil
    shutil.copytree(case_json.parent, folder, dirs_exist_ok=True)
    args = json.loads(case_json.read_text())["args"]
    run = subprocess.run([CLI, *args], cwd=folder, capture_output=True, text=True, timeout=300)
    errors = [line for line in run.stderr.splitlines() if not line.startswith("genbrep: warning: ")]
    assert run.returncode in (0, 1, 2), run.stderr
    if run.returncode == 1:
        assert len(errors) == 1 and errors[0].startswith("genbrep: error"), run.stderr


def _torus(n, m, major=3.0, minor=1.0):
    """A closed torus of 2·n·m triangles, as arrays."""
    import numpy as np
    u = np.linspace(0, 2 * np.pi, n, endpoint=False)[:, None]
    w = np.linspace(0, 2 * np.pi, m, endpoint=False)[None, :]
    ring = major + minor * np.cos(w)
    vertices = np.stack(np.broadcast_arrays(ring * np.cos(u), ring * np.sin(u),
                                            minor * np.sin(w)), -1).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(n), np.arange(m), indexing="ij")
    a, b = i * m + j, (i + 1) % n * m + j
    c, d = (i + 1) % n * m + (j + 1) % m, i * m + (j + 1) % m
    faces = np.concatenate([np.stack([a, b, c], -1).reshape(-1, 3),
                            np.stack([a, c, d], -1).reshape(-1, 3)]).astype(np.int32)
    return vertices, faces


def test_five_million_triangles_show_progress_cancel_and_stay_bounded(native):
    """A 5M-triangle design: the mesh stage reports progress while it checks the design,
    cancelling at a progress call stops the run there, and the peak memory stays below
    a bound proportional to the design (the arrays here take 120 MB)."""
    import resource
    vertices, faces = _torus(2000, 1250)
    assert len(faces) == 5_000_000
    pad_v, pad_f = corpus.box((2.8, -0.2, -0.2), (3.2, 0.2, 0.2))  # buried in the tube
    design = {"name": "big", "vertices": vertices, "faces": faces}
    solids = [{"name": "core", "role": "keep_in", "vertices": pad_v, "faces": pad_f}]
    seen = []

    def progress(stage, fraction):
        seen.append((stage, fraction))
        return stage != "incidence"        # cancel at the first word from incidence

    with pytest.raises(native.CancelledError):
        native.convert(design, solids, {"tolerance": 0.01}, progress)
    mesh_steps = [f for stage, f in seen if stage == "mesh"]
    assert mesh_steps[:4] == [0.0, 0.1, 0.2, 0.45], seen
    assert seen[-1] == ("incidence", 0.0) and [s for s, _ in seen].count("incidence") == 1
    peak_bytes = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
    assert peak_bytes < 600 * len(faces), f"peak {peak_bytes / 2**30:.1f} GiB"

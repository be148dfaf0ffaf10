"""corpus_judge on boxes whose verdict is known in advance, and bench/corpus --summary on a
hand-written corpus.jsonl."""
import json
import subprocess

import pytest

from conftest import BUILD, ROOT

JUDGE = BUILD / "bin" / "corpus_judge"
CORPUS = ROOT / "bench" / "corpus"

# A box's 12 triangles, counter-clockwise seen from outside, on corners indexed by bits
# (x, y, z) = (i & 1, i >> 1 & 1, i >> 2 & 1).
BOX_TRIANGLES = [(0, 2, 3), (0, 3, 1), (4, 5, 7), (4, 7, 6), (0, 1, 5), (0, 5, 4),
                 (2, 6, 7), (2, 7, 3), (0, 4, 6), (0, 6, 2), (1, 3, 7), (1, 7, 5)]


def box(lo, hi):
    """(corners, triangles) of the axis-aligned box lo..hi, facing outward."""
    corners = [tuple(hi[a] if i >> a & 1 else lo[a] for a in range(3)) for i in range(8)]
    return corners, list(BOX_TRIANGLES)


def write_obj(path, *meshes, flip=False, drop=0):
    """Writes meshes into one OBJ; `flip` reverses every triangle, `drop` leaves out the
    last `drop` triangles of the last mesh."""
    lines, offset = [], 0
    for m, (corners, triangles) in enumerate(meshes):
        lines += [f"v {x} {y} {z}" for x, y, z in corners]
        if drop and m == len(meshes) - 1:
            triangles = triangles[:-drop]
        for t in triangles:
            t = t[::-1] if flip else t
            lines.append("f " + " ".join(str(offset + i + 1) for i in t))
        offset += len(corners)
    path.write_text("\n".join(lines) + "\n")


def make_case(folder, design, keep_ins=(), keep_outs=(), names=None, tolerance=0.1):
    folder.mkdir(parents=True, exist_ok=True)
    write_obj(folder / "design.obj", design)
    meta = {"keep_in": [], "keep_out": [], "seed": [], "tolerance": tolerance, "voxel": tolerance,
            "names": names or {}, "generator": {"ignored": True}}
    for role, solids in (("keep_in", keep_ins), ("keep_out", keep_outs)):
        for i, solid in enumerate(solids):
            write_obj(folder / f"{role}_{i}.obj", solid)
            meta[role].append(f"{role}_{i}.obj")
    (folder / "meta.json").write_text(json.dumps(meta))
    return folder


def judge(case, result=None, samples=2000):
    command = [str(JUDGE), "--case", str(case), "--samples", str(samples)]
    if result is not None:
        command += ["--result", str(result)]
    done = subprocess.run(command, capture_output=True, text=True, check=True)
    return json.loads(done.stdout)


CUBE = box((0, 0, 0), (10, 10, 10))
INNER = box((2, 2, 2), (4, 4, 4))
BESIDE = box((10, 0, 0), (12, 10, 10))  # shares the cube's face x = 10: touching is allowed
ACROSS = box((8, 4, 4), (12, 6, 6))     # reaches 2 beyond the face x = 10


@pytest.fixture
def cube_case(tmp_path):
    return make_case(tmp_path / "case", CUBE, keep_ins=[INNER], keep_outs=[BESIDE])


def composed(tmp_path, *meshes, **options):
    out = tmp_path / "out"
    out.mkdir(exist_ok=True)
    write_obj(out / "composed.obj", *meshes, **options)
    return out


def test_closed_box_holding_the_keep_in_is_watertight(tmp_path, cube_case):
    verdict = judge(cube_case, composed(tmp_path, CUBE))
    assert verdict["errors"] == []
    assert verdict["consistency"]["verdict"] == "consistent"
    assert verdict["inputs"]["design"]["volume"] == pytest.approx(1000)
    result = verdict["result"]
    assert result["closed"] and result["manifold"]
    assert result["self_intersections"]["pairs"] == 0
    assert result["orientation"]["outward"] is True
    assert result["volume_vs_design"] == pytest.approx(1)
    assert result["keep_ins"][0]["points"] > 1000 and result["keep_ins"][0]["outside"] == 0
    assert result["keep_outs"][0]["material_points"] == 0 and result["keep_outs"][0]["vertices_inside"] == 0
    assert result["keep_ins_inside"] is True and result["keep_outs_empty"] is True
    assert result["watertight"] is True


def test_box_missing_a_triangle_is_open_and_not_classified(tmp_path, cube_case):
    result = judge(cube_case, composed(tmp_path, CUBE, drop=1))["result"]
    assert result["closed"] is False and result["boundary_edges"] == 3
    assert result["keep_ins_inside"] == "not checked"
    assert result["watertight"] is False


def test_two_overlapping_boxes_in_one_mesh_self_intersect(tmp_path, cube_case):
    result = judge(cube_case, composed(tmp_path, CUBE, box((5, 5, 5), (15, 15, 15))))["result"]
    assert result["closed"] and result["manifold"] and result["shells"] == 2
    assert result["self_intersections"]["pairs"] > 0
    assert result["watertight"] is False


def test_inside_out_box_is_not_outward(tmp_path, cube_case):
    result = judge(cube_case, composed(tmp_path, CUBE, flip=True))["result"]
    assert result["volume"] == pytest.approx(-1000)
    assert result["orientation"]["outward"] is False
    assert result["watertight"] is False


def test_boxes_sharing_a_corner_are_non_manifold_without_a_crash(tmp_path, cube_case):
    out = tmp_path / "out"
    out.mkdir()
    a, b = box((0, 0, 0), (1, 1, 1)), box((1, 1, 1), (2, 2, 2))
    corners = a[0] + [c for c in b[0] if c != (1, 1, 1)]
    shift = {i: (7 if i == 0 else 8 + i - 1) for i in range(8)}  # b's corner 0 is a's corner 7
    triangles = a[1] + [tuple(shift[i] for i in t) for t in b[1]]
    write_obj(out / "composed.obj", (corners, triangles))
    verdict = judge(cube_case, out)
    assert verdict["errors"] == []
    result = verdict["result"]
    assert result["closed"] is True and result["non_manifold_vertices"] == 1
    assert result["keep_outs_empty"] == "not checked" and result["watertight"] is False


def test_keep_out_crossing_the_composed_box_is_violated(tmp_path):
    case = make_case(tmp_path / "case", CUBE, keep_outs=[ACROSS], names={"keep_out_0.obj": "bore"})
    verdict = judge(case, composed(tmp_path, CUBE))
    keep_out = verdict["result"]["keep_outs"][0]
    assert keep_out["material_points"] > 0
    assert 0.5 < keep_out["max_depth"] <= 1 + 1e-9  # the overlap is 2 x 2 x 2 inside a 4 x 2 x 2 box
    assert verdict["result"]["keep_outs_empty"] is False and verdict["result"]["watertight"] is False
    reasons = verdict["consistency"]["reasons"]
    assert verdict["consistency"]["verdict"] == "inconsistent"
    assert reasons[0]["kind"] == "material inside a keep-out" and reasons[0]["name"] == "bore"


def test_keep_in_outside_the_design_is_inconsistent_and_named(tmp_path):
    case = make_case(tmp_path / "case", CUBE, keep_ins=[ACROSS], names={"keep_in_0.obj": "boss"})
    verdict = judge(case)
    assert "result" not in verdict
    consistency = verdict["consistency"]
    assert consistency["verdict"] == "inconsistent"
    reason = consistency["reasons"][0]
    assert (reason["kind"], reason["solid"], reason["name"]) == ("keep-in outside the design", "keep_in_0.obj", "boss")
    assert 1.5 < reason["max_distance"] <= 2 + 1e-9
    assert reason["at"][0] > 10


def test_missing_and_unreadable_results_are_reported(tmp_path, cube_case):
    out = tmp_path / "out"
    out.mkdir()
    assert judge(cube_case, out)["result"] == {"folder": str(out), "present": False, "watertight": False}
    (out / "composed.obj").write_text("v 0 0 0\nf 1 2 3\n")
    verdict = judge(cube_case, out)
    assert verdict["result"]["watertight"] is False
    assert any(e.startswith("result:") for e in verdict["errors"])


def test_verdict_repeats_exactly(tmp_path, cube_case):
    out = composed(tmp_path, CUBE)
    first, second = judge(cube_case, out), judge(cube_case, out)
    first.pop("seconds"), second.pop("seconds")
    assert first == second


def test_summary_reprints_a_saved_run(tmp_path):
    def record(case, watertight, verdict, components, **extra):
        return {"case": case, "exit": 0, "composed_ok": watertight, "signal": None, "timed_out": False, "seconds": 10.0, "peak_mb": 100,
                "components": components, "offender_named": extra.pop("named", None),
                "judge": {"consistency": {"verdict": verdict},
                          "result": {"present": True, "closed": True, "manifold": True,
                                     "watertight": watertight, "volume_vs_design": 1.01}},
                **extra}
    caged = {"caged": True, "field_aligned": True, "composed_from": "cage", "quads": 100, "fit_max_h": 0.5}
    fallback = {"caged": True, "field_aligned": False, "composed_from": "design region", "quads": 50}
    records = [
        record("a", True, "consistent", [caged, fallback]),
        record("b", False, "inconsistent", [{"caged": False}], named=True, seconds=30.0),
        {"case": "c", "exit": None, "signal": 11, "timed_out": False, "seconds": 2.0, "components": [],
         "judge": {"consistency": {"verdict": "consistent"}, "result": {"present": False, "watertight": False}}},
    ]
    path = tmp_path / "corpus.jsonl"
    path.write_text("".join(json.dumps(r) + "\n" for r in records))
    done = subprocess.run(["/usr/bin/python3", str(CORPUS), "--summary", str(path)],
                          capture_output=True, text=True, check=True)
    lines = done.stdout.splitlines()
    assert [line.split()[0] for line in lines[1:4]] == ["a", "b", "c"]
    assert "signal 11" in lines[3]
    for expected in ["watertight 1/3", "consistent cases watertight 1/2",
                     "inconsistent cases with a named diagnostic 1/1", "caged components 2/3",
                     "field-aligned 1/3", "components composed from their cage 1/3",
                     "volume within 2% of design 2/3", "seconds median 10.0, worst 30.0",
                     "crashes 1, timeouts 0"]:
        assert expected in lines, expected


FAKE_CLI = '''#!/usr/bin/python3
"""Stands in for genbrep convert: behaves as the case folder's name says."""
import json, os, pathlib, shutil, signal, sys, time
args = sys.argv[1:]
design = pathlib.Path(args[args.index("--design") + 1])
out = pathlib.Path(args[args.index("--out") + 1])
kind = design.parent.name
if kind == "crash":
    os.kill(os.getpid(), signal.SIGSEGV)
if kind == "slow":
    time.sleep(60)
report = {"stages": {"mesh": 0.5, "quad": 1.5}, "counts": {"organic_components": 1},
          "cages": [], "cage_failures": [], "diagnostics": []}
if kind in ("ok", "claims_ok"):
    text = design.read_text()
    if kind == "claims_ok":  # one triangle short: open, though the report says composed
        text = text[:text.rstrip().rindex("\\n")] + "\\n"
    (out / "composed.obj").write_text(text)
    (out / "cage_000.obj").write_text("v 0 0 0\\n" * 10)
    report["cages"] = [{"component": 0, "quads": 8, "irregular_vertices": 1,
                        "interior_valence4_fraction": 0.9, "method": "field-aligned patch layout",
                        "fit": {"max_design_to_limit": 0.2, "rms_design_to_limit": 0.05}}]
    report["composed"] = {"ok": True, "contacts": [{"component": 0, "surface": "cage"}]}
else:
    report["cage_failures"] = [{"component": 0, "reason": "no layout"}]
    report["diagnostics"] = ["9 design vertices lie deeper than d inside keep-in 'keep_in_0': "
                             "the design does not contain it there"]
(out / "report.json").write_text(json.dumps(report))
'''


def test_runner_records_each_case_with_its_fate(tmp_path):
    cli = tmp_path / "fake_genbrep"
    cli.write_text(FAKE_CLI)
    cli.chmod(0o755)
    corpus = tmp_path / "corpus"
    make_case(corpus / "ok", CUBE, keep_ins=[INNER])
    make_case(corpus / "bad", CUBE, keep_ins=[ACROSS], names={"keep_in_0.obj": "boss"})
    make_case(corpus / "claims_ok", CUBE)
    make_case(corpus / "crash", CUBE)
    make_case(corpus / "slow", CUBE)
    out = tmp_path / "run"
    done = subprocess.run(["/usr/bin/python3", str(CORPUS), str(corpus), "--jobs", "2", "--timeout", "2",
                           "--cli", str(cli), "--out", str(out)], capture_output=True, text=True, check=True)
    records = {r["case"]: r for r in map(json.loads, (out / "corpus.jsonl").read_text().splitlines())}
    assert sorted(records) == ["corpus/bad", "corpus/claims_ok", "corpus/crash", "corpus/ok", "corpus/slow"]
    assert records["corpus/claims_ok"]["judge"]["result"]["boundary_edges"] == 3
    ok = records["corpus/ok"]
    assert ok["exit"] == 0 and ok["peak_mb"] > 0 and ok["stages"] == {"mesh": 0.5, "quad": 1.5}
    assert ok["judge"]["result"]["watertight"] is True
    component = ok["components"][0]
    assert component["caged"] and component["field_aligned"] and component["composed_from"] == "cage"
    assert component["irregular_fraction"] == pytest.approx(0.1)
    assert component["fit_max_h"] == pytest.approx(2) and component["fit_rms_h"] == pytest.approx(0.5)
    bad = records["corpus/bad"]
    assert bad["judge"]["consistency"]["verdict"] == "inconsistent" and bad["offender_named"] is True
    assert bad["components"][0] == {"component": 0, "caged": False, "failure": "no layout"}
    assert records["corpus/crash"]["signal"] == 11 and not records["corpus/crash"]["timed_out"]
    assert records["corpus/slow"]["timed_out"] and records["corpus/slow"]["seconds"] < 30
    for expected in ["watertight 1/5", "inconsistent cases with a named diagnostic 1/1",
                     "components composed from their cage 2/3", "crashes 1, timeouts 1",
                     "converter reports composed but the judge finds it not watertight 1",
                     "cases without report.json (their components are not counted) 2"]:
        assert expected in done.stdout.splitlines(), expected


def test_a_diagnostic_names_an_offender_only_with_its_problem():
    import importlib.machinery
    import importlib.util
    loader = importlib.machinery.SourceFileLoader("corpus_runner", str(CORPUS))
    runner = importlib.util.module_from_spec(importlib.util.spec_from_loader("corpus_runner", loader))
    loader.exec_module(runner)
    judged = {"consistency": {"verdict": "inconsistent", "reasons": [
        {"kind": "keep-in outside the design", "solid": "keep_in_0.obj"},
        {"kind": "material inside a keep-out", "solid": "keep_out_1.obj"}]}}
    meta = {"names": {"keep_in_0.obj": "boss"}}
    mentions = ["the organic boundary crosses a gap between keep-in 'keep_in_0' and keep-out 'keep_out_1'"]
    assert runner.names_offender(judged, meta, mentions)[0] is False
    says = ["keep-in 'boss' is not inside the design: 3 design vertices lie up to 2 deep inside it",
            "4 design vertices lie deeper than d inside keep-out 'keep_out_1': material intrudes into it"]
    named, offenders = runner.names_offender(judged, meta, says)
    assert named is True and [o["named"] for o in offenders] == [True, True]
    assert runner.names_offender(judged, meta, says[:1])[0] is False

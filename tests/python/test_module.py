"""The compiled module on numpy arrays: results, errors, progress and cancel."""
import subprocess
import threading

import numpy as np
import pytest

from conftest import BUILD, load_scene

SCENES = ["grown_box", "tube", "two_arches", "eroded_seed", "bolt_hole"]


def test_module_describes_itself(native):
    assert native.__version__.count(".") == 2
    assert native.STAGES[:5] == ("mesh", "incidence", "partition", "relax", "field")
    assert "tolerance" in native.OPTION_KEYS and "size_scale" in native.OPTION_KEYS
    assert issubclass(native.CancelledError, native.ConversionError)


@pytest.mark.parametrize("scene", SCENES)
@pytest.mark.parametrize("mode", ["distance", "grid"])
def test_partition_of_each_scene(native, scenes, scene, mode):
    design, solids, (origin, h), (components, loops) = load_scene(native, scenes / scene)
    options = {"tolerance": h} if mode == "distance" else {"incidence": "grid", "grid_origin": origin, "grid_h": h}
    result = native.convert(design, solids, options)
    part = result["partition"]
    faces = result["design"]["faces"]
    assert part["organic_components"] == components
    assert len(part["loops"]) == loops
    assert part["face_solid"].shape == (len(faces),)
    assert part["face_solid"].dtype == np.int32
    assert part["face_solid"].min() >= -1 and part["face_solid"].max() < len(solids)
    # Organic faces carry a component, incident faces do not.
    assert np.array_equal(part["face_solid"] == -1, part["face_component"] >= 0)
    assert sorted(set(part["face_component"][part["face_component"] >= 0])) == list(range(components))
    # Each loop is a closed cycle whose consecutive vertices share an edge of the design.
    edges = {tuple(sorted(e)) for tri in faces for e in ((tri[0], tri[1]), (tri[1], tri[2]), (tri[2], tri[0]))}
    for loop in part["loops"]:
        cycle = list(loop["vertices"])
        assert len(set(cycle)) == len(cycle) >= 3
        assert all(tuple(sorted((a, b))) in edges for a, b in zip(cycle, cycle[1:] + cycle[:1]))
    report = result["report"]
    assert report["counts"]["boundary_loops"] == loops
    assert report["tolerance"]["mode"] == mode
    assert tuple(report["stages"]) == native.STAGES
    # Relaxation keeps the components and loops, on a remeshed design.
    relaxed = result["relaxed"]
    assert relaxed["partition"]["organic_components"] == components
    assert len(relaxed["partition"]["loops"]) == loops
    assert relaxed["partition"]["face_solid"].shape == (len(relaxed["faces"]),)
    for loop in report["relax"]["loops"]:
        assert loop["mean_turning_degrees_after"] < loop["mean_turning_degrees_before"]
    # Field, on the relaxed design: one unit direction per organic face; indices sum to 4χ.
    field = result["field"]
    organic = relaxed["partition"]["face_solid"] == -1
    assert np.allclose(np.linalg.norm(field["direction"][organic], axis=1), 1.0)
    assert np.all(field["size_u"][organic] > 0)
    chi = {"grown_box": 1, "tube": 0, "two_arches": 0, "eroded_seed": 1, "bolt_hole": 1}[scene]
    for c in range(components):
        assert field["singular_index"][field["singular_component"] == c].sum() == 4 * chi
    # Cages: pure quads, finite control points, one per component that could be meshed;
    # every component without a cage is named in the report with its reason.
    for cage in result["cages"]:
        assert cage["faces"].shape[1] == 4 and np.isfinite(cage["vertices"]).all()
        assert cage["faces"].max() < len(cage["vertices"])
        assert cage["subdivision"]["boundary_smooth"] == "ALL" and cage["subdivision"]["use_limit_surface"]
    failed = {f["component"] for f in report["cage_failures"]}
    assert {c["component"] for c in result["cages"]} | failed == set(range(components))
    # The composed solid: closed, 2-manifold and oriented by an independent count, and
    # within 2% of the design's volume.
    composed = result["composed"]
    assert report["composed"]["ok"], report["diagnostics"]
    # The status is the command line's: 3 exactly when some component fell back, each
    # fallback named with its component.
    assert result["status"] == (3 if result["fallbacks"] else 0)
    assert result["fallbacks"] == report["composed"]["fallbacks"]
    assert all(line.startswith("organic component ") for line in result["fallbacks"])
    counts = native.validate_mesh(composed["vertices"], composed["faces"])
    assert counts["closed_manifold"], counts
    assert counts["signed_volume"] == pytest.approx(report["inputs"]["design"]["volume"], rel=0.02)
    sources = set(composed["face_source"])
    assert sources & set(range(len(solids))) and min(sources) < 0  # solid and organic faces


def test_face_source_maps_back_to_input_triangles(native, scenes):
    design, solids, _, _ = load_scene(native, scenes / "tube")
    result = native.convert(design, solids)
    source = result["design"]["face_source"]
    assert len(source) == len(result["design"]["faces"])
    out_v = result["design"]["vertices"][result["design"]["faces"]]
    in_v = design["vertices"][design["faces"][source]]
    assert np.allclose(out_v, in_v)


def test_errors_name_the_object_and_the_problem(native, scenes):
    design, solids, _, _ = load_scene(native, scenes / "grown_box")
    open_solid = dict(solids[0], faces=solids[0]["faces"][:-2])
    with pytest.raises(native.ConversionError) as err:
        native.convert(design, [open_solid])
    assert "keep-in 'base' is open" in str(err.value)
    assert err.value.code == "invalid_input" and err.value.stage == "mesh"

    nan_design = dict(design, vertices=design["vertices"].copy())
    nan_design["vertices"][5, 2] = np.nan
    with pytest.raises(native.ConversionError, match="NaN"):
        native.convert(nan_design, solids)
    with pytest.raises(native.ConversionError, match="is empty"):
        native.convert(dict(design, faces=np.zeros((0, 3), np.int32)), solids)
    with pytest.raises(native.ConversionError, match="N×3"):
        native.convert(dict(design, vertices=np.zeros((4, 2))), solids)
    with pytest.raises(native.ConversionError, match="roles are"):
        native.convert(design, [dict(solids[0], role="keep_maybe")])
    with pytest.raises(native.ConversionError, match="unknown option 'tolerence'"):
        native.convert(design, solids, {"tolerence": 1})


def test_progress_reports_every_stage_and_can_cancel(native, scenes):
    design, solids, _, _ = load_scene(native, scenes / "two_arches")
    calls = []
    native.convert(design, solids, progress=lambda stage, f: calls.append((stage, f)))
    assert tuple(dict.fromkeys(stage for stage, _ in calls)) == native.STAGES
    assert all(0.0 <= f <= 1.0 for _, f in calls)
    with pytest.raises(native.CancelledError) as err:
        native.convert(design, solids, progress=lambda stage, f: stage != "incidence")
    assert err.value.stage == "incidence" and err.value.code == "cancelled"

    def broken(stage, fraction):
        raise ValueError("callback bug")
    with pytest.raises(native.ConversionError, match="callback bug"):
        native.convert(design, solids, progress=broken)


def test_runs_in_a_worker_thread(native, scenes):
    """The add-on's pattern: convert in a thread, progress through a shared variable."""
    design, solids, _, _ = load_scene(native, scenes / "bolt_hole")
    state = {"stage": None, "result": None}

    def work():
        state["result"] = native.convert(design, solids, progress=lambda s, f: state.update(stage=s) or True)
    worker = threading.Thread(target=work)
    worker.start()
    worker.join()
    assert state["stage"] == native.STAGES[-1]
    assert state["result"]["partition"]["organic_components"] == 1


def test_same_input_same_output(native, scenes):
    design, solids, _, _ = load_scene(native, scenes / "eroded_seed")
    a = native.convert(design, solids)
    b = native.convert(design, solids)
    assert np.array_equal(a["partition"]["face_solid"], b["partition"]["face_solid"])
    assert [list(l["vertices"]) for l in a["partition"]["loops"]] == [list(l["vertices"]) for l in b["partition"]["loops"]]


def test_validate_mesh_counts(native):
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    f = np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3]], np.int32)
    counts = native.validate_mesh(v, f)
    assert counts["boundary_edges"] == 3 and not counts["closed_manifold"]
    counts = native.validate_mesh(v, np.vstack([f, [[0, 3, 2]]]))
    assert counts["closed_manifold"] and counts["signed_volume"] == pytest.approx(1 / 6)


def test_recompose_from_the_converted_cages(native, scenes):
    design, solids, (origin, h), _ = load_scene(native, scenes / "tube")
    result = native.convert(design, solids, {"tolerance": h})
    assert [c["surface"] for c in result["report"]["composed"]["contacts"]] == ["cage"]
    # Made as asked: the command line's exit status 0, no fallback.
    assert result["status"] == 0 and result["fallbacks"] == []
    cages = [{k: c[k] for k in ("name", "vertices", "faces", "crease_edges", "crease_values")}
             for c in result["cages"]]
    again = native.recompose(solids, cages)
    assert again["report"]["composed"]["ok"], again["report"]["diagnostics"]
    assert again["status"] == 0 and again["fallbacks"] == []
    counts = native.validate_mesh(again["composed"]["vertices"], again["composed"]["faces"])
    assert counts["closed_manifold"] and counts["signed_volume"] > 0
    volume = result["report"]["composed"]["volume"]
    assert abs(counts["signed_volume"] - volume) < 1e-3 * volume
    assert [c["name"] for c in again["cages"]] == [c["name"] for c in cages]
    assert again["cages"][0]["faces"].shape == cages[0]["faces"].shape
    # Errors name the cage: triangles instead of quads, and a hole away from every solid.
    triangles = dict(cages[0], faces=np.array([[0, 1, 2]] * 3))
    with pytest.raises(native.ConversionError, match=r"cage 'component 0' is not a quad mesh: 3 faces have 3 corners"):
        native.recompose(solids, [triangles])
    vertices, faces = cages[0]["vertices"], cages[0]["faces"]
    middle = np.argmin(np.linalg.norm(vertices[faces].mean(axis=1) - vertices.mean(axis=0), axis=1))
    holed = dict(cages[0], faces=np.delete(faces, middle, axis=0))
    with pytest.raises(native.ConversionError, match=r"cage 'component 0' is open: its boundary loop"):
        native.recompose(solids, [holed])


def test_cages_name_their_irregular_vertices_off_singularities(native, tmp_path):
    # The 3 x 3 net at h 0.165 is a scene whose cage keeps such vertices (2, the CLI; of the
    # 3 x 3 net at 16 voxel sizes from 0.09 to 0.17, it and h 0.17 keep some). The 4 x 4 net
    # at h 0.145 kept one until windows counted the vertices beyond them that take their
    # singularities and the last rounds climbed by two; the 3 x 3 net at h 0.135 keeps none
    # since a dislocation at the boundary glides into the singular vertex beside it, the
    # 4 x 4 net at h 0.13 none since sequences of more than three edits place them, nor at
    # h 0.1 since layouts leaving 2 are read again; the fixtures keep none.
    subprocess.run([str(BUILD / "bin" / "make_scenes"), str(tmp_path), "0.165", "net", "3"], check=True)
    design, solids, (origin, h), _ = load_scene(native, tmp_path / "net")
    result = native.convert(design, solids, {"tolerance": h, "until": "quad"})
    (cage,), (stats,) = result["cages"], result["report"]["cages"]
    listed = stats["irregular_vertices_off_singularities_at"]
    off = cage["irregular_off_singularities"]
    assert len(listed) > 0, "the scene no longer keeps an unexplained vertex: pick another"
    assert len(off) == len(listed) == stats["irregular_vertices_off_singularities"]
    valence = np.bincount(cage["faces"].ravel(), minlength=len(cage["vertices"]))
    for v, point in zip(off, listed):
        np.testing.assert_allclose(cage["vertices"][v], point["position"])
        assert valence[v] == point["valence"] != 4
    # Through fitting and composing (the cage handed on is the pulled one), the indices
    # still name those vertices.
    full = native.convert(design, solids, {"tolerance": h})
    assert full["report"]["composed"]["ok"]
    (pulled,) = full["cages"]
    np.testing.assert_array_equal(pulled["irregular_off_singularities"], off)
    valence = np.bincount(pulled["faces"].ravel(), minlength=len(pulled["vertices"]))
    assert [valence[v] for v in off] == [point["valence"] for point in listed]


def test_fallback_gives_a_solid_and_status_three(native, tmp_path):
    """A dome across a keep-in and a keep-out 0.003 apart cannot be pulled across the gap:
    the solid comes from a lower tier, status 3, each fallback named with its reason."""
    subprocess.run([str(BUILD / "bin" / "make_scenes"), str(tmp_path), "0.05", "gap", "0.003"], check=True)
    design, solids, (origin, h), _ = load_scene(native, tmp_path / "gap_dome")
    result = native.convert(design, solids, {"tolerance": h})
    composed = result["report"]["composed"]
    assert composed["ok"], result["report"]["diagnostics"]
    counts = native.validate_mesh(result["composed"]["vertices"], result["composed"]["faces"])
    assert counts["closed_manifold"] and counts["signed_volume"] > 0
    assert result["status"] == 3
    assert result["fallbacks"] == composed["fallbacks"] and result["fallbacks"]
    assert any("crosses a gap of 0.003 between" in line and "keep-in 'boss'" in line
               and "keep-out 'bolt'" in line for line in result["fallbacks"]), result["fallbacks"]

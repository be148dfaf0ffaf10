"""Generated designs through bench/corpus and its independent judge, as the corpus report
runs them: the generator is a pure function of its seed, no conversion crashes, and each
design's composed solid is judged valid. Designs the converter fails on today stay here as
strict expected failures with their reason, so that a change which fixes one shows up."""
import filecmp
import json
import subprocess

import pytest

from conftest import BUILD, ROOT

GENERATE = BUILD / "bin" / "generate_design"
CORPUS = ROOT / "bench" / "corpus"

# Seeds whose designs convert in well under a minute. Per check, why it fails today on a
# seed (seeds not named pass).
SEEDS = (8, 53, 123, 127)
FLOOR = "a component has no working tier, so the solid is the design Boolean: "
FAILS = {
    "as_asked": {8: FLOOR + "component 0's design region folds after the pull (its cage too)",
                 53: "component 0's fitted boundary cannot be pulled into its keep-in without folding: "
                     "it composes from the cage extended into the keep-in, a fallback"},
    "from_cage": {8: FLOOR + "component 0's design region folds after the pull (its cage too)"},
    "volume": {8: "the design Boolean is 2.8% larger than the design (the keep-ins restore cut corners)",
               123: "the composed solid is 5% smaller than the design",
               127: "the composed solid is 8% smaller than the design"},
}


def seeds(check):
    return [pytest.param(s, marks=pytest.mark.xfail(strict=True, reason=FAILS[check][s]))
            if s in FAILS[check] else s for s in SEEDS]


@pytest.fixture(scope="module")
def corpus_run(tmp_path_factory):
    """bench/corpus over the seeds' designs: {case name: record}."""
    cases = tmp_path_factory.mktemp("cases")
    for seed in SEEDS:
        subprocess.run([str(GENERATE), "--seed", str(seed), "--out", str(cases / f"s{seed:03d}")],
                       check=True, capture_output=True)
    out = tmp_path_factory.mktemp("corpus")
    subprocess.run(["/usr/bin/python3", str(CORPUS), str(cases), "--out", str(out), "--jobs", "1",
                    "--timeout", "600"], check=True, capture_output=True)
    records = [json.loads(line) for line in (out / "corpus.jsonl").read_text().splitlines()]
    return {r["case"].rsplit("/", 1)[-1]: r for r in records}


def test_the_same_seed_writes_the_same_bytes(tmp_path):
    for run in ("a", "b"):
        subprocess.run([str(GENERATE), "--seed", "7", "--out", str(tmp_path / run)], check=True,
                       capture_output=True)
    names = sorted(p.name for p in (tmp_path / "a").iterdir())
    assert "design.obj" in names and "meta.json" in names
    match, mismatch, errors = filecmp.cmpfiles(tmp_path / "a", tmp_path / "b", names, shallow=False)
    assert mismatch == [] and errors == [] and sorted(match) == names
    meta = json.loads((tmp_path / "a" / "meta.json").read_text())
    assert all((tmp_path / "a" / f).is_file() for f in meta["keep_in"] + meta["keep_out"] + meta["seed"])


@pytest.mark.parametrize("seed", SEEDS)
def test_no_conversion_crashes_or_hangs(corpus_run, seed):
    record = corpus_run[f"s{seed:03d}"]
    assert record["signal"] is None, f"killed by signal {record['signal']}"
    assert not record["timed_out"]


@pytest.mark.parametrize("seed", SEEDS)
def test_valid_input_converts(corpus_run, seed):
    """A solid is written: exit 0, or 3 where some component fell back (each listed)."""
    record = corpus_run[f"s{seed:03d}"]
    assert record["judge"]["inputs"]["design"]["closed"]
    assert record["exit"] in (0, 3), record["diagnostics"][-3:]


@pytest.mark.parametrize("seed", seeds("as_asked"))
def test_every_component_composes_from_its_best_tier(corpus_run, seed):
    assert corpus_run[f"s{seed:03d}"]["exit"] == 0


@pytest.mark.parametrize("seed", seeds("from_cage"))
def test_every_component_composes_from_its_pulled_cage(corpus_run, seed):
    """Its fitted cage, or that cage extended into its solids: not the design."""
    components = corpus_run[f"s{seed:03d}"]["components"]
    assert components
    assert all(c.get("composed_from") in ("cage", "extended cage") for c in components), \
        [c.get("composed_from") for c in components]


@pytest.mark.parametrize("seed", SEEDS)
def test_the_composed_solid_is_valid(corpus_run, seed):
    record = corpus_run[f"s{seed:03d}"]
    result = record["judge"]["result"]
    assert result.get("present"), "no composed solid: " + "; ".join(record["diagnostics"][-2:])
    # closed, 2-manifold, outward, no self-intersections, keep-ins inside, keep-outs empty
    assert result["watertight"], json.dumps(result)[:2000]


@pytest.mark.parametrize("seed", seeds("volume"))
def test_the_composed_volume_is_the_designs(corpus_run, seed):
    result = corpus_run[f"s{seed:03d}"]["judge"]["result"]
    assert result.get("present"), "no composed solid"
    assert abs(result["volume_vs_design"] - 1) <= 0.02, result["volume_vs_design"]

"""benchmarks/fit_digest.py end to end on a few sets: sets, run (twice, with different worker
counts), diff; and the diff's classes on doctored records."""

import json
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))

import digest_diff  # noqa: E402
import digest_sets  # noqa: E402
import fit_digest  # noqa: E402

#: One call of each sort: fit_points (trials), the scan document (two stations), fit_auto.
SOURCES = "trials,two_station_boxes,auto_choice"


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """A tiny sets file and two runs of it: 2 workers, then 1."""
    tmp = tmp_path_factory.mktemp("digest")
    sets = tmp / "sets.npz"
    assert fit_digest.main(["sets", str(sets), "--scale", "0.001", "--sources", SOURCES]) == 0
    a, b = tmp / "a.json", tmp / "b.json"
    assert fit_digest.main(["run", str(sets), str(a), "--jobs", "2"]) == 0
    assert fit_digest.main(["run", str(sets), str(b), "--jobs", "1"]) == 0
    return sets, a, b


def test_a_run_diffed_against_another_run_of_the_same_code_is_identical(runs, capsys):
    sets, a, b = runs
    meta, entries, points, offsets = digest_sets.load(sets)
    assert len(entries) == meta["sets"] and len(offsets) == len(entries) + 1
    assert {e["call"] for e in entries} == {"fit_points", "scan", "fit_auto"}
    assert {e["kind"] for e in entries} == {"cylinder", "cuboid", "sphere", "plane", "auto"}
    assert points.shape == (offsets[-1], 3)
    run_a = fit_digest.load_run(a)
    assert run_a["commit"] and run_a["records_count"] == len(entries)
    assert [r["key"] for r in run_a["records"]] == [e["key"] for e in entries]
    assert fit_digest.load_run(b)["digest"] == run_a["digest"]  # 1 or 2 workers alike
    capsys.readouterr()
    assert fit_digest.main(["diff", str(a), str(b)]) == 0
    text = capsys.readouterr().out
    assert f"identical {len(entries)} | changed 0 | newly refused 0" in text
    assert text.splitlines()[-1] == f"verdict: IDENTICAL ({len(entries)} sets)"


def test_records_are_exact_reprs(runs):
    fitted = [r for r in fit_digest.load_run(runs[1])["records"] if r["status"] == "fit"]
    cylinder = next(r for r in fitted if r["fitted"] == "cylinder")
    assert set(cylinder["params"]) == {"radius", "center", "axis", "length"}
    assert repr(float(cylinder["params"]["radius"])) == cylinder["params"]["radius"]
    cuboid = next(r for r in fitted if r["fitted"] == "cuboid")
    assert len(cuboid["params"]["axes"]) == 3 and len(cuboid["params"]["observed"]) == 3
    auto = next(r for r in fitted if r["kind"] == "auto")
    assert auto["fitted"] in ("cylinder", "cuboid", "sphere", "plane")


def test_diff_sorts_changes_into_their_classes(runs):
    run = fit_digest.load_run(runs[1])
    other = json.loads(json.dumps(run))
    records = {r["key"]: r for r in other["records"]}
    cylinder = next(r for r in records.values() if r.get("fitted") == "cylinder")
    truth = cylinder["truth"]["radius"]
    radius = float(cylinder["params"]["radius"])
    # 2 mm further from the truth than before: worse
    cylinder["params"]["radius"] = repr(radius + (0.002 if radius >= truth else -0.002))
    refused = next(r for r in records.values() if r.get("fitted") == "sphere")
    refused.update(status="refused", error="FitError: doctored")
    text = digest_diff.report(run, other, show=3)
    assert "changed 1 | newly refused 1 | no longer refused 0" in text
    assert f"  {cylinder['key']} [worse]: radius_rel" in text
    assert text.splitlines()[-1].startswith(
        "verdict: CHANGED, net worse: 1 changed (0 better, 1 worse"
    )
    back = digest_diff.report(other, run, show=3)
    assert "no longer refused 1" in back and "(1 better, 0 worse" in back


def test_cuboid_errors_match_axes_whatever_their_order_and_sign():
    axes = [[0.6, 0.8, 0.0], [-0.8, 0.6, 0.0], [0.0, 0.0, 1.0]]
    fitted = [[0.0, 0.0, -1.0], [0.6, 0.8, 0.0], [0.8, -0.6, 0.0]]
    size, angle = digest_diff.cuboid_errors(fitted, [3.03, 0.3, 0.4], axes, [0.3, 0.4, 3.0])
    assert size == pytest.approx(0.01) and angle == pytest.approx(0.0, abs=1e-6)

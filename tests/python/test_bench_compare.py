"""`bsv bench compare`: two sets of `bench synth` runs of the same bodies, segment by segment."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from bsv.bench.compare import (
    LIMBS_ROW,
    OUTPUT_FILES,
    ROWS,
    compare_markdown,
    compare_runs,
    read_runs,
    write_compare,
)
from bsv.bench.main import main as bench_main
from bsv.bodies.variants import LIMB_SEGMENTS
from bsv.errors import BenchError, OutputExistsError

SEGMENTS = ROWS[:-1]


def _truth(subject: int) -> dict[str, float]:
    return {s: 1.0 + 0.1 * k + 0.01 * subject for k, s in enumerate(SEGMENTS)}


def _write(d: Path, seed: int, segmentation: str, errors: dict[tuple[int, str], dict[str, float]],
           failed: tuple[tuple[int, str], ...] = (), truth_shift: float = 0.0) -> Path:
    """A bench synth results.json whose runs have the given signed errors (%) per (subject, condition)."""
    runs = []
    for (subject, cond), errs in errors.items():
        truth = {s: v + truth_shift for s, v in _truth(subject).items()}
        est = {s: truth[s] * (1 + errs.get(s, 0.0) / 100) for s in SEGMENTS}
        ok = (subject, cond) not in failed
        runs.append({"subject": f"subject_{subject:03d}", "condition": cond, "method": "bsv", "ok": ok,
                     "truth_l": truth, "estimated_l": est if ok else {}})
    d.mkdir(parents=True, exist_ok=True)
    (d / "results.json").write_text(json.dumps({"config": {"seed": seed, "segmentation": segmentation}, "runs": runs}))
    return d


def test_the_gap_is_the_difference_of_the_mean_rves_paired_by_subject(tmp_path: Path) -> None:
    cam = {(0, "noer"): {"forearm_l": 3.0, "torso": -1.0}, (1, "noer"): {"forearm_l": -2.0, "torso": 0.5}}
    orc = {(0, "noer"): {"forearm_l": 0.5, "torso": 0.2}, (1, "noer"): {"forearm_l": -0.3, "torso": -0.2}}
    a = read_runs([_write(tmp_path / "cam", 3, "camera", cam)])
    b = read_runs([_write(tmp_path / "orc", 3, "oracle", orc)])
    r = compare_runs(a, b)
    assert r["labels"] == ["camera", "oracle"]  # the segmentations, which differ
    rows = r["conditions"]["noer"]["rows"]
    fa = rows["forearm_l"]
    assert fa["camera"]["mean_rve"] == pytest.approx(2.5) and fa["oracle"]["mean_rve"] == pytest.approx(0.4)
    assert fa["camera"]["signed"] == pytest.approx(0.5) and fa["camera"]["worst"] == pytest.approx(3.0)
    assert fa["camera"]["worst_run"] == "seed 3 subject_000"
    assert fa["gap"] == pytest.approx(2.1) and fa["over"]
    assert fa["gap_se"] == pytest.approx(np.std([2.5, 1.7], ddof=1) / np.sqrt(2))
    assert rows["torso"]["gap"] == pytest.approx(0.55) and not rows["torso"]["over"]
    # the limbs row: each run's mean over the eight limbs (only forearm_l is off here)
    assert rows[LIMBS_ROW]["camera"]["mean_rve"] == pytest.approx(2.5 / len(LIMB_SEGMENTS))
    assert rows[LIMBS_ROW]["camera"]["signed"] == pytest.approx(0.5 / len(LIMB_SEGMENTS))
    md = compare_markdown(r)
    assert "| forearm_l | 2.50 / +0.50 / +3.0 | 0.40 / +0.10 / +0.5 | **+2.10 +- 0.40** |" in md
    assert "Over 1 point: forearm_l noer (+2.10)." in md
    # a larger allowance marks nothing
    assert "Every gap is within 3 point." in compare_markdown(compare_runs(a, b, max_gap=3.0))


def test_several_seeds_pool_and_failed_pairs_are_left_out_and_counted(tmp_path: Path) -> None:
    err = {(0, "noer"): {"shin_l": 1.0}, (1, "noer"): {"shin_l": 2.0}, (0, "l515"): {"shin_l": 4.0}}
    a = read_runs([_write(tmp_path / "a0", 0, "camera", err, failed=((1, "noer"),)),
                   _write(tmp_path / "a1", 1, "camera", err)])
    b = read_runs([_write(tmp_path / "b0", 0, "oracle", {k: {} for k in err}),
                   _write(tmp_path / "b1", 1, "oracle", {k: {} for k in err}),
                   _write(tmp_path / "b2", 2, "oracle", {k: {} for k in err})])  # a seed the first set lacks
    r = compare_runs(a, b, labels=("new", "old"))
    noer = r["conditions"]["noer"]
    assert noer["pairs"] == 3 and noer["failed"] == {"new": 1, "old": 0}
    assert noer["rows"]["shin_l"]["n"] == 3
    assert noer["rows"]["shin_l"]["new"]["mean_rve"] == pytest.approx((1 + 1 + 2) / 3)
    assert list(r["conditions"]) == ["noer", "l515"]  # the benchmark's order
    assert "failed: 1 new" in compare_markdown(r)


def test_one_pair_has_no_standard_error_and_unreadable_volumes_are_left_out(tmp_path: Path) -> None:
    a = _write(tmp_path / "a", 0, "camera", {(0, "noer"): {"thigh_l": 2.0}, (1, "noer"): {"thigh_l": 1.0}})
    doc = json.loads((a / "results.json").read_text())
    doc["runs"][1]["estimated_l"]["thigh_l"] = None  # a damaged record: that pair's thigh is left out
    (a / "results.json").write_text(json.dumps(doc))
    r = compare_runs(read_runs([a]), read_runs([_write(tmp_path / "b", 0, "oracle", {(0, "noer"): {}, (1, "noer"): {}})]))
    row = r["conditions"]["noer"]["rows"]["thigh_l"]
    assert row["n"] == 1 and row["gap"] == pytest.approx(2.0) and row["gap_se"] is None
    assert "| thigh_l |" in compare_markdown(r) and "+- n/a" in compare_markdown(r)
    assert r["conditions"]["noer"]["rows"]["thigh_r"]["n"] == 2


def test_two_engines_in_folders_of_one_name_keep_both_columns(tmp_path: Path) -> None:
    a = read_runs([_write(tmp_path / "new" / "seed0", 0, "camera", {(0, "noer"): {"shin_r": 2.0}})])
    b = read_runs([_write(tmp_path / "old" / "seed0", 0, "camera", {(0, "noer"): {"shin_r": 1.0}})])
    r = compare_runs(a, b)
    assert r["labels"] == ["seed0 (runs)", "seed0 (against)"]
    assert r["conditions"]["noer"]["rows"]["shin_r"]["gap"] == pytest.approx(1.0)
    with pytest.raises(BenchError, match="different labels"):
        compare_runs(a, b, labels=("x", "x"))


def test_other_bodies_no_shared_runs_and_bad_folders_are_refused(tmp_path: Path) -> None:
    err = {(0, "noer"): {}}
    a = read_runs([_write(tmp_path / "a", 0, "camera", err)])
    with pytest.raises(BenchError, match=r"not the same body.*--seed"):
        compare_runs(a, read_runs([_write(tmp_path / "b", 0, "oracle", err, truth_shift=0.01)]))
    with pytest.raises(BenchError, match="share no"):
        compare_runs(a, read_runs([_write(tmp_path / "c", 1, "oracle", err)]))
    with pytest.raises(BenchError, match="not found"):
        read_runs([tmp_path / "missing"])
    (tmp_path / "junk").mkdir()
    (tmp_path / "junk" / "results.json").write_text("{not json")
    with pytest.raises(BenchError, match="not readable"):
        read_runs([tmp_path / "junk"])
    (tmp_path / "boxes").mkdir()
    (tmp_path / "boxes" / "results.json").write_text(json.dumps({"config": {"seeds": 3}, "runs": []}))
    with pytest.raises(BenchError, match="not a `bsv bench synth` run"):
        read_runs([tmp_path / "boxes"])
    (tmp_path / "seedless").mkdir()
    (tmp_path / "seedless" / "results.json").write_text(json.dumps({"config": {"seed": "x", "segmentation": "camera"},
                                                                    "runs": []}))
    with pytest.raises(BenchError, match="not a whole number"):
        read_runs([tmp_path / "seedless"])
    with pytest.raises(BenchError, match="both hold cohort seed 0"):
        read_runs([tmp_path / "a", tmp_path / "a"])
    with pytest.raises(BenchError, match="max_gap"):
        compare_runs(a, a, max_gap=float("nan"))


def test_outputs_are_written_whole_or_not_at_all(tmp_path: Path, monkeypatch) -> None:
    err = {(0, "noer"): {"thigh_r": 1.5}}
    a = read_runs([_write(tmp_path / "a", 0, "camera", err)])
    b = read_runs([_write(tmp_path / "b", 0, "oracle", {(0, "noer"): {}})])
    r = compare_runs(a, b)
    out = tmp_path / "out"
    paths = write_compare(out, r)
    assert [p.name for p in paths] == list(OUTPUT_FILES) and all(p.stat().st_size > 0 for p in paths)
    assert json.loads((out / "compare.json").read_text())["conditions"]["noer"]["rows"]["thigh_r"]["gap"] == pytest.approx(1.5)
    with pytest.raises(OutputExistsError, match="--overwrite"):
        write_compare(out, r)
    write_compare(out, r, overwrite=True)

    def broken(*_args: object) -> None:
        raise RuntimeError("figure failed")

    monkeypatch.setattr("bsv.bench.compare.compare_figure", broken)
    fresh = tmp_path / "fresh"
    with pytest.raises(RuntimeError):
        write_compare(fresh, r)
    assert list(fresh.iterdir()) == []  # nothing half-written


def test_the_command_prints_the_table_and_refuses_bad_input(tmp_path: Path, capsys) -> None:
    a = _write(tmp_path / "a", 0, "camera", {(0, "noer"): {"upper_arm_r": -2.0}})
    b = _write(tmp_path / "b", 0, "oracle", {(0, "noer"): {}})
    assert bench_main(["compare", "--runs", str(a), "--against", str(b), "--out", str(tmp_path / "o")]) == 0
    out = capsys.readouterr().out
    assert "| upper_arm_r | 2.00 / -2.00 / -2.0 | 0.00 / +0.00 / +0.0 | **+2.00" in out
    assert (tmp_path / "o" / "compare.png").exists()
    assert bench_main(["compare", "--runs", str(a), "--against", str(b), "--out", str(tmp_path / "o")]) == 2
    assert "--overwrite" in capsys.readouterr().err
    assert bench_main(["compare", "--runs", str(tmp_path / "none"), "--against", str(b)]) == 2
    assert "not found" in capsys.readouterr().err
    for bad in (["--labels", "x"], ["--max-gap", "-1"], ["--max-gap", "lots"]):
        with pytest.raises(SystemExit) as e:
            bench_main(["compare", "--runs", str(a), "--against", str(b), *bad])
        assert e.value.code == 2


def test_the_boundary_loops_are_summarised_per_set_from_the_loops_both_runs_measured(tmp_path: Path) -> None:
    err = {(0, "noer"): {}, (1, "noer"): {}, (2, "noer"): {}}
    loops_a = {0: {"elbow_l": 4.0, "elbow_r": -2.0, "knee_l": 1.0}, 1: {"elbow_l": 1.0, "elbow_r": 3.0},
               2: {"elbow_l": -1.0, "elbow_r": None, "knee_l": 3.0}}
    loops_b = {0: {"elbow_l": 1.0, "elbow_r": 0.0, "knee_l": 0.0}, 1: {"elbow_l": 0.0, "elbow_r": 1.0},
               2: {"elbow_l": 2.0, "elbow_r": 0.5, "knee_l": 1.0}}
    da, db = _write(tmp_path / "a", 0, "camera", err), _write(tmp_path / "b", 0, "oracle", err)
    for d, loops in ((da, loops_a), (db, loops_b)):
        doc = json.loads((d / "results.json").read_text())
        for r in doc["runs"]:
            r["info"] = {"boundary_errors_mm": loops[int(r["subject"][-3:])]}
        (d / "results.json").write_text(json.dumps(doc))
    r = compare_runs(read_runs([da]), read_runs([db]))
    loops = r["conditions"]["noer"]["loops"]
    # elbow_r of subject 2 is missing in the first set: its pair is left out of both sets' summaries
    assert loops["elbow"]["n"] == 5
    assert loops["elbow"]["camera"]["mean"] == pytest.approx(np.mean([4.0, -2.0, 1.0, 3.0, -1.0]))
    assert loops["elbow"]["oracle"]["sd"] == pytest.approx(np.std([1.0, 0.0, 0.0, 1.0, 2.0], ddof=1))
    assert loops["knee"]["n"] == 2 and "wrist" not in loops  # a kind no pair measured is left out
    md = compare_markdown(r)
    assert "| elbow (5) | +1.0 +- 2.5 | +0.8 +- 0.8 |" in md
    # runs without boundary errors (older results) give no loops table
    plain = compare_runs(read_runs([_write(tmp_path / "c", 0, "camera", err)]),
                         read_runs([_write(tmp_path / "d", 0, "oracle", err)]))
    assert plain["conditions"]["noer"]["loops"] == {} and "Boundary loops" not in compare_markdown(plain)


def test_each_loop_s_cost_is_the_limb_s_error_its_scatter_explains(tmp_path: Path) -> None:
    rng = np.random.default_rng(0)
    n = 8
    elbow = {(i, x): float(rng.normal(0.0, 3.0)) for i in range(n) for x in "lr"}
    wrist = {(i, x): float(rng.normal(-2.0, 4.0)) for i in range(n) for x in "lr"}
    # the camera's forearms follow their loops exactly (-0.8 % per mm of elbow, +0.2 of wrist, +0.5 offset); the
    # oracle's forearms err by a constant 0.3 % whatever their loops
    cam = {(i, "noer"): {f"forearm_{x}": 0.5 - 0.8 * elbow[i, x] + 0.2 * wrist[i, x] for x in "lr"} for i in range(n)}
    orc = {(i, "noer"): {"forearm_l": 0.3, "forearm_r": 0.3} for i in range(n)}
    da, db = _write(tmp_path / "a", 0, "camera", cam), _write(tmp_path / "b", 0, "oracle", orc)
    for d in (da, db):
        doc = json.loads((d / "results.json").read_text())
        for r in doc["runs"]:
            i = int(r["subject"][-3:])
            loops = {f"{k}_{x}": v[i, x] for k, v in (("elbow", elbow), ("wrist", wrist)) for x in "lr"}
            r["info"] = {"boundary_errors_mm": {**loops, "elbow_r": None} if i == 0 else loops}
        (d / "results.json").write_text(json.dumps(doc))
    r = compare_runs(read_runs([da]), read_runs([db]))
    costs = r["conditions"]["noer"]["loop_costs"]
    assert set(costs) == {"forearm"}  # no other limb has both loops measured
    fa = costs["forearm"]
    assert (fa["proximal"], fa["distal"]) == ("elbow", "wrist")
    cam_fit = fa["camera"]
    assert cam_fit["n"] == 2 * n - 1  # subject 0's right elbow is missing
    assert cam_fit["per_mm_proximal"] == pytest.approx(-0.8) and cam_fit["per_mm_distal"] == pytest.approx(0.2)
    keep = [(i, x) for i in range(n) for x in "lr" if (i, x) != (0, "r")]
    e = np.array([0.5 - 0.8 * elbow[k] + 0.2 * wrist[k] for k in keep])
    assert cam_fit["rve"] == pytest.approx(np.mean(np.abs(e)), rel=1e-4)
    # both loops at their means: every forearm errs by the error at the mean loops
    at_mean = 0.5 - 0.8 * np.mean([elbow[k] for k in keep]) + 0.2 * np.mean([wrist[k] for k in keep])
    assert cam_fit["rve_without_both"] == pytest.approx(abs(at_mean), rel=1e-4)
    e_no_elbow = e + 0.8 * (np.array([elbow[k] for k in keep]) - np.mean([elbow[k] for k in keep]))
    assert cam_fit["rve_without_proximal"] == pytest.approx(np.mean(np.abs(e_no_elbow)), rel=1e-4)
    # the oracle's constant error owes nothing to its loops
    assert fa["oracle"]["per_mm_proximal"] == pytest.approx(0.0, abs=1e-6)
    assert fa["oracle"]["rve_without_both"] == pytest.approx(0.3, rel=1e-4)
    md = compare_markdown(r)
    assert "| forearm (elbow, wrist; 15) | camera | -0.80, +0.20 |" in md
    # runs without boundary errors (older results) give no costs table
    plain = compare_runs(read_runs([_write(tmp_path / "c", 0, "camera", cam)]),
                         read_runs([_write(tmp_path / "d", 0, "oracle", orc)]))
    assert plain["conditions"]["noer"]["loop_costs"] == {} and "scatter costs" not in compare_markdown(plain)

"""`bsv bench synth --refine-calibration`: the virtual rig's board view refined as a user would, the cloud
rebuilt with the refined extrinsics, and the intervals scored with the refined covariance."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import bsv
from bsv.bench.common import Run
from bsv.bench.floor import CameraPose, read_camera_poses
from bsv.bench.synth import Refined, refine_condition
from bsv.uncertainty import PAPER_STD, paper_covariance, pose_delta


@pytest.fixture(scope="module")
def body() -> bsv.Mesh:
    return bsv.bodies.subject(1, 0).body.mesh()


def test_scan_json_gives_each_cameras_points_and_reexpress_undoes_the_calibration_error(body, tmp_path: Path):
    """l515 and l5ca of one seed share their depth noise: the l5ca cloud with each camera's points moved
    from its (wrong) calibrated to its true extrinsics is the l515 cloud."""
    l5ca = bsv.scan(body, "l5ca", 11, images=tmp_path / "l5ca")
    l515 = bsv.scan(body, "l515", 11)
    ranges = json.loads((tmp_path / "l5ca" / "scan.json").read_text())["camera_points"]
    assert ranges["front"][0] == 0 and ranges["front"][1] == ranges["back"][0] and ranges["back"][1] == len(l5ca)
    assert np.abs(l5ca.points - l515.points).max() > 1e-3  # the calibration error moves the cloud
    cams = read_camera_poses(tmp_path / "l5ca")
    exact = Refined([_refined(CameraPose(c.name, c.true_rotation, c.true_translation, c.true_rotation,
                                         c.true_translation)) for c in cams])
    back = exact.reexpress(l5ca, str(tmp_path / "l5ca"))
    np.testing.assert_allclose(back.points, l515.points, atol=1e-9)
    np.testing.assert_array_equal(back.labels, l515.labels)


def _refined(pose: CameraPose):  # type: ignore[no-untyped-def]
    from bsv.bench.refine import RefinedCamera

    return RefinedCamera(pose, paper_covariance(pose.name), "test", {}, {})


def test_refine_condition_removes_the_back_cameras_depth_error_and_shrinks_its_covariance(body, tmp_path: Path):
    """The user's path on the rig's board view (cali: exact depth): the back camera's depth error (paper
    SD 3.4 mm) and yaw, which dominate the trunk_limbs floor, go; the posterior is narrower there."""
    bsv.scan(body, "cali", 5, images=tmp_path)
    cams = read_camera_poses(tmp_path)
    ref = refine_condition(str(tmp_path), "cali", 5, cams, body)
    assert ref.ok, ref.error
    by = {c.pose.name: c for c in ref.cameras}
    for c in cams:
        std = np.asarray(PAPER_STD[c.name])
        before = pose_delta(c.true_rotation, c.true_translation, c.est_rotation, c.est_translation) / std
        p = by[c.name].pose
        after = pose_delta(p.true_rotation, p.true_translation, p.est_rotation, p.est_translation) / std
        post = np.sqrt(np.diag(by[c.name].covariance)) / std
        assert by[c.name].source == "paper default+board depth, refined by the floor"
        assert post.max() <= 1.0 + 1e-9
        if c.name == "back":
            assert abs(after[2]) < 0.1 * max(1.0, abs(before[2])), (before, after)
            assert post[2] < 0.3 and post[4] < 0.3
        np.testing.assert_allclose(np.asarray(p.true_rotation), np.asarray(c.true_rotation))
    assert set(ref.floor_l) >= {"trunk_limbs", "forearm_l"}
    assert ref.truth is body


def test_a_failed_refinement_is_recorded_not_raised(body, tmp_path: Path, monkeypatch):
    import bsv.bench.refine as refine
    from bsv.frontend.errors import BoardDepthError

    def fail(*_a, **_k):  # type: ignore[no-untyped-def]
        raise BoardDepthError("front: only 3 valid depth pixels on the board")

    monkeypatch.setattr(refine, "refine_calibration", fail)
    bsv.scan(body, "cali", 5, images=tmp_path)
    ref = refine_condition(str(tmp_path), "cali", 5, read_camera_poses(tmp_path), body)
    assert not ref.ok and "BoardDepthError" in ref.error
    assert ref.register(set(), 5, body, {}, None, "oracle") == {"error": ref.error}


def _run(condition: str, tl: float, cal_sd: float, refined_sd: float | None, floor_before: float = 61.0,
         floor_after: float = 60.1) -> Run:
    truth = {"trunk_limbs": 60.0, "asymmetry_forearm_pct": 0.0}
    est = {"trunk_limbs": tl, "asymmetry_forearm_pct": 0.5}
    info: dict = {"uncertainty": {"estimate": est, "truth": truth,
                                  "calibration_sd": {"trunk_limbs": cal_sd, "asymmetry_forearm_pct": 4.0}}}
    if refined_sd is not None:
        info["refined"] = {
            "estimated_l": {"trunk_limbs": 60.2}, "floor_l": {"trunk_limbs": floor_after, "forearm_l": 1.0,
                                                              "forearm_r": 1.0},
            "seconds": 1.0, "refine_seconds": 0.5,
            "cameras": {"back": {"error_paper_sd": [0.1] * 6, "error_posterior_sd": [1.0] * 6}},
            "uncertainty": {"estimate": {**est, "trunk_limbs": 60.2}, "truth": truth,
                            "calibration_sd": {"trunk_limbs": refined_sd, "asymmetry_forearm_pct": 1.0}}}
    return Run("s", condition, "bsv", True, truth_l={"trunk_limbs": 60.0, "forearm_l": 1.0, "forearm_r": 1.0},
               estimated_l={"trunk_limbs": tl}, floor_l={"trunk_limbs": floor_before, "forearm_l": 1.1,
                                                         "forearm_r": 1.0}, info=info)


def test_coverage_rows_score_the_paper_and_the_refined_covariance_side_by_side():
    from bsv.bench.coverage import coverage_markdown, coverage_rows, refinement_markdown, refinement_rows
    from bsv.uncertainty import ErrorModel

    model = ErrorModel({"trunk_limbs": (0.0, 0.002), "asymmetry_forearm_pct": (0.0, 1.0)})
    runs = [_run("l5ca", 61.0, 0.03, 0.005), _run("l5ca", 60.1, 0.03, 0.005), _run("noer", 60.1, 0.0, None)]
    rows = coverage_rows(runs, {"l515": model, "exact": model})
    by = {(r["condition"], r["calibration"]): r for r in rows}
    assert set(by) == {("l5ca", "paper"), ("l5ca", "refined"), ("noer", "paper")}
    paper, refined = by["l5ca", "paper"], by["l5ca", "refined"]
    assert paper["runs"] == refined["runs"] == 2
    assert refined["trunk_limbs_halfwidth_pct"] < 0.25 * paper["trunk_limbs_halfwidth_pct"]
    assert refined["asymmetry_halfwidth_pts"] < paper["asymmetry_halfwidth_pts"]
    md = "\n".join(coverage_markdown(rows, {"l515": model}))
    assert "| l5ca | paper | l515 | 2 |" in md and "| l5ca | refined | l515 | 2 |" in md and "| noer | exact |" in md
    assert "| 0.0 (0/2) |" in md  # the false 'distinguishable' count beside its rate
    (ref,) = refinement_rows(runs)
    assert ref["condition"] == "l5ca" and ref["runs"] == 2 and ref["failed"] == 0
    assert ref["floor_tl_before_pct"] == pytest.approx(100 / 60) and ref["floor_tl_after_pct"] == pytest.approx(0.1 / 0.6)
    assert ref["floor_forearm_asym_before_pts"] == pytest.approx(0.1 / 1.05 * 100) and ref["floor_forearm_asym_after_pts"] == 0
    assert ref["error_rms_posterior_sd"] == pytest.approx(1.0) and ref["seconds_added"] == pytest.approx(1.5)
    assert "| l5ca | 2 | 0 | 1.67 -> 0.17" in "\n".join(refinement_markdown([ref]))
    failed = _run("l5ca", 60.1, 0.03, 0.005)
    failed.info["refined"] = {"error": "BoardDepthError: ..."}
    assert refinement_rows([failed])[0]["failed"] == 1
    assert [r["calibration"] for r in coverage_rows([failed], {"l515": model})] == ["paper"]


@pytest.mark.slow
def test_bench_synth_refine_calibration_end_to_end(tmp_path: Path):
    from bsv.bench.main import main

    out = tmp_path / "b"
    assert main(["synth", "--n", "1", "--conditions", "cali", "--refine-calibration", "--out", str(out),
                 "--quiet"]) == 0
    doc = json.loads((out / "results.json").read_text())
    assert doc["config"]["refine_calibration"] is True
    cals = {r["calibration"] for r in doc["coverage"]}
    assert cals == {"paper", "refined"}
    (ref,) = doc["refinement"]
    assert ref["failed"] == 0 and ref["floor_tl_after_pct"] < ref["floor_tl_before_pct"] + 0.05
    (run,) = doc["runs"]
    assert set(run["info"]["refined"]) >= {"estimated_l", "floor_l", "uncertainty", "cameras"}
    report = (out / "report.md").read_text()
    assert "| cali | refined |" in report and "Calibration refined as a user would" in report
    # without the option, nothing of it
    out2 = tmp_path / "c"
    assert main(["synth", "--n", "1", "--conditions", "cali", "--out", str(out2), "--quiet"]) == 0
    doc2 = json.loads((out2 / "results.json").read_text())
    assert doc2["refinement"] == [] and {r["calibration"] for r in doc2["coverage"]} == {"paper"}
    assert "refined" not in doc2["runs"][0]["info"]

"""bsv.bench.joints: signed joint-centre errors in the true body frame and their tables (no MediaPipe)."""

from __future__ import annotations

import numpy as np
import pytest

from bsv.bench.common import Run
from bsv.bench.joints import INFO_KEY, joint_errors, joints_markdown, summarise
from bsv.bodies.joints import rig_joints
from bsv.errors import InputError
from bsv.frontend.landmarks import (
    ELBOW_FRACTION,
    ELBOW_LANDMARK_WEIGHT,
    JOINT_OFFSETS_M,
    OFFSET_PREDICTOR_RANGE,
    OFFSET_PREDICTORS,
    TRUNK_REF_M,
    apply_offsets,
    body_frame,
    elbows_at_proportion,
    offset_predictors,
    trunk_length,
)


def test_errors_are_signed_in_the_body_frame_and_mirrored() -> None:
    truth = rig_joints()
    frame = body_frame(truth)
    assert frame is not None and np.allclose(frame @ frame.T, np.eye(3), atol=1e-9)
    assert frame[0] @ (truth["shoulder_l"] - truth["shoulder_r"]) > 0   # x: the subject's left
    est = {k: v.copy() for k, v in truth.items()}
    est["knee_l"] = truth["knee_l"] + frame[0] * 0.010                   # 10 mm outward (left)
    est["knee_r"] = truth["knee_r"] - frame[0] * 0.010 + frame[1] * 0.02  # 10 mm outward (right), 20 mm up
    e = joint_errors(est, truth)
    assert np.allclose(e["knee_l"], [10, 0, 0], atol=1e-6)
    assert np.allclose(e["knee_r"], [10, 20, 0], atol=1e-6)
    assert np.allclose(e["hip_l"], 0.0)


def _arm(joints: dict, side: str) -> tuple[np.ndarray, float, np.ndarray]:
    """(shoulder, shoulder-to-wrist length, unit direction) of one arm."""
    sh, wr = joints[f"shoulder_{side}"], joints[f"wrist_{side}"]
    length = float(np.linalg.norm(wr - sh))
    return sh, length, (wr - sh) / length


def test_elbows_move_along_the_arm_only() -> None:
    truth = rig_joints()
    sh, length, u = _arm(truth, "l")
    f_true = float((truth["elbow_l"] - sh) @ u) / length
    table = {"1": f_true, "sex": 0.02}
    across = np.cross(u, [0.0, 0.0, 1.0])
    across /= np.linalg.norm(across)
    est = {k: v.copy() for k, v in truth.items()}
    est["elbow_l"] = truth["elbow_l"] + 0.015 * u + 0.005 * across  # 15 mm distal, 5 mm across
    moved = elbows_at_proportion(est, 0.0, table, weight=0.2)
    d = moved["elbow_l"] - truth["elbow_l"]
    assert np.isclose(d @ u, 0.2 * 0.015, atol=1e-9)  # the along-arm error shrinks to the landmark's share
    assert np.isclose(d @ across, 0.005, atol=1e-9)  # the flexion, across the arm, is as measured
    assert all(np.array_equal(moved[k], est[k]) for k in est if not k.startswith("elbow"))
    # the right arm mirrors the left on the default rig: its true elbow stays put
    assert np.linalg.norm(moved["elbow_r"] - truth["elbow_r"]) < 1e-6
    # weight 1 keeps the landmark, 0 puts the elbow at the proportion; the sex score moves that place
    assert np.allclose(elbows_at_proportion(est, 0.0, table, weight=1.0)["elbow_l"], est["elbow_l"])
    at = elbows_at_proportion(est, 1.0, table, weight=0.0)["elbow_l"]
    assert np.isclose(float((at - sh) @ u) / length, f_true + 0.02, atol=1e-12)
    assert np.isclose((at - est["elbow_l"]) @ across, 0.0, atol=1e-12)


def test_elbows_at_proportion_leave_incomplete_arms_and_refuse_a_bad_weight() -> None:
    truth = rig_joints()
    no_wrist = {k: v for k, v in truth.items() if k != "wrist_l"}
    assert np.array_equal(elbows_at_proportion(no_wrist, 0.0)["elbow_l"], truth["elbow_l"])
    folded = {**truth, "wrist_r": truth["shoulder_r"].copy()}  # shoulder and wrist coincide
    assert np.array_equal(elbows_at_proportion(folded, None)["elbow_r"], truth["elbow_r"])
    with pytest.raises(InputError, match="weight") as e:
        elbows_at_proportion(truth, 0.0, weight=1.5)
    assert e.value.argument == "weight"
    # the learned table is about the rig's elbows: MakeHuman's women and men lie around it
    assert 0.0 < ELBOW_LANDMARK_WEIGHT < 1.0 and ELBOW_FRACTION["sex"] > 0.0
    sh, length, u = _arm(truth, "l")
    assert abs(float((truth["elbow_l"] - sh) @ u) / length - ELBOW_FRACTION["1"]) < 0.03


def test_offsets_move_each_side_outward_alike() -> None:
    truth = rig_joints()
    moved = apply_offsets(truth, {"knee": {"1": (0.01, -0.02, 0.005)}})
    e = joint_errors(moved, truth)
    assert np.allclose(e["knee_l"], [10, -20, 5], atol=0.05) and np.allclose(e["knee_r"], [10, -20, 5], atol=0.05)
    assert np.allclose(e["ankle_l"], 0.0)
    # the trunk-length term: c_trunk (T - T_ref)
    t = trunk_length(truth)
    assert 0.3 < t < 0.7
    moved = apply_offsets(truth, {"hip": {"trunk": (0.0, 0.1, 0.0)}})
    assert np.allclose(joint_errors(moved, truth)["hip_r"], [0, 100 * (t - TRUNK_REF_M), 0], atol=0.05)
    assert set(JOINT_OFFSETS_M) == {"shoulder", "elbow", "wrist", "hip", "knee", "ankle"}
    assert all(set(row) <= set(OFFSET_PREDICTORS) and "1" in row for row in JOINT_OFFSETS_M.values())


def test_offset_predictors_are_the_build_minus_its_reference() -> None:
    truth = rig_joints()
    m = offset_predictors(truth)
    assert list(m) == list(OFFSET_PREDICTORS) and m["1"] == 1.0
    width = float(np.linalg.norm(truth["hip_l"] - truth["hip_r"]))
    assert np.isclose(m["hip_width"], width - OFFSET_PREDICTORS["hip_width"])
    assert np.isclose(m["trunk"], trunk_length(truth) - TRUNK_REF_M)
    legs = [float(np.linalg.norm(truth[f"hip_{s}"] - truth[f"ankle_{s}"])) for s in "lr"]
    assert np.isclose(m["leg_length"], np.mean(legs) - OFFSET_PREDICTORS["leg_length"])
    # a build measurement whose joints are missing is the reference (0): the other terms still act
    no_ankles = {k: v for k, v in truth.items() if not k.startswith("ankle")}
    assert offset_predictors(no_ankles)["leg_length"] == 0.0
    # a wider pelvis moves the hip by the hip-width coefficient times the extra width, mirrored per side
    wide = {k: v.copy() for k, v in truth.items()}
    frame = body_frame(truth)
    assert frame is not None
    wide["hip_l"] = truth["hip_l"] + frame[0] * 0.005
    wide["hip_r"] = truth["hip_r"] - frame[0] * 0.005
    assert m["hip_width"] + 0.01 < OFFSET_PREDICTOR_RANGE["hip_width"][1]  # inside the clip range
    table = {"hip": {"hip_width": (0.0, -0.5, 0.0)}}
    e = joint_errors(apply_offsets(wide, table), wide)
    assert np.allclose(e["hip_l"], [0, -0.5 * (m["hip_width"] + 0.01) * 1000, 0], atol=0.5)
    assert np.allclose(e["hip_r"], e["hip_l"], atol=1e-6)


def test_an_unknown_offset_predictor_is_refused_by_name() -> None:
    with pytest.raises(InputError, match="knee_height") as e:
        apply_offsets(rig_joints(), {"hip": {"knee_height": (0.0, 0.01, 0.0)}})
    assert e.value.argument == "offsets"
    # refused even when the joints give no body frame (no hips): the table is checked first
    with pytest.raises(InputError, match="knee_height"):
        apply_offsets({"knee_l": np.zeros(3)}, {"hip": {"knee_height": (0.0, 0.01, 0.0)}})


def test_a_build_far_outside_the_cohorts_is_clipped() -> None:
    truth = rig_joints()
    wide = {k: v.copy() for k, v in truth.items()}
    frame = body_frame(truth)
    assert frame is not None
    wide["hip_l"] = truth["hip_l"] + frame[0] * 0.2  # a hip width 40 cm over the true one
    wide["hip_r"] = truth["hip_r"] - frame[0] * 0.2
    assert offset_predictors(wide)["hip_width"] == OFFSET_PREDICTOR_RANGE["hip_width"][1]
    assert offset_predictors(truth)["hip_width"] == pytest.approx(
        float(np.linalg.norm(truth["hip_l"] - truth["hip_r"])) - OFFSET_PREDICTORS["hip_width"])


def test_tables_pool_sides_and_name_the_worst_subject() -> None:
    runs = []
    for i, err in enumerate((5.0, 10.0, 40.0)):
        info = {INFO_KEY: {"knee_l": [err, 0.0, 0.0], "knee_r": [0.0, -err, 0.0]}}
        runs.append(Run(f"subject_{i:03d}", "noer", "bsv", True, info=info))
        runs.append(Run(f"subject_{i:03d}", "noer", "trimesh", True, info=info))  # counted once per scan
    s = summarise(runs)["noer"]
    assert s["knee"]["n"] == 6 and s["all"]["n"] == 6
    assert s["knee"]["median_mm"] == 10.0 and s["knee"]["worst"] == "subject_002 l" and s["knee"]["worst_mm"] == 40.0
    assert np.allclose(s["knee"]["signed_median_mm"], [2.5, -2.5, 0.0])
    md = "\n".join(joints_markdown(runs))
    assert "| knee | 6 | 10.0 |" in md and "subject_002 l" in md
    assert joints_markdown([Run("s", "noer", "bsv", True)]) == []


def test_degraded_captures_are_counted_once_per_scan_by_source() -> None:
    from bsv.bench.joints import WARNINGS_KEY, degraded_captures

    warns = [["back image: left_wrist (visibility 0.72 < 0.75) taken from the other view through the calibration",
              ("front image: right_ankle used with visibility 0.66 < 0.75 (accepted down to the lower threshold 0.50): "
              "check its segment boundaries")], [], [("front image: left_wrist (visibility 0.6 < 0.75) taken from the "
                                                    "hand model's wrist"), ("back image: the person was found only with the image's brightness "
                                                    "scaled 2.2x (the subject is dimly lit: ...)"),
                                                   ("front image: no person found in it (nor in its mirror image, nor "
                                                    "brightened); its landmarks are the back view's ...")]]
    runs = []
    for i, w in enumerate(warns):
        info = {INFO_KEY: {"knee_l": [1.0, 0.0, 0.0]}, WARNINGS_KEY: w}
        runs.append(Run(f"subject_{i:03d}", "noer", "bsv", True, info=info))
        runs.append(Run(f"subject_{i:03d}", "noer", "trimesh", True, info=info))  # counted once per scan
    d = degraded_captures(runs)["noer"]
    assert d == {"captures": 3, "degraded": 2, "warnings": 5,
                 "by_source": {"other view": 1, "lower threshold": 1, "hand model": 1, "image brightened": 1,
                               "view stood in": 1}}
    md = "\n".join(joints_markdown(runs))
    assert "Degraded landmarks, noer: 2 of 3 captures" in md and "1 hand model" in md
    assert degraded_captures([Run("s", "noer", "bsv", True)]) == {}


def test_joint_figure_is_written_only_with_joints(tmp_path) -> None:
    from bsv.bench.joints import FIGURE, joint_figure
    from bsv.bench.output import FIGURE_PATTERNS

    assert FIGURE in FIGURE_PATTERNS  # an existing figure blocks a rerun without --overwrite
    runs = [Run(f"subject_{i:03d}", "noer", "bsv", True, info={INFO_KEY: {"hip_l": [float(i), 2.0, 3.0]}})
            for i in range(4)]
    out = joint_figure(runs, tmp_path / FIGURE)
    assert out is not None and out.stat().st_size > 1000
    assert joint_figure([Run("s", "noer", "bsv", True)], tmp_path / "none.png") is None
    assert not (tmp_path / "none.png").exists()


def test_oracle_joints_replace_only_the_asked_kinds() -> None:
    from bsv.bench.joints import oracle_joint_kinds, with_oracle_joints
    from bsv.frontend.landmarks import JointCentre

    truth = {k: np.asarray(v) for k, v in rig_joints().items()}
    measured = {k: JointCentre(np.asarray(v) + 0.01, 0.8, "front+back") for k, v in truth.items() if k != "knee_r"}
    kinds = oracle_joint_kinds("elbow+knee")
    assert kinds == ("elbow", "knee")
    out = with_oracle_joints(measured, truth, kinds)
    assert set(out) == set(measured)  # a joint the camera path did not place stays missing (knee_r)
    for name, joint in out.items():
        if name.rsplit("_", 1)[0] in kinds:
            assert np.array_equal(joint.xyz, truth[name]) and joint.source == "rig (oracle)"
            assert joint.confidence == 0.8
        else:
            assert joint is measured[name]
    assert np.allclose(measured["elbow_l"].xyz, truth["elbow_l"] + 0.01)  # the measured joints are not touched
    assert oracle_joint_kinds("all") == ("shoulder", "elbow", "wrist", "hip", "knee", "ankle")
    assert oracle_joint_kinds("none") == () and oracle_joint_kinds("") == ()
    assert with_oracle_joints(measured, None, ()) == measured


def test_oracle_joints_name_a_bad_kind_and_need_the_rigs_joints() -> None:
    from bsv.bench.joints import oracle_joint_kinds, with_oracle_joints
    from bsv.errors import BenchError

    with pytest.raises(BenchError, match=r"oracle_joints=elbow\+kne.*unknown: kne"):
        oracle_joint_kinds("elbow+kne")
    with pytest.raises(BenchError, match="standard cohort"):
        with_oracle_joints({}, None, ("elbow",))

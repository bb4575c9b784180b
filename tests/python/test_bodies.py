"""Synthetic MakeHuman bodies: closure, orientation, volumes, symmetry, cross-check numbers, solver, cohort."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]


from meshcheck import edges_closed  # noqa: E402

import bsv.errors  # noqa: E402
from bsv import bodies  # noqa: E402
from bsv.bodies.collide import penetrations, winding_numbers  # noqa: E402
from bsv.bodies.labels import boundary_loops  # noqa: E402
from bsv.bodies.meshio import read_ply  # noqa: E402


@pytest.fixture(scope="module")
def default_body():
    return bodies.make_body()


def test_clean_body_is_watertight_and_outward(default_body):
    b = default_body
    assert edges_closed(b.faces)
    assert b.volume_l > 0
    # outward: a point far outside has winding number 0, the pelvis centre 1
    w = winding_numbers(np.array([[0.0, 0.95, 0.0], [3.0, 1.0, 3.0]]), b.vertices, b.faces)
    assert w[0] == pytest.approx(1.0, abs=1e-6) and w[1] == pytest.approx(0.0, abs=1e-6)
    # Euler characteristic 2 (genus 0)
    ne = len(b.faces) * 3 // 2
    assert len(b.vertices) - ne + len(b.faces) == 2


def test_fourteen_segments_each_one_patch(default_body):
    b = default_body
    assert set(np.unique(b.face_labels)) == set(range(1, 15))
    assert set(np.unique(b.vertex_labels)) == set(range(1, 15))
    # each boundary between two segments is a closed loop; the limb chain has the expected neighbours
    pairs = {(s, t) for s, t, _ in boundary_loops(b.faces, b.face_labels)}
    assert pairs == {(1, 2), (2, 3), (2, 4), (3, 5), (4, 6), (5, 7), (6, 8), (2, 9), (2, 10), (9, 11),
                     (10, 12), (11, 13), (12, 14)}
    # the left segments lie at +X (the subject's left)
    for left, right in ((3, 4), (5, 6), (9, 10), (13, 14)):
        assert b.vertices[b.vertex_labels == left, 0].mean() > 0.05
        assert b.vertices[b.vertex_labels == right, 0].mean() < -0.05


def test_segment_volumes_add_up_to_whole(default_body):
    b = default_body
    v = b.volumes_l()
    segs = [k for k in v if k not in ("whole", "trunk_limbs", "arm_l", "arm_r", "leg_l", "leg_r")]
    assert len(segs) == 14
    assert sum(v[k] for k in segs) == pytest.approx(b.volume_l, rel=1e-12)
    assert v["whole"] == pytest.approx(b.volume_l, rel=1e-12)
    assert v["arm_l"] == pytest.approx(v["upper_arm_l"] + v["forearm_l"])
    assert v["trunk_limbs"] < v["whole"]


def test_volume_of_translated_body_is_unchanged(default_body):
    b = default_body
    shifted = bodies.segment_volumes(b.vertices + np.array([5.0, -2.0, 7.0]), b.faces, b.face_labels)
    orig = bodies.segment_volumes(b.vertices, b.faces, b.face_labels)
    for k in orig:
        assert shifted[k] == pytest.approx(orig[k], rel=1e-9)


def test_left_right_symmetry(default_body):
    v = default_body.volumes_l()
    for seg in ("upper_arm", "forearm", "hand", "thigh", "shin", "foot"):
        assert abs(v[f"{seg}_l"] - v[f"{seg}_r"]) / v[f"{seg}_l"] < 0.005, seg


@pytest.mark.parametrize("gender,stature,litres", [(1.0, 1.73, 63.5), (0.0, 1.59, 48.0), (0.5, 1.66, 55.0)])
def test_cross_check_against_independent_numbers(gender, stature, litres):
    b = bodies.make_body(bodies.Phenotype(gender=gender, age=bodies.Phenotype.age_from_years(25)))
    assert b.stature == pytest.approx(stature, rel=0.02)
    assert b.volume_l == pytest.approx(litres, rel=0.02)
    assert b.vertices[:, 1].min() == pytest.approx(0.0, abs=1e-12)


def test_phenotype_changes_volume_in_the_expected_direction():
    heavy = bodies.make_body(bodies.Phenotype(weight=1.0)).volume_l
    light = bodies.make_body(bodies.Phenotype(weight=0.0)).volume_l
    tall = bodies.make_body(bodies.Phenotype(height=1.0)).stature
    assert heavy > 1.1 * light
    assert tall > 2.2


def test_pose_angles_are_applied():
    a = bodies.load_asset()
    for down in (25.0, 50.0):
        b = bodies.make_body(pose=bodies.Pose.symmetric(arm_down=down, elbow=0.0))
        _v, j = bodies.shape(bodies.Phenotype(), a)
        from bsv.bodies.pose import bone_transforms
        R, T = bone_transforms(j, bodies.Pose.symmetric(arm_down=down, elbow=0.0), a)
        sh, el = (R[a.bone(n)] @ j[a.bone(n), 0] + T[a.bone(n)] for n in ("upperarm01.L", "lowerarm01.L"))
        d = el - sh
        assert np.degrees(np.arctan2(-d[1], d[0])) == pytest.approx(down, abs=1e-6)
        assert b.stature > 1.6


def test_dual_quaternion_pose_keeps_forearm_volume():
    a = bodies.load_asset()
    v, _j = bodies.shape(bodies.Phenotype(), a)
    rest = bodies.segment_volumes(v, a.faces, bodies.make_body().face_labels)
    posed = bodies.make_body().volumes_l()
    assert posed["forearm_l"] == pytest.approx(rest[5] * 1e3, rel=0.03)


def test_stature_bmi_solver():
    ph = bodies.solve_stature_bmi(1.76, 25.0, bodies.Phenotype(gender=0.5))
    b = bodies.make_body(ph)
    assert abs(b.stature - 1.76) < 1e-3
    assert abs(b.bmi - 25.0) < 0.1
    assert ph.muscle <= 0.5
    with pytest.raises(bodies.SolveError):
        bodies.solve_stature_bmi(1.76, 60.0)


def test_bad_inputs_are_rejected():
    with pytest.raises(bodies.PhenotypeError):
        bodies.make_body(bodies.Phenotype(weight=1.5))
    with pytest.raises(bodies.PhenotypeError):
        bodies.make_body(bodies.Phenotype(local={"nose/nose-huge": 0.5}))
    with pytest.raises(bodies.PoseError):
        bodies.make_body(pose=bodies.Pose(arm_down_l=170.0))


def test_local_modifier_moves_its_segment():
    base = bodies.make_body().volumes_l()
    fat = bodies.make_body(bodies.Phenotype(local={"legs/l-upperleg-fat": 1.0})).volumes_l()
    assert fat["thigh_l"] > base["thigh_l"] * 1.05
    assert fat["thigh_r"] == pytest.approx(base["thigh_r"], rel=1e-9)


def test_penetration_check_detects_contact():
    clean = bodies.make_body()
    assert penetrations(clean.vertices, clean.faces, clean.face_labels) == {}
    bad = bodies.make_body(bodies.Phenotype(weight=1.0, muscle=0.0), bodies.Pose.symmetric(80.0, 0.0, -3.0))
    hits = penetrations(bad.vertices, bad.faces, bad.face_labels)
    assert "upper_arm_l/torso" in hits and "thigh_l/thigh_r" in hits


def test_cohort_is_deterministic_and_plausible(tmp_path):
    a = bodies.write_cohort(tmp_path / "a", 2, seed=7)
    b = bodies.write_cohort(tmp_path / "b", 2, seed=7)
    for (pa, ja), (pb, jb) in zip(a, b, strict=True):
        assert pa.read_bytes() == pb.read_bytes()
        assert ja.read_bytes() == jb.read_bytes()
    doc = json.loads(a[0][1].read_text())
    assert json.loads((tmp_path / "a" / "cohort.json").read_text())["arm_down_deg"] == [25.0, 50.0]
    assert doc["subject"]["arm_down_deg"] == [25.0, 50.0]
    assert doc["subject"]["sex"] == "female" and json.loads(a[1][1].read_text())["subject"]["sex"] == "male"
    for _, j in a:
        d = json.loads(j.read_text())
        vol = d["volumes_l"]
        assert {"whole", "trunk_limbs", "arm_l", "arm_r", "leg_l", "leg_r", "torso"} <= set(vol)
        assert 18.3 <= d["subject"]["bmi"] <= 35.2
        assert abs(d["subject"]["stature_m"] - d["subject"]["stature_target_m"]) < 1e-3
        assert d["subject"]["phenotype"]["local"], "local modifiers are on by default"
    v, f, _vl, fl = read_ply(a[0][0])
    s0 = bodies.subject(0, seed=7)
    assert np.array_equal(v, s0.body.vertices) and np.array_equal(fl, s0.body.face_labels)
    assert edges_closed(f)
    vols = bodies.segment_volumes(v, f, fl)
    assert sum(vols.values()) * 1e3 == pytest.approx(doc["volumes_l"]["whole"], rel=1e-6)
    assert penetrations(v, f, fl) == {}
    other = bodies.subject(0, seed=8)
    assert not np.array_equal(other.body.vertices, s0.body.vertices)


#: Arm angles (arm_down_l, arm_down_r) of the default cohort's subjects 0-4 of seed 5 as drawn (check=False),
#: pinned before ``arm_range`` existed: the default range must keep drawing exactly these.
DEFAULT_ARMS_SEED5 = [(48.542005068, 50.0), (48.054584502, 50.0), (29.718649709, 25.507292691),
                      (31.734340477, 28.570516348), (27.057379923, 25.0)]


def test_wide_arm_range_changes_only_the_arms():
    """``arm_range`` draws the arms from a wider A-pose interval with the same random numbers: every
    other draw (sex, local modifiers, elbows, hips) stays, and the default range draws the pinned arms."""
    import dataclasses

    from bsv.bodies import ARM_DOWN_RANGE_DEG, WIDE_ARM_DOWN_RANGE_DEG

    lo, hi = WIDE_ARM_DOWN_RANGE_DEG
    arms = []
    for i, pinned in enumerate(DEFAULT_ARMS_SEED5):
        std = bodies.subject(i, seed=5, check=False)
        assert (round(std.pose.arm_down_l, 9), round(std.pose.arm_down_r, 9)) == pinned, i
        wide = bodies.subject(i, seed=5, check=False, arm_range=WIDE_ARM_DOWN_RANGE_DEG)
        assert wide.phenotype.local == std.phenotype.local and wide.sex == std.sex
        assert dataclasses.replace(wide.pose, arm_down_l=std.pose.arm_down_l,
                                   arm_down_r=std.pose.arm_down_r) == std.pose
        for a in (wide.pose.arm_down_l, wide.pose.arm_down_r):
            assert lo <= a <= hi
            arms.append(a)
        assert std.info()["arm_down_deg"] == list(ARM_DOWN_RANGE_DEG)
        assert wide.info()["arm_down_deg"] == list(WIDE_ARM_DOWN_RANGE_DEG)
    assert min(arms) < ARM_DOWN_RANGE_DEG[0] and max(arms) > ARM_DOWN_RANGE_DEG[1], arms


def test_a_narrow_stance_draws_the_same_subject_with_the_legs_closer():
    """--hip-abduction 0,1.5 keeps every other draw of a subject (sex, modifiers, arms) and only brings the
    thighs closer together; bad ranges are PoseErrors naming the hip abduction."""
    from bsv.bodies import HIP_ABDUCTION_RANGE_DEG, NARROW_HIP_ABDUCTION_RANGE_DEG

    lo, hi = NARROW_HIP_ABDUCTION_RANGE_DEG
    for i in range(3):
        std = bodies.subject(i, seed=5, check=False)
        narrow = bodies.subject(i, seed=5, check=False, leg_range=NARROW_HIP_ABDUCTION_RANGE_DEG)
        assert narrow.phenotype.local == std.phenotype.local and narrow.sex == std.sex
        assert (narrow.pose.arm_down_l, narrow.pose.elbow_r) == (std.pose.arm_down_l, std.pose.elbow_r)
        assert lo <= narrow.pose.hip_abduction_l <= hi and lo <= narrow.pose.hip_abduction_r <= hi
        assert narrow.pose.hip_abduction_l <= std.pose.hip_abduction_l
        assert std.info()["hip_abduction_deg"] == list(HIP_ABDUCTION_RANGE_DEG)
        assert narrow.info()["hip_abduction_deg"] == [lo, hi]
    assert bodies.check_leg_range("0,1.5") == (0.0, 1.5)
    for bad in ((3.0, 1.0), (-2.0, 4.0), (0.0, 25.0), (), "x,y", (math.nan, 2.0)):
        with pytest.raises(bodies.PoseError, match="hip abduction range"):
            bodies.subject(0, seed=5, leg_range=bad)


def test_relaxed_palms_draw_the_same_subject_with_its_palms_turned_in():
    """--palm-in 0,120 keeps every other draw (sex, modifiers, arms, legs) and turns only the forearms and hands, both
    palms near one drawn angle; the default keeps the palms forward (the pinned cohort); one angle (LOW = HIGH) is
    exact; bad ranges are PoseErrors naming the palm range."""
    import dataclasses

    from bsv.bodies import PALM_IN_RANGE_DEG, RELAXED_PALM_IN_RANGE_DEG
    from bsv.bodies.variants import hard_subject
    from bsv.types import SEGMENT_IDS

    lo, hi = RELAXED_PALM_IN_RANGE_DEG
    turns = []
    for i in range(6):
        std = bodies.subject(i, seed=5, check=False)
        assert (std.pose.palm_in_l, std.pose.palm_in_r) == (0.0, 0.0)
        relaxed = bodies.subject(i, seed=5, check=False, palm_range=RELAXED_PALM_IN_RANGE_DEG)
        assert relaxed.phenotype.local == std.phenotype.local and relaxed.sex == std.sex
        assert dataclasses.replace(relaxed.pose, palm_in_l=0.0, palm_in_r=0.0) == std.pose
        pl, pr = relaxed.pose.palm_in_l, relaxed.pose.palm_in_r
        assert lo <= pl <= hi and lo <= pr <= hi and abs(pl - pr) <= 10.0
        turns.append(pl)
        moved = np.linalg.norm(relaxed.body.vertices - std.body.vertices, axis=1)
        arms = np.isin(std.body.vertex_labels, [SEGMENT_IDS[f"{p}_{s}"] for p in ("upper_arm", "forearm", "hand")
                                                for s in "lr"])
        hands = np.isin(std.body.vertex_labels, [SEGMENT_IDS[n] for n in ("hand_l", "hand_r")])
        assert moved[~arms].max() < 1e-3 and (pl < 5.0 or moved[hands].max() > 0.02)  # the body re-solved: microns
        assert std.info()["palm_in_deg"] == list(PALM_IN_RANGE_DEG) and relaxed.info()["palm_in_deg"] == [lo, hi]
    assert max(turns) - min(turns) > 20.0, turns
    fixed = bodies.subject(0, seed=5, check=False, palm_range=(90.0, 90.0))
    assert (fixed.pose.palm_in_l, fixed.pose.palm_in_r) == (90.0, 90.0)
    assert hard_subject(3, seed=5, palm_range=(90.0, 90.0)).pose.palm_in_r == 90.0
    assert bodies.check_palm_range("0,120") == (0.0, 120.0)
    for bad in ((120.0, 0.0), (-40.0, 10.0), (0.0, 200.0), (), "x,y", (math.nan, 2.0)):
        with pytest.raises(bodies.PoseError, match="palm range"):
            bodies.subject(0, seed=5, palm_range=bad)
        with pytest.raises(bodies.PoseError, match="palm range"):
            bodies.cohort(0, palm_range=bad)


def test_a_turned_subject_is_the_same_body_turned_about_the_hips():
    """--turn -10,10 keeps every draw and turns the whole body about the vertical through the hip joints' midpoint:
    the same volumes, the same heights, the hips' midpoint in place; the truth joints turn with it; one angle (LOW =
    HIGH) is exact; bad ranges are PoseErrors naming the turn range."""
    import dataclasses

    from bsv.bodies import TURN_RANGE_DEG, TURNED_RANGE_DEG
    from bsv.bodies.joints import rig_joints

    std = bodies.subject(2, seed=5, check=False)
    assert std.pose.turn_deg == 0.0 and std.info()["turn_deg"] == list(TURN_RANGE_DEG)
    turned = bodies.subject(2, seed=5, check=False, turn_range=(12.0, 12.0))
    assert turned.pose.turn_deg == 12.0 and turned.sex == std.sex
    # the stature and BMI are solved again (to the same values, within the solver's tolerance)
    assert turned.volumes_l()["trunk_limbs"] == pytest.approx(std.volumes_l()["trunk_limbs"], rel=1e-4)
    exact = bodies.make_body(std.phenotype, dataclasses.replace(std.pose, turn_deg=12.0))
    j0, j1 = rig_joints(std.phenotype, std.pose), rig_joints(std.phenotype, exact.pose)
    mid0, mid1 = (j0["hip_l"] + j0["hip_r"]) / 2, (j1["hip_l"] + j1["hip_r"]) / 2
    np.testing.assert_allclose(mid1, mid0, atol=1e-9)
    a = np.radians(12.0)
    turn = np.array([[np.cos(a), 0.0, np.sin(a)], [0.0, 1.0, 0.0], [-np.sin(a), 0.0, np.cos(a)]])
    np.testing.assert_allclose((std.body.vertices - mid0) @ turn.T + mid0, exact.vertices, atol=1e-9)
    np.testing.assert_allclose((j0["wrist_l"] - mid0) @ turn.T + mid0, j1["wrist_l"], atol=1e-9)
    drawn = [bodies.subject(i, seed=5, check=False, turn_range=TURNED_RANGE_DEG).pose.turn_deg for i in range(6)]
    assert all(-10.0 <= t <= 10.0 for t in drawn) and max(drawn) - min(drawn) > 5.0, drawn
    assert bodies.check_turn_range("-10,10") == (-10.0, 10.0)
    for bad in ((10.0, -10.0), (-40.0, 0.0), "x,y", (math.nan, 2.0)):
        with pytest.raises(bodies.PoseError, match="turn range"):
            bodies.subject(0, seed=5, turn_range=bad)


def test_flexed_elbows_draw_the_same_subject_with_its_elbows_bent():
    """--elbow 20,40 keeps every other draw (sex, modifiers, arms, legs, stature) and bends only the elbows, by the
    same random numbers shifted into the range: the forearms and hands move, nothing else; the default keeps the
    cohort as it was; bad ranges are PoseErrors naming the elbow range."""
    import dataclasses

    from bsv.bodies import ELBOW_RANGE_DEG, FLEXED_ELBOW_RANGE_DEG
    from bsv.bodies.variants import hard_subject
    from bsv.types import SEGMENT_IDS

    lo, hi = FLEXED_ELBOW_RANGE_DEG
    for i in range(4):
        std = bodies.subject(i, seed=5, check=False)
        same = bodies.subject(i, seed=5, check=False, elbow_range=ELBOW_RANGE_DEG)
        np.testing.assert_array_equal(same.body.vertices, std.body.vertices)
        bent = bodies.subject(i, seed=5, check=False, elbow_range=FLEXED_ELBOW_RANGE_DEG)
        assert bent.phenotype.local == std.phenotype.local and bent.sex == std.sex
        assert dataclasses.replace(bent.pose, elbow_l=std.pose.elbow_l, elbow_r=std.pose.elbow_r) == std.pose
        assert lo <= bent.pose.elbow_l <= hi and lo <= bent.pose.elbow_r <= hi
        assert bent.pose.elbow_l == pytest.approx(std.pose.elbow_l + 20.0, abs=1e-9) or std.pose.elbow_l in (0.0, 20.0)
        moved = np.linalg.norm(bent.body.vertices - std.body.vertices, axis=1)
        lower = np.isin(std.body.vertex_labels, [SEGMENT_IDS[f"{p}_{s}"] for p in ("forearm", "hand") for s in "lr"])
        legs = np.isin(std.body.vertex_labels, [SEGMENT_IDS[f"{p}_{s}"] for p in ("thigh", "shin", "foot")
                                                for s in "lr"])
        assert moved[legs].max() < 1e-3 and moved[lower].max() > 0.03  # the body re-solved: microns elsewhere
        assert std.info()["elbow_deg"] == list(ELBOW_RANGE_DEG) and bent.info()["elbow_deg"] == [lo, hi]
    assert hard_subject(3, seed=5, elbow_range=(30.0, 30.0)).pose.elbow_r == 30.0
    assert bodies.check_elbow_range("20,40") == (20.0, 40.0)
    for bad in ((40.0, 20.0), (-5.0, 10.0), (0.0, 100.0), "x,y", (math.nan, 2.0)):
        with pytest.raises(bodies.PoseError, match="elbow range"):
            bodies.subject(0, seed=5, elbow_range=bad)
        with pytest.raises(bodies.PoseError, match="elbow range"):
            bodies.cohort(0, elbow_range=bad)


def test_a_bmi_shift_draws_the_same_subject_heavier():
    """--bmi-shift 8 keeps every other draw (sex, stature, modifiers, pose) and solves the body for the drawn BMI
    plus 8; bad shifts are PoseErrors naming the BMI shift."""
    from bsv.bodies import HEAVY_BMI_SHIFT

    std = bodies.subject(1, seed=5, check=False)
    heavy = bodies.subject(1, seed=5, check=False, bmi_shift=HEAVY_BMI_SHIFT)
    assert heavy.sex == std.sex and heavy.stature_target == std.stature_target and heavy.pose == std.pose
    assert heavy.phenotype.local == std.phenotype.local
    assert heavy.bmi_target == pytest.approx(std.bmi_target + HEAVY_BMI_SHIFT, abs=0.3)
    assert heavy.body.volume_l > std.body.volume_l * 1.15
    assert heavy.info()["bmi_shift"] == HEAVY_BMI_SHIFT and std.info()["bmi_shift"] == 0.0
    assert bodies.check_bmi_shift("8") == 8.0
    for bad in (-6.0, 16.0, math.nan, "heavy"):
        with pytest.raises(bodies.PoseError, match="BMI shift"):
            bodies.subject(0, seed=5, bmi_shift=bad)


def test_wide_macros_draw_the_same_subject_with_other_macros():
    """--macros wide keeps every other draw (sex, stature, BMI, modifiers, pose) and maps the same gender, muscle and
    proportions draws onto the wide ranges: a woman on the female half of the gender scale, a man on the male half;
    an unknown name is a PoseError naming the known ones."""
    from bsv.bodies import MACRO_RANGES
    from bsv.bodies.variants import hard_subject

    wide = MACRO_RANGES["wide"]
    for index in (0, 1):
        std = bodies.subject(index, seed=5, check=False)
        w = bodies.subject(index, seed=5, check=False, macros="wide")
        assert w.sex == std.sex and w.stature_target == std.stature_target and w.pose == std.pose
        assert w.bmi_target == std.bmi_target and w.phenotype.local == std.phenotype.local
        lo, hi = wide.gender_female if std.sex == "female" else wide.gender_male
        assert lo <= w.phenotype.gender <= hi and w.phenotype.gender != std.phenotype.gender
        assert wide.proportions[0] <= w.phenotype.proportions <= wide.proportions[1]
        assert w.body.stature == pytest.approx(std.body.stature, abs=0.01)
        assert w.info()["macros"] == "wide" and std.info()["macros"] == "standard"
    assert bodies.check_macros("standard") is MACRO_RANGES["standard"]
    for bad in ("widest", ""):
        with pytest.raises(bodies.PoseError, match=r"macro ranges .*standard, wide"):
            bodies.subject(0, seed=5, macros=bad)
        with pytest.raises(bodies.PoseError, match="macro ranges"):
            hard_subject(0, seed=5, macros=bad)


def test_bad_arm_ranges_are_pose_errors():
    from bsv.bodies.variants import hard_subject

    assert bodies.check_arm_range("15,60") == (15.0, 60.0) == bodies.check_arm_range([15, 60])
    for bad in ((60.0, 15.0), (-5.0, 30.0), (20.0, 95.0), (), (20.0,), (1.0, 2.0, 3.0), "a,b", (math.nan, 30.0)):
        with pytest.raises(bodies.PoseError, match="arm range"):
            bodies.subject(0, seed=5, arm_range=bad)
        with pytest.raises(bodies.PoseError, match="arm range"):
            hard_subject(0, seed=5, arm_range=bad)
        with pytest.raises(bodies.PoseError, match="arm range"):
            bodies.cohort(0, arm_range=bad)


def test_colliding_subject_keeps_its_arms_inside_the_arm_range():
    """Subject 6 of seed 3 has its thighs touching: the legs are spread, the arms (drawn near the
    horizontal, touching nothing) keep their drawn angles; they were once pushed to 10 deg, outside (0, 8).
    The subject's ``arm_down_deg`` reproduces it."""
    drawn = bodies.subject(6, seed=3, check=False, arm_range=(0.0, 8.0)).pose
    s = bodies.subject(6, seed=3, arm_range=(0.0, 8.0))
    assert s.pose.hip_abduction_l > drawn.hip_abduction_l, "the thighs collided: the legs were spread"
    assert (s.pose.arm_down_l, s.pose.arm_down_r) == (drawn.arm_down_l, drawn.arm_down_r)
    assert 0.0 <= s.pose.arm_down_l <= 8.0 and 0.0 <= s.pose.arm_down_r <= 8.0
    info = json.loads(bodies.volumes_json(s))["subject"]
    assert info["arm_down_deg"] == [0.0, 8.0]
    assert bodies.subject(info["index"], info["seed"], arm_range=tuple(info["arm_down_deg"])).pose == s.pose


def test_cohort_files_are_not_overwritten(tmp_path, capsys):
    from bsv.bodies.cohort import main as cohort_main
    from bsv.bodies.errors import OutputExistsError

    (tmp_path / "subject_001.json").write_text("mine")
    with pytest.raises(OutputExistsError, match=r"subject_001\.json") as e:
        bodies.write_cohort(tmp_path, 2, seed=7)
    assert isinstance(e.value, FileExistsError)
    assert not (tmp_path / "subject_000.ply").exists() and not (tmp_path / "cohort.json").exists()
    assert cohort_main([str(tmp_path), "2", "7"]) == 2 and "--overwrite" in capsys.readouterr().err
    assert (tmp_path / "subject_001.json").read_text() == "mine"
    for bad in ("60,15", "15", "a,b"):
        with pytest.raises(SystemExit):
            cohort_main([str(tmp_path), "1", "7", "--overwrite", "--arm-down", bad])
        assert "--arm-down" in capsys.readouterr().err
    cohort_main([str(tmp_path), "1", "7", "--overwrite", "--arm-down", "15,60", "--elbow", "20,40"])
    assert (tmp_path / "cohort.json").is_file() and (tmp_path / "subject_001.json").read_text() == "mine"
    index = json.loads((tmp_path / "cohort.json").read_text())
    assert index["arm_down_deg"] == [15.0, 60.0] and index["elbow_deg"] == [20.0, 40.0]
    written = json.loads((tmp_path / "subject_000.json").read_text())["subject"]
    assert written["arm_down_deg"] == [15.0, 60.0] and written["elbow_deg"] == [20.0, 40.0]
    assert all(15.0 <= written["pose"][k] <= 60.0 for k in ("arm_down_l", "arm_down_r"))
    assert all(20.0 <= written["pose"][k] <= 40.0 for k in ("elbow_l", "elbow_r"))
    with pytest.raises(OutputExistsError, match=r"cohort\.json"):
        bodies.write_cohort(tmp_path, 1, seed=7)
    s = bodies.subject(0, seed=7)
    with pytest.raises(OutputExistsError):
        bodies.write_subject(s, tmp_path)
    bodies.write_subject(s, tmp_path, overwrite=True)


def test_bodies_errors_are_bsv_errors():
    from bsv.bodies.errors import BsvError
    from bsv.bodies.template import TemplateError

    for cls, builtin in ((bodies.PoseError, ValueError), (bodies.PhenotypeError, ValueError),
                         (bodies.SolveError, ValueError), (bodies.LabelError, ValueError),
                         (bodies.AssetError, RuntimeError), (TemplateError, RuntimeError)):
        assert issubclass(cls, BsvError) and issubclass(cls, builtin), cls
    with pytest.raises(BsvError):
        bodies.make_body(bodies.Phenotype(weight=1.5))
    assert BsvError is bsv.errors.BsvError      # the one base class, which the extension raises too

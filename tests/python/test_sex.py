"""The subject's sex on the camera path (bsv.frontend.sex): the measurements on drawn geometry with known
answers, the model's probability and score, a given sex, and the parameters' ranges; the cut lines it moves
(bsv.frontend.segment.label_pixels) on a drawn pose."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from bsv.errors import SegmentationError
from bsv.frontend import sex as sx
from bsv.frontend.segment import POSE_NAMES, SEGMENT_IDS, SegmentParams, label_pixels

TRUNK, SW, HW = 0.5, 0.36, 0.2
FRAME = np.eye(3)  # left, up, forward = the world's x, y, z


def _joints(arm: float = 0.55) -> dict[str, np.ndarray]:
    """Shoulders 0.5 m above the hips, arms hanging straight down: upper arm and forearm ``arm`` / 2 each."""
    out = {}
    for s, x in (("l", 1.0), ("r", -1.0)):
        sh = np.array([x * SW / 2, 1.4, 0.0])
        out[f"shoulder_{s}"] = sh
        out[f"elbow_{s}"] = sh - [0, arm / 2, 0]
        out[f"wrist_{s}"] = sh - [0, arm, 0]
        out[f"hip_{s}"] = np.array([x * HW / 2, 1.4 - TRUNK, 0.0])
    return out


def _slab(front_z: float, back_z: float, bump: float) -> tuple[np.ndarray, np.ndarray]:
    """The front and back surfaces of a torso slab (1 cm grid, within the shoulders), the front raised by
    ``bump`` metres in two round breasts 8 cm to either side of the midline at 0.3 of the trunk below the
    shoulders."""
    xs, ys = np.meshgrid(np.arange(-0.15, 0.1501, 0.005), np.arange(0.95, 1.40, 0.002))
    x, y = xs.ravel(), ys.ravel()
    level = 1.4 - 0.3 * TRUNK
    r = np.minimum(np.hypot(x - 0.08, y - level), np.hypot(x + 0.08, y - level))
    front = np.column_stack([x, y, front_z + bump * np.clip(1 - r / 0.05, 0, 1)])
    back = np.column_stack([x, y, np.full_like(x, back_z)])
    return front, back


def test_the_measurements_of_a_drawn_torso():
    front, back = _slab(0.1, -0.12, 0.03)
    m = sx.sex_measurements(_joints(), FRAME, front, back, stature=1.75)
    assert m["chest_relief"] == pytest.approx(0.03, abs=0.002)  # the breast's top against the flat midline
    assert m["arm_to_stature"] == pytest.approx(0.55 / 1.75)
    assert m["shoulder_to_hip"] == pytest.approx(SW / HW)
    assert m["depth_to_trunk"] == pytest.approx(0.22 / TRUNK, abs=1e-9)  # the slab below the breasts


def test_a_missing_piece_is_nan_and_the_sex_stays_unknown():
    front, back = _slab(0.1, -0.12, 0.0)
    j = _joints()
    del j["wrist_l"]
    m = sx.sex_measurements(j, FRAME, front, back, 1.75)
    assert all(math.isnan(v) for v in m.values())
    assert all(math.isnan(v) for v in sx.sex_measurements(_joints(), None, front, back, 1.75).values())  # no frame
    m = sx.sex_measurements(_joints(), FRAME, front, np.zeros((0, 3)), float("nan"))
    assert math.isnan(m["depth_to_trunk"]) and math.isnan(m["arm_to_stature"]) and np.isfinite(m["chest_relief"])
    est = sx.inferred(m)
    assert est.source == "unknown" and est.score == 0.0 and est.p_female is None and est.gender == 0.5
    assert "not measurable" in est.sentence()


def test_the_probability_follows_the_measurements():
    base = dict(sx.SEX_MODEL["mean"])
    p0 = sx.female_probability(base)
    assert p0 is not None and abs(p0 - 0.5) < 0.02  # the training cohort's mean body is undecided
    more_chest = sx.female_probability({**base, "chest_relief": base["chest_relief"] + 0.01})
    longer_arms = sx.female_probability({**base, "arm_to_stature": base["arm_to_stature"] + 0.02})
    broader = sx.female_probability({**base, "shoulder_to_hip": base["shoulder_to_hip"] + 0.3})
    assert more_chest > p0 > longer_arms and p0 > broader
    woman = sx.inferred({**base, "chest_relief": 0.035, "arm_to_stature": 0.30, "shoulder_to_hip": 1.7,
                         "depth_to_trunk": 0.42})
    assert woman.sex == "female" and woman.p_female > sx.NAMED_AT
    assert woman.score == pytest.approx(2 * woman.p_female - 1) and woman.gender == pytest.approx(1 - woman.p_female)
    undecided = sx.inferred({**base, "chest_relief": base["chest_relief"] + 0.002})
    assert undecided.sex is None and 0 < undecided.score < 0.5
    record = woman.to_json()
    assert record["source"] == "inferred" and set(record["measurements"]) == set(sx.SEX_MEASUREMENTS)
    assert "read from the capture as female" in sx.describe(record)
    assert sx.template_gender(woman) == pytest.approx(woman.gender)


def test_a_given_sex_is_a_full_score():
    assert sx.given("female").score == 1.0 and sx.given("male").score == -1.0
    assert sx.given("male").gender == 1.0 and sx.template_gender(sx.given("male")) is None
    assert sx.from_score(-1.0).sex == "male" and sx.from_score(0.25).sex is None
    assert sx.describe(sx.given("female").to_json()) == "Sex: female, as given."
    with pytest.raises(SegmentationError, match="give one of"):
        sx.given("other")
    with pytest.raises(SegmentationError, match=r"sex_score must lie in \[-1, 1\]"):
        sx.from_score(1.5)


@pytest.mark.parametrize("bad", [{"sex_score": 2.0}, {"sex_score": -1.01}, {"knee_shift_sex": -0.01},
                                 {"hip_raise_sex": 0.2}, {"elbow_shift_sex": -0.01}, {"groin_offset_sex": 0.3}])
def test_the_sex_parameters_are_range_checked(bad):
    with pytest.raises(SegmentationError, match="sex"):
        SegmentParams(**bad)


def _standing_pose() -> np.ndarray:
    """33 landmarks (pixels) of a person 600 px tall facing the camera, the subject's left on the image's right."""
    p = {"nose": (200, 60), "left_ear": (215, 60), "right_ear": (185, 60),
         "left_shoulder": (245, 120), "right_shoulder": (155, 120), "left_elbow": (275, 210),
         "right_elbow": (125, 210), "left_wrist": (290, 290), "right_wrist": (110, 290),
         "left_pinky": (293, 305), "right_pinky": (107, 305), "left_index": (290, 308), "right_index": (110, 308),
         "left_thumb": (285, 302), "right_thumb": (115, 302), "left_hip": (225, 300), "right_hip": (175, 300),
         "left_knee": (228, 450), "right_knee": (172, 450), "left_ankle": (230, 590), "right_ankle": (170, 590),
         "left_heel": (230, 600), "right_heel": (170, 600), "left_foot_index": (240, 610),
         "right_foot_index": (160, 610)}
    out = np.zeros((len(POSE_NAMES), 3))
    for i, n in enumerate(POSE_NAMES):
        out[i] = [*p.get(n, (200, 60)), 1.0]
    return out


def test_the_sex_moves_the_knee_line_and_the_hip_corners():
    """A woman's knee line lies lower and her outer hip corners lower than a man's; the average body's lie
    between; a score of 0 is the plain rule. Below the hands only thigh, shin and torso pixels change."""
    h, w = 640, 400
    mask = np.zeros((h, w), bool)
    mask[55:615, 100:300] = True
    pose = _standing_pose()
    base = SegmentParams(knee_shift_sex=0.03, hip_raise_sex=0.05)
    lab = {s: label_pixels(mask, pose, [None, None], SegmentParams(**{**base.__dict__, "sex_score": s}))
           for s in (1.0, 0.0, -1.0)}
    plain = label_pixels(mask, pose, [None, None], SegmentParams(knee_shift_sex=0.0, hip_raise_sex=0.0))
    assert np.array_equal(lab[0.0], plain)
    shin = {s: int(np.isin(v, [SEGMENT_IDS["shin_l"], SEGMENT_IDS["shin_r"]]).sum()) for s, v in lab.items()}
    assert shin[1.0] < shin[0.0] < shin[-1.0]
    torso = {s: int((v == SEGMENT_IDS["torso"]).sum()) for s, v in lab.items()}
    assert torso[1.0] > torso[0.0] > torso[-1.0]  # a woman's hip corners lower: more torso
    changed = lab[1.0] != lab[-1.0]
    changed[:330] = False  # the drawn hands hang at the hips: the torso polygon's corners trade with them
    kinds = {SEGMENT_IDS[k] for k in ("thigh_l", "thigh_r", "shin_l", "shin_r", "torso")}
    assert set(np.unique(lab[1.0][changed])) <= kinds and set(np.unique(lab[-1.0][changed])) <= kinds


def test_the_sex_moves_the_elbow_and_groin_lines():
    """A woman's elbow line lies further towards the wrist (fewer forearm pixels) and her groin line lower (more
    torso, fewer thigh pixels) than a man's; a score of 0 is the plain rule. Only the upper arms, forearms,
    torso and thighs change."""
    h, w = 640, 400
    mask = np.zeros((h, w), bool)
    mask[55:615, 100:300] = True
    pose = _standing_pose()
    base = SegmentParams(elbow_shift_sex=0.05, groin_offset_sex=0.05, groin_angle=30.0, knee_shift_sex=0.0,
                         hip_raise_sex=0.0)
    crotch = np.array([200.0, 330.0])
    lab = {s: label_pixels(mask, pose, [None, None], dataclasses.replace(base, sex_score=s), crotch=crotch)
           for s in (1.0, 0.0, -1.0)}
    plain = label_pixels(mask, pose, [None, None], dataclasses.replace(base, elbow_shift_sex=0.0, groin_offset_sex=0.0),
                         crotch=crotch)
    assert np.array_equal(lab[0.0], plain)

    def count(v: np.ndarray, *names: str) -> int:
        return int(np.isin(v, [SEGMENT_IDS[n] for n in names]).sum())

    fore = {s: count(v, "forearm_l", "forearm_r") for s, v in lab.items()}
    assert fore[1.0] < fore[0.0] < fore[-1.0]
    thigh = {s: count(v, "thigh_l", "thigh_r") for s, v in lab.items()}
    assert thigh[1.0] < thigh[0.0] < thigh[-1.0]
    changed = lab[1.0] != lab[-1.0]
    kinds = {SEGMENT_IDS[k] for k in ("upper_arm_l", "upper_arm_r", "forearm_l", "forearm_r", "thigh_l", "thigh_r",
                                      "torso")}
    assert set(np.unique(lab[1.0][changed])) <= kinds and set(np.unique(lab[-1.0][changed])) <= kinds


def test_a_heavy_build_moves_the_elbow_and_groin_lines():
    """A build beyond the hinge (build_score > build_hinge) puts the elbow line further towards the wrist and the
    groin line lower; a build at or below the hinge is the plain rule; only the arms', thighs' and torso's labels
    change. The build score is the trunk's depth in the cohort's sds, clipped to the sex model's range, 0 when
    not measured; out-of-range scores and terms are refused."""
    h, w = 640, 400
    mask = np.zeros((h, w), bool)
    mask[55:615, 100:300] = True
    pose = _standing_pose()
    base = SegmentParams(elbow_shift_build=0.02, groin_offset_build=0.02, build_hinge=1.0, groin_angle=30.0,
                         knee_shift_sex=0.0, hip_raise_sex=0.0, sex_score=0.0)
    crotch = np.array([200.0, 330.0])
    lab = {b: label_pixels(mask, pose, [None, None], dataclasses.replace(base, build_score=b), crotch=crotch)
           for b in (4.0, 2.0, 1.0, -2.0)}
    plain = label_pixels(mask, pose, [None, None], dataclasses.replace(
        base, elbow_shift_build=0.0, groin_offset_build=0.0, build_score=4.0), crotch=crotch)
    assert np.array_equal(lab[1.0], plain) and np.array_equal(lab[-2.0], plain)

    def count(v: np.ndarray, *names: str) -> int:
        return int(np.isin(v, [SEGMENT_IDS[n] for n in names]).sum())

    fore = {b: count(v, "forearm_l", "forearm_r") for b, v in lab.items()}
    torso = {b: count(v, "torso") for b, v in lab.items()}
    assert fore[4.0] < fore[2.0] < fore[1.0] and torso[4.0] > torso[2.0] > torso[1.0]
    kinds = {SEGMENT_IDS[k] for k in ("upper_arm_l", "upper_arm_r", "forearm_l", "forearm_r", "thigh_l", "thigh_r",
                                      "torso")}
    changed = lab[4.0] != lab[1.0]
    assert set(np.unique(lab[4.0][changed])) <= kinds and set(np.unique(lab[1.0][changed])) <= kinds
    mean, scale = sx.SEX_MODEL["mean"]["depth_to_trunk"], sx.SEX_MODEL["scale"]["depth_to_trunk"]
    assert sx.build_score({"depth_to_trunk": mean + scale}) == pytest.approx(1.0)
    assert sx.build_score({"depth_to_trunk": 9.0}) == sx.build_score({"depth_to_trunk": sx.SEX_MODEL["range"]["depth_to_trunk"][1]})
    assert sx.build_score({}) == 0.0 and sx.build_score({"depth_to_trunk": float("nan")}) == 0.0
    for bad in ({"build_score": 11.0}, {"elbow_shift_build": 0.2}, {"groin_offset_build": -0.06}, {"build_hinge": 9.0}):
        with pytest.raises(SegmentationError):
            SegmentParams(**bad)


def test_the_shipped_lines_follow_a_heavy_build():
    """Both views' defaults move the elbow and groin lines for a build beyond the hinge; the build score goes
    into the sex record of volumes.json."""
    from bsv.frontend.segment import DEFAULT_PARAMS

    for p in DEFAULT_PARAMS.values():
        assert p.elbow_shift_build > 0 and p.groin_offset_build > 0 and p.build_hinge >= 0.5
    mean, scale = sx.SEX_MODEL["mean"]["depth_to_trunk"], sx.SEX_MODEL["scale"]["depth_to_trunk"]
    rec = sx.inferred({**sx.SEX_MODEL["mean"], "depth_to_trunk": mean + 2 * scale}).to_json()
    assert rec["build_score"] == pytest.approx(2.0)


def test_a_measurement_far_outside_the_cohort_counts_as_its_edge():
    """A shoulder width three times the hips' (a hip landmark centimetres off) weighs no more than the edge of
    the training range does."""
    base = dict(sx.SEX_MODEL["mean"])
    edge = sx.SEX_MODEL["range"]["shoulder_to_hip"][1]
    assert sx.female_probability({**base, "shoulder_to_hip": 3.0}) == sx.female_probability(
        {**base, "shoulder_to_hip": edge})

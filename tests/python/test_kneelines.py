"""The knee lines moved by the body's proportions (bsv.frontend.kneelines): the features, the shift and the recut."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from bsv.frontend import kneelines as kl
from bsv.frontend.intrinsics import Intrinsics
from bsv.frontend.landmarks import Camera
from bsv.frontend.segment import POSE_NAMES, SEGMENT_IDS, Segmentation, knee_line, view_params

FX = 600.0
DEPTH_M = 2.0


def _joints(thigh: float = 0.40, shin: float = 0.40) -> dict[str, np.ndarray]:
    """An upright body's joint centres (metres; x to its left, y up), the legs ``thigh`` and ``shin`` long."""
    j = {}
    for s, x in (("l", 0.09), ("r", -0.09)):
        ankle = np.array([x, 0.08, 0.0])
        j[f"ankle_{s}"] = ankle
        j[f"knee_{s}"] = ankle + np.array([0.0, shin, 0.0])
        j[f"hip_{s}"] = ankle + np.array([0.0, shin + thigh, 0.0])
        j[f"shoulder_{s}"] = j[f"hip_{s}"] + [x, 0.58, 0.0]
        j[f"wrist_{s}"] = j[f"shoulder_{s}"] + [0.25 * np.sign(x), -0.45, 0.0]
    return j


def test_proportions_are_scale_free_and_need_every_joint():
    j = _joints()
    p = kl.proportions(j)
    assert p is not None and p["thigh_fraction"] == pytest.approx(0.5)
    assert p["leg_over_trunk"] == pytest.approx(0.8 / 0.58)
    assert p["hip_width_over_leg"] == pytest.approx(0.18 / 0.8)
    twice = kl.proportions({k: 2 * v for k, v in j.items()})
    assert twice is not None and all(twice[k] == pytest.approx(p[k]) for k in p)
    assert kl.proportions({k: v for k, v in j.items() if k != "knee_r"}) is None
    assert kl.proportions({**j, "wrist_l": np.array([np.nan, 0.0, 0.0])}) is None


def test_a_body_whose_knee_loop_is_predicted_distal_has_its_knee_lines_raised():
    """A longer thigh (the same leg) predicts the fitted knee loop further down the leg: the line moves up (a
    negative shift), by the prediction's departure from the model's mean, at most MAX_SHIFT_MM."""
    segs: dict = {}
    even = kl.knee_line_shift_mm(_joints(), segs)
    long_thigh = kl.knee_line_shift_mm(_joints(thigh=0.43, shin=0.37), segs)
    assert even is not None and long_thigh is not None
    assert long_thigh < even
    coef = kl.KNEE_LOOP_MODEL["coef"]["thigh_fraction"]
    assert even - long_thigh == pytest.approx(coef * (0.43 / 0.80 - 0.5), rel=1e-6)
    # a thigh fraction beyond the training range counts as its end; a steeper model is clipped at MAX_SHIFT_MM
    top = kl.KNEE_LOOP_MODEL["range"]["thigh_fraction"][1]
    extreme = kl.knee_line_shift_mm(_joints(thigh=0.60, shin=0.20), segs)
    assert extreme is not None and even - extreme == pytest.approx(coef * (top - 0.5), rel=1e-6)
    steep = {**kl.KNEE_LOOP_MODEL, "coef": {**kl.KNEE_LOOP_MODEL["coef"], "thigh_fraction": 10 * coef}}
    assert kl.knee_line_shift_mm(_joints(thigh=0.60, shin=0.20), segs, model=steep) == -kl.MAX_SHIFT_MM
    assert kl.knee_line_shift_mm(_joints(), segs, gain=0.0) == 0.0
    assert kl.knee_line_shift_mm({k: v for k, v in _joints().items() if k != "ankle_l"}, segs) is None


def _view() -> tuple[Segmentation, Camera]:
    """A front view of two vertical legs (columns 280-300 and 340-360), labelled at the line
    :func:`knee_line` draws, and its camera (world = camera frame, the knees 2 m deep)."""
    h, w = 600, 640
    pose = np.zeros((33, 3))
    pose[:, 2] = 1.0
    at = {"left_shoulder": (370, 100), "right_shoulder": (270, 100), "left_hip": (350, 250), "right_hip": (290, 250),
          "left_knee": (350, 380), "right_knee": (290, 380), "left_ankle": (350, 510), "right_ankle": (290, 510)}
    for name, xy in at.items():
        pose[POSE_NAMES.index(name), :2] = xy
    prm = view_params("front")
    point, down = knee_line(pose, prm)
    labels = np.zeros((h, w), dtype=np.uint8)
    rows = np.arange(h)[:, None]
    below = (rows - point[1]) * down[1] > 0
    for lo, hi, s in ((340, 360, "l"), (280, 300, "r")):
        band = np.zeros((h, w), dtype=bool)
        band[250:520, lo:hi] = True
        labels[band & ~below] = SEGMENT_IDS[f"thigh_{s}"]
        labels[band & below] = SEGMENT_IDS[f"shin_{s}"]
    seg = Segmentation(labels=labels, mask=labels > 0, landmarks=np.zeros((71, 3)), view="front", pose=pose)
    cam = Camera(Intrinsics(w, h, FX, FX, w / 2, h / 2), np.eye(3), np.zeros(3))
    return seg, cam


def test_a_recut_moves_the_thigh_shin_line_by_the_millimetres_at_the_knees_depth():
    seg, cam = _view()
    joints = {f"knee_{s}": np.array([0.0, 0.0, DEPTH_M]) for s in "lr"}
    shin_ids = [SEGMENT_IDS["shin_l"], SEGMENT_IDS["shin_r"]]
    before = int(np.isin(seg.labels, shin_ids).sum())
    up = kl.recut_knee_lines({"front": seg}, joints, {"front": cam}, -10.0)["front"]
    px = 10e-3 * FX / DEPTH_M  # 3 px
    gained = int(np.isin(up.labels, shin_ids).sum()) - before
    assert gained == pytest.approx(2 * 20 * px, abs=2 * 20)  # 3 rows of both 20-px legs, within a row
    assert gained > 0
    assert ((up.labels == SEGMENT_IDS["shin_l"]) | (up.labels == SEGMENT_IDS["thigh_l"])).sum() == (
        (seg.labels == SEGMENT_IDS["shin_l"]) | (seg.labels == SEGMENT_IDS["thigh_l"])).sum()  # sides kept
    assert (up.labels[seg.labels == 0] == 0).all()
    assert up.knee_line_shift_mm == -10.0 and seg.knee_line_shift_mm is None
    same = kl.recut_knee_lines({"front": seg}, joints, {"front": cam}, None)["front"]
    assert same is seg


def test_a_view_without_its_knee_landmarks_or_in_front_of_the_knees_keeps_its_line():
    seg, cam = _view()
    joints = {f"knee_{s}": np.array([0.0, 0.0, DEPTH_M]) for s in "lr"}
    pose = seg.pose.copy()
    pose[POSE_NAMES.index("left_knee"), :2] = np.nan
    blind = dataclasses.replace(seg, pose=pose)
    assert kl.recut_knee_lines({"front": blind}, joints, {"front": cam}, -10.0)["front"] is blind
    behind = {f"knee_{s}": np.array([0.0, 0.0, -DEPTH_M]) for s in "lr"}
    assert kl.recut_knee_lines({"front": seg}, behind, {"front": cam}, -10.0)["front"] is seg

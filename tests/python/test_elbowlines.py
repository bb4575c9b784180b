"""The elbow lines moved by the elbows' flexion (bsv.frontend.elbowlines): the geometry and the recut."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bsv.frontend import elbowlines as el
from bsv.frontend.intrinsics import Intrinsics
from bsv.frontend.landmarks import Camera
from bsv.frontend.segment import POSE_NAMES, SEGMENT_IDS, Segmentation, elbow_line, view_params

FX = 600.0
DEPTH_M = 2.0


FORWARD = np.array([0.0, 0.0, 1.0])


def _arm(bend_deg: float, towards: np.ndarray = FORWARD) -> tuple[np.ndarray, ...]:
    """Shoulder, elbow and wrist centres (metres) of an arm hanging straight down from (0.2, 1.4, 2) and bent
    ``bend_deg`` at the elbow towards ``towards`` (unit, across the arm)."""
    sh, elbow = np.array([0.2, 1.4, DEPTH_M]), np.array([0.2, 1.1, DEPTH_M])
    a = math.radians(bend_deg)
    return sh, elbow, elbow + 0.25 * (np.array([0.0, -math.cos(a), 0.0]) + math.sin(a) * towards)


def test_the_shift_is_the_bisecting_planes_tilt_at_the_radius_less_the_reference_bend():
    """Seen along the bend (the camera behind the forearm's swing, which the view sees from the olecranon's side) the
    bisecting plane crosses the surface a radius r towards the camera r tan(bend / 2) past the joint: the shift is
    that less the reference bend's, towards the wrist; the camera on the other side gets it towards the shoulder.
    Within the reference bend, or bent across the line of sight, nothing moves; beyond the clip, the clip."""
    behind, ahead = np.array([0.2, 1.1, 0.0]), np.array([0.2, 1.1, 4.0])
    r, ref = 0.07, el.REFERENCE_FLEXION_DEG
    expected = 1000.0 * r * (math.tan(math.radians(15.0)) - math.tan(math.radians(ref / 2)))
    assert el.flexion_deg(*_arm(30.0)) == pytest.approx(30.0)
    assert el.flexion_shift_mm(*_arm(30.0), behind, r) == pytest.approx(expected, rel=1e-3)
    assert el.flexion_shift_mm(*_arm(30.0), ahead, r) == pytest.approx(-expected, rel=1e-3)
    assert el.flexion_shift_mm(*_arm(ref - 1.0), behind, r) == 0.0
    assert el.flexion_shift_mm(*_arm(30.0), behind, 0.0) == 0.0
    sideways = el.flexion_shift_mm(*_arm(30.0, np.array([1.0, 0.0, 0.0])), behind, r)
    assert abs(sideways) < 0.05 * expected
    assert el.flexion_shift_mm(*_arm(89.0), behind, 1.0) == el.MAX_SHIFT_MM
    sh, elbow, wrist = _arm(30.0)
    assert el.flexion_shift_mm(sh, elbow, wrist + np.nan, behind, r) == 0.0


def _view(view: str) -> tuple[Segmentation, Camera]:
    """A view of a vertical arm (columns 290-310, rows 100-400; the shoulder, elbow and wrist landmarks at rows 100,
    250 and 400), labelled at the line :func:`elbow_line` draws, and its camera at the world's origin looking
    along +z (the arm 2 m deep)."""
    h, w = 500, 640
    pose = np.zeros((33, 3))
    pose[:, 2] = 1.0
    at = {"left_shoulder": (300, 100), "left_elbow": (300, 250), "left_wrist": (300, 400),
          "right_shoulder": (200, 100), "right_elbow": (200, 250), "right_wrist": (200, 400)}
    for name, xy in at.items():
        pose[POSE_NAMES.index(name), :2] = xy
    point, normal = elbow_line(pose, "left", view_params(view))
    labels = np.zeros((h, w), dtype=np.uint8)
    band = np.zeros((h, w), dtype=bool)
    band[100:400, 290:310] = True
    rows = np.arange(h)[:, None]
    past = (rows - point[1]) * normal[1] > 0
    labels[band & ~past] = SEGMENT_IDS["upper_arm_l"]
    labels[band & past] = SEGMENT_IDS["forearm_l"]
    seg = Segmentation(labels=labels, mask=labels > 0, landmarks=np.zeros((71, 3)), view=view, pose=pose)
    return seg, Camera(Intrinsics(w, h, FX, FX, w / 2, h / 2), np.eye(3), np.zeros(3))


def test_a_bent_arm_seen_from_the_olecranons_side_has_its_line_moved_towards_the_wrist():
    """The back view of an arm bent 30 deg away from its camera: the line moves towards the wrist by the shift's
    pixels at the elbow's depth, the arm keeps its pixels and the other side (no joints) its labels; the front view
    (no radius) and an arm within the reference bend keep their lines."""
    sh, elbow, wrist = _arm(30.0)
    joints = {"shoulder_l": sh, "elbow_l": elbow, "wrist_l": wrist}
    seg, cam = _view("back")
    moved = el.recut_elbow_lines({"back": seg}, joints, {"back": cam})["back"]
    shift = el.flexion_shift_mm(sh, elbow, wrist, cam.translation, el.ELBOW_RADIUS_M["back"])
    assert shift > 5.0 and moved.elbow_line_shift_mm == (round(shift, 2), 0.0)
    fore = SEGMENT_IDS["forearm_l"]
    lost = int((seg.labels == fore).sum() - (moved.labels == fore).sum())
    px = shift / 1000.0 * FX / DEPTH_M
    assert lost == pytest.approx(20 * px, abs=20)  # whole rows of the 20-px arm, within a row
    assert ((moved.labels > 0) == (seg.labels > 0)).all()
    assert el.ELBOW_RADIUS_M["front"] == 0.0
    front, _ = _view("front")
    assert el.recut_elbow_lines({"front": front}, joints, {"front": cam})["front"] is front
    straight = dict(zip(("shoulder_l", "elbow_l", "wrist_l"), _arm(5.0), strict=True))
    assert el.recut_elbow_lines({"back": seg}, straight, {"back": cam})["back"] is seg
    assert el.recut_elbow_lines({"back": seg}, {}, {"back": cam})["back"] is seg

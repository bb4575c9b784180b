"""The elbow lines moved by the elbows' flexion (the camera path).

**Why.** Each view decides upper arm against forearm by a line through MediaPipe's elbow landmark, across the
arm (:func:`bsv.frontend.segment.elbow_line`), tuned on arms bent 0-20 deg. The anatomical boundary is a plane
through the elbow joint that bisects the upper arm's and the forearm's directions; on a bent arm it tilts, so on
the surface a camera sees it lies off the joint along the arm: by about the elbow's radius times the tangent of
half the flexion, towards the hand on the side the forearm bends away from (the back view of an arm bent
forwards) and towards the shoulder on the other. A 2-D line across the arm cannot see that. With the elbows bent
20 deg more than the cohort's, the back view's line, at MediaPipe's landmark on the olecranon, stayed 11-12 mm
short of the true boundary, while the front view's landmark (the crook of the elbow) followed it; the camera path's
forearms came out +1.4 to +2.1 % signed (noer), the oracle labels' did not move (BENCH.md, round 2 session 45).

**The correction.** :func:`flexion_shift_mm` takes the bisecting plane from the 3-D joint centres and gives, per
view, how far along the arm it crosses the surface the camera sees (:data:`ELBOW_RADIUS_M` off the joint
towards the camera), less the same for an arm bent :data:`REFERENCE_FLEXION_DEG` in the same plane (what the
lines' constants were tuned for): 0 for an arm bent no more than that. The radius is an effective one per view,
learned from the rig's true labels by ``benchmarks/learn_elbow_lines.py``: 0 for the front view, whose landmark
follows the boundary. :func:`recut_elbow_lines` moves each view's line by it, after the joint centres.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from typing import Any

import numpy as np

from ..keypoints import joint_xyz as _xyz
from ..types import SEGMENT_IDS
from .segment import Segmentation, drawn_params, elbow_line

#: The elbow's effective radius per view (metres): how far in front of the joint, towards the camera, the
#: boundary the view draws is taken to lie.
ELBOW_RADIUS_M: dict[str, float] = {"front": 0.0, "back": 0.07}
#: The flexion (degrees) the elbow lines' constants were tuned for: the standard cohort's elbows are bent 0-20.
REFERENCE_FLEXION_DEG = 10.0
#: An elbow bent less than this (degrees) keeps its line: the plane of the bend is not defined.
MIN_FLEXION_DEG = 2.0
#: The largest move of an elbow line (mm): a prediction beyond it is clipped.
MAX_SHIFT_MM = 25.0


def _unit(v: np.ndarray) -> np.ndarray:
    n = float(np.linalg.norm(v))
    return v / n if n > 0 else v


def _rotated(v: np.ndarray, axis: np.ndarray, angle: float) -> np.ndarray:
    """``v`` rotated by ``angle`` (radians) about the unit ``axis`` (Rodrigues)."""
    return v * np.cos(angle) + np.cross(axis, v) * np.sin(angle) + axis * (axis @ v) * (1.0 - np.cos(angle))


def flexion_deg(shoulder: np.ndarray, elbow: np.ndarray, wrist: np.ndarray) -> float:
    """The elbow's flexion (degrees; 0 straight) from three joint centres."""
    u, f = _unit(elbow - shoulder), _unit(wrist - elbow)
    return float(np.degrees(np.arccos(np.clip(u @ f, -1.0, 1.0))))


def flexion_shift_mm(shoulder: np.ndarray, elbow: np.ndarray, wrist: np.ndarray, camera_m: np.ndarray,
                     radius_m: float, reference_deg: float = REFERENCE_FLEXION_DEG) -> float:
    """How far (mm, + towards the wrist) the elbow's bisecting plane crosses the surface a camera at ``camera_m``
    sees (``radius_m`` off the joint towards it), less the same for the arm bent ``reference_deg`` in the same
    plane; 0 within :data:`MIN_FLEXION_DEG` of straight or at or below the reference, clipped to
    +-:data:`MAX_SHIFT_MM`. Joint centres and the camera's centre in metres, one frame."""
    if not all(np.all(np.isfinite(p)) for p in (shoulder, elbow, wrist, camera_m)):
        return 0.0
    u, f = _unit(elbow - shoulder), _unit(wrist - elbow)
    bend = flexion_deg(shoulder, elbow, wrist)
    if bend < max(MIN_FLEXION_DEG, reference_deg):
        return 0.0
    axis = _unit(np.cross(u, f))
    f_ref = _rotated(u, axis, np.radians(reference_deg))
    d = _unit(elbow - camera_m)  # from the camera to the elbow: the surface it sees lies -radius * d off the joint

    def along(forearm: np.ndarray) -> float:  # a surface point J + s forearm - radius d on the plane
        normal = _unit(u + forearm)
        return float(radius_m * (normal @ d) / max(normal @ forearm, 1e-6))

    shift = along(f) - along(f_ref)
    return float(np.clip(shift * 1000.0, -MAX_SHIFT_MM, MAX_SHIFT_MM))


def recut_elbow_lines(segs: Mapping[str, Segmentation], joints: Mapping[str, Any], cameras: Mapping[str, Any],
                      **params: Any) -> dict[str, Segmentation]:
    """Each view's segmentation with each side's upper-arm / forearm line moved along the arm by
    :func:`flexion_shift_mm` for that camera (the line :func:`bsv.frontend.segment.elbow_line` draws, for the view's
    parameters with ``params`` set and the segmentation's sex): every pixel of that side labelled upper arm or
    forearm takes the side of the moved line. The millimetres become pixels at the elbow's depth in that camera
    (``joints``: the joint centres, :class:`bsv.frontend.landmarks.JointCentre` or arrays; ``cameras``:
    calibrated :class:`bsv.frontend.landmarks.Camera`); each records the shifts (``elbow_line_shift_mm``). A side
    whose joints are missing, or a view without its landmarks or the elbow in front of it, keeps its line."""
    return {v: _recut_view(seg, cameras.get(v), joints, ELBOW_RADIUS_M.get(v, 0.0), **params)
            for v, seg in segs.items()}


def _recut_view(seg: Segmentation, cam: Any, joints: Mapping[str, Any], radius_m: float,
                **params: Any) -> Segmentation:
    """:func:`recut_elbow_lines` of one view, seen by ``cam`` (None: unknown) with the effective ``radius_m``."""
    if seg.pose is None or cam is None or not radius_m:
        return seg
    prm = drawn_params(seg, **params)
    centre = np.asarray(cam.translation, dtype=np.float64)
    labels, shifts = None, [0.0, 0.0]
    for k, (side, s) in enumerate((("left", "l"), ("right", "r"))):
        names = (f"shoulder_{s}", f"elbow_{s}", f"wrist_{s}")
        if not all(n in joints for n in names):
            continue
        sh, el, wr = (_xyz(joints[n]) for n in names)
        shift = flexion_shift_mm(sh, el, wr, centre, radius_m)
        depth = float((el - centre) @ cam.rotation[:, 2])
        point, normal = elbow_line(seg.pose, side, prm)
        if not shift or not (np.isfinite(depth) and depth > 0.0 and np.all(np.isfinite(point))):
            continue
        point = point + normal * (shift / 1000.0) * cam.intrinsics.fx / depth
        labels = seg.labels.copy() if labels is None else labels
        upper, fore = SEGMENT_IDS[f"upper_arm_{s}"], SEGMENT_IDS[f"forearm_{s}"]
        ys, xs = np.nonzero((labels == upper) | (labels == fore))
        past = (np.column_stack([xs, ys]) - point) @ normal > 0
        labels[ys, xs] = np.where(past, fore, upper)
        shifts[k] = round(shift, 2)
    return seg if labels is None else dataclasses.replace(seg, labels=labels, elbow_line_shift_mm=(shifts[0], shifts[1]))


__all__ = ["ELBOW_RADIUS_M", "MAX_SHIFT_MM", "MIN_FLEXION_DEG", "REFERENCE_FLEXION_DEG", "flexion_deg",
           "flexion_shift_mm", "recut_elbow_lines"]

"""The knee lines moved by the body's proportions (the camera path).

**Why.** A shin's volume follows where the fitted mesh's knee loop lands: -0.5 % per mm distal (BENCH.md,
round 2 session 37). The camera path places that loop through the thigh / shin line each view draws near
MediaPipe's knees (:func:`bsv.frontend.segment.label_pixels`, ``knee_shift``). Where the template's knee loop
lies against what MediaPipe sees moves with the body's proportions and build: over 240 fits of the standard and
the wide-macro cohorts (``bsv bench synth --macros wide``, noer), MakeHuman's muscle and proportions macros
correlate +0.47 and +0.44 with the loop's shift, and a muscular body's knee loop came out up to 17 mm distal (its shin
-5 %). The two knees share one line (the mid-knee's), so the shift is common to both legs (left and right
correlate 0.93).

**The correction.** :data:`KNEE_LOOP_MODEL` predicts the fitted knee loop's shift (mm, + distal) from
proportions of the capture's joint centres (:func:`proportions`: scale-free, so neither the stature nor the
camera's distance enters) and the build (:func:`bsv.frontend.sex.build_score`), a least-squares fit learned by
``benchmarks/learn_knee_lines.py``. :func:`recut_knee_lines` moves each view's thigh / shin line by
:data:`KNEE_LINE_GAIN` times the prediction's departure from the training cohort's mean, towards the hip when
the loop is predicted distal: the mean placement, which the cut lines' constants were tuned for, stays.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from typing import Any

import numpy as np

from ..keypoints import joint_xyz as _xyz
from ..types import SEGMENT_IDS
from .segment import Segmentation, drawn_params, knee_line
from .sex import build_score

#: The scale-free proportions of the joint centres :data:`KNEE_LOOP_MODEL` takes (:func:`proportions`), then
#: the build.
FEATURES: tuple[str, ...] = ("thigh_fraction", "leg_over_trunk", "hip_width_over_leg", "shoulder_width_over_leg",
                             "arm_over_leg", "build")
#: The fitted knee loop's shift (mm, + distal of the true loop) as ``"1" + sum coef_k * clip(x_k, range_k)``;
#: ``mean`` is the prediction's mean over the training fits (what :func:`recut_knee_lines` leaves in place).
#: Learned by ``benchmarks/learn_knee_lines.py`` (see there for the cohorts; BENCH.md, round 2 session 41).
KNEE_LOOP_MODEL: dict[str, Any] = {
    "1": -49.16,
    "coef": {"thigh_fraction": 79.76, "leg_over_trunk": -6.167, "hip_width_over_leg": -40.87,
             "shoulder_width_over_leg": 38.9, "arm_over_leg": 28.6, "build": -0.7074},
    "range": {"thigh_fraction": (0.4267, 0.5561), "leg_over_trunk": (1.529, 1.955), "hip_width_over_leg": (0.1807, 0.3385),
              "shoulder_width_over_leg": (0.2879, 0.5498), "arm_over_leg": (0.5244, 0.6493), "build": (-3.375, 5.409)},
    "mean": 1.731,
}
#: The knee line moves by this times the predicted loop shift's departure from its mean (1: by as much).
KNEE_LINE_GAIN = 1.0
#: The largest move of a knee line (mm): a prediction beyond it is clipped (a landmark centimetres off must
#: not carry the line with it).
MAX_SHIFT_MM = 15.0


def _dist(joints: Mapping[str, np.ndarray], a: str, b: str) -> float:
    return float(np.linalg.norm(joints[a] - joints[b]))


def proportions(joints: Mapping[str, Any]) -> dict[str, float] | None:
    """The scale-free proportions of joint centres by name (metres; :data:`FEATURES` but the build): the thigh's
    share of the leg (hip-knee over hip-knee plus knee-ankle, each the mean of the sides), the leg (hip-ankle)
    over the trunk (mid-hip to mid-shoulder), and the hip width, the shoulder width and the arm (shoulder-wrist)
    over the leg. ``joints``: :class:`bsv.frontend.landmarks.JointCentre` or arrays. None when a joint is
    missing or not finite, or a length is zero."""
    need = [f"{k}_{s}" for k in ("shoulder", "wrist", "hip", "knee", "ankle") for s in "lr"]
    if any(n not in joints for n in need):
        return None
    joints = {n: _xyz(joints[n]) for n in need}
    if not all(np.all(np.isfinite(p)) for p in joints.values()):
        return None
    thigh = float(np.mean([_dist(joints, f"hip_{s}", f"knee_{s}") for s in "lr"]))
    shin = float(np.mean([_dist(joints, f"knee_{s}", f"ankle_{s}") for s in "lr"]))
    leg = float(np.mean([_dist(joints, f"hip_{s}", f"ankle_{s}") for s in "lr"]))
    arm = float(np.mean([_dist(joints, f"shoulder_{s}", f"wrist_{s}") for s in "lr"]))
    trunk = float(np.linalg.norm((joints["shoulder_l"] + joints["shoulder_r"] - joints["hip_l"] - joints["hip_r"]) / 2))
    if min(thigh + shin, leg, trunk) <= 0.0:
        return None
    return {"thigh_fraction": thigh / (thigh + shin), "leg_over_trunk": leg / trunk,
            "hip_width_over_leg": _dist(joints, "hip_l", "hip_r") / leg,
            "shoulder_width_over_leg": _dist(joints, "shoulder_l", "shoulder_r") / leg, "arm_over_leg": arm / leg}


def predicted_loop_mm(features: Mapping[str, float], model: Mapping[str, Any] | None = None) -> float:
    """:data:`KNEE_LOOP_MODEL`'s (or ``model``'s) knee loop shift (mm, + distal) for ``features``
    (:data:`FEATURES`), each clipped to the model's range."""
    m = KNEE_LOOP_MODEL if model is None else model
    out = float(m["1"])
    for k in FEATURES:
        lo, hi = m["range"][k]
        out += float(m["coef"][k]) * float(np.clip(features[k], lo, hi))
    return out


def knee_line_shift_mm(joints: Mapping[str, Any], segs: Mapping[str, Segmentation],
                       model: Mapping[str, Any] | None = None, gain: float = KNEE_LINE_GAIN) -> float | None:
    """How far (mm) the knee lines move towards the feet (negative: towards the hips) for the capture's joint
    centres and its segmentations' build: minus ``gain`` times the predicted loop shift's departure from the
    model's mean, within +-:data:`MAX_SHIFT_MM`. None when the proportions cannot be taken."""
    feats = proportions(joints)
    if feats is None:
        return None
    sex = next((s.sex for s in segs.values() if s.sex is not None), None)
    feats["build"] = build_score(sex.measurements) if sex is not None else 0.0
    m = KNEE_LOOP_MODEL if model is None else model
    shift = -gain * (predicted_loop_mm(feats, m) - float(m["mean"]))
    return float(np.clip(shift, -MAX_SHIFT_MM, MAX_SHIFT_MM))


def recut_knee_lines(segs: Mapping[str, Segmentation], joints: Mapping[str, Any], cameras: Mapping[str, Any],
                     shift_mm: float | None, **params: Any) -> dict[str, Segmentation]:
    """Each view's segmentation with its thigh / shin line moved ``shift_mm`` towards the feet (the line
    :func:`bsv.frontend.segment.label_pixels` drew, for the view's parameters with ``params`` set and the
    segmentation's sex): every pixel labelled a thigh or a shin takes the side's thigh above the moved line
    and its shin below it. The millimetres become pixels at the knees' depth in that camera (``joints``: the
    joint centres, :class:`bsv.frontend.landmarks.JointCentre` or arrays; ``cameras``: calibrated
    :class:`bsv.frontend.landmarks.Camera`); each records the shift (``knee_line_shift_mm``). Unchanged when
    ``shift_mm`` is None or 0, or without knees; a view whose knee landmarks are not placed, or that does not
    see the knees in front of it, keeps its line."""
    if not shift_mm or any(f"knee_{s}" not in joints for s in "lr"):
        return dict(segs)
    knees = np.mean([_xyz(joints[f"knee_{s}"]) for s in "lr"], axis=0)
    out = {}
    for v, seg in segs.items():
        if seg.pose is None or v not in cameras:
            out[v] = seg
            continue
        cam = cameras[v]
        depth = float((knees - cam.translation) @ cam.rotation[:, 2])
        point, down = knee_line(seg.pose, drawn_params(seg, **params))
        if not (np.isfinite(depth) and depth > 0.0 and np.all(np.isfinite(point))):
            out[v] = seg  # the knees not in front of this camera, or its landmarks not placed: its line stays
            continue
        point = point + down * (shift_mm / 1000.0) * cam.intrinsics.fx / depth
        labels = seg.labels.copy()
        ys, xs = np.nonzero(np.isin(labels, [SEGMENT_IDS[f"{k}_{s}"] for k in ("thigh", "shin") for s in "lr"]))
        below = (np.column_stack([xs, ys]) - point) @ down > 0
        left = np.isin(labels[ys, xs], [SEGMENT_IDS["thigh_l"], SEGMENT_IDS["shin_l"]])
        labels[ys, xs] = np.where(left, np.where(below, SEGMENT_IDS["shin_l"], SEGMENT_IDS["thigh_l"]),
                                  np.where(below, SEGMENT_IDS["shin_r"], SEGMENT_IDS["thigh_r"]))
        out[v] = dataclasses.replace(seg, labels=labels, knee_line_shift_mm=round(float(shift_mm), 2))
    return out


def with_proportional_knee_lines(segs: Mapping[str, Segmentation], joints: Mapping[str, Any],
                                 cameras: Mapping[str, Any], **params: Any) -> dict[str, Segmentation]:
    """The camera path's step (``bsv process`` and ``bsv bench synth`` alike): each view's knee line moved by
    :func:`knee_line_shift_mm` of the capture's joint centres (:func:`recut_knee_lines`)."""
    return recut_knee_lines(segs, joints, cameras, knee_line_shift_mm(joints, segs), **params)


__all__ = ["FEATURES", "KNEE_LINE_GAIN", "KNEE_LOOP_MODEL", "MAX_SHIFT_MM", "knee_line_shift_mm", "predicted_loop_mm",
           "proportions", "recut_knee_lines", "with_proportional_knee_lines"]

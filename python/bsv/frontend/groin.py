"""Where each thigh begins, from the crotch the depth images show (the camera path's hip-loop targets).

On the camera path a thigh's volume follows its boundary loop with the torso: -0.5 % of the thigh per mm the
loop lies distal (benchmarks/BENCH.md, round 2 session 36). The registration carries the template's own loop
there, and where it lands scatters by 4-4.5 mm (sd) against 1.2-1.6 mm with oracle labels; the fitted crotch's
height explains two thirds of that scatter, because both cameras see the crotch edge-on and few points hold it
up or down. MediaPipe's person mask is too soft between the thighs to say where the crotch is (sd 7 mm), but
the depth images are sharp there: the top of the gap between the legs, where the body's depth gives way to the
background's, lies 29 mm (sd 7) above MakeHuman's crotch on the rig's renders of the cohort, and the sex and
the build explain most of that spread (residual sd 3 mm).

So :func:`crotch_from_depth` finds that gap's top in each view (:func:`bsv.frontend.segment.gap_top` on the
depth's own silhouette of the body, in the box between the knees below the hips that the 2-D landmarks span),
lifts it at the body's depth just above it and averages the views; :func:`hip_loop_targets` places each
thigh's loop centre (the centre of the ring of thigh vertices next to the torso,
:data:`bsv.keypoints.BOUNDARY_RINGS`) at the learned offset :data:`HIP_LOOP_OFFSETS_M` from it, in the body
frame, for the capture's sex and build and the measured thighs' length. ``bsv process`` and ``bsv bench synth
--segmentation camera`` give them to the registration with the measured joints, and its keypoint term pulls
each template loop's centre up or down to its target, along the body's up axis only (:class:`LoopTarget`).

No target is given (and the registration does as before) where the crotch is not seen: thighs that touch
below it in either view (the gap opens lower than :func:`bsv.frontend.segment.expected_crotch_depth` allows,
the rule of :func:`bsv.frontend.segment.agreeing_crotches`, or lower than the measured hips and thighs put the
crotch by more than :data:`CROTCH_LOW_MARGIN_M`), no gap, views that disagree by more than
:data:`CROTCH_VIEWS_DISAGREE_M`, a missing hip or knee, or no depth at the gap. Such thighs are less certain
(:func:`hip_loop_extra_sd` widens their intervals; ``bsv process`` says so, :data:`NO_TARGET_WARNING`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from .landmarks import Camera, JointCentre, body_frame
from .segment import (
    CROTCH_DEPTH_SENSITIVITY,
    CROTCH_TOUCH_MARGIN,
    POSE_NAMES,
    VIEWS,
    Segmentation,
    body_axes,
    expected_crotch_depth,
    gap_top,
    thigh_angle_deg,
)
from .sex import build_score

#: The depth's silhouette of the body: pixels whose point lies within this horizontal distance (metres) of the
#: hips' midpoint (the wall and anything beside the subject lie farther) ...
BODY_RADIUS_M = 0.4
#: ... and at least this high above the floor (metres).
ABOVE_FLOOR_M = 0.03
#: The gap's top is lifted at the median depth of the body's pixels in this many rows above it, within this
#: many columns either side.
LIFT_WINDOW_PX: tuple[int, int] = (4, 4)
#: The two views' crotches disagree when their heights differ by more than this (metres; on the rig's renders
#: the front view's lies 2 mm below the back's, sd 3 mm).
CROTCH_VIEWS_DISAGREE_M = 0.02
#: How far below the measured hips' midpoint the crotch the depth shows is expected (metres, along the body's
#: up axis): ``"1"`` plus ``"sex"`` per unit of the sex score plus ``"thigh"`` per metre of the measured thighs'
#: length (hip to knee, the mean of both). Learned with :data:`HIP_LOOP_OFFSETS_M` (residual sd 5.2 mm on the
#: training subjects, 5.0 held out).
CROTCH_BELOW_HIPS: dict[str, float] = {"1": 0.0234, "sex": 0.0031, "thigh": 0.1349}
#: A crotch lower than :data:`CROTCH_BELOW_HIPS` expects by more than this (metres; three sds of its residual)
#: is where thighs that touch below the crotch part, not the crotch: on a narrow stance (seed 0, feet nearly
#: together) two subjects' lay 25 and 39 mm low, and their thighs' loops, pulled there, came out 7 % small.
CROTCH_LOW_MARGIN_M = 0.015
#: Where each thigh's loop centre lies from the measured crotch, in the body frame (metres: lateral, outward
#: from the midline; up; forward): ``"1"`` plus ``"sex"`` per unit of the capture's sex score (+1 a woman, -1 a
#: man) plus ``"build"`` per unit of its build score (:func:`bsv.frontend.sex.build_score`) plus ``"thigh"`` per
#: metre of the measured thighs' length (:func:`thigh_length`). Learned by
#: ``benchmarks/learn_hip_loops.py`` on the 60 subjects of seeds 11-16 (room, noer; one whose crotch lay beyond
#: :data:`CROTCH_LOW_MARGIN_M` left out): held out (seeds 0 and 2) the height scatters 3.1 mm (sd) around it, 3.5
#: without the thighs' length, 4.4 with the constant alone. Only the height is pulled
#: (:class:`LoopTarget`), and the target is set :data:`HIP_LOOP_PULL_RAISE_M` higher.
HIP_LOOP_OFFSETS_M: dict[str, tuple[float, float, float]] = {
    "1": (0.0670, 0.0030, 0.0262), "sex": (0.0028, -0.0010, 0.0092), "build": (0.0009, 0.0005, 0.0020),
    "thigh": (0.0594, 0.0493, -0.0560)}
#: How much higher than the learned place the target is set (metres, along the body's up axis): the pulled loop stops short of its target, 1-2 mm distal of it on average, held by the points and the
#: template's stiffness. Of -2, 0 and +2 mm on the camera path's room seeds 0-1 (noer and l515), +2 mm
#: brought the loops' mean nearest 0 and the thighs' mean error lowest (benchmarks/BENCH.md, round 2 session 38).
HIP_LOOP_PULL_RAISE_M = 0.002
#: The confidence a hip-loop target pulls with (the keypoint term's per-keypoint weight, 0..1).
HIP_LOOP_CONFIDENCE = 1.0
#: Where no hip-loop target is given (the crotch not seen: thighs that touch, mostly the heaviest bodies), the
#: thighs' loops follow the 2-D labels' crotch alone, as uncertain as a crotch depth with this sd (a fraction of
#: the hip-knee length, through :data:`bsv.frontend.segment.CROTCH_DEPTH_SENSITIVITY`). Measured on session 41's
#: engine (benchmarks/BENCH.md, round 2 session 42; 500 camera-path captures of the room, the wide macros, the
#: heavier cohort and the looks): the thighs' log errors scatter 0.031-0.035 (rms) without a target against the
#: error model's 0.0255 and 0.020 with one, so their 95 % intervals held 86-91 % of the truths against 99 %;
#: 0.045 adds the difference (0.020 to a thigh).
NO_TARGET_CROTCH_SD = 0.045
#: The sd a capture without hip-loop targets adds to the quantities its thighs' boundaries move, in the error
#: models' comparison space (natural log): :data:`NO_TARGET_CROTCH_SD` times
#: :data:`bsv.frontend.segment.CROTCH_DEPTH_SENSITIVITY`.
NO_TARGET_SD: dict[str, float] = {k: NO_TARGET_CROTCH_SD * v for k, v in CROTCH_DEPTH_SENSITIVITY.items()}


@dataclass(frozen=True)
class LoopTarget:
    """Where the registration is to put a segment boundary's centre: a height along the body's axis (the
    keypoint term pulls the template's boundary ring along ``direction`` alone)."""

    #: (3,) metres, world frame; only its component along ``direction`` is measured.
    xyz: np.ndarray
    #: The keypoint term's weight for it (0..1).
    confidence: float
    #: How it was found, e.g. "front+back depth (crotch)".
    source: str
    #: (3,) unit vector, world frame: the body's up axis.
    direction: np.ndarray

    def to_json(self) -> dict[str, object]:
        """``{"xyz", "confidence", "source", "direction"}`` (rounded)."""
        return {"xyz": [round(float(c), 5) for c in self.xyz], "confidence": round(float(self.confidence), 3),
                "source": self.source, "direction": [round(float(c), 5) for c in self.direction]}


@dataclass(frozen=True)
class Crotch:
    """The crotch the depth images show: the top of the gap between the legs, lifted to the world frame."""

    #: (3,) metres, world frame: the mean of the views'.
    xyz: np.ndarray
    #: Each view's lifted gap top.
    views: dict[str, np.ndarray]


def _sex_and_build(segs: Mapping[str, Segmentation]) -> tuple[float, float]:
    """The capture's sex score and build score (:mod:`bsv.frontend.sex`; both views hold the same estimate),
    0 and 0 without one."""
    sex = next((s.sex for s in segs.values() if s.sex is not None), None)
    return (0.0, 0.0) if sex is None else (float(sex.score), build_score(sex.measurements))


def _view_gap_top(seg: Segmentation, depth: np.ndarray, camera: Camera, hips_mid: np.ndarray) -> np.ndarray | None:
    """One view's crotch (world, metres): the top of the gap between the legs in the depth's silhouette of the
    body, lifted at the body's depth just above it; None without the gap, with thighs that touch below the
    crotch, or without depth there."""
    if seg.pose is None:
        return None
    P = {n: seg.pose[i, :2].astype(np.float64) for i, n in enumerate(POSE_NAMES)}
    if not all(np.all(np.isfinite(P[n])) for n in ("left_hip", "right_hip", "left_knee", "right_knee",
                                                   "left_shoulder", "right_shoulder")):
        return None
    d = np.asarray(depth, dtype=np.float64)
    h, w = d.shape
    _, h_mid, down, lat = body_axes(P)
    span = float(((P["left_knee"] + P["right_knee"]) / 2 - h_mid) @ down)
    if not span > 1.0:
        return None
    # the box the gap is searched in (the 2-D landmarks'), and the depth's silhouette of the body inside it
    x0, x1 = sorted((float(P["left_knee"][0]), float(P["right_knee"][0])))
    y0, y1 = float(h_mid[1]), max(float(P["left_knee"][1]), float(P["right_knee"][1]))
    r0, r1 = int(max(0, math.floor(y0))), int(min(h, math.ceil(y1) + 1))
    c0, c1 = int(max(0, math.floor(x0))), int(min(w, math.ceil(x1) + 1))
    if r1 - r0 < 4 or c1 - c0 < 4:
        return None
    body = np.zeros((h, w), dtype=bool)
    ys, xs = np.nonzero(d[r0:r1, c0:c1] > 0)
    ys, xs = ys + r0, xs + c0
    if len(ys) == 0:
        return None
    pts = np.asarray(camera.deproject(np.column_stack([xs, ys]).astype(np.float64), d[ys, xs]))
    near = (np.hypot(pts[:, 0] - hips_mid[0], pts[:, 2] - hips_mid[2]) < BODY_RADIUS_M) & (pts[:, 1] > ABOVE_FLOOR_M)
    body[ys[near], xs[near]] = True
    top = gap_top(body, x0, x1, y0, y1)
    if top is None:
        return None
    spread = (thigh_angle_deg(P["left_hip"], P["left_knee"], down, lat)
              + thigh_angle_deg(P["right_hip"], P["right_knee"], down, -lat)) / 2
    sex = seg.sex.score if seg.sex is not None else 0.0
    expected = expected_crotch_depth(seg.view, sex, spread if math.isfinite(spread) else 0.0)
    if float((top - h_mid) @ down) / span > expected + CROTCH_TOUCH_MARGIN:
        return None  # the thighs touch below the crotch: the gap opens lower
    gx, gy = round(float(top[0])), round(float(top[1]))
    dy, dx = LIFT_WINDOW_PX
    a0, b0, b1 = max(gy - dy, 0), max(gx - dx, 0), min(gx + dx + 1, w)
    above = d[a0:gy, b0:b1][body[a0:gy, b0:b1]]
    if len(above) == 0:
        return None
    return np.asarray(camera.deproject(np.array([[top[0], top[1] - 0.5]]), np.array([float(np.median(above))]))[0])


def crotch_from_depth(segs: Mapping[str, Segmentation], depths: Mapping[str, np.ndarray],
                      cameras: Mapping[str, Camera], joints: Mapping[str, JointCentre],
                      gate: bool = True) -> Crotch | None:
    """The crotch both views' depth images show (see the module notes), or None where it is not seen: a view
    without the gap's top (or whose thighs touch below the crotch) gives none, two views that disagree by more
    than :data:`CROTCH_VIEWS_DISAGREE_M` give none; one view alone gives its own; a crotch lower than the hips and
    the thighs' length put it by more than :data:`CROTCH_LOW_MARGIN_M` (:func:`expected_crotch_below_hips`) gives
    none (``gate`` False skips that check: the learning script's raw reading). ``joints``: the capture's joint
    centres (:func:`bsv.frontend.landmarks.joint_centres`), for the hips' midpoint."""
    if "hip_l" not in joints or "hip_r" not in joints:
        return None
    hips_mid = (np.asarray(joints["hip_l"].xyz) + np.asarray(joints["hip_r"].xyz)) / 2
    found: dict[str, np.ndarray] = {}
    for v in VIEWS:
        if v in segs and v in depths and v in cameras:
            p = _view_gap_top(segs[v], depths[v], cameras[v], hips_mid)
            if p is not None and np.all(np.isfinite(p)):
                found[v] = p
    if not found:
        return None
    if len(found) == 2 and abs(found["front"][1] - found["back"][1]) > CROTCH_VIEWS_DISAGREE_M:
        return None
    crotch = Crotch(np.mean(list(found.values()), axis=0), found)
    if gate:
        frame = body_frame({k: np.asarray(j.xyz) for k, j in joints.items()})
        expected = expected_crotch_below_hips(joints, _sex_and_build(segs)[0])
        if frame is not None and expected is not None \
                and float((hips_mid - crotch.xyz) @ frame[1]) > expected + CROTCH_LOW_MARGIN_M:
            return None
    return crotch


def thigh_length(joints: Mapping[str, JointCentre]) -> float | None:
    """The measured thighs' length (metres, hip to knee, the mean of both sides), or None without both hips and
    knees."""
    if any(f"{k}_{s}" not in joints for k in ("hip", "knee") for s in "lr"):
        return None
    return float(np.mean([np.linalg.norm(np.asarray(joints[f"hip_{s}"].xyz) - np.asarray(joints[f"knee_{s}"].xyz))
                          for s in "lr"]))


def expected_crotch_below_hips(joints: Mapping[str, JointCentre], sex_score: float,
                               table: Mapping[str, float] | None = None) -> float | None:
    """How far below the measured hips' midpoint the crotch the depth shows is expected (metres, along the
    body's up axis; :data:`CROTCH_BELOW_HIPS` or ``table``), or None without both hips and knees."""
    thigh = thigh_length(joints)
    if thigh is None:
        return None
    t = CROTCH_BELOW_HIPS if table is None else table
    return float(t["1"]) + float(t["sex"]) * float(sex_score) + float(t["thigh"]) * thigh


def hip_loop_offsets(sex_score: float, build: float, thigh: float,
                     table: Mapping[str, tuple[float, float, float]] | None = None) -> np.ndarray:
    """The left thigh's loop target from the crotch in the body frame (metres: lateral outward, up, forward):
    :data:`HIP_LOOP_OFFSETS_M` (or ``table``) at this sex score, build score and thighs' length (metres), raised
    by :data:`HIP_LOOP_PULL_RAISE_M`; the right thigh's mirrors the lateral component."""
    t = HIP_LOOP_OFFSETS_M if table is None else table
    out = np.asarray(t["1"], dtype=np.float64) + float(sex_score) * np.asarray(t["sex"], dtype=np.float64) \
        + float(build) * np.asarray(t["build"], dtype=np.float64) + float(thigh) * np.asarray(t["thigh"], dtype=np.float64)
    out[1] += HIP_LOOP_PULL_RAISE_M
    return out


def hip_loop_targets(segs: Mapping[str, Segmentation], depths: Mapping[str, np.ndarray],
                     cameras: Mapping[str, Camera], joints: Mapping[str, JointCentre],
                     table: Mapping[str, tuple[float, float, float]] | None = None) -> dict[str, LoopTarget]:
    """Targets of the thighs' loop centres (``hip_loop_l``, ``hip_loop_r``; :data:`bsv.keypoints.BOUNDARY_RINGS`)
    from the crotch the depth images show (:func:`crotch_from_depth`), for the registration's keypoint term:
    heights along the body's up axis (the measured joints' body frame); empty where the crotch is not seen or
    the body frame (hips and shoulders) or the thighs' length is not measured."""
    crotch = crotch_from_depth(segs, depths, cameras, joints)
    frame = body_frame({k: np.asarray(j.xyz) for k, j in joints.items()})
    thigh = thigh_length(joints)
    if crotch is None or frame is None or thigh is None:
        return {}
    off = hip_loop_offsets(*_sex_and_build(segs), thigh, table)
    source = "+".join(crotch.views) + " depth (crotch)"
    out = {}
    for name, lateral in (("hip_loop_l", 1.0), ("hip_loop_r", -1.0)):
        local = np.array([lateral * off[0], off[1], off[2]])
        out[name] = LoopTarget(crotch.xyz + frame.T @ local, HIP_LOOP_CONFIDENCE, source, frame[1].copy())
    return out


def hip_loop_extra_sd(targets: Mapping[str, LoopTarget]) -> dict[str, float]:
    """The sd (comparison space, per quantity) the thighs' boundaries add to the intervals when the capture has
    no hip-loop targets (:func:`hip_loop_targets` gave none): :data:`NO_TARGET_SD`; none when it has them."""
    return {} if targets else dict(NO_TARGET_SD)


#: What ``volumes.json`` and the report say when a camera capture has no hip-loop targets.
NO_TARGET_WARNING = ("thighs: the crotch was not seen in the depth images (the thighs touch, or the views disagree), "
                     "so the thighs' boundaries with the torso follow the colour images' labels alone; their "
                     "intervals are widened")


__all__ = [
    "ABOVE_FLOOR_M",
    "BODY_RADIUS_M",
    "CROTCH_BELOW_HIPS",
    "CROTCH_LOW_MARGIN_M",
    "CROTCH_VIEWS_DISAGREE_M",
    "HIP_LOOP_CONFIDENCE",
    "HIP_LOOP_OFFSETS_M",
    "HIP_LOOP_PULL_RAISE_M",
    "LIFT_WINDOW_PX",
    "NO_TARGET_CROTCH_SD",
    "NO_TARGET_SD",
    "NO_TARGET_WARNING",
    "Crotch",
    "LoopTarget",
    "crotch_from_depth",
    "expected_crotch_below_hips",
    "hip_loop_extra_sd",
    "hip_loop_offsets",
    "hip_loop_targets",
    "thigh_length",
]

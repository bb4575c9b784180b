"""Both camera views together: landmarks filled in across views, and 3-D joint centres.

**No capture thrown away for one landmark.** :func:`segment_views` runs MediaPipe on the front and back
images, then makes every required landmark (shoulders, elbows, wrists, hips, knees, ankles) of each view
usable, in this order (:func:`bsv.frontend.segment.resolve_landmarks`):

1. seen confidently in this view (visibility >= ``min_visibility``, the paper's 0.75);
2. seen confidently in the OTHER view: lifted to 3-D there (on its ray, halfway in depth between the
   person's surface around it and the surface this view's depth shows behind it: the middle of the limb;
   :func:`_lift_across`) and projected into this image through the calibration (both cameras' intrinsics
   and extrinsics);
3. for a wrist, the hand model's wrist (MediaPipe Holistic's hand landmark 0);
4. this view's own landmark, if its visibility is at least the documented lower threshold
   ``fallback_visibility`` (0.5).

A landmark seen confidently but not repeatably in one view (its image and mirror-image detections lie
centimetres apart while the other view's agree: :func:`unrepeatable_landmarks`, the same test that leaves
a view out of a joint centre) is also taken from the other view, for the labels as for the joints: a dim
back view lit from one side put both wrists 160 px from where its mirror image put them. So is a leg
landmark (hip, knee, ankle) that the two views, lifted to 3-D, place at heights more than
:data:`VIEWS_DISAGREE_M` apart, from the view whose height lies farther from where the body's proportions
put that landmark (:func:`implausible_landmarks`): a back view whose dark lower legs merged with a dark
floor put the ankles 10-30 cm up the shins and a knee at mid-thigh, repeatably, while the front view had
them right.

**A view without a person.** When MediaPipe finds nobody in one image, not in its mirror image and not
brightened either (:func:`bsv.frontend.segment.detect`), the other view stands in for it
(:func:`detection_from_other_view`): its landmarks, lifted to the middle of the body between the two
views' surfaces and projected through the calibration, and its person mask from its own depth, with a
warning. Only a capture with no person in either view fails (:class:`bsv.errors.PersonNotFoundError`).

**Ankles at the body's proportions.** The shin/foot line of each view is drawn at its ankle landmark, and
the knee line a fraction of the knee-ankle length below the knees; MediaPipe's ankle height scatters by
12 mm (sd) against the rig's ankle joint, which itself sits at 0.043 of the stature with sd 3.4 mm. So,
once resolved, each view's ankle landmarks are moved to the height above the floor that
``SegmentParams.ankle_height`` gives as a fraction of the stature (read from the depth:
:func:`person_stature`), keeping their place across (:func:`place_ankles`); the joint centres take the
moved ankles too. Once the labels are drawn, each leg's shin and foot pixels are split again in 3-D
(:func:`cut_feet_at_ankle_plane`): below :data:`ANKLE_PLANE`, a height above the floor at the ankle that
rises towards the toes (the body's own ankle loop lies 91 mm up, sd 4 mm, on every body of the cohort; the
stature and the sex read from the capture place it within 2 mm), foot; above it, shin. The 2-D line stays
where there is no depth or no stature.

Every substitute is a warning naming the landmark (:attr:`Segmentation.warnings`, the volumes JSON's
``warnings``, the report). Only a landmark that none of these gives (in practice: a limb not seen in
either view) fails, with :class:`bsv.errors.LimbMissingError` naming the limb and what to do.

**Joint centres in 3-D.** :func:`joint_centres` lifts the 2-D joints of both views to the world frame:
per view, the surface point under the landmark (the median depth of that side's pixels of the two
segments meeting at the joint, within :data:`DEPTH_RADIUS_PX`); seen from both views, the centre is the
midpoint of the front and back surface points (the joint lies midway between the two opposite surfaces
of the limb's cross-section); seen usably by one view only, the surface point pushed along the ray by the
limb's half-thickness. An offset per joint kind in the body's own frame, linear in the body's measurements
(trunk length; for the hip and the shoulder also the hip and shoulder widths and the leg length:
:data:`JOINT_OFFSETS_M`, learned on synthetic subjects, see there), then moves MediaPipe's landmark to the
anatomical joint centre. Along the arm MediaPipe's elbow scatters more than the arm's proportions do: each
elbow is moved along its shoulder-to-wrist line most of the way to the place :data:`ELBOW_FRACTION` gives for
the sex read from the capture (:func:`elbows_at_proportion`; across the arm, where the flexion shows, it
stays where it was lifted).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import InputError, LimbMissingError, PersonNotFoundError, PoseTooSmallError, SegmentationError
from ..keypoints import JOINT_NAMES
from .intrinsics import Intrinsics
from .segment import (
    EXPECTED_CROTCH_SD,
    POSE_NAMES,
    REQUIRED_LANDMARKS,
    SEGMENT_IDS,
    VIEWS,
    Detection,
    Segmentation,
    SegmentParams,
    agreeing_crotches,
    detect,
    disagreeing_arm_angles,
    label_detection,
    person_mask,
    resolve_landmarks,
    unconfident_landmarks,
    view_params,
)
from .sex import SexEstimate, build_score, sex_measurements
from .sex import from_score as sex_from_score
from .sex import inferred as sex_inferred

#: Joint centres estimated, named as :func:`bsv.bodies.joints.rig_joints` and :data:`bsv.biomech` name them.
JOINTS: tuple[str, ...] = JOINT_NAMES
#: The limbs, by their landmarks (a landmark found in neither view names its limb).
LIMBS: dict[str, tuple[str, ...]] = {
    f"{side} {limb}": tuple(f"{side}_{j}" for j in joints)
    for side in ("left", "right")
    for limb, joints in (("arm", ("shoulder", "elbow", "wrist")), ("leg", ("hip", "knee", "ankle")))
}
#: Per joint kind: the two segments that meet there (their pixels of the joint's side give its depth), and
#: the joints the limb's axis runs between (the limb's width is measured across that axis).
_KINDS: dict[str, tuple[tuple[str, str], tuple[str, str], float]] = {
    # kind: (segments, (axis from, axis to), where along the axis the width is measured)
    "shoulder": (("upper_arm", "torso"), ("shoulder", "elbow"), 0.25),
    "elbow": (("upper_arm", "forearm"), ("shoulder", "wrist"), 0.5),
    "wrist": (("forearm", "hand"), ("elbow", "wrist"), 1.0),
    "hip": (("thigh", "torso"), ("hip", "knee"), 0.25),
    "knee": (("thigh", "shin"), ("hip", "ankle"), 0.5),
    "ankle": (("shin", "foot"), ("knee", "ankle"), 1.0),
}
#: A body is thinner than this (metres) between the front and back surfaces at any joint: a surface behind a
#: landmark farther than that is not the same limb's (:func:`_lift_across`).
MAX_THICKNESS_M = 0.6
#: A view that stands in for another (:func:`detection_from_other_view`) leaves out of the person the pixels
#: lower than this above the floor (metres): the floor around the feet lies within the person's depth.
FLOOR_CLEARANCE_M = 0.01
#: Pixels around a landmark whose depth gives the surface under it.
DEPTH_RADIUS_PX = 7
#: The repeatable part of a landmark's error (metres) in :func:`joint_centres`' weighting of the two views:
#: each view weighs ``1 / (LANDMARK_SD_M^2 + s^2)``, ``s`` the landmark's image-vs-mirror spread
#: (``Segmentation.pose_spread``) at its depth. About MediaPipe's elbow and knee scatter on the synthetic
#: cohort; a view whose two detections of a landmark lie centimetres apart (a back view that put both
#: ankles on one foot) then hardly counts.
LANDMARK_SD_M = 0.01
#: A view whose weight (see :data:`LANDMARK_SD_M`) is this many times smaller than the other view's is left
#: out of that joint (its landmark is about 3 cm from repeatable or worse): the other view places it alone.
UNRELIABLE_WEIGHT_RATIO = 10.0
#: Heights above the floor (y = 0) of the leg's landmarks as fractions of the stature: the greater
#: trochanter 0.530, the knee 0.285, the ankle (malleolus) 0.039 (Drillis and Contini's segment proportions,
#: as tabulated in Winter, Biomechanics and Motor Control of Human Movement, fig. 4.1). The synthetic cohort's
#: rig joints: 0.524, 0.288, 0.043 (sd 0.008, 0.008, 0.002). Used only to tell which of two views that
#: disagree is wrong (:func:`implausible_landmarks`), never to move a landmark.
LEG_HEIGHT_FRACTIONS: dict[str, float] = {"hip": 0.530, "knee": 0.285, "ankle": 0.039}
#: Two views' 3-D lifts (:func:`_lift_from`) of one leg landmark farther apart in height than this (metres)
#: cannot both be right. Views that agree differ by at most 20 mm (hip, knee) and 40 mm (ankle) in nine
#: cases of ten (cohort seeds 0-7, 80 subjects, clinic room, varied lights); in all 26 cases beyond it the
#: view farther from the proportions' height was the wrong one (benchmarks/BENCH.md, round 2 session 18).
VIEWS_DISAGREE_M = 0.04
#: The stature is this percentile of the heights of the person's pixels with depth (the top of the head),
#: the higher of the two views'.
STATURE_PERCENTILE = 99.9
#: ... of the pixels within this depth (metres) of the person's median depth in that view.
STATURE_DEPTH_BAND_M = 0.5
#: Trunk length (metres, mid-hip to mid-shoulder of the uncorrected estimates) at which the trunk term of
#: :data:`JOINT_OFFSETS_M` is zero.
TRUNK_REF_M = 0.48
#: The measurements of the uncorrected joint centres an offset of :data:`JOINT_OFFSETS_M` may depend on,
#: each with the reference value (metres, about the cohort's mean) at which its term is zero
#: (:func:`offset_predictors`): the trunk length (mid-hip to mid-shoulder), the hip width (hip to hip), the
#: shoulder width and the leg length (hip to ankle, mean of the sides). ``"1"`` is the constant term.
OFFSET_PREDICTORS: dict[str, float] = {"1": 0.0, "trunk": TRUNK_REF_M, "hip_width": 0.17, "shoulder_width": 0.33,
                                       "leg_length": 0.80}
#: The range (metres, minus the reference) each measurement of :data:`OFFSET_PREDICTORS` is clipped to: the
#: training cohort's range widened by a quarter of its span on each side (printed by
#: ``benchmarks/learn_joint_offsets.py``). The build terms rise and fall together, so their fitted
#: coefficients are large and of opposite signs; clipped, a build far outside the cohort's (or a hip width
#: centimetres off) cannot move a joint by centimetres. Of the held-out subjects of seeds 0, 2, 4, 6 one is
#: clipped, by 1 mm (seed 4 subject 3's hip width; the heavy pose model's ranges, round 2 session 27).
OFFSET_PREDICTOR_RANGE: dict[str, tuple[float, float]] = {
    "trunk": (-0.095, 0.065), "hip_width": (-0.018, 0.043), "shoulder_width": (-0.081, 0.078),
    "leg_length": (-0.168, 0.188),
}
#: Offset (metres) from the landmark-based estimate to the anatomical joint centre, per joint kind, in the
#: body frame (x: lateral, toward the joint's own side; y: up, hips to shoulders; z: forward, the
#: subject's facing direction), linear in the body's measurements (an anthropometric regression, like the
#: hip-joint-centre models of gait labs, which take the pelvis width and the leg length):
#: offset = sum over the kind's predictors p of c_p * (m_p - reference_p), with the measurements m_p of
#: :data:`OFFSET_PREDICTORS`, as ``{predictor: c_p}``. Each kind's predictors are the ones that lower its
#: held-out error (the hip and the shoulder: all four; the others: the trunk length, as all kinds before). Least squares on
#: cohort seeds 11-18 (80 subjects, clinic room, noer; left and right pooled; MediaPipe's heavy pose model
#: on each image and its mirror image, averaged: ``SegmentParams.flip_average``) by
#: ``benchmarks/learn_joint_offsets.py``; held out, seeds 0, 2, 4 and 6 (40 subjects): see benchmarks/BENCH.md,
#: round 2 session 12 (the hip's vertical error sd 9.9 mm with the trunk length alone, 6.6 mm with the four,
#: its p95 3-D error 24.0 -> 19.2 mm; the shoulder's lateral error sd 7.3 -> 6.1 mm) and session 27 (re-learned
#: for the heavy model: medians shoulder 7.8, elbow 5.3, wrist 4.6, hip 8.5, knee 8.8, ankle 5.2 mm). What it corrects: MediaPipe's ankle is the malleoli's outline, about 40 mm above the rig's
#: ankle joint (the head of the foot bone); its hip, knee, elbow and shoulder lie 10-15 mm medial of the
#: joint centres; its hip marks the hip's outline, not the femoral head, and where the femoral head lies
#: below it depends on the build (trunk, pelvis and shoulder widths, legs).
JOINT_OFFSETS_M: dict[str, dict[str, tuple[float, float, float]]] = {
    "shoulder": {"1": (0.0187, 0.0025, 0.0033), "trunk": (0.1217, 0.0936, -0.0328), "hip_width": (-0.3346, -0.0589, 0.1079), "shoulder_width": (0.2703, 0.0614, -0.0716), "leg_length": (-0.0644, 0.0079, -0.0248)},
    "elbow": {"1": (0.0107, 0.0005, -0.0089), "trunk": (-0.0003, 0.0442, -0.1300)},
    "wrist": {"1": (0.0004, 0.0003, -0.0016), "trunk": (0.0350, 0.0040, 0.0365)},
    "hip": {"1": (0.0212, 0.0114, -0.0105), "trunk": (0.0647, 0.7095, -0.0317), "hip_width": (-0.2720, -0.4367, 0.2362), "shoulder_width": (-0.0010, 0.1687, -0.0793), "leg_length": (0.0840, -0.2184, -0.0733)},
    "knee": {"1": (0.0044, -0.0235, 0.0014), "trunk": (-0.0021, -0.2445, 0.0711)},
    "ankle": {"1": (0.0028, -0.0436, -0.0019), "trunk": (0.0283, -0.1593, -0.0962)},
}

#: Where the elbow joint centre lies along the line from the shoulder's to the wrist's (corrected) joint
#: centre, as a fraction of that distance from the shoulder: ``"1"`` at sex score 0 and ``"sex"`` per unit of
#: the sex score (:mod:`bsv.frontend.sex`: +1 a woman, -1 a man). Learned with :data:`JOINT_OFFSETS_M` by
#: ``benchmarks/learn_joint_offsets.py`` on the 80 training subjects of seeds 11-18, on top of the shipped
#: offsets: on held-out seeds 0, 2, 4, 6 the elbow's median 3-D error goes 6.4 -> 5.3 mm, its 95th percentile
#: 13.9 -> 11.6 mm (MediaPipe's elbow scatters more along the arm than the arm's proportions do; re-learned
#: for the heavy pose model in round 2 session 27). The rig's
#: own elbows lie at 0.525 (a woman) and 0.485 (a man) of their true shoulder-to-wrist lines.
ELBOW_FRACTION: dict[str, float] = {"1": 0.5095, "sex": 0.0111}
#: The weight of the lifted landmark's own place along the arm against :data:`ELBOW_FRACTION`'s (0: the
#: proportion alone, 1: the landmark alone), the one of 0, 0.05, ..., 1 that scatters least on the training
#: subjects (with the full pose model; with the heavy one the script prints 0.3, whose elbow is 0.2 mm better
#: at the median but whose fitted elbow loops scatter 0.1-0.4 mm more and the forearms 0.06-0.16 points more:
#: round 2 session 27, seeds 1, 3, 5, 7).
ELBOW_LANDMARK_WEIGHT = 0.1


#: The camera path's shin / foot boundary, a plane in the world (:func:`cut_feet_at_ankle_plane`): at the
#: ankle, ``height_m + height_per_stature x stature + height_per_sex x sex score`` above the floor (the sex
#: score of :mod:`bsv.frontend.sex`: +1 a woman, -1 a man), rising towards the toes by ``forward_slope``
#: (metres up per metre forward), that height holding ``forward_offset_m`` forward of the ankle. The rig's
#: true ankle loops (bsv.anatomy's ankle boundary) fitted by ``benchmarks/learn_ankle_plane.py`` on the 160
#: legs of seeds 11-18: the loop's centroid lies 91 mm above the floor (sd 3.9 mm), 10 mm forward of the ankle
#: joint, the loop tilted 16 deg. The stature alone explains almost none of the height, the stature and the
#: sex together most of it (a woman's loop lies 10 mm higher than a man's of the same stature): on held-out
#: seeds 0-7 the plane's height is off by sd 1.9 mm (4.2 mm with the stature alone; round 2 session 29, when
#: the camera path's shins had come out 0.8-1.0 % larger per unit of the sex score, their ends 3.4-3.8 mm
#: lower). The 2-D line through MediaPipe's ankle, placed at a fraction of the stature, put the cloud's shin
#: end 10 mm (sd) off the true loop (benchmarks/BENCH.md, round 2 session 25).
ANKLE_PLANE: dict[str, float] = {"height_m": 0.0121, "height_per_stature": 0.0467, "height_per_sex": 0.00512,
                                 "forward_slope": 0.291, "forward_offset_m": 0.0104}
#: A leg pixel farther than this (metres, horizontally) from its ankle keeps its 2-D label: the plane is the
#: ankle's, not the mask's spill onto the floor or the wall.
ANKLE_PLANE_RADIUS_M = 0.2
#: The floor the plane stands on is the one the view sees around each ankle (:func:`floor_near_ankles`): its
#: background pixels between these horizontal distances from the ankle (metres) ...
FLOOR_RING_M: tuple[float, float] = (0.08, 0.5)
#: ... that the calibration puts within this height of y = 0 (metres) ...
FLOOR_NEAR_M = 0.05
#: ... when there are at least this many of them (every second row and column); else the floor is y = 0.
FLOOR_MIN_PIXELS = 200

_LEGS: tuple[tuple[str, int, int], ...] = (("l", SEGMENT_IDS["shin_l"], SEGMENT_IDS["foot_l"]),
                                           ("r", SEGMENT_IDS["shin_r"], SEGMENT_IDS["foot_r"]))


def floor_near_ankles(labels: np.ndarray, depth: np.ndarray, camera: Camera,
                      ankles: Mapping[str, np.ndarray]) -> dict[str, float]:
    """The floor's height (world y, metres) one view sees around each ankle: the median height of its
    background pixels (label 0, with depth; every second row and column) between :data:`FLOOR_RING_M` from the
    ankle across the floor and within :data:`FLOOR_NEAR_M` of y = 0; 0.0 for an ankle with fewer than
    :data:`FLOOR_MIN_PIXELS` such pixels (no floor in view: the calibration's floor). A camera whose
    calibration is off by a fraction of a degree sees the floor at the feet centimetres from y = 0, and its
    own pixels of the legs are off by as much: heights above the floor it sees do not depend on that."""
    d = np.asarray(depth, dtype=np.float64)[::2, ::2]
    bg = (np.asarray(labels)[::2, ::2] == 0) & (d > 0) & np.isfinite(d)
    ys, xs = np.nonzero(bg)
    out = {f"ankle_{side}": 0.0 for side, _, _ in _LEGS}
    if len(ys) == 0:
        return out
    w = camera.deproject(np.column_stack([2 * xs, 2 * ys]).astype(np.float64), d[ys, xs])
    w = w[np.abs(w[:, 1]) < FLOOR_NEAR_M]
    for name in out:
        a = ankles.get(name)
        if a is None or not np.all(np.isfinite(a)):
            continue
        r = np.hypot(w[:, 0] - a[0], w[:, 2] - a[2])
        ring = (r >= FLOOR_RING_M[0]) & (r <= FLOOR_RING_M[1])
        if ring.sum() >= FLOOR_MIN_PIXELS:
            out[name] = float(np.median(w[ring, 1]))
    return out


def cut_feet_at_ankle_plane(labels: np.ndarray, depth: np.ndarray, camera: Camera, ankles: Mapping[str, np.ndarray],
                            stature: float, forward: np.ndarray | None = None,
                            plane: Mapping[str, float] | None = None, seen_floor: bool = True,
                            sex_score: float | None = None) -> np.ndarray:
    """One view's labels with each leg's shin and foot pixels split again in 3-D by the ankle plane.

    ``labels`` (H, W) segment ids and ``depth`` (H, W) metres of one view, its calibrated ``camera``; ``ankles``
    the 3-D ankles by joint name (``ankle_l``, ``ankle_r``; world frame, y up, the floor y = 0); ``stature``
    metres; ``forward`` the subject's horizontal facing direction (default +z, the world frame's
    convention); ``plane`` :data:`ANKLE_PLANE`'s keys; ``seen_floor``: the plane's height is above the floor
    this view sees around each ankle (:func:`floor_near_ankles`), else above y = 0; ``sex_score`` the subject's
    (:mod:`bsv.frontend.sex`: +1 a woman, -1 a man; None counts as 0) for the plane's ``height_per_sex``. A
    pixel of a leg's shin or foot with depth, within :data:`ANKLE_PLANE_RADIUS_M` of its ankle across the
    floor, becomes foot below the plane and shin above it; every other pixel, a leg whose ankle is missing and every pixel when the stature
    is unknown keep their labels. The input is not modified."""
    pl = ANKLE_PLANE if plane is None else plane
    up = np.array([0.0, 1.0, 0.0])
    f = np.array([0.0, 0.0, 1.0]) if forward is None else np.asarray(forward, dtype=np.float64)
    f = f - (f @ up) * up
    if not np.all(np.isfinite(f)) or np.linalg.norm(f) < 1e-9:
        f = np.array([0.0, 0.0, 1.0])
    f = f / np.linalg.norm(f)
    out = np.array(labels, copy=True)
    if not np.isfinite(stature) or stature <= 0:
        return out
    height = pl["height_m"] + pl["height_per_stature"] * stature + pl.get("height_per_sex", 0.0) * (sex_score or 0.0)
    d = np.asarray(depth, dtype=np.float64)
    floor = floor_near_ankles(out, d, camera, ankles) if seen_floor else {}
    for side, shin, foot in _LEGS:
        a = ankles.get(f"ankle_{side}")
        if a is None or not np.all(np.isfinite(a)):
            continue
        a = np.asarray(a, dtype=np.float64)
        ys, xs = np.nonzero(((out == shin) | (out == foot)) & (d > 0) & np.isfinite(d))
        if len(ys) == 0:
            continue
        w = camera.deproject(np.column_stack([xs, ys]).astype(np.float64), d[ys, xs])
        rel = w - a
        near = np.hypot(rel[:, 0], rel[:, 2]) <= ANKLE_PLANE_RADIUS_M
        cut = floor.get(f"ankle_{side}", 0.0) + height + pl["forward_slope"] * (rel @ f - pl["forward_offset_m"])
        out[ys[near], xs[near]] = np.where(w[near, 1] < cut[near], foot, shin)
    return out


def elbows_at_proportion(joints: Mapping[str, np.ndarray], sex_score: float | None,
                         fraction: Mapping[str, float] | None = None,
                         weight: float = ELBOW_LANDMARK_WEIGHT) -> dict[str, np.ndarray]:
    """Joint centres by name with each elbow moved along its shoulder-to-wrist line to ``weight`` times its
    own place plus ``1 - weight`` times the place ``fraction`` (default :data:`ELBOW_FRACTION`) gives for
    ``sex_score`` (None: 0); only the component along that line changes, so the elbow's flexion stays as
    measured. An arm without its shoulder, elbow and wrist, or whose shoulder and wrist coincide, is left
    as it is. Raises :class:`bsv.errors.InputError` naming ``weight`` outside [0, 1]."""
    if not 0.0 <= weight <= 1.0:
        err = InputError(f"elbows_at_proportion(weight={weight!r}): a weight lies in [0, 1]")
        err.argument = "weight"
        raise err
    table = ELBOW_FRACTION if fraction is None else fraction
    f = float(table["1"]) + float(table["sex"]) * float(sex_score or 0.0)
    out = {j: np.asarray(p, dtype=np.float64) for j, p in joints.items()}
    for side in ("l", "r"):
        names = (f"shoulder_{side}", f"elbow_{side}", f"wrist_{side}")
        if not all(n in out for n in names):
            continue
        sh, el, wr = (out[n] for n in names)
        length = float(np.linalg.norm(wr - sh))
        if not np.isfinite(length) or length <= 0.0:
            continue
        u = (wr - sh) / length
        along = float((el - sh) @ u)
        out[names[1]] = el + (1.0 - weight) * (f * length - along) * u
    return out


def build_measurements(joints: Mapping[str, np.ndarray]) -> dict[str, float]:
    """The build measurements of :data:`OFFSET_PREDICTORS` (all but ``"1"``) of joint centres by name, each
    minus its reference, unclipped; NaN when their joints are missing. The leg length is the mean of the
    legs that have both joints."""

    def dist(a: str, b: str) -> float:
        if a not in joints or b not in joints:
            return float("nan")
        return float(np.linalg.norm(np.asarray(joints[a], dtype=np.float64) - np.asarray(joints[b], dtype=np.float64)))

    legs = [dist(f"hip_{s}", f"ankle_{s}") for s in ("l", "r")]
    legs = [x for x in legs if np.isfinite(x)]
    m = {"trunk": trunk_length(joints), "hip_width": dist("hip_l", "hip_r"),
         "shoulder_width": dist("shoulder_l", "shoulder_r"), "leg_length": float(np.mean(legs)) if legs else np.nan}
    return {k: m[k] - ref for k, ref in OFFSET_PREDICTORS.items() if k != "1"}


def offset_predictors(joints: Mapping[str, np.ndarray]) -> dict[str, float]:
    """The predictors of :data:`JOINT_OFFSETS_M` of joint centres by name: ``"1"`` (1) and the
    :func:`build_measurements` clipped to :data:`OFFSET_PREDICTOR_RANGE`. A measurement whose joints are
    missing is 0 (its reference value: the cohort's mean build), so a joint without ankles is still moved by
    the other terms."""
    out = {"1": 1.0}
    for k, v in build_measurements(joints).items():
        lo, hi = OFFSET_PREDICTOR_RANGE[k]
        out[k] = float(np.clip(v, lo, hi)) if np.isfinite(v) else 0.0
    return out


@dataclass(frozen=True)
class Camera:
    """One calibrated camera: its intrinsics and camera-to-world rotation and translation (metres)."""

    intrinsics: Intrinsics
    rotation: np.ndarray
    translation: np.ndarray

    @classmethod
    def from_json(cls, intrinsics: Intrinsics, camera_to_world: Mapping[str, Any]) -> Camera:
        """From the intrinsics and a ``{"rotation": 3x3, "translation": 3}`` camera-to-world transform."""
        try:
            r = np.asarray(camera_to_world["rotation"], dtype=np.float64).reshape(3, 3)
            t = np.asarray(camera_to_world["translation"], dtype=np.float64).reshape(3)
        except (KeyError, TypeError, ValueError) as e:
            raise SegmentationError(f"camera_to_world needs a 3x3 rotation and a 3-vector translation ({e})") from e
        return cls(intrinsics, r, t)

    def _normalised(self, uv: np.ndarray) -> np.ndarray:
        """(N, 2) pixels -> (N, 2) undistorted normalised image coordinates."""
        import cv2

        k = self.intrinsics
        pts = np.asarray(uv, dtype=np.float64).reshape(-1, 1, 2)
        if any(k.coeffs):
            return np.asarray(cv2.undistortPoints(pts, k.matrix, k.dist)).reshape(-1, 2)
        return np.column_stack([(pts[:, 0, 0] - k.cx) / k.fx, (pts[:, 0, 1] - k.cy) / k.fy])

    def deproject(self, uv: np.ndarray, depth: np.ndarray | float) -> np.ndarray:
        """World points (N, 3) of pixels (N, 2) at depth (z in the camera frame, metres)."""
        n = self._normalised(uv)
        z = np.broadcast_to(np.asarray(depth, dtype=np.float64), (len(n),))
        cam = np.column_stack([n * z[:, None], z])
        return cam @ self.rotation.T + self.translation

    def project(self, xyz: np.ndarray) -> np.ndarray:
        """Pixels (N, 2) of world points (N, 3)."""
        import cv2

        cam = (np.asarray(xyz, dtype=np.float64).reshape(-1, 3) - self.translation) @ self.rotation
        k = self.intrinsics
        uv, _ = cv2.projectPoints(cam, np.zeros(3), np.zeros(3), k.matrix, k.dist)
        return np.asarray(uv).reshape(-1, 2)

    def axis(self) -> np.ndarray:
        """The viewing direction (the camera's z axis) in the world frame."""
        return np.asarray(self.rotation[:, 2], dtype=np.float64)


@dataclass(frozen=True)
class JointCentre:
    """One estimated joint centre (world frame, metres) with its confidence (0..1) and how it was found."""

    xyz: np.ndarray
    confidence: float
    #: "front+back", "front" or "back", with any degraded landmark in brackets, e.g.
    #: "front+back (back: hand model)".
    source: str

    def to_json(self) -> dict[str, Any]:
        """``{"xyz": [x, y, z], "confidence": c, "source": s}`` (the volumes JSON's ``joints_m`` entry)."""
        return {"xyz": [round(float(c), 5) for c in self.xyz], "confidence": round(float(self.confidence), 3),
                "source": self.source}


def _kind(joint: str) -> tuple[str, str]:
    """("knee", "left") of "knee_l"."""
    kind, s = joint.rsplit("_", 1)
    return kind, "left" if s == "l" else "right"


def _xy(pose: np.ndarray, name: str) -> np.ndarray:
    return np.asarray(pose[POSE_NAMES.index(name), :2], dtype=np.float64)


def _surface_depth(depth: np.ndarray, region: np.ndarray, uv: np.ndarray) -> float:
    """Median depth of the ``region`` pixels within :data:`DEPTH_RADIUS_PX` of ``uv`` (NaN if none)."""
    h, w = depth.shape
    r = DEPTH_RADIUS_PX
    x, y = round(float(uv[0])), round(float(uv[1]))
    y0, y1, x0, x1 = max(y - r, 0), min(y + r + 1, h), max(x - r, 0), min(x + r + 1, w)
    if y0 >= y1 or x0 >= x1:
        return float("nan")
    yy, xx = np.mgrid[y0:y1, x0:x1]
    near = (xx - x) ** 2 + (yy - y) ** 2 <= r * r
    d = depth[y0:y1, x0:x1]
    ok = near & region[y0:y1, x0:x1] & (d > 0) & np.isfinite(d)
    return float(np.median(d[ok])) if ok.sum() >= 3 else float("nan")


def _width_px(mask: np.ndarray, at: np.ndarray, along: np.ndarray, limit: int = 200) -> float:
    """Width (pixels) of the mask across the direction ``along`` through the point ``at`` (NaN if off it)."""
    h, w = mask.shape
    n = float(np.hypot(*along))
    if n < 1e-9:
        return float("nan")
    perp = np.array([-along[1], along[0]]) / n
    total = 0
    for sign in (1.0, -1.0):
        steps = np.arange(limit)
        pts = at[None] + sign * steps[:, None] * perp[None]
        xi, yi = np.round(pts[:, 0]).astype(int), np.round(pts[:, 1]).astype(int)
        inside = (xi >= 0) & (xi < w) & (yi >= 0) & (yi < h)
        on = np.zeros(limit, dtype=bool)
        on[inside] = mask[yi[inside], xi[inside]]
        if not on[0]:
            return float("nan")
        off = np.nonzero(~on)[0]
        total += int(off[0]) if off.size else limit
    return float(total - 1)


def _half_thickness(mask: np.ndarray, pose: np.ndarray, joint: str, depth_m: float, fx: float) -> float:
    """Half the limb's width (metres) across its axis near the joint, from one view's mask."""
    kind, side = _kind(joint)
    _, (a, b), t = _KINDS[kind]
    pa, pb = _xy(pose, f"{side}_{a}"), _xy(pose, f"{side}_{b}")
    own = _xy(pose, f"{side}_{kind}")
    at = own + (t if kind in ("shoulder", "hip") else 0.0) * (pb - pa)
    wpx = _width_px(mask, at, pb - pa)
    return 0.5 * wpx * depth_m / fx if np.isfinite(wpx) else float("nan")


def view_weight(spread_px: float, depth_m: float, fx: float) -> float:
    """The weight of one view's landmark across the viewing axis: ``1 / (LANDMARK_SD_M^2 + s^2)``, ``s`` its
    image-vs-mirror spread (pixels; NaN: unknown, taken as 0) in metres at ``depth_m``."""
    s = spread_px * depth_m / fx if np.isfinite(spread_px) else 0.0
    return 1.0 / (LANDMARK_SD_M**2 + s**2)


def unrepeatable_landmarks(dets: Mapping[str, Detection], cameras: Mapping[str, Camera],
                           depths: Mapping[str, np.ndarray]) -> dict[str, dict[str, float]]:
    """Per view, the required landmarks that view does not repeat while the other view does: its weight
    (:func:`view_weight`, at the person's median depth in that view) under a
    :data:`UNRELIABLE_WEIGHT_RATIO`-th of the other view's, the other view's landmark confident: ``{view:
    {name: spread px}}``. Both views' image-and-mirror detections are needed (``flip_average``)."""
    out: dict[str, dict[str, float]] = {v: {} for v in dets}
    spreads = {v: d.spread for v, d in dets.items() if d.spread is not None}
    if len(dets) != 2 or len(spreads) != 2:
        return out
    depth_at: dict[str, float] = {}
    for v, det in dets.items():
        d = np.asarray(depths[v], dtype=np.float64)
        person = (d > 0) & np.isfinite(d)
        if det.mask_soft is not None and det.mask_soft.shape == d.shape:
            person &= det.mask_soft > det.params.mask_threshold
        depth_at[v] = float(np.median(d[person])) if person.any() else float("nan")
    if not all(np.isfinite(x) for x in depth_at.values()):
        return out
    for v in dets:
        o = next(x for x in dets if x != v)
        other_bad = {n for n, _ in _unconfident(dets[o])}
        for name in REQUIRED_LANDMARKS:
            if name in other_bad:
                continue
            i = POSE_NAMES.index(name)
            w = view_weight(float(spreads[v][i]), depth_at[v], cameras[v].intrinsics.fx)
            w_o = view_weight(float(spreads[o][i]), depth_at[o], cameras[o].intrinsics.fx)
            if w_o > UNRELIABLE_WEIGHT_RATIO * w:
                out[v][name] = float(spreads[v][i])
    return out


def person_stature(dets: Mapping[str, Detection], cameras: Mapping[str, Camera],
                   depths: Mapping[str, np.ndarray]) -> float:
    """The subject's stature (metres above the floor, the world's y = 0): the :data:`STATURE_PERCENTILE`-th
    percentile of the world heights of the person's pixels with depth (within :data:`STATURE_DEPTH_BAND_M`
    of the person's median depth), the higher of the views' (a view
    whose mask lost the top of the head does not lower it); NaN when no view has a person mask with depth."""
    best = float("nan")
    for v, det in dets.items():
        if det.mask_soft is None or v not in cameras or v not in depths:
            continue
        d = np.asarray(depths[v], dtype=np.float64)
        if d.shape != det.mask_soft.shape:
            continue
        person = (det.mask_soft > det.params.mask_threshold) & (d > 0) & np.isfinite(d)
        if np.count_nonzero(person) < 100:
            continue
        # The mask's spill onto the wall behind the head lies metres deeper: only the person's depth band.
        person &= np.abs(d - float(np.median(d[person]))) < STATURE_DEPTH_BAND_M
        ys, xs = np.nonzero(person)
        pts = cameras[v].deproject(np.column_stack([xs, ys]).astype(np.float64), d[ys, xs])
        top = float(np.percentile(pts[:, 1], STATURE_PERCENTILE))
        best = top if not np.isfinite(best) else max(best, top)
    return best


def implausible_landmarks(dets: Mapping[str, Detection], cameras: Mapping[str, Camera],
                          depths: Mapping[str, np.ndarray],
                          skip: Mapping[str, Mapping[str, Any]] | None = None,
                          stature: float | None = None) -> dict[str, dict[str, str]]:
    """Per view, the leg landmarks (:data:`LEG_HEIGHT_FRACTIONS`) that both views see (visibility at least
    ``fallback_visibility``: a view may be the better one without being confident) but lift
    to 3-D (:func:`_lift_from`) at heights more than :data:`VIEWS_DISAGREE_M` apart, in the view whose
    height lies farther from the fraction of the stature (:func:`person_stature`): ``{view: {name: why}}``,
    ``why`` a phrase for the warning. A view whose landmark has no person under it (MediaPipe's mask lost the
    lower legs, or the landmark lies off them) is judged by the height of its pixel's ray at the other view's
    depth (:func:`_height_at_depth_of`): confident but lifted nowhere, it would otherwise stay unjudged (a back
    view's ankles at mid-shin once took half of both shins away). Landmarks in ``skip`` (``{view: names}``, e.g. the
    :func:`unrepeatable_landmarks`) of either view are not judged; ``stature`` (metres) saves reading it
    again. Needs both views."""
    out: dict[str, dict[str, str]] = {v: {} for v in dets}
    if set(dets) != set(VIEWS) or any(v not in cameras or v not in depths for v in VIEWS):
        return out
    if stature is None:
        stature = person_stature(dets, cameras, depths)
    if not np.isfinite(stature) or stature <= 0:
        return out
    unsure = {n for v in VIEWS for n, _ in unconfident_landmarks(dets[v].pose, dets[v].shape,
                                                                dets[v].params.fallback_visibility)}
    unsure |= {n for names in (skip or {}).values() for n in names}
    for kind, fraction in LEG_HEIGHT_FRACTIONS.items():
        for side in ("left", "right"):
            name = f"{side}_{kind}"
            if name in unsure:
                continue
            lifts = {v: _lift_from(dets[v], cameras[v], np.asarray(depths[v], dtype=np.float64), name)
                     for v in VIEWS}
            found = {v: p for v, p in lifts.items() if p is not None and np.all(np.isfinite(p))}
            if len(found) == 1:  # the other view's landmark has no person (mask and depth) under it
                seen = next(iter(found))
                off = "back" if seen == "front" else "front"
                ray = _height_at_depth_of(dets[off], cameras[off], name, float(found[seen][2]))
                if ray is not None:
                    found[off] = np.array([found[seen][0], ray, found[seen][2]])
            if len(found) < 2:
                continue
            height = {v: float(p[1]) for v, p in found.items()}
            gap = height["front"] - height["back"]
            if abs(gap) <= VIEWS_DISAGREE_M:
                continue
            expected = fraction * stature
            bad = max(VIEWS, key=lambda v: abs(height[v] - expected))
            good = "back" if bad == "front" else "front"
            out[bad][name] = (f"{1000 * abs(height[bad] - height[good]):.0f} mm "
                              f"{'above' if height[bad] > height[good] else 'below'} the {good} view's, "
                              f"farther from the {1000 * expected:.0f} mm the body's proportions give "
                              f"({fraction:.3f} of the stature {stature:.2f} m),")
    return out


def _height_at_depth_of(det: Detection, cam: Camera, name: str, z_world: float) -> float | None:
    """The height (world y, metres) of landmark ``name``'s pixel ray of one view where it reaches the world depth
    ``z_world`` (the other view's lift of the same landmark): for a landmark with no person under it (MediaPipe's
    mask lost the limb, or the landmark lies beside it), whose own depth says nothing. None where the ray runs
    parallel to that plane or the landmark has no pixel."""
    uv = _xy(det.pose, name)
    if not np.all(np.isfinite(uv)):
        return None
    near, far = np.asarray(cam.deproject(np.stack([uv, uv]), np.array([1.0, 2.0])))
    step = far - near  # the ray per metre of the camera's depth
    if abs(step[2]) < 1e-6:
        return None
    p = near + (z_world - near[2]) / step[2] * step
    return float(p[1]) if np.all(np.isfinite(p)) else None


def place_ankles(det: Detection, pose: np.ndarray, camera: Camera, depth: np.ndarray, stature: float) -> None:
    """Moves the two ankle landmarks of one view's resolved ``pose`` (in place) to the height above the floor
    its parameters give (``SegmentParams.ankle_height`` x ``stature``, metres): each ankle is lifted to 3-D
    (:func:`_lift_from`), put at that height, and projected back into the view. Nothing moves when the
    parameter is 0, the stature is unknown or the ankle has no depth under it."""
    fraction = det.params.ankle_height
    if fraction <= 0 or not np.isfinite(stature) or stature <= 0:
        return
    with_pose = dataclasses.replace(det, pose=pose)
    for side in ("left", "right"):
        name = f"{side}_ankle"
        p = _lift_from(with_pose, camera, np.asarray(depth, dtype=np.float64), name)
        if p is None or not np.all(np.isfinite(p)):
            continue
        at = np.array([p[0], fraction * stature, p[2]])
        uv = np.asarray(camera.project(at[None]))[0]
        if np.all(np.isfinite(uv)):
            pose[POSE_NAMES.index(name), :2] = uv


def _region(labels: np.ndarray, kind: str, side: str) -> np.ndarray:
    """Pixels of the side's two segments meeting at a joint of this kind (the torso has no side)."""
    sfx = "_l" if side == "left" else "_r"
    ids = [SEGMENT_IDS[s] if s == "torso" else SEGMENT_IDS[s + sfx] for s in _KINDS[kind][0]]
    return np.isin(labels, ids)


def _under(det: Detection, depth: np.ndarray, name: str) -> tuple[np.ndarray, np.ndarray, float] | None:
    """A view's person mask, its landmark ``name`` (pixels) and the surface depth under it (the mask's); None
    without a mask or depth there."""
    if det.mask_soft is None:
        return None
    mask = np.asarray(det.mask_soft > det.params.mask_threshold)
    uv = _xy(det.pose, name)
    d = _surface_depth(depth, mask, uv)
    return (mask, uv, d) if np.isfinite(d) else None


def _lift_from(det: Detection, cam: Camera, depth: np.ndarray, name: str) -> np.ndarray | None:
    """3-D point of a confident landmark of one view, before labelling (the person mask, the surface depth
    under it pushed inward by the limb's half-thickness); None without depth there."""
    under = _under(det, depth, name)
    if under is None:
        return None
    mask, uv, d = under
    side, kind = name.split("_", 1)
    joint = f"{kind}_{side[0]}"
    half = _half_thickness(mask, det.pose, joint, d, cam.intrinsics.fx)
    return np.asarray(cam.deproject(uv[None], d + (half if np.isfinite(half) else 0.0))[0])


def _lift_across(det: Detection, cam: Camera, depth: np.ndarray, name: str, target: Detection,
                 target_cam: Camera, target_depth: np.ndarray) -> np.ndarray | None:
    """3-D point of a confident landmark of one view, to stand in for the ``target`` view's: on the ray through
    the landmark, halfway in depth between the surface under it (the person mask's) and the surface the target
    view's depth shows behind it (its person mask's, around where that surface point falls in its image): the
    middle of the limb's cross-section. Without that depth, or with a surface behind it nearer than this one or
    farther than :data:`MAX_THICKNESS_M`, the half-thickness push of :func:`_lift_from`. None without depth under
    the landmark.

    Why not the half-thickness push alone: at a shoulder or a hip, the mask's width across the limb runs on into
    the torso or the other thigh (a 'half thickness' of 0.18-0.30 m), which put the stand-in landmark centimetres
    off the body (round 2 session 39)."""
    under = _under(det, depth, name)
    if under is None:
        return None
    _, uv, d = under
    surf = np.asarray(cam.deproject(uv[None], d)[0])
    if target.mask_soft is not None:
        region = np.asarray(target.mask_soft > target.params.mask_threshold)
        opposite = _surface_behind(surf, target_cam, target_depth, region)
        if opposite is not None:
            thickness = float((opposite - surf) @ cam.axis())
            if 0.0 < thickness < MAX_THICKNESS_M:
                return np.asarray(cam.deproject(uv[None], d + thickness / 2)[0])
    return _lift_from(det, cam, depth, name)


def _surface_behind(point: np.ndarray, camera: Camera, depth: np.ndarray, region: np.ndarray) -> np.ndarray | None:
    """The surface another view sees where ``point`` (world, metres) falls in its image: that view's ``region``
    pixels' median depth around the projection, deprojected; None off its image or without depth there."""
    uv = np.asarray(camera.project(point[None]))[0]
    if not np.all(np.isfinite(uv)):
        return None
    d = _surface_depth(np.asarray(depth, dtype=np.float64), region, uv)
    return np.asarray(camera.deproject(uv[None], d)[0]) if np.isfinite(d) else None


#: The sd a view stood in for by the other (:func:`detection_from_other_view`) adds to each quantity, in the error
#: models' comparison space (natural log; points for the asymmetries). Measured on session 41's engine (round 2
#: session 43, benchmarks/BENCH.md): the room's seeds 0 and 1 (40 captures per view, noer and l515) with the back
#: view, then the front view, forced lost, against the same captures as shipped; per quantity the rms errors'
#: difference in quadrature, the larger of the two views' and of the two sides'. The stand-in's labels follow the
#: other view's landmarks and this view's depth, not its own cut lines: the upper arms and the forearm-to-upper-arm
#: ratios move most with the back view lost (0.06, 0.08), the shins and the shin-to-thigh ratios with the front
#: view lost (0.055, 0.075).
STAND_IN_SD: dict[str, float] = {
    "torso": 0.013, "trunk_limbs": 0.007, "whole": 0.030,
    **{f"{k}_{s}": sd for k, sd in (("upper_arm", 0.060), ("forearm", 0.032), ("thigh", 0.026), ("shin", 0.055),
                                     ("arm", 0.035), ("leg", 0.016), ("forearm_to_upper_arm", 0.082),
                                     ("shin_to_thigh", 0.075)) for s in "lr"},
    **{f"asymmetry_{k}_pct": sd for k, sd in (("upper_arm", 1.63), ("forearm", 0.65), ("thigh", 0.92),
                                             ("shin", 0.99), ("arm", 0.79), ("leg", 0.62))},
}


def detection_from_other_view(view: str, shape: tuple[int, int], other: Detection, other_camera: Camera,
                              other_depth: np.ndarray, camera: Camera, depth: np.ndarray,
                              params: SegmentParams, why: str | None = None) -> Detection:
    """A stand-in :class:`Detection` of the ``view`` camera, whose (H, W) = ``shape`` image MediaPipe found no
    person in (not even brightened), made from the ``other`` view's, with the other view's visibilities and
    no hand model (the labels then draw the pose's coarse hands):

    - the person mask: this view's pixels above the floor within ``params.depth_band`` of the torso's depth
      (the median inside the other view's shoulders and hips projected here), the connected part holding the
      mid-hip;
    - each pose landmark: the surface point under it in the other view (its person's depth only: the mask's
      spill onto a wall is left out), and the surface point this view's depth shows behind it; the landmark
      is the midpoint of the two (the middle of the limb's cross-section), projected into this image.

    Its note (the segmentation's first warning) says what was done and what to do; ``why`` replaces its first
    words, "no person found in it (...)", where MediaPipe's own detection was refused for another reason."""
    import cv2

    mask_o = np.asarray(other.mask_soft > other.params.mask_threshold) if other.mask_soft is not None else None
    od = np.asarray(other_depth, dtype=np.float64)
    person_o = mask_o & (od > 0) & np.isfinite(od) if mask_o is not None else np.zeros(od.shape, dtype=bool)
    if not person_o.any():
        raise PersonNotFoundError(f"no person found in the {view} image, and the other view has no person with depth "
                                  "to stand in for it: light both sides of the subject, check both depth streams")
    median_o = float(np.median(od[person_o]))
    person_o &= np.abs(od - median_o) < params.depth_band
    uv_o = other.pose[:, :2]
    front = np.array([other_camera.deproject(uv[None], _finite_or(_surface_depth(od, person_o, uv), median_o))[0]
                      for uv in uv_o])
    first = camera.project(front)  # the other view's surface points, seen from here

    d = np.asarray(depth, dtype=np.float64)
    h, w = d.shape
    valid = (d > 0) & np.isfinite(d)
    quad = np.zeros((h, w), np.uint8)
    corners = [first[POSE_NAMES.index(n)] for n in ("left_shoulder", "right_shoulder", "right_hip", "left_hip")]
    cv2.fillPoly(quad, [np.round(np.array(corners)).astype(np.int32)], 1)
    torso = valid & (quad > 0)
    if torso.sum() < 20:
        raise PersonNotFoundError(f"no person found in the {view} image, and its depth image has no depth where the "
                                  "other view puts the torso: check the calibration and the depth stream")
    person = valid & (np.abs(d - float(np.median(d[torso]))) < params.depth_band)
    ys, xs = np.nonzero(person)  # the floor (the world's y = 0) is not the person
    person[ys, xs] = camera.deproject(np.column_stack([xs, ys]).astype(np.float64), d[ys, xs])[:, 1] > FLOOR_CLEARANCE_M
    _, parts = cv2.connectedComponents(person.astype(np.uint8), connectivity=8)
    hip = np.round((first[POSE_NAMES.index("left_hip")] + first[POSE_NAMES.index("right_hip")]) / 2).astype(int)
    label = int(parts[np.clip(hip[1], 0, h - 1), np.clip(hip[0], 0, w - 1)])
    if label > 0:
        person = parts == label

    back = np.array([camera.deproject(uv[None], dd)[0] if np.isfinite(dd := _surface_depth(d, person, uv)) else p
                     for uv, p in zip(first, front, strict=True)])
    pose = np.column_stack([camera.project((front + back) / 2), other.pose[:, 2]])
    reason = why or "no person found in it (nor in its mirror image, nor brightened)"
    note = (f"{view} image: {reason}; its landmarks are the "
            f"{other.view} view's through the calibration and its person mask is the depth's: light this side of "
            "the subject and capture again for labels of its own")
    return Detection(view, shape, pose, [None, None], person.astype(np.float32), (), params, None, (note,))


def _finite_or(x: float, default: float) -> float:
    """``x`` if finite, else ``default``."""
    return x if np.isfinite(x) else default


def segment_views(images: Mapping[str, Mapping[str, Any]], cameras: Mapping[str, Camera],
                  use_depth: bool = True, **params: Any) -> dict[str, Segmentation]:
    """Segments the front and back images of one capture together: ``images[view]`` holds ``colour`` (RGB
    uint8) and ``depth_m`` (metres, aligned to the colour, 0 = none), ``cameras[view]`` its calibrated
    :class:`Camera`. Required landmarks not seen confidently in one view are filled in from the other view,
    the hand model or the lower threshold (see the module notes), each a warning in the result's
    :attr:`~bsv.frontend.segment.Segmentation.warnings`. ``params``: :class:`SegmentParams` overrides for
    both views. Raises :class:`bsv.errors.LimbMissingError` when a limb's landmark is found in neither view."""
    views = [v for v in VIEWS if v in images]
    if set(images) != set(views) or len(views) != 2 or any(v not in cameras for v in views):
        raise SegmentationError(f"segment_views needs the front and back images and cameras, got images "
                                f"{sorted(images)} and cameras {sorted(cameras)}")
    depths = {v: np.asarray(images[v]["depth_m"], dtype=np.float64) for v in views}
    dets: dict[str, Detection] = {}
    lost: dict[str, PersonNotFoundError] = {}
    for v in views:
        try:
            dets[v] = detect(images[v]["colour"], v, depth=depths[v], camera=cameras[v], **params)
        except PersonNotFoundError as e:
            lost[v] = e
    if len(lost) == len(views):
        raise PersonNotFoundError(f"no person found in either camera's image ({'; '.join(str(e) for e in lost.values())})")
    for v in lost:  # the other view stands in for this one, through the calibration
        o = "back" if v == "front" else "front"
        h, w = np.asarray(images[v]["colour"]).shape[:2]
        err = lost[v]
        why = (f"MediaPipe's pose of it spans {100 * err.span:.0f} % of the person's height in the depth image at "
               "most (a part of the person, or something else)") if isinstance(err, PoseTooSmallError) else None
        dets[v] = detection_from_other_view(v, (h, w), dets[o], cameras[o], depths[o], cameras[v], depths[v],
                                            view_params(v, **params), why)
    unrepeatable = unrepeatable_landmarks(dets, cameras, depths)
    stature = person_stature(dets, cameras, depths)
    implausible = implausible_landmarks(dets, cameras, depths, skip=unrepeatable, stature=stature)
    resolved = {}
    for v in views:
        o = "back" if v == "front" else "front"
        own_bad = [n for n, _ in _unconfident(dets[v])]
        own_bad += [n for n in [*unrepeatable[v], *implausible[v]] if n not in own_bad]
        other_bad = {n for n, _ in _unconfident(dets[o])}
        other_weak = {n for n, _ in unconfident_landmarks(dets[o].pose, dets[o].shape,
                                                          dets[o].params.fallback_visibility)}
        from_other: dict[str, np.ndarray] = {}
        for name in own_bad:
            if name in other_bad and name not in implausible[v] and name in other_weak:
                continue  # neither view sees it even at the lower threshold: the hand model may
            p = _lift_across(dets[o], cameras[o], depths[o], name, dets[v], cameras[v], depths[v])
            if p is not None:
                uv = cameras[v].project(p[None])[0]
                from_other[name] = np.array([uv[0], uv[1], dets[o].pose[POSE_NAMES.index(name), 2]])
        resolved[v] = resolve_landmarks(dets[v], from_other, unrepeatable[v], implausible[v])
    missing = {v: dict(r[3]) for v, r in resolved.items()}
    if any(missing.values()):
        raise _limb_error(missing)
    sex = sex_estimate(dets, {v: resolved[v][0] for v in views}, cameras, depths, stature)
    for v in views:
        place_ankles(dets[v], resolved[v][0], cameras[v], depths[v], stature)
    masks = {v: person_mask(dets[v], depths[v] if use_depth else None, resolved[v][0]) for v in views}
    crotches, crotch_notes = agreeing_crotches(masks, {v: resolved[v][0] for v in views}, sex.score)
    arm_notes = disagreeing_arm_angles({v: resolved[v][0] for v in views})
    build = build_score(sex.measurements)
    segs = {v: label_detection(dets[v], depths[v] if use_depth else None, resolved[v][0], resolved[v][1],
                               [*resolved[v][2], *([crotch_notes[v]] if v in crotch_notes else []),
                                *([arm_notes[v]] if v in arm_notes else [])], sex=sex,
                               mask=masks[v], crotch=crotches[v], build=build) for v in views}
    if crotch_notes:  # a crotch placed at its expected depth: the thighs' intervals widen by its sd
        segs = {v: dataclasses.replace(s, extra_sd={**s.extra_sd, **EXPECTED_CROTCH_SD}) for v, s in segs.items()}
    for v in lost:  # a view stood in for by the other: every boundary it draws is less certain
        extra = {k: max(sd, segs[v].extra_sd.get(k, 0.0)) for k, sd in STAND_IN_SD.items()}
        segs[v] = dataclasses.replace(segs[v], extra_sd={**segs[v].extra_sd, **extra})
    if not use_depth or not np.isfinite(stature):
        return segs
    poses = {v: resolved[v][0] for v in views}
    lifted = lifted_joints(dets, poses, cameras, depths, ("ankle_l", "ankle_r", "hip_l", "hip_r", "shoulder_l", "shoulder_r"))
    frame = _body_frame(lifted)
    forward = None if frame is None else frame[2]
    return {v: dataclasses.replace(segs[v], labels=cut_feet_at_ankle_plane(segs[v].labels, depths[v], cameras[v], lifted,
                                                                            stature, forward, sex_score=sex.score))
            for v in views}


#: The joints :func:`sex_estimate` lifts (:func:`bsv.frontend.sex.sex_measurements` takes them).
SEX_JOINTS: tuple[str, ...] = tuple(f"{k}_{s}" for k in ("shoulder", "elbow", "wrist", "hip") for s in "lr")


def _torso_points(det: Detection, pose: np.ndarray, cam: Camera, depth: np.ndarray) -> np.ndarray:
    """The world points of a view's person mask with depth between its shoulder and hip landmarks (the
    image's box around them, 10 px wider), within :data:`STATURE_DEPTH_BAND_M` of the person's median
    depth (the mask's spill onto the wall lies metres deeper); (0, 3) without a mask."""
    d = np.asarray(depth, dtype=np.float64)
    if det.mask_soft is None or d.shape != det.mask_soft.shape:
        return np.zeros((0, 3))
    person = (det.mask_soft > det.params.mask_threshold) & (d > 0) & np.isfinite(d)
    corners = np.array([_xy(pose, f"{s}_{k}") for s in ("left", "right") for k in ("shoulder", "hip")])
    if not person.any() or not np.all(np.isfinite(corners)):
        return np.zeros((0, 3))
    h, w = d.shape
    (x0, y0), (x1, y1) = np.floor(corners.min(axis=0)) - 10, np.ceil(corners.max(axis=0)) + 10
    box = np.zeros_like(person)
    box[int(np.clip(y0, 0, h)):int(np.clip(y1, 0, h)), int(np.clip(x0, 0, w)):int(np.clip(x1, 0, w))] = True
    person &= box & (np.abs(d - float(np.median(d[person]))) < STATURE_DEPTH_BAND_M)
    ys, xs = np.nonzero(person)
    return np.asarray(cam.deproject(np.column_stack([xs, ys]).astype(np.float64), d[ys, xs]))


def lifted_joints(dets: Mapping[str, Detection], poses: Mapping[str, np.ndarray], cameras: Mapping[str, Camera],
                  depths: Mapping[str, np.ndarray], names: Sequence[str] = JOINTS) -> dict[str, np.ndarray]:
    """The joints ``names`` of the resolved ``poses`` lifted to 3-D before the labels: in each view the
    surface depth under the landmark (the person mask's) pushed inward by the limb's half-thickness, the
    views' mean; a joint no view has depth under is left out."""
    joints: dict[str, np.ndarray] = {}
    for joint in names:
        kind, side = _kind(joint)
        lifted = []
        for v, det in dets.items():
            if det.mask_soft is None or v not in poses:
                continue
            mask = np.asarray(det.mask_soft > det.params.mask_threshold)
            uv = _xy(poses[v], f"{side}_{kind}")
            d = _surface_depth(np.asarray(depths[v], dtype=np.float64), mask, uv)
            if not np.isfinite(d):
                continue
            half = _half_thickness(mask, poses[v], joint, d, cameras[v].intrinsics.fx)
            lifted.append(np.asarray(cameras[v].deproject(uv[None], d + (half if np.isfinite(half) else 0.0))[0]))
        if lifted:
            joints[joint] = np.mean(lifted, axis=0)
    return joints


def sex_estimate(dets: Mapping[str, Detection], poses: Mapping[str, np.ndarray], cameras: Mapping[str, Camera],
                 depths: Mapping[str, np.ndarray], stature: float) -> SexEstimate:
    """The sex the labels are drawn for (:mod:`bsv.frontend.sex`): the detections' ``sex_score`` when the
    caller fixed it, else read from the capture: the resolved ``poses``' shoulders, elbows, wrists and hips
    lifted to 3-D (:func:`lifted_joints`), the person's points of both views between the shoulders and the
    hips and the ``stature``."""
    fixed = next((d.params.sex_score for d in dets.values() if d.params.sex_score is not None), None)
    joints = lifted_joints(dets, poses, cameras, depths, SEX_JOINTS)
    points = {v: _torso_points(dets[v], poses[v], cameras[v], depths[v]) if v in dets and v in poses else np.zeros((0, 3))
              for v in VIEWS}
    measured = sex_measurements(joints, _body_frame(joints), points["front"], points["back"], stature)
    if fixed is not None:  # the measurements still give the build (bsv.frontend.sex.build_score)
        return dataclasses.replace(sex_from_score(fixed), measurements={k: float(v) for k, v in measured.items()})
    return sex_inferred(measured)


def _unconfident(det: Detection) -> list[tuple[str, str]]:
    """The required landmarks of a detection under its ``min_visibility`` (or outside the image)."""
    return unconfident_landmarks(det.pose, det.shape, det.params.min_visibility)


def _limb_error(missing: Mapping[str, Mapping[str, str]]) -> LimbMissingError:
    """LimbMissingError naming every limb with a landmark found in neither view, and what to do."""
    names = sorted({n for m in missing.values() for n in m}, key=POSE_NAMES.index)
    limbs = [limb for limb, lms in LIMBS.items() if any(n in lms for n in names)]
    what = "; ".join(
        f"{n} (" + ", ".join(f"{v}: {m[n]}" for v, m in missing.items() if n in m) + ")" for n in names)
    err = LimbMissingError(
        f"{' and '.join(limbs)} not found in the camera views (nor by the other view, the hand model or the "
        f"lower visibility threshold): {what}. Capture again: step back so that the whole "
        "body, hands and feet included, is inside both images; hold the arms open, away from the body (A-pose); "
        "light the subject evenly from the front and the back")
    err.missing = names
    err.limbs = limbs
    return err


def _body_frame(pts: Mapping[str, np.ndarray]) -> np.ndarray | None:
    """Rows x (subject's left), y (up, hips to shoulders), z (forward) of the body frame, from the hip and
    shoulder centres; None when they are missing."""
    need = ("hip_l", "hip_r", "shoulder_l", "shoulder_r")
    if any(k not in pts or not np.all(np.isfinite(pts[k])) for k in need):
        return None
    x = pts["hip_l"] - pts["hip_r"]
    y = (pts["shoulder_l"] + pts["shoulder_r"] - pts["hip_l"] - pts["hip_r"]) / 2
    x = x / np.linalg.norm(x)
    y = y - (y @ x) * x
    y = y / np.linalg.norm(y)
    return np.vstack([x, y, np.cross(x, y)])


def body_frame(joints: Mapping[str, np.ndarray]) -> np.ndarray | None:
    """The body frame (3x3, rows x left, y up, z forward) of joint centres by name; None without hips and
    shoulders. The frame of :data:`JOINT_OFFSETS_M`."""
    return _body_frame(joints)


def joint_centres(segs: Mapping[str, Segmentation], depths: Mapping[str, np.ndarray],
                  cameras: Mapping[str, Camera], correct: bool = True) -> dict[str, JointCentre]:
    """3-D centres (world frame, metres) of the joints of :data:`JOINTS` from the two views' segmentations
    (:func:`segment_views`), their aligned depth images (metres) and calibrated cameras; see the module
    notes. ``correct``: add the learned offsets of :data:`JOINT_OFFSETS_M` and move the elbows along the arms
    (:func:`elbows_at_proportion`, for the sex the labels were drawn for). A joint that no view could place
    (no depth under it) is left out."""
    views = [v for v in VIEWS if v in segs]
    raw: dict[str, np.ndarray] = {}
    conf: dict[str, float] = {}
    src: dict[str, str] = {}
    for joint in JOINTS:
        kind, side = _kind(joint)
        name = f"{side}_{kind}"
        per: dict[str, tuple[np.ndarray, float, float, str, float]] = {}
        for v in views:
            s = segs[v]
            how = s.sources.get(name, "")
            if how == "other view" or s.pose is None:
                continue  # not independent of the other view
            uv = _xy(s.pose, name)
            d = _surface_depth(np.asarray(depths[v], dtype=np.float64), _region(s.labels, kind, side), uv)
            if not np.isfinite(d):
                d = _surface_depth(np.asarray(depths[v], dtype=np.float64), s.mask, uv)
            if not np.isfinite(d):
                continue
            cam = cameras[v]
            surf = np.asarray(cam.deproject(uv[None], d)[0])
            half = _half_thickness(s.mask, s.pose, joint, d, cam.intrinsics.fx)
            vis = float(s.pose[POSE_NAMES.index(name), 2]) * (0.5 if how else 1.0)
            spread_px = np.nan if s.pose_spread is None else float(s.pose_spread[POSE_NAMES.index(name)])
            per[v] = (surf, half, vis, how, view_weight(spread_px, d, cam.intrinsics.fx))
        if not per:
            continue
        notes = [f"{v}: {how}" for v, (_, _, _, how, _) in per.items() if how]
        if len(per) == 2:
            w_front, w_back = per["front"][4], per["back"][4]
            if max(w_front, w_back) > UNRELIABLE_WEIGHT_RATIO * min(w_front, w_back):
                # One view's two detections disagree by centimetres: its landmark (and the depth under it)
                # is not to be trusted; the other view places the joint alone.
                dropped = "back" if w_front > w_back else "front"
                del per[dropped]
                notes.append(f"{dropped}: left out (its image and mirror-image landmarks disagree)")
        opposite = None  # the other view's surface behind the one view that places the joint
        if len(per) == 1 and len(views) == 2:
            (kept, (surf, _, _, _, _)), = per.items()
            other = next(v for v in views if v != kept)
            opposite = _surface_behind(surf, cameras[other], depths[other], segs[other].mask)
        if len(per) == 2:
            (sf, _, vf, _, wf), (sb, _, vb, _, wb) = per["front"], per["back"]
            ax = cameras["front"].axis()
            # Along the viewing axis: midway between the front and back surfaces. Across it: the views
            # weighed by how repeatable each view's landmark is (its image-vs-mirror spread); equal
            # weights (the plain mean) without the mirror detection.
            mid = (sf + sb) / 2
            across = (wf * (sf - (sf @ ax) * ax) + wb * (sb - (sb @ ax) * ax)) / (wf + wb)
            xyz = across + (mid @ ax) * ax
            gap = sf - sb - ((sf - sb) @ ax) * ax  # the two views' disagreement across the viewing axis
            confidence = min(vf, vb) * max(0.0, 1.0 - float(np.linalg.norm(gap)) / 0.05)
            where = "front+back"
        else:
            (v, (surf, half, vis, _, _)), = per.items()
            if opposite is not None:  # midway between this view's surface and the other's, behind it
                ax = cameras[v].axis()
                xyz = surf + ((opposite - surf) @ ax) / 2 * ax
            else:
                xyz = surf + cameras[v].axis() * (half if np.isfinite(half) else 0.0)
            confidence = 0.5 * vis
            where = v
        raw[joint] = xyz
        conf[joint] = float(np.clip(confidence, 0.0, 1.0))
        src[joint] = where + (f" ({'; '.join(notes)})" if notes else "")
    out_xyz = elbows_at_proportion(apply_offsets(raw), _sex_score(segs)) if correct else raw
    return {j: JointCentre(out_xyz[j], conf[j], src[j]) for j in raw}


def _sex_score(segs: Mapping[str, Segmentation]) -> float | None:
    """The sex score the views' labels were drawn for (both views hold the same), None without one."""
    return next((float(s.sex.score) for s in segs.values() if s.sex is not None), None)


def trunk_length(joints: Mapping[str, np.ndarray]) -> float:
    """Distance (metres) from the mid-hip to the mid-shoulder of joint centres by name (NaN without them)."""
    need = ("hip_l", "hip_r", "shoulder_l", "shoulder_r")
    if any(k not in joints for k in need):
        return float("nan")
    p = {k: np.asarray(joints[k], dtype=np.float64) for k in need}
    return float(np.linalg.norm((p["shoulder_l"] + p["shoulder_r"] - p["hip_l"] - p["hip_r"]) / 2))


def apply_offsets(joints: Mapping[str, np.ndarray],
                  offsets: Mapping[str, Mapping[str, Sequence[float]]] | None = None,
                  ) -> dict[str, np.ndarray]:
    """Joint centres moved by the per-kind offsets ``{predictor: c}`` (default :data:`JOINT_OFFSETS_M`):
    the sum of c times the predictor's measurement (:func:`offset_predictors` of the given joints) in
    their body frame (x mirrored for the right side); unchanged without hips and shoulders to build the
    frame. Joints that are not of :data:`JOINTS` (e.g. the neck) are not moved."""
    table = JOINT_OFFSETS_M if offsets is None else offsets
    for kind, row in table.items():
        unknown = sorted(set(row) - set(OFFSET_PREDICTORS))
        if unknown:
            err = InputError(f"apply_offsets(offsets=...): kind {kind!r}: unknown predictor(s) {unknown}; known: "
                             f"{', '.join(OFFSET_PREDICTORS)}")
            err.argument = "offsets"
            raise err
    frame = _body_frame(joints)
    if frame is None or not np.isfinite(trunk_length(joints)):
        return {j: np.asarray(p, dtype=np.float64) for j, p in joints.items()}
    measured = offset_predictors(joints)
    out = {}
    for j, p in joints.items():
        if j not in JOINTS or _kind(j)[0] not in table:
            out[j] = np.asarray(p, dtype=np.float64)
            continue
        kind, side = _kind(j)
        off = sum((measured[name] * np.asarray(c, dtype=np.float64) for name, c in table[kind].items()),
                  np.zeros(3))
        off = off * np.array([1.0 if side == "left" else -1.0, 1.0, 1.0])
        out[j] = np.asarray(p, dtype=np.float64) + off @ frame
    return out


def capture_joints(capture_dir: Any, calibration: Any = None, cameras: Sequence[str] = VIEWS,
                   **params: Any) -> tuple[dict[str, JointCentre], dict[str, Segmentation]]:
    """Joint centres of a capture folder (``<dir>/front``, ``<dir>/back`` with colour, depth, camera.json):
    the calibration is ``calibration`` (calibration.json, as ``bsv process`` takes it) or, when None, each
    camera.json's ``camera_to_world`` (the virtual scanner's). Returns (joints by name, segmentations)."""
    from pathlib import Path

    from .capture import read_capture

    root = Path(capture_dir)
    data = {v: read_capture(root / v) for v in cameras}
    if calibration is None:
        try:
            ext = {v: data[v]["meta"]["camera_to_world"] for v in cameras}
        except KeyError as e:
            raise SegmentationError(f"{root}: camera.json has no camera_to_world; pass the calibration.json") from e
    else:
        from .calibrate import read_calibration

        c = read_calibration(calibration)
        ext = {v: {"rotation": c.cameras[v].rotation, "translation": c.cameras[v].translation} for v in cameras}
    cams = {v: Camera.from_json(data[v]["intrinsics"], ext[v]) for v in cameras}
    segs = segment_views({v: {"colour": data[v]["colour"], "depth_m": data[v]["depth_m"]} for v in cameras}, cams,
                         **params)
    return joint_centres(segs, {v: data[v]["depth_m"] for v in cameras}, cams), segs


__all__ = [
    "ANKLE_PLANE",
    "ANKLE_PLANE_RADIUS_M",
    "DEPTH_RADIUS_PX",
    "ELBOW_FRACTION",
    "ELBOW_LANDMARK_WEIGHT",
    "FLOOR_CLEARANCE_M",
    "FLOOR_MIN_PIXELS",
    "FLOOR_NEAR_M",
    "FLOOR_RING_M",
    "JOINTS",
    "JOINT_OFFSETS_M",
    "LIMBS",
    "MAX_THICKNESS_M",
    "OFFSET_PREDICTORS",
    "OFFSET_PREDICTOR_RANGE",
    "STAND_IN_SD",
    "TRUNK_REF_M",
    "Camera",
    "JointCentre",
    "apply_offsets",
    "body_frame",
    "build_measurements",
    "capture_joints",
    "cut_feet_at_ankle_plane",
    "detection_from_other_view",
    "elbows_at_proportion",
    "floor_near_ankles",
    "joint_centres",
    "lifted_joints",
    "offset_predictors",
    "segment_views",
    "sex_estimate",
    "trunk_length",
]

"""How squarely the subject faces the front camera, from the capture's joint centres.

The camera path's 2-D cut lines, the crotch the two views must agree on and the shoulder line are drawn for a
subject who faces the front camera. Turned about the vertical, the subject shows each camera one side more than
the other. On the room's seeds 0-1 turned by 10 deg (every other subject the other way) the eight limbs came out
1.76 / 2.04 % (noer / l515) against 1.35 / 1.41 % facing the camera, 11 of 40 captures lost the crotch target and
one thigh came out -10 %; the oracle labels on the same bodies did not move (benchmarks/BENCH.md, round 2 session
44). The capture cannot undo the turn yet, but it can say so: :func:`turn_deg` measures it (the subject's left from
the hip and shoulder joint centres, against the horizontal direction from the hips to the front camera; about
0.4 deg sd on square subjects, 1.2 on turned ones, which it reads about 15 % short), :func:`turn_warning` asks
to capture again above :data:`TURN_WARN_DEG`, and :func:`turn_extra_sd` widens the intervals by the turn
(:data:`TURN_SD_PER_DEG`): turned, an asymmetry's error follows the turn.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from ..keypoints import joint_xyz as _xyz

#: A subject turned more than this (degrees about the vertical from facing the front camera) gets a warning. Turned
#: 8-10 deg, the eight limbs lost 0.38 point on average; a subject turned 5.8 deg had an upper arm -12 % (its
#: shoulder loop 12 mm off); square subjects read within 1.3 deg (BENCH.md, round 2 session 44).
TURN_WARN_DEG = 4.0
#: The sd (per degree of the measured turn) a turned subject adds to each quantity of the volumes report, in the
#: error models' comparison space (:func:`bsv.uncertainty.transform`: natural log for volumes and ratios, points
#: for asymmetries): per quantity, the rms error of turned captures and of the same subjects square, their
#: difference in quadrature over the turns' rms (the larger side of each pair for both; room seeds 0, 1, 20 and 21
#: turned -10..10 deg against square, 80 paired runs, ``--turn=-10,10``; derived on seeds 0-1 alone and held out on
#: 20-21, the asymmetries' coverage went 72-80 -> 88-92 %). Turned, an asymmetry's error follows the turn
#: (the thighs' -0.35 point per deg): without it 70-85 % of the asymmetries' truths fell inside their intervals and
#: 17-32 % of the symmetric pairs read distinguishable (BENCH.md, round 2 session 44).
TURN_SD_PER_DEG: dict[str, float] = {
    "arm_l": 0.00407, "arm_r": 0.00407,
    "asymmetry_arm_pct": 0.484,
    "asymmetry_forearm_pct": 0.133,
    "asymmetry_leg_pct": 0.305,
    "asymmetry_shin_pct": 0.151,
    "asymmetry_thigh_pct": 0.424,
    "asymmetry_upper_arm_pct": 0.657,
    "forearm_l": 0.00106, "forearm_r": 0.00106,
    "forearm_to_upper_arm_l": 0.00235, "forearm_to_upper_arm_r": 0.00235,
    "leg_l": 0.00224, "leg_r": 0.00224,
    "shin_l": 0.00103, "shin_r": 0.00103,
    "shin_to_thigh_l": 0.00281, "shin_to_thigh_r": 0.00281,
    "thigh_l": 0.00302, "thigh_r": 0.00302,
    "torso": 0.00043,
    "trunk_limbs": 0.0001,
    "upper_arm_l": 0.00549, "upper_arm_r": 0.00549,
}
#: The joints whose left-right lines give the subject's left.
LINES: tuple[tuple[str, str], ...] = (("hip_l", "hip_r"), ("shoulder_l", "shoulder_r"))


def turn_deg(joints: Mapping[str, Any], front_camera_m: np.ndarray | Sequence[float] | None) -> float | None:
    """The subject's turn about the vertical (degrees, world +Y up; + when the subject's left has gone backwards,
    as :attr:`bsv.bodies.pose.Pose.turn_deg`) from facing the front camera, whose centre is ``front_camera_m``
    (world metres): the subject's forward is its left (the sum of the left-minus-right lines of :data:`LINES`)
    crossed with up. None without both hips and the camera."""
    if front_camera_m is None or not all(a in joints and b in joints for a, b in LINES[:1]):
        return None
    left = sum((_xyz(joints[a]) - _xyz(joints[b]) for a, b in LINES if a in joints and b in joints),
               np.zeros(3))
    left[1] = 0.0
    hips = (_xyz(joints["hip_l"]) + _xyz(joints["hip_r"])) / 2
    to_camera = np.asarray(front_camera_m, dtype=np.float64) - hips
    to_camera[1] = 0.0
    if np.linalg.norm(left) < 1e-6 or np.linalg.norm(to_camera) < 1e-6:
        return None
    forward = np.cross(left, [0.0, 1.0, 0.0])
    return float(np.degrees(np.arctan2(np.cross(to_camera, forward)[1], to_camera @ forward)))


def turn_extra_sd(turn: float | None) -> dict[str, float]:
    """The sd a subject turned ``turn`` degrees adds to each quantity (:data:`TURN_SD_PER_DEG` times the turn's size;
    empty when the turn was not measured), as :attr:`bsv.frontend.segment.Segmentation.extra_sd` holds it."""
    if turn is None:
        return {}
    return {name: sd * abs(turn) for name, sd in TURN_SD_PER_DEG.items()}


def turn_warning(turn: float | None) -> str | None:
    """The warning for a subject turned more than :data:`TURN_WARN_DEG` (None otherwise or when not measured)."""
    if turn is None or abs(turn) <= TURN_WARN_DEG:
        return None
    side = "left" if turn > 0 else "right"
    return (f"the subject stood turned {abs(turn):.0f} deg from facing the front camera (the {side} side back): the "
            "limbs' boundaries are less certain (turned 8-10 deg, their volumes erred 0.4 percentage points more on "
            f"average); have the subject face the front camera squarely (within {TURN_WARN_DEG:g} deg) and capture again")


__all__ = ["LINES", "TURN_SD_PER_DEG", "TURN_WARN_DEG", "turn_deg", "turn_extra_sd", "turn_warning"]

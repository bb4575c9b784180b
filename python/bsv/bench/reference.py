"""Published numbers the benchmark is compared with (DESIGN.md "Paper results to beat").

``PAPER``: the source paper's mean RVE (%) on FAUST per segment, in its NoEr and L5Ca conditions (it
reports Cali equal to NoEr and L515 close to it; we compare Cali with NoEr and L515 with NoEr too, and
say so in the report). ``P2PV``: Point2PartVolume's accuracies (100 - RVE, %) on BUFF and PDT13.
"""

from __future__ import annotations

from ..types import TRUNK_LIMBS

#: The nine segments of trunk_limbs, in report order.
SEGMENTS: tuple[str, ...] = TRUNK_LIMBS
#: Every volume the synthetic benchmark records: segments, then aggregates.
MEASURED: tuple[str, ...] = (*SEGMENTS, "arm_l", "arm_r", "leg_l", "leg_r", "trunk_limbs")
#: Report rows of the paper-style table.
PAPER_ROWS: tuple[str, ...] = ("trunk_limbs", *SEGMENTS)

#: The paper's mean RVE (%) on FAUST: {segment: (NoEr, L5Ca)}.
PAPER: dict[str, tuple[float, float]] = {
    "trunk_limbs": (1.23, 2.13),
    "torso": (5.07, 6.72),
    "upper_arm_l": (5.82, 14.30),
    "upper_arm_r": (10.06, 19.26),
    "forearm_l": (6.21, 5.71),
    "forearm_r": (4.92, 6.99),
    "thigh_l": (5.90, 6.27),
    "thigh_r": (6.82, 5.43),
    "shin_l": (7.13, 8.48),
    "shin_r": (8.33, 9.40),
}

#: Which paper column each condition is compared with.
PAPER_COLUMN: dict[str, int] = {"noer": 0, "l515": 0, "cali": 0, "l5ca": 1}

#: Rows of the Point2PartVolume-style table.
P2PV_ROWS: tuple[str, ...] = ("torso", "arm_l", "arm_r", "leg_l", "leg_r", "trunk_limbs")
#: Point2PartVolume accuracy (100 - RVE, %) on BUFF.
P2PV_BUFF: dict[str, float] = {
    "torso": 88.64, "arm_l": 96.97, "arm_r": 98.38, "leg_l": 93.53, "leg_r": 89.88, "trunk_limbs": 89.26,
}
#: Point2PartVolume accuracy (100 - RVE, %) on PDT13.
P2PV_PDT13: dict[str, float] = {
    "torso": 87.41, "arm_l": 28.09, "arm_r": 29.98, "leg_l": 69.31, "leg_r": 61.01, "trunk_limbs": 84.39,
}

#: Conditions of the virtual rig, in report order.
CONDITIONS: tuple[str, ...] = ("noer", "l515", "cali", "l5ca")
#: Conditions with a calibration error (the floor is computed for them).
CALIBRATED: frozenset[str] = frozenset({"cali", "l5ca"})


def paper_value(segment: str, condition: str) -> float | None:
    """The paper's mean RVE (%) for a segment and condition, or None when it has none."""
    row = PAPER.get(segment)
    col = PAPER_COLUMN.get(condition)
    if row is None or col is None:
        return None
    return row[col]


def ordered_conditions(conditions: set[str]) -> list[str]:
    """Conditions in the benchmark's order (:data:`CONDITIONS`; unknown ones last, by name)."""
    return sorted(conditions, key=lambda c: (CONDITIONS.index(c) if c in CONDITIONS else len(CONDITIONS), c))

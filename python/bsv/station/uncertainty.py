"""Intervals of a result's volumes and the comparison of two sessions (the one place of the rule).

A result's volumes JSON may carry ``"intervals": {"level": 0.95, "volumes_l": {name: [lo, hi]},
"ratios": {name: [lo, hi]}}`` (written by the pipeline when it estimates them). When it does not, the
station falls back to :data:`REPEATABILITY_PCT` / :data:`ASYMMETRY_REPEATABILITY_PTS`, a per-segment
repeatability table built from the anchors of DESIGN.md ("Facts from round 2"): the calibration floor
of trunk_limbs (1.6-2.5 %, the upper end used), the forearm/upper-arm floors (3.4-9.4 %, the upper end),
the smallest real difference of circumference-derived leg volume (3.4-3.8 %) widened for the camera
path's thigh/shin cut-line spread, and the 15-19 point floor of a forearm asymmetry. The pages label
such intervals "repeatability table", not "from the pipeline".

Two sessions differ *significantly* in a segment only when ``|change| > sqrt(h_a^2 + h_b^2)``, with
``h`` the half-widths of the two 95 % intervals (the combined uncertainty of the difference).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

#: Half-width of the 95 % interval of one measurement, % of the segment volume (fallback table).
REPEATABILITY_PCT: dict[str, float] = {
    "torso": 2.5, "trunk_limbs": 2.5, "whole": 2.5,
    "upper_arm_l": 9.4, "upper_arm_r": 9.4, "forearm_l": 9.4, "forearm_r": 9.4,
    "arm_l": 9.4, "arm_r": 9.4,
    "thigh_l": 6.0, "thigh_r": 6.0, "shin_l": 6.0, "shin_r": 6.0, "leg_l": 6.0, "leg_r": 6.0,
    "head": 15.0, "hand_l": 15.0, "hand_r": 15.0, "foot_l": 15.0, "foot_r": 15.0,
}
#: Half-width of the 95 % interval of one left/right asymmetry, percentage points (fallback table).
ASYMMETRY_REPEATABILITY_PTS: dict[str, float] = {
    "asymmetry_upper_arm_pct": 19.0, "asymmetry_forearm_pct": 19.0, "asymmetry_arm_pct": 13.0,
    "asymmetry_thigh_pct": 8.5, "asymmetry_shin_pct": 8.5, "asymmetry_leg_pct": 8.5,
}
#: Label shown next to intervals taken from the table above.
TABLE_LABEL = "repeatability table (DESIGN.md anchors), 95 %"
#: Label shown next to intervals written by the pipeline.
PIPELINE_LABEL = "intervals from the pipeline"
#: The segments the station follows over time, in display order.
SEGMENTS = ("torso", "upper_arm_l", "upper_arm_r", "forearm_l", "forearm_r", "thigh_l", "thigh_r",
            "shin_l", "shin_r", "trunk_limbs")
#: The left/right asymmetries (ratios keys) followed over time.
ASYMMETRIES = ("asymmetry_upper_arm_pct", "asymmetry_forearm_pct", "asymmetry_thigh_pct", "asymmetry_shin_pct")


@dataclass(frozen=True)
class Interval:
    """A value with its 95 % interval and where the interval comes from (``pipeline`` or ``table``)."""

    value: float
    lo: float
    hi: float
    source: str

    @property
    def half_width(self) -> float:
        """Half the interval's width (the uncertainty used in comparisons)."""
        return 0.5 * (self.hi - self.lo)


def _given(volumes: dict[str, Any], section: str, name: str) -> tuple[float, float] | None:
    iv = volumes.get("intervals")
    if not isinstance(iv, dict):
        return None
    pair = (iv.get(section) or {}).get(name) if isinstance(iv.get(section), dict) else None
    if (isinstance(pair, list | tuple) and len(pair) == 2 and all(isinstance(x, int | float) for x in pair)
            and math.isfinite(pair[0]) and math.isfinite(pair[1]) and pair[0] <= pair[1]):
        return float(pair[0]), float(pair[1])
    return None


def volume_interval(volumes: dict[str, Any], name: str) -> Interval | None:
    """Segment ``name``'s volume (L) with its interval, or None when the segment is absent."""
    v = (volumes.get("volumes_l") or {}).get(name)
    if not isinstance(v, int | float):
        return None
    given = _given(volumes, "volumes_l", name)
    if given is not None:
        return Interval(float(v), given[0], given[1], "pipeline")
    h = abs(float(v)) * REPEATABILITY_PCT.get(name, 15.0) / 100.0
    return Interval(float(v), float(v) - h, float(v) + h, "table")


def ratio_interval(volumes: dict[str, Any], name: str) -> Interval | None:
    """Ratio / asymmetry ``name`` with its interval, or None when absent."""
    v = (volumes.get("ratios") or {}).get(name)
    if not isinstance(v, int | float):
        return None
    given = _given(volumes, "ratios", name)
    if given is not None:
        return Interval(float(v), given[0], given[1], "pipeline")
    h = ASYMMETRY_REPEATABILITY_PTS.get(name, 19.0)
    return Interval(float(v), float(v) - h, float(v) + h, "table")


def source_label(sources: set[str]) -> str:
    """The label of a set of interval sources, as the pages show it."""
    if sources == {"pipeline"}:
        return PIPELINE_LABEL
    if sources == {"table"}:
        return TABLE_LABEL
    return f"{PIPELINE_LABEL} where given, else the {TABLE_LABEL}"


@dataclass(frozen=True)
class Change:
    """The change of one segment from session A to session B."""

    segment: str
    a_l: float
    b_l: float
    change_ml: float
    change_pct: float
    combined_ml: float
    significant: bool
    sources: tuple[str, str]


def compare(a: dict[str, Any], b: dict[str, Any], segments: tuple[str, ...] = SEGMENTS) -> list[Change]:
    """Per-segment change from volumes JSON ``a`` to ``b`` (mL and % of A), significant only when it
    exceeds the combined uncertainty ``sqrt(h_a^2 + h_b^2)`` of the two 95 % intervals."""
    out = []
    for name in segments:
        ia, ib = volume_interval(a, name), volume_interval(b, name)
        if ia is None or ib is None:
            continue
        d = ib.value - ia.value
        comb = math.hypot(ia.half_width, ib.half_width)
        out.append(Change(name, ia.value, ib.value, d * 1e3, 100.0 * d / ia.value if ia.value else math.nan,
                          comb * 1e3, abs(d) > comb, (ia.source, ib.source)))
    return out


__all__ = ["ASYMMETRIES", "ASYMMETRY_REPEATABILITY_PTS", "PIPELINE_LABEL", "REPEATABILITY_PCT", "SEGMENTS",
           "TABLE_LABEL", "Change", "Interval", "compare", "ratio_interval", "source_label", "volume_interval"]

"""The subject's sex on the camera path: given by the user, or read from the capture.

**Why the camera path needs it.** MakeHuman's women and men differ in where a segment boundary lies
against the joints and the skin the camera sees: over 40 cohort subjects (seeds 0-3) the knee loop's centroid
lies 18.9 mm below the knee joint on women and 12.3 mm on men, the shoulder loop's +1.9 against -5.3 mm.
The camera path's cut lines and its average (gender 0.5) template put one boundary for both, so on the
eighty subjects of seeds 0-7 every limb of a woman came out 1.3-2.4 % too large on average and a man's
thighs and shins 1.5-3.1 % too small, the torso the other way (benchmarks/BENCH.md, round 2 session 21).

**The score.** The sex enters as a score ``s`` from +1 (female) to -1 (male), 0 for the average body
(:attr:`SexEstimate.score`): the knee line moves by ``s * knee_shift_sex`` and the outer hip corners by
``s * hip_raise_sex`` (:class:`bsv.frontend.segment.SegmentParams`), and the template's MakeHuman gender is
``(1 - s) / 2`` (:func:`bsv.posed_template.posed_template`). Given (``bsv process --sex``, a clinic's subject
record) it is +-1. Otherwise it is ``2 p - 1``, ``p`` the probability that the subject is a woman from a
logistic model (:data:`SEX_MODEL`) of four measurements of the capture that do not scale with the body's size
(:func:`sex_measurements`): the chest's relief across (the front surface beside the midline against the
midline, at 0.3 of the trunk below the shoulders), the arm's length over the stature, the shoulder width
over the hip width and the body's depth over the trunk length. An uncertain subject thus moves little, and
a confident one nearly as far as a given sex. Learned on cohort seeds 11-18 (80 subjects, clinic room, noer)
by ``benchmarks/learn_sex_model.py``; held out, seeds 0-7 (see there and BENCH.md).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..types import SEXES
from .errors import SegmentationError

#: The sexes a user may give (``bsv process --sex``, :data:`bsv.types.SEXES`), with their scores.
SEX_SCORES: dict[str, float] = {s: 1.0 if s == "female" else -1.0 for s in SEXES}
#: The measurements of :func:`sex_measurements`, in the order of :data:`SEX_MODEL`'s coefficients.
SEX_MEASUREMENTS: tuple[str, ...] = ("chest_relief", "arm_to_stature", "shoulder_to_hip", "depth_to_trunk")
#: The logistic model of ``p(female)``: ``1 / (1 + exp(-(intercept + sum coef_k (m_k - mean_k) / scale_k)))``,
#: each measurement ``m_k`` first clipped to ``range`` (the training cohort's range widened by a quarter of its
#: span on each side: a landmark misplaced by centimetres cannot make one measurement decide alone).
#: Ridge-regularised (lambda 1 on the standardised measurements) on cohort seeds 11-18 by
#: ``benchmarks/learn_sex_model.py`` (78 of 80 on the right side of 1/2; one subject named the wrong sex). Held out, seeds 0-7 (80 subjects,
#: clinic room, noer): all 80 on the right side of 1/2, 71 % named (p beyond :data:`NAMED_AT`), none wrongly;
#: the score lies 0.08 of a given sex's shift from the truth on average (0.48 at worst). Ridge 0.3 named more
#: (80 %) but was surer of its training mistake; 3 named 61 %.
SEX_MODEL: dict[str, Any] = {
    "intercept": 0.0461,
    "mean": {"chest_relief": 0.01767, "arm_to_stature": 0.312, "shoulder_to_hip": 1.852, "depth_to_trunk": 0.4566},
    "scale": {"chest_relief": 0.007383, "arm_to_stature": 0.009499, "shoulder_to_hip": 0.1463, "depth_to_trunk": 0.05665},
    "coef": {"chest_relief": 1.752, "arm_to_stature": -1.171, "shoulder_to_hip": -1.301, "depth_to_trunk": -0.895},
    "range": {"chest_relief": (-0.009042, 0.03698), "arm_to_stature": (0.2829, 0.3493), "shoulder_to_hip": (1.347, 2.284),
              "depth_to_trunk": (0.2568, 0.6801)},
}
#: A probability at least this far from 1/2 names the sex in the result (``sex``); the score uses ``p`` itself.
NAMED_AT = 0.9
#: Where the measurements are taken, as fractions of the trunk length (mid-shoulder to mid-hip) below the
#: mid-shoulder: the chest's relief, and the body's depth.
CHEST_LEVEL = 0.30
DEPTH_LEVEL = 0.45
#: Half the height (metres) of the horizontal band a measurement reads, and the width of its columns across.
BAND_M = 0.01
COLUMN_M = 0.01
#: Only the points within this fraction of the shoulder width of the midline (the arms hang farther out).
WITHIN_SHOULDERS = 0.45
#: The chest's relief: the front-most point of the columns 4-11 cm to either side of the midline against
#: that of the midline's column.
RELIEF_COLUMNS = range(4, 12)


@dataclass(frozen=True)
class SexEstimate:
    """The sex the camera path took for one capture (:mod:`bsv.frontend.sex`)."""

    #: +1 female ... -1 male; 0 the average body. What the cut lines and the template take.
    score: float
    #: "given" (the user's), "inferred" (from the capture) or "unknown" (not given, not measurable).
    source: str
    #: "female" or "male" when given or inferred with ``p`` beyond :data:`NAMED_AT`; None otherwise.
    sex: str | None = None
    #: The model's probability that the subject is a woman (inferred only).
    p_female: float | None = None
    #: The measurements of :func:`sex_measurements` (inferred only; NaN: not measurable).
    measurements: dict[str, float] = field(default_factory=dict)

    @property
    def gender(self) -> float:
        """MakeHuman's gender macro of the template that goes with the score: 0 female, 1 male, 0.5 average."""
        return (1.0 - self.score) / 2.0

    def to_json(self) -> dict[str, Any]:
        """volumes.json's ``sex`` record."""
        out: dict[str, Any] = {"sex": self.sex, "source": self.source, "score": round(self.score, 4),
                               "template_gender": round(self.gender, 4)}
        if self.p_female is not None:
            out["p_female"] = round(self.p_female, 4)
        if self.measurements:
            out["measurements"] = {k: (round(v, 5) if math.isfinite(v) else None) for k, v in self.measurements.items()}
            out["build_score"] = round(build_score(self.measurements), 4)
        return out

    def sentence(self) -> str:
        """One sentence for the report (:func:`describe` of :meth:`to_json`)."""
        return describe(self.to_json())


def describe(record: Mapping[str, Any]) -> str:
    """One sentence for the report from volumes.json's ``sex`` record (:meth:`SexEstimate.to_json`)."""
    source = record.get("source")
    if source == "given":
        return f"Sex: {record.get('sex')}, as given."
    if source != "inferred":
        return "Sex: not given and not measurable in the capture; the average body's boundaries and template."
    named = record.get("sex") or "undecided"
    return (f"Sex: not given; read from the capture as {named} (p(female) {float(record.get('p_female', 0.5)):.2f}): "
            f"the knee and hip lines and the template's build moved by {float(record.get('score', 0.0)):+.2f} of a given "
            "sex's (+1 female, -1 male).")


def build_score(measurements: Mapping[str, float]) -> float:
    """The subject's build from the capture's measurements (:func:`sex_measurements`): the trunk's depth
    (``depth_to_trunk``, clipped to :data:`SEX_MODEL`'s range) against the cohort's, in its sds (the same table
    as the sex model's; correlation 0.8 with the BMI on the cohort); 0 (the average body) when not measurable."""
    v = float(measurements.get("depth_to_trunk", float("nan")))
    if not math.isfinite(v):
        return 0.0
    lo, hi = SEX_MODEL["range"]["depth_to_trunk"]
    return (min(max(v, lo), hi) - SEX_MODEL["mean"]["depth_to_trunk"]) / SEX_MODEL["scale"]["depth_to_trunk"]


def given(sex: str) -> SexEstimate:
    """The estimate of a sex the user gives ("female" or "male"); SegmentationError otherwise."""
    if sex not in SEX_SCORES:
        raise SegmentationError(f"sex {sex!r}: give one of {', '.join(SEX_SCORES)}")
    return SexEstimate(SEX_SCORES[sex], "given", sex)


def from_score(score: float) -> SexEstimate:
    """The estimate of a score a caller fixes (``SegmentParams.sex_score``): +-1 names the sex."""
    if not (-1.0 <= score <= 1.0):
        raise SegmentationError(f"sex_score must lie in [-1, 1] (+1 female, -1 male, 0 the average body), got {score!r}")
    name = next((k for k, v in SEX_SCORES.items() if v == score), None)
    return SexEstimate(float(score), "given", name)


def template_gender(estimate: SexEstimate | None) -> float | None:
    """The template's gender for an estimate read from the capture (:attr:`SexEstimate.gender`); None (the
    template of the given sex, or the average one) otherwise."""
    return estimate.gender if estimate is not None and estimate.source == "inferred" else None


def female_probability(measurements: Mapping[str, float]) -> float | None:
    """:data:`SEX_MODEL`'s probability that the subject of ``measurements`` is a woman; None when one is
    missing or not finite."""
    z = 0.0
    for k in SEX_MEASUREMENTS:
        v = measurements.get(k, float("nan"))
        if not math.isfinite(v):
            return None
        lo, hi = SEX_MODEL["range"][k]
        z += SEX_MODEL["coef"][k] * (min(max(v, lo), hi) - SEX_MODEL["mean"][k]) / SEX_MODEL["scale"][k]
    z += SEX_MODEL["intercept"]
    return 1.0 / (1.0 + math.exp(-max(-50.0, min(50.0, z))))


def inferred(measurements: Mapping[str, float]) -> SexEstimate:
    """The estimate from the capture's measurements (:func:`sex_measurements`): ``score = 2 p - 1``."""
    m = {k: float(v) for k, v in measurements.items()}
    p = female_probability(m)
    if p is None:
        return SexEstimate(0.0, "unknown", measurements=m)
    name = "female" if p >= NAMED_AT else "male" if p <= 1.0 - NAMED_AT else None
    return SexEstimate(2.0 * p - 1.0, "inferred", name, p, m)


def _band(q: np.ndarray, level: float) -> np.ndarray:
    return q[np.abs(q[:, 1] + level) < BAND_M]


def _columns(q: np.ndarray, front: bool) -> dict[int, float]:
    """Per column across (index of :data:`COLUMN_M`), the front-most (``front``) or back-most z."""
    idx = np.round(q[:, 0] / COLUMN_M).astype(int)
    out = {}
    for i in np.unique(idx):
        z = q[idx == i, 2]
        if z.size >= 3:
            out[int(i)] = float(z.max() if front else z.min())
    return out


def sex_measurements(joints: Mapping[str, np.ndarray], frame: np.ndarray | None, front_points: np.ndarray,
                     back_points: np.ndarray, stature: float) -> dict[str, float]:
    """The measurements of :data:`SEX_MEASUREMENTS` from the joints (world frame, metres; shoulders, elbows,
    wrists and hips of both sides), their body ``frame`` (rows: left, up, forward;
    :func:`bsv.frontend.landmarks.body_frame`), the person's points seen by the front and the back camera
    (world frame) and the stature (metres). A measurement whose inputs are missing is NaN."""
    nan = float("nan")
    out = dict.fromkeys(SEX_MEASUREMENTS, nan)
    need = [f"{k}_{s}" for k in ("shoulder", "elbow", "wrist", "hip") for s in "lr"]
    if frame is None or any(k not in joints or not np.all(np.isfinite(joints[k])) for k in need):
        return out
    j = {k: np.asarray(joints[k], dtype=np.float64) for k in need}
    top = (j["shoulder_l"] + j["shoulder_r"]) / 2
    trunk = float(np.linalg.norm(top - (j["hip_l"] + j["hip_r"]) / 2))
    sw = float(np.linalg.norm(j["shoulder_l"] - j["shoulder_r"]))
    hw = float(np.linalg.norm(j["hip_l"] - j["hip_r"]))
    arm = float(np.mean([np.linalg.norm(j[f"shoulder_{s}"] - j[f"elbow_{s}"]) + np.linalg.norm(j[f"elbow_{s}"] - j[f"wrist_{s}"])
                         for s in "lr"]))
    if trunk <= 0 or hw <= 0:
        return out
    if math.isfinite(stature) and stature > 0:
        out["arm_to_stature"] = arm / stature
    out["shoulder_to_hip"] = sw / hw

    def local(points: np.ndarray) -> np.ndarray:
        q = (np.asarray(points, dtype=np.float64).reshape(-1, 3) - top) @ np.asarray(frame).T
        return q[np.abs(q[:, 0]) < WITHIN_SHOULDERS * sw]

    qf, qb = local(front_points), local(back_points)
    chest = _columns(_band(qf, CHEST_LEVEL * trunk), front=True)
    sides = [chest[i] for i in (*RELIEF_COLUMNS, *(-c for c in RELIEF_COLUMNS)) if i in chest]
    if 0 in chest and sides:
        out["chest_relief"] = max(sides) - chest[0]
    f, b = _band(qf, DEPTH_LEVEL * trunk), _band(qb, DEPTH_LEVEL * trunk)
    if len(f) >= 3 and len(b) >= 3:
        out["depth_to_trunk"] = float(f[:, 2].max() - b[:, 2].min()) / trunk
    return out


__all__ = [
    "NAMED_AT",
    "SEX_MEASUREMENTS",
    "SEX_MODEL",
    "SEX_SCORES",
    "SexEstimate",
    "build_score",
    "describe",
    "female_probability",
    "from_score",
    "given",
    "inferred",
    "sex_measurements",
    "template_gender",
]

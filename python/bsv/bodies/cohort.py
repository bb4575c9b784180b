"""A deterministic synthetic cohort of plausible adults with ground-truth segment volumes.

Subject i of seed s depends only on (s, i): even indices are women, odd indices men. Stature is drawn
from normal distributions (women 1.63 +- 0.065 m, men 1.77 +- 0.07 m, clipped at 2.5 sd), BMI from a
normal 25 +- 4 truncated to [18.5, 35], age 20-65 years, MakeHuman's gender 0-0.15 (women) or 0.85-1 (men), a
muscle start value 0.3-0.6, proportions 0.3-0.7 (``macros``: :data:`MACRO_RANGES`; ``wide`` draws gender 0-0.5 /
0.5-1, muscle and proportions 0.1-0.9), random race mix; A-pose: arms 25-50 deg below horizontal (``arm_range``, e.g. 15-60 for wide
A-poses: :data:`ARM_DOWN_RANGE_DEG`, :data:`WIDE_ARM_DOWN_RANGE_DEG`), elbows 0-20 deg, hips 0-6 deg
(small left/right differences). MakeHuman LOCAL modifiers (stomach, buttocks, hip, pelvis, torso,
breast, arms, legs) are applied by default: each modifier with probability 1/2, value uniform in
+-0.6; left/right pairs share a value except with probability 1/5 (asymmetric). Height and weight
(then muscle) are solved for the drawn stature and BMI. A body whose arms enter the torso or thighs, or
whose thighs enter each other, has the colliding arm(s) raised / legs spread step by step until it is free;
an arm is raised below the arm range's low bound only when that bound is above 10 deg and the body is not
free before (:data:`ARM_FREE_FLOOR_DEG`; none of the default cohorts of seeds 0-3 needs it).
"""

from __future__ import annotations

import json
from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import TypeVar

import numpy as np

from ..errors import OutputExistsError
from .body import Body, SolveError, make_body, solve_stature_bmi
from .collide import penetrations
from .meshio import ply_bytes
from .model import Phenotype
from .pose import Pose, PoseError

#: The central MakeHuman local modifiers a subject may get (each with probability 1/2, value in +-0.6).
LOCAL_CENTRAL = ("stomach/stomach-pregnant", "stomach/stomach-tone", "buttocks/buttocks-volume",
                 "hip/hip-scale-depth", "hip/hip-scale-horiz", "pelvis/pelvis-tone", "torso/torso-scale-depth",
                 "torso/torso-scale-horiz", "torso/torso-vshape", "torso/measure-waist-circ",
                 "torso/measure-bust-circ", "torso/torso-muscle-pectoral", "breast/breast-volume-vert",
                 "breast/breast-dist")
#: The left/right local modifier pairs (``{s}``: l or r), drawn like :data:`LOCAL_CENTRAL`, sides asymmetric
#: with probability 1/5.
LOCAL_SIDED = ("arms/{s}-upperarm-fat", "arms/{s}-upperarm-muscle", "arms/{s}-lowerarm-fat",
               "arms/{s}-lowerarm-muscle", "legs/{s}-upperleg-fat", "legs/{s}-upperleg-muscle",
               "legs/{s}-lowerleg-fat", "legs/{s}-lowerleg-muscle")

#: The cohort's arm angle below the horizontal (degrees, both sides drawn around one value): the A-pose
#: range the standard cohort covers.
ARM_DOWN_RANGE_DEG: tuple[float, float] = (25.0, 50.0)
#: A wider A-pose range (``bsv bench synth --arm-down 15,60``): arms from nearly horizontal to close to
#: the body, where the camera path's shoulder boundary moves (BENCH.md, round 2 session 10).
WIDE_ARM_DOWN_RANGE_DEG: tuple[float, float] = (15.0, 60.0)
#: The cohort's hip abduction (degrees, each thigh outward of the vertical, both sides drawn around one value):
#: the stance the standard cohort covers.
HIP_ABDUCTION_RANGE_DEG: tuple[float, float] = (0.0, 6.0)
#: A narrow stance (``bsv bench synth --hip-abduction 0,1.5``): feet nearly together, where a heavier subject's
#: thighs touch below the crotch and the gap between the legs opens only under them (BENCH.md, round 2
#: session 30).
NARROW_HIP_ABDUCTION_RANGE_DEG: tuple[float, float] = (0.0, 1.5)
#: The cohort's palms (degrees turned in from facing forward, :attr:`bsv.bodies.pose.Pose.palm_in_l`): forward,
#: as the standard cohort has always stood.
PALM_IN_RANGE_DEG: tuple[float, float] = (0.0, 0.0)
#: Palms from forward to facing the body and a little past it (``bsv bench synth --palm-in 0,120``), as people
#: stand when nobody tells them to turn their palms forward; MakeHuman's hand with no twist lies at about 118.
#: The camera path's template must turn its forearms likewise (BENCH.md, round 2 session 44).
RELAXED_PALM_IN_RANGE_DEG: tuple[float, float] = (0.0, 120.0)
#: The bounds a palm range must lie in (degrees; see :func:`check_palm_range`).
_PALM_IN_LIMITS_DEG: tuple[float, float] = (-30.0, 150.0)
#: The cohort's elbow flexion (degrees, :attr:`bsv.bodies.pose.Pose.elbow_l`, both sides drawn around one value): arms
#: nearly straight, as the standard cohort has always stood.
ELBOW_RANGE_DEG: tuple[float, float] = (0.0, 20.0)
#: Elbows bent 20-40 deg (``bsv bench synth --elbow 20,40``), as relaxed arms hang when nobody asks for them
#: straight: the camera path's forearms lose more than the oracle labels' (BENCH.md, round 2 session 45).
FLEXED_ELBOW_RANGE_DEG: tuple[float, float] = (20.0, 40.0)
#: The bounds an elbow range must lie in (degrees; see :func:`check_elbow_range`).
_ELBOW_LIMITS_DEG: tuple[float, float] = (0.0, 90.0)
#: The cohort's turn about the vertical (degrees, :attr:`bsv.bodies.pose.Pose.turn_deg`): facing the front camera
#: squarely, as the standard cohort always has.
TURN_RANGE_DEG: tuple[float, float] = (0.0, 0.0)
#: Subjects standing up to 10 deg off square (``bsv bench synth --turn -10,10``), as they do when nobody lines
#: them up with the cameras (BENCH.md, round 2 session 44).
TURNED_RANGE_DEG: tuple[float, float] = (-10.0, 10.0)
#: The bounds a turn range must lie in (degrees; see :func:`check_turn_range`).
_TURN_LIMITS_DEG: tuple[float, float] = (-30.0, 30.0)
#: ``bsv bench synth --bmi-shift``: the BMI added to every subject's draw for a heavier cohort (the standard
#: draw is 25 +- 4 within 18.5-35; +8 gives about 27-41, where the camera path's boundaries drift, BENCH.md round 2
#: session 30), and the bounds a shift must lie in.
HEAVY_BMI_SHIFT = 8.0
_BMI_SHIFT_LIMITS: tuple[float, float] = (-5.0, 15.0)
#: The lowest angle (degrees below the horizontal) the collision loop raises a colliding arm to: the arm
#: range's low bound, or this when the bound is higher (a body must come out free; the cohorts before
#: ``arm_range`` existed used this floor).
ARM_FREE_FLOOR_DEG = 10.0
#: The bounds an arm range must lie in (degrees below the horizontal; see :func:`check_arm_range`).
_ARM_DOWN_LIMITS_DEG: tuple[float, float] = (0.0, 80.0)
#: The bounds a hip abduction range must lie in (degrees; see :func:`check_leg_range`).
_HIP_ABDUCTION_LIMITS_DEG: tuple[float, float] = (0.0, 20.0)


@dataclass(frozen=True)
class MacroRanges:
    """The intervals a cohort draws MakeHuman's macro modifiers from (each one uniform draw, so that every
    other draw of a subject stays the same whatever the ranges)."""

    #: A woman's gender (0 female ... 1 male).
    gender_female: tuple[float, float]
    #: A man's gender.
    gender_male: tuple[float, float]
    #: The muscle start value (the solve for stature and BMI may move it).
    muscle: tuple[float, float]
    #: MakeHuman's "proportions" (0 uncommon ... 1 ideal).
    proportions: tuple[float, float]


#: The macro ranges a cohort may be drawn with (``macros`` of :func:`subject`, ``bsv bench synth --macros``):
#: ``standard``, the cohort as it always was, each sex at its end of MakeHuman's gender scale and the middle of
#: the muscle and proportions scales; ``wide``, women and men anywhere on their half of the gender scale
#: (androgynous bodies included) and muscle and proportions from 0.1 to 0.9, as a generator drawing the
#: macros over their whole range would (BENCH.md, round 2 session 41: the camera path's boundaries move with
#: them).
MACRO_RANGES: dict[str, MacroRanges] = {
    "standard": MacroRanges((0.0, 0.15), (0.85, 1.0), (0.3, 0.6), (0.3, 0.7)),
    "wide": MacroRanges((0.0, 0.5), (0.5, 1.0), (0.1, 0.9), (0.1, 0.9)),
}


def check_macros(macros: str) -> MacroRanges:
    """The :data:`MACRO_RANGES` entry named ``macros``; a PoseError naming the known ones otherwise."""
    try:
        return MACRO_RANGES[macros]
    except (KeyError, TypeError):
        raise PoseError(f"macro ranges {macros!r}: use one of {', '.join(MACRO_RANGES)}") from None


@dataclass
class Subject:
    """One cohort member: its draws, the solved phenotype, the pose and the posed labelled body."""

    index: int
    seed: int
    sex: str
    stature_target: float
    bmi_target: float
    phenotype: Phenotype
    pose: Pose
    body: Body
    #: What :mod:`bsv.bodies.variants` changed on the body (empty for a plain cohort member).
    variant: dict = field(default_factory=dict)
    #: The interval the arm angles were drawn from (``arm_range`` of :func:`subject`; degrees below the
    #: horizontal): with (index, seed) it reproduces the subject.
    arm_range: tuple[float, float] = ARM_DOWN_RANGE_DEG
    #: The interval the hips' abduction was drawn from (``leg_range`` of :func:`subject`; degrees).
    leg_range: tuple[float, float] = HIP_ABDUCTION_RANGE_DEG
    #: The BMI added to the drawn one (``bmi_shift`` of :func:`subject`).
    bmi_shift: float = 0.0
    #: The interval the palms' turn was drawn from (``palm_range`` of :func:`subject`; degrees).
    palm_range: tuple[float, float] = PALM_IN_RANGE_DEG
    #: The interval the body's turn about the vertical was drawn from (``turn_range`` of :func:`subject`; degrees).
    turn_range: tuple[float, float] = TURN_RANGE_DEG
    #: The interval the elbows' flexion was drawn from (``elbow_range`` of :func:`subject`; degrees).
    elbow_range: tuple[float, float] = ELBOW_RANGE_DEG
    #: The macro ranges the subject was drawn with (``macros`` of :func:`subject`: :data:`MACRO_RANGES`).
    macros: str = "standard"

    def volumes_l(self) -> dict[str, float]:
        """Ground-truth volumes (litres): 14 segments and aggregates."""
        return self.body.volumes_l()

    def info(self) -> dict:
        """JSON-ready description (draws, phenotype, pose, the arm range ``arm_down_deg``, the hips'
        ``hip_abduction_deg``, the palms' ``palm_in_deg``, the body's ``turn_deg``, the elbows' ``elbow_deg``, the
        ``macros`` ranges, measured
        stature/BMI)."""
        return {"index": self.index, "seed": self.seed, "sex": self.sex,
                "stature_target_m": self.stature_target, "bmi_target": self.bmi_target,
                "stature_m": self.body.stature, "bmi": self.body.bmi, "volume_l": self.body.volume_l,
                "phenotype": asdict(self.phenotype), "pose": asdict(self.pose),
                "arm_down_deg": [float(a) for a in self.arm_range],
                "hip_abduction_deg": [float(a) for a in self.leg_range],
                "palm_in_deg": [float(a) for a in self.palm_range],
                "turn_deg": [float(a) for a in self.turn_range],
                "elbow_deg": [float(a) for a in self.elbow_range],
                "bmi_shift": float(self.bmi_shift),
                "macros": self.macros,
                **({"variant": self.variant} if self.variant else {})}


def _draw_local(rng: np.random.Generator) -> dict[str, float]:
    out: dict[str, float] = {}
    for name in LOCAL_CENTRAL:
        if rng.random() < 0.5:
            out[name] = round(float(rng.uniform(-0.6, 0.6)), 4)
        else:
            rng.uniform()  # keep the stream aligned
    for pat in LOCAL_SIDED:
        use, val, asym, val_r = rng.random(), rng.uniform(-0.6, 0.6), rng.random(), rng.uniform(-0.6, 0.6)
        if use < 0.5:
            out[pat.format(s="l")] = round(float(val), 4)
            out[pat.format(s="r")] = round(float(val_r if asym < 0.2 else val), 4)
    return out


def _solve(ph: Phenotype, stature: float, bmi: float, pose: Pose) -> tuple[Phenotype, float]:
    """Solve, shrinking an unreachable BMI into the reachable range."""
    try:
        return solve_stature_bmi(stature, bmi, ph, pose), bmi
    except SolveError as e:
        if e.reachable is None:
            raise
        lo, hi = e.reachable
        b2 = float(np.clip(bmi, lo + 0.2, hi - 0.2))
        return solve_stature_bmi(stature, b2, ph, pose), b2


def check_arm_range(arm_range: Sequence[float] | str) -> tuple[float, float]:
    """``arm_range`` (two angles, or the command line's ``"LOW,HIGH"``) as floats, or PoseError when it is
    not an increasing pair inside [0, 80] degrees below the horizontal. This is narrower than
    :meth:`Pose.validate`'s [-10, 85], which bounds any pose the skinning accepts: a cohort subject is in
    an A-pose (no arm above the horizontal), and beyond 80 deg a collision-free A-pose cannot be kept (the
    arm meets the torso)."""
    return _angle_range(arm_range, "arm range", "two angles in degrees below the horizontal, LOW < HIGH, e.g. 15,60",
                        _ARM_DOWN_LIMITS_DEG, " (degrees below the horizontal)")


def _angle_range(value: Sequence[float] | str, name: str, give: str, limits: tuple[float, float],
                 unit_note: str = "", equal_ok: bool = False) -> tuple[float, float]:
    """``value`` (two angles, or ``"LOW,HIGH"``) as an increasing pair of floats inside ``limits`` (with
    ``equal_ok``, LOW = HIGH too: one angle), or PoseError naming ``name`` and, for a value that is not two
    numbers, what to ``give``."""
    parts = value.split(",") if isinstance(value, str) else value
    try:
        lo, hi = (float(x) for x in parts)
    except (TypeError, ValueError) as exc:
        raise PoseError(f"{name} {value!r}: give {give}") from exc
    low, high = limits
    if not (low <= lo <= hi <= high and (equal_ok or lo < hi)):
        raise PoseError(f"{name} ({lo:g}, {hi:g}) deg: need {low:g} <= low {'<=' if equal_ok else '<'} high "
                        f"<= {high:g}{unit_note}")
    return lo, hi


def check_leg_range(leg_range: Sequence[float] | str) -> tuple[float, float]:
    """``leg_range`` (two hip abduction angles, or the command line's ``"LOW,HIGH"``) as floats, or PoseError
    when it is not an increasing pair inside [0, 20] degrees (each thigh outward of the vertical: from feet
    together to a wide stance; the collision loop may spread the legs further)."""
    return _angle_range(leg_range, "hip abduction range", "two angles in degrees, LOW < HIGH, e.g. 0,1.5",
                        _HIP_ABDUCTION_LIMITS_DEG)


def check_palm_range(palm_range: Sequence[float] | str) -> tuple[float, float]:
    """``palm_range`` (two angles the palms are turned in from facing forward, or the command line's
    ``"LOW,HIGH"``; LOW = HIGH for one angle) as floats, or PoseError when it is not an increasing pair inside
    [-30, 150] degrees (0 palms forward, 90 facing the body)."""
    return _angle_range(palm_range, "palm range", "two angles in degrees, LOW <= HIGH, e.g. 0,120",
                        _PALM_IN_LIMITS_DEG, " (degrees turned in from palms forward)", equal_ok=True)


def check_turn_range(turn_range: Sequence[float] | str) -> tuple[float, float]:
    """``turn_range`` (two angles of the body about the vertical, or the command line's ``"LOW,HIGH"``; LOW = HIGH
    for one angle) as floats, or PoseError when it is not an increasing pair inside [-30, 30] degrees (0 facing
    the front camera squarely)."""
    return _angle_range(turn_range, "turn range", "two angles in degrees, LOW <= HIGH, e.g. -10,10",
                        _TURN_LIMITS_DEG, " (degrees about the vertical from facing the front camera)", equal_ok=True)


def check_elbow_range(elbow_range: Sequence[float] | str) -> tuple[float, float]:
    """``elbow_range`` (two elbow flexion angles, or the command line's ``"LOW,HIGH"``; LOW = HIGH for one angle) as
    floats, or PoseError when it is not an increasing pair inside [0, 90] degrees (0 the arm straight)."""
    return _angle_range(elbow_range, "elbow range", "two angles in degrees, LOW <= HIGH, e.g. 20,40",
                        _ELBOW_LIMITS_DEG, " (degrees of elbow flexion from straight)", equal_ok=True)


T = TypeVar("T")


def _usage_checked(check: Callable[[str], T], text: str) -> T:
    """``check(text)``, its PoseError's message as an argparse usage error."""
    import argparse

    try:
        return check(text)
    except PoseError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def arm_range_arg(text: str) -> tuple[float, float]:
    """The argparse type of ``--arm-down LOW,HIGH`` (``bsv cohort``, ``bsv bench synth``):
    :func:`check_arm_range`, its message as the usage error."""
    return _usage_checked(check_arm_range, text)


def check_bmi_shift(shift: float | str) -> float:
    """``shift`` (kg/m^2, or the command line's text) as a float, or PoseError when it is not a finite number in
    [-5, 15]."""
    try:
        value = float(shift)
    except (TypeError, ValueError) as exc:
        raise PoseError(f"BMI shift {shift!r}: give a number of kg/m^2, e.g. {HEAVY_BMI_SHIFT:g}") from exc
    low, high = _BMI_SHIFT_LIMITS
    if not (np.isfinite(value) and low <= value <= high):
        raise PoseError(f"BMI shift {value:g}: need {low:g} <= shift <= {high:g} kg/m^2")
    return value


def bmi_shift_arg(text: str) -> float:
    """The argparse type of ``--bmi-shift`` (``bsv bench synth``): :func:`check_bmi_shift`, its message as the
    usage error."""
    return _usage_checked(check_bmi_shift, text)


def leg_range_arg(text: str) -> tuple[float, float]:
    """The argparse type of ``--hip-abduction LOW,HIGH`` (``bsv bench synth``): :func:`check_leg_range`, its
    message as the usage error."""
    return _usage_checked(check_leg_range, text)


def palm_range_arg(text: str) -> tuple[float, float]:
    """The argparse type of ``--palm-in LOW,HIGH`` (``bsv cohort``, ``bsv bench synth``): :func:`check_palm_range`,
    its message as the usage error."""
    return _usage_checked(check_palm_range, text)


def turn_range_arg(text: str) -> tuple[float, float]:
    """The argparse type of ``--turn LOW,HIGH`` (``bsv cohort``, ``bsv bench synth``): :func:`check_turn_range`,
    its message as the usage error."""
    return _usage_checked(check_turn_range, text)


def elbow_range_arg(text: str) -> tuple[float, float]:
    """The argparse type of ``--elbow LOW,HIGH`` (``bsv cohort``, ``bsv bench synth``): :func:`check_elbow_range`,
    its message as the usage error."""
    return _usage_checked(check_elbow_range, text)


def _range_help(what: str, default: tuple[float, float], default_note: str, other: tuple[float, float],
                other_note: str) -> str:
    """The help text of a cohort's ``--OPTION LOW,HIGH``: the interval ``what`` is drawn from, its ``default`` (and
    what that is) and the ``other`` range the bench uses for a class (and what for)."""
    (lo, hi), (olo, ohi) = default, other
    return (f"the interval {what} is drawn from, degrees (default {lo:g},{hi:g}{default_note}; {olo:g},{ohi:g} for "
            f"{other_note})")


def elbow_help() -> str:
    """The help text of ``--elbow LOW,HIGH`` (``bsv cohort``, ``bsv bench synth``)."""
    return _range_help("the elbows' flexion from straight", ELBOW_RANGE_DEG, ": arms nearly straight",
                       FLEXED_ELBOW_RANGE_DEG, "relaxed arms")


def turn_help() -> str:
    """The help text of ``--turn LOW,HIGH`` (``bsv cohort``, ``bsv bench synth``)."""
    return _range_help("the body's turn about the vertical", TURN_RANGE_DEG, ": facing the front camera squarely",
                       TURNED_RANGE_DEG, "subjects nobody lined up with the cameras")


def palm_in_help() -> str:
    """The help text of ``--palm-in LOW,HIGH`` (``bsv cohort``, ``bsv bench synth``)."""
    return _range_help("the palms' turn in from facing forward", PALM_IN_RANGE_DEG, ": palms forward",
                       RELAXED_PALM_IN_RANGE_DEG, "palms as people hold them unasked, up to facing the body")


def arm_down_help() -> str:
    """The help text of ``--arm-down LOW,HIGH`` (``bsv cohort``, ``bsv bench synth``)."""
    return _range_help("the arms' A-pose angle below the horizontal", ARM_DOWN_RANGE_DEG, "",
                       WIDE_ARM_DOWN_RANGE_DEG, "wide A-poses")


def _free_step(pose: Pose, hits: Iterable[str], arm_floor: float) -> Pose:
    """The collision loop's next pose: each arm that enters the torso or a thigh raised by 3 deg but not
    past ``arm_floor`` (the other arm unchanged), both legs spread by 1 deg when a thigh is involved."""
    raise_arm = {"l": False, "r": False}
    legs = 0.0
    for k in hits:
        part = k.split("/")[0]
        if part == "thigh_l":
            legs = 1.0
        else:
            raise_arm[part[-1]] = True
            if k.endswith(("thigh_l", "thigh_r")):
                legs = 1.0

    def arm(angle: float, side: str) -> float:
        return max(angle - 3.0, arm_floor) if raise_arm[side] else angle

    return Pose(arm(pose.arm_down_l, "l"), arm(pose.arm_down_r, "r"), pose.elbow_l, pose.elbow_r,
                pose.hip_abduction_l + legs, pose.hip_abduction_r + legs, pose.palm_in_l, pose.palm_in_r,
                pose.turn_deg)


def _palms(index: int, seed: int, lo: float, hi: float) -> tuple[float, float]:
    """Subject ``index``'s palm turns (left, right; degrees) drawn in [lo, hi] from a stream of their own: both
    around one value, the sides 10 deg apart at most; exactly ``lo`` for a single angle."""
    if hi <= lo:
        return lo, lo
    rng = np.random.default_rng([int(seed), int(index), 1])
    mid, d = rng.uniform(lo, hi), float(np.clip(rng.normal(0.0, 3.0), -5.0, 5.0))
    return float(np.clip(mid + d, lo, hi)), float(np.clip(mid - d, lo, hi))


def _turn(index: int, seed: int, lo: float, hi: float) -> float:
    """Subject ``index``'s turn about the vertical (degrees) drawn in [lo, hi] from a stream of its own; exactly
    ``lo`` for a single angle."""
    if hi <= lo:
        return lo
    return float(np.random.default_rng([int(seed), int(index), 2]).uniform(lo, hi))


def subject(index: int, seed: int = 0, local: bool = True, check: bool = True,
            arm_range: tuple[float, float] = ARM_DOWN_RANGE_DEG,
            leg_range: tuple[float, float] = HIP_ABDUCTION_RANGE_DEG, bmi_shift: float = 0.0,
            macros: str = "standard", palm_range: tuple[float, float] = PALM_IN_RANGE_DEG,
            turn_range: tuple[float, float] = TURN_RANGE_DEG,
            elbow_range: tuple[float, float] = ELBOW_RANGE_DEG) -> Subject:
    """Subject ``index`` of the cohort of ``seed`` (deterministic). ``arm_range``: the interval (degrees
    below the horizontal, :func:`check_arm_range`) the arms' angle is drawn from; the default keeps the
    cohort as it always was, a wider one (:data:`WIDE_ARM_DOWN_RANGE_DEG`) draws the same random numbers,
    so every other draw stays. Both arm angles stay inside ``arm_range`` unless a collision raises an arm
    (then down to ``min(low, ARM_FREE_FLOOR_DEG)``); a body that still collides there is a SolveError.
    ``leg_range`` likewise for the hips' abduction (degrees, :func:`check_leg_range`; a narrower stance,
    :data:`NARROW_HIP_ABDUCTION_RANGE_DEG`, draws the same random numbers); a collision spreads the legs past
    it. ``bmi_shift`` (:func:`check_bmi_shift`) is added to the drawn BMI, every draw the same (a BMI the body
    cannot reach is brought into its reachable range, as always). ``macros`` names the :data:`MACRO_RANGES`
    the gender, muscle and proportions are drawn from (the same draws, scaled to other intervals; a PoseError
    for an unknown name). ``palm_range`` (:func:`check_palm_range`) is the interval the palms' turn in from
    facing forward is drawn from, both sides around one value, from a random stream of its own: every other
    draw stays; ``turn_range`` (:func:`check_turn_range`) the whole body's turn about the vertical, likewise.
    ``elbow_range`` (:func:`check_elbow_range`): the elbows' flexion, drawn as the arms' angle is (the same random
    numbers, so every other draw stays; the default keeps the cohort as it was)."""
    lo, hi = check_arm_range(arm_range)
    llo, lhi = check_leg_range(leg_range)
    shift = check_bmi_shift(bmi_shift)
    ranges = check_macros(macros)
    palm_lo, palm_hi = check_palm_range(palm_range)
    turn_lo, turn_hi = check_turn_range(turn_range)
    elo, ehi = check_elbow_range(elbow_range)
    rng = np.random.default_rng([int(seed), int(index)])
    female = index % 2 == 0
    mu, sd = (1.63, 0.065) if female else (1.77, 0.07)
    stature = float(mu + sd * np.clip(rng.standard_normal(), -2.5, 2.5))
    bmi = float(rng.normal(25.0, 4.0))
    while not 18.5 <= bmi <= 35.0:
        bmi = float(rng.normal(25.0, 4.0))
    years = float(rng.uniform(20.0, 65.0))
    race = rng.dirichlet([1.0, 1.0, 1.0])
    ph = Phenotype(gender=float(rng.uniform(*(ranges.gender_female if female else ranges.gender_male))),
                   age=Phenotype.age_from_years(years), muscle=float(rng.uniform(*ranges.muscle)),
                   proportions=float(rng.uniform(*ranges.proportions)), african=float(race[0]), asian=float(race[1]),
                   caucasian=float(race[2]))
    arm, elbow, hip = rng.uniform(lo, hi), rng.uniform(elo, ehi), rng.uniform(llo, lhi)
    d = rng.normal(0, 1.5, size=3)
    pose = Pose(float(np.clip(arm + d[0], lo, hi)), float(np.clip(arm - d[0], lo, hi)),
                float(np.clip(elbow + d[1], elo, ehi)), float(np.clip(elbow - d[1], elo, ehi)),
                float(np.clip(hip + d[2] / 3, llo, lhi)), float(np.clip(hip - d[2] / 3, llo, lhi)),
                *_palms(index, seed, palm_lo, palm_hi), _turn(index, seed, turn_lo, turn_hi))
    loc = _draw_local(rng)
    if local:
        ph = ph.with_(local=loc)
    ph, bmi_used = _solve(ph, stature, bmi + shift, pose)
    body = make_body(ph, pose)
    for _ in range(12 if check else 0):
        hits = penetrations(body.vertices, body.faces, body.face_labels)
        if not hits:
            break
        floor = min(lo, ARM_FREE_FLOOR_DEG)
        step = _free_step(pose, hits, floor)
        if step == pose:
            raise SolveError(f"cohort subject {index} (seed {seed}) self-intersects ({', '.join(sorted(hits))}) "
                             f"with its colliding arms raised to {floor:g} deg below the horizontal")
        pose = step
        ph, bmi_used = _solve(ph, stature, bmi_used, pose)
        body = make_body(ph, pose)
    else:
        if check and penetrations(body.vertices, body.faces, body.face_labels):
            raise SolveError(f"cohort subject {index} (seed {seed}) still self-intersects after pose changes")
    return Subject(index, int(seed), "female" if female else "male", stature, bmi_used, ph, pose, body,
                   arm_range=(lo, hi), leg_range=(llo, lhi), bmi_shift=shift, macros=macros,
                   palm_range=(palm_lo, palm_hi), turn_range=(turn_lo, turn_hi), elbow_range=(elo, ehi))


def cohort(n: int, seed: int = 0, local: bool = True, check: bool = True,
           arm_range: tuple[float, float] = ARM_DOWN_RANGE_DEG,
           palm_range: tuple[float, float] = PALM_IN_RANGE_DEG,
           turn_range: tuple[float, float] = TURN_RANGE_DEG,
           elbow_range: tuple[float, float] = ELBOW_RANGE_DEG) -> list[Subject]:
    """``n`` plausible adults (half female), deterministic for a seed; local modifiers on by default.
    ``arm_range``: the interval (degrees below the horizontal) the arm angles are drawn from, as in
    :func:`subject` (:data:`ARM_DOWN_RANGE_DEG` by default, :data:`WIDE_ARM_DOWN_RANGE_DEG` for wide
    A-poses); ``palm_range`` the palms' (:data:`RELAXED_PALM_IN_RANGE_DEG` for palms as people hold them
    unasked), ``turn_range`` the body's turn about the vertical, ``elbow_range`` the elbows' flexion
    (:data:`FLEXED_ELBOW_RANGE_DEG` for relaxed arms); a bad range is a PoseError before any subject is made."""
    if n < 0:
        raise ValueError(f"cohort size {n}: must be >= 0")
    check_arm_range(arm_range)
    check_palm_range(palm_range)
    check_turn_range(turn_range)
    check_elbow_range(elbow_range)
    return list(iter_cohort(n, seed, local, check, arm_range, palm_range, turn_range, elbow_range))


def iter_cohort(n: int, seed: int = 0, local: bool = True, check: bool = True,
                arm_range: tuple[float, float] = ARM_DOWN_RANGE_DEG,
                palm_range: tuple[float, float] = PALM_IN_RANGE_DEG,
                turn_range: tuple[float, float] = TURN_RANGE_DEG,
                elbow_range: tuple[float, float] = ELBOW_RANGE_DEG) -> Iterator[Subject]:
    """Like cohort() but yields subjects one at a time. ``arm_range``, ``palm_range``, ``turn_range`` and
    ``elbow_range``: the intervals (degrees) the arm angles, the palms' turn, the body's and the elbows' flexion are
    drawn from (:func:`subject`); a bad range is a PoseError at the first subject."""
    for i in range(n):
        yield subject(i, seed, local, check, arm_range, palm_range=palm_range, turn_range=turn_range,
                      elbow_range=elbow_range)


def volumes_json(s: Subject) -> str:
    """The ground-truth volumes JSON of a subject (DESIGN.md volumes format plus a "subject" block)."""
    doc = {"units": {"length": "m", "volume": "L"},
           "volumes_l": {k: round(v, 6) for k, v in s.volumes_l().items()},
           "subject": s.info()}
    return json.dumps(doc, indent=1, sort_keys=True) + "\n"


def subject_files(index: int, out_dir: str | Path) -> tuple[Path, Path]:
    """Paths of subject ``index``'s mesh and volumes files in ``out_dir``."""
    out = Path(out_dir)
    return out / f"subject_{index:03d}.ply", out / f"subject_{index:03d}.json"


def _refuse_existing(paths: list[Path], overwrite: bool) -> None:
    existing = [str(p) for p in paths if p.exists()]
    if existing and not overwrite:
        raise OutputExistsError(f"{', '.join(existing)} already exist(s); pass overwrite=True (--overwrite) to "
                                "replace, or choose another output folder")


def write_subject(s: Subject, out_dir: str | Path, overwrite: bool = False) -> tuple[Path, Path]:
    """Write ``subject_NNN.ply`` (labelled, binary little-endian) and ``subject_NNN.json`` (volumes);
    existing files are refused (:class:`bsv.errors.OutputExistsError`) unless ``overwrite``."""
    out = Path(out_dir)
    ply, js = subject_files(s.index, out)
    _refuse_existing([ply, js], overwrite)
    out.mkdir(parents=True, exist_ok=True)
    b = s.body
    ply.write_bytes(ply_bytes(b.vertices, b.faces, b.vertex_labels, b.face_labels))
    js.write_text(volumes_json(s))
    return ply, js


def write_cohort(out_dir: str | Path, n: int, seed: int = 0, local: bool = True, overwrite: bool = False,
                 arm_range: tuple[float, float] = ARM_DOWN_RANGE_DEG,
                 palm_range: tuple[float, float] = PALM_IN_RANGE_DEG,
                 turn_range: tuple[float, float] = TURN_RANGE_DEG,
                 elbow_range: tuple[float, float] = ELBOW_RANGE_DEG) -> list[tuple[Path, Path]]:
    """Generate and write a cohort: one PLY + JSON per subject and ``cohort.json`` listing them (with the
    seed, local modifiers, ``arm_down_deg``, ``palm_in_deg``, ``turn_deg`` and ``elbow_deg``, the ranges of
    :func:`subject`).
    A bad range (PoseError) or any of these files already present is refused before anything is generated
    (:class:`bsv.errors.OutputExistsError`) unless ``overwrite``."""
    out = Path(out_dir)
    lo, hi = check_arm_range(arm_range)
    palms = check_palm_range(palm_range)
    turns = check_turn_range(turn_range)
    elbows = check_elbow_range(elbow_range)
    _refuse_existing([out / "cohort.json", *(p for i in range(max(n, 0)) for p in subject_files(i, out))], overwrite)
    paths = [write_subject(s, out, overwrite) for s in iter_cohort(n, seed, local, arm_range=(lo, hi),
                                                                   palm_range=palms, turn_range=turns,
                                                                   elbow_range=elbows)]
    index = {"seed": int(seed), "n": int(n), "local_modifiers": bool(local), "arm_down_deg": [lo, hi],
             "palm_in_deg": list(palms), "turn_deg": list(turns), "elbow_deg": list(elbows), "subjects": [{"mesh": p.name, "volumes": j.name} for p, j in paths]}
    (out / "cohort.json").write_text(json.dumps(index, indent=1) + "\n")
    return paths


def main(argv: list[str] | None = None) -> int:
    """``python -m bsv.bodies.cohort OUT_DIR N [SEED] [--no-local] [--arm-down LOW,HIGH] [--palm-in LOW,HIGH]
    [--turn LOW,HIGH] [--elbow LOW,HIGH] [--overwrite]``:
    write a cohort; returns the exit status (2 and a message if files exist and --overwrite is not given,
    see bsv.exitcodes)."""
    import argparse

    from ..argtypes import seed, whole

    ap = argparse.ArgumentParser(description="Write a synthetic MakeHuman cohort (PLY + ground-truth JSON).")
    ap.add_argument("out_dir")
    ap.add_argument("n", type=whole(1, 100_000, "N subjects"))
    ap.add_argument("seed", type=seed, nargs="?", default=0)
    ap.add_argument("--no-local", action="store_true", help="macro phenotypes only (no local modifiers)")
    ap.add_argument("--arm-down", type=arm_range_arg, default=ARM_DOWN_RANGE_DEG, metavar="LOW,HIGH",
                    help=arm_down_help())
    ap.add_argument("--palm-in", type=palm_range_arg, default=PALM_IN_RANGE_DEG, metavar="LOW,HIGH",
                    help=palm_in_help())
    ap.add_argument("--turn", type=turn_range_arg, default=TURN_RANGE_DEG, metavar="LOW,HIGH", help=turn_help())
    ap.add_argument("--elbow", type=elbow_range_arg, default=ELBOW_RANGE_DEG, metavar="LOW,HIGH", help=elbow_help())
    ap.add_argument("--overwrite", action="store_true", help="replace subject files and cohort.json already in OUT_DIR")
    args = ap.parse_args(argv)
    from ..exitcodes import run_command

    def run() -> int:
        written = write_cohort(args.out_dir, args.n, args.seed, not args.no_local, overwrite=args.overwrite,
                               arm_range=args.arm_down, palm_range=args.palm_in, turn_range=args.turn,
                               elbow_range=args.elbow)
        for ply, js in written:
            print(ply, js)
        return 0

    return run_command("bsv cohort", run)


__all__ = [
    "ARM_DOWN_RANGE_DEG",
    "ARM_FREE_FLOOR_DEG",
    "ELBOW_RANGE_DEG",
    "FLEXED_ELBOW_RANGE_DEG",
    "HEAVY_BMI_SHIFT",
    "HIP_ABDUCTION_RANGE_DEG",
    "LOCAL_CENTRAL",
    "LOCAL_SIDED",
    "MACRO_RANGES",
    "NARROW_HIP_ABDUCTION_RANGE_DEG",
    "PALM_IN_RANGE_DEG",
    "RELAXED_PALM_IN_RANGE_DEG",
    "TURNED_RANGE_DEG",
    "TURN_RANGE_DEG",
    "WIDE_ARM_DOWN_RANGE_DEG",
    "MacroRanges",
    "Subject",
    "arm_down_help",
    "arm_range_arg",
    "bmi_shift_arg",
    "check_arm_range",
    "check_bmi_shift",
    "check_elbow_range",
    "check_leg_range",
    "check_macros",
    "check_palm_range",
    "check_turn_range",
    "cohort",
    "elbow_help",
    "elbow_range_arg",
    "iter_cohort",
    "leg_range_arg",
    "main",
    "palm_in_help",
    "palm_range_arg",
    "subject",
    "subject_files",
    "turn_help",
    "turn_range_arg",
    "volumes_json",
    "write_cohort",
    "write_subject",
]


if __name__ == "__main__":
    raise SystemExit(main())

"""How far each palm is turned in, read from MediaPipe's hand model on both views.

**Why the camera path needs it.** The template is posed like the subject before the registration
(:mod:`bsv.posed_template`), with its palms forward. A subject who stands as people do unasked holds the palms
towards the thighs or a little behind: MakeHuman's hand with no twist lies 118 deg in from forward. The
registration then has to twist the template's forearm a quarter turn or more, and it shrinks it: on the room's
seeds 0-1 with every palm at 118 deg, the camera path's forearms came out -1.2 % (noer) and -2.3 % (l515) signed,
against +0.0 and -1.0 % with the palms forward; the template posed with the subject's true palms brought them
back to +0.1 and -1.0 % (benchmarks/BENCH.md, round 2 session 44).

**The measurement.** Per view and hand, from the hand model's landmarks in the image (:func:`view_readings`):
how far the thumb's tip lies from the wrist across the hand's axis (wrist to the middle finger's knuckle),
towards the arm's outer side, over the hand's length. With the palm forward the thumb points outward (about
+1); turned in, the thumb comes forward and then inward (about -0.2 in the front view and -0.6 in the back view
at 110 deg). A linear model of the two views' readings (:data:`PALM_TURN_MODEL`, one of each view alone when
the other found no hand) gives the pose's angle (:attr:`bsv.bodies.pose.Pose.palm_in_l`). It was learned by
``benchmarks/learn_palm_turns.py`` on 60 cohort captures (seeds 40-45) with palms drawn in 0-120 deg, half of
them in the rig's realistic render. Learned on seeds 40-43 and held out on 44-45 its error is 4.4 deg rms with
both views (8.9 with the front view's alone, 7.2 with the back's); the knuckles' line with the hand model's
relative depth, tried first, read 6-27 deg rms.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

#: The pose's palm angle (deg) from the views' readings: ``both`` = (intercept, front coefficient, back
#: coefficient), ``front`` and ``back`` = (intercept, coefficient) for a hand one view only found; the result is
#: clipped to ``range`` (the cohort's palms, 0-120 deg, and a little beyond). ``benchmarks/learn_palm_turns.py``.
PALM_TURN_MODEL: dict[str, Any] = {"both": (78.4, -26.1, -40.2), "front": (95.5, -76.0), "back": (69.1, -58.4),
                                   "range": (-10.0, 135.0)}
#: A hand shorter than this in the image (wrist to the middle finger's knuckle, pixels) is not read.
MIN_HAND_PX = 8.0
#: The hand landmarks a reading takes (names of :data:`bsv.frontend.segment.HAND_NAMES`).
READ_FROM: tuple[str, str, str] = ("wrist", "middle_finger_mcp", "thumb_tip")


def _reading(seg: Any, side: str) -> float | None:
    """One view's reading of the subject's ``side`` ("left" or "right") palm, or None."""
    try:
        wrist, middle, thumb = (np.asarray(seg.landmark(f"{side}_hand_{n}")[:2], dtype=np.float64) for n in READ_FROM)
    except KeyError:
        return None
    if not (np.all(np.isfinite(wrist)) and np.all(np.isfinite(middle)) and np.all(np.isfinite(thumb))):
        return None
    axis = middle - wrist
    length = float(np.hypot(*axis))
    if length < MIN_HAND_PX:
        return None
    across = np.array([-axis[1], axis[0]]) / length
    # the arm's outer side in the image: the subject's left is on the front image's right, the back image's left
    outward = (1.0 if side == "left" else -1.0) * (1.0 if seg.view == "front" else -1.0)
    if across[0] * outward < 0:
        across = -across
    return float((thumb - wrist) @ across / length)


def view_readings(seg: Any) -> tuple[float | None, float | None]:
    """A view's (left, right) readings from a :class:`bsv.frontend.segment.Segmentation`: the thumb tip's offset
    from the wrist across the hand, towards the arm's outer side, over the hand's length; None for a hand the hand
    model did not find (or one too small to read)."""
    found = getattr(seg, "hands_found", (True, True))
    return (_reading(seg, "left") if found[0] else None, _reading(seg, "right") if found[1] else None)


def palm_turn(front: float | None, back: float | None) -> float | None:
    """The pose's palm angle (deg) of one hand's front and back readings (:data:`PALM_TURN_MODEL`), None when
    neither view read it."""
    m = PALM_TURN_MODEL
    if front is not None and back is not None:
        c0, cf, cb = m["both"]
        turn = c0 + cf * front + cb * back
    elif front is not None or back is not None:
        c0, c = m["front"] if front is not None else m["back"]
        turn = c0 + c * (front if front is not None else back)
    else:
        return None
    lo, hi = m["range"]
    return float(np.clip(turn, lo, hi))


def palm_turns(readings: Mapping[str, tuple[float | None, float | None]]) -> tuple[float | None, float | None]:
    """The subject's (left, right) palm angles (deg) from each view's readings (``{"front": (l, r), "back": ...}``,
    :func:`view_readings`; a view absent reads nothing)."""
    none = (None, None)
    front, back = readings.get("front", none), readings.get("back", none)
    return palm_turn(front[0], back[0]), palm_turn(front[1], back[1])


def palms_of(segs: Mapping[str, Any]) -> tuple[float | None, float | None]:
    """:func:`palm_turns` of a capture's segmentations (``{view: Segmentation}``)."""
    return palm_turns({v: view_readings(s) for v, s in segs.items()})


def template_palms(turns: tuple[float | None, float | None]) -> tuple[dict[str, float], list[str]]:
    """The :class:`bsv.bodies.pose.Pose` keywords of measured palm angles (``palm_in_l``, ``palm_in_r``) and a note
    for each palm left forward, the template's own, because no view read it."""
    kw: dict[str, float] = {}
    notes: list[str] = []
    for side, turn in zip(("l", "r"), turns, strict=True):
        if turn is None:
            which = "left" if side == "l" else "right"
            notes.append(f"the template's {which} palm kept forward: the hand model found that hand in neither view")
        else:
            kw[f"palm_in_{side}"] = turn
    return kw, notes


__all__ = ["MIN_HAND_PX", "PALM_TURN_MODEL", "READ_FROM", "palm_turn", "palm_turns", "palms_of", "template_palms",
           "view_readings"]

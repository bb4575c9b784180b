"""The segment palette and plain-language segment names: one table for every figure, legend, preview and PLY.

The colours are Rust's ``bsv_core::PALETTE`` (what the Rust writers put in labelled PLY files, exported by
the extension as ``bsv._bsv.PALETTE``): Okabe & Ito's and Paul Tol's colour-blind-safe colours, chosen so
that every pair differs clearly for normal vision and under deuteranopia and protanopia simulation
(``tests/python/test_palette.py``).
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from .types import PALETTE, SEGMENT_NAMES

#: Plain-language name of each segment id (what a report reader sees; the canonical names stay in files).
PLAIN_NAMES: dict[str, str] = {
    "unlabelled": "not assigned", "head": "Head and neck", "torso": "Torso",
    "upper_arm_l": "Left upper arm", "upper_arm_r": "Right upper arm", "forearm_l": "Left forearm",
    "forearm_r": "Right forearm", "hand_l": "Left hand", "hand_r": "Right hand", "thigh_l": "Left thigh",
    "thigh_r": "Right thigh", "shin_l": "Left lower leg", "shin_r": "Right lower leg", "foot_l": "Left foot",
    "foot_r": "Right foot",
    "trunk_limbs": "Torso, arms and legs", "whole": "All measured segments", "arm_l": "Left arm (upper arm + forearm)",
    "arm_r": "Right arm (upper arm + forearm)", "leg_l": "Left leg (thigh + lower leg)",
    "leg_r": "Right leg (thigh + lower leg)",
    # the parts of a left/right pair (asymmetry rows)
    "upper_arm": "upper arm", "forearm": "forearm", "thigh": "thigh", "shin": "lower leg", "arm": "arm", "leg": "leg",
}


def plain_name(name: str) -> str:
    """The plain-language name of a segment or aggregate (the canonical name when it has none)."""
    return PLAIN_NAMES.get(name, name.replace("_", " "))


def rgb01() -> npt.NDArray[np.float64]:
    """(15, 3) float RGB in [0, 1] of the segment ids."""
    return np.asarray(PALETTE, dtype=np.float64) / 255.0


def hex_colour(segment_id: int) -> str:
    """``#rrggbb`` of a segment id (HTML legends)."""
    r, g, b = (int(c) for c in PALETTE[segment_id])
    return f"#{r:02x}{g:02x}{b:02x}"


def colourise(ids: npt.ArrayLike, background: tuple[int, int, int] = (255, 255, 255)) -> npt.NDArray[np.uint8]:
    """An (H, W, 3) uint8 RGB image of a segment-id image (ids 0-14; 0 and ids above 14 get ``background``,
    white by default: previews that print well)."""
    a = np.asarray(ids)
    lut = np.asarray(PALETTE, dtype=np.uint8).copy()
    lut[0] = background
    rgb = lut[np.clip(a, 0, len(lut) - 1)]
    rgb[a >= len(lut)] = background
    return rgb


def segment_id(name: str) -> int:
    """The id of a canonical segment name (KeyError for an aggregate)."""
    return next(k for k, v in SEGMENT_NAMES.items() if v == name)


__all__ = ["PLAIN_NAMES", "colourise", "hex_colour", "plain_name", "rgb01", "segment_id"]

"""The segment palette (bsv_core::PALETTE, one table for every figure, legend, preview and fitted.ply): every
pair of segment colours, and each against the unlabelled grey, differs clearly for normal vision and under
deuteranopia and protanopia (Machado et al. 2009 simulation at full severity), measured in CAM02-UCS (a
perceptually uniform space; about 1 unit is a just-noticeable difference, 10 is clearly distinct patches)."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from bsv.types import PALETTE, SEGMENT_NAMES

colorspacious = pytest.importorskip("colorspacious", reason="colorspacious is in requirements-dev.txt")

#: The smallest CAM02-UCS distance between two segment colours (the palette's is 10.2).
MIN_DISTANCE = 10.0


def _ucs(rgb: np.ndarray, cvd: str | None) -> np.ndarray:
    x = rgb.astype(np.float64) / 255.0
    if cvd:
        x = np.clip(colorspacious.cspace_convert(x, {"name": "sRGB1+CVD", "cvd_type": cvd, "severity": 100}, "sRGB1"),
                    0.0, 1.0)
    return np.asarray(colorspacious.cspace_convert(x, "sRGB1", "CAM02-UCS"))


@pytest.mark.parametrize("vision", [None, "deuteranomaly", "protanomaly"])
def test_every_pair_of_segment_colours_differs_clearly(vision):
    lab = _ucs(np.asarray(PALETTE), vision)
    close = [(SEGMENT_NAMES[i], SEGMENT_NAMES[j], round(float(np.linalg.norm(lab[i] - lab[j])), 1))
             for i, j in itertools.combinations(range(len(PALETTE)), 2)
             if np.linalg.norm(lab[i] - lab[j]) < MIN_DISTANCE]
    assert close == [], f"too close ({vision or 'normal vision'}): {close}"


def test_the_check_finds_the_old_near_identical_colours():
    """torso (70,130,180) and upper_arm_r (55,126,184) of the old palette were near-identical."""
    lab = _ucs(np.array([[70, 130, 180], [55, 126, 184]]), None)
    assert np.linalg.norm(lab[0] - lab[1]) < MIN_DISTANCE / 2


def test_left_and_right_of_each_limb_segment_differ_in_lightness():
    """Left is the darker of a pair: the two sides stay apart even when hue is not seen at all."""
    lab = _ucs(np.asarray(PALETTE), "deuteranomaly")
    for i in range(3, 15, 2):
        assert lab[i + 1][0] - lab[i][0] > 5.0, (SEGMENT_NAMES[i], SEGMENT_NAMES[i + 1])

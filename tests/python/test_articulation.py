"""The articulated initialisation carries the template's shoulder boundary with the arm: with template
labels, a subject's upper-arm volumes hardly depend on how far the arms are raised."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import bsv
from bsv.bodies import make_body, subject

ARMS_DEG = (20.0, 55.0)


def _upper_arm_errors(index: int, rigid: bool) -> dict[float, np.ndarray]:
    """Signed upper-arm errors (%, left and right) of cohort subject ``index`` (seed 0) re-posed with both
    arms at each angle of ARMS_DEG, scanned noise-free and fitted with the template's own labels."""
    s = subject(index, 0, check=False)
    out = {}
    for arm in ARMS_DEG:
        body = make_body(s.phenotype, dataclasses.replace(s.pose, arm_down_l=arm, arm_down_r=arm))
        truth = body.volumes_l()
        fit = bsv.register(bsv.scan(body.mesh(), "noer", 0), label_source="template",
                           articulate_rigid_shoulders=rigid)
        vols = fit.volumes["volumes_l"]
        out[arm] = np.array([100.0 * (vols[k] / truth[k] - 1.0) for k in ("upper_arm_l", "upper_arm_r")])
    return out


@pytest.mark.parametrize("index", [0, 2])
def test_the_upper_arm_volume_does_not_follow_the_arm_angle(index: int) -> None:
    """Blended across the shoulder, the template's boundary lags behind the arm's turn: between arms
    20 and 55 deg below the horizontal the upper arms' error moves by 5-8 points. Kept rigid with the
    arm, by under half of that."""
    blended = _upper_arm_errors(index, rigid=False)
    rigid = _upper_arm_errors(index, rigid=True)
    moved_blended = np.abs(blended[ARMS_DEG[1]] - blended[ARMS_DEG[0]])
    moved_rigid = np.abs(rigid[ARMS_DEG[1]] - rigid[ARMS_DEG[0]])
    assert moved_blended.min() > 4.0, moved_blended
    assert np.all(moved_rigid < 0.5 * moved_blended), (moved_rigid, moved_blended)
    assert np.all(np.abs(rigid[ARMS_DEG[0]]) < np.abs(blended[ARMS_DEG[0]]) + 0.5)

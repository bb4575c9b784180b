"""The articulated initialisation carries the template's shoulder boundary with the arm: with template
labels, a subject's upper-arm volumes hardly depend on how far the arms are raised; with the cloud's
labels (the oracle path) the rigid shoulders do not apply."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import bsv
from bsv.bodies import make_body, subject
from bsv.bodies.collide import penetrations

ARMS_DEG = (20.0, 55.0)
UPPER_ARMS = ("upper_arm_l", "upper_arm_r")


def _upper_arm_errors(index: int) -> dict[bool, dict[float, np.ndarray]]:
    """Signed upper-arm errors (%, left and right) of cohort subject ``index`` (seed 0) re-posed with both
    arms at each angle of ARMS_DEG, scanned noise-free once per angle and fitted with the template's own
    labels, shoulders blended (False) and rigid (True)."""
    s = subject(index, 0, check=False)
    out: dict[bool, dict[float, np.ndarray]] = {False: {}, True: {}}
    for arm in ARMS_DEG:
        body = make_body(s.phenotype, dataclasses.replace(s.pose, arm_down_l=arm, arm_down_r=arm))
        assert not penetrations(body.vertices, body.faces, body.face_labels), "the truth must be a free body"
        truth = body.volumes_l()
        cloud = bsv.scan(body.mesh(), "noer", 0)
        for rigid in (False, True):
            vols = bsv.register(cloud, label_source="template", articulate_rigid_shoulders=rigid).volumes["volumes_l"]
            out[rigid][arm] = np.array([100.0 * (vols[k] / truth[k] - 1.0) for k in UPPER_ARMS])
    return out


@pytest.mark.slow
@pytest.mark.parametrize("index", [0, 2])
def test_the_upper_arm_volume_does_not_follow_the_arm_angle(index: int) -> None:
    """Blended across the shoulder, the template's boundary lags behind the arm's turn: between arms
    20 and 55 deg below the horizontal the upper arms' error moves by 5-8 points. Kept rigid with the
    arm, by well under that: under half until the torso's correspondences were pruned at 6 x the median
    (round 2 session 31), 0.44-0.53 of it since on subject 0 (its torso now follows the shoulder more)."""
    errors = _upper_arm_errors(index)
    blended, rigid = errors[False], errors[True]
    moved_blended = np.abs(blended[ARMS_DEG[1]] - blended[ARMS_DEG[0]])
    moved_rigid = np.abs(rigid[ARMS_DEG[1]] - rigid[ARMS_DEG[0]])
    assert moved_blended.min() > 4.0, moved_blended
    assert np.all(moved_rigid < 0.6 * moved_blended), (moved_rigid, moved_blended)
    assert np.all(np.abs(rigid[ARMS_DEG[0]]) < np.abs(blended[ARMS_DEG[0]]) + 0.5)


def test_rigid_shoulders_do_not_apply_with_the_clouds_labels() -> None:
    """With the cloud's labels (the oracle path) the result's segments come from the cloud and the blended
    shoulder fits better: the parameter must change nothing there, and must change the template-label fit."""
    s = subject(0, 0)
    cloud = bsv.scan(s.body.mesh(), "noer", 0)

    def vols(source: str, rigid: bool) -> dict[str, float]:
        return bsv.register(cloud, label_source=source, articulate_rigid_shoulders=rigid).volumes["volumes_l"]

    assert vols("cloud", True) == vols("cloud", False)
    on, off = vols("template", True), vols("template", False)
    assert any(abs(on[k] - off[k]) > 1e-6 for k in UPPER_ARMS), (on, off)

"""bsv.bodies.variants: reshaped and swollen limb segments, bumps, the hard cohort of the registration."""

from __future__ import annotations

import numpy as np
import pytest

from bsv.bodies import subject
from bsv.bodies.variants import HARD_CLASSES, SegmentShape, add_bumps, hard_subject, reshape_segment
from bsv.errors import PhenotypeError


@pytest.fixture(scope="module")
def base():
    return subject(1, 0).body


def test_reshape_changes_only_its_segment(base) -> None:
    before = base.volumes_l()
    after = reshape_segment(base, SegmentShape("forearm_r", 1.2, 1.2)).volumes_l()
    assert after["forearm_r"] > before["forearm_r"] * 1.2  # ~1.2^2 where the blend is full
    for seg in ("torso", "forearm_l", "upper_arm_r", "upper_arm_l", "thigh_l", "shin_r"):
        assert after[seg] == pytest.approx(before[seg], rel=1e-9), seg


def test_deeper_and_narrower_moves_the_right_axes(base) -> None:
    from bsv.types import SEGMENT_IDS

    b = reshape_segment(base, SegmentShape("upper_arm_l", 1.5, 1.0))
    ids = base.vertex_labels == SEGMENT_IDS["upper_arm_l"]
    depth0, depth1 = np.ptp(base.vertices[ids, 2]), np.ptp(b.vertices[ids, 2])
    height0, height1 = np.ptp(base.vertices[ids, 1]), np.ptp(b.vertices[ids, 1])
    assert depth1 > depth0 * 1.3
    assert height1 == pytest.approx(height0, rel=0.05)


def test_bumps_are_bounded_and_deterministic(base) -> None:
    a = add_bumps(base, np.random.default_rng(3))
    b = add_bumps(base, np.random.default_rng(3))
    moved = np.linalg.norm(a.vertices - base.vertices, axis=1)
    assert np.array_equal(a.vertices, b.vertices)
    assert 0.005 < moved.max() < 0.04


def test_bad_shape_is_refused(base) -> None:
    with pytest.raises(PhenotypeError, match="segment 'head'"):
        reshape_segment(base, SegmentShape("head", 1.2))
    with pytest.raises(PhenotypeError, match="depth factor"):
        reshape_segment(base, SegmentShape("forearm_l", float("nan")))


def test_hard_cohort_cycles_through_its_classes() -> None:
    subjects = [hard_subject(i, 0) for i in range(len(HARD_CLASSES))]
    assert [s.variant["class"] for s in subjects] == list(HARD_CLASSES)
    deep = subjects[0]
    plain = subject(0, 0)
    assert deep.volumes_l()["upper_arm_l"] > plain.volumes_l()["upper_arm_l"] * 1.08
    assert deep.info()["variant"]["class"] == "deep_upper_arms"
    again = hard_subject(0, 0)
    assert np.array_equal(again.body.vertices, deep.body.vertices)

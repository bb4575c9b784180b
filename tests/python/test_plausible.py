"""Plausibility before the fit and quality after it (issue 10), from Python: implausible clouds raise
:class:`bsv.ImplausibleCloudError` naming the problem; the synthetic cohort in every condition, with and
without a room and without labels, passes; the per-segment quality figures are in the typed result and
the report, and the ``doubtful`` flag fires on a deliberately bad fit but not on good fits."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

import bsv
from bsv import bodies
from bsv.errors import ImplausibleCloudError, RegistrationInputError


@pytest.fixture(scope="module")
def subject_mesh() -> Any:
    return bodies.subject(0, 0).body.mesh()


@pytest.fixture(scope="module")
def cloud(subject_mesh: Any) -> bsv.PointCloud:
    return bsv.scan(subject_mesh, "l515", 0)


TURNS = {
    "90 deg about x": lambda p: np.c_[p[:, 0], -p[:, 2], p[:, 1]],
    "90 deg about y": lambda p: np.c_[p[:, 2], p[:, 1], -p[:, 0]],
    "90 deg about z": lambda p: np.c_[-p[:, 1], p[:, 0], p[:, 2]],
    "upside down": lambda p: np.c_[p[:, 0], -p[:, 1], -p[:, 2]],
}


@pytest.mark.parametrize("turn", sorted(TURNS))
@pytest.mark.parametrize("labelled", [True, False])
def test_a_turned_cloud_is_refused_with_a_typed_error(cloud: bsv.PointCloud, turn: str, labelled: bool) -> None:
    points = TURNS[turn](cloud.points)
    with pytest.raises(ImplausibleCloudError) as e:
        bsv.register(points, cloud.labels if labelled else None, schedule="m2p:1")
    assert isinstance(e.value, RegistrationInputError) and e.value.parameter == "check_plausible"
    assert "+y" in str(e.value) or "+z" in str(e.value)


def test_a_sphere_and_a_plane_are_refused() -> None:
    rng = np.random.default_rng(0)
    d = rng.normal(size=(20000, 3))
    sphere = 0.276 * d / np.linalg.norm(d, axis=1)[:, None] + [0, 1, 0]
    with pytest.raises(ImplausibleCloudError, match="compact"):
        bsv.register(sphere)
    plane = np.c_[rng.uniform(-0.5, 0.5, 20000), rng.uniform(0, 1.5, 20000), np.zeros(20000)]
    with pytest.raises(ImplausibleCloudError, match="flat"):
        bsv.register(plane)


def test_the_cohort_passes_in_every_condition_and_good_fits_are_not_doubtful() -> None:
    for i in range(2):
        mesh = bodies.subject(i, 0).body.mesh()
        for condition in ("noer", "l515", "cali", "l5ca"):
            c = bsv.scan(mesh, condition, i)
            fit = bsv.register(c.points, c.labels)
            doubtful = [k for k, q in fit.quality.items() if q.doubtful]
            assert not doubtful, (i, condition, {k: fit.quality[k] for k in doubtful})
            assert set(fit.quality) >= {"torso", "thigh_l", "forearm_r"}
            # In a room (mixed pixels toward the walls) and without labels the checks pass too; one
            # iteration is enough: they run before the fit.
            room = bsv.scan(mesh, condition, i, room=True)
            bsv.register(room.points, room.labels, schedule="m2p:1")
            bsv.register(room.points, schedule="m2p:1")


def test_quality_figures_are_typed_and_the_flag_fires_on_a_bad_fit(cloud: bsv.PointCloud) -> None:
    good = bsv.register(cloud.points, cloud.labels)
    q = good.quality["torso"]
    assert isinstance(q, bsv.types.SegmentQuality) and q.vertices > 100
    assert 0 <= q.gap_fraction <= 1 - q.coverage + 1e-12 and q.rms_mm < 8
    assert good.summary["quality"]["torso"]["coverage"] == q.coverage
    bad = bsv.register(cloud.points, cloud.labels, schedule="m2p:1", articulate=False, data_weight=0.05)
    assert any(q.doubtful for q in bad.quality.values()), bad.quality


def test_the_report_shows_the_quality_table() -> None:
    from bsv.report import quality_html

    html = quality_html({"quality": {"torso": {"rms_mm": 2.0, "coverage": 0.8, "gap_fraction": 0.1,
                                               "exposed_uncovered": 0.05, "doubtful": False, "vertices": 900},
                                     "forearm_l": {"rms_mm": 9.0, "coverage": 0.2, "gap_fraction": 0.3,
                                                   "exposed_uncovered": 0.5, "doubtful": True, "vertices": 90}}})
    assert "Fit quality" in html and "Left forearm" in html and html.count("doubtful") >= 2
    assert quality_html({}) == ""

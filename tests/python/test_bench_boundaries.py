"""bsv.bench.boundaries: the fitted mesh's segment boundaries against the true ones, in millimetres along
the limb, checked on the template against copies of it whose loops were moved by a known distance."""

from __future__ import annotations

import numpy as np
import pytest

import bsv
from bsv.bench.boundaries import (
    INFO_KEY,
    KINDS,
    best_split,
    boundaries_markdown,
    boundary_errors,
    distance_to_segments,
    end_errors,
    explained,
    limb_boundaries,
    loop_edges,
    summarise,
)
from bsv.bench.common import Run
from bsv.bodies.template import subdivide_midpoint
from bsv.errors import BsvError
from bsv.types import SEGMENT_IDS, Mesh


@pytest.fixture(scope="module")
def template() -> Mesh:
    return bsv.default_template()


@pytest.fixture(scope="module")
def fine(template: Mesh) -> Mesh:
    """The template with its faces split twice (edges of about 8 mm): a truth whose loops can be moved finely."""
    return subdivide_midpoint(subdivide_midpoint(template))


def moved(mesh: Mesh, grow: str, into: str, mm: float) -> Mesh:
    """``mesh`` with the faces of ``into`` within ``mm`` of its loop with ``grow`` relabelled ``grow``."""
    v, f = np.asarray(mesh.vertices), np.asarray(mesh.faces)
    fl = np.asarray(mesh.face_labels).copy()
    g, i = SEGMENT_IDS[grow], SEGMENT_IDS[into]
    e = loop_edges(f, fl, g, i)
    d = distance_to_segments(v[f].mean(axis=1), v[e[:, 0]], v[e[:, 1]])
    fl[(fl == i) & (d < mm / 1000.0)] = g
    return Mesh(v, f, None, fl)


def test_a_mesh_against_itself_has_no_boundary_error(template: Mesh) -> None:
    errs = boundary_errors(template, template)
    assert set(errs) == {f"{k}_{s}" for k in KINDS for s in "lr"}
    assert max(abs(e) for e in errs.values()) < 0.2


def test_a_true_loop_moved_down_the_shin_reads_as_the_fitted_loop_too_high(template: Mesh, fine: Mesh) -> None:
    errs = boundary_errors(template, moved(fine, "thigh_l", "shin_l", 20.0))
    assert errs["knee_l"] == pytest.approx(-20.0, abs=2.0)  # the fitted loop lies 20 mm proximal of the truth
    assert all(abs(e) < 1.0 for j, e in errs.items() if j != "knee_l")


def test_a_true_loop_moved_into_the_torso_reads_as_the_fitted_loop_too_low(template: Mesh, fine: Mesh) -> None:
    errs = boundary_errors(template, moved(fine, "thigh_r", "torso", 12.0))
    assert errs["hip_r"] == pytest.approx(12.0, abs=2.0)  # the true thigh reaches 12 mm higher
    assert abs(errs["hip_l"]) < 1.0 and abs(errs["knee_r"]) < 1.0


def test_a_loop_far_off_is_found_in_the_wider_band(template: Mesh, fine: Mesh) -> None:
    errs = boundary_errors(template, moved(fine, "thigh_l", "shin_l", 80.0))  # beyond BAND_M
    assert errs["knee_l"] == pytest.approx(-80.0, abs=3.0)


def test_a_joint_whose_segments_a_mesh_lacks_is_left_out(template: Mesh) -> None:
    fl = np.asarray(template.face_labels).copy()
    fl[fl == SEGMENT_IDS["forearm_l"]] = SEGMENT_IDS["upper_arm_l"]  # no left elbow loop
    errs = boundary_errors(Mesh(template.vertices, template.faces, None, fl), template)
    assert "elbow_l" not in errs and "elbow_r" in errs
    assert boundary_errors(Mesh(template.vertices, template.faces), template) == {}  # no labels, no boundaries


def test_a_diverged_fit_is_a_bsv_error(template: Mesh) -> None:
    v = np.asarray(template.vertices).copy()
    v[0] = np.nan
    with pytest.raises(BsvError):
        boundary_errors(Mesh(v, template.faces, template.vertex_labels, template.face_labels), template)


def test_the_best_split_is_the_middle_of_the_gap() -> None:
    h = np.array([-3.0, -2.0, -1.0, 1.0, 2.0, 3.0])
    assert best_split(h, h > 0) == pytest.approx(0.0)
    assert best_split(h, h > 1.5) == pytest.approx(1.5)
    noisy = np.array([False, False, True, False, True, True])  # one point on each wrong side
    assert -1.0 <= best_split(h, noisy) <= 1.0


def test_the_table_pools_sides_and_names_the_worst() -> None:
    runs = [Run(f"subject_{i:03d}", "noer", "bsv", True, info={INFO_KEY: {"knee_l": e, "knee_r": -e, "hip_l": 1.0}})
            for i, e in enumerate((2.0, 6.0))]
    runs.append(Run("subject_009", "noer", "trimesh", True, info={INFO_KEY: {"knee_l": 99.0}}))  # not bsv: left out
    table = summarise(runs)["noer"]
    assert table["knee"]["n"] == 4 and table["knee"]["mean_mm"] == pytest.approx(0.0)
    assert table["knee"]["median_abs_mm"] == pytest.approx(4.0) and abs(table["knee"]["worst_mm"]) == 6.0
    assert table["hip"]["n"] == 2
    md = "\n".join(boundaries_markdown(runs))
    assert "| knee | 4 | +0.0 |" in md and "subject_001" in md
    assert boundaries_markdown([]) == []


def test_each_limb_is_bounded_by_the_joints_the_table_names() -> None:
    assert limb_boundaries("upper_arm") == ("shoulder", "elbow")
    assert limb_boundaries("thigh") == ("hip", "knee")
    assert limb_boundaries("forearm") == ("elbow", "wrist")  # the forearm's far end: end_errors
    assert limb_boundaries("shin") == ("knee", "ankle")
    assert limb_boundaries("torso") == (None, None)


def _limb_runs(n: int, shoulder_cost: float, elbow_cost: float, at_zero: float, noise: float = 0.0) -> list[Run]:
    rng = np.random.default_rng(3)
    runs = []
    for i in range(n):
        sh, el = rng.normal(0.0, 3.0, 2)
        err = at_zero + shoulder_cost * sh + elbow_cost * el + noise * rng.normal()
        runs.append(Run(f"subject_{i:03d}", "noer", "bsv", True, truth_l={"upper_arm_l": 2.0},
                        estimated_l={"upper_arm_l": 2.0 * (1 + err / 100)},
                        info={INFO_KEY: {"shoulder_l": float(sh), "elbow_l": float(el)}}))
    return runs


def test_a_volume_error_made_of_boundary_errors_is_explained_whole() -> None:
    split = explained(_limb_runs(12, -0.9, 0.3, 0.5))["noer"]["upper_arm"]
    assert split["n"] == 12
    assert split["at_zero"] == pytest.approx(0.5, abs=1e-9)
    assert split["per_mm"] == pytest.approx({"shoulder": -0.9, "elbow": 0.3}, abs=1e-9)
    assert split["rve_left"] == pytest.approx(0.0, abs=1e-9) and split["rve"] > 1.0


def test_what_the_boundaries_do_not_explain_is_left() -> None:
    split = explained(_limb_runs(200, -0.9, 0.3, 0.0, noise=1.0))["noer"]["upper_arm"]
    assert split["rve_left"] == pytest.approx(np.sqrt(2 / np.pi), rel=0.15)  # the noise's mean |x|
    assert split["per_mm"]["shoulder"] == pytest.approx(-0.9, abs=0.05)


def test_too_few_runs_are_not_fitted_and_the_report_says_what_is() -> None:
    assert explained(_limb_runs(5, -0.9, 0.3, 0.5)) == {}
    md = "\n".join(boundaries_markdown(_limb_runs(12, -0.9, 0.3, 0.5)))
    assert "What the boundaries cost each limb" in md and "| noer | upper_arm | 12 |" in md


def test_where_a_fitted_forearm_or_shin_ends_against_the_true_wrist_or_ankle(template: Mesh) -> None:
    """end_errors: the 9-segment template (its forearms and shins end in caps) against its own full body reads
    within 3 mm of zero (its caps' rims are not quite its loops); against a full body whose left wrist loop and
    right ankle loop were moved 15 mm into the hand and the foot it reads the fitted segments 15 mm short there,
    and the other ends as before. A fitted mesh that has the hands and feet is not measured."""
    full = bsv.default_template(full=True)
    base = end_errors(template, full)
    assert set(base) == {f"{k}_{s}" for k in ("wrist", "ankle") for s in "lr"}
    assert all(abs(e) < 3.0 for e in base.values()), base
    fine = subdivide_midpoint(full)
    shifted = end_errors(template, moved(moved(fine, "forearm_l", "hand_l", 15.0), "shin_r", "foot_r", 15.0))
    assert shifted["wrist_l"] - base["wrist_l"] == pytest.approx(-15.0, abs=2.5)
    assert shifted["ankle_r"] - base["ankle_r"] == pytest.approx(-15.0, abs=2.5)
    assert shifted["wrist_r"] == pytest.approx(base["wrist_r"]) and shifted["ankle_l"] == pytest.approx(base["ankle_l"])
    assert end_errors(full, full) == {}


def test_the_far_ends_join_the_table_and_the_split() -> None:
    """Runs that measured the elbow and the wrist: the table has a wrist row and the forearm's error is split
    over both (a forearm 1 mm short at the wrist is 0.15 % smaller)."""
    rng = np.random.default_rng(5)
    runs = []
    for i in range(12):
        el, wr = rng.normal(0.0, 3.0, 2)
        err = -0.7 * el + 0.15 * wr
        runs.append(Run(f"subject_{i:03d}", "noer", "bsv", True, truth_l={"forearm_l": 1.0},
                        estimated_l={"forearm_l": 1.0 * (1 + err / 100)},
                        info={INFO_KEY: {"elbow_l": float(el), "wrist_l": float(wr)}}))
    assert summarise(runs)["noer"]["wrist"]["n"] == 12
    split = explained(runs)["noer"]["forearm"]
    assert split["per_mm"] == pytest.approx({"elbow": -0.7, "wrist": 0.15}, abs=1e-9)
    assert "| wrist | 12 |" in "\n".join(boundaries_markdown(runs))

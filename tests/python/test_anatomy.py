"""The segment definitions (bsv.anatomy): what the docs and the report say about where each boundary runs
is what the template's loops measure, and the docs hold the generated table."""

from __future__ import annotations

from pathlib import Path

import pytest

from bsv import anatomy, report
from bsv.biomech.tables import JOINTS

DESIGN = Path(__file__).resolve().parents[2] / "docs" / "DESIGN.md"


@pytest.fixture(scope="module")
def loops() -> dict[str, anatomy.LoopGeometry]:
    return {k.removesuffix("_l"): g for k, g in anatomy.measure_boundaries().items()}


def test_every_joint_and_segment_has_a_definition() -> None:
    assert set(anatomy.BOUNDARIES) == {j.removesuffix("_l").removesuffix("_r") for j in JOINTS}
    for k in anatomy.SEGMENT_KINDS:
        prox, dist = anatomy.bounds(k)
        assert prox or dist, k
    assert anatomy.bounds("thigh") == (["hip"], ["knee"])
    assert anatomy.bounds("torso") == (["neck"], ["shoulder", "hip"])
    assert anatomy.kind_name("shin") == "Lower leg"


def test_the_shoulder_loop_runs_from_above_the_joint_down_through_the_armpit(loops) -> None:
    s = loops["shoulder"]
    assert s.sides_mm["top"] == pytest.approx(s.span_mm[0]) and s.sides_mm["top"] < -30  # above, medial
    assert s.sides_mm["medial"] < -30
    assert s.sides_mm["bottom"] == pytest.approx(s.span_mm[1]) and s.sides_mm["bottom"] > 20  # the armpit
    assert s.tilt_deg > 30


def test_the_elbow_and_wrist_loops_lie_at_their_joints(loops) -> None:
    e, w = loops["elbow"], loops["wrist"]
    assert abs(e.centroid_mm) < 15 and abs(w.centroid_mm) < 10
    assert e.sides_mm["medial"] < e.sides_mm["front"] - 10 and e.sides_mm["back"] < e.sides_mm["front"] - 10


def test_the_hip_loop_is_level_with_the_joint_at_the_side_and_lowest_at_the_crotch(loops) -> None:
    h = loops["hip"]
    assert abs(h.sides_mm["lateral"]) < 15
    assert h.sides_mm["front"] > 20 and h.sides_mm["back"] > 20
    assert h.sides_mm["medial"] > max(h.sides_mm["front"], h.sides_mm["back"]) + 20


def test_the_knee_loop_is_below_the_joint_and_lower_at_the_front(loops) -> None:
    k = loops["knee"]
    assert 0 < k.centroid_mm < 25 and k.sides_mm["front"] > k.sides_mm["back"] + 10


def test_the_ankle_loop_is_above_the_joint_and_higher_at_the_front(loops) -> None:
    a = loops["ankle"]
    assert a.centroid_mm < 0 and a.span_mm[1] < 5 and a.sides_mm["front"] < a.sides_mm["back"] - 10


def test_the_design_notes_hold_the_generated_tables() -> None:
    assert anatomy.markdown() in DESIGN.read_text(), "regenerate: python -m bsv.anatomy (docs/DESIGN.md)"


def test_the_report_says_how_this_results_boundaries_were_placed() -> None:
    tpl = report.definitions_html({"registration": {"params": {"labels": "template"}}, "template": {"kind": "female"}})
    cloud = report.definitions_html({"registration": {"params": {"labels": "cloud"}}})
    assert "same anatomical loop on every subject" in tpl and "nearest measured point" in cloud
    assert "Template: the female MakeHuman body" in tpl and "Template:" not in cloud
    assert "Posed like the subject" not in tpl
    pose = {"arm_down_l": 31.4, "arm_down_r": 44.6, "elbow_l": 18.0, "elbow_r": 21.0, "hip_abduction_l": 3.0,
            "hip_abduction_r": 5.0}
    posed = report.definitions_html({"registration": {"params": {"labels": "template"}},
                                     "template": {"kind": "default", "pose": pose}})
    assert "Posed like the subject" in posed and "arms 31 / 45 deg below horizontal" in posed
    assert "depth images" not in posed
    pulled = report.definitions_html({"registration": {"params": {"labels": "template"}},
                                      "boundaries_m": {"hip_loop_l": {"xyz": [0.09, 0.8, 0.0]}}}, "pdf")
    assert "pulled to the height the crotch in the depth images gives" in pulled
    assert tpl.count("<tr>") == len(anatomy.BOUNDARIES) + 1
    assert "through the armpit" in tpl and "centroid +38 mm" in tpl
    assert "Segment boundaries in this result" not in report.definitions_html({})
    pdf = report.definitions_html({"registration": {"params": {"labels": "template"}}}, "pdf")
    assert "<table" not in pdf and "knee" in pdf and "same anatomical loop" in pdf

"""bsv.bench.classes: the hard cohort's errors tabulated per class, with the reshaped segments' own error."""

from __future__ import annotations

import pytest

from bsv.bench.classes import changed_segments, classes_markdown, summarise
from bsv.bench.common import Run
from bsv.bodies.variants import HARD_CLASSES, LIMB_SEGMENTS


def _run(subject: str, condition: str, errors: dict[str, float]) -> Run:
    """A bsv run whose every limb and trunk_limbs has truth 2 L and the given signed errors (%, default 0)."""
    names = (*LIMB_SEGMENTS, "trunk_limbs")
    truth = dict.fromkeys(names, 2.0)
    est = {k: 2.0 * (1 + errors.get(k, 0.0) / 100) for k in names}
    return Run(subject, condition, "bsv", True, truth_l=truth, estimated_l=est)


def test_changed_segments_of_each_class() -> None:
    assert changed_segments({"class": "swollen", "segment": "shin_l"}) == ("shin_l",)
    assert changed_segments({"class": "deep_upper_arms"}) == ("upper_arm_l", "upper_arm_r")
    assert changed_segments({"class": "bumps"}) == () == changed_segments({"class": "swollen", "segment": "torso"})


def test_errors_are_summarised_per_class_and_condition() -> None:
    infos = [{"subject": "s0", "variant": {"class": "deep_upper_arms"}},
             {"subject": "s1", "variant": {"class": "swollen", "segment": "thigh_r"}},
             {"subject": "s2", "variant": {"class": "swollen", "segment": "forearm_l"}},
             {"subject": "plain"}]  # a subject without a variant is not a class
    runs = [_run("s0", "noer", {"upper_arm_l": -4.0, "upper_arm_r": -2.0}),
            _run("s1", "noer", {"thigh_r": +8.0, "shin_l": -1.0}),
            _run("s2", "noer", {"forearm_l": -2.0, "trunk_limbs": 0.5}),
            _run("s1", "l515", {"thigh_r": +1.0}),
            _run("plain", "noer", {"thigh_l": 50.0}),
            Run("s2", "l515", "bsv", False, error="diverged"),  # a failed run is not counted
            Run("s0", "noer", "trimesh", True)]  # another method
    t = summarise(infos, runs)
    assert list(t) == ["noer", "l515"] and list(t["noer"]) == ["deep_upper_arms", "swollen"]
    deep, swollen = t["noer"]["deep_upper_arms"], t["noer"]["swollen"]
    assert deep["n"] == 1 and deep["limbs_rve"] == pytest.approx(6.0 / 8) and deep["changed_signed"] == pytest.approx(-3.0)
    assert swollen["n"] == 2 and swollen["changed_signed"] == pytest.approx((8.0 - 2.0) / 2)
    assert swollen["limbs_rve"] == pytest.approx(11.0 / 16) and swollen["trunk_limbs_rve"] == pytest.approx(0.25)
    assert swollen["worst"] == pytest.approx(8.0) and swollen["worst_subject"] == "s1 thigh_r"
    assert t["l515"]["swollen"]["n"] == 1
    md = "\n".join(classes_markdown(infos, runs))
    assert "## By hard class" in md and "| swollen | 2 | 0.69 | 0.25 | +3.00 | +8.0 (s1 thigh_r) |" in md
    assert "| deep_upper_arms | 1 | 0.75 | 0.00 | -3.00 |" in md
    assert classes_markdown([{"subject": "plain"}], runs) == []
    assert set(HARD_CLASSES) >= {"deep_upper_arms", "swollen"}

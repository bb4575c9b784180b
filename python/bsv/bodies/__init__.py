"""Synthetic MakeHuman bodies (CC0 assets): phenotype blending, dual-quaternion A-pose, 14-segment labels,
ground-truth segment volumes, the stature/BMI solver, the synthetic cohort and the default templates.

numpy, with the segment volumes and label rules from the extension; reads the vendored asset ``assets/makehuman/body.npz`` (see scripts/make_assets.py).
"""

from __future__ import annotations

from ..errors import LabelError
from .asset import AssetError, asset_path, load_asset
from .body import Body, SolveError, make_body, solve_stature_bmi
from .cohort import (
    ARM_DOWN_RANGE_DEG,
    ELBOW_RANGE_DEG,
    FLEXED_ELBOW_RANGE_DEG,
    HEAVY_BMI_SHIFT,
    HIP_ABDUCTION_RANGE_DEG,
    MACRO_RANGES,
    NARROW_HIP_ABDUCTION_RANGE_DEG,
    PALM_IN_RANGE_DEG,
    RELAXED_PALM_IN_RANGE_DEG,
    TURN_RANGE_DEG,
    TURNED_RANGE_DEG,
    WIDE_ARM_DOWN_RANGE_DEG,
    MacroRanges,
    Subject,
    check_arm_range,
    check_bmi_shift,
    check_elbow_range,
    check_leg_range,
    check_macros,
    check_palm_range,
    check_turn_range,
    cohort,
    iter_cohort,
    subject,
    volumes_json,
    write_cohort,
    write_subject,
)
from .collide import penetrations
from .labels import PALETTE, segment_volumes, volume
from .model import Phenotype, PhenotypeError, shape
from .pose import Pose, PoseError
from .template import templates, write_templates

__all__ = [
    "ARM_DOWN_RANGE_DEG",
    "ELBOW_RANGE_DEG",
    "FLEXED_ELBOW_RANGE_DEG",
    "HEAVY_BMI_SHIFT",
    "HIP_ABDUCTION_RANGE_DEG",
    "MACRO_RANGES",
    "NARROW_HIP_ABDUCTION_RANGE_DEG",
    "PALETTE",
    "PALM_IN_RANGE_DEG",
    "RELAXED_PALM_IN_RANGE_DEG",
    "TURNED_RANGE_DEG",
    "TURN_RANGE_DEG",
    "WIDE_ARM_DOWN_RANGE_DEG",
    "AssetError",
    "Body",
    "LabelError",
    "MacroRanges",
    "Phenotype",
    "PhenotypeError",
    "Pose",
    "PoseError",
    "SolveError",
    "Subject",
    "asset_path",
    "check_arm_range",
    "check_bmi_shift",
    "check_elbow_range",
    "check_leg_range",
    "check_macros",
    "check_palm_range",
    "check_turn_range",
    "cohort",
    "iter_cohort",
    "load_asset",
    "make_body",
    "penetrations",
    "segment_volumes",
    "shape",
    "solve_stature_bmi",
    "subject",
    "templates",
    "volume",
    "volumes_json",
    "write_cohort",
    "write_subject",
    "write_templates",
]

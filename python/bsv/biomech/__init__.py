"""Biomechanics outputs: body-segment inertial parameters (mass from segment densities, centre of mass,
inertia tensor, joint centres, segment lengths) of a labelled closed mesh, compared with de Leva (1996),
exported as JSON, a de Leva-layout CSV and an OpenSim model. The public entry point is :func:`bsv.bsip`.
"""

from __future__ import annotations

from .compute import BSIP, SEXES, Endpoint, SegmentBSIP, compute, densities
from .export import (
    FILES,
    check_output,
    csv_text,
    osim_model,
    write_all,
    write_csv,
    write_figure,
    write_json,
    write_osim,
)
from .tables import DE_LEVA, DE_LEVA_SOURCE, DEMPSTER_DENSITY_KG_M3, DENSITY_SOURCE, JOINTS, DeLeva

__all__ = [
    "BSIP", "DEMPSTER_DENSITY_KG_M3", "DENSITY_SOURCE", "DE_LEVA", "DE_LEVA_SOURCE", "FILES", "JOINTS", "SEXES",
    "DeLeva", "Endpoint", "SegmentBSIP", "check_output", "compute", "csv_text", "densities", "osim_model", "write_all", "write_csv",
    "write_figure", "write_json", "write_osim",
]

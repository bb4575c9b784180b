"""Test helper: the two-camera rig of the uncertainty tests (one definition for every test file)."""

from __future__ import annotations

import numpy as np

from bsv import uncertainty as unc


def paper_rig(cov_scale: float = 1.0) -> list[unc.CameraSpread]:
    """Front and back cameras 2 m from the body at 1 m height, the paper's covariance times ``cov_scale``."""
    out = []
    for name, z in (("front", 2.0), ("back", -2.0)):
        fwd = np.array([0.0, 0.0, -np.sign(z)])
        down = np.array([0.0, -1.0, 0.0])
        rot = np.column_stack([np.cross(down, fwd), down, fwd])
        out.append(unc.CameraSpread(name, rot, np.array([0.0, 1.0, z]), unc.paper_covariance(name) * cov_scale))
    return out

"""The rig's joint centres of a posed synthetic body (the ground truth of the joint centres that
:mod:`bsv.biomech` finds on a labelled mesh)."""

from __future__ import annotations

import numpy as np

from .asset import Asset, load_asset
from .model import Phenotype, shape
from .pose import Pose, bone_transforms, pose_vertices

#: Joint name (as :data:`bsv.biomech.tables.JOINTS`) -> the MakeHuman bone whose head is that joint.
RIG_BONES: dict[str, str] = {
    "neck": "neck01",
    **{f"{j}_{s}": f"{b}.{s.upper()}" for s in ("l", "r")
       for j, b in (("shoulder", "upperarm01"), ("elbow", "lowerarm01"), ("wrist", "wrist"),
                    ("hip", "upperleg01"), ("knee", "lowerleg01"), ("ankle", "foot"))},
}


def rig_joints(phenotype: Phenotype | None = None, pose: Pose | None = None,
               asset: Asset | None = None) -> dict[str, np.ndarray]:
    """Joint centres (m, world frame of :func:`bsv.bodies.make_body`) of the rig of a body with this
    phenotype and pose: the posed heads of the bones of :data:`RIG_BONES`."""
    a = asset or load_asset()
    ph = phenotype or Phenotype()
    po = pose or Pose()
    v, j = shape(ph, a)
    R, T = bone_transforms(j, po, a)
    pv = pose_vertices(v, j, po, a)
    hips = [a.bone("upperleg01.L"), a.bone("upperleg01.R")]
    centre = j[hips, 0, :].mean(axis=0)
    offset = np.array([centre[0], pv[:, 1].min(), centre[2]])  # as make_body
    out = {}
    for name, bone in RIG_BONES.items():
        b = a.bone(bone)
        out[name] = R[b] @ j[b, 0, :] + T[b] - offset
    return out

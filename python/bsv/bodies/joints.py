"""The rig's joint centres of a posed synthetic body (the ground truth of the joint centres that
:mod:`bsv.biomech` finds on a labelled mesh)."""

from __future__ import annotations

import numpy as np

from .asset import Asset, load_asset
from .model import Phenotype, shape
from .pose import Pose, bone_transforms, dq_skin

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
    v, j = shape(phenotype or Phenotype(), a)
    return posed_rig_joints(v, j, pose or Pose(), a)[1]


def posed_rig_joints(rest_vertices: np.ndarray, rest_joints: np.ndarray, pose: Pose,
                     asset: Asset) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """A rest body posed as :func:`bsv.bodies.make_body` poses it (dual-quaternion skinning, then moved to
    floor y = 0 with the hips centred on x = z = 0) and its rig's joint centres (the posed heads of the
    bones of :data:`RIG_BONES`) in the same frame: ``(vertices, {joint: xyz})``."""
    R, T = bone_transforms(rest_joints, pose, asset)
    pv = dq_skin(rest_vertices, R, T, asset)  # pose_vertices, with the transforms computed once
    hips = [asset.bone("upperleg01.L"), asset.bone("upperleg01.R")]
    # the posed hip joints: the thighs' heads follow their parents (pelvis), which are not rotated
    centre = rest_joints[hips, 0, :].mean(axis=0)
    offset = np.array([centre[0], pv[:, 1].min(), centre[2]])
    out = {}
    for name, bone in RIG_BONES.items():
        b = asset.bone(bone)
        out[name] = R[b] @ rest_joints[b, 0, :] + T[b] - offset
    return pv - offset, out

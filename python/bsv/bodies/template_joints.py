"""Joint centres carried by the default templates: each joint of :data:`bsv.frontend.landmarks.JOINTS`
as a fixed convex combination of template vertices (``assets/template/template_joints.json``).

The centre is the MakeHuman rig's (:func:`bsv.bodies.joints.rig_joints`: the head of the distal bone)
of the body the templates are made from. Its vertices are the ring of the template's surface around
the limb at the joint: vertices within :data:`SLAB_M` of the plane through the joint perpendicular to the
limb's axis and within :data:`RADIUS_M` of the axis. The weights are the minimum-norm non-negative
weights that sum to 1 and reproduce the centre on the template exactly, so the registration's keypoint
term (``bsv_register::Keypoints``) can move a joint by moving its ring, and a rigid motion of the ring
moves the joint with it. Regenerate with ``python -m bsv.bodies.template`` (written with the templates).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import TemplateError
from ..types import Mesh

#: Joint -> (the joint whose direction from this one gives the ring's axis). Distal ends (wrist, ankle)
#: use the proximal neighbour (the axis of the forearm / shin).
AXIS_TO: dict[str, str] = {
    **{f"{a}_{s}": f"{b}_{s}" for s in ("l", "r")
       for a, b in (("shoulder", "elbow"), ("elbow", "wrist"), ("wrist", "elbow"),
                    ("hip", "knee"), ("knee", "ankle"), ("ankle", "knee"))},
}

#: Joints at the end of a limb: absent from a template whose hands and feet were removed when the
#: centre lies beyond the cap.
DISTAL: tuple[str, ...] = ("wrist", "ankle")

#: Half-thickness (m) of the slab around the joint's cross-section plane.
SLAB_M = 0.02
#: Largest distance (m) of a ring vertex from the limb's axis.
RADIUS_M = 0.14
#: Largest distance (m) between the combination and the rig's centre on the template.
TOLERANCE_M = 1e-6


def convex_weights(points: np.ndarray, centre: np.ndarray) -> np.ndarray:
    """Minimum-norm weights w >= 0, sum 1, with ``w @ points == centre`` (active-set on the negatives).
    Raises :class:`TemplateError` when the centre is outside the points' convex hull."""
    active = np.ones(len(points), dtype=bool)
    b = np.append(centre, 1.0)
    for _ in range(len(points)):
        a = np.vstack([points[active].T, np.ones(int(active.sum()))])  # 4 x k
        w_act = a.T @ np.linalg.lstsq(a @ a.T, b, rcond=None)[0]
        if (w_act >= -1e-12).all():
            w = np.zeros(len(points))
            w[active] = np.clip(w_act, 0.0, None)
            w /= w.sum()
            if np.linalg.norm(w @ points - centre) > TOLERANCE_M:
                break
            return w
        idx = np.flatnonzero(active)
        active[idx[w_act < 0]] = False
        if active.sum() < 4:
            break
    raise TemplateError(f"joint centre {centre.round(4).tolist()} is not inside its ring of template vertices")


def joint_ring(vertices: np.ndarray, centre: np.ndarray, towards: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(vertex indices, weights) of the ring around ``centre`` perpendicular to ``towards - centre``."""
    axis = towards - centre
    axis /= np.linalg.norm(axis)
    rel = vertices - centre
    along = rel @ axis
    radial = np.linalg.norm(rel - np.outer(along, axis), axis=1)
    idx = np.flatnonzero((np.abs(along) <= SLAB_M) & (radial <= RADIUS_M))
    if len(idx) < 4:
        raise TemplateError(f"only {len(idx)} template vertices around the joint at {centre.round(3).tolist()}")
    # Keep the component of the slab that surrounds the axis: the vertices nearest the axis first, up to
    # the radius where the ring closes (the torso beside a limb is farther than the limb's own surface).
    w = convex_weights(vertices[idx], centre)
    keep = w > 0
    return idx[keep], w[keep]


def template_joints(mesh: Mesh, centres: dict[str, np.ndarray]) -> dict[str, dict[str, Any]]:
    """``{joint: {"centre", "vertices", "weights"}}`` of a template and the rig's joint centres (a
    :data:`DISTAL` joint beyond the template's cap is left out)."""
    out: dict[str, dict[str, Any]] = {}
    for joint, other in AXIS_TO.items():
        try:
            idx, w = joint_ring(mesh.vertices, centres[joint], centres[other])
        except TemplateError:
            if joint.startswith(DISTAL):
                continue  # the template ends before this joint (hands and feet removed)
            raise
        out[joint] = {"centre": [round(float(c), 9) for c in centres[joint]],
                      "vertices": [int(i) for i in idx], "weights": [float(x) for x in w]}
    return out


__all__ = ["AXIS_TO", "DISTAL", "RADIUS_M", "SLAB_M", "convex_weights", "joint_ring", "template_joints"]

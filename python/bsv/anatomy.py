"""Segment definitions: which joint bounds each segment, and where on the body its boundary runs.

The segments are the MakeHuman template's (``assets/template``): every vertex belongs to the segment whose
rig bones weigh most on it (:mod:`bsv.bodies.labels`; the neck's bones go with the head, the clavicles'
and shoulders' with the torso). A boundary between two segments is therefore a closed loop of the
surface at a joint, not a plane: :data:`BOUNDARIES` says where each loop runs as a biomechanist would
read it, and :func:`measure_boundaries` measures it on the template against the rig's joint centres (the
numbers of ``docs/DESIGN.md``, "Segment definitions", printed by ``python -m bsv.anatomy``).

Where a result's boundaries come from depends on its label source (:data:`LABEL_SOURCE_TEXT`): with
``labels=template`` (the camera path, ``bsv process``) the fitted mesh keeps the template's segments, so
each boundary is this same anatomical loop on every subject; with ``labels=cloud`` each fitted vertex takes
the label of its nearest measured point, so the boundaries follow the cloud's labels (a scanner's, or
the camera images' cut lines).
"""

from __future__ import annotations

import functools
import sys
from dataclasses import dataclass

import numpy as np

from . import _bsv
from .biomech.tables import DE_LEVA, JOINTS, kind
from .palette import plain_name
from .types import SEGMENT_IDS, Mesh

#: Segment kinds in head-to-toe order (the rows of :func:`definition_rows`).
SEGMENT_KINDS: tuple[str, ...] = ("head", "torso", "upper_arm", "forearm", "hand", "thigh", "shin", "foot")

def kind_name(segment_kind: str) -> str:
    """The plain-language name of a segment kind (:func:`bsv.palette.plain_name` without the side)."""
    name = plain_name(segment_kind if segment_kind in SEGMENT_IDS else f"{segment_kind}_l")
    return name.removeprefix("Left ").capitalize()


@dataclass(frozen=True)
class Boundary:
    """One joint's boundary loop (its two segments: :data:`bsv.biomech.tables.JOINTS`)."""

    #: Joint kind (``shoulder``, ``hip``, ...; :data:`bsv.biomech.tables.JOINTS` without the side).
    joint: str
    #: Where the loop runs (checked against :func:`measure_boundaries` by the tests).
    text: str

    @property
    def segments(self) -> tuple[str, str]:
        """The two segment kinds the loop separates, in :data:`bsv.biomech.tables.JOINTS`'s order."""
        a, b = JOINTS[self.joint if self.joint in JOINTS else f"{self.joint}_l"]
        return kind(a), kind(b)


#: The seven boundaries by joint kind.
BOUNDARIES: dict[str, Boundary] = {b.joint: b for b in (
    Boundary("neck", "around the base of the neck (the neck goes with the head, the clavicles with the torso)"),
    Boundary("shoulder", "an oblique loop from the top of the shoulder, medial to and above the shoulder joint centre, "
             "down through the armpit: the deltoid goes with the upper arm"),
    Boundary("elbow", "around the elbow near its joint centre, higher on the inner and back side"),
    Boundary("wrist", "around the wrist at its joint centre"),
    Boundary("hip", "an oblique loop from the side of the hip, level with the hip joint centre, through the groin at "
             "the front and across the buttock at the back to the crotch on the inner side: the buttock's "
             "upper part goes with the torso"),
    Boundary("knee", "around the knee just below its joint centre, lower at the front than at the back (the hollow "
             "of the knee)"),
    Boundary("ankle", "around the ankle above its joint centre, higher at the front than at the heel"),
)}

#: How a result's segment boundaries were placed, by its label source (the registration's ``labels``).
LABEL_SOURCE_TEXT: dict[str, str] = {
    "template": "the template's own segments carried by the fit: each boundary is the same anatomical loop "
                "on every subject",
    "cloud": "each point of the fitted surface takes the segment of the nearest measured point: the boundaries "
             "follow the measured cloud's labels",
}


#: The templates a result can be fitted with (volumes.json ``template.kind``), in words.
TEMPLATE_TEXT: dict[str, str] = {
    "default": "the average MakeHuman body",
    "female": "the female MakeHuman body (the subject's sex)",
    "male": "the male MakeHuman body (the subject's sex)",
    "fine": "the average MakeHuman body, subdivided",
    "full": "the average MakeHuman body with head, hands and feet",
    "custom": "a template given by the user",
}


def bounds(segment_kind: str) -> tuple[list[str], list[str]]:
    """The joint kinds at the proximal and at the distal end of a segment kind (from
    :data:`bsv.biomech.tables.JOINTS`, whose pairs are (proximal, distal) but for the neck's (head, torso)):
    the torso's neck loop is its proximal end, the head's is listed as distal."""
    prox: list[str] = []
    dist: list[str] = []
    for joint, (a, b) in JOINTS.items():
        j = joint.removesuffix("_l").removesuffix("_r")
        if joint.endswith("_r"):
            continue
        if kind(b) == segment_kind:
            prox.append(j)
        if kind(a) == segment_kind:
            dist.append(j)
    return prox, dist


def segment_rows() -> list[tuple[str, str, str]]:
    """Rows (segment, the joint loops that bound it, de Leva's endpoints of its inertial parameters) of the
    segment table in the docs."""
    rows = []
    for k in SEGMENT_KINDS:
        prox, dist = bounds(k)
        if prox:
            ends = ", ".join(f"{j} loop ({where})" for joints, where in ((prox, "proximal"), (dist, "distal"))
                             for j in joints)
        else:  # the head: its one loop
            ends = ", ".join(f"{j} loop" for j in dist)
        lev = DE_LEVA["male"][k]
        rows.append((kind_name(k), ends, f"{lev.origin} to {lev.other}"))
    return rows


def boundary_rows() -> list[tuple[str, str, str, str]]:
    """Rows (joint, the two segments, where the loop runs, where it lies on the template against the rig's
    joint centre) of the boundary table in the report and the docs."""
    geometry = measure_boundaries()
    rows = []
    for b in BOUNDARIES.values():
        g = geometry.get(f"{b.joint}_l")
        where = ("-" if g is None else f"centroid {g.centroid_mm:+.0f} mm, from {g.span_mm[0]:+.0f} to "
                 f"{g.span_mm[1]:+.0f} mm, tilted {g.tilt_deg:.0f} deg")
        rows.append((b.joint.capitalize(), f"{kind_name(b.segments[0])} / {kind_name(b.segments[1]).lower()}",
                     b.text, where))
    return rows


@dataclass(frozen=True)
class LoopGeometry:
    """A boundary loop of the template measured against the rig's joint centre, along the axis of the
    limb (proximal to distal; millimetres, positive = distal)."""

    #: Joint name (left side).
    joint: str
    #: The loop's centroid along the axis.
    centroid_mm: float
    #: The loop's most proximal and most distal point along the axis.
    span_mm: tuple[float, float]
    #: Angle between the loop's best-fit plane and the limb's cross-section (degrees).
    tilt_deg: float
    #: Along the axis, the loop's point farthest in each direction from its centroid: ``front``, ``back``,
    #: ``lateral``, ``medial``, ``top``, ``bottom``.
    sides_mm: dict[str, float]


#: The other joint that gives a joint's limb axis (proximal to distal), and its direction.
_AXIS: dict[str, tuple[str, int]] = {"shoulder_l": ("elbow_l", 1), "elbow_l": ("wrist_l", 1),
                                     "wrist_l": ("elbow_l", -1), "hip_l": ("knee_l", 1),
                                     "knee_l": ("ankle_l", 1), "ankle_l": ("knee_l", -1)}
#: World directions of the left side (X is the subject's left, Y up, Z forward).
_SIDES: dict[str, tuple[float, float, float]] = {"front": (0, 0, 1), "back": (0, 0, -1), "lateral": (1, 0, 0),
                                                 "medial": (-1, 0, 0), "top": (0, 1, 0), "bottom": (0, -1, 0)}


def _loop(mesh: Mesh, a: str, b: str) -> np.ndarray:
    """The vertices on the boundary between segments ``a`` and ``b`` of a labelled closed mesh."""
    f = np.asarray(mesh.faces)
    fl = (np.asarray(mesh.face_labels) if mesh.face_labels is not None
          else np.asarray(_bsv.face_labels_from_vertices(f, mesh.vertex_labels)))
    la, lb = SEGMENT_IDS[a], SEGMENT_IDS[b]
    mine = np.isin(fl, (la, lb))
    e = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    lab = np.tile(fl, 3)
    keep = np.tile(mine, 3)
    e, lab = np.sort(e[keep], axis=1), lab[keep]
    order = np.lexsort((e[:, 1], e[:, 0]))
    e, lab = e[order], lab[order]
    shared = np.all(e[1:] == e[:-1], axis=1) & (lab[1:] != lab[:-1])
    return np.unique(e[1:][shared])


@functools.cache
def measure_boundaries() -> dict[str, LoopGeometry]:
    """The limb joints' boundary loops of the full template (left side) against the template's joint
    centres (the MakeHuman rig's, ``assets/template/template_joints.json``)."""
    mesh = Mesh(*_bsv.default_template(True))
    v = np.asarray(mesh.vertices)
    centres = {name: np.asarray(w) @ v[np.asarray(ids)] for name, ids, w, *_ in _bsv.template_joints("full")}
    out = {}
    for joint, (other, sign) in _AXIS.items():
        a, b = JOINTS[joint]
        p = v[_loop(mesh, a, b)]
        c, jc = p.mean(axis=0), centres[joint]
        axis = sign * (centres[other] - jc)
        axis /= np.linalg.norm(axis)
        s = (p - jc) @ axis
        normal = np.linalg.svd(p - c)[2][2]
        sides = {k: float(1e3 * s[np.argmax((p - c) @ np.asarray(d))]) for k, d in _SIDES.items()}
        out[joint] = LoopGeometry(joint, float(1e3 * (c - jc) @ axis), (float(1e3 * s.min()), float(1e3 * s.max())),
                                  float(np.degrees(np.arccos(min(1.0, abs(float(normal @ axis)))))), sides)
    return out


def markdown() -> str:
    """The segment definitions and the template's measured loops as Markdown (``docs/DESIGN.md``)."""
    lines = ["| segment | bounded by | de Leva endpoints (inertial parameters) |", "|---|---|---|"]
    lines += [f"| {' | '.join(r)} |" for r in segment_rows()]
    lines += ["", ("| boundary | between | where the loop runs | on the template (mm along the limb from the rig's "
                   "joint centre, + = distal; tilt against the cross-section) |"), "|---|---|---|---|"]
    lines += [f"| {' | '.join(r)} |" for r in boundary_rows()]
    lines += ["", "The limb loops' points farthest in each direction from their centroid, mm along the limb:", "",
              "| joint | front | back | lateral | medial | top | bottom |", "|---|---|---|---|---|---|---|"]
    for g in measure_boundaries().values():
        s = g.sides_mm
        lines.append(f"| {g.joint.removesuffix('_l')} | " + " | ".join(f"{s[k]:+.0f}" for k in _SIDES) + " |")
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    sys.stdout.write(markdown())

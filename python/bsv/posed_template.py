"""The embedded templates posed like the subject before the registration (the camera path).

The embedded templates are MakeHuman bodies in the default A-pose (arms 40 deg below horizontal, elbows
flexed 10 deg, each leg 4 deg out from vertical). A subject holds an A-pose of its own: arms 25-50 deg down, elbows
10-25 deg. The registration can rotate a limb into place, but the region where the limb meets the trunk
then bends the way the registration's smoothness dictates, not the way a body bends, and the template's
shoulder boundary (the upper arm's top) lands off the subject's: measured on the camera path, upper arms
3-4 % mean RVE on the cohorts whose arms hang lower or higher than 40 deg, too large on lowered arms and too
small on raised ones (BENCH.md, round 2 session 14).

So the camera path poses the template first, exactly as the MakeHuman rig poses a body:

1. :func:`pose_from_joints` reads the angles of :class:`bsv.bodies.pose.Pose` from the measured joint
   centres (``joints_m``): each arm's angle below horizontal (shoulder to elbow), its elbow flexion
   (elbow to wrist, about the axis across the upper arm and the forward direction) and each leg's
   abduction (hip to ankle), in the frame of the hips (x along the hip line in the horizontal plane,
   y up). On the rig's own joints it returns the arm and leg angles exactly and the elbows within 1 deg
   (the forearm's twist moves the wrist a little off the flexion plane).
2. :func:`posed_template` poses the template's rest body with the rig's dual-quaternion skinning
   (:func:`bsv.bodies.joints.posed_rig_joints`, the same function that poses every synthetic body),
   removes head, hands and feet and caps the holes as the embedded template is made
   (:func:`bsv.bodies.template.trunk_limbs_mesh`), and rebuilds the joint rings the keypoint term pulls
   (:func:`bsv.bodies.template_joints.template_joints`). The segments are the skinning weights', as on
   every MakeHuman body. With the default pose it reproduces the embedded template.

An arm is posed no lower than :data:`ARM_POSE_MAX_DOWN_DEG` below the horizontal: from there the registration's
articulation lowers it. Posed all the way down to an arm hanging 50-60 deg, the template's shoulder boundary
landed 2.7 mm distal of the subject's and the upper arm came out 2.5 % too small (BENCH.md, round 2 session 40).

The rest bodies and the rig come from ``bsv/data/template_rig.npz`` (about 1 MB, written with the templates
by ``python -m bsv.bodies.template``), not from the 17 MB MakeHuman asset.
"""

from __future__ import annotations

import dataclasses
import zipfile
import zlib
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np

from .bodies.pose import Pose
from .bodies.template import POSABLE
from .errors import TemplateError
from .types import Mesh

#: The measured joints :func:`pose_from_joints` reads.
POSE_JOINTS: tuple[str, ...] = tuple(f"{j}_{s}" for s in ("l", "r")
                                     for j in ("shoulder", "elbow", "wrist", "hip", "ankle"))
#: Template kinds that can be posed (the 9-segment templates: average, female, male).
POSABLE_KINDS: tuple[str, ...] = tuple(POSABLE)
#: An angle measured this far (deg) outside the pose's range is clipped without a warning (the measured
#: elbow flexion scatters by 1.5 deg: a straight arm reads -1 deg).
CLIP_SILENT_DEG = 3.0
#: The lowest the camera path poses the template's arms (degrees below the horizontal; its own A-pose is 40).
#: An arm measured hanging lower is posed at this angle, and the registration's articulation takes it the rest
#: of the way. Posed all the way to 50-60 deg, the template's shoulder boundary came out 2.7 mm distal of the
#: subject's and those upper arms -2.5 % signed (|error| 2.5 %); posed at 45 deg, +0.8 mm and -1.2 % (|error|
#: 1.4 %). Raised arms are posed as measured: there full posing is right (+0.8 % signed at 15-25 deg) and less
#: posing makes them too small. Wide A-poses (``bench synth --arm-down 15,60``), seeds 0-1 (BENCH.md, round 2
#: session 40).
ARM_POSE_MAX_DOWN_DEG = 45.0


def rig_path() -> Path:
    """Where the templates' rig is: the package's ``data/template_rig.npz``, else the repository's
    ``assets/template/template_rig.npz``."""
    here = Path(__file__).resolve().parent
    for c in (here / "data" / "template_rig.npz", here.parents[1] / "assets" / "template" / "template_rig.npz"):
        if c.is_file():
            return c
    return here / "data" / "template_rig.npz"


@dataclass(frozen=True)
class TemplateRig:
    """The rig of the posable templates: one rest body and rig asset per kind, with the full body's
    faces and 14-segment face labels."""

    assets: dict[str, Any]
    faces: np.ndarray
    face_labels: np.ndarray


@lru_cache(maxsize=1)
def load_template_rig() -> TemplateRig:
    """Read :func:`rig_path` once; :class:`bsv.errors.TemplateError` naming the file and the fix when it
    is missing or incomplete."""
    from .bodies.asset import rig_asset

    p = rig_path()
    fix = "reinstall bsv, or regenerate it with `python -m bsv.bodies.template --overwrite`"
    if not p.is_file():
        raise TemplateError(f"{p}: the templates' rig is missing; {fix}")
    try:
        with np.load(p, allow_pickle=False) as d:
            common = {k: d[k] for k in ("bone_parent", "skin_vertex", "skin_bone", "skin_weight")}
            names = tuple(str(s) for s in d["bone_names"])
            faces = d["faces"].astype(np.int64)
            assets = {kind: rig_asset(d[f"rest_vertices_{kind}"], faces, names, common["bone_parent"],
                                      d[f"rest_joints_{kind}"], common["skin_vertex"], common["skin_bone"],
                                      common["skin_weight"]) for kind in POSABLE_KINDS}
            return TemplateRig(assets, faces, d["face_labels"].astype(np.uint8))
    except (KeyError, ValueError, OSError, EOFError, zipfile.BadZipFile, zlib.error) as e:
        raise TemplateError(f"{p}: not a valid template rig ({type(e).__name__}: {e}); {fix}") from e


@dataclass(eq=False, repr=False)
class PosedTemplate(Mesh):
    """An embedded template posed by :func:`posed_template`: a labelled :class:`~bsv.types.Mesh` that also
    carries its kind, its pose and its joint rings (``(name, vertices, weights)``, as
    :func:`bsv.keypoints.joint_rings` gives for the embedded templates)."""

    kind: str = "default"
    pose: Pose = field(default_factory=Pose)
    #: MakeHuman's gender of the rest body when it was blended between the female and the male one
    #: (:func:`posed_template`'s ``gender``); None for the kind's own body.
    gender: float | None = None
    #: The joint rings; None (as for any other mesh) when they were not built.
    joint_rings: list[tuple[str, list[int], list[float]]] | None = None

    def pose_json(self) -> dict[str, float]:
        """The pose's angles in degrees (``arm_down_l``, ``elbow_l``, ``hip_abduction_l``, ... rounded to 0.1)."""
        return {k: round(float(getattr(self.pose, k)), 1) for k in Pose.RANGES}

    def __repr__(self) -> str:
        return f"PosedTemplate({self.kind}, {len(self.vertices)} vertices, pose {self.pose_json()})"


def _angles(p: dict[str, np.ndarray]) -> dict[str, Any]:
    """The pose angles (deg) of the joints in :data:`POSE_JOINTS` (see :func:`pose_from_joints`)."""
    x = p["hip_l"] - p["hip_r"]
    x[1] = 0.0
    x /= np.linalg.norm(x)
    up = np.array([0.0, 1.0, 0.0])
    frame = np.vstack([x, up, np.cross(x, up)])  # rows: the subject's left, up, forward
    angles: dict[str, Any] = {}
    for side, sx in (("l", 1.0), ("r", -1.0)):
        s, e, w, h, a = (frame @ p[f"{j}_{side}"] for j in ("shoulder", "elbow", "wrist", "hip", "ankle"))
        ua = e - s
        angles[f"arm_down_{side}"] = float(np.degrees(np.arctan2(-ua[1], sx * ua[0])))
        u = ua / np.linalg.norm(ua)
        n = np.cross(u, [0.0, 0.0, 1.0])
        n /= np.linalg.norm(n)
        f = w - e
        angles[f"elbow_{side}"] = float(np.degrees(np.arctan2(np.cross(u, f) @ n, u @ f)))
        leg = a - h
        angles[f"hip_abduction_{side}"] = float(np.degrees(np.arctan2(sx * leg[0], -leg[1])))
    return angles


def pose_from_joints(joints: Mapping[str, Any]) -> tuple[Pose, list[str]]:
    """The :class:`bsv.bodies.pose.Pose` of measured joint centres (``{name: xyz or JointCentre}``, metres,
    Y up, the subject facing +Z) and the notes on any angle clipped to the pose's range (more than
    :data:`CLIP_SILENT_DEG` outside it). Raises :class:`KeyError` naming the joints of :data:`POSE_JOINTS`
    that are missing, :class:`ValueError` when the joints give no angle (coincident or non-finite joints)."""
    from .keypoints import joint_xyz

    missing = [n for n in POSE_JOINTS if n not in joints]
    if missing:
        raise KeyError(", ".join(missing))
    with np.errstate(invalid="ignore", divide="ignore"):  # coincident joints: NaN angles, refused below
        angles = _angles({n: joint_xyz(joints[n]) for n in POSE_JOINTS})
    bad = [name for name, v in angles.items() if not np.isfinite(v)]
    if bad:
        raise ValueError(f"no angle for {', '.join(bad)} (coincident joints)")
    notes = []
    for name, (lo, hi) in Pose.RANGES.items():
        if name not in angles:  # the palms: not read from the joints (bsv.frontend.palms)
            continue
        v = angles[name]
        clipped = min(max(v, lo), hi)
        if abs(v - clipped) > CLIP_SILENT_DEG:
            notes.append(f"{name} {round(v):d} deg measured, the template posed at {round(clipped):d} "
                         f"(the pose's range is {lo} to {hi} deg)")
        angles[name] = clipped
    return Pose(**angles), notes


def posed_template(kind: str, pose: Pose, gender: float | None = None) -> PosedTemplate:
    """The 9-segment embedded template of ``kind`` (:data:`POSABLE_KINDS`) in ``pose`` (a
    :class:`bsv.bodies.pose.Pose`), with its joint rings; see the module notes. ``gender`` (the average
    template only; 0 female ... 1 male): its rest body and rest joints blended between the female and the male
    ones, as MakeHuman's gender macro blends them (the average body is their exact midpoint, gender 0.5)."""
    from .bodies.joints import posed_rig_joints
    from .bodies.labels import vertex_labels_from_faces
    from .bodies.template import trunk_limbs_mesh
    from .bodies.template_joints import template_joints

    if kind not in POSABLE_KINDS:
        raise TemplateError(f"template kind {kind!r} cannot be posed; use one of {', '.join(POSABLE_KINDS)}")
    rig = load_template_rig()
    a = rig.assets[kind]
    rest, joints = a.vertices, a.joints_rest
    if gender is not None:
        if kind != "default" or not (0.0 <= gender <= 1.0):
            raise TemplateError(f"a template's gender blends the average template only and lies in [0, 1]; got "
                                f"kind {kind!r}, gender {gender!r}")
        f, m = rig.assets["female"], rig.assets["male"]
        rest = f.vertices + gender * (m.vertices - f.vertices)
        joints = f.joints_rest + gender * (m.joints_rest - f.joints_rest)
    vertices, centres = posed_rig_joints(rest, joints, pose, a)
    full = Mesh(vertices, rig.faces, vertex_labels_from_faces(len(vertices), rig.faces, rig.face_labels), rig.face_labels)
    trunk = trunk_limbs_mesh(full)
    rings = [(name, list(r["vertices"]), list(r["weights"])) for name, r in sorted(template_joints(trunk, centres).items())]
    return PosedTemplate(trunk.vertices, trunk.faces, trunk.vertex_labels, trunk.face_labels,
                         kind=kind, pose=pose, joint_rings=rings, gender=gender)


def camera_template(template: Mesh | None, sex: str | None, joints: Mapping[str, Any],
                    gender: float | None = None,
                    palms: tuple[float | None, float | None] | None = None) -> tuple[Mesh | None, list[str]]:
    """The template the camera path registers, as ``bsv process`` and ``bsv bench synth --segmentation camera``
    choose it: ``template`` (None: the embedded template of ``sex``, or the average one, of MakeHuman's
    ``gender`` when given: the sex read from the capture, :attr:`bsv.frontend.sex.SexEstimate.gender`) posed
    like the subject (:func:`pose_from_joints`, :func:`posed_template`; an arm no lower than
    :data:`ARM_POSE_MAX_DOWN_DEG`), its palms turned as measured (``palms``: the (left, right) angles of
    :func:`bsv.frontend.palms.palm_turns`, deg; None for a palm not read, which stays forward with a note; None
    for both: forward, as the template's own), and the notes on what was not as measured (a clipped angle; a
    joint missing, when the template stays in its own pose). A template that cannot be posed (a user's mesh,
    the fine or full template) is returned as it is, without notes."""
    from .keypoints import template_kind

    kind = (sex or "default") if template is None else template_kind(template)
    blend = gender if kind == "default" else None
    if kind not in POSABLE_KINDS:
        return template, []
    if not joints:
        return template, ["the template kept its own A-pose: no 3-D joint centres (both cameras are needed)"]
    try:
        pose, notes = pose_from_joints(joints)
    except KeyError as e:
        names = str(e.args[0])
        which = f"joints {names} were" if "," in names else f"joint {names} was"
        return template, [f"the template kept its own A-pose: {which} not measured"]
    except ValueError as e:
        return template, [f"the template kept its own A-pose: {e}"]
    pose = dataclasses.replace(pose, arm_down_l=min(pose.arm_down_l, ARM_POSE_MAX_DOWN_DEG),
                               arm_down_r=min(pose.arm_down_r, ARM_POSE_MAX_DOWN_DEG))
    if palms is not None:
        from .frontend.palms import template_palms

        turned, palm_notes = template_palms(palms)
        pose = dataclasses.replace(pose, **turned)
        notes = [*notes, *palm_notes]
    return posed_template(kind, pose, blend), notes


def template_record(template: Mesh | None, sex: str | None) -> dict[str, Any]:
    """volumes.json's ``template`` record: the ``kind`` fitted (``"default"``, ``"female"``, ``"male"``,
    ``"fine"``, ``"full"`` or ``"custom"``), the ``sex`` asked for, and for a posed template its ``pose``
    (degrees, :meth:`PosedTemplate.pose_json`)."""
    from .keypoints import template_kind

    if isinstance(template, PosedTemplate):
        out: dict[str, Any] = {"kind": template.kind, "sex": sex, "pose": template.pose_json()}
        if template.gender is not None:
            out["gender"] = round(template.gender, 4)
        return out
    return {"kind": "default" if template is None else template_kind(template) or "custom", "sex": sex}


__all__ = [
    "ARM_POSE_MAX_DOWN_DEG",
    "POSABLE_KINDS",
    "POSE_JOINTS",
    "PosedTemplate",
    "TemplateRig",
    "camera_template",
    "load_template_rig",
    "pose_from_joints",
    "posed_template",
    "rig_path",
    "template_record",
]

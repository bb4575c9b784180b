"""Measured joint centres for the registration's keypoint term (``bsv.register(..., keypoints=...)``)
and the template joints they pull (the joint rings the embedded templates carry, see
:mod:`bsv.bodies.template_joints` and ``bsv_register::Keypoints``)."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from functools import lru_cache
from typing import Any

import numpy as np

from . import _bsv
from .errors import InputError
from .types import SEGMENT_IDS, Mesh, PointCloud

#: Every joint a template may carry (the names of :data:`bsv.frontend.landmarks.JOINTS`).
JOINT_NAMES: tuple[str, ...] = tuple(f"{j}_{s}" for s in ("l", "r")
                                     for j in ("shoulder", "elbow", "wrist", "hip", "knee", "ankle"))

#: Kinds of the embedded templates that carry joint rings, by vertex count (the sexed templates share the
#: default's mesh and count).
_KINDS_BY_VERTICES = {4177: ("default", "female", "male"), 16702: ("fine",), 13380: ("full",)}


@lru_cache(maxsize=5)
def _embedded_vertices(kind: str) -> np.ndarray:
    return np.asarray(_bsv.default_template(kind=kind)[0])


def template_kind(mesh: Mesh) -> str | None:
    """The embedded template's kind (``"default"``, ``"fine"``, ``"full"``, ``"female"``, ``"male"``) when
    ``mesh`` is that template (its vertices, in its order, before any fit), else None. The fine template is
    recognised by the default's vertices it begins with (its midpoints follow), as the benchmark's own
    subdivision of the default may round a midpoint differently in the last bit."""
    v = np.asarray(mesh.vertices)
    for kind in _KINDS_BY_VERTICES.get(len(v), ()):
        ref = _embedded_vertices("default" if kind == "fine" else kind)
        if np.array_equal(v[: len(ref)], ref):
            return kind
    return None


def joint_rings(mesh: Mesh) -> list[tuple[str, list[int], list[float]]] | None:
    """The joint rings of an embedded template (or of one posed by :mod:`bsv.posed_template`, which carries
    them) as ``(name, vertices, weights)``, or None for any other mesh."""
    carried = getattr(mesh, "joint_rings", None)
    if carried is not None:
        return [(name, list(v), list(w)) for name, v, w in carried]
    kind = template_kind(mesh)
    if kind is None:
        return None
    return [(name, list(v), list(w)) for name, v, w, _ in _bsv.template_joints(kind)]


#: Segment boundaries the camera path can pull like joints (``bsv.register``'s keypoint term): name -> (the
#: segment whose vertices form the ring, the segment across the boundary). A boundary ring is the ring of the
#: first segment's vertices that share an edge with a vertex of the second (uniform weights), read from any
#: labelled template, so it is the same anatomical loop on every MakeHuman template; its centre is pulled to a
#: height the capture measures, along the target's direction (:mod:`bsv.frontend.groin`: the thighs' proximal
#: boundary from the crotch the depth images show, along the body's up axis).
BOUNDARY_RINGS: dict[str, tuple[str, str]] = {"hip_loop_l": ("thigh_l", "torso"), "hip_loop_r": ("thigh_r", "torso")}


def boundary_rings(mesh: Mesh, names: Sequence[str] | None = None) -> list[tuple[str, list[int], list[float]]]:
    """The :data:`BOUNDARY_RINGS` (those of ``names``, default all) of a labelled template as ``(name,
    vertices, weights)``; a boundary the template's labels do not have is left out (none without vertex
    labels)."""
    labels = getattr(mesh, "vertex_labels", None)
    if labels is None:
        return []
    lab = np.asarray(labels)
    faces = np.asarray(mesh.faces, dtype=np.int64)
    edges = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    out = []
    for name in BOUNDARY_RINGS if names is None else names:
        if name not in BOUNDARY_RINGS:
            continue
        inner, outer = (SEGMENT_IDS[s] for s in BOUNDARY_RINGS[name])
        a, b = lab[edges[:, 0]], lab[edges[:, 1]]
        ring = np.union1d(edges[(a == inner) & (b == outer), 0], edges[(b == inner) & (a == outer), 1])
        if len(ring) >= 3:
            out.append((name, [int(v) for v in ring], [1.0 / len(ring)] * len(ring)))
    return out


def _bad(message: str) -> InputError:
    e = InputError(message)
    e.argument = "keypoints"
    return e


def _one(name: str, value: Any) -> tuple[str, list[float], float, list[float] | None]:
    """``(name, xyz, confidence, direction)`` of one measured joint or boundary: a
    :class:`bsv.frontend.landmarks.JointCentre` or an object with ``xyz``, ``confidence`` and optionally
    ``direction`` (:class:`bsv.frontend.groin.LoopTarget`), a ``{"xyz", "confidence", "direction"}`` dict (the
    volumes JSON's ``joints_m`` entry; the last two optional), ``(xyz, confidence)`` or xyz. ``direction``: the
    one direction the measurement holds (the registration pulls along it alone), None for a full position."""
    direction: Any = None
    if hasattr(value, "xyz"):
        xyz, conf, direction = value.xyz, getattr(value, "confidence", 1.0), getattr(value, "direction", None)
    elif isinstance(value, Mapping):
        if "xyz" not in value:
            raise _bad(f"keypoints[{name!r}]: a dict needs an 'xyz' entry (and optionally 'confidence')")
        xyz, conf, direction = value["xyz"], value.get("confidence", 1.0), value.get("direction")
    elif isinstance(value, tuple) and len(value) == 2 and np.ndim(value[0]) == 1:
        xyz, conf = value
    else:
        xyz, conf = value, 1.0
    try:
        p = np.asarray(xyz, dtype=np.float64).reshape(-1)
        c = float(conf)
        a = None if direction is None else np.asarray(direction, dtype=np.float64).reshape(-1)
    except (TypeError, ValueError) as e:
        raise _bad(f"keypoints[{name!r}]: expected 3 coordinates (metres) and a confidence, got {value!r}") from e
    if p.shape != (3,) or not np.isfinite(p).all():
        raise _bad(f"keypoints[{name!r}]: expected 3 finite coordinates in metres, got {xyz!r}")
    if not (math.isfinite(c) and 0.0 <= c <= 1.0):
        raise _bad(f"keypoints[{name!r}]: confidence must be in [0, 1], got {conf!r}")
    if a is not None and (a.shape != (3,) or not np.isfinite(a).all() or not np.linalg.norm(a) > 0.0):
        raise _bad(f"keypoints[{name!r}]: a direction is 3 finite coordinates, not all zero, got {direction!r}")
    return str(name), [float(x) for x in p], c, None if a is None else [float(x) for x in a]


def as_keypoints(keypoints: Mapping[str, Any]) -> list[tuple[str, list[float], float, list[float] | None]]:
    """The measured joints (and boundaries) of a ``{name: joint}`` mapping as ``(name, xyz, confidence,
    direction)`` tuples (direction None for a full position)."""
    if not isinstance(keypoints, Mapping):
        raise _bad(f"keypoints must be a dict {{joint name: position}}, got {type(keypoints).__name__}")
    return [_one(name, value) for name, value in keypoints.items()]


#: The joint kinds the camera path lets pull the template by default (``bsv process``, ``bench synth
#: --segmentation camera``): the shoulders, the elbows, the wrists and the hips. Measured on the synthetic cohort
#: (benchmarks/BENCH.md): the shoulders and wrists lower the upper arms' mean error on five of six runs (by
#: 0.3-0.6 points, seeds 0, 2, 4; round 2 session 5); the hips, since their offsets depend on the body's
#: build (:data:`bsv.frontend.landmarks.JOINT_OFFSETS_M`, session 12: vertical error sd 10 -> 6.6 mm), lower
#: the torso's error and the eight limbs' mean on all eight runs of seeds 0, 2, 4, 6 x noer, l515 (thighs on 15
#: of 16 sides: seed 0 2.5-2.8 -> 1.3-2.0 %, seed 2 3.7-3.9 -> 2.6-3.1 %); with the trunk-only offsets they made seed 4 worse (its
#: measured hips lay 12-31 mm low on five subjects: thighs 3.9 -> 4.5 %). The elbows joined them in round 2
#: session 26, once each lay at the arm's proportion (:func:`bsv.frontend.landmarks.elbows_at_proportion`,
#: session 24) and a gross one-view landmark was caught (session 18): over the 80 subjects of seeds 0-7 the
#: upper arms' mean RVE 1.81-2.08 -> 1.64-1.85 %, the forearms' 2.03-2.45 -> 1.94-2.10 %, the elbow loop's sd
#: 3.4-4.3 -> 2.9-3.8 mm, the eight limbs' mean 2.01 / 2.03 -> 1.93 / 1.95 % (noer / l515; with the wrist
#: lines moved, :data:`bsv.frontend.segment.DEFAULT_PARAMS`).
#: Before that, where one view's elbow cut lay 5 cm up the arm (seed 6 subject 9) the elbow's pull against
#: the mislabelled points collapsed the forearm (-11 -> -40 %); it now reads -3.6 to -4.8 %. Left out: the
#: knees (their vertical error, sd 11-13 mm, exceeds the 2-D labels' knee loop's; the shins got worse on
#: every try, last in session 25). The thighs' loops (``hip_loop``, :data:`BOUNDARY_RINGS`) joined in round 2
#: session 38, each pulled to the height the crotch in the depth images gives (:mod:`bsv.frontend.groin`): held
#: out (room seeds 20-21) the hip loop's sd 4.4-5.5 -> 3.5-4.5 mm, the thighs 1.62-2.25 -> 1.20-1.82 %, the
#: torso 0.97-1.20 -> 0.64-0.79 % (benchmarks/BENCH.md).
CAMERA_KEYPOINT_KINDS: tuple[str, ...] = ("shoulder", "elbow", "wrist", "hip", "hip_loop")


def select_joints(joints: Mapping[str, Any], kinds: Sequence[str] | None) -> dict[str, Any]:
    """The entries of ``joints`` whose kind (the name without ``_l`` / ``_r``) is in ``kinds``
    (all of them when ``kinds`` is None)."""
    return {k: v for k, v in joints.items() if kinds is None or k.rsplit("_", 1)[0] in kinds}


def camera_joints(joints: Mapping[str, Any] | None, which: bool | None,
                  kinds: Sequence[str] | None = None) -> dict[str, Any] | None:
    """The measured joints that pull the template on the camera path (``bsv process``, ``bench synth``):
    ``which`` None (the default) the :data:`CAMERA_KEYPOINT_KINDS`, True every joint, False none (None is
    returned); ``kinds``, when given, overrides the choice of kinds. None also without ``joints``."""
    if not joints or which is False:
        return None
    keep = list(kinds) if kinds else None if which else list(CAMERA_KEYPOINT_KINDS)
    return select_joints(joints, keep)


#: Default of :func:`confine_upper_arms`: an upper-arm point farther than this (m) from the measured
#: shoulder-elbow segment is torso. The 99th percentile of the true upper-arm points' distances from
#: that segment (joints as measured) is 64-96 mm on the synthetic cohort (seeds 0, 2, 6); the torso patch
#: a hanging arm's view mislabels lies mostly beyond 100 mm (median 112 mm on seed 6 subject 9).
UPPER_ARM_MAX_DISTANCE_M = 0.1


def confine_upper_arms(points: Any, labels: Any, joints: Mapping[str, Any],
                       max_distance_m: float = UPPER_ARM_MAX_DISTANCE_M) -> tuple[np.ndarray, int]:
    """Cloud labels with every upper-arm point farther than ``max_distance_m`` from its side's measured
    shoulder-elbow segment relabelled torso, and how many points changed.

    Why: the colour segmentation labels each pixel by the nearest bone in 2-D, so where a hanging arm
    covers the torso's side in one view, that view can label a large patch of torso as upper arm (seed 6
    subject 9 of the synthetic cohort: 45 % of the right upper arm's points were torso). The articulated
    initialisation and the label-aware fit then pull the template's upper arm onto the torso and its
    shoulder boundary far down the arm (-34 % upper arm). The 3-D joint centres come from both views
    together and are not fooled by one view's overlap. ``joints``: ``{name: joint}`` as
    :func:`as_keypoints` reads them (a :class:`bsv.frontend.landmarks.JointCentre`, a ``{"xyz", ...}``
    dict, ``(xyz, confidence)`` or xyz); a side without both its shoulder and elbow is left as it is.
    """
    pts = np.asarray(points, dtype=np.float64)
    lab = np.array(labels, dtype=np.uint8, copy=True)
    if pts.ndim != 2 or pts.shape[1] != 3 or len(lab) != len(pts):
        raise _bad(f"confine_upper_arms: points must be (N, 3) with N labels, got {pts.shape} and {lab.shape}")
    if not (math.isfinite(max_distance_m) and max_distance_m > 0):
        raise _bad(f"confine_upper_arms: max_distance_m must be positive, got {max_distance_m!r}")
    measured = {name: np.asarray(xyz) for name, xyz, _, _ in as_keypoints(joints)}
    torso = SEGMENT_IDS["torso"]
    changed = 0
    for side in ("l", "r"):
        a, b = measured.get(f"shoulder_{side}"), measured.get(f"elbow_{side}")
        arm = lab == SEGMENT_IDS[f"upper_arm_{side}"]
        if a is None or b is None or not arm.any():
            continue
        far = _segment_distance(pts[arm], a, b) > max_distance_m
        idx = np.nonzero(arm)[0][far]
        lab[idx] = torso
        changed += len(idx)
    return lab, changed


def confine_cloud_upper_arms(cloud: PointCloud, joints: Mapping[str, Any] | None,
                             max_distance_m: float = UPPER_ARM_MAX_DISTANCE_M) -> tuple[PointCloud, int]:
    """:func:`confine_upper_arms` on a labelled cloud: the cloud with its labels confined (the same
    cloud when it has no labels, no joints are given or nothing changes) and how many points changed."""
    if cloud.labels is None or not joints:
        return cloud, 0
    labels, changed = confine_upper_arms(cloud.points, cloud.labels, joints, max_distance_m)
    if changed == 0:
        return cloud, 0
    return PointCloud(cloud.points, cloud.normals, cloud.colors, labels), changed


def joint_xyz(value: Any) -> np.ndarray:
    """A joint centre's position as a float (3,) array: a :class:`bsv.frontend.landmarks.JointCentre`'s (or any
    object's) ``xyz``, or the value itself."""
    return np.asarray(getattr(value, "xyz", value), dtype=np.float64).reshape(3)


def _segment_distance(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distance of each point of ``p`` (N, 3) from the segment ``a``-``b`` (a point when they coincide)."""
    ab = b - a
    den = float(ab @ ab)
    t = np.zeros(len(p)) if den == 0.0 else np.clip((p - a) @ ab / den, 0.0, 1.0)
    return np.asarray(np.linalg.norm(p - (a + t[:, None] * ab), axis=1))


__all__ = ["BOUNDARY_RINGS", "CAMERA_KEYPOINT_KINDS", "JOINT_NAMES", "UPPER_ARM_MAX_DISTANCE_M", "as_keypoints", "boundary_rings", "camera_joints", "confine_cloud_upper_arms", "confine_upper_arms", "joint_rings", "joint_xyz", "select_joints", "template_kind"]

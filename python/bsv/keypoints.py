"""Measured joint centres for the registration's keypoint term (``bsv.register(..., keypoints=...)``)
and the template joints they pull (the joint rings the embedded templates carry, see
:mod:`bsv.bodies.template_joints` and ``bsv_register::Keypoints``)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from functools import lru_cache
from typing import Any

import numpy as np

from . import _bsv
from .errors import InputError
from .types import Mesh

#: Every joint a template may carry (the names of :data:`bsv.frontend.landmarks.JOINTS`).
JOINT_NAMES: tuple[str, ...] = tuple(f"{j}_{s}" for s in ("l", "r")
                                     for j in ("shoulder", "elbow", "wrist", "hip", "knee", "ankle"))

#: Kinds of the embedded templates that carry joint rings, by vertex count.
_KIND_BY_VERTICES = {4177: "default", 16702: "fine", 13380: "full"}


@lru_cache(maxsize=2)
def _embedded_vertices(full: bool) -> np.ndarray:
    return np.asarray(_bsv.default_template(full)[0])


def template_kind(mesh: Mesh) -> str | None:
    """"default", "fine" or "full" when ``mesh`` is that embedded template (its vertices, in its order,
    before any fit), else None."""
    kind = _KIND_BY_VERTICES.get(len(mesh.vertices))
    if kind is None:
        return None
    ref = _embedded_vertices(kind == "full")
    head = np.asarray(mesh.vertices[: len(ref)])
    return kind if np.array_equal(head, ref) else None


def joint_rings(mesh: Mesh) -> list[tuple[str, list[int], list[float]]] | None:
    """The joint rings of an embedded template as ``(name, vertices, weights)``, or None for any other mesh."""
    kind = template_kind(mesh)
    if kind is None:
        return None
    return [(name, list(v), list(w)) for name, v, w, _ in _bsv.template_joints(kind)]


def _bad(message: str) -> InputError:
    e = InputError(message)
    e.argument = "keypoints"
    return e


def _one(name: str, value: Any) -> tuple[str, list[float], float]:
    """``(name, xyz, confidence)`` of one measured joint: a :class:`bsv.frontend.landmarks.JointCentre`,
    a ``{"xyz", "confidence"}`` dict (the volumes JSON's ``joints_m`` entry), ``(xyz, confidence)`` or xyz."""
    if hasattr(value, "xyz"):
        xyz, conf = value.xyz, getattr(value, "confidence", 1.0)
    elif isinstance(value, Mapping):
        if "xyz" not in value:
            raise _bad(f"keypoints[{name!r}]: a dict needs an 'xyz' entry (and optionally 'confidence')")
        xyz, conf = value["xyz"], value.get("confidence", 1.0)
    elif isinstance(value, tuple) and len(value) == 2 and np.ndim(value[0]) == 1:
        xyz, conf = value
    else:
        xyz, conf = value, 1.0
    try:
        p = np.asarray(xyz, dtype=np.float64).reshape(-1)
        c = float(conf)
    except (TypeError, ValueError) as e:
        raise _bad(f"keypoints[{name!r}]: expected 3 coordinates (metres) and a confidence, got {value!r}") from e
    if p.shape != (3,) or not np.isfinite(p).all():
        raise _bad(f"keypoints[{name!r}]: expected 3 finite coordinates in metres, got {xyz!r}")
    if not (math.isfinite(c) and 0.0 <= c <= 1.0):
        raise _bad(f"keypoints[{name!r}]: confidence must be in [0, 1], got {conf!r}")
    return str(name), [float(x) for x in p], c


def as_keypoints(keypoints: Mapping[str, Any]) -> list[tuple[str, list[float], float]]:
    """The measured joints of a ``{name: joint}`` mapping as ``(name, xyz, confidence)`` tuples."""
    if not isinstance(keypoints, Mapping):
        raise _bad(f"keypoints must be a dict {{joint name: position}}, got {type(keypoints).__name__}")
    return [_one(name, value) for name, value in keypoints.items()]


__all__ = ["JOINT_NAMES", "as_keypoints", "joint_rings", "template_kind"]

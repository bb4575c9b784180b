"""Bodies off the template's beaten track: reshaped and swollen limb segments, free-form surface bumps.

The registration's hard cases (issue 10): a limb segment much deeper front-to-back or narrower than the
template's (MakeHuman's own ``*-scale-depth`` targets reach only about +10 % of an upper arm's volume at
their maximum, so the shape is also set geometrically), one segment swollen by up to ~45 % (lymphoedema),
and bumps of 6-15 mm anywhere on the surface. Every variant moves the vertices of a posed :class:`Body`
and keeps its faces and labels, so the ground truth is the deformed body's own segment volumes
(:meth:`Body.volumes_l`). Deformations fade to zero at the segment's boundary loops over ``blend``
metres, so the surface stays smooth and the neighbouring segments are untouched.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from ..errors import PhenotypeError
from ..types import SEGMENT_IDS
from .body import Body, make_body
from .cohort import (
    ARM_DOWN_RANGE_DEG,
    ELBOW_RANGE_DEG,
    HIP_ABDUCTION_RANGE_DEG,
    PALM_IN_RANGE_DEG,
    TURN_RANGE_DEG,
    Subject,
    subject,
)
from .collide import penetrations

#: The limb segments a variant may reshape or swell.
LIMB_SEGMENTS: tuple[str, ...] = ("upper_arm_l", "upper_arm_r", "forearm_l", "forearm_r",
                                  "thigh_l", "thigh_r", "shin_l", "shin_r")


@dataclass(frozen=True)
class SegmentShape:
    """A change of one limb segment's cross-section about its own axis.

    ``depth`` scales the cross-section along the world front-back axis (z, made perpendicular to the
    segment's axis), ``width`` along the third axis; a swelling is ``depth = width``. Factors > 0."""

    segment: str
    depth: float = 1.0
    width: float = 1.0

    def check(self) -> None:
        """Raise PhenotypeError on an unknown segment or a non-positive factor."""
        if self.segment not in LIMB_SEGMENTS:
            raise PhenotypeError(f"segment {self.segment!r}: use one of {', '.join(LIMB_SEGMENTS)}")
        for name, f in (("depth", self.depth), ("width", self.width)):
            if not (np.isfinite(f) and 0.2 <= f <= 3.0):
                raise PhenotypeError(f"{self.segment} {name} factor {f}: use a value in [0.2, 3]")


def _boundary_weight(body: Body, seg: int, blend: float) -> tuple[np.ndarray, np.ndarray]:
    """(vertex ids of the segment, weight in [0, 1]): 0 on its boundary loops, 1 beyond ``blend`` metres."""
    ids = np.flatnonzero(body.vertex_labels == seg)
    inside = body.vertex_labels[body.faces] == seg
    mixed = body.faces[inside.any(axis=1) & ~inside.all(axis=1)]
    boundary = np.unique(mixed[body.vertex_labels[mixed] == seg])
    if len(boundary) == 0:
        return ids, np.ones(len(ids))
    p, b = body.vertices[ids], body.vertices[boundary]
    d = np.full(len(ids), np.inf)
    for s in range(0, len(b), 256):
        d = np.minimum(d, np.linalg.norm(p[:, None, :] - b[None, s:s + 256, :], axis=2).min(axis=1))
    t = np.clip(d / blend, 0.0, 1.0)
    return ids, t * t * (3.0 - 2.0 * t)


def reshape_segment(body: Body, shape: SegmentShape, blend: float = 0.04) -> Body:
    """The body with one limb segment's cross-section scaled (see :class:`SegmentShape`)."""
    shape.check()
    seg = SEGMENT_IDS[shape.segment]
    ids, w = _boundary_weight(body, seg, blend)
    p = body.vertices[ids]
    c = p.mean(axis=0)
    axis = np.linalg.svd(p - c, full_matrices=False)[2][0]
    depth = np.array([0.0, 0.0, 1.0]) - axis[2] * axis
    depth /= np.linalg.norm(depth)
    width = np.cross(axis, depth)
    r = p - c
    a = r @ axis
    # the cross-section's own centre at each height along the axis (a bent or tapered limb is not a
    # cylinder about the mean axis): a running mean of the vertices in 1 cm slices
    bins = np.floor((a - a.min()) / 0.01).astype(int)
    cnt = np.bincount(bins)
    centre = np.stack([np.bincount(bins, weights=r[:, k]) for k in range(3)], 1) / np.maximum(cnt, 1)[:, None]
    q = r - centre[bins]
    qd, qw = q @ depth, q @ width
    moved = r + ((w * (shape.depth - 1.0) * qd)[:, None] * depth + (w * (shape.width - 1.0) * qw)[:, None] * width)
    v = body.vertices.copy()
    v[ids] = c + moved
    return replace(body, vertices=v)


def _vertex_normals(v: np.ndarray, f: np.ndarray) -> np.ndarray:
    fn = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    n = np.zeros_like(v)
    for k in range(3):
        np.add.at(n, f[:, k], fn)
    return n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)


def add_bumps(body: Body, rng: np.random.Generator, count: int = 12, amplitude_m: tuple[float, float] = (0.006, 0.015),
              radius_m: tuple[float, float] = (0.03, 0.08)) -> Body:
    """The body with ``count`` Gaussian bumps (random sign, amplitude and radius) pushed along the
    surface normals of the trunk and limbs: the free-form departures no MakeHuman target makes."""
    v = body.vertices
    n = _vertex_normals(v, body.faces)
    measured = np.flatnonzero(np.isin(body.vertex_labels, [SEGMENT_IDS[s] for s in ("torso", *LIMB_SEGMENTS)]))
    offset = np.zeros(len(v))
    for _ in range(count):
        centre = v[measured[rng.integers(len(measured))]]
        amp = rng.uniform(*amplitude_m) * (1.0 if rng.random() < 0.5 else -1.0)
        rad = rng.uniform(*radius_m)
        d2 = ((v - centre) ** 2).sum(axis=1)
        offset += amp * np.exp(-0.5 * d2 / rad ** 2)
    return replace(body, vertices=v + offset[:, None] * n)




#: The hard classes of :func:`hard_subject`, in the order subject indices cycle through them.
HARD_CLASSES: tuple[str, ...] = ("deep_upper_arms", "bumps", "swollen", "extreme_modifiers")


def _first_clean(body: Body, make: Callable[[float], Body]) -> tuple[Body, float]:
    """``make(t)`` for the largest t in 1, 0.8, ... 0.2 whose body does not self-intersect."""
    for t in (1.0, 0.8, 0.6, 0.4, 0.2):
        b = make(t)
        if not penetrations(b.vertices, b.faces, b.face_labels):
            return b, t
    return body, 0.0


def hard_subject(index: int, seed: int = 0, local: bool = True,
                 arm_range: tuple[float, float] = ARM_DOWN_RANGE_DEG,
                 leg_range: tuple[float, float] = HIP_ABDUCTION_RANGE_DEG, bmi_shift: float = 0.0,
                 macros: str = "standard", palm_range: tuple[float, float] = PALM_IN_RANGE_DEG,
                 turn_range: tuple[float, float] = TURN_RANGE_DEG,
                 elbow_range: tuple[float, float] = ELBOW_RANGE_DEG) -> Subject:
    """Cohort subject ``index`` of ``seed`` reshaped into one of the registration's hard classes
    (:data:`HARD_CLASSES`, cycling with the index; deterministic): both upper arms 1.3-1.6x deeper
    front-to-back and 0.75-0.9x narrower; 12 bumps of 6-15 mm; one limb segment swollen by
    ~20-45 %; MakeHuman's segment scale targets (depth and width of every limb segment) at
    0.6-1.0 of their range. A change that would make a limb cut into another segment is scaled down
    (``variant["strength"]`` < 1). The truth is the changed body's own volumes. ``arm_range`` and the rest:
    the base subject's (:func:`bsv.bodies.subject`; a bad range is its PoseError)."""
    base = subject(index, seed, local=local, arm_range=arm_range, leg_range=leg_range, bmi_shift=bmi_shift,
                   macros=macros, palm_range=palm_range, turn_range=turn_range, elbow_range=elbow_range)
    rng = np.random.default_rng([int(seed), int(index), 10])
    kind = HARD_CLASSES[index % len(HARD_CLASSES)]
    variant: dict[str, Any] = {"class": kind}
    body = base.body
    if kind == "deep_upper_arms":
        d, w = float(rng.uniform(1.3, 1.6)), float(rng.uniform(0.75, 0.9))
        variant.update(depth=round(d, 3), width=round(w, 3))

        def deep(t: float) -> Body:
            b = body
            for s in ("upper_arm_l", "upper_arm_r"):
                b = reshape_segment(b, SegmentShape(s, 1 + t * (d - 1), 1 + t * (w - 1)))
            return b

        body, variant["strength"] = _first_clean(body, deep)
    elif kind == "bumps":
        body = add_bumps(body, rng)
        variant["count"] = 12
    elif kind == "swollen":
        seg = LIMB_SEGMENTS[int(rng.integers(len(LIMB_SEGMENTS)))]
        f = float(rng.uniform(1.1, 1.22))
        variant.update(segment=seg, factor=round(f, 3))
        body, variant["strength"] = _first_clean(
            body, lambda t: reshape_segment(body, SegmentShape(seg, 1 + t * (f - 1), 1 + t * (f - 1))))
    else:
        mods: dict[str, float] = {}
        for side in ("l", "r"):
            for group, part in (("arms", "upperarm"), ("arms", "lowerarm"), ("legs", "upperleg"), ("legs", "lowerleg")):
                for k in ("scale-depth", "scale-horiz"):
                    mods[f"{group}/{side}-{part}-{k}"] = round(float(rng.choice([-1, 1]) * rng.uniform(0.6, 1.0)), 3)
        variant["modifiers"] = mods
        ph = base.phenotype.with_(local={**base.phenotype.local, **mods})
        body, variant["strength"] = _first_clean(body, lambda t: make_body(
            ph.with_(local={**base.phenotype.local, **{k: v * t for k, v in mods.items()}}), base.pose))
    return replace(base, body=body, variant=variant)


__all__ = ["HARD_CLASSES", "LIMB_SEGMENTS", "SegmentShape", "add_bumps", "hard_subject", "reshape_segment"]

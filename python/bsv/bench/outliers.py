"""Room outliers injected into a synthetic cloud: what survives cloud cleaning in a real room.

A real capture sees the floor around the feet and a wall behind the subject, and a person mask spills
a few percent of its pixels onto them (DESIGN.md, facts from round 2: 3.5-4.3 % of the mask, labelled
like the nearest limb). The virtual rig has an empty background, so :func:`inject` adds them to a
labelled cloud (the trunk and limbs a lab registers), per subject and reproducibly:

- ``floor``: dense floor patches (6 discs of 4 cm radius) at y ~ 0 (2 mm noise) around and between
  the feet, 5-30 cm from the shins, labelled ``shin_l`` / ``shin_r`` by side; 1.5 % of the cloud's points.
- ``wall``: a sliver on a wall 0.3-1 m behind the body (depth drawn per subject), where the front
  camera's rays through the outline of the torso and the upper arms land, 0-3 cm outward of it,
  labelled like the outline point; 1.5 %.
- ``mixed``: mixed pixels scattered along those rays between the outline and the wall, labelled like
  the outline point; 0.5 %.

The bench reads the request from the registration parameters (``--param bench_outliers=floor,wall,mixed``
or ``all``); :func:`split_request` removes that key before the parameters reach :func:`bsv.register`,
and it stays in the run's recorded configuration.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
import numpy.typing as npt

from ..errors import BenchError
from ..types import SEGMENT_IDS, PointCloud

#: The registration-parameter key that requests an injection (removed before registering).
PARAM_KEY = "bench_outliers"
#: The kinds of outliers, in injection order.
KINDS: tuple[str, ...] = ("floor", "wall", "mixed")
#: Fraction of the cloud's point count added per kind.
FRACTIONS: dict[str, float] = {"floor": 0.015, "wall": 0.015, "mixed": 0.005}
#: The front camera's centre (DESIGN.md rig: 1.0 m high, 2.0 m in front of the subject).
FRONT_CAMERA = np.array([0.0, 1.0, 2.0])
#: Floor blobs per subject and their radius: 1.5 % of a 120k-point cloud on ~0.03 m^2 is about the
#: density a camera 1 m high and 2 m away samples the floor with (~60k points / m^2).
BLOBS = 6
BLOB_RADIUS_M = 0.04

FloatArray = npt.NDArray[np.float64]


def split_request(params: Mapping[str, Any] | None) -> tuple[tuple[str, ...], dict[str, Any]]:
    """The outlier kinds requested by ``params[PARAM_KEY]`` and the parameters without that key."""
    rest = dict(params or {})
    text = rest.pop(PARAM_KEY, None)
    if text is None or text == "" or text == "none":
        return (), rest
    items = KINDS if text == "all" else tuple(k.strip() for k in str(text).split(",") if k.strip())
    bad = [k for k in items if k not in KINDS]
    if bad:
        raise BenchError(f"{PARAM_KEY}={text}: use a comma list of {','.join(KINDS)} or all")
    return items, rest


def inject(cloud: PointCloud, kinds: tuple[str, ...], seed: int) -> PointCloud:
    """``cloud`` (labelled, metres, y up, subject facing +z) with the requested outliers appended."""
    if not kinds:
        return cloud
    if cloud.labels is None:
        raise BenchError("outlier injection needs a labelled cloud")
    rng = np.random.default_rng([int(seed), 11])
    wall_z = float(cloud.points[:, 2].min() - rng.uniform(0.3, 1.0))  # per subject: 0.3-1 m behind the back
    n = len(cloud)
    pts: list[FloatArray] = [cloud.points]
    labs: list[npt.NDArray[np.uint8]] = [np.asarray(cloud.labels, dtype=np.uint8)]
    for kind in KINDS:
        if kind not in kinds:
            continue
        count = round(FRACTIONS[kind] * n)
        if kind == "floor":
            p, lab = floor_patch(cloud.points, cloud.labels, count, rng)
        else:
            p, lab = wall_and_mixed(cloud.points, cloud.labels, count, rng, wall_z, mixed=kind == "mixed")
        pts.append(p)
        labs.append(lab)
    normals = None
    if cloud.normals is not None:  # outliers carry the normals a depth camera would estimate there
        extra = np.concatenate(pts[1:]) if len(pts) > 1 else np.zeros((0, 3))
        normals = np.concatenate([cloud.normals, _fake_normals(extra)])
    return PointCloud(np.concatenate(pts), normals, None, np.concatenate(labs))


def _fake_normals(p: FloatArray) -> FloatArray:
    """Unit normals toward the front camera (the best a camera's normal estimate can say there)."""
    d = FRONT_CAMERA - p
    return np.asarray(d / np.maximum(np.linalg.norm(d, axis=1, keepdims=True), 1e-12))


def floor_patch(points: FloatArray, labels: Any, count: int, rng: np.random.Generator
                ) -> tuple[FloatArray, npt.NDArray[np.uint8]]:
    """``count`` floor points (y ~ 0) around and between the feet, 5-30 cm from the shins."""
    from scipy.spatial import cKDTree

    shins = np.isin(labels, [SEGMENT_IDS["shin_l"], SEGMENT_IDS["shin_r"]])
    if not shins.any():
        return np.zeros((0, 3)), np.zeros(0, np.uint8)
    sp = points[shins]
    low = sp[sp[:, 1] < sp[:, 1].min() + 0.05]  # the ankles
    lo, hi = low.min(0), low.max(0)
    tree = cKDTree(sp)
    # Blob centres 5-30 cm from the shins (rejection sampling in the box around the ankles), then a
    # dense disc of floor points around each (a spill of the mask is a blob of pixels, not a spray).
    centres = np.zeros((0, 3))
    for _ in range(50):
        c = np.column_stack([rng.uniform(lo[0] - 0.15, hi[0] + 0.15, 64), np.zeros(64),
                             rng.uniform(lo[2] - 0.10, hi[2] + 0.25, 64)])
        d, _ = tree.query(c)
        centres = np.concatenate([centres, c[(d > 0.05 + BLOB_RADIUS_M) & (d < 0.30 - BLOB_RADIUS_M)]])
        if len(centres) >= BLOBS:
            break
    if len(centres) == 0:
        return np.zeros((0, 3)), np.zeros(0, np.uint8)
    centres = centres[:BLOBS]
    k = rng.integers(0, len(centres), count)
    r = BLOB_RADIUS_M * np.sqrt(rng.uniform(0.0, 1.0, count))
    a = rng.uniform(0.0, 2.0 * np.pi, count)
    out = centres[k] + np.column_stack([r * np.cos(a), rng.normal(0.0, 0.002, count), r * np.sin(a)])
    out = out[:count]
    mid = 0.5 * (lo[0] + hi[0])
    lab = np.where(out[:, 0] > mid, SEGMENT_IDS["shin_l"], SEGMENT_IDS["shin_r"]).astype(np.uint8)
    return out, lab


def outline(points: FloatArray, labels: Any, bin_m: float = 0.01) -> tuple[FloatArray, npt.NDArray[np.uint8], FloatArray]:
    """The outermost points (seen from the front) of the torso and the upper arms per height bin of
    ``bin_m``: (points, labels, outward x direction +-1)."""
    ids = {"torso": SEGMENT_IDS["torso"], "upper_arm_l": SEGMENT_IDS["upper_arm_l"],
           "upper_arm_r": SEGMENT_IDS["upper_arm_r"]}
    sides = {"torso": (1.0, -1.0), "upper_arm_l": (1.0,), "upper_arm_r": (-1.0,)}
    out_p, out_l, out_s = [], [], []
    for name, lid in ids.items():
        p = points[labels == lid]
        if len(p) == 0:
            continue
        b = np.floor(p[:, 1] / bin_m).astype(np.int64)
        for s in sides[name]:
            order = np.lexsort((-s * p[:, 0], b))  # per bin, the outermost first
            first = np.ones(len(order), bool)
            first[1:] = b[order][1:] != b[order][:-1]
            sel = p[order[first]]
            out_p.append(sel)
            out_l.append(np.full(len(sel), lid, np.uint8))
            out_s.append(np.full(len(sel), s))
    if not out_p:
        return np.zeros((0, 3)), np.zeros(0, np.uint8), np.zeros(0)
    return np.concatenate(out_p), np.concatenate(out_l), np.concatenate(out_s)


def wall_and_mixed(points: FloatArray, labels: Any, count: int, rng: np.random.Generator, wall_z: float,
                   mixed: bool) -> tuple[FloatArray, npt.NDArray[np.uint8]]:
    """``count`` points on the wall plane z = ``wall_z`` where the front camera's rays through the outline
    land (``mixed`` False), or mixed pixels along those rays between the outline and the wall (True)."""
    op, ol, os_ = outline(points, labels)
    if len(op) == 0 or count == 0:
        return np.zeros((0, 3)), np.zeros(0, np.uint8)
    k = rng.integers(0, len(op), count)
    p, s = op[k], os_[k]
    ray = p - FRONT_CAMERA
    t = (wall_z - FRONT_CAMERA[2]) / ray[:, 2]
    wall = FRONT_CAMERA + t[:, None] * ray
    wall[:, 0] += s * rng.uniform(0.0, 0.03, count)  # the spill band, outward of the outline
    wall[:, 1] += rng.uniform(-0.005, 0.005, count)
    if not mixed:
        return wall, ol[k]
    f = rng.uniform(0.05, 0.95, count)[:, None]
    return p + f * (wall - p), ol[k]

"""Self-intersection checks between body segments (vectorised generalised winding numbers, numpy)."""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np

from ..types import SEGMENT_IDS
from .labels import boundary_loops

#: Pairs (moving part, body part) checked by default: arms against the torso and the thighs, thighs together.
DEFAULT_PAIRS = (
    ("upper_arm_l", "torso"), ("upper_arm_r", "torso"), ("forearm_l", "torso"), ("forearm_r", "torso"),
    ("hand_l", "torso"), ("hand_r", "torso"), ("hand_l", "thigh_l"), ("hand_r", "thigh_r"),
    ("forearm_l", "thigh_l"), ("forearm_r", "thigh_r"), ("thigh_l", "thigh_r"),
)


def closed_segment(vertices: np.ndarray, faces: np.ndarray, face_labels: np.ndarray,
                   seg: int) -> tuple[np.ndarray, np.ndarray]:
    """The closed surface of one segment: its faces plus a centroid fan on each boundary loop."""
    f = faces[face_labels == seg]
    v = vertices
    extra_v, extra_f = [], []
    n = len(v)
    for s, t, ed in boundary_loops(faces, face_labels):
        if seg not in (s, t):
            continue
        e = ed if s == seg else ed[:, ::-1]
        c = v[np.unique(e)].mean(axis=0)
        extra_v.append(c)
        extra_f.append(np.stack([e[:, 1], e[:, 0], np.full(len(e), n)], 1))
        n += 1
    if extra_v:
        v = np.concatenate([v, np.array(extra_v)])
        f = np.concatenate([f, *extra_f])
    return v, f


def winding_numbers(points: np.ndarray, vertices: np.ndarray, faces: np.ndarray, chunk: int = 64) -> np.ndarray:
    """Generalised winding number of each point w.r.t. a closed outward mesh (1 inside, 0 outside)."""
    out = np.zeros(len(points))
    tri = vertices[faces]
    for s in range(0, len(points), chunk):
        p = points[s:s + chunk, None, None, :]
        a, b, c = (tri[None, :, k, :] - p[:, :, 0, :] for k in range(3))
        la, lb, lc = (np.linalg.norm(x, axis=-1) for x in (a, b, c))
        det = np.einsum("ptk,ptk->pt", a, np.cross(b, c))
        den = (la * lb * lc + np.einsum("ptk,ptk->pt", a, b) * lc + np.einsum("ptk,ptk->pt", b, c) * la
               + np.einsum("ptk,ptk->pt", c, a) * lb)
        out[s:s + chunk] = 2.0 * np.arctan2(det, den).sum(axis=1) / (4.0 * np.pi)
    return out


def penetrations(vertices: np.ndarray, faces: np.ndarray, face_labels: np.ndarray,
                 pairs: Iterable[tuple[str, str]] = DEFAULT_PAIRS, margin: float = 0.03,
                 max_points: int = 400) -> dict[str, int]:
    """Number of (sampled) vertices of the first segment inside the closed second one, per pair.

    Vertices of the first segment within ``margin`` metres of a shared boundary are skipped (a joint's
    crease is not a collision). Returns only the pairs with penetrating vertices ({} = no contact)."""
    res = {}
    present = set(np.unique(face_labels).tolist())
    for a_name, b_name in pairs:
        a, b = SEGMENT_IDS[a_name], SEGMENT_IDS[b_name]
        if a not in present or b not in present:
            continue
        va = np.unique(faces[face_labels == a])
        vb_set = np.unique(faces[face_labels == b])
        va = np.setdiff1d(va, vb_set)
        shared = np.intersect1d(np.unique(faces[face_labels == a]), vb_set)
        pts = vertices[va]
        if len(shared):
            d = np.min(np.linalg.norm(pts[:, None, :] - vertices[shared][None, :, :], axis=2), axis=1)
            pts = pts[d > margin]
        if len(pts) > max_points:
            pts = pts[np.linspace(0, len(pts) - 1, max_points).astype(int)]
        cv, cf = closed_segment(vertices, faces, face_labels, b)
        lo, hi = cv[np.unique(cf)].min(axis=0) - 1e-9, cv[np.unique(cf)].max(axis=0) + 1e-9
        pts = pts[np.all((pts >= lo) & (pts <= hi), axis=1)]
        if len(pts) == 0:
            continue
        inside = int((winding_numbers(pts, cv, cf) > 0.5).sum())
        if inside:
            res[f"{a_name}/{b_name}"] = inside
    return res

"""Segment labels from skinning weights, the segment boundaries, and segment volumes (from Rust).

Every vertex belongs to the segment whose bones weigh most on it; a face to the segment with the
largest summed weight over its corners; small islands are merged into their surroundings so each
segment is one patch. Segment volumes are the Rust ones (``bsv_volume``: each boundary loop capped by
a fan shared with the neighbour, so they add up to the whole); vertex labels from face labels use
Rust's one rule.
"""

from __future__ import annotations

import re

import numpy as np

from .. import _bsv
from ..types import PALETTE as _PALETTE
from ..types import SEGMENT_IDS, SEGMENT_NAMES
from .asset import Asset, load_asset

#: Palette colours (sRGB) per segment id: Rust's ``bsv_core::PALETTE`` (what the Rust writers put in PLY
#: files); used by the report figures.
PALETTE = _PALETTE


def bone_segment(name: str) -> int:
    """Segment id of a MakeHuman default-rig bone (neck with head; clavicles, shoulders with torso)."""
    side = None
    if name.endswith(".L"):
        side = "l"
    elif name.endswith(".R"):
        side = "r"
    stem = name[:-2] if side else name
    sided = {"upperarm": "upper_arm", "lowerarm": "forearm", "wrist": "hand", "metacarpal": "hand",
             "finger": "hand", "upperleg": "thigh", "lowerleg": "shin", "foot": "foot", "toe": "foot"}
    for prefix, seg in sided.items():
        if stem.startswith(prefix) and side:
            return SEGMENT_IDS[f"{seg}_{side}"]
    if re.match(r"^(root|spine\d+|pelvis|breast|clavicle|shoulder\d+)", stem):
        return SEGMENT_IDS["torso"]
    return SEGMENT_IDS["head"]  # head, neck, jaw, eyes, tongue and the facial bones


def segment_weights(asset: Asset | None = None) -> np.ndarray:
    """(N, 15) summed skinning weight of each segment per vertex."""
    a = asset or load_asset()
    seg_of_bone = np.array([bone_segment(n) for n in a.bone_names])
    n = len(a.vertices)
    w = np.zeros((n, 15))
    np.add.at(w, (a.skin_vertex, seg_of_bone[a.skin_bone]), a.skin_weight)
    return w


def edge_faces(faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Face-adjacency pairs (E, 2) over interior edges of a closed manifold mesh, and the edges (E, 2)."""
    nf = len(faces)
    e = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    fid = np.tile(np.arange(nf), 3)
    key = np.sort(e, axis=1)
    order = np.lexsort((key[:, 1], key[:, 0]))
    key, fid = key[order], fid[order]
    same = np.all(key[1:] == key[:-1], axis=1)
    i = np.nonzero(same)[0]
    return np.stack([fid[i], fid[i + 1]], 1), key[i]


def _components(n: int, pairs: np.ndarray) -> np.ndarray:
    """Connected component id of n nodes given undirected pairs (union-find, vectorised passes)."""
    comp = np.arange(n)
    if len(pairs) == 0:
        return comp
    while True:
        a, b = comp[pairs[:, 0]], comp[pairs[:, 1]]
        m = np.minimum(a, b)
        new = comp.copy()
        np.minimum.at(new, pairs[:, 0], m)
        np.minimum.at(new, pairs[:, 1], m)
        new = new[new]
        if np.array_equal(new, comp):
            return comp
        comp = new


def clean_islands(faces: np.ndarray, labels: np.ndarray, max_iter: int = 20) -> np.ndarray:
    """Relabel every face island that is not its label's largest patch to its most common neighbour label."""
    labels = labels.copy()
    adj, _ = edge_faces(faces)
    for _ in range(max_iter):
        same = labels[adj[:, 0]] == labels[adj[:, 1]]
        comp = _components(len(faces), adj[same])
        size = np.bincount(comp, minlength=len(faces))
        # largest component of each label
        keep = np.zeros(len(faces), bool)
        for lab in np.unique(labels):
            idx = np.nonzero(labels == lab)[0]
            cs = comp[idx]
            best = cs[np.argmax(size[cs])]
            keep[comp == best] = True
        if keep.all():
            return labels
        # move stray faces to the label of a neighbour that is kept (majority over their edges)
        diff = ~same
        pa, pb = adj[diff, 0], adj[diff, 1]
        votes: dict[tuple[int, int], int] = {}
        for f, g in ((pa, pb), (pb, pa)):
            sel = ~keep[f]
            for fi, lab in zip(f[sel], labels[g[sel]], strict=True):
                votes[(int(fi), int(lab))] = votes.get((int(fi), int(lab)), 0) + 1
        best_lab: dict[int, tuple[int, int]] = {}
        for (fi, lab), c in votes.items():
            if fi not in best_lab or c > best_lab[fi][0] or (c == best_lab[fi][0] and lab < best_lab[fi][1]):
                best_lab[fi] = (c, lab)
        if not best_lab:
            break
        for fi, (_, lab) in best_lab.items():
            labels[fi] = lab
    return labels


def vertex_labels_from_faces(n: int, faces: np.ndarray, face_labels: np.ndarray) -> np.ndarray:
    """Each vertex takes the most common label of its faces (ties -> the lower id): Rust's one rule,
    ``bsv_volume::vertex_labels_from_faces``."""
    return _bsv.vertex_labels_from_faces(n, faces, face_labels)


def body_labels(faces: np.ndarray, asset: Asset | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(vertex labels, face labels) of the MakeHuman body, uint8 segment ids 1..14."""
    a = asset or load_asset()
    w = segment_weights(a)
    fl = np.argmax(w[faces].sum(axis=1), axis=1)
    fl = clean_islands(faces, fl)
    vl = vertex_labels_from_faces(len(w), faces, fl)
    return vl, fl.astype(np.uint8)


def boundary_loops(faces: np.ndarray, face_labels: np.ndarray) -> list[tuple[int, int, np.ndarray]]:
    """Directed boundary edges between segments: list of (s, t, edges (k, 2)) for each connected
    s|t boundary component, edges oriented as in the faces of s (so reversed they are oriented for t)."""
    e = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    lab = np.tile(face_labels, 3)
    key = np.sort(e, axis=1)
    order = np.lexsort((key[:, 1], key[:, 0]))
    ks, es, ls = key[order], e[order], lab[order]
    same = np.all(ks[1:] == ks[:-1], axis=1)
    i = np.nonzero(same)[0]
    cross = ls[i] != ls[i + 1]
    i = i[cross]
    # edge j = es[i] belongs to face of label ls[i]; its twin to ls[i+1]
    s1, s2 = ls[i], ls[i + 1]
    dir_e = es[i]
    out = []
    lo, hi = np.minimum(s1, s2), np.maximum(s1, s2)
    # orient every edge as seen from the lower label
    edges = np.where((s1 == lo)[:, None], dir_e, dir_e[:, ::-1])
    for s, t in sorted(set(zip(lo.tolist(), hi.tolist(), strict=True))):
        sel = edges[(lo == s) & (hi == t)]
        verts, inv = np.unique(sel, return_inverse=True)
        comp = _components(len(verts), inv.reshape(-1, 2))
        for c in np.unique(comp[inv[:, 0]]):
            out.append((int(s), int(t), sel[comp[inv[:, 0]] == c]))
    return out


def segment_volumes(vertices: np.ndarray, faces: np.ndarray, face_labels: np.ndarray) -> dict[int, float]:
    """Volume (m^3) of each segment present, closed by fan caps shared with its neighbours: the Rust
    segment volumes (``bsv_volume``, triple junctions included), by segment id."""
    litres = _bsv.volumes(vertices, faces, None, face_labels).volumes_l
    return {i: litres[n] / 1e3 for i, n in SEGMENT_NAMES.items() if i != 0 and n in litres}


def _tet_volumes(v: np.ndarray, f: np.ndarray, origin: np.ndarray) -> np.ndarray:
    a, b, c = v[f[:, 0]] - origin, v[f[:, 1]] - origin, v[f[:, 2]] - origin
    return np.einsum("ij,ij->i", a, np.cross(b, c)) / 6.0


def volume(vertices: np.ndarray, faces: np.ndarray) -> float:
    """Divergence-theorem volume (m^3) of a closed, outward triangle mesh (about the vertex mean).

    Kept in numpy on purpose: the stature/BMI solver evaluates it in its loop, and the cohort's
    bodies (their bytes) depend on this exact summation order."""
    v = np.asarray(vertices, dtype=np.float64)
    return float(_tet_volumes(v, faces, v.mean(axis=0)).sum())

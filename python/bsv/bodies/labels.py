"""Segment labels from skinning weights, segment closing by shared fan caps, and segment volumes (numpy).

Every vertex belongs to the segment whose bones weigh most on it; a face to the segment with the
largest summed weight over its corners; small islands are merged into their surroundings so each
segment is one patch. Closing: the boundary between segments s and t is split into connected loops;
each loop is capped by a fan to its centroid, and the same cap (with opposite orientation) closes the
neighbour, so segment volumes add up to the volume of the whole mesh exactly.
"""

from __future__ import annotations

import re

import numpy as np

from ..types import SEGMENT_IDS, SEGMENT_NAMES, TRUNK_LIMBS
from .asset import Asset, load_asset
from ..errors import LabelError

#: Palette colours (sRGB) per segment id, exactly crates/bsv-core/src/segment.rs PALETTE (what the Rust
#: writers put in PLY files); used by the PLY writer here and by the report figures.
PALETTE = np.array([
    [200, 200, 200],  # 0 unlabelled
    [255, 213, 170],  # 1 head
    [70, 130, 180],   # 2 torso
    [228, 26, 28],    # 3 upper_arm_l
    [55, 126, 184],   # 4 upper_arm_r
    [255, 127, 0],    # 5 forearm_l
    [77, 175, 74],    # 6 forearm_r
    [247, 129, 191],  # 7 hand_l
    [152, 78, 163],   # 8 hand_r
    [166, 86, 40],    # 9 thigh_l
    [27, 158, 119],   # 10 thigh_r
    [255, 255, 51],   # 11 shin_l
    [102, 194, 165],  # 12 shin_r
    [153, 153, 153],  # 13 foot_l
    [31, 120, 180],   # 14 foot_r
], dtype=np.uint8)



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
            for fi, lab in zip(f[sel], labels[g[sel]]):
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
    """Each vertex takes the most common label of its faces (ties -> the lower id)."""
    cnt = np.zeros((n, 15), dtype=np.int64)
    np.add.at(cnt, (faces.ravel(), np.repeat(face_labels, 3)), 1)
    return np.argmax(cnt, axis=1).astype(np.uint8)


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
    for s, t in sorted(set(zip(lo.tolist(), hi.tolist()))):
        sel = edges[(lo == s) & (hi == t)]
        verts, inv = np.unique(sel, return_inverse=True)
        comp = _components(len(verts), inv.reshape(-1, 2))
        for c in np.unique(comp[inv[:, 0]]):
            out.append((int(s), int(t), sel[comp[inv[:, 0]] == c]))
    return out


def check_loops(loops: list[tuple[int, int, np.ndarray]]) -> None:
    """Raise LabelError unless every boundary component is a closed cycle (in-degree = out-degree)."""
    for s, t, ed in loops:
        out_d = np.bincount(ed[:, 0], minlength=ed.max() + 1)
        in_d = np.bincount(ed[:, 1], minlength=ed.max() + 1)
        if not np.array_equal(out_d, in_d):
            raise LabelError(f"boundary between {SEGMENT_NAMES[s]} and {SEGMENT_NAMES[t]} is not a closed "
                             "loop (three segments meet at a vertex); relabel so each boundary is a loop")


def _tet_volumes(v: np.ndarray, f: np.ndarray, origin: np.ndarray) -> np.ndarray:
    a, b, c = v[f[:, 0]] - origin, v[f[:, 1]] - origin, v[f[:, 2]] - origin
    return np.einsum("ij,ij->i", a, np.cross(b, c)) / 6.0


def segment_volumes(vertices: np.ndarray, faces: np.ndarray, face_labels: np.ndarray) -> dict[int, float]:
    """Volume (m^3) of each segment present, closed by fan caps shared with its neighbours."""
    v = np.asarray(vertices, dtype=np.float64)
    origin = v.mean(axis=0)
    tv = _tet_volumes(v, faces, origin)
    vol = np.bincount(face_labels, weights=tv, minlength=15)
    loops = boundary_loops(faces, face_labels)
    check_loops(loops)
    for s, t, ed in loops:
        c = v[np.unique(ed)].mean(axis=0) - origin
        a, b = v[ed[:, 0]] - origin, v[ed[:, 1]] - origin
        # the cap closes s with triangles (b, a, c): the edge reversed, as a neighbour face would be
        cap = np.einsum("ij,ij->i", b, np.cross(a, np.broadcast_to(c, a.shape))).sum() / 6.0
        vol[s] += cap
        vol[t] -= cap
    present = np.unique(face_labels)
    return {int(k): float(vol[k]) for k in present}


def aggregates(seg_litres: dict[str, float]) -> dict[str, float]:
    """Add trunk_limbs, whole, arm_l/r, leg_l/r to a {segment name: litres} dict (absent parts skipped)."""
    out = dict(seg_litres)
    out["whole"] = float(sum(seg_litres.values()))
    if all(k in seg_litres for k in TRUNK_LIMBS):
        out["trunk_limbs"] = float(sum(seg_litres[k] for k in TRUNK_LIMBS))
    for side in ("l", "r"):
        if f"upper_arm_{side}" in seg_litres and f"forearm_{side}" in seg_litres:
            out[f"arm_{side}"] = seg_litres[f"upper_arm_{side}"] + seg_litres[f"forearm_{side}"]
        if f"thigh_{side}" in seg_litres and f"shin_{side}" in seg_litres:
            out[f"leg_{side}"] = seg_litres[f"thigh_{side}"] + seg_litres[f"shin_{side}"]
    return out


def volume(vertices: np.ndarray, faces: np.ndarray) -> float:
    """Divergence-theorem volume (m^3) of a closed, outward triangle mesh."""
    v = np.asarray(vertices, dtype=np.float64)
    return float(_tet_volumes(v, faces, v.mean(axis=0)).sum())

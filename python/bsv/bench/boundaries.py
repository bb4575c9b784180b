"""Where a fitted mesh's segment boundaries lie against the true ones: for each limb joint's boundary
loop (shoulder, elbow, hip, knee), how far the fitted loop sits from the true loop along the limb; for the
wrists and ankles, where the fitted forearms and shins end (:func:`end_errors`: the hands and feet are not
fitted, so each ends in a cap), against the true loop.

What decides a limb's volume besides its surface is where it is cut off. A run's boundary error is read
on the fitted surface itself: points are drawn on it (area-weighted, the same draw for every run), each
takes the true segment of the true body's nearest triangle (points farther than :data:`NEAR_M` from the
true surface, where the fit guessed an unseen side, are left out), and its signed distance to the fitted
loop (+ on the distal segment's side). The true loop lies at the distance that best splits the points
into the true proximal and distal segments (the fewest points on the wrong side); the error is the fitted
loop's place minus the true one, in millimetres, + = the fitted loop lies distal of the true one (the
proximal segment too long, the distal one too short). A loop's offset, not its shape: a fitted loop
tilted against the true one splits the difference.

What 1 mm along the limb is worth on the average template (its loops moved 5 mm each way): the hip 0.65 %
of a thigh, the knee 0.46 % of a shin (0.19 % of the thigh), the shoulder 1.0 % of an upper arm, the elbow
0.8 % of a forearm (0.4 % of the upper arm).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .. import _bsv
from ..biomech.tables import JOINTS
from ..types import SEGMENT_IDS, Mesh
from .common import Run, surface_samples
from .reference import ordered_conditions

#: Key of :attr:`Run.info` holding a run's boundary errors ({joint: mm, + = the fitted loop distal}).
INFO_KEY = "boundary_errors_mm"
#: The limb joints whose loops separate two measured segments, in table order.
KINDS: tuple[str, ...] = ("shoulder", "elbow", "hip", "knee")
#: Every kind a run's :data:`INFO_KEY` may hold, in table order (proximal to distal per limb): the limb joints
#: of :data:`bsv.biomech.tables.JOINTS`.
ALL_KINDS: tuple[str, ...] = tuple(dict.fromkeys(j.rsplit("_", 1)[0] for j in JOINTS if j.endswith(("_l", "_r"))))
#: The far ends of the forearms and the shins (the kinds not in :data:`KINDS`): the hands and feet are not
#: fitted, so each of these segments ends in a cap, measured by :func:`end_errors` against the true wrist or
#: ankle loop when the truth has them.
END_KINDS: tuple[str, ...] = tuple(k for k in ALL_KINDS if k not in KINDS)
#: A fitted face belongs to a segment's far cap when its normal lies within this cosine of the limb's axis ...
CAP_COS = 0.85
#: ... and its centre within this distance (metres) of the segment's farthest face along the axis.
CAP_DEPTH_M = 0.04
#: Points drawn on the fitted surface (the same draw for every run: seed 0).
SAMPLES = 200_000
#: A drawn point counts only within this distance of the true surface (metres).
NEAR_M = 0.005
#: ... and within this distance of the fitted loop (metres): the loop's neighbourhood; widened to
#: :data:`WIDE_BAND_M` when the true loop lies beyond it (every point of the band on one side).
BAND_M = 0.06
#: The widest neighbourhood searched (metres); a loop farther off than that is not measured.
WIDE_BAND_M = 0.15
#: Fewer points than this on either side of a loop: no error is given for it.
MIN_POINTS = 100
#: File name of the boundary-error figure in a benchmark's output folder.
FIGURE = "boundary_errors.png"


def _face_labels(mesh: Mesh) -> np.ndarray | None:
    """The mesh's face labels (from its vertex labels when it has no face labels); None without labels."""
    if mesh.face_labels is not None:
        return np.asarray(mesh.face_labels, dtype=np.uint8)
    if mesh.vertex_labels is None:
        return None
    return np.asarray(_bsv.face_labels_from_vertices(np.asarray(mesh.faces), mesh.vertex_labels), dtype=np.uint8)


def loop_edges(faces: np.ndarray, face_labels: np.ndarray, a: int, b: int) -> np.ndarray:
    """The edges (E, 2) shared by a face labelled ``a`` and a face labelled ``b``: their boundary loop."""
    f = np.asarray(faces, dtype=np.int64)
    e = np.sort(np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]), axis=1)
    lab = np.tile(np.asarray(face_labels), 3)
    keep = np.isin(lab, (a, b))
    e, lab = e[keep], lab[keep]
    order = np.lexsort((e[:, 1], e[:, 0]))
    e, lab = e[order], lab[order]
    shared = np.all(e[1:] == e[:-1], axis=1) & (lab[1:] != lab[:-1])
    return e[1:][shared]


def distance_to_segments(points: np.ndarray, a: np.ndarray, b: np.ndarray, chunk: int = 4096) -> np.ndarray:
    """Distance of each point (N, 3) to the nearest of the line segments ``a[k]``-``b[k]`` (K, 3)."""
    ab = b - a
    ll = np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-24)
    out = np.empty(len(points))
    for s in range(0, len(points), chunk):
        q = points[s:s + chunk, None, :] - a[None]
        t = np.clip(np.einsum("nkj,kj->nk", q, ab) / ll, 0.0, 1.0)
        out[s:s + chunk] = np.sqrt(np.min(np.sum((q - t[..., None] * ab) ** 2, axis=2), axis=1))
    return out


def best_split(h: np.ndarray, distal: np.ndarray) -> float:
    """The threshold on ``h`` (at least one value) that puts the fewest points on the wrong side
    (``distal`` ones below it, the others above it): the median of the middles of the gaps where that
    fewest is reached (beyond the ends: a tenth of the values' range, or 1e-3, past the last value)."""
    order = np.argsort(h, kind="stable")
    hs, ds = h[order], distal[order]
    pad = max(1e-3, 0.1 * float(hs[-1] - hs[0]))
    # errors if the threshold lies just below hs[j]: distal points before j + proximal points from j on
    errors = np.concatenate([[0], np.cumsum(ds)]) + np.concatenate([np.cumsum((~ds)[::-1])[::-1], [0]])
    best = np.flatnonzero(errors == errors.min())
    ext = np.concatenate([[hs[0] - pad], hs, [hs[-1] + pad]])
    return float(np.median(0.5 * (ext[best] + ext[best + 1])))


def boundary_errors(fitted: Mesh, truth: Mesh, samples: int = SAMPLES) -> dict[str, float]:
    """{joint: mm} for every limb joint of :data:`KINDS` (both sides) whose two segments both meshes have:
    the fitted loop's place along the limb minus the true loop's, + = distal (see the module notes).
    ``truth``: the true body, labelled like the fitted mesh (the same segment ids). A joint is left out when
    the fitted mesh has no loop between its segments, the truth lacks one of them, or fewer than
    :data:`MIN_POINTS` points fall on either side within :data:`WIDE_BAND_M` of the fitted loop (a loop
    that far off); empty when either mesh has no labels. A mesh that cannot be measured (a non-finite
    vertex, no area) raises a :class:`bsv.errors.BsvError`."""
    fl, tl = _face_labels(fitted), _face_labels(truth)
    if fl is None or tl is None:  # an unlabelled mesh has no boundaries
        return {}
    pts, tri = surface_samples(fitted, samples)
    dist, tface = _bsv.surface_nearest(pts, truth.vertices, truth.faces)
    own, true_lab = fl[tri], tl[np.asarray(tface, dtype=np.int64)]
    near = np.asarray(dist) < NEAR_M
    v = np.asarray(fitted.vertices, dtype=np.float64)
    out: dict[str, float] = {}
    for kind in KINDS:
        for side in ("l", "r"):
            joint = f"{kind}_{side}"
            a, b = (SEGMENT_IDS[s] for s in JOINTS[joint])
            edges = loop_edges(fitted.faces, fl, a, b)
            if len(edges) == 0 or not (np.any(tl == a) and np.any(tl == b)):
                continue
            for band in (BAND_M, WIDE_BAND_M):
                ends = v[edges.ravel()]
                lo, hi = ends.min(axis=0) - band, ends.max(axis=0) + band
                sel = (near & np.isin(own, (a, b)) & np.isin(true_lab, (a, b))
                       & np.all((pts >= lo) & (pts <= hi), axis=1))
                d = distance_to_segments(pts[sel], v[edges[:, 0]], v[edges[:, 1]])
                keep = d < band
                h = np.where(own[sel][keep] == b, d[keep], -d[keep])
                is_distal = true_lab[sel][keep] == b
                if min(int(is_distal.sum()), int((~is_distal).sum())) >= MIN_POINTS:
                    out[joint] = round(-1000.0 * best_split(h, is_distal), 2)
                    break
    return out


def _loop_centroid(v: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """The length-weighted centroid of a loop's edges (E, 2) over vertices ``v``."""
    a, b = v[edges[:, 0]], v[edges[:, 1]]
    length = np.linalg.norm(b - a, axis=1)
    return np.asarray(((a + b) / 2 * length[:, None]).sum(axis=0) / max(float(length.sum()), 1e-12))


def end_errors(fitted: Mesh, truth: Mesh) -> dict[str, float]:
    """{joint: mm} for the wrists and ankles (:data:`END_KINDS`, both sides): where the fitted forearm or shin
    ends (the centroid of its cap's rim; the cap: its faces facing along the limb, within :data:`CAP_DEPTH_M`
    of its far end) minus where the true one does (the centroid of the true wrist or ankle loop), along the true
    limb's axis (from its near loop's centroid to its far loop's), + = the fitted segment reaches farther.
    Measured only when the fitted mesh has the segment and not the hand or foot beyond it, and the truth has
    both and the loop before it; empty when either mesh has no labels. The embedded template against its own
    full body reads -1.4 mm at the wrists and +2.3 mm at the ankles (its caps' rims are not quite its loops)."""
    fl, tl = _face_labels(fitted), _face_labels(truth)
    if fl is None or tl is None:
        return {}
    vf, ff = np.asarray(fitted.vertices, dtype=np.float64), np.asarray(fitted.faces, dtype=np.int64)
    vt, ft = np.asarray(truth.vertices, dtype=np.float64), np.asarray(truth.faces, dtype=np.int64)
    out: dict[str, float] = {}
    for kind in END_KINDS:
        for side in ("l", "r"):
            joint = f"{kind}_{side}"
            seg, beyond = JOINTS[joint]
            before = next(a for a, b in JOINTS.values() if b == seg)
            p, d, o = SEGMENT_IDS[seg], SEGMENT_IDS[beyond], SEGMENT_IDS[before]
            if not np.any(fl == p) or np.any(fl == d):
                continue
            far, near = loop_edges(ft, tl, p, d), loop_edges(ft, tl, o, p)
            if len(far) == 0 or len(near) == 0:
                continue
            end = _loop_centroid(vt, far)
            axis = end - _loop_centroid(vt, near)
            axis = axis / max(float(np.linalg.norm(axis)), 1e-12)
            tri = vf[ff[fl == p]]
            cross = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
            area = np.linalg.norm(cross, axis=1)
            centre = tri.mean(axis=1)
            along = centre @ axis
            cap = ((cross @ axis) > CAP_COS * area) & (along > along.max() - CAP_DEPTH_M)
            rim = loop_edges(ff[fl == p], np.where(cap, 1, 2).astype(np.uint8), 1, 2)
            if len(rim) == 0:
                continue
            out[joint] = round(1000.0 * float((_loop_centroid(vf, rim) - end) @ axis), 2)
    return out


def _collect(runs: Sequence[Run]) -> dict[tuple[str, str], list[tuple[str, float]]]:
    """(condition, kind) -> [(subject side, mm)] of the bsv runs that measured their boundaries."""
    out: dict[tuple[str, str], list[tuple[str, float]]] = {}
    for r in runs:
        errs = (r.info or {}).get(INFO_KEY)
        if not errs or r.method != "bsv":
            continue
        for joint, e in errs.items():
            out.setdefault((r.condition, joint.rsplit("_", 1)[0]), []).append((f"{r.subject} {joint[-1]}", float(e)))
    return out


def summarise(runs: Sequence[Run]) -> dict[str, dict[str, dict[str, Any]]]:
    """{condition: {kind: {n, mean_mm, sd_mm, median_abs_mm, p95_abs_mm, worst, worst_mm}}}."""
    data = _collect(runs)
    table: dict[str, dict[str, dict[str, Any]]] = {}
    for cond in ordered_conditions({c for c, _ in data}):
        rows = {}
        for kind in ALL_KINDS:
            items = data.get((cond, kind), [])
            if not items:
                continue
            e = np.array([x for _, x in items])
            w = int(np.argmax(np.abs(e)))
            rows[kind] = {"n": len(e), "mean_mm": float(e.mean()), "sd_mm": float(e.std()),
                          "median_abs_mm": float(np.median(np.abs(e))), "p95_abs_mm": float(np.percentile(np.abs(e), 95)),
                          "worst": items[w][0], "worst_mm": float(e[w])}
        table[cond] = rows
    return table


#: The limb segment kinds whose volume error :func:`explained` splits, in table order.
LIMBS: tuple[str, ...] = ("upper_arm", "forearm", "thigh", "shin")
#: Fewest runs (subject sides) of a condition and limb for :func:`explained` to fit its line.
MIN_EXPLAINED = 8


def limb_boundaries(limb: str) -> tuple[str | None, str | None]:
    """The joint kinds of :data:`ALL_KINDS` whose loops (or, for the wrist and the ankle, the segment's far
    end: :func:`end_errors`) bound a limb segment kind: (proximal, distal), None where nothing bounds it. From
    :data:`bsv.biomech.tables.JOINTS`, the one table of which two segments each joint separates."""
    prox = next((k for k in ALL_KINDS if JOINTS[f"{k}_l"][1] == f"{limb}_l"), None)
    dist = next((k for k in ALL_KINDS if JOINTS[f"{k}_l"][0] == f"{limb}_l"), None)
    return prox, dist


def explained(runs: Sequence[Run]) -> dict[str, dict[str, dict[str, Any]]]:
    """How much of each limb's volume error is where its boundaries lie: {condition: {limb: {n, rve, signed,
    at_zero, per_mm: {joint kind: % per mm}, rve_left}}}.

    Per condition and limb kind (both sides pooled, the bsv runs whose boundaries were measured), the signed
    volume error (%) is fitted by least squares as a line in the errors (mm, + distal) of the loops that bound
    it (:func:`limb_boundaries`): ``at_zero`` is the error with both loops in place, ``per_mm`` what 1 mm of
    each loop costs, ``rve_left`` the mean absolute error the line leaves (in-sample, so slightly optimistic).
    Left out with fewer than :data:`MIN_EXPLAINED` runs. What a better boundary could gain at most is
    ``rve`` - ``rve_left``; the rest is the surface."""
    table: dict[str, dict[str, dict[str, Any]]] = {}
    rows: dict[tuple[str, str], list[tuple[float, list[float]]]] = {}
    for r in runs:
        errs = (r.info or {}).get(INFO_KEY)
        if not errs or r.method != "bsv" or not r.ok:
            continue
        for limb in LIMBS:
            kinds = [k for k in limb_boundaries(limb) if k is not None]
            for side in ("l", "r"):
                seg = f"{limb}_{side}"
                t, e = r.truth_l.get(seg), r.estimated_l.get(seg)
                mm = [errs.get(f"{k}_{side}") for k in kinds]
                if t is None or e is None or not t > 0 or any(x is None for x in mm):
                    continue
                rows.setdefault((r.condition, limb), []).append((100.0 * (e - t) / t, [float(x) for x in mm if x is not None]))
    for cond in ordered_conditions({c for c, _ in rows}):
        out: dict[str, dict[str, Any]] = {}
        for limb in LIMBS:
            items = rows.get((cond, limb), [])
            if len(items) < MIN_EXPLAINED:
                continue
            y = np.array([v for v, _ in items])
            x = np.array([m for _, m in items], dtype=np.float64).reshape(len(items), -1)
            design = np.column_stack([np.ones(len(y)), x])
            coef, *_ = np.linalg.lstsq(design, y, rcond=None)
            kinds = [k for k in limb_boundaries(limb) if k is not None]
            out[limb] = {"n": len(y), "rve": float(np.abs(y).mean()), "signed": float(y.mean()), "at_zero": float(coef[0]),
                         "per_mm": {k: float(c) for k, c in zip(kinds, coef[1:], strict=True)},
                         "rve_left": float(np.abs(y - design @ coef).mean())}
        if out:
            table[cond] = out
    return table


def boundary_figure(runs: Sequence[Run], path: str | Path) -> Path | None:
    """Box plot of the signed boundary errors (mm) per joint kind, one box per condition; None (nothing
    written) when no run measured them."""
    from .figures import kind_boxplot

    data = _collect(runs)
    conds = ordered_conditions({c for c, _ in data})
    if not conds:
        return None
    kinds = tuple(k for k in ALL_KINDS if any(data.get((c, k)) for c in conds))
    values = {c: [[e for _, e in data.get((c, kind), [])] for kind in kinds] for c in conds}
    return kind_boxplot(values, kinds, path, ylabel="fitted loop - true loop along the limb (mm, + distal)",
                        title="Segment boundaries of the fitted mesh against the truth", line=(0.0, None))


def boundaries_markdown(runs: Sequence[Run]) -> list[str]:
    """The report.md section of the boundary errors (empty when no run measured them)."""
    table = summarise(runs)
    if not table:
        return []
    md = ["## Segment boundaries: fitted loop against the true loop (mm along the limb; bsv)", "",
          ("The fitted mesh's boundary loop between two segments against the true body's, read on the fitted "
           "surface (bsv.bench.boundaries): + = the fitted loop lies distal of the true one (the proximal "
           "segment too long; for the wrist and the ankle, the forearm's or shin's cap against the true loop, + = "
           "the segment reaches too far). Left and right pooled. 1 mm is about 0.65 % of a thigh at the hip, 0.46 % of a "
           f"shin at the knee, 1.0 % of an upper arm at the shoulder, 0.8 % of a forearm at the elbow. Figure: {FIGURE}."), ""]
    for cond, rows in table.items():
        md += [f"**{cond}**", "", "| boundary | n | mean (signed) | sd | median abs | p95 abs | worst (subject side) |",
               "|---|---|---|---|---|---|---|"]
        for kind, s in rows.items():
            md.append(f"| {kind} | {s['n']} | {s['mean_mm']:+.1f} | {s['sd_mm']:.1f} | {s['median_abs_mm']:.1f} | "
                      f"{s['p95_abs_mm']:.1f} | {s['worst_mm']:+.1f} ({s['worst']}) |")
        md.append("")
    split = explained(runs)
    if split:
        md += ["### What the boundaries cost each limb", "",
               ("Each limb's signed volume error (%, both sides) fitted as a line in the errors of the loops that "
                "bound it (bsv.bench.boundaries.explained; the wrist and ankle: where the fitted forearm or shin "
                "ends, its cap against the true loop, when every run measured it): the error "
                "with the loops in place, what 1 mm costs, and the mean RVE the line leaves (in-sample). "
                "RVE minus that is what a better boundary could gain at most."), "",
               "| condition | limb | n | mean RVE | signed | with the loops in place | % per mm (proximal, distal) | RVE left |",
               "|---|---|---|---|---|---|---|---|"]
        for cond, limbs in split.items():
            for limb, s in limbs.items():
                per = ", ".join(f"{k} {v:+.2f}" for k, v in s["per_mm"].items())
                md.append(f"| {cond} | {limb} | {s['n']} | {s['rve']:.2f} | {s['signed']:+.2f} | {s['at_zero']:+.2f} | "
                          f"{per} | {s['rve_left']:.2f} |")
        md.append("")
    return md


__all__ = [
    "ALL_KINDS",
    "BAND_M",
    "CAP_COS",
    "CAP_DEPTH_M",
    "END_KINDS",
    "FIGURE",
    "INFO_KEY",
    "KINDS",
    "LIMBS",
    "MIN_EXPLAINED",
    "MIN_POINTS",
    "NEAR_M",
    "SAMPLES",
    "WIDE_BAND_M",
    "best_split",
    "boundaries_markdown",
    "boundary_errors",
    "boundary_figure",
    "distance_to_segments",
    "end_errors",
    "explained",
    "limb_boundaries",
    "loop_edges",
    "summarise",
]

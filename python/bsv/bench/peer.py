"""The peer: ``trimesh.registration.nricp_amberg`` (Amberg et al. 2007 optimal-step non-rigid ICP) run
from the same pre-alignment as BSV, labelled and measured the same way (optional extra ``peer``:
``pip install bsv[peer]`` = trimesh + scipy).

Pre-alignment: :func:`prealign` reproduces bsv-register's similarity (robust 0.1 %/99.9 % bounding
boxes, centres matched, isotropic scale = ratio of box diagonals, or per-axis scales when a box's
proportions differ from the template's by more than 50 %, or as forced by ``prealign``). nricp_amberg
runs with its default steps on the raw cloud (normals estimated from 8 neighbours). Each fitted vertex
takes the label of its nearest cloud point (the paper's rule, as BSV does) and :func:`bsv.volumes`
measures the segments.
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from typing import Any

import numpy as np

from ..types import Mesh, PointCloud
from .common import BenchError, Fit

#: Robust box quantile (bsv-register's default ``bbox_quantile``).
BBOX_QUANTILE: float = 0.001
#: Per-axis scaling when a normalised box side differs by more than this (``auto_aspect_threshold``).
AUTO_ASPECT: float = 0.5


def robust_box(points: np.ndarray, q: float = BBOX_QUANTILE) -> tuple[np.ndarray, np.ndarray]:
    """Per-axis lower/upper order statistics at quantile ``q`` (plain min/max for q = 0)."""
    p = np.asarray(points, dtype=np.float64)
    if len(p) == 0:
        raise BenchError("empty point set: nothing to pre-align")
    if q <= 0:
        return p.min(axis=0), p.max(axis=0)
    n = len(p)
    lo = min(int(np.floor(q * n)), n - 1)
    hi = min(max(int(np.ceil((1.0 - q) * n)) - 1, lo), n - 1)
    s = np.sort(p, axis=0)
    return s[lo], s[hi]


def prealign(template_vertices: np.ndarray, points: np.ndarray, mode: str = "auto") -> tuple[np.ndarray, str]:
    """Template vertices moved and scaled onto the cloud's box (bsv-register's similarity) and the mode used."""
    tmin, tmax = np.min(template_vertices, axis=0), np.max(template_vertices, axis=0)
    cmin, cmax = robust_box(points)
    te, ce = tmax - tmin, cmax - cmin
    td, cd = max(float(np.linalg.norm(te)), np.finfo(float).tiny), float(np.linalg.norm(ce))
    per_axis_ok = bool(np.all(te > 1e-9 * td) and np.all(ce > 1e-9 * cd))
    mode = mode.replace("_", "").replace("-", "").lower()
    if mode == "auto":
        differs = bool(np.any(np.abs((ce / cd) / (te / td) - 1.0) > AUTO_ASPECT))
        mode = "peraxis" if differs and per_axis_ok else "isotropic"
    elif mode == "peraxis" and not per_axis_ok:
        mode = "isotropic"
    elif mode not in ("isotropic", "peraxis"):
        raise BenchError(f"prealign mode {mode!r}: use isotropic, per_axis or auto")
    scale = ce / te if mode == "peraxis" else np.full(3, cd / td)
    tc, cc = 0.5 * (tmin + tmax), 0.5 * (cmin + cmax)
    return cc + scale * (np.asarray(template_vertices) - tc), mode


def register_trimesh(cloud: PointCloud, template: Mesh, params: Mapping[str, Any] | None = None) -> Fit:
    """nricp_amberg of the pre-aligned template onto the cloud; vertex labels from the nearest cloud point."""
    try:
        import trimesh
        from scipy.spatial import cKDTree
        from trimesh.registration import nricp_amberg
    except ImportError as exc:
        raise BenchError(f"--peer trimesh needs trimesh and scipy ({exc}); install them: pip install 'bsv[peer]'") from exc
    from .. import volumes

    p = dict(params or {})
    t0 = time.perf_counter()
    start, mode = prealign(template.vertices, cloud.points, str(p.get("prealign", "auto")))
    src = trimesh.Trimesh(start, template.faces, process=False)
    # use_faces=False: the target is a cloud (trimesh 4.x fails on a PointCloud target otherwise)
    fitted = np.asarray(nricp_amberg(src, cloud.points, use_faces=False), dtype=np.float64)
    if cloud.labels is not None:
        _, nearest = cKDTree(cloud.points).query(fitted)
        labels = cloud.labels[nearest]
    elif template.vertex_labels is not None:
        labels = template.vertex_labels
    else:
        raise BenchError("neither the cloud nor the template has labels: cannot measure segments")
    seconds = time.perf_counter() - t0
    mesh = Mesh(fitted, template.faces, labels, None)
    vols = volumes(mesh)["volumes_l"]
    return Fit("trimesh", mesh, dict(vols), seconds, {"prealign": mode})

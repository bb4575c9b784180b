"""The one-page report of ``bsv process`` / ``bsv demo``: ``report.html`` with PNG figures (matplotlib Agg).

Figures: the segmented fitted body seen from the front and from the subject's left side (a flat-shaded
painter's-algorithm render of the labelled mesh in palette colours), the cloud over the fitted mesh,
volume bars per segment (with the true volumes when known). Tables: volumes, ratios and left/right
asymmetry, estimated mass, cloud and registration figures, and "Cloud cleaning": per camera what was
removed from the person mask (floor, depth edges, far, separate parts, outliers) and the floor check of
the calibration (tilt, height at the subject, agreement between cameras), with its warnings.
"""

from __future__ import annotations

import html
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from . import _bsv
from .errors import OutputExistsError
from .types import PALETTE, SEGMENT_NAMES

PathLike = str | Path

#: PNG figures written next to report.html.
FIGURES = ("body_front.png", "body_side.png", "cloud_over_mesh.png", "volumes.png")

#: Views: (screen x axis, screen y axis, toward-viewer axis) as world direction vectors (DESIGN.md frame:
#: Y up, subject faces +Z, +X = subject's left).
VIEWS = {
    "front": (np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0]), np.array([0.0, 0.0, 1.0])),
    "side": (np.array([0.0, 0.0, -1.0]), np.array([0.0, 1.0, 0.0]), np.array([1.0, 0.0, 0.0])),
    "back": (np.array([-1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0]), np.array([0.0, 0.0, -1.0])),
}


def palette() -> np.ndarray:
    """(15, 3) float RGB in [0, 1] of the segment ids (:data:`bsv.types.PALETTE`, Rust's palette)."""
    return np.asarray(PALETTE, dtype=np.float64) / 255.0


def face_labels(faces: np.ndarray, vertex_labels: np.ndarray | None, face_labels_: np.ndarray | None = None) -> np.ndarray:
    """Per-face segment ids: the given face labels, else Rust's one rule
    (``bsv_volume::face_labels_from_vertices``: the label shared by two corners; three different: the
    corner with the smallest vertex index)."""
    if face_labels_ is not None and len(face_labels_) == len(faces):
        return np.asarray(face_labels_, dtype=np.uint8)
    if vertex_labels is None:
        return np.zeros(len(faces), dtype=np.uint8)
    return _bsv.face_labels_from_vertices(faces, vertex_labels)


def render_mesh(ax: Any, vertices: np.ndarray, faces: np.ndarray, labels: np.ndarray | None, view: str = "front",
                alpha: float = 1.0, grey: bool = False) -> None:
    """Draws a labelled mesh on a 2-D matplotlib axis: orthographic projection, faces sorted far to near
    (painter's algorithm), Lambert-shaded palette colours (or grey)."""
    from matplotlib.collections import PolyCollection

    sx, sy, toward = VIEWS[view]
    v = np.asarray(vertices, dtype=np.float64)
    f = np.asarray(faces, dtype=np.int64)
    tri = v[f]
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
    facing = n @ toward
    light = toward + 0.35 * sy + 0.2 * sx
    light /= np.linalg.norm(light)
    shade = 0.3 + 0.7 * np.clip(n @ light, 0.0, 1.0)
    keep = facing > -0.05  # back faces are hidden anyway: skip them
    depth = (tri @ toward).mean(axis=1)
    order = np.argsort(depth[keep], kind="stable")
    idx = np.flatnonzero(keep)[order]
    xy = np.stack([tri[idx] @ sx, tri[idx] @ sy], axis=-1)
    base = np.full((len(idx), 3), 0.78) if grey else palette()[np.clip(np.asarray(labels)[idx], 0, 14)]
    colours = np.clip(base * shade[idx, None], 0.0, 1.0)
    rgba = np.concatenate([colours, np.full((len(idx), 1), alpha)], axis=1)
    # matplotlib's stub asks for a Sequence; an (N, 3, 2) array is what PolyCollection handles fastest
    ax.add_collection(PolyCollection(xy, facecolors=rgba, edgecolors=rgba, linewidths=0.15))  # type: ignore[arg-type]
    ax.set_xlim(xy[..., 0].min() - 0.05, xy[..., 0].max() + 0.05)
    ax.set_ylim(xy[..., 1].min() - 0.05, xy[..., 1].max() + 0.05)
    ax.set_aspect("equal")
    ax.set_axis_off()


def _legend(fig: Any, ids: Sequence[int]) -> None:
    from matplotlib.patches import Patch

    pal = palette()
    handles = [Patch(color=pal[i], label=SEGMENT_NAMES[i]) for i in ids if i != 0]
    fig.legend(handles=handles, loc="lower center", ncol=min(3, max(1, len(handles))), fontsize=7, frameon=False)


def _body_figure(path: Path, mesh: Any, labels: np.ndarray, view: str) -> None:
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(3.6, 5.6), dpi=110)
    render_mesh(ax, mesh.vertices, mesh.faces, labels, view)
    ax.set_title(f"fitted body, {'front' if view == 'front' else 'left side'}", fontsize=9)
    _legend(fig, sorted({int(x) for x in np.unique(labels)}))
    fig.subplots_adjust(bottom=0.2, top=0.95, left=0.02, right=0.98)
    fig.savefig(path)
    plt.close(fig)


def _cloud_figure(path: Path, mesh: Any, labels: np.ndarray, cloud: Any, max_points: int = 25_000) -> None:
    import matplotlib.pyplot as plt

    pts = np.asarray(cloud.points)
    lab = np.zeros(len(pts), dtype=np.uint8) if cloud.labels is None else np.asarray(cloud.labels)
    if len(pts) > max_points:
        sel = np.random.default_rng(0).choice(len(pts), max_points, replace=False)
        pts, lab = pts[sel], lab[sel]
    pal = palette()
    fig, axes = plt.subplots(1, 2, figsize=(6.4, 5.6), dpi=110)
    for ax, view in zip(axes, ("front", "side"), strict=True):
        render_mesh(ax, mesh.vertices, mesh.faces, labels, view, grey=True)
        sx, sy, _ = VIEWS[view]
        ax.scatter(pts @ sx, pts @ sy, s=0.3, c=pal[np.clip(lab, 0, 14)], linewidths=0)
        ax.set_title(f"cloud over fitted mesh ({view})", fontsize=9)
    fig.subplots_adjust(left=0.02, right=0.98, top=0.94, bottom=0.02, wspace=0.05)
    fig.savefig(path)
    plt.close(fig)


def _segments(volumes_l: dict[str, float]) -> list[str]:
    return [SEGMENT_NAMES[i] for i in range(1, 15) if SEGMENT_NAMES[i] in volumes_l]


def _volume_figure(path: Path, volumes_l: dict[str, float], truth: dict[str, float] | None) -> None:
    import matplotlib.pyplot as plt

    names = _segments(volumes_l)
    x = np.arange(len(names))
    est = np.array([volumes_l[n] for n in names])
    pal = palette()
    fig, ax = plt.subplots(figsize=(7.0, 3.2), dpi=110)
    colours = [pal[next(k for k, v in SEGMENT_NAMES.items() if v == n)] for n in names]
    if truth:
        tv = np.array([truth.get(n, np.nan) for n in names])
        ax.bar(x - 0.2, est, 0.4, color=colours, edgecolor="k", linewidth=0.4, label="estimated")
        ax.bar(x + 0.2, tv, 0.4, color="white", edgecolor="k", linewidth=0.6, hatch="///", label="true")
        ax.legend(fontsize=8)
    else:
        ax.bar(x, est, 0.6, color=colours, edgecolor="k", linewidth=0.4)
    for xi, e in zip(x.tolist(), est.tolist(), strict=True):
        ax.text(xi, e, f"{e:.1f}", ha="center", va="bottom", fontsize=6)
    ax.set_xticks(x)
    ax.set_xticklabels(names, rotation=35, ha="right", fontsize=8)
    ax.set_ylabel("volume (L)")
    ax.set_title("segment volumes", fontsize=9)
    ax.spines[["top", "right"]].set_visible(False)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def _opt(x: Any, digits: int) -> str:
    return "" if x is None else _fmt(x, digits)


def cleaning_html(cloud_report: dict[str, Any]) -> str:
    """The "Cloud cleaning" section: one row per camera (points removed at each step, the floor check),
    the floor agreement between cameras and the warnings (highlighted)."""
    rows = []
    for v in cloud_report.get("views", []):
        c = v.get("cleaning") or {}
        f = v.get("floor") or {}
        seen = f.get("status") == "seen"
        rows.append([html.escape(str(v.get("name", ""))), v.get("deprojected", ""), c.get("floor_removed", ""),
                     c.get("edge_removed", ""), c.get("far_removed", ""), c.get("separate_removed", ""),
                     v.get("sor_removed", ""), "seen" if seen else "not seen",
                     _opt(f.get("pitch_deg"), 2), _opt(f.get("roll_deg"), 2), _opt(f.get("height_mm"), 1)])
    table = _table(["camera", "mask points", "floor", "edges", "far", "separate", "outliers (SOR)", "floor check",
                    "pitch deg", "roll deg", "floor height mm"], rows)
    agree = [[html.escape(" / ".join(a.get("cameras", []))), _fmt(a.get("tilt_deg"), 2), _fmt(a.get("height_mm"), 1)]
             for a in cloud_report.get("floor_agreement", [])]
    agree_html = _table(["cameras", "floor angle deg", "height difference mm"], agree) if agree else ""
    warnings = cloud_report.get("warnings", [])
    warn_html = ("<ul class=\"warn\">" + "".join(f"<li>{html.escape(str(w))}</li>" for w in warnings) + "</ul>"
                 if warnings else "<p class=\"note\">No calibration warning.</p>")
    return f"<h2>Cloud cleaning</h2>{table}{agree_html}{warn_html}"


def _landmark_warnings_html(vols: dict[str, Any]) -> str:
    """The volumes JSON's ``warnings`` (landmarks not seen confidently and where they came from), highlighted."""
    warnings = vols.get("warnings") or []
    return ("<ul class=\"warn\">" + "".join(f"<li>{html.escape(str(w))}</li>" for w in warnings) + "</ul>"
            if warnings else "")


def _fmt(x: Any, digits: int = 3) -> str:
    if isinstance(x, (int, float)) and math.isfinite(float(x)):
        return f"{float(x):.{digits}f}"
    return html.escape(str(x))


def _table(headers: Sequence[str], rows: Sequence[Sequence[Any]]) -> str:
    head = "".join(f"<th>{html.escape(h)}</th>" for h in headers)
    body = "".join("<tr>" + "".join(f"<td>{c}</td>" for c in r) + "</tr>" for r in rows)
    return f"<table><tr>{head}</tr>{body}</table>"


CSS = """body{font-family:sans-serif;font-size:12px;margin:16px;max-width:1100px}
h1{font-size:18px;margin:0 0 6px}h2{font-size:13px;margin:10px 0 4px}
table{border-collapse:collapse;margin:2px 0 8px}td,th{border:1px solid #ccc;padding:2px 6px;text-align:right}
th{background:#f0f0f0}td:first-child{text-align:left}.row{display:flex;gap:14px;align-items:flex-start;flex-wrap:wrap}
img{max-height:420px}.note{color:#555}.warn{color:#a00000;font-weight:bold}"""


def quality_html(registration: dict[str, Any]) -> str:
    """The per-segment fit quality table (``registration["quality"]``, rule in bsv-register quality.rs);
    a doubtful segment is marked in red. Empty when the summary has no quality figures."""
    quality: dict[str, dict[str, Any]] = registration.get("quality") or {}
    if not quality:
        return ""
    rows = [[html.escape(name), _fmt(q.get("rms_mm"), 1), _fmt(100 * q.get("coverage", math.nan), 0),
             _fmt(100 * q.get("gap_fraction", math.nan), 0), _fmt(100 * q.get("exposed_uncovered", math.nan), 0),
             '<span class="warn">doubtful</span>' if q.get("doubtful") else "ok"] for name, q in quality.items()]
    return ("<h2>Fit quality</h2>" + _table(["segment", "RMS (mm)", "covered %", "in gaps %", "seen, uncovered %",
                                              "fit"], rows)
            + '<p class="note">covered: a cloud point within 10 mm; doubtful: RMS &gt; 10 mm, seen-uncovered &gt; 20 % '
              "or covered &lt; 50 %: check the cloud of that segment before using its volume.</p>")


def write_report(result: Any, out_dir: PathLike, *, title: str = "BSV report", overwrite: bool = False) -> dict[str, Path]:
    """Draws the figures and writes ``report.html`` for a :class:`bsv.pipeline.ProcessResult`; returns the
    paths (keys: report and the figure stems). Refuses to replace existing files unless ``overwrite``."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    out = Path(out_dir)
    paths = {Path(f).stem: out / f for f in FIGURES}
    report = out / "report.html"
    existing = [p.name for p in (*paths.values(), report) if p.exists()]
    if existing and not overwrite:
        raise OutputExistsError(f"{out} already holds {', '.join(existing)}; pass overwrite=True to replace them")
    out.mkdir(parents=True, exist_ok=True)
    mesh = result.registration.mesh
    flabels = face_labels(mesh.faces, mesh.vertex_labels, mesh.face_labels)
    vols = result.volumes
    volumes_l = vols.get("volumes_l", {})
    truth = getattr(result, "truth", None)
    _body_figure(paths["body_front"], mesh, flabels, "front")
    _body_figure(paths["body_side"], mesh, flabels, "side")
    _cloud_figure(paths["cloud_over_mesh"], mesh, flabels, result.cloud)
    _volume_figure(paths["volumes"], volumes_l, truth)

    # Volumes table (segments, then aggregates), each with its 95 % interval (bsv.uncertainty).
    from .uncertainty import Intervals, asymmetry_text

    iv = Intervals.from_json(vols["intervals"]) if vols.get("intervals") else None

    def band(name: str, digits: int = 3) -> str:
        b = iv.get(name) if iv else None
        return f"{_fmt(b[0], digits)} to {_fmt(b[1], digits)}" if b else "n/a"

    rows = []
    for name, v in volumes_l.items():
        r = [html.escape(name), _fmt(v), band(name)]
        if truth:
            t = truth.get(name)
            r += [_fmt(t) if t is not None else "", _fmt((v - t) / t * 100, 2) if t else ""]
        rows.append(r)
    vol_table = _table(["segment", "volume (L)", "95 % interval"] + (["true (L)", "error %"] if truth else []), rows)
    ratios = vols.get("ratios", {}) or {}
    ratio_rows = [[html.escape(k), _fmt(v), band(k)] for k, v in ratios.items() if not k.startswith("asymmetry_")]
    asym_rows = [[html.escape(k[len("asymmetry_"):].removesuffix("_pct")),
                  html.escape(asymmetry_text(v, iv.get(k) if iv else None)) if v is not None else _fmt(v, 1)]
                 for k, v in ratios.items() if k.startswith("asymmetry_")]
    mass = vols.get("mass_kg")
    density = vols.get("density_kg_m3", 1000.0)
    measured = ", ".join(_segments(volumes_l))
    reg = vols.get("registration") or {}
    reg_rows = [[html.escape(k), _fmt(v, 3)] for k, v in reg.items() if isinstance(v, (int, float, str))]
    cr = result.cloud_report
    cloud_rows = [[html.escape(v["name"]), v["mask_pixels"], v["deprojected"], v["sor_removed"],
                   sum(v["dropped"].values()), v["kept"]] for v in cr["views"]]
    seg_rows = [[html.escape(k), html.escape(str(s.get("source", ""))), s.get("labelled_pixels", "")]
                for k, s in result.segmentation.items()]
    timing_rows = [[html.escape(k), _fmt(v, 2)] for k, v in result.timings.items()]
    mband = iv.get("mass_trunk_limbs_kg") if iv else None
    mass_html = (f"<p><b>Estimated mass</b> of the measured segments ({html.escape(measured)}): "
                 f"<b>{_fmt(mass, 1)} kg</b> (volume x {_fmt(density, 0)} kg/m&sup3;)"
                 + (f"; trunk and limbs 95 % interval {_fmt(mband[0], 1)} to {_fmt(mband[1], 1)} kg" if mband else "")
                 + ".</p>") if mass is not None else ""
    notes = "".join(f"<li>{html.escape(str(n))}</li>" for n in vols.get("notes", []) or [])
    doc = f"""<!DOCTYPE html>
<html><head><meta charset="utf-8"><title>{html.escape(title)}</title><style>{CSS}</style></head><body>
<h1>{html.escape(title)}</h1>
<p class="note">bsv {html.escape(str(vols.get('bsv_version', '')))} &middot; lengths in metres, volumes in litres &middot;
{len(result.cloud)} cloud points &middot; segmentation: {html.escape(str(vols.get('cloud', {}).get('segmentation', '')))}</p>
<div class="row">
<img src="body_front.png" alt="fitted body, front"><img src="body_side.png" alt="fitted body, side">
<img src="cloud_over_mesh.png" alt="cloud over the fitted mesh">
</div>
<div class="row"><div><img src="volumes.png" alt="segment volumes" style="max-height:300px"></div></div>
{mass_html}
{f'<p class="note">95 % intervals: {html.escape(iv.method)}.</p>' if iv else ""}
<div class="row">
<div><h2>Volumes</h2>{vol_table}</div>
<div><h2>Distal / proximal ratios</h2>{_table(["ratio", "value", "95 % interval"], ratio_rows)}
<h2>Left / right asymmetry</h2>{_table(["part", "(L-R)/mean %"], asym_rows)}</div>
<div><h2>Cloud</h2>{_table(["camera", "mask px", "points", "SOR removed", "dropped", "kept"], cloud_rows)}
<h2>Segmentation</h2>{_table(["camera", "source", "labelled px"], seg_rows)}{_landmark_warnings_html(vols)}
<h2>Registration</h2>{_table(["", ""], reg_rows)}
{quality_html(reg)}
<h2>Timings (s)</h2>{_table(["step", "s"], timing_rows)}</div>
</div>
<div class="row"><div>{cleaning_html(cr)}</div></div>
{f"<h2>Notes</h2><ul>{notes}</ul>" if notes else ""}
</body></html>
"""
    report.write_text(doc)
    return {"report": report, **paths}


__all__ = ["FIGURES", "VIEWS", "cleaning_html", "face_labels", "palette", "quality_html", "render_mesh", "write_report"]

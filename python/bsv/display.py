"""Notebook display of results: a small HTML table and an inline PNG thumbnail of the segmented body.

``Registration._repr_html_`` and ``ProcessResult._repr_html_`` call :func:`registration_html`; Jupyter
shows it when a cell ends with the result. Everything is inlined (a ``data:`` URI), nothing is written.
"""

from __future__ import annotations

import base64
import html
import io
from typing import Any

import numpy as np

from .types import SEGMENT_NAMES, TRUNK_LIMBS, Mesh

#: Rows of the volume table: the total first, then the nine segments in DESIGN.md order.
VOLUME_ROWS: tuple[str, ...] = ("trunk_limbs", *TRUNK_LIMBS)


def thumbnail_png(mesh: Mesh, height_px: int = 220, view: str = "front") -> bytes:
    """A small PNG of the labelled mesh (palette colours, flat shading; ``bsv.report.render_mesh``)."""
    from matplotlib.figure import Figure  # no pyplot: the notebook's backend is left alone

    from .report import face_labels, render_mesh

    labels = face_labels(mesh.faces, mesh.vertex_labels, mesh.face_labels)
    dpi = 100
    fig = Figure(figsize=(height_px * 0.5 / dpi, height_px / dpi), dpi=dpi)
    ax = fig.add_axes((0.0, 0.0, 1.0, 1.0))
    render_mesh(ax, mesh.vertices, mesh.faces, labels, view)
    buf = io.BytesIO()
    fig.savefig(buf, format="png")
    return buf.getvalue()


def _rows(volumes_l: dict[str, float], truth: dict[str, float] | None) -> list[str]:
    rows = []
    for name in VOLUME_ROWS:
        if name not in volumes_l:
            continue
        est = float(volumes_l[name])
        cells = [html.escape(name), f"{est:.3f}"]
        if truth is not None and name in truth and truth[name] > 0:
            cells += [f"{truth[name]:.3f}", f"{(est / truth[name] - 1.0) * 100.0:+.2f}"]
        rows.append("<tr>" + "".join(f"<td>{c}</td>" for c in cells) + "</tr>")
    return rows


def registration_html(reg: Any, truth: dict[str, float] | None = None, title: str = "Registration") -> str:
    """HTML of a :class:`bsv.Registration` (or anything with ``mesh``, ``volumes``, ``seconds``, ``log``):
    volumes in litres (and against ``truth`` when given), the fit's rms and time, and a thumbnail."""
    volumes_l: dict[str, float] = reg.volumes.get("volumes_l", {})
    summary: dict[str, Any] = reg.volumes.get("registration") or {}
    head = ["segment", "volume (L)"] + (["true (L)", "error (%)"] if truth else [])
    header = "".join(f"<th style='text-align:left;padding-right:8px'>{h}</th>" for h in head)
    body = "".join(_rows(volumes_l, truth))
    table = f"<table style='border-collapse:collapse;font-size:12px'><tr>{header}</tr>{body}</table>"
    rms = summary.get("rms_mesh_to_points_mm")
    fit = (
        f"{len(reg.log)} iterations, {reg.seconds:.2f} s"
        + ("" if rms is None else f", mesh-to-cloud rms {float(rms):.2f} mm")
    )
    mass = reg.volumes.get("mass_kg")
    if mass is not None and np.isfinite(mass):
        fit += f", mass at the given density {float(mass):.1f} kg"
    try:
        png = base64.b64encode(thumbnail_png(reg.mesh)).decode("ascii")
        img = f"<img alt='segmented fitted body' src='data:image/png;base64,{png}' style='height:220px'/>"
    except Exception as e:  # a display must never fail the cell: say why the picture is missing
        img = f"<p>(no thumbnail: {html.escape(str(e))})</p>"
    segments = ", ".join(SEGMENT_NAMES[i] for i in sorted({int(x) for x in np.unique(reg.mesh.vertex_labels)} - {0})) \
        if reg.mesh.vertex_labels is not None else "none"
    return (
        f"<div><b>{html.escape(title)}</b> <span style='font-size:11px'>({html.escape(fit)})</span>"
        "<div style='display:flex;gap:16px;align-items:flex-start'>"
        f"<div>{table}</div><div>{img}</div></div>"
        f"<div style='font-size:10px;color:#555'>segments: {html.escape(segments)}</div></div>"
    )


__all__ = ["VOLUME_ROWS", "registration_html", "thumbnail_png"]

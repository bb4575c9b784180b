#!/usr/bin/env python3
"""Draws the README's picture (``docs/images/segmented-body.png``) with the report's own figure code.

By default it runs ``bsv demo`` with its defaults (:func:`bsv.pipeline.demo` into a temporary folder:
synthetic subject 0 of cohort seed 0, the virtual two-camera rig in a clinic room, L515 depth noise,
MediaPipe segmentation of the colour images, cloud building, registration of the MakeHuman template) and
draws three panels: the labelled cloud of the two cameras, and the fitted, segmented body from the front
and from the subject's left side (:func:`bsv.report.render_mesh`: flat-shaded, in the colour-blind-safe
palette of :mod:`bsv.palette`), with each segment's fitted volume in the legend. Everything is seeded:
re-running gives the same picture. ``--from DIR`` draws an existing demo or process output folder.

Usage: python scripts/make_readme_figure.py [--out docs/images/segmented-body.png] [--from DIR] [--overwrite]
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def draw(out_dir: Path) -> Any:
    """The matplotlib figure of a ``bsv demo`` / ``bsv process`` output folder (its cloud.ply, fitted.ply,
    volumes.json and, for a demo, demo.json's true volumes): the labelled cloud, the fitted segmented body
    from the front and the left side (one scale for the three panels) and a legend of the fitted volumes."""
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt
    from matplotlib.patches import Patch

    import bsv
    from bsv.palette import plain_name, rgb01, segment_id
    from bsv.report import VIEWS, face_labels, render_mesh
    from bsv.types import SEGMENT_NAMES, TRUNK_LIMBS

    mesh = bsv.read_mesh(out_dir / "fitted.ply")
    cloud = bsv.read_point_cloud(out_dir / "cloud.ply")
    vols = json.loads((out_dir / "volumes.json").read_text())["volumes_l"]
    demo_json = out_dir / "demo.json"
    truth = json.loads(demo_json.read_text())["true_volumes_l"] if demo_json.is_file() else {}
    labels = face_labels(mesh.faces, mesh.vertex_labels, mesh.face_labels)
    pal = rgb01()

    fig, axes = plt.subplots(1, 3, figsize=(9.0, 5.4), dpi=100)
    pts = np.asarray(cloud.points)
    lab = np.zeros(len(pts), dtype=np.uint8) if cloud.labels is None else np.asarray(cloud.labels)
    sel = np.random.default_rng(0).choice(len(pts), min(len(pts), 30_000), replace=False)
    sx, sy, _ = VIEWS["front"]
    axes[0].scatter(pts[sel] @ sx, pts[sel] @ sy, s=0.25, c=pal[np.clip(lab[sel], 0, 14)], linewidths=0)
    axes[0].set_axis_off()
    axes[0].set_title(f"two cameras: {len(pts):,} labelled points", fontsize=9)
    for ax, view, title in ((axes[1], "front", "fitted template, front"), (axes[2], "side", "left side")):
        render_mesh(ax, mesh.vertices, mesh.faces, labels, view)
        ax.set_title(title, fontsize=9)
    # one scale for the three panels: the widest x range and the common y range, centred per panel
    spans = [ax.get_xlim() for ax in axes]
    half = max(hi - lo for lo, hi in spans) / 2.0
    y0 = min(min(ax.get_ylim()) for ax in axes)
    y1 = max(max(ax.get_ylim()) for ax in axes)
    for ax, (lo, hi) in zip(axes, spans, strict=True):
        ax.set_xlim((lo + hi) / 2.0 - half, (lo + hi) / 2.0 + half)
        ax.set_ylim(y0, y1)
        ax.set_aspect("equal")
    names = [SEGMENT_NAMES[i] for i in range(1, 15) if SEGMENT_NAMES[i] in TRUNK_LIMBS and SEGMENT_NAMES[i] in vols]
    handles = [Patch(color=pal[segment_id(n)], label=f"{plain_name(n)}: {vols[n]:.2f} L") for n in names]
    title = f"fitted segment volumes (trunk and limbs {vols['trunk_limbs']:.1f} L"
    title += f", true {truth['trunk_limbs']:.1f} L)" if "trunk_limbs" in truth else ")"
    fig.legend(handles=handles, loc="lower center", ncol=5, fontsize=7.5, frameon=False, title=title,
               title_fontsize=8)
    fig.subplots_adjust(left=0.01, right=0.99, top=0.94, bottom=0.14, wspace=0.02)
    return fig


def main(argv: list[str] | None = None) -> int:
    """Command line: see the module docstring."""
    import tempfile

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "images" / "segmented-body.png")
    ap.add_argument("--from", dest="source", type=Path,
                    help="draw this bsv demo / bsv process output folder instead of running the demo")
    ap.add_argument("--overwrite", action="store_true")
    a = ap.parse_args(argv)
    if a.out.exists() and not a.overwrite:
        raise SystemExit(f"{a.out} exists; pass --overwrite to replace it")
    with tempfile.TemporaryDirectory(prefix="bsv-figure-") as tmp:
        source = a.source
        if source is None:
            from bsv.pipeline import demo

            source = Path(tmp) / "demo"
            demo(source, progress=False)
        fig = draw(source)
    a.out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(a.out)
    print(f"wrote {a.out} ({a.out.stat().st_size / 1e3:.0f} kB)")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""The figure of the biomechanics outputs (``bsip.png``): the fitted body, front and side, with each
segment's centre of mass (dot, area by mass), its de Leva endpoints joined by its length axis, and the
joint centres (crosses)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..types import Mesh
from .compute import BSIP


def draw(b: BSIP, mesh: Mesh, path: Path) -> None:
    """Draws ``b`` over ``mesh`` into the PNG ``path`` (matplotlib Agg; the caller makes it atomic)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..report import VIEWS, face_labels, render_mesh

    labels = face_labels(mesh.faces, mesh.vertex_labels, mesh.face_labels)
    fig, axes = plt.subplots(1, 2, figsize=(6.4, 5.8), dpi=110)
    biggest = max(s.mass_kg for s in b.segments.values())
    for ax, view in zip(axes, ("front", "side"), strict=True):
        render_mesh(ax, mesh.vertices, mesh.faces, labels, view, alpha=0.35)
        sx, sy, _ = VIEWS[view]
        for s in b.segments.values():
            ends = np.array([s.origin.point, s.other.point])
            ax.plot(ends @ sx, ends @ sy, color="0.15", lw=0.8, ls="-" if s.other.how == "joint" else ":")
            ax.scatter([s.com @ sx], [s.com @ sy], s=8 + 60 * s.mass_kg / biggest, c="black", zorder=3)
        j = np.array(list(b.joints.values())) if b.joints else np.zeros((0, 3))
        ax.scatter(j @ sx, j @ sy, marker="x", s=25, c="#d62728", linewidths=1.2, zorder=4)
        ax.set_title(f"{view}: centres of mass (dots), joint centres (x)", fontsize=8)
    fig.suptitle(f"segment inertial parameters, body-mass estimate {b.body_mass_kg:.1f} kg", fontsize=9)
    fig.subplots_adjust(left=0.02, right=0.98, top=0.9, bottom=0.02, wspace=0.05)
    fig.savefig(path, format="png")
    plt.close(fig)

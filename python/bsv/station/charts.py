"""The follow-up charts of a subject page: every segment's volume and the left/right asymmetries over
the sessions, each point with its 95 % interval (matplotlib, PNG inlined as base64)."""

from __future__ import annotations

import base64
import io
import threading
from collections.abc import Sequence
from typing import Any

from .uncertainty import ASYMMETRIES, SEGMENTS, Interval, ratio_interval, volume_interval

_lock = threading.Lock()  # pyplot's state is global: one figure at a time


def _png(fig: Any) -> str:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=80)
    return "data:image/png;base64," + base64.b64encode(buf.getvalue()).decode()


def history_png(labels: Sequence[str], volumes: Sequence[dict[str, Any]]) -> str:
    """Small multiples (one panel per segment and asymmetry) of ``volumes`` (one volumes JSON per session,
    oldest first, x labels ``labels``) with error bars; a data: URL."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    panels: list[tuple[str, str, list[Interval | None]]] = []
    panels += [(s, "L", [volume_interval(v, s) for v in volumes]) for s in SEGMENTS]
    panels += [(a.replace("asymmetry_", "asym. ").replace("_pct", ""), "% (L-R)/mean",
                [ratio_interval(v, a) for v in volumes]) for a in ASYMMETRIES]
    with _lock:
        fig, axes = plt.subplots(2, 7, figsize=(15, 4.4), constrained_layout=True)
        try:
            x = list(range(len(labels)))
            for ax, (title, unit, ivs) in zip(axes.flat, panels, strict=False):
                pts = [(i, iv) for i, iv in zip(x, ivs, strict=True) if iv is not None]
                if pts:
                    xs = [i for i, _ in pts]
                    ys = [iv.value for _, iv in pts]
                    err = [[iv.value - iv.lo for _, iv in pts], [iv.hi - iv.value for _, iv in pts]]
                    ax.errorbar(xs, ys, yerr=err, fmt="o-", capsize=3, ms=4, lw=1)
                ax.set_title(title, fontsize=9)
                ax.set_ylabel(unit, fontsize=7)
                ax.set_xticks(x, [str(s) for s in labels], fontsize=7)
                ax.tick_params(axis="y", labelsize=7)
                ax.set_xlim(-0.5, max(len(labels) - 0.5, 0.5))
            for ax in list(axes.flat)[len(panels):]:
                ax.axis("off")
            return _png(fig)
        finally:
            plt.close(fig)


__all__ = ["history_png"]

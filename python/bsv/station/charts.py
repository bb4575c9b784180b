"""The follow-up charts of a subject page: every segment's volume and the left/right asymmetries over
the sessions, each point with its 95 % interval (matplotlib, PNG inlined as base64). A dashed line between
two sessions marks a change of the template the results were fitted with (:func:`result_template_kind`),
so that a template change is not read as a change in the subject.

:func:`subject_chart` caches each chart in ``DATA/charts/`` under a name made of the results it shows
(results never change, so neither does the chart). The worker process draws the chart right after it
stores a result, so that the web process, whose threads share one interpreter lock, rarely draws."""

from __future__ import annotations

import base64
import hashlib
import io
import threading
import uuid
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from .uncertainty import ASYMMETRIES, SEGMENTS, Interval, ratio_interval, volume_interval

_lock = threading.Lock()  # pyplot's state is global: one figure at a time
#: Part of every cached chart's name: changed whenever the drawing changes, so no older drawing is served.
_CHART_VERSION = "2"  # 2: template changes marked
#: The template of a result whose volumes JSON has no ``template`` record (fitted before the sexed templates).
DEFAULT_TEMPLATE_KIND = "default"


def result_template_kind(volumes: Mapping[str, Any]) -> str:
    """The kind of the template (``"default"``, ``"female"``, ``"male"``, ``"custom"``, ...) a result was
    fitted with, from its volumes JSON's ``template`` record; :data:`DEFAULT_TEMPLATE_KIND` (the average
    template) when the record or its kind is missing, as in a result stored before the sexed templates.

    The one rule of the station (comparison page, subject page, CSV and PDF exports, history chart)."""
    record = volumes.get("template")
    kind = record.get("kind") if isinstance(record, Mapping) else None
    return str(kind) if kind else DEFAULT_TEMPLATE_KIND


def template_changes(kinds: Sequence[str]) -> list[int]:
    """The indices ``i`` (``1 <= i < len(kinds)``) at which ``kinds[i]`` differs from ``kinds[i - 1]``: the
    sessions (oldest first) fitted with another template than the session before them."""
    return [i for i in range(1, len(kinds)) if kinds[i] != kinds[i - 1]]


def _png(fig: Any) -> str:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=80)
    return "data:image/png;base64," + base64.b64encode(buf.getvalue()).decode()


def subject_chart(data: Path, sessions: Sequence[Any]) -> str:
    """The history chart (a data: URL) of ``sessions`` (ORM sessions, oldest first; those without a result
    are left out), from ``data/charts/`` when drawn before, else drawn and stored there; "" without results."""
    done = [(s.id, s.latest) for s in sessions if s.latest is not None]
    if not done:
        return ""
    key = f"v{_CHART_VERSION};" + ",".join(f"{sid}:{res.id}" for sid, res in done)
    path = data / "charts" / (hashlib.sha256(key.encode()).hexdigest()[:32] + ".txt")
    with _file_lock:
        if path.is_file():
            return path.read_text()
        url = history_png([f"#{sid}" for sid, _ in done], [res.volumes for _, res in done])
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_name(f".{uuid.uuid4().hex}.tmp")
        tmp.write_text(url)
        tmp.replace(path)
        return url


_file_lock = threading.Lock()  # one drawing at a time; concurrent requests for the same chart wait for it


def history_png(labels: Sequence[str], volumes: Sequence[dict[str, Any]]) -> str:
    """Small multiples (one panel per segment and asymmetry) of ``volumes`` (one volumes JSON per session,
    oldest first, x labels ``labels``) with error bars; a data: URL.

    Where the template kind (:func:`result_template_kind`) changes between two consecutive sessions, every
    panel has a dashed vertical line between them, labelled with the change (e.g. "default → female"),
    and the figure's title lists the changes."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    panels: list[tuple[str, str, list[Interval | None]]] = []
    panels += [(s, "L", [volume_interval(v, s) for v in volumes]) for s in SEGMENTS]
    panels += [(a.replace("asymmetry_", "asym. ").replace("_pct", ""), "% (L-R)/mean",
                [ratio_interval(v, a) for v in volumes]) for a in ASYMMETRIES]
    kinds = [result_template_kind(v) for v in volumes]
    changes = template_changes(kinds)
    with _lock:
        fig, axes = plt.subplots(2, 7, figsize=(15, 4.4), constrained_layout=True)
        try:
            if changes:
                fig.suptitle("Dashed line: the template changed (" + "; ".join(
                    f"{labels[i - 1]} → {labels[i]}: {kinds[i - 1]} → {kinds[i]}" for i in changes)
                    + "); a change across it can be the template's", fontsize=8, color="tab:red")
            x = list(range(len(labels)))
            for ax, (title, unit, ivs) in zip(axes.flat, panels, strict=False):
                pts = [(i, iv) for i, iv in zip(x, ivs, strict=True) if iv is not None]
                if pts:
                    xs = [i for i, _ in pts]
                    ys = [iv.value for _, iv in pts]
                    # The interval is for the true value (the error model's bias removed): it need not
                    # contain the estimate, so it is drawn from its own ends, not as an error bar.
                    ax.plot(xs, ys, "o-", ms=4, lw=1)
                    ax.vlines(xs, [iv.lo for _, iv in pts], [iv.hi for _, iv in pts], lw=1, color="0.35")
                    ax.plot(xs + xs, [iv.lo for _, iv in pts] + [iv.hi for _, iv in pts], "_", ms=6, color="0.35")
                for i in changes:
                    ax.axvline(i - 0.5, ls="--", lw=1, color="tab:red")
                    ax.annotate(f"{kinds[i - 1]} → {kinds[i]}", (i - 0.5, 0.98), xycoords=ax.get_xaxis_transform(),
                                xytext=(-2, 0), textcoords="offset points", rotation=90, ha="right", va="top",
                                fontsize=6, color="tab:red")
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


__all__ = ["DEFAULT_TEMPLATE_KIND", "history_png", "result_template_kind", "subject_chart", "template_changes"]

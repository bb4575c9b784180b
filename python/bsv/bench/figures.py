"""PNG figures of a benchmark (matplotlib, Agg backend): RVE per segment against the paper (grouped
bars, one group per segment, one bar per condition x method plus the paper's NoEr and L5Ca bars and the
floor as a marker) and the trunk_limbs RVE histogram per condition."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .reference import CONDITIONS, PAPER, PAPER_ROWS


def _plt() -> Any:
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    return plt


def rve_bars(summary: Mapping[str, Any], path: str | Path, paper: bool = False) -> Path:
    """Grouped bars of mean RVE per segment (conditions x methods; with ``paper``, a run on FAUST, also the
    paper's NoEr/L5Ca bars: like for like only); floors as ticks."""
    plt = _plt()
    methods = [m for m in ("bsv", "trimesh") if m in summary] + sorted(set(summary) - {"bsv", "trimesh"})
    conds = [c for c in CONDITIONS if any(c in summary[m] for m in methods)]
    series = [(f"{c} {m}" if len(methods) > 1 else c, m, c) for m in methods for c in conds]
    nbars = len(series) + (2 if paper else 0)
    x = np.arange(len(PAPER_ROWS))
    width = 0.85 / nbars
    fig, ax = plt.subplots(figsize=(max(8.0, 1.1 * len(PAPER_ROWS) * nbars / 3), 4.8))
    cmap = plt.get_cmap("tab10")
    for k, (label, m, c) in enumerate(series):
        cells = [summary[m].get(c, {}).get(s) for s in PAPER_ROWS]
        mean = [np.nan if cl is None else cl["rve_mean"] for cl in cells]
        std = [0.0 if cl is None else cl["rve_std"] for cl in cells]
        xs = x + (k - nbars / 2 + 0.5) * width
        low = [min(s, m) if not np.isnan(m) else 0.0 for s, m in zip(std, mean, strict=True)]  # RVE >= 0: clip the bar
        ax.bar(xs, mean, width, yerr=[low, std], capsize=2, label=label, color=cmap(k % 10))
        floors = [np.nan if cl is None else cl.get("floor_rve_mean", np.nan) for cl in cells]
        if not np.all(np.isnan(floors)):
            ax.scatter(xs, floors, marker="_", s=120, color="black", zorder=3,
                       label="floor" if k == next(i for i, s in enumerate(series) if s[2] in ("cali", "l5ca")) else None)
    for j, (label, col, hatch) in enumerate((("paper NoEr", 0, "//"), ("paper L5Ca", 1, "xx")) if paper else ()):
        xs = x + (len(series) + j - nbars / 2 + 0.5) * width
        ax.bar(xs, [PAPER[s][col] for s in PAPER_ROWS], width, label=label, color="white", edgecolor="grey",
               hatch=hatch)
    ax.set_xticks(x)
    ax.set_xticklabels(PAPER_ROWS, rotation=30, ha="right")
    ax.set_ylabel("RVE (%)")
    ax.set_title("Relative volume error per segment (mean ± std) against the paper (FAUST)" if paper
                 else "Relative volume error per segment (mean ± std), synthetic bodies")
    ax.legend(fontsize=7, ncol=2)
    ax.grid(axis="y", alpha=0.3)
    fig.tight_layout()
    out = Path(path)
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return out


def trunk_limbs_histogram(table: Sequence[Mapping[str, Any]], path: str | Path, method: str = "bsv") -> Path:
    """One histogram panel per condition of the per-subject trunk_limbs RVE (floor RVE overlaid)."""
    plt = _plt()
    conds = [c for c in CONDITIONS if any(r["condition"] == c and r["method"] == method for r in table)]
    fig, axes = plt.subplots(1, max(1, len(conds)), figsize=(3.2 * max(1, len(conds)), 3.0), squeeze=False)
    for ax, c in zip(axes[0], conds, strict=False):
        rs = [r for r in table if r["condition"] == c and r["method"] == method and r["segment"] == "trunk_limbs"]
        v = [r["rve_pct"] for r in rs]
        fl = [r["floor_rve_pct"] for r in rs if r.get("floor_rve_pct") is not None]
        hi = max(v + fl + [0.1])
        bins = np.linspace(0.0, hi * 1.05, 12)
        ax.hist(v, bins=bins, color="tab:blue", alpha=0.8, label=method)
        if fl:
            ax.hist(fl, bins=bins, histtype="step", color="black", label="floor")
        ax.set_title(c)
        ax.set_xlabel("trunk_limbs RVE (%)")
        ax.legend(fontsize=7)
    axes[0][0].set_ylabel("subjects")
    fig.tight_layout()
    out = Path(path)
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return out


def kind_boxplot(values: Mapping[str, Sequence[Sequence[float]]], kinds: Sequence[str], path: str | Path, *,
                 ylabel: str, title: str, line: tuple[float, str | None]) -> Path:
    """Box plot of per-kind values, one box per condition and kind (``values[condition][k]`` are kind
    ``kinds[k]``'s values; an empty list draws nothing), with a horizontal ``line`` (y, legend label or
    None); written to ``path``."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(8.0, 4.0))
    width = 0.8 / max(1, len(values))
    for k, (cond, per_kind) in enumerate(values.items()):
        vals = [list(v) or [np.nan] for v in per_kind]
        pos = np.arange(len(kinds)) + (k - len(values) / 2 + 0.5) * width
        b = ax.boxplot(vals, positions=pos, widths=width * 0.9, patch_artist=True, showfliers=True)
        for patch in b["boxes"]:
            patch.set_facecolor(plt.get_cmap("tab10")(k))
        ax.plot([], [], color=plt.get_cmap("tab10")(k), lw=6, label=cond)
    y, label = line
    ax.axhline(y, color="k", ls="--" if label else "-", lw=1 if label else 0.8, label=label)
    ax.set_xticks(np.arange(len(kinds)), list(kinds))
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.legend(fontsize=8)
    fig.tight_layout()
    out = Path(path)
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return out

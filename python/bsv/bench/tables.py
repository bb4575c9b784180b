"""Results files and report tables: per-row CSV/JSON, the summary statistics, the paper-style table
(with the floor and the excess for calibrated conditions), the Point2PartVolume-style table, the signed
bias of trunk_limbs, timing, and the target check."""

from __future__ import annotations

import csv
import json
import math
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .common import Run, rve, signed_error
from .reference import CALIBRATED, CONDITIONS, MEASURED, P2PV_BUFF, P2PV_PDT13, P2PV_ROWS, PAPER_ROWS, paper_value

#: Columns of results.csv, in order.
CSV_COLUMNS: tuple[str, ...] = (
    "subject", "condition", "method", "segment", "estimated_l", "true_l", "rve_pct", "signed_pct",
    "floor_l", "floor_rve_pct", "excess_pct", "seconds", "cloud_far_2cm_pct", "cloud_far_10cm_pct",
    "unfiltered_far_2cm_pct", "unfiltered_far_10cm_pct",
)

#: Marks a table cell without a value (an en dash).
EMPTY_CELL = "\u2013"

#: Targets of the registration issue (percent; oracle labels): mean RVE of trunk_limbs and of every
#: segment in noer and l515, no single subject's segment worse than TARGET_WORST, |mean signed
#: trunk_limbs| in noer and l515, and the excess over the calibration floor in cali and l5ca.
TARGET_TRUNK_LIMBS = 0.5
TARGET_SEGMENT = 2.5
TARGET_WORST = 6.0
TARGET_EXCESS_TRUNK_LIMBS = 0.3
TARGET_EXCESS_SEGMENT = 1.5
TARGET_BIAS = 0.4


def rows(runs: Iterable[Run], segments: Sequence[str] = MEASURED) -> list[dict[str, Any]]:
    """One row per run x segment present in both the estimate and the truth (successful runs only)."""
    out = []
    for r in runs:
        if not r.ok:
            continue
        for seg in segments:
            if seg not in r.estimated_l or seg not in r.truth_l:
                continue
            est, tru = float(r.estimated_l[seg]), float(r.truth_l[seg])
            row: dict[str, Any] = {
                "subject": r.subject, "condition": r.condition, "method": r.method, "segment": seg,
                "estimated_l": est, "true_l": tru, "rve_pct": rve(est, tru), "signed_pct": signed_error(est, tru),
                "floor_l": None, "floor_rve_pct": None, "excess_pct": None, "seconds": r.seconds,
                "cloud_far_2cm_pct": r.cloud_far_2cm_pct, "cloud_far_10cm_pct": r.cloud_far_10cm_pct,
                "unfiltered_far_2cm_pct": r.unfiltered_far_2cm_pct, "unfiltered_far_10cm_pct": r.unfiltered_far_10cm_pct,
            }
            if seg in r.floor_l:
                fl = float(r.floor_l[seg])
                row["floor_l"] = fl
                row["floor_rve_pct"] = rve(fl, tru)
                row["excess_pct"] = row["rve_pct"] - row["floor_rve_pct"]
            out.append(row)
    return out


def write_csv(path: str | Path, table: Sequence[Mapping[str, Any]]) -> None:
    """results.csv: :data:`CSV_COLUMNS`, floats with 6 decimals, empty cells for absent values."""
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(CSV_COLUMNS)
        for row in table:
            w.writerow(["" if row.get(c) is None else (f"{row[c]:.6f}" if isinstance(row[c], float) else row[c])
                        for c in CSV_COLUMNS])


def read_csv(path: str | Path) -> list[dict[str, Any]]:
    """Reads results.csv back (numbers as float, empty cells as None)."""
    out = []
    with open(path, newline="") as fh:
        for row in csv.DictReader(fh):
            d: dict[str, Any] = {}
            for k, v in row.items():
                if k in ("subject", "condition", "method", "segment"):
                    d[k] = v
                else:
                    d[k] = None if v == "" else float(v)
            out.append(d)
    return out


def _stats(values: list[float]) -> tuple[float, float]:
    if not values:
        return math.nan, math.nan
    a = np.asarray(values, dtype=np.float64)
    return float(a.mean()), float(a.std(ddof=1)) if len(a) > 1 else 0.0


def summarise(table: Sequence[Mapping[str, Any]]) -> dict[str, dict[str, dict[str, dict[str, float]]]]:
    """summary[method][condition][segment] = n, rve_mean, rve_std, rve_max, signed_mean, signed_std and,
    with a floor, floor_rve_mean, floor_signed_mean, excess_mean (mean of per-subject RVE - floor RVE)."""
    groups: dict[tuple[str, str, str], list[Mapping[str, Any]]] = {}
    for row in table:
        groups.setdefault((row["method"], row["condition"], row["segment"]), []).append(row)
    out: dict[str, dict[str, dict[str, dict[str, float]]]] = {}
    for (m, c, s), rs in groups.items():
        rm, rsd = _stats([r["rve_pct"] for r in rs])
        sm, ssd = _stats([r["signed_pct"] for r in rs])
        cell = {"n": float(len(rs)), "rve_mean": rm, "rve_std": rsd, "rve_max": max(r["rve_pct"] for r in rs),
                "signed_mean": sm, "signed_std": ssd}
        fl = [r for r in rs if r.get("floor_rve_pct") is not None]
        if fl:
            cell["floor_rve_mean"] = _stats([r["floor_rve_pct"] for r in fl])[0]
            cell["floor_signed_mean"] = _stats([signed_error(r["floor_l"], r["true_l"]) for r in fl])[0]
            cell["excess_mean"] = _stats([r["excess_pct"] for r in fl])[0]
        out.setdefault(m, {}).setdefault(c, {})[s] = cell
    return out


def _present(summary: Mapping[str, Any], key: str) -> list[str]:
    order = {"conditions": list(CONDITIONS), "methods": ["bsv", "trimesh"]}[key]
    have = set(summary) if key == "methods" else {c for m in summary.values() for c in m}
    return [x for x in order if x in have] + sorted(have - set(order))


def _mark(ours: float, ref: float | None, lower_is_better: bool = True) -> str:
    if ref is None or math.isnan(ours):
        return ""
    better = ours < ref if lower_is_better else ours > ref
    return " ✓" if better else " ✗"


def paper_table(summary: Mapping[str, Any], like_for_like: bool = False) -> str:
    """Markdown: mean ± std RVE (%) per segment (rows) and condition x method (columns), the paper's FAUST
    value beside each cell, and for cali/l5ca the floor and the excess over it. ``like_for_like`` (a run on
    FAUST itself): the cell is marked ✓ better / ✗ worse than the paper; otherwise (synthetic bodies) the
    paper's value is context only and nothing is marked."""
    conds, methods = _present(summary, "conditions"), _present(summary, "methods")
    head = ["segment"]
    for c in conds:
        for m in methods:
            head.append(f"{c} {m}" if len(methods) > 1 else c)
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for seg in PAPER_ROWS:
        cells = [seg]
        for c in conds:
            for m in methods:
                cell = summary.get(m, {}).get(c, {}).get(seg)
                if cell is None:
                    cells.append(EMPTY_CELL)
                    continue
                ref = paper_value(seg, c)
                txt = f"{cell['rve_mean']:.2f} ± {cell['rve_std']:.2f}"
                if ref is not None:
                    txt += f" ({ref:.2f}){_mark(cell['rve_mean'], ref) if like_for_like else ''}"
                if "floor_rve_mean" in cell:
                    txt += f"<br>floor {cell['floor_rve_mean']:.2f}, excess {cell['excess_mean']:+.2f}"
                cells.append(txt)
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def p2pv_table(summary: Mapping[str, Any]) -> str:
    """Markdown: accuracy = 100 - mean RVE (%) for torso, arms, legs, trunk_limbs per condition x method,
    beside Point2PartVolume's BUFF and PDT13 accuracies, for context only: those are other data sets, so no
    cell is marked better or worse."""
    conds, methods = _present(summary, "conditions"), _present(summary, "methods")
    head = ["part"] + [f"{c} {m}" if len(methods) > 1 else c for c in conds for m in methods]
    head += ["P2PV on BUFF (other data)", "P2PV on PDT13 (other data)"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for part in P2PV_ROWS:
        cells = [part]
        for c in conds:
            for m in methods:
                cell = summary.get(m, {}).get(c, {}).get(part)
                if cell is None:
                    cells.append(EMPTY_CELL)
                else:
                    acc = 100.0 - cell["rve_mean"]
                    cells.append(f"{acc:.2f}")
        cells += [f"{P2PV_BUFF[part]:.2f}", f"{P2PV_PDT13[part]:.2f}"]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def bias_table(summary: Mapping[str, Any], segment: str = "trunk_limbs") -> str:
    """Markdown: mean ± std signed error (%) of ``segment`` per condition x method (and the floor's)."""
    conds, methods = _present(summary, "conditions"), _present(summary, "methods")
    lines = ["| condition | " + " | ".join(methods) + " | floor |", "|---|" + "---|" * (len(methods) + 1)]
    for c in conds:
        cells = [c]
        floor = EMPTY_CELL
        for m in methods:
            cell = summary.get(m, {}).get(c, {}).get(segment)
            if cell is None:
                cells.append(EMPTY_CELL)
                continue
            cells.append(f"{cell['signed_mean']:+.2f} ± {cell['signed_std']:.2f}")
            if "floor_signed_mean" in cell:
                floor = f"{cell['floor_signed_mean']:+.2f}"
        lines.append("| " + " | ".join([*cells, floor]) + " |")
    return "\n".join(lines)


def signed_table(summary: Mapping[str, Any], method: str = "bsv") -> str:
    """Markdown: mean signed error (%) of every segment (rows) per condition (columns) for ``method``."""
    s = summary.get(method, {})
    conds = [c for c in _present(summary, "conditions") if c in s]
    lines = ["| segment | " + " | ".join(conds) + " |", "|---|" + "---|" * len(conds)]
    for seg in PAPER_ROWS:
        cells = [f"{s[c][seg]['signed_mean']:+.2f}" if seg in s[c] else EMPTY_CELL for c in conds]
        lines.append(f"| {seg} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def worst_table(table: Sequence[Mapping[str, Any]], method: str = "bsv") -> str:
    """Markdown: per segment (rows) and condition (columns) the worst subject's signed error (%) and
    who it is: what a mean hides."""
    worst: dict[tuple[str, str], Mapping[str, Any]] = {}
    for r in table:
        if r["method"] != method:
            continue
        key = (r["segment"], r["condition"])
        if key not in worst or r["rve_pct"] > worst[key]["rve_pct"]:
            worst[key] = r
    conds = [c for c in CONDITIONS if any(k[1] == c for k in worst)]
    lines = ["| segment | " + " | ".join(conds) + " |", "|---|" + "---|" * len(conds)]
    for seg in PAPER_ROWS:
        cells = []
        for c in conds:
            w = worst.get((seg, c))
            cells.append(EMPTY_CELL if w is None else f"{w['signed_pct']:+.2f} ({w['subject'].removeprefix('subject_')})")
        lines.append(f"| {seg} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def timing_table(runs: Sequence[Run]) -> str:
    """Markdown: registration seconds per subject (rows) and condition x method, with the mean and the
    median; with the peer, the median over subjects of each subject's peer / bsv time ratio (the same
    cloud, the same run: the speed-up that machine load does not move)."""
    conds = [c for c in CONDITIONS if any(r.condition == c for r in runs)]
    methods = [m for m in ("bsv", "trimesh") if any(r.method == m for r in runs)]
    cols = [(c, m) for c in conds for m in methods]
    head = ["subject"] + [f"{c} {m}" if len(methods) > 1 else c for c, m in cols]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    by = {(r.subject, r.condition, r.method): r for r in runs}
    subjects = sorted({r.subject for r in runs})
    for s in subjects:
        cells = [s]
        for c, m in cols:
            r = by.get((s, c, m))
            cells.append("failed" if r is None or not r.ok else f"{r.seconds:.2f}")
        lines.append("| " + " | ".join(cells) + " |")
    means = ["**mean**"]
    for c, m in cols:
        v = [r.seconds for r in runs if r.condition == c and r.method == m and r.ok]
        means.append(f"{np.mean(v):.2f}" if v else EMPTY_CELL)
    lines.append("| " + " | ".join(means) + " |")
    medians = ["**median**"]
    for c, m in cols:
        v = [r.seconds for r in runs if r.condition == c and r.method == m and r.ok]
        medians.append(f"{np.median(v):.2f}" if v else EMPTY_CELL)
    lines.append("| " + " | ".join(medians) + " |")
    if "trimesh" in methods and "bsv" in methods:
        ratios = ["**trimesh / bsv** (median of per-subject ratios)"]
        for c, m in cols:
            q = [by[(s, c, "trimesh")].seconds / by[(s, c, "bsv")].seconds for s in subjects
                 if all((s, c, k) in by and by[(s, c, k)].ok and by[(s, c, k)].seconds > 0 for k in ("bsv", "trimesh"))]
            ratios.append(f"{np.median(q):.1f}x" if m == "trimesh" and q else "")
        lines.append("| " + " | ".join(ratios) + " |")
    return "\n".join(lines)


def _mean_max(values: Sequence[float | None]) -> str:
    v = [float(x) for x in values if x is not None]
    return f"{np.mean(v):.2f} ({max(v):.2f})" if v else EMPTY_CELL


def cloud_table(runs: Sequence[Run]) -> str:
    """Markdown: per condition x method, the mean (and worst) percent of the registered cloud's points
    farther than 2 cm and than 10 cm from the true body surface, and the same before the outlier
    removal when measured (lab path); empty when no run measured it."""
    measured = [r for r in runs if r.cloud_far_2cm_pct is not None and r.cloud_far_10cm_pct is not None]
    if not measured:
        return ""
    head = ("| condition | method | runs | > 2 cm mean (max) | > 10 cm mean (max) | uncleaned > 2 cm | "
            "uncleaned > 10 cm |")
    lines = [head, "|---|---|---|---|---|---|---|"]
    for c in [c for c in CONDITIONS if any(r.condition == c for r in measured)]:
        for m in sorted({r.method for r in measured if r.condition == c}):
            rs = [r for r in measured if r.condition == c and r.method == m]
            cells = [_mean_max([r.cloud_far_2cm_pct for r in rs]), _mean_max([r.cloud_far_10cm_pct for r in rs]),
                     _mean_max([r.unfiltered_far_2cm_pct for r in rs]),
                     _mean_max([r.unfiltered_far_10cm_pct for r in rs])]
            lines.append(f"| {c} | {m} | {len(rs)} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def target_check(summary: Mapping[str, Any], method: str = "bsv") -> list[tuple[str, bool, str]]:
    """The issue's accuracy targets for ``method``: (target, met, measured evidence)."""
    out: list[tuple[str, bool, str]] = []
    s = summary.get(method, {})
    segs = [r for r in PAPER_ROWS if r != "trunk_limbs"]
    for c in ("noer", "l515"):
        if c not in s:
            continue
        tl = s[c].get("trunk_limbs", {}).get("rve_mean", math.nan)
        out.append((f"{c}: trunk_limbs mean RVE <= {TARGET_TRUNK_LIMBS} %", tl <= TARGET_TRUNK_LIMBS, f"{tl:.2f} %"))
        worst = max(segs, key=lambda g: s[c].get(g, {}).get("rve_mean", -1.0))
        wv = s[c].get(worst, {}).get("rve_mean", math.nan)
        out.append((f"{c}: every segment mean RVE <= {TARGET_SEGMENT} %", wv <= TARGET_SEGMENT,
                    f"worst {worst} {wv:.2f} %"))
        one = max(segs, key=lambda g: s[c].get(g, {}).get("rve_max", -1.0))
        ov = s[c].get(one, {}).get("rve_max", math.nan)
        out.append((f"{c}: no subject's segment worse than {TARGET_WORST} %", ov <= TARGET_WORST,
                    f"worst {one} {ov:.2f} %"))
        if "trunk_limbs" in s[c]:
            b = s[c]["trunk_limbs"]["signed_mean"]
            out.append((f"{c}: trunk_limbs mean signed error within ±{TARGET_BIAS} %", abs(b) <= TARGET_BIAS,
                        f"{b:+.2f} %"))
    for c in sorted(CALIBRATED):
        if c not in s or "excess_mean" not in s[c].get("trunk_limbs", {}):
            continue
        ex = s[c]["trunk_limbs"]["excess_mean"]
        out.append((f"{c}: trunk_limbs excess over floor <= {TARGET_EXCESS_TRUNK_LIMBS} %",
                    ex <= TARGET_EXCESS_TRUNK_LIMBS, f"{ex:+.2f} %"))
        worst = max(segs, key=lambda g: s[c].get(g, {}).get("excess_mean", -math.inf))
        wv = s[c].get(worst, {}).get("excess_mean", math.nan)
        out.append((f"{c}: every segment excess over floor <= {TARGET_EXCESS_SEGMENT} %",
                    wv <= TARGET_EXCESS_SEGMENT, f"worst {worst} {wv:+.2f} %"))
    return out


def targets_md(checks: Sequence[tuple[str, bool, str]]) -> str:
    """Markdown list of the target checks."""
    return "\n".join(f"- {'met' if ok else '**MISSED**'}: {name} (measured {ev})" for name, ok, ev in checks)


def write_json(path: str | Path, doc: Mapping[str, Any]) -> None:
    """Writes a JSON document (NaN written as null)."""
    Path(path).write_text(json.dumps(_clean(doc), indent=1, sort_keys=False) + "\n")


def _clean(x: Any) -> Any:
    if isinstance(x, float):
        return None if math.isnan(x) or math.isinf(x) else x
    if isinstance(x, dict):
        return {str(k): _clean(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_clean(v) for v in x]
    if isinstance(x, (np.floating, np.integer)):
        return _clean(x.item())
    if isinstance(x, np.ndarray):
        return _clean(x.tolist())
    return x


def coverage_md(runs: Sequence[Run]) -> tuple[list[dict[str, Any]], list[str]]:
    """Coverage rows of the 95 % intervals per condition and their report section (:mod:`bsv.bench.coverage`,
    with the packaged error model); empty when no run kept the intervals' ingredients."""
    from ..uncertainty import error_models
    from .coverage import coverage_markdown, coverage_rows, refinement_markdown, refinement_rows

    models = error_models()
    table = coverage_rows(runs, models)
    return table, coverage_markdown(table, models) + refinement_markdown(refinement_rows(runs))

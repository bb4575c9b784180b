"""``bsv bench compare``: two sets of ``bench synth`` runs of the same bodies, segment by segment.

The camera path's headline is its gap to the oracle labels on the same bodies: a segment's mean RVE with the
camera's labels less its mean RVE with the scanner's true labels (issue 12's target: at most
:data:`DEFAULT_MAX_GAP` point). The same table answers "did this change help?" for two engines run on one
cohort. Runs are paired by (cohort seed, subject, condition); per condition and segment the table gives each
set's mean RVE, mean signed error and worst subject's signed error, the difference of the mean RVEs (first set
less second) with its paired standard error, and marks a difference above ``max_gap``. The last row, ``limbs``,
is each run's mean RVE over the eight limb segments (upper arms, forearms, thighs, shins), averaged. Under each
condition's table, the boundary loops (:mod:`bsv.bench.boundaries`: how far each fitted loop lies from the true one
along the limb, left and right pooled) give each set's mean and scatter: what places a segment's volume. Then what
each loop's scatter costs each limb (:func:`loop_costs`): per set, the limb's signed error fitted on its two loops'
errors, and the mean RVE left were one loop placed at its mean (the other as it is): where a gap comes from.

Two sets are compared only when they hold the same bodies: every paired run must carry the same true volumes
(the bodies are regenerated from the seed by each run), else :class:`bsv.errors.BenchError` names the subject
and what to run instead. A pair in which either registration failed is left out and counted.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..biomech.tables import JOINTS
from ..bodies.variants import LIMB_SEGMENTS
from ..errors import BenchError
from .boundaries import ALL_KINDS as LOOP_KINDS
from .boundaries import INFO_KEY as LOOPS_KEY
from .common import signed_error
from .reference import ordered_conditions

#: The issue's target for the camera path: at most this many points of mean RVE above the oracle labels.
DEFAULT_MAX_GAP = 1.0
#: The row holding each run's mean RVE over :data:`LIMB_SEGMENTS`.
LIMBS_ROW = "limbs"
#: The table's rows, in order.
ROWS: tuple[str, ...] = ("trunk_limbs", "torso", *LIMB_SEGMENTS, LIMBS_ROW)
#: The files ``write_compare`` writes into its output folder.
OUTPUT_FILES: tuple[str, ...] = ("compare.md", "compare.json", "compare.png")
#: The limb kinds :func:`loop_costs` attributes, proximal to distal, each with its (proximal, distal) loop kinds
#: from :data:`bsv.biomech.tables.JOINTS` (a joint's loop separates its first segment from its second).
LIMB_LOOPS: dict[str, tuple[str, str]] = {
    limb: (next(j[:-2] for j, (_, b) in JOINTS.items() if b == f"{limb}_l"),
           next(j[:-2] for j, (a, _) in JOINTS.items() if a == f"{limb}_l"))
    for limb in dict.fromkeys(s[:-2] for s in LIMB_SEGMENTS)
}
#: :func:`loop_costs` fits a limb's error on its loops only from at least this many limbs (left and right count
#: apart).
MIN_COST_LIMBS = 6
#: Two true volumes (litres) closer than this are the same body's.
SAME_VOLUME_L = 1e-6

Key = tuple[int, str, str]


@dataclass(frozen=True)
class RunSet:
    """The runs of one or more ``bench synth`` output folders."""

    #: What the set is called in the table.
    label: str
    #: The folders read.
    dirs: tuple[Path, ...]
    #: The ``config`` block of each folder's results.json, by cohort seed.
    configs: dict[int, dict[str, Any]]
    #: The method's runs by (cohort seed, subject, condition), as results.json holds them.
    runs: dict[Key, dict[str, Any]]


def _read_results(d: Path) -> dict[str, Any]:
    path = d / "results.json"
    try:
        doc = json.loads(path.read_text())
    except FileNotFoundError:
        raise BenchError(f"{path}: not found; give the --out folder of a finished `bsv bench synth` run") from None
    except (OSError, ValueError) as exc:
        raise BenchError(f"{path}: not readable as a benchmark's results ({exc}); run `bsv bench synth` into "
                         "that folder again") from exc
    if not isinstance(doc, dict) or not isinstance(doc.get("config"), dict) or not isinstance(doc.get("runs"), list):
        raise BenchError(f"{path}: no config and runs in it; give the --out folder of a `bsv bench synth` run")
    if "seed" not in doc["config"] or "segmentation" not in doc["config"]:
        raise BenchError(f"{path}: not a `bsv bench synth` run (its config has no cohort seed); compare takes "
                         "synthetic-cohort runs, whose bodies are known")
    return doc


def read_runs(dirs: Sequence[str | Path], label: str | None = None, method: str = "bsv") -> RunSet:
    """The ``method``'s runs of the ``bench synth`` output folders ``dirs``; ``label`` (default: the first
    folder's name). :class:`bsv.errors.BenchError` naming the folder for one that is missing or not a
    ``bench synth`` output, or for two folders of the same cohort seed."""
    if not dirs:
        raise BenchError("compare: give at least one `bsv bench synth` output folder per set")
    paths = tuple(Path(d) for d in dirs)
    configs: dict[int, dict[str, Any]] = {}
    runs: dict[Key, dict[str, Any]] = {}
    where: dict[int, Path] = {}
    for d in paths:
        doc = _read_results(d)
        try:
            seed = int(doc["config"]["seed"])
        except (TypeError, ValueError):
            raise BenchError(f"{d / 'results.json'}: its cohort seed {doc['config']['seed']!r} is not a whole number; "
                             "run `bsv bench synth` into that folder again") from None
        if seed in configs:
            raise BenchError(f"{d} and {where[seed]} both hold cohort seed {seed}: give each seed once per set")
        configs[seed], where[seed] = doc["config"], d
        for r in doc["runs"]:
            if isinstance(r, dict) and r.get("method") == method and "subject" in r and "condition" in r:
                runs[(seed, str(r["subject"]), str(r["condition"]))] = r
    return RunSet(label or paths[0].name, paths, configs, runs)


def default_labels(a: RunSet, b: RunSet) -> tuple[str, str]:
    """The sets' labels: their segmentation ("camera", "oracle") when that is what differs, else their own
    (marked "(runs)" and "(against)" when those are the same)."""
    seg_a = {str(c.get("segmentation")) for c in a.configs.values()}
    seg_b = {str(c.get("segmentation")) for c in b.configs.values()}
    if len(seg_a) == 1 and len(seg_b) == 1 and seg_a != seg_b:
        return seg_a.pop(), seg_b.pop()
    if a.label == b.label:  # e.g. two engines' runs of one seed, each in a folder of the same name
        return f"{a.label} (runs)", f"{b.label} (against)"
    return a.label, b.label


def pairs(a: RunSet, b: RunSet) -> list[Key]:
    """The (seed, subject, condition) keys both sets ran, checked to be the same bodies (equal true volumes);
    :class:`bsv.errors.BenchError` when none are shared or a shared key's bodies differ."""
    keys = sorted(set(a.runs) & set(b.runs))
    if not keys:
        raise BenchError(f"compare: {a.label} (seeds {sorted(a.configs)}) and {b.label} (seeds {sorted(b.configs)}) "
                         "share no (seed, subject, condition): run both on the same --seed, --n and --conditions")
    for k in keys:
        for seg in ROWS[:-1]:
            ta, tb = _volume(a.runs[k].get("truth_l"), seg), _volume(b.runs[k].get("truth_l"), seg)
            if ta is not None and tb is not None and abs(ta - tb) > SAME_VOLUME_L:
                raise BenchError(
                    f"compare: seed {k[0]} {k[1]} is not the same body in {a.label} and {b.label} (true {seg} "
                    f"{ta:.4f} L against {tb:.4f} L): compare runs of one cohort (the same --seed, --cohort, "
                    "--macros, --bmi-shift and pose ranges)")
    return keys


def _errors(run: Mapping[str, Any], row: str) -> tuple[float, float]:
    """(RVE, signed error) of a run's row, %: for :data:`LIMBS_ROW` the means over the eight limb segments."""
    if row == LIMBS_ROW:
        e = np.array([_errors(run, s)[1] for s in LIMB_SEGMENTS])
        return float(np.mean(np.abs(e))), float(np.mean(e))
    e1 = signed_error(float(run["estimated_l"][row]), float(run["truth_l"][row]))
    return abs(e1), e1


def _number(table: Any, key: str) -> float | None:
    """``table[key]`` as a float when ``table`` is a mapping holding a finite number there, else None."""
    v = table.get(key) if isinstance(table, Mapping) else None
    return float(v) if isinstance(v, (int, float)) and math.isfinite(v) else None


def _volume(table: Any, segment: str) -> float | None:
    """A run's volume (litres) of ``segment`` in its ``estimated_l`` or ``truth_l`` table, None when it is missing
    or not a finite positive number."""
    v = _number(table, segment)
    return v if v is not None and v > 0 else None


def _has(run: Mapping[str, Any], row: str) -> bool:
    """Whether a successful run holds the row's estimated and true volumes."""
    segs = LIMB_SEGMENTS if row == LIMBS_ROW else (row,)
    return bool(run.get("ok")) and all(_volume(run.get("estimated_l"), s) is not None
                                       and _volume(run.get("truth_l"), s) is not None for s in segs)


def _side(runs: Sequence[Mapping[str, Any]], keys: Sequence[Key], row: str) -> dict[str, Any]:
    """One set's cell: mean RVE, mean signed error, and the worst run's signed error (for :data:`LIMBS_ROW`:
    its mean RVE over the limbs) and which run it is."""
    e = np.array([_errors(r, row) for r in runs])
    worst = int(np.argmax(e[:, 0]))
    return {"mean_rve": float(np.mean(e[:, 0])), "signed": float(np.mean(e[:, 1])),
            "worst": float(e[worst, 0] if row == LIMBS_ROW else e[worst, 1]),
            "worst_run": f"seed {keys[worst][0]} {keys[worst][1]}"}


def _loop_mm(run: Mapping[str, Any], name: str) -> float | None:
    """A run's boundary error (mm) of loop ``name`` (e.g. ``elbow_l``), None when it has none."""
    info = run.get("info")
    return _number(info.get(LOOPS_KEY) if isinstance(info, Mapping) else None, name)


def compare_loops(ra: Sequence[Mapping[str, Any]], rb: Sequence[Mapping[str, Any]], la: str, lb: str,
                  ) -> dict[str, Any]:
    """Per loop kind of :data:`LOOP_KINDS` (left and right pooled) over paired runs ``ra`` / ``rb``: ``n`` and each
    set's ``mean`` and ``sd`` (mm, + = the fitted loop distal of the true one), from the loops both runs of a pair
    measured; a kind with fewer than two such loops is left out."""
    out: dict[str, Any] = {}
    for kind in LOOP_KINDS:
        va, vb = [], []
        for x, y in zip(ra, rb, strict=True):
            for side in ("l", "r"):
                p, q = _loop_mm(x, f"{kind}_{side}"), _loop_mm(y, f"{kind}_{side}")
                if p is not None and q is not None:
                    va.append(p)
                    vb.append(q)
        if len(va) >= 2:
            out[kind] = {"n": len(va), la: {"mean": float(np.mean(va)), "sd": float(np.std(va, ddof=1))},
                         lb: {"mean": float(np.mean(vb)), "sd": float(np.std(vb, ddof=1))}}
    return out


def _limb_rows(runs: Sequence[Mapping[str, Any]], limb: str) -> list[tuple[float, float, float] | None]:
    """Per run and side (l, r in turn): (signed error %, proximal loop mm, distal loop mm) of ``limb``, or None
    where the run lacks the segment's volumes or either loop."""
    near, far = LIMB_LOOPS[limb]
    out: list[tuple[float, float, float] | None] = []
    for run in runs:
        for side in ("l", "r"):
            seg = f"{limb}_{side}"
            p, d = _loop_mm(run, f"{near}_{side}"), _loop_mm(run, f"{far}_{side}")
            out.append(None if p is None or d is None or not _has(run, seg) else (_errors(run, seg)[1], p, d))
    return out


def _costs(rows: Sequence[tuple[float, float, float]]) -> dict[str, float]:
    """The least-squares fit of a limb's signed error on its proximal and distal loop errors (``per_mm``: % per mm
    of each, + = the loop distal), its mean RVE, and the mean RVE with each loop's scatter taken out (the loop at
    its mean, the error moved by its fitted share) and with both."""
    e, p, d = (np.array(c, dtype=np.float64) for c in zip(*rows, strict=True))
    design = np.column_stack([np.ones_like(e), p, d])
    coef, *_ = np.linalg.lstsq(design, e, rcond=None)
    share_p, share_d = coef[1] * (p - p.mean()), coef[2] * (d - d.mean())
    return {"n": len(e), "per_mm_proximal": float(coef[1]), "per_mm_distal": float(coef[2]),
            "rve": float(np.mean(np.abs(e))), "rve_without_proximal": float(np.mean(np.abs(e - share_p))),
            "rve_without_distal": float(np.mean(np.abs(e - share_d))),
            "rve_without_both": float(np.mean(np.abs(e - share_p - share_d)))}


def loop_costs(ra: Sequence[Mapping[str, Any]], rb: Sequence[Mapping[str, Any]], la: str, lb: str,
               ) -> dict[str, Any]:
    """What each loop's scatter costs each limb kind of :data:`LIMB_LOOPS` (left and right pooled) over paired
    runs ``ra`` / ``rb``, from the limbs whose volumes and two loops both runs of a pair hold: per kind its
    ``proximal`` and ``distal`` loop kinds and per set the fit of :func:`_costs`. A kind with fewer than
    :data:`MIN_COST_LIMBS` such limbs is left out (three coefficients need more)."""
    out: dict[str, Any] = {}
    for limb, (near, far) in LIMB_LOOPS.items():
        both = [(x, y) for x, y in zip(_limb_rows(ra, limb), _limb_rows(rb, limb), strict=True)
                if x is not None and y is not None]
        if len(both) >= MIN_COST_LIMBS:
            out[limb] = {"proximal": near, "distal": far, la: _costs([x for x, _ in both]),
                         lb: _costs([y for _, y in both])}
    return out


def compare_runs(a: RunSet, b: RunSet, max_gap: float = DEFAULT_MAX_GAP,
                 labels: tuple[str, str] | None = None) -> dict[str, Any]:
    """The comparison of ``a`` against ``b`` (JSON-ready; see the module notes): ``labels``, ``max_gap``, and
    per condition the pairs used, the pairs left out because a run failed (by set) and one record per row of
    :data:`ROWS`: each set's ``mean_rve``, ``signed``, ``worst`` (signed %, and which run), the ``gap`` (first
    less second, points), its paired standard error ``gap_se`` (None from one pair) and ``over`` (gap >
    ``max_gap``); ``loops``, the boundary loops of the pairs (:func:`compare_loops`); and ``loop_costs``, what
    each loop's scatter costs each limb (:func:`loop_costs`)."""
    if not (np.isfinite(max_gap) and max_gap >= 0):
        raise BenchError(f"compare: max_gap must be a number of points >= 0, got {max_gap!r}")
    la, lb = labels or default_labels(a, b)
    if la == lb:
        raise BenchError(f"compare: the two sets need different labels, got {la!r} twice")
    keys = pairs(a, b)
    out: dict[str, Any] = {"labels": [la, lb], "max_gap": float(max_gap),
                           "dirs": [[str(d) for d in a.dirs], [str(d) for d in b.dirs]], "conditions": {}}
    for cond in ordered_conditions({k[2] for k in keys}):
        ck = [k for k in keys if k[2] == cond]
        failed = {la: sum(not a.runs[k].get("ok") for k in ck), lb: sum(not b.runs[k].get("ok") for k in ck)}
        rows: dict[str, Any] = {}
        for row in ROWS:
            kk = [k for k in ck if _has(a.runs[k], row) and _has(b.runs[k], row)]
            if not kk:
                continue
            ra, rb = [a.runs[k] for k in kk], [b.runs[k] for k in kk]
            sa, sb = _side(ra, kk, row), _side(rb, kk, row)
            d = np.array([_errors(r, row)[0] for r in ra]) - np.array([_errors(r, row)[0] for r in rb])
            se = float(np.std(d, ddof=1) / np.sqrt(len(d))) if len(d) > 1 else None
            gap = sa["mean_rve"] - sb["mean_rve"]
            rows[row] = {"n": len(kk), la: sa, lb: sb, "gap": float(gap), "gap_se": se, "over": bool(gap > max_gap)}
        ok = [k for k in ck if a.runs[k].get("ok") and b.runs[k].get("ok")]
        ra, rb = [a.runs[k] for k in ok], [b.runs[k] for k in ok]
        out["conditions"][cond] = {"pairs": len(ok), "failed": failed, "rows": rows,
                                   "loops": compare_loops(ra, rb, la, lb), "loop_costs": loop_costs(ra, rb, la, lb)}
    return out


def _cell(side: Mapping[str, Any]) -> str:
    return f"{side['mean_rve']:.2f} / {side['signed']:+.2f} / {side['worst']:+.1f}"


def compare_markdown(result: Mapping[str, Any]) -> str:
    """The comparison (:func:`compare_runs`) as markdown: one table per condition, the cells over the gap
    in bold, and a line listing them."""
    la, lb = result["labels"]
    md = [(f"Mean RVE / mean signed / worst subject's signed error (%), {la} against {lb} on the same bodies; "
           f"gap = {la} less {lb} (points, +- its paired standard error); **bold**: more than "
           f"{result['max_gap']:g} point. `{LIMBS_ROW}`: each run's mean RVE and mean signed error over the eight limb "
           "segments; its worst is the largest run's mean RVE."), ""]
    over = []
    for cond, c in result["conditions"].items():
        fails = ", ".join(f"{n} {lab}" for lab, n in c["failed"].items() if n)
        md += [f"### {cond} ({c['pairs']} pairs{'; failed: ' + fails if fails else ''})", "",
               f"| segment | {la} | {lb} | gap |", "|---|---|---|---|"]
        for row, r in c["rows"].items():
            gap = f"{r['gap']:+.2f} +- " + ("n/a" if r["gap_se"] is None else f"{r['gap_se']:.2f}")
            if r["over"]:
                gap = f"**{gap}**"
                over.append(f"{row} {cond} ({r['gap']:+.2f})")
            md.append(f"| {row} | {_cell(r[la])} | {_cell(r[lb])} | {gap} |")
        md.append("")
        if c.get("loops"):
            md += [("Boundary loops: where each fitted loop lies from the true one along the limb, mm (+ distal; "
                    "left and right pooled), mean +- sd:"), "", f"| loop | {la} | {lb} |", "|---|---|---|"]
            md += [f"| {kind} ({r['n']}) | {r[la]['mean']:+.1f} +- {r[la]['sd']:.1f} | "
                   f"{r[lb]['mean']:+.1f} +- {r[lb]['sd']:.1f} |" for kind, r in c["loops"].items()]
            md.append("")
        if c.get("loop_costs"):
            md += [("What each loop's scatter costs (left and right pooled): the limb's signed error fitted on its "
                    "two loops' errors, % per mm of each (+ = the loop distal); its mean RVE, and the mean RVE were "
                    "the proximal loop, the distal loop or both placed at their mean:"), "",
                   "| limb | set | % per mm proximal, distal | mean RVE | without proximal | without distal | without both |",
                   "|---|---|---|---|---|---|---|"]
            for limb, r in c["loop_costs"].items():
                for lab in (la, lb):
                    q = r[lab]
                    md.append(f"| {limb} ({r['proximal']}, {r['distal']}; {q['n']}) | {lab} | "
                              f"{q['per_mm_proximal']:+.2f}, {q['per_mm_distal']:+.2f} | {q['rve']:.2f} | "
                              f"{q['rve_without_proximal']:.2f} | {q['rve_without_distal']:.2f} | "
                              f"{q['rve_without_both']:.2f} |")
            md.append("")
    md.append(f"Over {result['max_gap']:g} point: {', '.join(over)}." if over
              else f"Every gap is within {result['max_gap']:g} point.")
    return "\n".join(md) + "\n"


def compare_figure(result: Mapping[str, Any], path: str | Path) -> Path:
    """Per condition, each segment's mean RVE in both sets (bars) and the gap (printed above, red when over
    ``max_gap``), as a PNG."""
    from .figures import _plt

    plt = _plt()
    la, lb = result["labels"]
    conds = list(result["conditions"].items())
    fig, axes = plt.subplots(len(conds), 1, figsize=(10.0, 3.4 * len(conds)), squeeze=False)
    for ax, (cond, c) in zip(axes[:, 0], conds, strict=True):
        names = list(c["rows"])
        x = np.arange(len(names))
        va = [c["rows"][n][la]["mean_rve"] for n in names]
        vb = [c["rows"][n][lb]["mean_rve"] for n in names]
        ax.bar(x - 0.2, va, 0.4, label=la, color="tab:blue")
        ax.bar(x + 0.2, vb, 0.4, label=lb, color="tab:grey")
        for xi, n in zip(x, names, strict=True):
            r = c["rows"][n]
            ax.annotate(f"{r['gap']:+.2f}", (xi, max(r[la]["mean_rve"], r[lb]["mean_rve"])), xytext=(0, 3),
                        textcoords="offset points", ha="center", fontsize=8,
                        color="tab:red" if r["over"] else "black", fontweight="bold" if r["over"] else "normal")
        ax.set_ylim(0.0, 1.18 * max([*va, *vb, 0.1]))
        ax.set_xticks(x)
        ax.set_xticklabels(names, rotation=30, ha="right")
        ax.set_ylabel("mean RVE (%)")
        ax.set_title(f"{cond}: {la} against {lb} ({c['pairs']} pairs; gap above each pair, red: over "
                     f"{result['max_gap']:g} point)", fontsize=9)
        ax.legend(fontsize=8)
        ax.grid(axis="y", alpha=0.3)
    fig.tight_layout()
    out = Path(path)
    fig.savefig(out, dpi=110, format="png")
    plt.close(fig)
    return out


def existing(out: str | Path) -> list[str]:
    """The files of :data:`OUTPUT_FILES` already in ``out``."""
    return [n for n in OUTPUT_FILES if (Path(out) / n).exists()]


def write_compare(out: str | Path, result: Mapping[str, Any], overwrite: bool = False) -> list[Path]:
    """Writes compare.md, compare.json and compare.png into ``out`` (created). Existing ones are refused
    (:class:`bsv.errors.OutputExistsError`) unless ``overwrite``; each file is written under a temporary name
    and renamed only when all three are made, so a failure leaves no partial set."""
    from .output import check_outputs

    check_outputs(out, overwrite, existing)
    d = Path(out)
    d.mkdir(parents=True, exist_ok=True)
    tmp = {n: d / f".{n}.partial" for n in OUTPUT_FILES}
    try:
        tmp["compare.md"].write_text("# bsv bench compare\n\n" + compare_markdown(result))
        tmp["compare.json"].write_text(json.dumps(result, indent=1) + "\n")
        compare_figure(result, tmp["compare.png"])
        for n, p in tmp.items():
            os.replace(p, d / n)
    finally:
        for p in tmp.values():
            if p.exists():
                p.unlink()
    return [d / n for n in OUTPUT_FILES]


def main_compare(runs: Iterable[str], against: Iterable[str], labels: tuple[str, str] | None = None,
                 max_gap: float = DEFAULT_MAX_GAP, out: str | None = None, overwrite: bool = False) -> int:
    """``bsv bench compare``: prints the comparison's markdown and, with ``out``, writes its files; returns 0.
    An ``out`` already holding its files is refused before anything is read (unless ``overwrite``)."""
    if out is not None:  # before anything is read
        from .output import check_outputs

        check_outputs(out, overwrite, existing)
    a, b = read_runs(list(runs)), read_runs(list(against))
    result = compare_runs(a, b, max_gap, labels)
    print(compare_markdown(result), end="")
    if out is not None:
        write_compare(out, result, overwrite=overwrite)
        print(f"wrote {out}/compare.md, compare.json, compare.png")
    return 0


__all__ = ["DEFAULT_MAX_GAP", "LIMBS_ROW", "LIMB_LOOPS", "LOOP_KINDS", "MIN_COST_LIMBS", "OUTPUT_FILES", "ROWS", "RunSet",
           "compare_figure", "compare_loops", "compare_markdown", "compare_runs", "default_labels", "loop_costs",
           "main_compare", "pairs", "read_runs", "write_compare"]

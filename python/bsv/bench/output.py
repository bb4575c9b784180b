"""Writes a benchmark's output folder: results.json, results.csv, report.md and the PNG figures."""

from __future__ import annotations

import platform
import time
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

from ..errors import OutputExistsError
from .boundaries import FIGURE as BOUNDARY_FIGURE
from .common import Run
from .coverage import refinement_rows
from .figures import rve_bars, trunk_limbs_histogram
from .joints import summarise as joint_summary
from .tables import (
    bias_table,
    cloud_table,
    coverage_md,
    p2pv_table,
    paper_table,
    rows,
    signed_table,
    summarise,
    target_check,
    targets_md,
    timing_table,
    worst_table,
    write_csv,
    write_json,
)

#: Files every benchmark writes into its output folder (besides the figures, :data:`FIGURE_PATTERNS`).
OUTPUT_FILES = ("results.json", "results.csv", "report.md")
#: Glob patterns of the figures a benchmark writes.
FIGURE_PATTERNS = ("rve_per_segment.png", "trunk_limbs_hist_*.png", "joint_errors.png", BOUNDARY_FIGURE, "coverage.png")


def existing_outputs(out: str | Path) -> list[str]:
    """Names of benchmark outputs (tables, report, figures) already in ``out``."""
    d = Path(out)
    if not d.is_dir():
        return []
    names = [n for n in OUTPUT_FILES if (d / n).exists()]
    for pat in FIGURE_PATTERNS:
        names += sorted(p.name for p in d.glob(pat))
    return names


def check_outputs(out: str | Path, overwrite: bool = False,
                  existing: Callable[[str | Path], list[str]] = existing_outputs) -> None:
    """Refuses (:class:`bsv.errors.OutputExistsError`) an output folder that already holds benchmark
    outputs (the names ``existing`` finds in it: by default :func:`existing_outputs`), unless ``overwrite``;
    also refuses a file in place of the folder."""
    d = Path(out)
    if d.exists() and not d.is_dir():
        raise OutputExistsError(f"{d} exists and is not a folder; choose another --out folder")
    found = existing(d)
    if found and not overwrite:
        raise OutputExistsError(f"{d} already holds {', '.join(found)}; pass --overwrite (overwrite=True) to "
                                "replace them, or choose another --out folder")


def write_outputs(out: str | Path, title: str, config: Mapping[str, Any], infos: Sequence[Mapping[str, Any]],
                  runs: Sequence[Run], wall_seconds: float, notes: Sequence[str] = (),
                  overwrite: bool = False, on_faust: bool = False) -> dict[str, Any]:
    """Writes every output file into ``out`` (created) and returns the summary; existing outputs are
    refused (:func:`check_outputs`) unless ``overwrite``. ``on_faust``: the runs are on MPI-FAUST, the
    paper's data, so its values are compared (marked better / worse, drawn beside ours); otherwise they
    are shown as context only."""
    check_outputs(out, overwrite)
    d = Path(out)
    d.mkdir(parents=True, exist_ok=True)
    table = rows(runs)
    summary = summarise(table)
    failures = [{"subject": r.subject, "condition": r.condition, "method": r.method, "error": r.error}
                for r in runs if not r.ok]
    checks = target_check(summary) if "bsv" in summary else []
    coverage, coverage_lines = coverage_md(runs)
    from .. import __version__

    write_json(d / "results.json", {
        "bsv_version": __version__, "benchmark": title, "config": dict(config),
        "created": time.strftime("%Y-%m-%d %H:%M:%S"), "machine": platform.platform(),
        "wall_seconds": wall_seconds, "subjects": list(infos), "runs": [r.to_json() for r in runs],
        "summary": summary, "failures": failures, "coverage": coverage, "refinement": refinement_rows(runs),
        "joints": joint_summary(runs),
        "targets": [{"target": n, "met": ok, "measured": ev} for n, ok, ev in checks],
    })
    write_csv(d / "results.csv", table)
    figs = []
    if table:
        figs.append(rve_bars(summary, d / "rve_per_segment.png", paper=on_faust).name)
        for m in summary:
            figs.append(trunk_limbs_histogram(table, d / f"trunk_limbs_hist_{m}.png", m).name)
    if coverage:
        from .coverage import coverage_figure

        figs.append(coverage_figure(coverage, d / "coverage.png").name)
    n_ok = sum(r.ok for r in runs)
    md = [f"# {title}", "",
          (f"bsv {__version__}; {len(infos)} subjects, {n_ok}/{len(runs)} registrations succeeded; "
           f"wall time {wall_seconds:.1f} s ({platform.machine()}, {platform.python_version()})."), ""]
    md += [f"- {k}: `{v}`" for k, v in config.items()]
    md += [""] + [f"{n}" for n in notes]
    md += ["", "## Relative volume error (%), mean ± std over subjects", "",
           (("Each cell: ours (the paper's FAUST value) ✓ better / ✗ worse. " if on_faust else
             "Each cell: ours (the paper's FAUST value, for context only: these are synthetic bodies, not FAUST "
             "scans, so nothing is marked better or worse). ") + "The paper reports NoEr and L5Ca; "
            "noer, l515 and cali are compared with its NoEr column, l5ca with its L5Ca column. For cali and l5ca, "
            "`floor` is the mean RVE of a perfect registration of that cloud (bsv.bench.floor) and `excess` the "
            "mean of (RVE - floor RVE) per subject."), "", paper_table(summary, like_for_like=on_faust), "",
           "## Point2PartVolume-style accuracy (100 - mean RVE, %)", "",
           "Point2PartVolume's numbers are on other data sets (BUFF, PDT13): context only, not compared.", "",
           p2pv_table(summary), "",
           "## Signed error of trunk_limbs (%, mean ± std; negative = the fit shrinks the body)", "",
           bias_table(summary), ""]
    if "bsv" in summary:
        md += ["## Signed error per segment (%, mean over subjects; bsv)", "", signed_table(summary), "",
               "## Worst subject per segment (signed error %, subject index; bsv)", "", worst_table(table), ""]
    from .joints import joint_figure, joints_markdown

    md += joints_markdown(runs)
    if joint_figure(runs, d / "joint_errors.png") is not None:
        figs.append("joint_errors.png")
    from .boundaries import boundaries_markdown, boundary_figure

    md += boundaries_markdown(runs)
    if boundary_figure(runs, d / BOUNDARY_FIGURE) is not None:
        figs.append(BOUNDARY_FIGURE)
    from .looks import looks_markdown

    md += looks_markdown(runs)
    from .classes import classes_markdown

    md += classes_markdown(infos, runs)
    md += ["## Registration time per subject (s)", "", timing_table(runs), ""]
    far = cloud_table(runs)
    if far:
        md += ["## Cloud points off the body (% of the registered cloud)", "",
               ("Points farther than 2 cm / 10 cm from the true body surface (exact point-to-triangle distance): "
                "floor, wall or mask spill, flying pixels and calibration shifts that survived the cloud building; "
                "`uncleaned`: the lab path's cloud of the person mask alone, before floor removal, person isolation "
                "and outlier removal (what the mask let through)."),
               "", far, ""]
    md += coverage_lines
    if checks:
        md += ["## Targets (bsv)", "", targets_md(checks), ""]
    if failures:
        md += ["## Failures", ""] + [f"- {f['subject']} {f['condition']} {f['method']}: {f['error']}" for f in failures]
        md.append("")
    if figs:
        md += ["## Figures", ""] + [f"![{f}]({f})" for f in figs] + [""]
    (d / "report.md").write_text("\n".join(md))
    return summary

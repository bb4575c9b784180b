"""Coverage of the 95 % intervals (:mod:`bsv.uncertainty`) on the synthetic benchmark.

Per registration, :func:`record` keeps what the intervals need (the estimate's and the truth's volumes
and ratios, the calibration Monte Carlo spread: the paper's covariance at the capture's estimated
extrinsics in cali/l5ca, none in noer/l515 where the calibration is exact) in ``Run.info["uncertainty"]``.
:func:`coverage_rows` then combines them with the error model of the condition's depth sensor
(:data:`DEPTH_OF_CONDITION`: noise-free depth in noer and cali, the L515's in l515 and l5ca), per condition:

- ``segment_coverage_pct``: the fraction of (subject, segment) with the true volume inside the interval
  (the 9 trunk-and-limb segments and trunk_limbs);
- ``asymmetry_coverage_pct``: the same for the four limb-segment asymmetries;
- ``trunk_limbs_halfwidth_pct``: median half-width of trunk_limbs, percent of the estimate;
- ``asymmetry_halfwidth_pts``: median half-width of the limb-segment asymmetries, percentage points;
- ``symmetric_false_pct``: of the (subject, limb segment) whose true asymmetry is within
  :data:`SYMMETRIC_PTS` of 0, the percent reported distinguishable from symmetric (interval without 0).

The error model must come from other subjects than the ones scored (see :mod:`bsv.bench.noisemodel`:
the packaged models were derived from cohort seed 1, and seed 3 for the camera path; the benchmark's
default seed is 0).
"""

from __future__ import annotations

import time
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from statistics import median
from typing import Any

import numpy as np

from ..types import TRUNK_LIMBS, Mesh
from ..uncertainty import CameraSpread, ErrorModel, calibration_spread, combine, paper_covariance, quantities
from .common import Run
from .floor import CameraPose

#: The depth model (:func:`bsv.uncertainty.error_models`) of each benchmark condition.
DEPTH_OF_CONDITION: dict[str, str] = {"noer": "exact", "cali": "exact", "l515": "l515", "l5ca": "l515"}
#: Limb segments whose left/right asymmetry is scored.
LIMB_PARTS: tuple[str, ...] = ("upper_arm", "forearm", "thigh", "shin")
#: Volumes whose coverage is scored.
SCORED_VOLUMES: tuple[str, ...] = (*TRUNK_LIMBS, "trunk_limbs")
#: A true asymmetry within this many points of 0 counts as symmetric for the false-positive rate.
SYMMETRIC_PTS: float = 1.0
#: Calibration Monte Carlo draws per benchmark run (fewer than bsv process's: 200 runs add up).
BENCH_SAMPLES: int = 100


def record(fitted: Mesh, truth: Mesh, cameras: Sequence[CameraPose] | None, density: float = 1000.0,
           samples: int = BENCH_SAMPLES, segmentation: str = "oracle") -> dict[str, Any]:
    """What :func:`coverage_rows` needs from one registration (JSON-ready). ``cameras``: the capture's
    true and estimated extrinsics in a calibrated condition (None: exact calibration); ``segmentation``
    selects the error model (:func:`model_name`)."""
    from .. import volumes

    t0 = time.perf_counter()
    spread = [CameraSpread(c.name, c.est_rotation, c.est_translation, paper_covariance(c.name), "paper default")
              for c in cameras or []]
    cal = calibration_spread(fitted, spread, samples=samples, density=density) if spread else {}
    return {"estimate": quantities(volumes(fitted, islands=True, density=density)),
            "truth": quantities(volumes(truth, density=density)), "calibration_sd": cal,
            "segmentation": segmentation, "seconds": time.perf_counter() - t0}


def model_name(condition: str, segmentation: str = "oracle") -> str:
    """The error model of a benchmark run: its condition's depth sensor (:data:`DEPTH_OF_CONDITION`),
    suffixed ``_camera`` on the camera-segmentation path (:func:`bsv.uncertainty.model_for`)."""
    from ..uncertainty import model_for

    return model_for(DEPTH_OF_CONDITION.get(condition, "l515"), segmentation)


def _asym(part: str) -> str:
    return f"asymmetry_{part}_pct"


def coverage_rows(runs: Iterable[Run], models: Mapping[str, ErrorModel]) -> list[dict[str, Any]]:
    """One row per condition (see the module doc) with the model of its depth sensor (``models`` by
    :data:`DEPTH_OF_CONDITION`); runs without ``info["uncertainty"]`` are skipped."""
    by: dict[tuple[str, str], list[dict[str, Any]]] = {}
    for r in runs:
        u = r.info.get("uncertainty") if r.ok else None
        if u:
            by.setdefault((r.condition, model_name(r.condition, u.get("segmentation", "oracle"))), []).append(u)
    rows = []
    for (cond, name), recs in by.items():
        if name not in models:
            continue
        model = models[name]
        inside_v, inside_a, hw_tl, hw_a, sym = [], [], [], [], []
        for u in recs:
            est, truth = u["estimate"], u["truth"]
            iv = combine(est, model, u.get("calibration_sd"))
            for n in SCORED_VOLUMES:
                if n in iv and n in truth:
                    inside_v.append(iv[n][0] <= truth[n] <= iv[n][1])
            if "trunk_limbs" in iv:
                lo, hi = iv["trunk_limbs"]
                hw_tl.append((hi - lo) / 2.0 / est["trunk_limbs"] * 100.0)
            for p in LIMB_PARTS:
                n = _asym(p)
                if n in iv and n in truth:
                    lo, hi = iv[n]
                    inside_a.append(lo <= truth[n] <= hi)
                    hw_a.append((hi - lo) / 2.0)
                    if abs(truth[n]) <= SYMMETRIC_PTS:
                        sym.append(not (lo <= 0.0 <= hi))
        rows.append({"condition": cond, "depth_model": name, "runs": len(recs),
                     "segment_coverage_pct": _pct(inside_v), "asymmetry_coverage_pct": _pct(inside_a),
                     "trunk_limbs_halfwidth_pct": median(hw_tl) if hw_tl else None,
                     "asymmetry_halfwidth_pts": median(hw_a) if hw_a else None,
                     "symmetric_pairs": len(sym), "symmetric_false_pct": _pct(sym)})
    return rows


def _pct(flags: Sequence[bool]) -> float | None:
    return 100.0 * sum(flags) / len(flags) if flags else None


def coverage_markdown(rows: Sequence[dict[str, Any]], models: Mapping[str, ErrorModel]) -> list[str]:
    """The coverage section of report.md (empty without rows)."""
    if not rows:
        return []

    def f(x: float | None, fmt: str) -> str:
        return "n/a" if x is None else format(x, fmt)

    src = next(iter(models.values())).derivation.get("source", "see bsv/data/noise_model.json") if models else ""
    desc = "; ".join(f"{k}: {m.description}" for k, m in models.items())
    out = ["## Coverage of the 95 % intervals", "",
           (f"Error models ({desc}), derived from {src}; never from the subjects scored here "
           "unless this run used the same cohort seed). Calibration part: the paper's covariance at each "
           "capture's estimated extrinsics (cali, l5ca)."), "",
           ("| condition | depth model | runs | segments: truth inside % | asymmetries: truth inside % | trunk_limbs median "
           "half-width % | limb asymmetry median half-width (points) | symmetric pairs | false 'distinguishable' % |"),
           "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        out.append(f"| {r['condition']} | {r['depth_model']} | {r['runs']} | {f(r['segment_coverage_pct'], '.1f')} | "
                   f"{f(r['asymmetry_coverage_pct'], '.1f')} | {f(r['trunk_limbs_halfwidth_pct'], '.2f')} | "
                   f"{f(r['asymmetry_halfwidth_pts'], '.1f')} | {r['symmetric_pairs']} | "
                   f"{f(r['symmetric_false_pct'], '.1f')} |")
    out.append("")
    return out


def coverage_figure(rows: Sequence[dict[str, Any]], path: str | Path) -> Path:
    """Bars of the truth-inside percentages per condition (segments, asymmetries) against the 90-99 % target
    band, with the median half-widths written under each condition."""
    from .figures import _plt

    plt = _plt()
    fig, ax = plt.subplots(figsize=(7.0, 4.0))
    x = np.arange(len(rows))
    seg = [np.nan if r["segment_coverage_pct"] is None else r["segment_coverage_pct"] for r in rows]
    asym = [np.nan if r["asymmetry_coverage_pct"] is None else r["asymmetry_coverage_pct"] for r in rows]
    ax.axhspan(90.0, 99.0, color="tab:green", alpha=0.15, label="target 90-99 %")
    ax.bar(x - 0.2, seg, 0.4, label="segment volumes")
    ax.bar(x + 0.2, asym, 0.4, label="limb asymmetries")
    ax.set_xticks(x, [f"{r['condition']}\ntl ±{r['trunk_limbs_halfwidth_pct'] or float('nan'):.1f} %\n"
                      f"asym ±{r['asymmetry_halfwidth_pts'] or float('nan'):.1f} pt" for r in rows])
    ax.set_ylim(50, 101)
    ax.set_ylabel("truth inside the 95 % interval (%)")
    ax.legend(loc="lower right", fontsize=8)
    fig.tight_layout()
    out = Path(path)
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return out


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m bsv.bench.coverage RESULTS.json``: the coverage table of a finished benchmark with the
    packaged error models."""
    import argparse

    from ..uncertainty import error_models
    from .noisemodel import load_runs

    ap = argparse.ArgumentParser(prog="python -m bsv.bench.coverage", description=main.__doc__)
    ap.add_argument("results", nargs="+", help="results.json of bsv bench synth")
    a = ap.parse_args(argv)
    runs, _ = load_runs(a.results)
    models = error_models()
    print("\n".join(coverage_markdown(coverage_rows(runs, models), models)))
    return 0


if __name__ == "__main__":  # pragma: no cover
    from ..exitcodes import run_command

    raise SystemExit(run_command("python -m bsv.bench.coverage", main))

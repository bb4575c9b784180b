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
  A 10-subject cohort has ~29 such pairs, and their errors are clustered by subject (on the camera path
  the upper-arm and thigh asymmetry errors of one subject correlate at r = 0.93, noer and l515 at 0.75-0.98):
  with an exact model (5.1 % expected with truths up to 1 point) a cohort shows 2 or more of 29 (6.9 %)
  in 44 % of draws, so the report gives the count; judge the rate pooled over held-out cohorts.

With ``bench synth --refine-calibration`` each calibrated run also has ``info["refined"]``: the same capture
with its calibration refined as a user would and registered again (:class:`bsv.bench.synth.Refined`);
its rows have ``calibration`` "refined" (:data:`CALIBRATIONS`), and :func:`refinement_rows` gives the
floor before and after.

The error model must come from other subjects than the ones scored (see :mod:`bsv.bench.noisemodel` and
``benchmarks/derive_noise_model.sh``: cohort seeds 1 and 3, and 4-10 for the camera path; the benchmark's
default seed is 0, and 2 is the other held-out seed).
"""

from __future__ import annotations

import time
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from statistics import median
from typing import Any

import numpy as np

from ..types import TRUNK_LIMBS, Mesh
from ..uncertainty import (
    PARAMETERS,
    CameraSpread,
    ErrorModel,
    calibration_spread,
    combine,
    paper_covariance,
    quantities,
)
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
           samples: int = BENCH_SAMPLES, segmentation: str = "oracle",
           covariances: Sequence[np.ndarray] | None = None, source: str = "paper default",
           extra_sd: Mapping[str, float] | None = None) -> dict[str, Any]:
    """What :func:`coverage_rows` needs from one registration (JSON-ready). ``cameras``: the capture's
    true and estimated extrinsics in a calibrated condition (None: exact calibration); ``covariances``:
    their 6 x 6 covariances (default: the paper's, :func:`bsv.uncertainty.paper_covariance`) from
    ``source``; ``segmentation`` selects the error model (:func:`model_name`); ``extra_sd``: the sd the
    capture's degraded boundaries add per quantity, as ``bsv process`` adds it
    (:func:`bsv.pipeline.segmentation_extra_sd`)."""
    from .. import volumes

    t0 = time.perf_counter()
    cams = list(cameras or [])
    covs = [paper_covariance(c.name) for c in cams] if covariances is None else list(covariances)
    spread = [CameraSpread(c.name, c.est_rotation, c.est_translation, cov, source)
              for c, cov in zip(cams, covs, strict=True)]
    cal = calibration_spread(fitted, spread, samples=samples, density=density) if spread else {}
    return {"estimate": quantities(volumes(fitted, islands=True, density=density)),
            "truth": quantities(volumes(truth, density=density)), "calibration_sd": cal,
            "segmentation": segmentation, "extra_sd": {k: float(v) for k, v in (extra_sd or {}).items()},
            "seconds": time.perf_counter() - t0}


def model_name(condition: str, segmentation: str = "oracle") -> str:
    """The error model of a benchmark run: its condition's depth sensor (:data:`DEPTH_OF_CONDITION`),
    suffixed ``_camera`` on the camera-segmentation path (:func:`bsv.uncertainty.model_for`)."""
    from ..uncertainty import model_for

    return model_for(DEPTH_OF_CONDITION.get(condition, "l515"), segmentation)


def _asym(part: str) -> str:
    return f"asymmetry_{part}_pct"


#: The calibration covariances scored (:func:`coverage_rows`): the capture's own ("paper": the paper's
#: repeatability the rig draws its errors from) and, with ``bench synth --refine-calibration``, the one
#: after the board-depth and floor refinement ("refined").
CALIBRATIONS: tuple[str, ...] = ("paper", "refined")


def interval_record(run: Run, calibration: str = "paper") -> dict[str, Any] | None:
    """The intervals' ingredients of a run for ``calibration`` (:data:`CALIBRATIONS`): ``info["uncertainty"]``,
    or the refined registration's ``info["refined"]["uncertainty"]``; None when the run has none."""
    if not run.ok:
        return None
    if calibration == "refined":
        return (run.info.get("refined") or {}).get("uncertainty")
    return run.info.get("uncertainty")


def run_build_score(r: Run) -> float | None:
    """The subject's build score a camera run read from its capture (``info["sex"]["build_score"]``,
    :func:`bsv.frontend.sex.build_score`); None when it has none (the oracle path, an older run)."""
    v = (r.info.get("sex") or {}).get("build_score")
    return float(v) if isinstance(v, (int, float)) and np.isfinite(v) else None


def coverage_rows(runs: Iterable[Run], models: Mapping[str, ErrorModel],
                  calibrations: Sequence[str] = CALIBRATIONS) -> list[dict[str, Any]]:
    """One row per condition and calibration covariance (see the module doc; ``calibration`` "paper" or
    "refined", :func:`interval_record`) with the model of its depth sensor (``models`` by
    :data:`DEPTH_OF_CONDITION`), at the run's build score when the model follows the build
    (:func:`run_build_score`); runs without the ingredients are skipped."""
    by: dict[tuple[str, str, str], list[tuple[dict[str, Any], float | None]]] = {}
    for cal in calibrations:
        for r in runs:
            u = interval_record(r, cal)
            if u:
                by.setdefault((r.condition, model_name(r.condition, u.get("segmentation", "oracle")), cal),
                              []).append((u, run_build_score(r)))
    rows = []
    for (cond, name, cal), recs in by.items():
        if name not in models:
            continue
        model = models[name]
        inside_v, inside_a, hw_tl, hw_a, sym = [], [], [], [], []
        for u, build in recs:
            est, truth = u["estimate"], u["truth"]
            iv = combine(est, model, u.get("calibration_sd"), u.get("extra_sd"), build_score=build)
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
        rows.append({"condition": cond, "calibration": cal, "depth_model": name, "runs": len(recs),
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
           "unless this run used the same cohort seed). Calibration part (cali, l5ca): `paper`, the paper's "
           "covariance at each capture's estimated extrinsics; `refined` (--refine-calibration), the capture "
           "refined by the board's depth and the floor as a user would, registered again, with the refined "
           "covariance."), "",
           ("| condition | calibration | depth model | runs | segments: truth inside % | asymmetries: truth inside % "
            "| trunk_limbs median half-width % | limb asymmetry median half-width (points) | symmetric pairs "
            "| false 'distinguishable' % (pairs) |"),
           "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        cal = r.get("calibration", "paper") if r["condition"] in ("cali", "l5ca") else "exact"
        out.append(f"| {r['condition']} | {cal} | {r['depth_model']} | {r['runs']} | {f(r['segment_coverage_pct'], '.1f')} | "
                   f"{f(r['asymmetry_coverage_pct'], '.1f')} | {f(r['trunk_limbs_halfwidth_pct'], '.2f')} | "
                   f"{f(r['asymmetry_halfwidth_pts'], '.1f')} | {r['symmetric_pairs']} | "
                   f"{f(r['symmetric_false_pct'], '.1f')}{_count(r['symmetric_false_pct'], r['symmetric_pairs'])} |")
    out.append("")
    return out


def _count(pct: float | None, n: int) -> str:
    """`` (k/n)`` after a percentage of n: 4 of 29 pairs is 13.8 %, and with so few pairs a model that is
    right (5 % false) gives 2 or more of 29 in 44 % of cohorts."""
    return "" if pct is None or not n else f" ({round(pct * n / 100.0)}/{n})"


def refinement_rows(runs: Iterable[Run]) -> list[dict[str, Any]]:
    """Per calibrated condition with refined runs (``bench synth --refine-calibration``): the calibration
    floor (:mod:`bsv.bench.floor`) and the registration's error of trunk_limbs before and after the
    refinement (mean RVE %, worst subject), the forearm-asymmetry floor's mean |error| (points), the
    remaining extrinsic error RMS in the paper's and in the refined posterior's SDs (all cameras and
    parameters; ~1 for an honest posterior; also per camera and parameter of
    :data:`bsv.uncertainty.PARAMETERS`), the refinements that failed, and the mean seconds added."""
    from .common import rve

    by: dict[str, list[Run]] = {}
    for r in runs:
        if r.ok and "refined" in r.info:
            by.setdefault(r.condition, []).append(r)
    rows = []
    for cond, rs in by.items():
        good = [r for r in rs if "uncertainty" in r.info["refined"]]
        fl_b, fl_a, reg_b, reg_a, fa_b, fa_a, paper_sd, post_sd, secs = [], [], [], [], [], [], [], [], []
        by_cam: dict[str, list[list[float]]] = {}
        for r in good:
            ref = r.info["refined"]
            t = r.truth_l
            if "trunk_limbs" in r.floor_l and "trunk_limbs" in ref["floor_l"]:
                fl_b.append(rve(r.floor_l["trunk_limbs"], t["trunk_limbs"]))
                fl_a.append(rve(ref["floor_l"]["trunk_limbs"], t["trunk_limbs"]))
            if "trunk_limbs" in r.estimated_l and "trunk_limbs" in ref["estimated_l"]:
                reg_b.append(rve(r.estimated_l["trunk_limbs"], t["trunk_limbs"]))
                reg_a.append(rve(ref["estimated_l"]["trunk_limbs"], t["trunk_limbs"]))
            if all(k in d for d in (r.floor_l, ref["floor_l"], t) for k in ("forearm_l", "forearm_r")):
                fa_b.append(abs(_asym_pts(r.floor_l) - _asym_pts(t)))
                fa_a.append(abs(_asym_pts(ref["floor_l"]) - _asym_pts(t)))
            for cam, c in ref["cameras"].items():
                paper_sd += c["error_paper_sd"]
                post_sd += c["error_posterior_sd"]
                by_cam.setdefault(cam, []).append(c["error_posterior_sd"])
            secs.append(float(ref.get("refine_seconds", 0.0)) + float(ref.get("seconds", 0.0)))
        rows.append({"condition": cond, "runs": len(rs), "failed": len(rs) - len(good),
                     "floor_tl_before_pct": _mean(fl_b), "floor_tl_after_pct": _mean(fl_a),
                     "floor_tl_worst_before_pct": max(fl_b, default=None),
                     "floor_tl_worst_after_pct": max(fl_a, default=None),
                     "rve_tl_before_pct": _mean(reg_b), "rve_tl_after_pct": _mean(reg_a),
                     "floor_forearm_asym_before_pts": _mean(fa_b), "floor_forearm_asym_after_pts": _mean(fa_a),
                     "error_rms_paper_sd": _rms(paper_sd), "error_rms_posterior_sd": _rms(post_sd),
                     "error_rms_posterior_sd_by_parameter": {
                         cam: np.sqrt(np.mean(np.square(v), axis=0)).tolist() for cam, v in by_cam.items()},
                     "seconds_added": _mean(secs)})
    return rows


def _asym_pts(vol: Mapping[str, float]) -> float:
    """The forearm asymmetry in points, as :func:`bsv.volumes` defines it (left minus right over their mean)."""
    lft, rgt = float(vol["forearm_l"]), float(vol["forearm_r"])
    return (lft - rgt) / ((lft + rgt) / 2.0) * 100.0


def _mean(x: Sequence[float]) -> float | None:
    return float(np.mean(x)) if len(x) else None


def _rms(x: Sequence[float]) -> float | None:
    return float(np.sqrt(np.mean(np.square(x)))) if len(x) else None


def refinement_markdown(rows: Sequence[dict[str, Any]]) -> list[str]:
    """The refinement section of report.md (empty without rows)."""
    if not rows:
        return []

    def f(x: float | None, fmt: str = ".2f") -> str:
        return "n/a" if x is None else format(x, fmt)

    out = ["## Calibration refined as a user would (--refine-calibration)", "",
           ("Each calibrated capture's extrinsics refined by the board's depth (`bsv calibrate --depth`, from "
            "the rig's board view under the same seed) and the floor around it (`bsv process --refine-floor`); "
            "its cloud rebuilt with them and registered again. Floor = a perfect registration of the capture "
            "(mean RVE %, worst subject); remaining extrinsic error RMS over cameras and parameters in the "
            "paper's SDs and in the refined posterior's (about 1 when the posterior is honest)."), "",
           ("| condition | runs | refinement failed | trunk_limbs floor before -> after % (worst) | trunk_limbs RVE "
            "before -> after % | forearm asym. floor abs. error before -> after (points) | error RMS (paper SD) "
            "| error RMS (posterior SD) | seconds added per run |"),
           "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        out.append(f"| {r['condition']} | {r['runs']} | {r['failed']} | {f(r['floor_tl_before_pct'])} -> "
                   f"{f(r['floor_tl_after_pct'])} ({f(r['floor_tl_worst_before_pct'])} -> "
                   f"{f(r['floor_tl_worst_after_pct'])}) | {f(r['rve_tl_before_pct'])} -> {f(r['rve_tl_after_pct'])} | "
                   f"{f(r['floor_forearm_asym_before_pts'])} -> {f(r['floor_forearm_asym_after_pts'])} | "
                   f"{f(r['error_rms_paper_sd'])} | {f(r['error_rms_posterior_sd'])} | {f(r['seconds_added'], '.1f')} |")
    out += ["", "Remaining extrinsic error RMS per parameter in the refined posterior's SDs:", "",
            "| condition | camera | " + " | ".join(PARAMETERS) + " |", "|---|---|" + "---|" * len(PARAMETERS)]
    for r in rows:
        for cam, v in sorted(r.get("error_rms_posterior_sd_by_parameter", {}).items()):
            out.append(f"| {r['condition']} | {cam} | " + " | ".join(f"{x:.2f}" for x in v) + " |")
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
    ax.set_xticks(x, [f"{r['condition']}{' ref.' if r.get('calibration') == 'refined' else ''}\ntl ±{r['trunk_limbs_halfwidth_pct'] or float('nan'):.1f} %\n"
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

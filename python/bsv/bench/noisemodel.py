"""Derives the depth-noise/registration error model of :mod:`bsv.uncertainty` from benchmark results.

Input: ``results.json`` files of ``bsv bench synth`` (each bsv run keeps the estimate's and the truth's
volumes and ratios in ``info["uncertainty"]``, :func:`bsv.bench.coverage.record`). For every quantity
present in both (``whole`` excepted: the fitted template has no head, hands or feet), over the runs of
one condition without calibration error (whose share the calibration Monte Carlo adds: noer gives the
``exact`` depth model, l515 the ``l515`` one), the residual ``T(estimate) - T(truth)`` (natural log of volumes and ratios, points of
asymmetry) gives ``bias`` = its mean and ``sd`` = its standard deviation widened to a 95 % prediction
interval for a new subject: ``s * sqrt(1 + 1/n) * t(0.975, n - 1) / 1.96``. Gross failures (fits with a
residual beyond :data:`GROSS_SIGMAS` robust SDs of its quantity's median: a segment missed by tens of
percent) are left out of both and listed per model (``gross_failures``, out of ``fits``): the intervals
describe fits without such a failure, and the list says how often the derivation saw one.

Calibrate on some cohort seeds and score the coverage on others (never on the derivation's subjects)::

    python -m bsv.bench.noisemodel bench_seed1/results.json bench_seed3/results.json -o noise_model.json

How many subjects: the prediction interval is exact on average for normal residuals, but one derivation's
SD of a quantity is off by about ``1 / sqrt(2 (n - 1))`` (16 % with n = 20), and a held-out cohort of 10
subjects then shows false "distinguishable" asymmetries from 0 to 14 % where 5 % is due. Every model
should rest on at least :data:`MIN_SUBJECTS` subjects (a warning says when not). The results files of one
cohort seed are a group (its subjects, in every look the files hold); with two groups or more,
:func:`cross_validate` scores every group with the model derived from the others (coverage, half-widths,
false "distinguishable" rate of :func:`bsv.bench.coverage.coverage_rows`) and the document keeps it under
``derivation.cross_validation``: a self-check of the derivation on subjects it did not see.

The camera path's error drifts with the subject's build (:func:`bsv.frontend.sex.build_score`, recorded in
every camera run's ``info["sex"]``): when every fit of a camera model has its build and at least
:data:`MIN_BUILD_FITS` lie beyond :data:`BUILD_HINGE` (the heavier cohort's, ``bench synth --bmi-shift 8``, and
the heavier of the standard cohort), the model gets a :class:`bsv.uncertainty.BuildTerm` (:func:`build_term`):
per quantity, a straight line of the residual against the build over every fit (the model's bias is its value
at the hinge), and a straight line of what it leaves, squared, against the build beyond the hinge (the model's
variance at or under the hinge and its growth per unit beyond it, never below 0).
"""

from __future__ import annotations

import argparse
import json
import math
import time
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import BenchError, OutputExistsError
from ..uncertainty import Z95, BuildTerm, transform
from .common import Run
from .coverage import run_build_score

#: Error model -> the benchmark condition and segmentation whose residuals define it
#: (:func:`bsv.uncertainty.model_for`).
MODEL_CONDITIONS: dict[str, tuple[str, str]] = {
    "exact": ("noer", "oracle"), "l515": ("l515", "oracle"),
    "exact_camera": ("noer", "camera"), "l515_camera": ("l515", "camera"),
}
#: Fewest subjects a model should rest on (the SD of one quantity is then known to ~ +-11 %, 1 SD).
MIN_SUBJECTS: int = 40
#: A fit with a residual farther than this many robust SDs (1.4826 x the median absolute deviation) from
#: its quantity's median is a gross failure, not noise: the whole fit is left out of every quantity's bias
#: and SD and listed (``gross_failures``). On the 240 derivation and held-out fits of cohort seeds 0-7
#: the worst quantity of every other fit lies within 6.5 robust SDs (4.2 outside oracle l515); the fits
#: beyond 10 missed a segment by 20-58 % (an upper arm fitted 36 % small on the camera path, seed 6
#: subject 9: a 40-point asymmetry error; both upper arms 19-23 % small in oracle l515, seed 3 subjects 7
#: and 10). One such fit among 60 would widen every user's upper-arm asymmetry interval from +-10 to
#: +-16 points and still not cover such a failure.
GROSS_SIGMAS: float = 10.0
#: Quantities never modelled (the fitted template's "whole" lacks the head, hands and feet of the truth's).
EXCLUDED: tuple[str, ...] = ("whole",)
#: Fewest fits beyond the build hinge a camera model's :class:`bsv.uncertainty.BuildTerm` rests on.
MIN_BUILD_FITS: int = 20
#: The build score from which a camera model's error grows (:class:`bsv.uncertainty.BuildTerm`): the average
#: body (0). The cut lines move only beyond ``SegmentParams.build_hinge`` (1), but the errors grow from the
#: average body up: over the 200 camera fits per sensor of the derivation (clinic room, studio and the heavier
#: cohort) the mean squared standardised residual is 1.0 at builds under 1 and 1.1-1.4 just above it, rising
#: to 1.8-2.2 beyond 3. The held-out heavier bodies (seeds 0 and 2) are covered 91.5 % with the hinge at 1,
#: 92.5 % at 0.5 and 92.5-93 % at 0; the room and the studio 95-99 % at all three (benchmarks/BENCH.md, round 2
#: session 33).
BUILD_HINGE: float = 0.0


def t975(dof: int) -> float:
    """Student's t 97.5 % quantile (Cornish-Fisher expansion; within 0.2 % of the exact value for dof >= 5)."""
    if dof < 1:
        raise BenchError("need at least 2 runs to estimate a spread")
    z, v = Z95, float(dof)
    return (z + (z**3 + z) / (4 * v) + (5 * z**5 + 16 * z**3 + 3 * z) / (96 * v**2)
            + (3 * z**7 + 19 * z**5 + 17 * z**3 - 15 * z) / (384 * v**3))


def _ingredients(r: Run, conditions: Sequence[str], segmentation: str) -> dict[str, Any] | None:
    """A bsv run's interval ingredients when it is of ``conditions`` and ``segmentation``; else None."""
    u = r.info.get("uncertainty") if (r.ok and r.method == "bsv" and r.condition in conditions) else None
    if not u or u.get("segmentation", "oracle") != segmentation:
        return None
    return u


def run_build_scores(runs: Sequence[Run], conditions: Sequence[str], segmentation: str = "oracle") -> list[float | None]:
    """The :func:`run_build_score` of each run :func:`run_residuals` keeps, in its order."""
    return [run_build_score(r) for r in runs if _ingredients(r, conditions, segmentation) is not None]


def run_residuals(runs: Sequence[Run], conditions: Sequence[str], segmentation: str = "oracle"
                  ) -> list[tuple[str, dict[str, float]]]:
    """Per bsv run of ``conditions`` and ``segmentation`` that kept its ingredients: (its subject, per
    quantity ``T(estimate) - T(truth)``)."""
    out: list[tuple[str, dict[str, float]]] = []
    for r in runs:
        u = _ingredients(r, conditions, segmentation)
        if u is None:
            continue
        res: dict[str, float] = {}
        for name, est in u["estimate"].items():
            tru = u["truth"].get(name)
            if name in EXCLUDED or tru is None:
                continue
            d = transform(name, est) - transform(name, tru)
            if math.isfinite(d):
                res[name] = d
        out.append((r.subject, res))
    return out


def residuals(runs: Sequence[Run], conditions: Sequence[str], segmentation: str = "oracle") -> dict[str, list[float]]:
    """Per quantity, ``T(estimate) - T(truth)`` over the bsv runs of ``conditions`` and ``segmentation``
    that kept their ingredients."""
    out: dict[str, list[float]] = {}
    for _, res in run_residuals(runs, conditions, segmentation):
        for name, d in res.items():
            out.setdefault(name, []).append(d)
    return out


def gross_failures(per_run: Sequence[tuple[str, dict[str, float]]], sigmas: float = GROSS_SIGMAS
                   ) -> dict[int, dict[str, Any]]:
    """The fits of ``per_run`` (:func:`run_residuals`) with a quantity beyond ``sigmas`` robust SDs of
    that quantity's median (:data:`GROSS_SIGMAS`), by index: their subject, worst quantity, its residual
    and its distance in robust SDs. A quantity without spread (all residuals equal) flags nothing."""
    by: dict[str, list[float]] = {}
    for _, res in per_run:
        for name, d in res.items():
            by.setdefault(name, []).append(d)
    centre: dict[str, tuple[float, float]] = {}
    for name, ds in by.items():
        a = np.asarray(ds)
        med = float(np.median(a))
        centre[name] = (med, 1.4826 * float(np.median(np.abs(a - med))))
    out: dict[int, dict[str, Any]] = {}
    for i, (subject, res) in enumerate(per_run):
        z = {n: abs(d - centre[n][0]) / centre[n][1] for n, d in res.items() if centre[n][1] > 0}
        worst = max(z, key=lambda n: z[n], default=None)
        if worst is not None and z[worst] > sigmas:
            out[i] = {"subject": subject, "quantity": worst, "residual": res[worst], "robust_sds": z[worst]}
    return out


def _widening(n: int) -> float:
    """The factor that turns a sample sd of ``n`` residuals into a 95 % prediction sd for a new subject."""
    return math.sqrt(1 + 1 / n) * t975(n - 1) / Z95


def _quantity(name: str, bias: float, raw_sd: float, n: int) -> dict[str, Any]:
    """One quantity's record of a model: its bias, its sd widened for a new subject (:func:`_widening`),
    the sample sd, the number of fits and the comparison space."""
    return {"bias": bias, "sd": raw_sd * _widening(n), "raw_sd": raw_sd, "n": n,
            "space": "points" if name.startswith("asymmetry_") else "log"}


def build_term(per_run: Sequence[tuple[float, Mapping[str, float]]], hinge: float
               ) -> tuple[dict[str, dict[str, Any]], BuildTerm]:
    """The quantities and the build term of a camera model from its fits (``per_run``: (build score,
    residuals per quantity), gross failures left out). Per quantity, over every fit: least squares of its
    residual ``r`` against the build, ``r = bias + slope (b - hinge)``; then of the squared remainder ``u^2``
    against the build beyond the hinge ``e = max(b - hinge, 0)``, ``u^2 = s^2 (1 + c e)``: the model's sd is
    ``s`` (widened for a new subject with the number of fits) and ``c`` the variance's growth per unit (never
    below 0)."""
    q: dict[str, dict[str, Any]] = {}
    bias: dict[str, float] = {}
    variance: dict[str, float] = {}
    for name in sorted({n for _, res in per_run for n in res}):
        pts = [(b - hinge, res[name]) for b, res in per_run if name in res]
        d = np.array([p[0] for p in pts])
        r = np.array([p[1] for p in pts])
        e = np.maximum(d, 0.0)
        n = len(pts)
        if n < 4 or (d <= 0).sum() < 2 or (e > 0).sum() < 2:
            continue
        (b0, b1), *_ = np.linalg.lstsq(np.column_stack([np.ones(n), d]), r, rcond=None)
        u2 = (r - b0 - b1 * d) ** 2 * n / (n - 2)  # unbiased for the two fitted coefficients
        (v0, v1), *_ = np.linalg.lstsq(np.column_stack([np.ones(n), e]), u2, rcond=None)
        s2 = float(v0) if v0 > 0 else float(u2[d <= 0].mean())
        s = math.sqrt(s2)
        q[name] = _quantity(name, float(b0), s, n)
        bias[name] = float(b1)
        variance[name] = max(float(v1) / s2, 0.0) if s2 > 0 else 0.0
    return q, BuildTerm(hinge, bias, variance)


def derive_one(runs: Sequence[Run], condition: str, segmentation: str = "oracle") -> dict[str, Any]:
    """One error model (``{"condition", "segmentation", "quantities", "gross_failures"}``, and ``"build"`` for a
    camera model with :data:`MIN_BUILD_FITS` fits beyond the build hinge: see the module notes) from the runs
    of ``condition``, the gross failures (:func:`gross_failures`) left out."""
    per_run = run_residuals(runs, (condition,), segmentation)
    if not per_run:
        raise BenchError(f"no bsv run of {condition} ({segmentation} segmentation) with interval ingredients "
                         "(info['uncertainty']); run `bsv bench synth` with this version first")
    gross = gross_failures(per_run)
    builds = run_build_scores(runs, (condition,), segmentation)
    kept = [(builds[i], r) for i, (_, r) in enumerate(per_run) if i not in gross]
    with_build = [(b, r) for b, r in kept if b is not None] if segmentation == "camera" else []
    beyond = sum(b > BUILD_HINGE for b, _ in with_build)
    out: dict[str, Any] = {"condition": condition, "segmentation": segmentation,
                           "description": f"synthetic cohort, {condition}, {segmentation} segmentation, default template"}
    if beyond >= MIN_BUILD_FITS and len(with_build) == len(kept):
        q, term = build_term(with_build, BUILD_HINGE)
        return {**out, "quantities": q, "build": {**term.to_json(), "fits": beyond}, "fits": len(per_run),
                "gross_failures": list(gross.values())}
    res: dict[str, list[float]] = {}
    for _, r in kept:
        for name, x in r.items():
            res.setdefault(name, []).append(x)
    q = {}
    for name, xs in sorted(res.items()):
        n = len(xs)
        if n < 3:
            continue
        a = np.asarray(xs)
        q[name] = _quantity(name, float(a.mean()), float(np.std(a, ddof=1)), n)
    return {**out, "quantities": q, "fits": len(per_run), "gross_failures": list(gross.values())}


def derive(runs: Sequence[Run], models: dict[str, tuple[str, str]] | None = None, source: str = "") -> dict[str, Any]:
    """The error-model document (``bsv/data/noise_model.json``): one model per depth sensor and
    segmentation (``models``: name -> (condition, segmentation)); by default every model of
    :data:`MODEL_CONDITIONS` that the runs hold (at least one)."""
    if models is None:
        have = {(r.condition, (r.info.get("uncertainty") or {}).get("segmentation", "oracle")) for r in runs}
        m = {k: v for k, v in MODEL_CONDITIONS.items() if v in have}
        if not m:
            raise BenchError("no bsv run of noer or l515 with interval ingredients; run `bsv bench synth` first")
    else:
        m = models
    return {"derivation": {"source": source, "created": time.strftime("%Y-%m-%d"),
                           "rule": "per quantity and depth model: bias = mean of T(estimate) - T(truth); "
                                   "sd = s * sqrt(1 + 1/n) * t(0.975, n-1) / 1.96 (95 % prediction interval "
                                   "for a new subject); T = log, or the value for asymmetries (points); "
                                   f"a fit with a residual beyond {GROSS_SIGMAS:g} robust SDs of its quantity's "
                                   "median is a gross failure, left out and listed (gross_failures): the "
                                   "intervals hold for fits without one; a camera model's bias follows the "
                                   "subject's build (a line over its fits, the bias at the hinge), its "
                                   "variance is constant up to the hinge and grows linearly beyond it (the "
                                   f"build term, with at least {MIN_BUILD_FITS} fits beyond the hinge)"},
            "depth_models": {name: derive_one(runs, cond, seg) for name, (cond, seg) in m.items()}}


def cross_validate(groups: Mapping[str, Sequence[Run]]) -> list[dict[str, Any]]:
    """Leave one group out: per group (e.g. the runs of one cohort seed) and condition, the coverage row
    (:func:`bsv.bench.coverage.coverage_rows`) of that group's runs scored with the models derived from
    the other groups (those that can be derived from them)."""
    from ..uncertainty import ErrorModel
    from .coverage import coverage_rows

    out: list[dict[str, Any]] = []
    for held, runs in groups.items():
        rest = [r for g, rs in groups.items() if g != held for r in rs]
        try:
            doc = derive(rest)
        except BenchError:  # the other groups hold no run this model could come from
            continue
        models = {k: ErrorModel.from_json(v, f"cross-validation model {k}") for k, v in doc["depth_models"].items()}
        subjects = {k: min((q["n"] for q in v["quantities"].values()), default=0)
                    for k, v in doc["depth_models"].items()}
        for row in coverage_rows(runs, models, calibrations=("paper",)):
            out.append({"held_out": held, "derived_from_subjects": subjects.get(row["depth_model"], 0),
                        **{k: row[k] for k in ("condition", "depth_model", "runs", "segment_coverage_pct",
                                               "asymmetry_coverage_pct", "trunk_limbs_halfwidth_pct",
                                               "asymmetry_halfwidth_pts", "symmetric_pairs", "symmetric_false_pct")}})
    return out


def cross_validation_markdown(rows: Sequence[Mapping[str, Any]]) -> str:
    """The table of :func:`cross_validate`, and per depth model the mean and range over held-out groups."""
    def f(x: Any, fmt: str) -> str:
        return "n/a" if x is None else format(x, fmt)

    out = [("| held out | condition | depth model | derived from (subjects) | runs | segments inside % "
            "| asymmetries inside % | trunk_limbs half-width % | asym. half-width pts | false 'distinguishable' % |"),
           "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        out.append(f"| {r['held_out']} | {r['condition']} | {r['depth_model']} | {r['derived_from_subjects']} | "
                   f"{r['runs']} | {f(r['segment_coverage_pct'], '.1f')} | {f(r['asymmetry_coverage_pct'], '.1f')} | "
                   f"{f(r['trunk_limbs_halfwidth_pct'], '.2f')} | {f(r['asymmetry_halfwidth_pts'], '.1f')} | "
                   f"{f(r['symmetric_false_pct'], '.1f')} |")
    for model in sorted({r["depth_model"] for r in rows}):
        rs = [r for r in rows if r["depth_model"] == model]
        false = [r["symmetric_false_pct"] for r in rs if r["symmetric_false_pct"] is not None]
        seg = [r["segment_coverage_pct"] for r in rs if r["segment_coverage_pct"] is not None]
        pairs = sum(r["symmetric_pairs"] for r in rs)
        pooled = (sum(r["symmetric_false_pct"] * r["symmetric_pairs"] for r in rs if r["symmetric_false_pct"] is not None)
                  / pairs if pairs else None)
        out.append(f"\n{model}: {len(rs)} held-out groups; segments inside {f(min(seg, default=None), '.0f')}-"
                   f"{f(max(seg, default=None), '.0f')} %; false 'distinguishable' {f(min(false, default=None), '.1f')}-"
                   f"{f(max(false, default=None), '.1f')} % per group, {f(pooled, '.1f')} % pooled over {pairs} pairs")
    return "\n".join(out)


def load_groups(paths: Sequence[str | Path]) -> tuple[dict[str, list[Run]], str]:
    """The runs of the ``results.json`` files grouped by cohort seed, and a description of their
    configurations. The files of one seed hold the same subjects (other looks, another segmentation), so
    they form one group, named by their folders and the seed ("camera_seed4 + studio_seed4 (seed 4)"): leaving
    out one look of a seed while its other look stays in would score the subjects on a model derived from
    themselves. A file without a seed is a group of its own."""
    by_seed: dict[Any, list[tuple[str, list[Run]]]] = {}
    where = []
    for k, p in enumerate(paths):
        runs, desc = load_runs([p])
        try:
            seed = json.loads(Path(p).read_text()).get("config", {}).get("seed")
        except (OSError, json.JSONDecodeError) as exc:  # load_runs read it a moment ago
            raise BenchError(f"{p}: cannot read benchmark results ({exc})") from exc
        by_seed.setdefault(seed if seed is not None else ("file", k), []).append((Path(p).parent.name or str(p), runs))
        where.append(desc)
    groups: dict[str, list[Run]] = {}
    for seed, files in by_seed.items():
        label = f"seed {seed}" if not isinstance(seed, tuple) else "no seed"
        name = f"{' + '.join(f for f, _ in files)} ({label})"
        groups[name if name not in groups else f"{name} #{len(groups)}"] = [r for _, rs in files for r in rs]
    return groups, "; ".join(where)


def load_runs(paths: Sequence[str | Path]) -> tuple[list[Run], str]:
    """The runs of ``results.json`` files and a description of their configurations."""
    runs: list[Run] = []
    where = []
    for p in paths:
        try:
            doc = json.loads(Path(p).read_text())
        except (OSError, json.JSONDecodeError) as exc:
            raise BenchError(f"{p}: cannot read benchmark results ({exc})") from exc
        runs += [Run.from_json(r) for r in doc.get("runs", [])]
        cfg = doc.get("config", {})
        room = cfg.get("room")  # "clinic", "studio", or False: the body alone on grey
        room = f", {'clinic room' if room == 'clinic' else room} renders" if room else ""
        shift = float(cfg.get("bmi_shift") or 0.0)  # a heavier cohort (bench synth --bmi-shift)
        heavy = f", BMI {shift:+g}" if shift else ""
        where.append(f"bench synth seed {cfg.get('seed')} n {cfg.get('n')} ({cfg.get('conditions')}, "
                     f"{cfg.get('segmentation')}, local modifiers {cfg.get('local_modifiers')}{room}{heavy})")
    return runs, "; ".join(where)


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m bsv.bench.noisemodel RESULTS.json... -o noise_model.json``."""
    ap = argparse.ArgumentParser(prog="python -m bsv.bench.noisemodel", description=__doc__.split("\n")[0])
    ap.add_argument("results", nargs="+", help="results.json of bsv bench synth runs (calibration cohort)")
    ap.add_argument("-o", "--out", required=True, help="output JSON (e.g. python/bsv/data/noise_model.json)")
    ap.add_argument("--overwrite", action="store_true")
    a = ap.parse_args(argv)
    out = Path(a.out)
    if out.exists() and not a.overwrite:
        raise OutputExistsError(f"{out} exists; pass --overwrite to replace it")
    groups, source = load_groups(a.results)
    runs = [r for rs in groups.values() for r in rs]
    doc = derive(runs, source=source)
    for name, m in doc["depth_models"].items():
        n = min((q["n"] for q in m["quantities"].values()), default=0)
        if n < MIN_SUBJECTS:
            print(f"warning: model {name} rests on {n} subjects (fewer than {MIN_SUBJECTS}): its SDs are uncertain "
                  f"by about +-{100 / math.sqrt(2 * max(n - 1, 1)):.0f} %; derive it from more cohort seeds")
    cv = cross_validate(groups) if len(groups) > 1 else []
    doc["derivation"]["cross_validation"] = cv
    tmp = out.with_suffix(out.suffix + ".tmp")
    tmp.write_text(json.dumps(doc, indent=1) + "\n")
    tmp.replace(out)
    print(f"wrote {out}: depth models {', '.join(doc['depth_models'])} from {source}")
    if cv:
        print("leave-one-group-out check (each group scored with the model of the others):")
        print(cross_validation_markdown(cv))
    return 0


if __name__ == "__main__":  # pragma: no cover
    from ..exitcodes import run_command

    raise SystemExit(run_command("python -m bsv.bench.noisemodel", main))

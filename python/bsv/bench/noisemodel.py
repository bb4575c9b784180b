"""Derives the depth-noise/registration error model of :mod:`bsv.uncertainty` from benchmark results.

Input: ``results.json`` files of ``bsv bench synth`` (each bsv run keeps the estimate's and the truth's
volumes and ratios in ``info["uncertainty"]``, :func:`bsv.bench.coverage.record`). For every quantity
present in both (``whole`` excepted: the fitted template has no head, hands or feet), over the runs of
one condition without calibration error (whose share the calibration Monte Carlo adds: noer gives the
``exact`` depth model, l515 the ``l515`` one), the residual ``T(estimate) - T(truth)`` (natural log of volumes and ratios, points of
asymmetry) gives ``bias`` = its mean and ``sd`` = its standard deviation widened to a 95 % prediction
interval for a new subject: ``s * sqrt(1 + 1/n) * t(0.975, n - 1) / 1.96``.

Calibrate on one cohort seed and score the coverage on another (the packaged model: seed 1, scored on
seed 0)::

    python -m bsv.bench.noisemodel bench_seed1/results.json -o python/bsv/data/noise_model.json
"""

from __future__ import annotations

import argparse
import json
import math
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import BenchError, OutputExistsError
from ..uncertainty import Z95, transform
from .common import Run

#: Error model -> the benchmark condition and segmentation whose residuals define it
#: (:func:`bsv.uncertainty.model_for`).
MODEL_CONDITIONS: dict[str, tuple[str, str]] = {
    "exact": ("noer", "oracle"), "l515": ("l515", "oracle"),
    "exact_camera": ("noer", "camera"), "l515_camera": ("l515", "camera"),
}
#: Quantities never modelled (the fitted template's "whole" lacks the head, hands and feet of the truth's).
EXCLUDED: tuple[str, ...] = ("whole",)


def t975(dof: int) -> float:
    """Student's t 97.5 % quantile (Cornish-Fisher expansion; within 0.2 % of the exact value for dof >= 5)."""
    if dof < 1:
        raise BenchError("need at least 2 runs to estimate a spread")
    z, v = Z95, float(dof)
    return (z + (z**3 + z) / (4 * v) + (5 * z**5 + 16 * z**3 + 3 * z) / (96 * v**2)
            + (3 * z**7 + 19 * z**5 + 17 * z**3 - 15 * z) / (384 * v**3))


def residuals(runs: Sequence[Run], conditions: Sequence[str], segmentation: str = "oracle") -> dict[str, list[float]]:
    """Per quantity, ``T(estimate) - T(truth)`` over the bsv runs of ``conditions`` and ``segmentation``
    that kept their ingredients."""
    out: dict[str, list[float]] = {}
    for r in runs:
        u = r.info.get("uncertainty") if (r.ok and r.method == "bsv" and r.condition in conditions) else None
        if not u or u.get("segmentation", "oracle") != segmentation:
            continue
        for name, est in u["estimate"].items():
            tru = u["truth"].get(name)
            if name in EXCLUDED or tru is None:
                continue
            d = transform(name, est) - transform(name, tru)
            if math.isfinite(d):
                out.setdefault(name, []).append(d)
    return out


def derive_one(runs: Sequence[Run], condition: str, segmentation: str = "oracle") -> dict[str, Any]:
    """One error model (``{"condition", "segmentation", "quantities"}``) from the runs of ``condition``."""
    res = residuals(runs, (condition,), segmentation)
    if not res:
        raise BenchError(f"no bsv run of {condition} ({segmentation} segmentation) with interval ingredients "
                         "(info['uncertainty']); run `bsv bench synth` with this version first")
    q: dict[str, Any] = {}
    for name, d in sorted(res.items()):
        n = len(d)
        if n < 3:
            continue
        a = np.asarray(d)
        s = float(np.std(a, ddof=1))
        q[name] = {"bias": float(a.mean()), "sd": s * math.sqrt(1 + 1 / n) * t975(n - 1) / Z95, "raw_sd": s, "n": n,
                   "space": "points" if name.startswith("asymmetry_") else "log"}
    return {"condition": condition, "segmentation": segmentation,
            "description": f"synthetic cohort, {condition}, {segmentation} segmentation, default template", "quantities": q}


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
                                   "for a new subject); T = log, or the value for asymmetries (points)"},
            "depth_models": {name: derive_one(runs, cond, seg) for name, (cond, seg) in m.items()}}


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
        where.append(f"bench synth seed {cfg.get('seed')} n {cfg.get('n')} ({cfg.get('conditions')}, "
                     f"{cfg.get('segmentation')}, local modifiers {cfg.get('local_modifiers')})")
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
    runs, source = load_runs(a.results)
    doc = derive(runs, source=source)
    tmp = out.with_suffix(out.suffix + ".tmp")
    tmp.write_text(json.dumps(doc, indent=1) + "\n")
    tmp.replace(out)
    print(f"wrote {out}: depth models {', '.join(doc['depth_models'])} from {source}")
    return 0


if __name__ == "__main__":  # pragma: no cover
    from ..exitcodes import run_command

    raise SystemExit(run_command("python -m bsv.bench.noisemodel", main))

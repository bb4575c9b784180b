"""Learns bsv.frontend.kneelines.KNEE_LOOP_MODEL (the camera path's fitted knee loop shift from the body's
proportions) from ``bsv bench synth --segmentation camera`` runs, and evaluates it on others.

Each run of the given output folders (their results.json) holds, per subject and condition, the fitted knee
loops' shifts against the true loops (``info.boundary_errors_mm``, mm, + distal), the measured joint centres'
errors against the rig's (``info.joint_errors_mm``) and the sex model's measurements (``info.sex``). The rig's
joints are made again from each subject's phenotype and pose, so the measured joint centres are the rig's plus
their errors: exactly those ``bsv process`` had. The target is the mean of the two knee loops (they share one
line, :func:`bsv.frontend.segment.knee_line`); the features are :data:`bsv.frontend.kneelines.FEATURES`.
Least squares over the training runs (both conditions pooled), each feature's range the training range
widened by a quarter of its span on each side; ``mean`` the mean prediction over the training runs. The runs
must come from an engine without the correction (``bsv.frontend.kneelines.KNEE_LINE_GAIN`` set to 0), or their
loops carry it already. The shipped table (round 2 session 41):

    for s in 0 1 2 3 4 5 6 7 11 12 13 14 15 16 17 18 20 21; do .venv/bin/bsv bench synth --n 10 --seed $s \
        --conditions noer,l515 --segmentation camera --out runs/room_$s; done
    for s in 0 1 2 3 4 5 6 7; do .venv/bin/bsv bench synth --n 10 --seed $s --conditions noer,l515 \
        --segmentation camera --macros wide --out runs/wide_$s; done
    .venv/bin/python benchmarks/learn_knee_lines.py --train runs/room_{0,1,2,3,4,5,6,7,11,12,13,14,15,16,17,18} \
        runs/wide_{2,3,4,5,6,7} --eval runs/room_20 runs/room_21 runs/wide_0 runs/wide_1

Prints the table for bsv/frontend/kneelines.py and, per evaluation folder, the loops' rms about the training
mean against the residual's.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

import numpy as np

from bsv.bodies.joints import rig_joints
from bsv.bodies.model import Phenotype
from bsv.bodies.pose import Pose
from bsv.frontend.kneelines import FEATURES, predicted_loop_mm, proportions
from bsv.frontend.sex import build_score


def rows(folder: Path) -> list[tuple[dict[str, float], float]]:
    """(features, mean knee loop mm) of every camera-path run in ``folder``'s results.json that has both."""
    doc = json.loads((folder / "results.json").read_text())
    subjects = {s["subject"]: s for s in doc["subjects"] if "phenotype" in s}
    truth: dict[str, dict[str, np.ndarray]] = {}
    out = []
    for run in doc["runs"]:
        info: dict[str, Any] = run.get("info") or {}
        loops = info.get("boundary_errors_mm") or {}
        errs = info.get("joint_errors_mm") or {}
        s = subjects.get(run["subject"])
        if not run.get("ok") or s is None or not errs or loops.get("knee_l") is None or loops.get("knee_r") is None:
            continue
        if s["subject"] not in truth:
            truth[s["subject"]] = rig_joints(Phenotype(**s["phenotype"]), Pose(**s["pose"]))
        joints = {k: np.asarray(truth[s["subject"]][k]) + np.asarray(v) / 1000.0 for k, v in errs.items()}
        feats = proportions(joints)
        if feats is None:
            continue
        feats["build"] = build_score((info.get("sex") or {}).get("measurements") or {})
        out.append((feats, 0.5 * (loops["knee_l"] + loops["knee_r"])))
    return out


def fit(train: list[tuple[dict[str, float], float]]) -> dict[str, Any]:
    """KNEE_LOOP_MODEL fitted to ``train``."""
    x = np.array([[f[k] for k in FEATURES] for f, _ in train])
    y = np.array([t for _, t in train])
    lo, hi = x.min(axis=0), x.max(axis=0)
    rng = {k: (float(lo[i] - (hi[i] - lo[i]) / 4), float(hi[i] + (hi[i] - lo[i]) / 4)) for i, k in enumerate(FEATURES)}
    a = np.column_stack([np.ones(len(x)), x])
    c, *_ = np.linalg.lstsq(a, y, rcond=None)
    model: dict[str, Any] = {"1": float(c[0]), "coef": {k: float(c[i + 1]) for i, k in enumerate(FEATURES)},
                             "range": rng, "mean": 0.0}
    model["mean"] = float(np.mean([predicted_loop_mm(f, model) for f, _ in train]))
    return model


def main(argv: list[str] | None = None) -> int:
    """Fits on ``--train``, prints the table and the evaluation; returns the exit code."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--train", nargs="+", required=True, help="bench synth output folders to learn from")
    ap.add_argument("--eval", nargs="*", default=[], help="bench synth output folders to evaluate on")
    args = ap.parse_args(argv)
    train = [r for d in args.train for r in rows(Path(d))]
    if len(train) < 2 * len(FEATURES):
        raise SystemExit(f"error: {len(train)} usable runs in --train; need at least {2 * len(FEATURES)}")
    model = fit(train)
    y = np.array([t for _, t in train])
    res = y - np.array([predicted_loop_mm(f, model) for f, _ in train])
    print(f"training: {len(train)} runs, knee loop sd {y.std():.2f} mm -> residual {res.std():.2f} mm")
    print("KNEE_LOOP_MODEL = {")
    print(f'    "1": {model["1"]:.4g},')
    print('    "coef": {' + ", ".join(f'"{k}": {v:.4g}' for k, v in model["coef"].items()) + "},")
    print('    "range": {' + ", ".join(f'"{k}": ({a:.4g}, {b:.4g})' for k, (a, b) in model["range"].items()) + "},")
    print(f'    "mean": {model["mean"]:.4g},')
    print("}")
    for d in args.eval:
        ev = rows(Path(d))
        if not ev:
            print(f"{d}: no usable runs")
            continue
        t = np.array([r for _, r in ev])
        p = np.array([predicted_loop_mm(f, model) for f, _ in ev])
        print(f"{d}: {len(ev)} runs, rms about the training mean {np.sqrt(np.mean((t - y.mean()) ** 2)):.2f} mm "
              f"-> residual {np.sqrt(np.mean((t - p) ** 2)):.2f} mm (sd {t.std():.2f} -> {np.std(t - p):.2f})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""Learns bsv.frontend.groin.HIP_LOOP_OFFSETS_M (where each thigh's boundary loop with the torso lies from
the crotch the depth images show) and bsv.frontend.groin.CROTCH_BELOW_HIPS (where that crotch is expected
below the measured hips), and evaluates them on other cohorts.

For every subject of the training cohorts (seeds ``--train-seeds``) and the evaluation cohorts (``--eval-seeds``)
the virtual rig captures the body in a room (``--condition``), the camera path segments both views and lifts
the joints (bsv.bench.joints.camera_segmentations) and finds the crotch (bsv.frontend.groin.crotch_from_depth,
without its low-crotch check). CROTCH_BELOW_HIPS is the least-squares fit of the crotch's depth below the
measured hips' midpoint (along the body's up axis) on the sex score and the measured thighs' length; the
captures whose crotch lies more than bsv.frontend.groin.CROTCH_LOW_MARGIN_M below that fit (thighs that touch
below the crotch) are left out of both fits, and the fit of CROTCH_BELOW_HIPS is made again without them.
The true loop centre of each thigh is the centre of the ring of thigh vertices next to the torso on the true
body (bsv.keypoints.boundary_rings, the ring the template's loop is pulled by). Its offset from the crotch, in
the body frame of the measured joints (lateral outward, up, forward; both sides pooled), is fitted by least
squares on the capture's sex score, build score (bsv.frontend.sex.build_score) and measured thighs' length. The script prints the table
and the evaluation cohorts' residuals (mean, sd per component) with the constant alone and with the fit, and how
many captures gave no crotch.

    .venv/bin/python benchmarks/learn_hip_loops.py --n 10 --train-seeds 11,12,13,14,15,16 --eval-seeds 0,2 \
        --narrow-seeds 0

``--cache FILE`` keeps the measured crotches and true loops (JSON) so that a second run re-learns without
MediaPipe.
"""

from __future__ import annotations

import argparse
import json
import tempfile
from pathlib import Path

import numpy as np
from tqdm import tqdm

import bsv
from bsv.bench.joints import camera_segmentations, capture_views_geometry
from bsv.bodies.cohort import HIP_ABDUCTION_RANGE_DEG, NARROW_HIP_ABDUCTION_RANGE_DEG
from bsv.frontend.groin import CROTCH_LOW_MARGIN_M, crotch_from_depth
from bsv.frontend.landmarks import body_frame
from bsv.frontend.sex import build_score
from bsv.keypoints import boundary_rings

#: One subject: (the capture's crotch or None, the true loop centres {name: xyz}, the measured joints' body
#: frame (3x3) or None, sex score, build score, the crotch's depth below the measured hips (m, NaN without
#: it), the measured thighs' length (m, NaN without it)).
Row = tuple[np.ndarray | None, dict[str, np.ndarray], np.ndarray | None, float, float, float, float]
PREDICTORS = ("1", "sex", "build", "thigh")
BELOW_PREDICTORS = ("1", "sex", "thigh")


def collect(n: int, seed: int, condition: str, cache: dict, narrow: bool = False, macros: str = "standard") -> list[Row]:
    """The rows of the first ``n`` subjects of a cohort seed (read from and added to ``cache``); ``narrow``: the
    cohort standing with its feet nearly together (bsv.bodies.NARROW_HIP_ABDUCTION_RANGE_DEG); ``macros``: the
    cohort's macro ranges (bsv.bodies.MACRO_RANGES; "wide": MakeHuman's gender, muscle and proportions over
    their whole range)."""
    out = []
    tag = (" narrow" if narrow else "") + ("" if macros == "standard" else f" {macros}")
    for i in tqdm(range(n), desc=f"seed {seed}{tag}", unit="subject"):
        key = f"{seed}/{i}/{condition}" + ("/narrow" if narrow else "") + ("" if macros == "standard" else f"/{macros}")
        if key not in cache:
            s = bsv.bodies.subject(i, seed, leg_range=NARROW_HIP_ABDUCTION_RANGE_DEG if narrow
                                   else HIP_ABDUCTION_RANGE_DEG, macros=macros)
            mesh = s.body.mesh()
            loops = {name: np.asarray(mesh.vertices)[v].mean(axis=0).tolist() for name, v, _ in boundary_rings(mesh)}
            with tempfile.TemporaryDirectory(prefix="bsv-capture-") as tmp:
                bsv.scan(mesh, condition, seed * 1000 + i, images=tmp, overwrite=True, room=True)
                segs, joints = camera_segmentations(tmp)
                depths, cameras = capture_views_geometry(tmp)
                crotch = crotch_from_depth(segs, depths, cameras, joints, gate=False)
            frame = body_frame({k: np.asarray(j.xyz) for k, j in joints.items()})
            sex = next((g.sex for g in segs.values() if g.sex is not None), None)
            below = thigh = float("nan")
            if crotch is not None and frame is not None and all(f"{k}_{s}" in joints for k in ("hip", "knee") for s in "lr"):
                hips = (np.asarray(joints["hip_l"].xyz) + np.asarray(joints["hip_r"].xyz)) / 2
                below = float((hips - crotch.xyz) @ frame[1])
                thigh = float(np.mean([np.linalg.norm(np.asarray(joints[f"hip_{s}"].xyz) - np.asarray(joints[f"knee_{s}"].xyz))
                                       for s in "lr"]))
            cache[key] = {"crotch": None if crotch is None else crotch.xyz.tolist(), "loops": loops,
                          "frame": None if frame is None else frame.tolist(),
                          "sex": 0.0 if sex is None else float(sex.score),
                          "build": 0.0 if sex is None else float(build_score(sex.measurements)),
                          "below": below, "thigh": thigh,
                          "joints": {k: np.asarray(j.xyz).tolist() for k, j in joints.items()}}
        c = cache[key]
        out.append((None if c["crotch"] is None else np.array(c["crotch"]),
                    {k: np.array(v) for k, v in c["loops"].items()},
                    None if c["frame"] is None else np.array(c["frame"]), float(c["sex"]), float(c["build"]),
                    float(c["below"]), float(c["thigh"])))
    return out


def fit_below(rows: list[Row]) -> np.ndarray:
    """CROTCH_BELOW_HIPS's coefficients (BELOW_PREDICTORS order) fitted on the rows with a crotch, once on all of
    them and again without those more than CROTCH_LOW_MARGIN_M below the first fit."""
    ok = [r for r in rows if np.isfinite(r[5]) and np.isfinite(r[6])]
    x = np.array([[1.0, r[3], r[6]] for r in ok])
    y = np.array([r[5] for r in ok])
    coef = np.linalg.lstsq(x, y, rcond=None)[0]
    keep = y - x @ coef <= CROTCH_LOW_MARGIN_M
    return np.linalg.lstsq(x[keep], y[keep], rcond=None)[0]


def low(row: Row, below: np.ndarray) -> bool:
    """Whether a row's crotch lies more than CROTCH_LOW_MARGIN_M below where ``below`` expects it."""
    return bool(np.isfinite(row[5]) and row[5] - np.array([1.0, row[3], row[6]]) @ below > CROTCH_LOW_MARGIN_M)


def offsets(rows: list[Row]) -> tuple[np.ndarray, np.ndarray]:
    """(predictor rows (M, 3), offsets (M, 3) in metres, body frame, lateral outward) of every loop of the
    rows with a crotch and a frame."""
    x, y = [], []
    for crotch, loops, frame, sex, build, _, thigh in rows:
        if crotch is None or frame is None or not np.isfinite(thigh):
            continue
        for name, p in loops.items():
            local = frame @ (p - crotch)
            if name.endswith("_r"):
                local[0] = -local[0]
            x.append([1.0, sex, build, thigh])
            y.append(local)
    return np.array(x), np.array(y)


def main() -> None:
    """Command line: learn on the training seeds, evaluate on the others, print the table."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=10)
    ap.add_argument("--train-seeds", default="11,12,13,14,15,16")
    ap.add_argument("--eval-seeds", default="0,2")
    ap.add_argument("--narrow-seeds", default="", help="evaluation cohorts standing with their feet nearly together")
    ap.add_argument("--wide-train-seeds", default="", help="training cohorts drawn with the wide macro ranges")
    ap.add_argument("--wide-eval-seeds", default="", help="evaluation cohorts drawn with the wide macro ranges")
    ap.add_argument("--condition", default="noer")
    ap.add_argument("--cache", help="JSON file of measured crotches and true loops (read if present, then written)")
    a = ap.parse_args()
    cache: dict = {}
    if a.cache and Path(a.cache).is_file():
        cache = json.loads(Path(a.cache).read_text())
    try:
        train = [r for s in a.train_seeds.split(",") for r in collect(a.n, int(s), a.condition, cache)]
        train += [r for s in a.wide_train_seeds.split(",") if s for r in collect(a.n, int(s), a.condition, cache,
                                                                                 macros="wide")]
        evaluation = [r for s in a.eval_seeds.split(",") for r in collect(a.n, int(s), a.condition, cache)]
        narrow = [r for s in a.narrow_seeds.split(",") if s for r in collect(a.n, int(s), a.condition, cache, narrow=True)]
        wide = [r for s in a.wide_eval_seeds.split(",") if s for r in collect(a.n, int(s), a.condition, cache,
                                                                               macros="wide")]
    finally:
        if a.cache:
            Path(a.cache).write_text(json.dumps(cache))
    below = fit_below(train)
    print("CROTCH_BELOW_HIPS = {" + ", ".join(f'"{p}": {c:.4f}' for p, c in zip(BELOW_PREDICTORS, below, strict=True)) + "}")
    x, y = offsets([r for r in train if not low(r, below)])
    coef = np.linalg.lstsq(x, y, rcond=None)[0]
    print("HIP_LOOP_OFFSETS_M = {")
    for i, p in enumerate(PREDICTORS):
        print(f'    "{p}": ({coef[i, 0]:.4f}, {coef[i, 1]:.4f}, {coef[i, 2]:.4f}),')
    print("}")
    for name, every in (("train", train), ("eval", evaluation), ("narrow stance", narrow), ("wide macros", wide)):
        if not every:
            continue
        rows = [r for r in every if not low(r, below)]
        res = [r[5] - np.array([1.0, r[3], r[6]]) @ below for r in rows if np.isfinite(r[5])]
        print(f"\n{name}: the crotch below the hips, residual sd {np.std(res) * 1e3:.1f} mm; "
              f"{len(every) - len(rows)} captures' crotch more than {CROTCH_LOW_MARGIN_M * 1e3:.0f} mm lower "
              f"({', '.join(f'{(r[5] - np.array([1.0, r[3], r[6]]) @ below) * 1e3:+.0f}' for r in every if low(r, below))} mm)")
        xe, ye = offsets(rows)
        missing = sum(r[0] is None for r in rows)
        const = ye - y.mean(axis=0)
        fitted = ye - xe @ coef
        print(f"{name}: {len(rows)} captures, {missing} without a crotch; the loops' residual mm (lateral, up, forward)")
        print(f"  constant: mean {np.round(const.mean(axis=0) * 1e3, 1)} sd {np.round(const.std(axis=0) * 1e3, 1)}")
        print(f"  fitted:   mean {np.round(fitted.mean(axis=0) * 1e3, 1)} sd {np.round(fitted.std(axis=0) * 1e3, 1)}")


if __name__ == "__main__":
    main()

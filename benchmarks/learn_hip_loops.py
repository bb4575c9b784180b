"""Learns bsv.frontend.groin.HIP_LOOP_OFFSETS_M: where each thigh's boundary loop with the torso lies from
the crotch the depth images show, and evaluates it on other cohorts.

For every subject of the training cohorts (seeds ``--train-seeds``) and the evaluation cohorts (``--eval-seeds``)
the virtual rig captures the body in a room (``--condition``), the camera path segments both views and lifts
the joints (bsv.bench.joints.camera_segmentations) and finds the crotch (bsv.frontend.groin.crotch_from_depth).
The true loop centre of each thigh is the centre of the ring of thigh vertices next to the torso on the true
body (bsv.keypoints.boundary_rings, the ring the template's loop is pulled by). Its offset from the crotch, in
the body frame of the measured joints (lateral outward, up, forward; both sides pooled), is fitted by least
squares on the capture's sex score and build score (bsv.frontend.sex.build_score). The script prints the table
and the evaluation cohorts' residuals (mean, sd per component) with the constant alone and with the fit, and how
many captures gave no crotch.

    .venv/bin/python benchmarks/learn_hip_loops.py --n 10 --train-seeds 11,12,13,14,15,16 --eval-seeds 0,2

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
from bsv.frontend.groin import crotch_from_depth
from bsv.frontend.landmarks import body_frame
from bsv.frontend.sex import build_score
from bsv.keypoints import boundary_rings

#: One subject: (the capture's crotch or None, the true loop centres {name: xyz}, the measured joints' body
#: frame (3x3) or None, sex score, build score).
Row = tuple[np.ndarray | None, dict[str, np.ndarray], np.ndarray | None, float, float]
PREDICTORS = ("1", "sex", "build")


def collect(n: int, seed: int, condition: str, cache: dict) -> list[Row]:
    """The rows of the first ``n`` subjects of a cohort seed (read from and added to ``cache``)."""
    out = []
    for i in tqdm(range(n), desc=f"seed {seed}", unit="subject"):
        key = f"{seed}/{i}/{condition}"
        if key not in cache:
            s = bsv.bodies.subject(i, seed)
            mesh = s.body.mesh()
            loops = {name: np.asarray(mesh.vertices)[v].mean(axis=0).tolist() for name, v, _ in boundary_rings(mesh)}
            with tempfile.TemporaryDirectory(prefix="bsv-capture-") as tmp:
                bsv.scan(mesh, condition, seed * 1000 + i, images=tmp, overwrite=True, room=True)
                segs, joints = camera_segmentations(tmp)
                depths, cameras = capture_views_geometry(tmp)
                crotch = crotch_from_depth(segs, depths, cameras, joints)
            frame = body_frame({k: np.asarray(j.xyz) for k, j in joints.items()})
            sex = next((g.sex for g in segs.values() if g.sex is not None), None)
            cache[key] = {"crotch": None if crotch is None else crotch.xyz.tolist(), "loops": loops,
                          "frame": None if frame is None else frame.tolist(),
                          "sex": 0.0 if sex is None else float(sex.score),
                          "build": 0.0 if sex is None else float(build_score(sex.measurements))}
        c = cache[key]
        out.append((None if c["crotch"] is None else np.array(c["crotch"]),
                    {k: np.array(v) for k, v in c["loops"].items()},
                    None if c["frame"] is None else np.array(c["frame"]), float(c["sex"]), float(c["build"])))
    return out


def offsets(rows: list[Row]) -> tuple[np.ndarray, np.ndarray]:
    """(predictor rows (M, 3), offsets (M, 3) in metres, body frame, lateral outward) of every loop of the
    rows with a crotch and a frame."""
    x, y = [], []
    for crotch, loops, frame, sex, build in rows:
        if crotch is None or frame is None:
            continue
        for name, p in loops.items():
            local = frame @ (p - crotch)
            if name.endswith("_r"):
                local[0] = -local[0]
            x.append([1.0, sex, build])
            y.append(local)
    return np.array(x), np.array(y)


def main() -> None:
    """Command line: learn on the training seeds, evaluate on the others, print the table."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=10)
    ap.add_argument("--train-seeds", default="11,12,13,14,15,16")
    ap.add_argument("--eval-seeds", default="0,2")
    ap.add_argument("--condition", default="noer")
    ap.add_argument("--cache", help="JSON file of measured crotches and true loops (read if present, then written)")
    a = ap.parse_args()
    cache: dict = {}
    if a.cache and Path(a.cache).is_file():
        cache = json.loads(Path(a.cache).read_text())
    try:
        train = [r for s in a.train_seeds.split(",") for r in collect(a.n, int(s), a.condition, cache)]
        evaluation = [r for s in a.eval_seeds.split(",") for r in collect(a.n, int(s), a.condition, cache)]
    finally:
        if a.cache:
            Path(a.cache).write_text(json.dumps(cache))
    x, y = offsets(train)
    coef = np.linalg.lstsq(x, y, rcond=None)[0]
    print("HIP_LOOP_OFFSETS_M = {")
    for i, p in enumerate(PREDICTORS):
        print(f'    "{p}": ({coef[i, 0]:.4f}, {coef[i, 1]:.4f}, {coef[i, 2]:.4f}),')
    print("}")
    for name, rows in (("train", train), ("eval", evaluation)):
        xe, ye = offsets(rows)
        missing = sum(r[0] is None for r in rows)
        const = ye - y.mean(axis=0)
        fitted = ye - xe @ coef
        print(f"\n{name}: {len(rows)} captures, {missing} without a crotch; residual mm (lateral, up, forward)")
        print(f"  constant: mean {np.round(const.mean(axis=0) * 1e3, 1)} sd {np.round(const.std(axis=0) * 1e3, 1)}")
        print(f"  fitted:   mean {np.round(fitted.mean(axis=0) * 1e3, 1)} sd {np.round(fitted.std(axis=0) * 1e3, 1)}")


if __name__ == "__main__":
    main()

#!/usr/bin/env python
"""Tunes the cut lines of the camera segmentation (bsv.frontend.segment) on segment VOLUME error.

Per subject (cohort seed x index) the virtual capture ("noer", as ``bsv demo`` does it) and MediaPipe
Holistic (pose, hands, cleaned and depth-refined person mask) run once and are cached in ``--cache``;
every parameter set then only re-runs ``label_pixels`` -> cloud building -> registration -> volumes, and
compares the 9 trunk_limbs segments (and trunk_limbs) with the body's ground truth, plus the per-view pixel
IoU per segment against the scanner's label image.

    .venv/bin/python benchmarks/tune_segmentation.py --sets fit,held            # current defaults
    .venv/bin/python benchmarks/tune_segmentation.py --sets fit --config front.knee_shift=0.15 \
        --config back.knee_shift=0.1                                             # one candidate
    .venv/bin/python benchmarks/tune_segmentation.py --sets fit --search        # coordinate search

Sets: fit = cohort seed 1, subjects 0-3; held = cohort seed 7, subjects 0-3; demo = the `bsv demo` subject
(seed 0, subject 0). Objective: mean |error %|
over the 9 trunk_limbs segments and the subjects.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import pickle
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

SEGMENTS = ["torso", "upper_arm_l", "upper_arm_r", "forearm_l", "forearm_r",
            "thigh_l", "thigh_r", "shin_l", "shin_r"]
SETS = {"fit": (1, range(4)), "held": (7, range(4)), "demo": (0, range(1))}
CAMERAS = ("front", "back")


def prepared(cache: Path, seed: int, index: int) -> dict[str, Any]:
    """Capture and MediaPipe results of one subject (cached): per camera the oriented pose, hands, mask,
    truth labels, depth, intrinsics and extrinsics; and the true volumes."""
    f = cache / f"seg_s{seed}_i{index}.pkl"
    if f.is_file():
        return pickle.loads(f.read_bytes())
    import bsv
    from bsv import bodies
    from bsv.frontend import segment as sg
    from bsv.frontend.capture import read_capture
    from bsv.frontend.landmarks import Camera
    from bsv.pipeline import _calibration, _read_label_png

    subj = bodies.subject(index, seed)
    cap = cache / f"capture_s{seed}_i{index}"
    bsv.scan(subj.body.mesh(), "noer", seed, images=cap, overwrite=True)
    data = {cam: read_capture(cap / cam) for cam in CAMERAS}
    ext = _calibration(cap / "calibration.json", cap, CAMERAS, {c: d["intrinsics"] for c, d in data.items()})
    out: dict[str, Any] = {"truth": {k: float(v) for k, v in subj.volumes_l().items()}, "views": {}}
    for cam in CAMERAS:
        d = data[cam]
        prm = sg.DEFAULT_PARAMS[cam]
        camera = Camera.from_json(d["intrinsics"], ext[cam])
        # oriented; averaged with the mirror image (flip_average); on the neutral background, as bsv process does
        det = sg.detect(d["colour"], cam, prm, depth=d["depth_m"], camera=camera)
        pose, hands = det.pose, det.hands
        if det.mask_soft is None:
            raise SystemExit(f"{cap / cam}: MediaPipe returned no person mask")
        mask = sg._clean_mask(det.mask_soft > prm.mask_threshold)
        mask = sg.refine_mask_with_depth(mask, d["depth_m"], prm.depth_band, prm.depth_grow_px)
        truth_lab = _read_label_png(cap / cam / d["meta"].get("labels", "labels.png"))
        out["views"][cam] = {"pose": pose, "hands": hands, "mask": mask, "truth_labels": truth_lab,
                             "intrinsics": d["intrinsics"].to_json(), "camera_to_world": ext[cam],
                             "depth": np.ascontiguousarray(d["depth_m"], dtype=np.float32),
                             "colors": np.ascontiguousarray(d["colour"], dtype=np.uint8)}
    cache.mkdir(parents=True, exist_ok=True)
    f.write_bytes(pickle.dumps(out))
    return out


def evaluate(subj: dict[str, Any], params: dict[str, Any]) -> dict[str, Any]:
    """Signed volume error % per segment and pixel IoU per view for one prepared subject."""
    import bsv
    from bsv.frontend import segment as sg
    from bsv.pipeline import build_cloud, compare

    views, ious = [], {}
    for cam in CAMERAS:
        v = subj["views"][cam]
        labels = sg.label_pixels(v["mask"], v["pose"], v["hands"], params[cam])
        acc = sg.label_accuracy(labels, v["truth_labels"])
        ious[cam] = {"accuracy": acc["accuracy"], **acc["iou"]}
        views.append({"name": cam, "intrinsics": v["intrinsics"], "camera_to_world": v["camera_to_world"],
                      "depth": v["depth"], "labels": labels, "colors": v["colors"]})
    cloud, _ = build_cloud(views)
    reg = bsv.register(cloud, progress=False)
    rows = compare(dict(reg.volumes), subj["truth"])
    return {"err": {r["segment"]: r["error_pct"] for r in rows}, "iou": ious}


def parse_config(items: list[str], base: dict[str, Any]) -> dict[str, Any]:
    """``view.field=value`` (view front/back/both) overrides on top of ``base``."""
    out = dict(base)
    for kv in items:
        key, val = kv.split("=", 1)
        view, name = key.split(".", 1)
        for cam in (CAMERAS if view == "both" else (view,)):
            out[cam] = dataclasses.replace(out[cam], **{name: json.loads(val)})
    return out


def run_set(subjects: list[dict[str, Any]], params: dict[str, Any]) -> list[dict[str, Any]]:
    return [evaluate(s, params) for s in subjects]


def objective(results: list[dict[str, Any]]) -> float:
    return float(np.mean([abs(r["err"][s]) for r in results for s in SEGMENTS]))


def table(name: str, results: list[dict[str, Any]]) -> str:
    """Mean signed error, mean |error| per segment, mean IoU per view."""
    lines = [f"== {name}: objective mean|err| = {objective(results):.2f} %",
             f"{'segment':<13}{'mean err%':>10}{'mean|err|%':>11}{'IoU front':>10}{'IoU back':>9}"]
    for s in [*SEGMENTS, "trunk_limbs"]:
        e = [r["err"][s] for r in results]
        iou = ["" if s == "trunk_limbs" else f"{np.nanmean([r['iou'][c][s] for r in results]):.3f}" for c in CAMERAS]
        lines.append(f"{s:<13}{np.mean(e):>+10.2f}{np.mean(np.abs(e)):>11.2f}{iou[0]:>10}{iou[1]:>9}")
    acc = [f"{np.mean([r['iou'][c]['accuracy'] for r in results]):.3f}" for c in CAMERAS]
    lines.append(f"{'pixel acc':<13}{'':>10}{'':>11}{acc[0]:>10}{acc[1]:>9}")
    return "\n".join(lines)


#: Coordinate-search space: (view, field, step).
SEARCH = [
    ("both", "hip_raise", 0.05), ("both", "crotch_drop", 0.05), ("both", "hip_widen", 0.1),
    ("both", "shoulder_inset", 0.05), ("both", "knee_shift", 0.03), ("both", "elbow_shift", 0.04),
    ("front", "knee_shift", 0.03), ("back", "knee_shift", 0.03), ("both", "torso_weight", 0.1),
    ("front", "shoulder_inset", 0.05), ("back", "shoulder_inset", 0.05), ("front", "hip_raise", 0.05),
    ("back", "hip_raise", 0.05), ("front", "elbow_shift", 0.04), ("back", "elbow_shift", 0.04),
    ("both", "wrist_shift", 0.03),
]


def search(subjects: list[dict[str, Any]], params: dict[str, Any], rounds: int, budget_s: float,
           step_scale: float = 1.0) -> dict[str, Any]:
    """Greedy coordinate search on the objective (each field moved by +-step * step_scale while it
    improves by more than 0.02 points)."""
    t0 = time.time()
    best = objective(run_set(subjects, params))
    print(f"start {best:.3f}", flush=True)
    for _ in range(rounds):
        improved = False
        for view, name, step0 in SEARCH:
            step = step0 * step_scale
            for sign in (1, -1):
                while time.time() - t0 < budget_s:
                    cand = dict(params)
                    for cam in (CAMERAS if view == "both" else (view,)):
                        cand[cam] = dataclasses.replace(cand[cam], **{name: round(getattr(cand[cam], name) + sign * step, 4)})
                    try:
                        val = objective(run_set(subjects, cand))
                    except Exception as e:  # invalid parameter values end the direction
                        print(f"  {view}.{name} {sign:+d}: {e}", flush=True)
                        break
                    print(f"  {view}.{name} {'+' if sign > 0 else '-'}{step}: {val:.3f} (best {best:.3f})", flush=True)
                    if val < best - 0.02:
                        best, params, improved = val, cand, True
                    else:
                        break
        if not improved or time.time() - t0 >= budget_s:
            break
    for cam in CAMERAS:
        print(f"{cam}: {params[cam]}")
    return params


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sets", default="fit", help="comma list of fit, held")
    ap.add_argument("--cache", default="/tmp/bsv_tune_seg", help="cache folder of captures and MediaPipe results")
    ap.add_argument("--config", action="append", default=[], metavar="VIEW.FIELD=VALUE",
                    help="parameter override on top of DEFAULT_PARAMS (view front/back/both; repeatable)")
    ap.add_argument("--search", action="store_true", help="coordinate search on the first set")
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--budget", type=float, default=900.0, help="search wall-time budget in seconds")
    ap.add_argument("--step-scale", type=float, default=1.0, help="multiplies the search steps")
    a = ap.parse_args()
    from bsv.frontend.segment import DEFAULT_PARAMS

    params = parse_config(a.config, dict(DEFAULT_PARAMS))
    cache = Path(a.cache)
    sets = {name: [prepared(cache, SETS[name][0], i) for i in SETS[name][1]] for name in a.sets.split(",")}
    if a.search:
        params = search(sets[a.sets.split(",")[0]], params, a.rounds, a.budget, a.step_scale)
    for name, subjects in sets.items():
        res = run_set(subjects, params)
        print(table(f"{name} (seed {SETS[name][0]})", res), flush=True)
        for i, r in enumerate(res):
            print(f"  subject {i}: " + " ".join(f"{s}={r['err'][s]:+.1f}" for s in [*SEGMENTS, "trunk_limbs"]))
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Learns the fixed joint-centre offsets of bsv.frontend.landmarks.JOINT_OFFSETS_M on one synthetic cohort
and evaluates them on another.

For every subject of the training cohort (seed ``--train-seed``) and the evaluation cohort (``--eval-seed``)
the virtual rig captures the body in a room (noer), the camera path lifts the joints to 3-D WITHOUT the
offsets, and the signed errors against the rig's joint centres are taken in the body frame. The offset of
a joint kind is minus the median training error (left and right pooled, lateral mirrored); the script
prints it as a Python table and the evaluation cohort's errors before and after.

    .venv/bin/python benchmarks/learn_joint_offsets.py --n 6 --train-seed 11 --eval-seed 12
"""

from __future__ import annotations

import argparse
import json
import tempfile

import numpy as np
from tqdm import tqdm

import bsv
from bsv.bench.joints import KINDS, camera_segmentations, joint_errors
from bsv.bodies.joints import rig_joints
from bsv.frontend.landmarks import apply_offsets


def raw_joints(n: int, seed: int, condition: str) -> list[tuple[dict, dict]]:
    """(uncorrected joint centres, true joint centres) of the first ``n`` subjects of a cohort seed."""
    out = []
    for i in tqdm(range(n), desc=f"seed {seed}", unit="subject"):
        s = bsv.bodies.subject(i, seed)
        with tempfile.TemporaryDirectory(prefix="bsv-joints-") as tmp:
            bsv.scan(s.body.mesh(), condition, seed * 1000 + i, images=tmp, overwrite=True, room=True)
            _, joints = camera_segmentations(tmp, correct=False)
        out.append(({k: j.xyz for k, j in joints.items()}, rig_joints(s.phenotype, s.pose)))
    return out


def table(pairs: list[tuple[dict, dict]], offsets: dict | None) -> dict[str, tuple[float, float, list[float]]]:
    """kind -> (median, p95 of the 3-D error mm, median signed [lat, up, fwd] mm), offsets applied if given."""
    errs: dict[str, list[list[float]]] = {k: [] for k in KINDS}
    for est, truth in pairs:
        moved = apply_offsets(est, offsets) if offsets is not None else est
        for j, e in joint_errors(moved, truth).items():
            errs[j.rsplit("_", 1)[0]].append(e)
    out = {}
    allv = []
    for k, v in errs.items():
        a = np.array(v)
        allv += v
        d = np.linalg.norm(a, axis=1)
        out[k] = (float(np.median(d)), float(np.percentile(d, 95)), np.median(a, axis=0).round(1).tolist())
    a = np.array(allv)
    d = np.linalg.norm(a, axis=1)
    out["all"] = (float(np.median(d)), float(np.percentile(d, 95)), np.median(a, axis=0).round(1).tolist())
    return out


def main() -> None:
    """Command line: learn on one seed, evaluate on another, print the tables."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=6)
    ap.add_argument("--train-seed", type=int, default=11)
    ap.add_argument("--eval-seed", type=int, default=12)
    ap.add_argument("--condition", default="noer")
    a = ap.parse_args()
    train = raw_joints(a.n, a.train_seed, a.condition)
    evaluation = raw_joints(a.n, a.eval_seed, a.condition)
    learned = {k: tuple(round(-c / 1000.0, 4) for c in v[2]) for k, v in table(train, None).items() if k != "all"}
    print("JOINT_OFFSETS_M =", json.dumps(learned, indent=1))
    for name, pairs, off in (("train, raw", train, None), ("eval, raw", evaluation, None),
                             ("eval, corrected", evaluation, learned)):
        print(f"\n{name}: joint | median mm | p95 mm | signed median lat/up/fwd mm")
        for k, (med, p95, signed) in table(pairs, off).items():
            print(f"  {k:9s} {med:6.1f} {p95:6.1f}  {signed}")


if __name__ == "__main__":
    main()

"""Learns the joint-centre offsets of bsv.frontend.landmarks.JOINT_OFFSETS_M on synthetic cohorts and
evaluates them on others.

For every subject of the training cohorts (seeds ``--train-seeds``) and the evaluation cohorts (``--eval-seeds``)
the virtual rig captures the body in a room (noer), the camera path lifts the joints to 3-D WITHOUT the
offsets, and the signed errors against the rig's joint centres are taken in the body frame. The offset of
a joint kind is minus the least-squares fit of the training errors (left and right pooled, lateral
mirrored) as a linear function of the kind's predictors (the keys of its row of JOINT_OFFSETS_M: the
constant, the trunk length, for the hip and the shoulder also the hip and shoulder widths and the leg length, each minus its
reference: bsv.frontend.landmarks.offset_predictors); the script prints the table and the evaluation
cohorts' errors without offsets, with a constant offset (the median), with the trunk length alone and with
the fit. It then learns where the elbow lies along the line from the shoulder to the wrist, both corrected by
the shipped offsets (JOINT_OFFSETS_M, so that the elbow's table can be updated alone):
bsv.frontend.landmarks.ELBOW_FRACTION, the least squares of the rig's elbow's fraction of that line on the
capture's sex score, and ELBOW_LANDMARK_WEIGHT, the weight of the landmark's own place against it (the one of
0, 0.05, ..., 1 whose along-arm error scatters least on the training subjects); it prints the evaluation
cohorts' errors with them too.

    .venv/bin/python benchmarks/learn_joint_offsets.py --n 10 --train-seeds 11,12,13,14,15,16,17,18 \
        --eval-seeds 0,2,4,6

``--cache FILE`` keeps the uncorrected joint centres (JSON) so that a second run re-learns without MediaPipe.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
from tqdm import tqdm

import bsv
from bsv.bench.joints import KINDS, joint_errors, subject_segmentations
from bsv.bodies.joints import rig_joints
from bsv.frontend.landmarks import (
    JOINT_OFFSETS_M,
    apply_offsets,
    body_frame,
    build_measurements,
    elbows_at_proportion,
    offset_predictors,
)

#: One training or evaluation subject: (uncorrected joint centres, true joint centres, the capture's sex score).
Pair = tuple[dict, dict, float]


def raw_joints(n: int, seed: int, condition: str, cache: dict) -> list[Pair]:
    """(uncorrected joint centres, true joint centres, sex score) of the first ``n`` subjects of a cohort seed
    (read from and added to ``cache``: key "seed/index/condition" -> {"est": ..., "truth": ..., "sex_score": ...};
    an entry of an older cache without the sex score is made again)."""
    out = []
    for i in tqdm(range(n), desc=f"seed {seed}", unit="subject"):
        key = f"{seed}/{i}/{condition}"
        if "sex_score" not in cache.get(key, {}):
            s = bsv.bodies.subject(i, seed)
            segs, joints = subject_segmentations(s, condition, seed * 1000 + i, correct=False)
            sex = next((g.sex for g in segs.values() if g.sex is not None), None)
            cache[key] = {"est": {k: j.xyz.tolist() for k, j in joints.items()},
                          "truth": {k: v.tolist() for k, v in rig_joints(s.phenotype, s.pose).items()},
                          "sex_score": 0.0 if sex is None else float(sex.score)}
        c = cache[key]
        out.append(({k: np.array(v) for k, v in c["est"].items()}, {k: np.array(v) for k, v in c["truth"].items()},
                    float(c["sex_score"])))
    return out


def table(pairs: list[Pair], offsets: dict | None, elbows: tuple[dict, float] | None = None,
          ) -> dict[str, tuple[float, float, list[float], list[float]]]:
    """kind -> (median, p95 of the 3-D error mm, median signed [lat, up, fwd] mm, their sd), offsets applied
    if given, then the elbows moved along the arms (``elbows``: fraction table and landmark weight) if given."""
    errs: dict[str, list[list[float]]] = {k: [] for k in KINDS}
    for est, truth, sex in pairs:
        moved = apply_offsets(est, offsets) if offsets is not None else est
        if elbows is not None:
            moved = elbows_at_proportion(moved, sex, elbows[0], elbows[1])
        for j, e in joint_errors(moved, truth).items():
            errs[j.rsplit("_", 1)[0]].append(e)
    out = {}
    allv = []
    for k, v in errs.items():
        a = np.array(v)
        allv += v
        d = np.linalg.norm(a, axis=1)
        out[k] = (float(np.median(d)), float(np.percentile(d, 95)), np.median(a, axis=0).round(1).tolist(),
                  a.std(axis=0).round(1).tolist())
    a = np.array(allv)
    d = np.linalg.norm(a, axis=1)
    out["all"] = (float(np.median(d)), float(np.percentile(d, 95)), np.median(a, axis=0).round(1).tolist(),
                  a.std(axis=0).round(1).tolist())
    return out


def main() -> None:
    """Command line: learn on the training seeds, evaluate on the others, print the tables."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=10)
    ap.add_argument("--train-seeds", default="11,12,13,14,15,16,17,18")
    ap.add_argument("--eval-seeds", default="0,2,4,6")
    ap.add_argument("--condition", default="noer")
    ap.add_argument("--cache", help="JSON file of uncorrected joint centres (read if present, then written)")
    a = ap.parse_args()
    cache: dict = {}
    if a.cache and Path(a.cache).is_file():
        cache = json.loads(Path(a.cache).read_text())
    train = [p for s in a.train_seeds.split(",") for p in raw_joints(a.n, int(s), a.condition, cache)]
    evaluation = [p for s in a.eval_seeds.split(",") for p in raw_joints(a.n, int(s), a.condition, cache)]
    if a.cache:
        Path(a.cache).write_text(json.dumps(cache))
    constant = {k: {"1": tuple(-c / 1000.0 for c in v[2])} for k, v in table(train, None).items() if k != "all"}
    trunk_only = fit(train, dict.fromkeys(KINDS, ("1", "trunk")))
    learned = fit(train, {k: tuple(JOINT_OFFSETS_M[k]) for k in KINDS})
    print("OFFSET_PREDICTOR_RANGE = {")
    for name, (lo, hi) in predictor_range(train).items():
        print(f'    "{name}": ({lo:.3f}, {hi:.3f}),')
    print("}")
    print("JOINT_OFFSETS_M = {")
    for k, row in learned.items():
        cells = ", ".join(f'"{p}": ({c[0]:.4f}, {c[1]:.4f}, {c[2]:.4f})' for p, c in row.items())
        print(f'    "{k}": {{{cells}}},')
    print("}")
    # on top of the shipped offsets, so that the elbow table can be updated alone
    fraction, weight = learn_elbows(train, JOINT_OFFSETS_M)
    print(f'ELBOW_FRACTION = {{"1": {fraction["1"]:.4f}, "sex": {fraction["sex"]:.4f}}}')
    print(f"ELBOW_LANDMARK_WEIGHT = {weight:.2f}")
    runs: list[tuple[str, list[Pair], dict | None, tuple[dict, float] | None]] = [
        ("train, raw", train, None, None), ("eval, raw", evaluation, None, None),
        ("eval, constant offset", evaluation, constant, None), ("eval, trunk length only", evaluation, trunk_only, None),
        ("eval, fitted", evaluation, learned, None),
        ("eval, shipped offsets", evaluation, JOINT_OFFSETS_M, None),
        ("eval, shipped offsets, elbows at the arm's proportion", evaluation, JOINT_OFFSETS_M, (fraction, weight))]
    for name, pairs, off, elbows in runs:
        print(f"\n{name}: joint | median mm | p95 mm | signed median lat/up/fwd mm | sd lat/up/fwd mm")
        for k, (med, p95, signed, sd) in table(pairs, off, elbows).items():
            print(f"  {k:9s} {med:6.1f} {p95:6.1f}  {signed}  {sd}")


def learn_elbows(pairs: list[Pair], offsets: dict) -> tuple[dict[str, float], float]:
    """(ELBOW_FRACTION, ELBOW_LANDMARK_WEIGHT) of the training subjects, their joints corrected by ``offsets``:
    the true elbow's fraction along the corrected shoulder-to-wrist line fitted on the sex score, and the
    landmark weight whose along-arm error scatters least (see the module notes)."""
    rows = []  # (sex score, arm length m, the landmark's fraction, the true elbow's fraction)
    for est, truth, sex in pairs:
        moved = apply_offsets(est, offsets)
        for side in ("l", "r"):
            names = (f"shoulder_{side}", f"elbow_{side}", f"wrist_{side}")
            if all(n in moved for n in names) and f"elbow_{side}" in truth:
                sh, el, wr = (moved[n] for n in names)
                length = float(np.linalg.norm(wr - sh))
                if not np.isfinite(length) or length <= 0.0:  # elbows_at_proportion leaves such an arm alone
                    continue
                u = (wr - sh) / length
                rows.append((sex, length, float((el - sh) @ u) / length, float((truth[f"elbow_{side}"] - sh) @ u) / length))
    r = np.array(rows)
    x = np.column_stack([np.ones(len(r)), r[:, 0]])
    coef = np.linalg.lstsq(x, r[:, 3], rcond=None)[0]
    prop = x @ coef
    weights = np.linspace(0.0, 1.0, 21)
    spread = [float(np.std((w * r[:, 2] + (1 - w) * prop - r[:, 3]) * r[:, 1])) for w in weights]
    return {"1": round(float(coef[0]), 4), "sex": round(float(coef[1]), 4)}, float(weights[int(np.argmin(spread))])


def predictor_range(pairs: list[Pair]) -> dict[str, tuple[float, float]]:
    """Per build measurement (bsv.frontend.landmarks.build_measurements, unclipped): the training range widened
    by a quarter of its span on each side (bsv.frontend.landmarks.OFFSET_PREDICTOR_RANGE)."""
    values: dict[str, list[float]] = {}
    for est, _, _ in pairs:
        for k, v in build_measurements(est).items():
            if np.isfinite(v):
                values.setdefault(k, []).append(float(v))
    out = {}
    for k, v in values.items():
        lo, hi = min(v), max(v)
        out[k] = (lo - (hi - lo) / 4, hi + (hi - lo) / 4)
    return out


def fit(pairs: list[Pair], predictors: dict[str, tuple[str, ...]],
        ) -> dict[str, dict[str, tuple[float, float, float]]]:
    """Per kind ``{predictor: c}``: minus the least-squares fit of the signed errors (m) as a linear function
    of the kind's ``predictors`` (names of bsv.frontend.landmarks.OFFSET_PREDICTORS)."""
    rows: dict[str, list[tuple[dict[str, float], list[float]]]] = {k: [] for k in KINDS}
    for est, truth, _ in pairs:
        if body_frame(est) is None:  # apply_offsets leaves such joints unmoved: they teach nothing
            continue
        m = offset_predictors(est)
        for j, e in joint_errors(est, truth).items():
            rows[j.rsplit("_", 1)[0]].append((m, e))
    out = {}
    for k, r in rows.items():
        names = predictors[k]
        x = np.array([[m[p] for p in names] for m, _ in r])
        y = np.array([e for _, e in r]) / 1000.0
        coef = np.linalg.lstsq(x, y, rcond=None)[0]
        out[k] = {p: tuple(round(float(-c), 4) for c in coef[i]) for i, p in enumerate(names)}
    return out


if __name__ == "__main__":
    main()

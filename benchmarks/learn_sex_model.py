"""Learns bsv.frontend.sex.SEX_MODEL (the probability that a subject is a woman from four measurements of the
capture) on synthetic cohorts and evaluates it on others.

For every subject of the training cohorts (``--train-seeds``) and the evaluation cohorts (``--eval-seeds``) the
virtual rig captures the body in a room (noer) and the camera path segments both views
(bsv.frontend.landmarks.segment_views), which takes the measurements of bsv.frontend.sex.sex_measurements.
A ridge-regularised logistic regression (``--ridge`` on the standardised measurements, Newton's method) is
fitted to the training subjects' sexes (each measurement clipped to the training range widened by a quarter of
its span, as the model applies it); the script prints the SEX_MODEL table and, on the evaluation
cohorts, the accuracy, the mean distance of the score 2p - 1 from the true +-1 (in units of a given sex's
shift: 0 is a known sex, 0.5 the average body) and the subjects named confidently but wrongly.

    .venv/bin/python benchmarks/learn_sex_model.py --train-seeds 11,12,13,14,15,16,17,18 --eval-seeds 0,1,2,3,4,5,6,7

With ``--wide-train-seeds`` (cohorts of the wide macro ranges, ``bsv.bodies.subject(macros="wide")``: MakeHuman's
gender over its whole scale) it also fits a gender model, the same logistic form fitted to the fractional target
1 - gender on the training seeds of both kinds, and prints, on every set, each model's score 2p - 1 against the
true 1 - 2 x gender (rms, and the subjects on the wrong side of 0). Round 2 session 46 tried that model's score
for the shoulder lines and did not keep it (BENCH.md):

    .venv/bin/python benchmarks/learn_sex_model.py --train-seeds 11,12,13,14,15,16,17,18 --eval-seeds "" \
        --wide-train-seeds 11,12,13,14 --wide-eval-seeds 0,1

``--cache FILE`` keeps the measurements (JSON) so that a second run re-learns without MediaPipe; ``--only-measure``
fills the cache and stops (two such runs on disjoint seeds can share the two cores).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
from tqdm import tqdm

import bsv
from bsv.bench.joints import subject_segmentations
from bsv.frontend.sex import NAMED_AT, SEX_MEASUREMENTS


def measure(n: int, seed: int, cache: dict, macros: str = "standard",
            target: str = "female") -> list[tuple[dict[str, float], float]]:
    """(measurements, target) of the first ``n`` subjects of a cohort seed drawn with the ``macros`` ranges (read
    from and added to ``cache``: key "seed/index" (+ "/wide") -> {"m": ..., "female": ..., "gender": ...}). The
    target: ``"female"`` 1 for a woman else 0; ``"gender"`` 1 - MakeHuman's gender macro (1 the most female body,
    0 the most male)."""
    out = []
    for i in tqdm(range(n), desc=f"seed {seed}{'' if macros == 'standard' else ' ' + macros}", unit="subject"):
        key = f"{seed}/{i}" + ("" if macros == "standard" else f"/{macros}")
        if "gender" not in cache.get(key, {}):
            s = bsv.bodies.subject(i, seed, macros=macros)
            segs, _ = subject_segmentations(s, "noer", seed * 1000 + i)
            est = segs["front"].sex
            cache[key] = {"m": dict(est.measurements) if est is not None else {}, "female": s.sex == "female",
                          "gender": float(s.phenotype.gender)}
        c = cache[key]
        y = (1.0 if c["female"] else 0.0) if target == "female" else 1.0 - float(c["gender"])
        out.append(({k: float(c["m"].get(k, np.nan)) for k in SEX_MEASUREMENTS}, y))
    return out


def fit(rows: list[tuple[dict[str, float], float]], ridge: float) -> dict:
    """SEX_MODEL fitted to ``rows`` (subjects with a missing measurement left out)."""
    ok = [(m, y) for m, y in rows if all(np.isfinite(m[k]) for k in SEX_MEASUREMENTS)]
    X = np.array([[m[k] for k in SEX_MEASUREMENTS] for m, _ in ok])
    y = np.array([y for _, y in ok])
    mean, scale = X.mean(axis=0), X.std(axis=0)
    Z = np.column_stack([np.ones(len(X)), (X - mean) / scale])
    w = np.zeros(Z.shape[1])
    penalty = ridge * np.diag(np.r_[0.0, np.ones(Z.shape[1] - 1)])
    for _ in range(100):
        p = 1.0 / (1.0 + np.exp(-Z @ w))
        step = np.linalg.solve(Z.T @ (Z * (p * (1 - p))[:, None]) + penalty, Z.T @ (p - y) + penalty @ w)
        w -= step
        if np.abs(step).max() < 1e-10:
            break
    lo, hi = X.min(axis=0), X.max(axis=0)
    widened = np.column_stack([lo - (hi - lo) / 4, hi + (hi - lo) / 4])
    return {"intercept": float(w[0]),
            "range": {k: (float(a), float(b)) for k, (a, b) in zip(SEX_MEASUREMENTS, widened, strict=True)},
            "mean": {k: float(v) for k, v in zip(SEX_MEASUREMENTS, mean, strict=True)},
            "scale": {k: float(v) for k, v in zip(SEX_MEASUREMENTS, scale, strict=True)},
            "coef": {k: float(v) for k, v in zip(SEX_MEASUREMENTS, w[1:], strict=True)}}


def probability(model: dict, m: dict[str, float]) -> float:
    """The model's p(female) of one subject's measurements (NaN when one is missing)."""
    z = model["intercept"] + sum(model["coef"][k] * (float(np.clip(m[k], *model["range"][k])) - model["mean"][k])
                                 / model["scale"][k] for k in SEX_MEASUREMENTS)
    return float(1.0 / (1.0 + np.exp(-z)))


def report(name: str, model: dict, rows: list[tuple[dict[str, float], float]]) -> None:
    """Accuracy, mean score distance and confident mistakes of ``model`` on ``rows``."""
    p = np.array([probability(model, m) for m, _ in rows])
    y = np.array([y for _, y in rows])
    ok = np.isfinite(p)
    p, y = p[ok], y[ok]
    score_gap = np.abs((2 * p - 1) - (2 * y - 1)) / 2
    named = (p >= NAMED_AT) | (p <= 1 - NAMED_AT)
    wrong = named & ((p >= 0.5) != (y == 1))
    print(f"{name}: n {len(p)} (not measurable {int((~ok).sum())}), accuracy {np.mean((p >= 0.5) == (y == 1)):.3f}, "
          f"mean |score - truth| / 2 {score_gap.mean():.3f} (worst {score_gap.max():.2f}), named {named.mean():.2f}, "
          f"named wrongly {int(wrong.sum())}")


def print_model(name: str, model: dict) -> None:
    """Prints a fitted model (:func:`fit`) as the Python table it is pasted as."""
    print(f"{name} = {{")
    print(f'    "intercept": {model["intercept"]:.4f},')
    for part in ("mean", "scale", "coef"):
        cells = ", ".join(f'"{k}": {v:.4g}' for k, v in model[part].items())
        print(f'    "{part}": {{{cells}}},')
    cells = ", ".join(f'"{k}": ({lo:.4g}, {hi:.4g})' for k, (lo, hi) in model["range"].items())
    print(f'    "range": {{{cells}}},')
    print("}")


def report_scores(name: str, models: dict[str, dict], rows: list[tuple[dict[str, float], float]]) -> None:
    """Each model's score 2p - 1 against the true continuous score 1 - 2 x gender: rms and the subjects on the wrong
    side of 0."""
    truth = np.array([2 * y - 1 for _, y in rows])
    cells = []
    for label, model in models.items():
        score = np.array([2 * probability(model, m) - 1 for m, _ in rows])
        ok = np.isfinite(score)
        cells.append(f"{label} rms {np.sqrt(np.mean((score[ok] - truth[ok]) ** 2)):.2f}, "
                     f"wrong side {int(np.sum(np.sign(score[ok]) != np.sign(truth[ok])))}")
    print(f"{name} (n {len(rows)}), the score against 1 - 2 gender: " + "; ".join(cells))


def main() -> None:
    """Command line: measure, learn on the training seeds, evaluate on the others, print the table."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=10)
    ap.add_argument("--train-seeds", default="11,12,13,14,15,16,17,18")
    ap.add_argument("--eval-seeds", default="0,1,2,3,4,5,6,7")
    ap.add_argument("--ridge", type=float, default=1.0)
    ap.add_argument("--cache", action="append", default=[],
                    help="JSON file of measurements (repeatable: all are read; the first is written)")
    ap.add_argument("--only-measure", action="store_true", help="fill the cache for the seeds given and stop")
    ap.add_argument("--wide-train-seeds", default="", help="cohorts of the wide macro ranges (MakeHuman's gender "
                    "over its whole scale) added to the training seeds for the gender model")
    ap.add_argument("--wide-eval-seeds", default="", help="cohorts of the wide macro ranges to evaluate on")
    a = ap.parse_args()
    cache: dict = {}
    for f in a.cache:
        if Path(f).is_file():
            cache.update(json.loads(Path(f).read_text()))
    seeds = lambda text: [int(s) for s in text.split(",") if s]  # noqa: E731
    try:
        train = [r for s in seeds(a.train_seeds) for r in measure(a.n, s, cache)]
        evaluation = [r for s in seeds(a.eval_seeds) for r in measure(a.n, s, cache)]
        gender = {name: [r for s in seeds(std) for r in measure(a.n, s, cache, target="gender")]
                  + [r for s in seeds(wide) for r in measure(a.n, s, cache, macros="wide", target="gender")]
                  for name, std, wide in (("train", a.train_seeds, a.wide_train_seeds), ("eval", a.eval_seeds, ""),
                                          ("wide eval", "", a.wide_eval_seeds))}
    finally:
        if a.cache:
            Path(a.cache[0]).write_text(json.dumps(cache))
    if a.only_measure:
        return
    model = fit(train, a.ridge)
    print_model("SEX_MODEL", model)
    report("train", model, train)
    if evaluation:
        report("eval", model, evaluation)
    if not seeds(a.wide_train_seeds):
        return
    continuous = fit(gender["train"], a.ridge)  # fractional targets: the same Newton steps
    print_model("gender model", continuous)
    for name, rows in gender.items():
        if rows:
            report_scores(name, {"SEX_MODEL": model, "gender model": continuous}, rows)


if __name__ == "__main__":
    main()

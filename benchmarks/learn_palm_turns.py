"""Learns bsv.frontend.palms.PALM_TURN_MODEL (how far each palm is turned in, from the hand model's landmarks of
both views) on synthetic cohorts and evaluates it on others.

For every subject of the training cohorts (``--train-seeds``) and the evaluation cohorts (``--eval-seeds``),
drawn with palms turned 0-120 deg in from forward (bsv.bodies.RELAXED_PALM_IN_RANGE_DEG), the virtual rig
captures the body in a room (noer; every other subject with the realistic look, smooth shading and the colour
sensor) and the camera path segments both views (bsv.bench.joints.subject_segmentations). Each view's reading of
each hand is bsv.frontend.palms.view_readings. Least squares fits the pose's palm angle to the two readings
(``both``) and to each alone (``front``, ``back``: a hand the other view did not find); the script prints the
PALM_TURN_MODEL table and, on the evaluation cohorts, the error (rms, mean, worst) of each model.

    .venv/bin/python benchmarks/learn_palm_turns.py --train-seeds 40,41,42,43 --eval-seeds 44,45

``--cache FILE`` keeps the readings (JSON) so that a second run re-learns without MediaPipe; ``--only-measure``
fills the cache and stops (two such runs on disjoint seeds can share the two cores).
"""

from __future__ import annotations

import numpy as np
from learning import learn
from tqdm import tqdm

import bsv
from bsv.bench.joints import subject_segmentations
from bsv.frontend.palms import PALM_TURN_MODEL, view_readings

#: The realistic render (bsv.scan's look) every other subject is captured with.
REALISTIC = {"smooth_shading": True, "colour_sensor": True}


def measure(n: int, seed: int, cache: dict) -> list[tuple[float, float | None, float | None]]:
    """(true palm angle, front reading, back reading) of both hands of the first ``n`` subjects of a cohort seed
    (read from and added to ``cache``: key "seed/index" -> {"truth": [l, r], "front": [l, r], "back": [l, r]})."""
    out = []
    for i in tqdm(range(n), desc=f"seed {seed}", unit="subject"):
        key = f"{seed}/{i}"
        if key not in cache:
            s = bsv.bodies.subject(i, seed, palm_range=bsv.bodies.RELAXED_PALM_IN_RANGE_DEG)
            segs, _ = subject_segmentations(s, "noer", seed * 1000 + i, look=REALISTIC if i % 2 else None)
            cache[key] = {"truth": [s.pose.palm_in_l, s.pose.palm_in_r],
                          **{v: list(view_readings(seg)) for v, seg in segs.items()}}
        c = cache[key]
        none = [None, None]
        out += [(c["truth"][k], c.get("front", none)[k], c.get("back", none)[k]) for k in (0, 1)]
    return out


def fit(rows: list[tuple[float, float | None, float | None]]) -> dict:
    """PALM_TURN_MODEL fitted to ``rows``: ``both`` on the hands both views read, ``front`` and ``back`` on the
    hands that view read."""
    def lsq(cols: list[int]) -> tuple[float, ...]:
        ok = [r for r in rows if all(r[c] is not None for c in cols)]
        X = np.column_stack([np.ones(len(ok))] + [[float(r[c]) for r in ok] for c in cols])  # type: ignore[arg-type]
        coef, *_ = np.linalg.lstsq(X, np.array([r[0] for r in ok]), rcond=None)
        return tuple(round(float(x), 1) for x in coef)

    return {"both": lsq([1, 2]), "front": lsq([1]), "back": lsq([2]), "range": PALM_TURN_MODEL["range"]}


def evaluate(model: dict, rows: list[tuple[float, float | None, float | None]]) -> None:
    """Prints each model's error on ``rows`` (deg: rms, mean, worst)."""
    for name, cols in (("both", (1, 2)), ("front", (1,)), ("back", (2,))):
        coef = model[name]
        err = np.array([coef[0] + sum(c * float(r[k]) for c, k in zip(coef[1:], cols, strict=True)) - r[0]  # type: ignore[arg-type]
                        for r in rows if all(r[k] is not None for k in cols)])
        if len(err):
            print(f"  {name:5s}: {len(err)} hands, rms {np.sqrt(np.mean(err ** 2)):.1f} deg, mean {err.mean():+.1f}, "
                  f"worst {err[np.argmax(np.abs(err))]:+.1f}")


def main() -> None:
    """Command line: measure, learn PALM_TURN_MODEL on the training seeds, evaluate it and the shipped model on both
    sets."""

    def both(model: dict, rows: list[tuple[float, float | None, float | None]]) -> None:
        evaluate(model, rows)
        print("  the shipped model:")
        evaluate(PALM_TURN_MODEL, rows)

    learn(__doc__, "40,41,42,43", "44,45", 10, measure, fit, "PALM_TURN_MODEL", both)


if __name__ == "__main__":
    main()

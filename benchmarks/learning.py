"""What the learning scripts (``benchmarks/learn_palm_turns.py``, ``benchmarks/learn_elbow_lines.py``) share: the
training and evaluation seeds, the subjects per seed, a JSON cache of the measurements, ``--only-measure``, and the
run itself (:func:`learn`: measure, fit on the training seeds, print, evaluate on both sets)."""

from __future__ import annotations

import argparse
import json
from collections.abc import Callable
from pathlib import Path
from typing import TypeVar

T = TypeVar("T")
M = TypeVar("M")


def parser(doc: str, train_seeds: str, eval_seeds: str, n: int) -> argparse.ArgumentParser:
    """The command line of a learning script described by ``doc`` (its first paragraph), with these defaults."""
    ap = argparse.ArgumentParser(description=doc.split("\n\n")[0])
    ap.add_argument("--train-seeds", default=train_seeds)
    ap.add_argument("--eval-seeds", default=eval_seeds)
    ap.add_argument("--n", type=int, default=n, help="subjects per seed")
    ap.add_argument("--cache", type=Path, default=None, help="JSON file of the measurements (read and extended)")
    ap.add_argument("--only-measure", action="store_true", help="fill the cache for the seeds given and stop")
    return ap


def measured(args: argparse.Namespace,
             measure: Callable[[int, int, dict], list[T]]) -> tuple[dict[str, list[int]], dict[str, list[T]]] | None:
    """The seeds (``"train_seeds"``, ``"eval_seeds"``) and the rows ``measure(n, seed, cache)`` gives for each, the
    cache read from and written back to ``args.cache`` (also when a measurement fails); None with
    ``--only-measure``."""
    cache = json.loads(args.cache.read_text()) if args.cache and args.cache.exists() else {}
    seeds = {name: [int(s) for s in getattr(args, name).split(",") if s] for name in ("train_seeds", "eval_seeds")}
    try:
        rows = {name: [r for s in ss for r in measure(args.n, s, cache)] for name, ss in seeds.items()}
    finally:
        if args.cache:
            args.cache.write_text(json.dumps(cache))
    return None if args.only_measure else (seeds, rows)


def learn(doc: str, train_seeds: str, eval_seeds: str, n: int, measure: Callable[[int, int, dict], list[T]],
          fit: Callable[[list[T]], M], constant: str, evaluate: Callable[[M, list[T]], None]) -> None:
    """A learning script's whole run: its command line (:func:`parser` with these defaults), the rows
    (:func:`measured`), the model ``fit`` gives on the training seeds printed as ``constant``, and ``evaluate``
    of it on the training and the held-out seeds' rows."""
    got = measured(parser(doc, train_seeds, eval_seeds, n).parse_args(), measure)
    if got is None:
        return
    seeds, rows = got
    model = fit(rows["train_seeds"])
    print(f"{constant} =", model)
    for name, key in (("training", "train_seeds"), ("held out", "eval_seeds")):
        print(f"{name} seeds {seeds[key]}:")
        evaluate(model, rows[key])

"""argparse value types shared by the ``bsv`` front ends: the range checks of their numeric options.

Each raises ``argparse.ArgumentTypeError`` with what was wrong and what to give, so argparse turns a
bad value into a usage error (exit 2, one line, no traceback) before any work. Bounds: counts and seeds
are whole numbers; seeds fit the 64-bit generators (``0 .. 2**63 - 1``); counts have a ceiling far above
any real use so that a typo cannot ask for a billion subjects or worker processes."""

from __future__ import annotations

import argparse
import json
import math
from collections.abc import Callable
from typing import Any

#: Largest seed (the generators take 64-bit seeds).
MAX_SEED = 2**63 - 1


def whole(lo: int, hi: int, what: str = "value") -> Callable[[str], int]:
    """A type accepting whole numbers in ``lo ..= hi``."""

    def parse(text: str) -> int:
        try:
            value = int(text.strip())
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not a whole number ({what}: {lo} .. {hi})") from None
        if not lo <= value <= hi:
            raise argparse.ArgumentTypeError(f"{value} is out of range ({what}: {lo} .. {hi})")
        return value

    return parse


def real(lo: float, hi: float, what: str = "value") -> Callable[[str], float]:
    """A type accepting finite numbers in ``lo ..= hi``."""

    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not a number ({what}: {lo:g} .. {hi:g})") from None
        if not (math.isfinite(value) and lo <= value <= hi):
            raise argparse.ArgumentTypeError(f"{value} is out of range ({what}: {lo:g} .. {hi:g})")
        return value

    return parse


#: A seed: 0 .. 2**63 - 1.
seed = whole(0, MAX_SEED, "seed")


def key_value(text: str) -> tuple[str, Any]:
    """``KEY=VALUE`` with VALUE read as JSON, or kept as a plain string when it is not JSON."""
    if "=" not in text:
        raise argparse.ArgumentTypeError(f"{text!r}: use KEY=VALUE (VALUE as JSON, or a plain string)")
    k, v = text.split("=", 1)
    if not k.strip():
        raise argparse.ArgumentTypeError(f"{text!r}: the KEY before '=' is empty")
    try:
        return k.strip(), json.loads(v)
    except (json.JSONDecodeError, RecursionError):
        return k.strip(), v


__all__ = ["MAX_SEED", "key_value", "real", "seed", "whole"]

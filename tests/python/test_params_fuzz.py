"""Fuzz-style tests of the parameter parsers (issue 14), seeded, a few thousand cases in a few seconds:
random and mutated registration parameters (``bsv.RegisterParams``, the ``--param KEY=VALUE`` strings of
``bsv process`` / ``demo`` / ``bench``) and the numeric options of ``bsv process``, ``bsv demo`` and
``bsv bench`` either work or fail with a typed error (a :class:`bsv.errors.BsvError` with a message, or
argparse's usage error, exit 2): never another exception, a panic or an abort."""

from __future__ import annotations

import json
import math
import random
from pathlib import Path
from typing import Any

import pytest

import bsv
from bsv.bench.main import main as bench_main
from bsv.errors import BsvError, RegistrationParameterError
from bsv.pipeline import _register_args, main_demo, main_process

NAMES = [*bsv.RegisterParams().to_dict(), "alpah", "", "schedule ", "ALPHA"]
VALUES: list[Any] = [0, -1, 1, 2**64, -(2**63), 2**64 - 1, 10**30, 1e300, -1e300, 5e-324, math.nan, math.inf, -math.inf,
                     True, None, [], [1, 2], {"a": 1}, "", "m2p:5", "m2p:18446744073709551615,m2p:1", "m2p:1000000000000000",
                     "p2m:-1", "auto", "cloud", "template", "x" * 300, "\u00e9\u0000", 0.5, 3, 1000]


def _mutate(rng: random.Random, text: str) -> str:
    chars = list(text)
    for _ in range(rng.randint(1, 4)):
        op = rng.randrange(3)
        pos = rng.randrange(len(chars) + 1)
        if op == 0:
            chars.insert(pos, rng.choice("=:,.-+e0123456789 \"[]{}x\u00e9"))
        elif op == 1 and chars:
            del chars[min(pos, len(chars) - 1)]
        elif chars:
            chars[min(pos, len(chars) - 1)] = rng.choice(":,=9-")
    return "".join(chars)


def _value(rng: random.Random) -> Any:
    v = rng.choice(VALUES)
    if rng.random() < 0.3:
        v = rng.uniform(-1e6, 1e6) if rng.random() < 0.5 else rng.randint(-(2**70), 2**70)
    if isinstance(v, str) and rng.random() < 0.5:
        v = _mutate(rng, v)
    return v


def test_random_register_params_are_accepted_or_refused_by_name() -> None:
    rng = random.Random(1410)
    accepted = 0
    for _ in range(3000):
        kwargs = {rng.choice(NAMES): _value(rng) for _ in range(rng.randint(1, 3))}
        try:
            bsv.RegisterParams(**kwargs)
            accepted += 1
        except RegistrationParameterError as e:
            assert str(e), kwargs
            assert e.parameter is None or e.parameter in NAMES, (kwargs, e.parameter)
    assert accepted > 100


def test_random_param_strings_parse_or_fail_typed() -> None:
    rng = random.Random(14)
    seeds = [f"{k}={json.dumps(v) if not isinstance(v, str) else v}" for k in NAMES[:12] for v in VALUES[:12]]
    for _ in range(3000):
        text = _mutate(rng, rng.choice(seeds)) if rng.random() < 0.7 else "".join(
            chr(rng.randrange(1, 0x250)) for _ in range(rng.randint(0, 20)))
        try:
            bsv.RegisterParams(**_register_args([text]))
        except BsvError as e:
            assert str(e), text


def _exit(run: Any) -> int:
    try:
        return int(run())
    except SystemExit as e:  # argparse: usage error
        return int(e.code) if isinstance(e.code, int) else 1


NUMBERS = ["0", "1", "-1", "-5", "2", "600", "1e3", "nan", "inf", "-inf", "0.05", "99999999999999999999999", "x", "",
           " 3", "1_0", "0x10", "9223372036854775808", "1e309"]


@pytest.fixture()
def occupied(tmp_path: Path) -> Path:
    """An output folder that already holds every output, so a call whose options are valid stops (exit 2)
    before any work."""
    from bsv.pipeline import output_files

    for name in [*output_files(("front", "back"), True), "results.json", "results.csv", "report.md"]:
        p = tmp_path / name
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_text("{}")
    return tmp_path


def test_numeric_options_of_process_demo_and_bench_are_range_checked(occupied: Path, capsys: Any) -> None:
    rng = random.Random(2026)
    missing = str(occupied / "no-such-capture")
    calls = [
        lambda v: main_process([missing, "-o", str(occupied), "--sor-k", v, "--quiet"]),
        lambda v: main_process([missing, "-o", str(occupied), "--sor-std", v, "--quiet"]),
        lambda v: main_process([missing, "-o", str(occupied), "--param", f"alpha={v}", "--quiet"]),
        lambda v: main_demo(["-o", str(occupied), "--seed", v, "--quiet"]),
        lambda v: main_demo(["-o", str(occupied), "--subject", v, "--quiet"]),
        lambda v: main_demo(["-o", str(occupied), "--param", f"data_weight={v}", "--quiet"]),
        lambda v: bench_main(["synth", "--out", str(occupied), "--n", v, "--quiet"]),
        lambda v: bench_main(["synth", "--out", str(occupied), "--seed", v, "--quiet"]),
        lambda v: bench_main(["synth", "--out", str(occupied), "--jobs", v, "--quiet"]),
        lambda v: bench_main(["boxes", "--out", str(occupied), "--seeds", v, "--quiet"]),
        lambda v: bench_main(["synth", "--out", str(occupied), "--param", f"schedule={v}", "--quiet"]),
    ]
    for _ in range(400):
        value = rng.choice(NUMBERS)
        if rng.random() < 0.3:
            value = _mutate(rng, value)
        call = rng.choice(calls)
        code = _exit(lambda call=call, value=value: call(value))
        assert code in (1, 2), (value, code)
    err = capsys.readouterr().err
    assert "Traceback" not in err


def test_bad_numeric_options_name_the_range(capsys: Any) -> None:
    for argv in (["--seed", "-5"], ["--subject", "-1"], ["--seed", "1e3"]):
        assert _exit(lambda argv=argv: main_demo(["-o", "unused", *argv])) == 2
        err = capsys.readouterr().err
        assert "out of range" in err or "not a whole number" in err, err
    assert _exit(lambda: bench_main(["synth", "--n", "0"])) == 2
    assert "--n subjects: 1 .. 100000" in capsys.readouterr().err
    from bsv.bodies.cohort import main as cohort_main
    from bsv.cli import main as bsv_main

    assert _exit(lambda: cohort_main(["unused", "-3"])) == 2
    assert _exit(lambda: bsv_main(["capture", "unused", "--seconds", "nan"])) == 2
    assert "out of range" in capsys.readouterr().err

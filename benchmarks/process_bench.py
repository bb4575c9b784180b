#!/usr/bin/env python3
"""Whole-command timing of ``bsv process`` (capture folder -> volumes.json, report.html, report.pdf,
volumes.csv), as a user runs it: a fresh Python process per run, against a peer in the same run.

The peer is another checkout of BSV (``--peer PYTHONPATH``: its ``python/`` folder with its compiled
extension, e.g. a ``git worktree`` of an earlier commit built with ``cargo build --release -p bsv-py``
and ``lib_bsv.so`` copied to ``python/bsv/_bsv.abi3.so``); without it, only this checkout is timed.
Rounds are interleaved (this checkout, then the peer) so that both see the same machine. The capture is
``--capture`` (with ``--calibration``, default ``CAPTURE/calibration.json``), or the demo's synthetic room
capture, rendered once by ``bsv demo`` into a temporary folder.

Prints a table: the median wall time of the command and its range, the median of the total that the
command itself prints (``[bsv] done in X s``: from its first step to the report written), and the ratio
of the medians.

Usage: python benchmarks/process_bench.py [--capture DIR] [--calibration FILE] [--peer PYTHONPATH]
                                          [--peer-label TEXT] [--rounds 5] [--segmentation camera]
"""

from __future__ import annotations

import argparse
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
DONE = re.compile(r"\[bsv\] done in ([0-9.]+) s")


def _run(pythonpath: str | None, args: list[str]) -> tuple[float, float]:
    """Wall time of one ``python -m bsv.cli ARGS`` and the total it prints."""
    env = dict(os.environ)
    if pythonpath:
        env["PYTHONPATH"] = pythonpath
    t = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "bsv.cli", *args], env=env, capture_output=True, text=True)
    wall = time.perf_counter() - t
    if proc.returncode != 0:
        raise SystemExit(f"error: `bsv {' '.join(args)}` failed ({proc.returncode}):\n{proc.stderr[-2000:]}")
    m = DONE.search(proc.stdout)
    return wall, float(m.group(1)) if m else float("nan")


def main(argv: list[str] | None = None) -> int:
    """Runs the benchmark; returns the exit code."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--capture", help="capture folder (default: the demo's, rendered once)")
    ap.add_argument("--calibration", help="calibration.json (default: CAPTURE/calibration.json)")
    ap.add_argument("--peer", help="PYTHONPATH of the peer checkout (its python/ folder, extension built)")
    ap.add_argument("--peer-label", default="peer", help="the peer's name in the table")
    ap.add_argument("--rounds", type=int, default=5, help="timed runs of each command (default 5)")
    ap.add_argument("--segmentation", default="camera", choices=("camera", "oracle"))
    args = ap.parse_args(argv)
    if args.rounds < 1:
        print("error: --rounds must be at least 1", file=sys.stderr)
        return 2
    if args.peer and not (Path(args.peer) / "bsv" / "__init__.py").is_file():
        print(f"error: --peer {args.peer} has no bsv package (pass the peer checkout's python/ folder)",
              file=sys.stderr)
        return 2
    ours = str(ROOT / "python")
    with tempfile.TemporaryDirectory(prefix="bsv-process-bench-") as tmp:
        if args.capture:
            cap = Path(args.capture)
        else:
            print("rendering the demo capture ...", flush=True)
            _run(ours, ["demo", "-o", f"{tmp}/demo", "--overwrite", "--quiet"])
            cap = Path(tmp) / "demo" / "capture"
        cal = Path(args.calibration) if args.calibration else cap / "calibration.json"
        cmd = ["process", str(cap), "--calibration", str(cal), "--segmentation", args.segmentation,
               "-o", f"{tmp}/out", "--overwrite"]
        variants = [("this checkout", ours)] + ([(args.peer_label, args.peer)] if args.peer else [])
        for _, path in variants:  # warm the file cache and the byte-code of both
            _run(path, cmd)
        times: dict[str, list[tuple[float, float]]] = {name: [] for name, _ in variants}
        for r in range(args.rounds):
            for name, path in variants:
                times[name].append(_run(path, cmd))
            print(f"round {r + 1}/{args.rounds}", flush=True)
    base = statistics.median(w for w, _ in times[variants[-1][0]])
    print(f"\n`bsv process` on {cap} ({args.segmentation} segmentation), {args.rounds} interleaved rounds, "
          f"fresh process each, {os.cpu_count()} cores\n")
    print("| command | wall s, median | min-max | its own total s, median | ratio to " + variants[-1][0] + " |")
    print("|---|---|---|---|---|")
    for name, _ in variants:
        walls = [w for w, _ in times[name]]
        totals = [t for _, t in times[name]]
        med = statistics.median(walls)
        print(f"| {name} | {med:.2f} | {min(walls):.2f}-{max(walls):.2f} | {statistics.median(totals):.2f} | "
              f"{med / base:.2f} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

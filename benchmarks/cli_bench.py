#!/usr/bin/env python3
"""Whole-command timing of ``bsv-cli register`` against the peer, in the same run.

For ``--n`` subjects of the synthetic cohort (``bsv.bodies``, seed ``--seed``) in each of the
``--conditions``, the virtual rig scans the body (``bsv.scan``: the merged, labelled two-camera cloud,
120-160k points) and writes it as a PLY file. Then, for ``--rounds`` rounds, every cloud is registered by

* ``bsv-cli register CLOUD --json OUT -q --force`` (the embedded default template): the wall time of the
  whole process (start, PLY read, checks, registration, volumes, JSON written), and
* ``trimesh.registration.nricp_amberg`` (the peer of ``bsv bench synth --peer trimesh``) on the same
  cloud, in this process, once per cloud (it takes seconds; its spread is small against the ratio),

interleaved cloud by cloud so that both see the same machine. Prints a table: median wall time per
condition, the peer's median, their ratio, and bsv's trunk_limbs error against the truth (a fast wrong
answer is not a result).

Usage: python benchmarks/cli_bench.py [--cli PATH] [--n 3] [--seed 1] [--conditions noer,l515]
                                      [--rounds 5] [--no-peer] [--json FILE]
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def main(argv: list[str] | None = None) -> int:
    """Runs the benchmark; returns the exit code."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--cli", default=str(ROOT / "target" / "release" / "bsv-cli"),
                    help="the bsv-cli binary (default: the release build of this checkout)")
    ap.add_argument("--n", type=int, default=3, help="subjects per condition (default 3)")
    ap.add_argument("--seed", type=int, default=1, help="cohort seed (default 1)")
    ap.add_argument("--conditions", default="noer,l515", help="comma list of noer,l515,cali,l5ca")
    ap.add_argument("--rounds", type=int, default=5, help="timed runs of the command per cloud (default 5)")
    ap.add_argument("--no-peer", action="store_true", help="do not run trimesh's nricp_amberg")
    ap.add_argument("--json", help="also write the timings here")
    args = ap.parse_args(argv)
    cli = Path(args.cli)
    if not cli.is_file():
        print(f"error: {cli} does not exist: build it with `cargo build --release -p bsv-cli` or pass --cli",
              file=sys.stderr)
        return 2
    if args.n < 1 or args.rounds < 1:
        print("error: --n and --rounds must be at least 1", file=sys.stderr)
        return 2

    import bsv
    from bsv.bench.common import register_method
    from bsv.bodies import subject

    conditions = [c.strip() for c in args.conditions.split(",") if c.strip()]
    template = bsv.default_template()
    with tempfile.TemporaryDirectory(prefix="bsv_cli_bench_") as tmp:
        clouds = []  # (condition, subject index, cloud path, cloud, truth)
        for c in conditions:
            for i in range(args.n):
                s = subject(i, args.seed)
                cloud = bsv.scan(s.body.mesh(), c, seed=i)
                path = Path(tmp) / f"{c}_{i:03d}.ply"
                bsv.write_point_cloud(path, cloud)
                clouds.append((c, i, path, cloud, s.volumes_l()))
                print(f"scanned {c} subject {i}: {len(cloud.points)} points", flush=True)
        wall: dict[str, list[float]] = {c: [] for c in conditions}
        peer: dict[str, list[float]] = {c: [] for c in conditions}
        err: dict[str, list[float]] = {c: [] for c in conditions}
        peer_err: dict[str, list[float]] = {c: [] for c in conditions}
        for r in range(args.rounds):
            for c, i, path, cloud, truth in clouds:
                out = Path(tmp) / f"{c}_{i:03d}.json"
                t0 = time.perf_counter()
                done = subprocess.run([str(cli), "register", str(path), "--json", str(out), "-q", "--force"],
                                      capture_output=True, text=True)
                dt = time.perf_counter() - t0
                if done.returncode != 0:
                    print(f"error: bsv-cli register {path.name} failed ({done.returncode}): {done.stderr.strip()}",
                          file=sys.stderr)
                    return 1
                wall[c].append(dt)
                if r == 0:
                    est = json.loads(out.read_text())["volumes_l"]["trunk_limbs"]
                    err[c].append(100 * (est - truth["trunk_limbs"]) / truth["trunk_limbs"])
                    if not args.no_peer:
                        fit = register_method("trimesh", cloud, template)
                        peer[c].append(fit.seconds)
                        pv = fit.volumes_l["trunk_limbs"]
                        peer_err[c].append(100 * (pv - truth["trunk_limbs"]) / truth["trunk_limbs"])
            print(f"round {r + 1}/{args.rounds} done", flush=True)

    print()
    print("| condition | clouds | `bsv-cli register` median s (min-max) | trunk_limbs signed % | "
          "nricp_amberg median s | its trunk_limbs signed % | peer / bsv |")
    print("|---|---|---|---|---|---|---|")
    rows = []
    for c in conditions:
        m = statistics.median(wall[c])
        pm = statistics.median(peer[c]) if peer[c] else float("nan")
        e = statistics.mean(err[c])
        pe = statistics.mean(peer_err[c]) if peer_err[c] else float("nan")
        print(f"| {c} | {len(err[c])} | {m:.3f} ({min(wall[c]):.3f}-{max(wall[c]):.3f}) | {e:+.2f} | "
              f"{pm:.2f} | {pe:+.2f} | {pm / m:.1f}x |")
        rows.append({"condition": c, "bsv_cli_seconds": wall[c], "peer_seconds": peer[c],
                     "trunk_limbs_signed_pct": err[c], "peer_trunk_limbs_signed_pct": peer_err[c]})
    allw = [x for c in conditions for x in wall[c]]
    allp = [x for c in conditions for x in peer[c]]
    if allp:
        print(f"| all | {len(clouds)} | {statistics.median(allw):.3f} | | {statistics.median(allp):.2f} | | "
              f"{statistics.median(allp) / statistics.median(allw):.1f}x |")
    else:
        print(f"| all | {len(clouds)} | {statistics.median(allw):.3f} | | | | |")
    if args.json:
        Path(args.json).write_text(json.dumps({"seed": args.seed, "rounds": args.rounds, "rows": rows}, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""Scaling numbers of ``bsv batch``: 1 vs N workers on the same synthetic items, and the scheduler's
per-task overhead.

``python -m bsv.batch.bench [--items 20] [--workers 1,2] [--noop 2000] [--write benchmarks/BATCH.md]``

Items: labelled virtual two-camera scans (:func:`bsv.scan`, condition l515) of cohort subjects (4
subjects x 5 scan seeds by default), written as PLY clouds; each item is a full default registration and
its volumes, as ``bsv batch`` runs a cloud file. Every worker count gets a fresh output folder and a
LocalCluster started before the clock runs (the cluster's start-up is reported apart).

Overhead: ``--noop`` empty tasks submitted at once and gathered (:func:`bsv.batch.task.noop`), wall time
per task; and, for the real items, the batch's wall time x workers minus the time the tasks spent in
their work, per item (scheduling, transfer, journal and table writes, idle tail).
"""

from __future__ import annotations

import argparse
import os
import platform
import tempfile
import time
from collections.abc import Sequence
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from ..errors import OutputExistsError


@dataclass
class Measure:
    """One worker count: wall seconds of the batch, summed task seconds, items, cluster start-up."""

    workers: int
    items: int
    wall_s: float
    task_s: float
    startup_s: float
    noop_ms: float
    failed: int

    @property
    def per_min(self) -> float:
        """Throughput, items per minute."""
        return self.items / self.wall_s * 60.0

    @property
    def overhead_ms(self) -> float:
        """Per item: worker-seconds the batch held beyond the tasks' own work, in ms."""
        return max(0.0, self.wall_s * self.workers - self.task_s) / self.items * 1000.0


def make_items(folder: Path, n: int, subjects: int = 4) -> list[Path]:
    """``n`` labelled virtual scans (l515) of ``subjects`` cohort subjects as PLY files in ``folder``."""
    from .. import scan, write_point_cloud
    from ..bodies import subject

    meshes = [subject(i, 0, local=False).body.mesh() for i in range(subjects)]
    paths = []
    for k in range(n):
        p = folder / f"scan_{k:03d}.ply"
        write_point_cloud(p, scan(meshes[k % subjects], "l515", k))
        paths.append(p)
    return paths


def noop_ms(client: Any, n: int) -> float:
    """Wall milliseconds per empty task, ``n`` submitted at once and gathered."""
    from .task import noop

    client.gather(client.map(noop, range(20), pure=False))  # warm up
    t = time.perf_counter()
    client.gather(client.map(noop, range(n), pure=False))
    return (time.perf_counter() - t) / n * 1000.0


def measure(paths: Sequence[Path], workers: int, noop: int, root: Path) -> Measure:
    """Runs the batch of ``paths`` on a fresh LocalCluster of ``workers`` one-thread workers."""
    from distributed import Client, LocalCluster

    from .items import collect_items
    from .runner import run_batch

    items = collect_items(list(paths))
    t = time.perf_counter()
    with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, \
            Client(cluster) as client:
        startup = time.perf_counter() - t
        ms = noop_ms(client, noop)
        res = run_batch(items, root / f"out_{workers}", client=client, progress=True)
    task_s = sum(float(r.get("seconds") or 0.0) for r in res.records.values())
    return Measure(workers, len(items), res.wall_s, task_s, startup, ms, len(res.failed))


def _load() -> str:
    try:
        return " / ".join(f"{x:.1f}" for x in os.getloadavg())
    except OSError:
        return "n/a"


def _cpu() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown CPU"


def markdown(rows: Sequence[Measure], load_before: str, load_after: str, n_items: int, noop: int) -> str:
    """The results as BATCH.md."""
    base = rows[0]
    lines = [
        "# bsv batch: scaling on this machine",
        "",
        (f"Measured {datetime.now(UTC):%Y-%m-%d %H:%M} UTC with `python -m bsv.batch.bench` on {os.cpu_count()} "
        f"cores ({_cpu()}), Python {platform.python_version()}."),
        "",
        (f"**The machine was shared with other engineers' builds and tests while this ran** (load average "
        f"1/5/15 min: {load_before} before, {load_after} after, on {os.cpu_count()} cores): the absolute "
        "times are inflated and noisy, and the speed-up from a second worker is smaller than on an idle machine."),
        "",
        (f"Items: {n_items} labelled virtual two-camera scans (l515 depth noise, about 140,000 points each) of 4 "
        "synthetic cohort subjects, as PLY cloud files; each item is `bsv batch`'s cloud path: read, default "
        "registration, volumes, fitted.ply + volumes.json written atomically, one journal line and the table rows."),
        "",
        ("| workers | items | wall (s) | items/min | speed-up | mean task (s) | overhead / item (ms) "
        "| no-op task (ms) | cluster start (s) | failed |"),
        "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for m in rows:
        lines.append(f"| {m.workers} | {m.items} | {m.wall_s:.1f} | {m.per_min:.1f} | {base.wall_s / m.wall_s:.2f} "
                     f"| {m.task_s / m.items:.2f} | {m.overhead_ms:.0f} | {m.noop_ms:.2f} | {m.startup_s:.1f} "
                     f"| {m.failed} |")
    lines += [
        "",
        (f"- *no-op task*: {noop} empty tasks submitted at once and gathered, wall time per task: the scheduler's "
        "own cost per task (submit, schedule, run, report back)."),
        ("- *overhead / item*: wall time x workers minus the tasks' own work time, per item: scheduling, "
        "transfer of the small task and record, the client's journal and table writes, and the idle tail at "
        "the end (the last items run while other workers have nothing left)."),
        ("- *mean task*: the work of one item as timed inside the task; with two workers on two shared cores it "
        "grows, since the registration's own threads of both workers share the cores."),
    ]
    return "\n".join(lines) + "\n"


def main(argv: Sequence[str] | None = None) -> int:
    """Runs the scaling benchmark; prints the table (and writes it with ``--write``)."""
    ap = argparse.ArgumentParser(prog="python -m bsv.batch.bench", description=__doc__.split("\n\n")[0])
    ap.add_argument("--items", type=int, default=20, help="synthetic items (default 20)")
    ap.add_argument("--workers", default="1,2", help="comma list of worker counts (default 1,2)")
    ap.add_argument("--noop", type=int, default=2000, help="empty tasks for the overhead (default 2000)")
    ap.add_argument("--write", help="also write the table to this Markdown file (e.g. benchmarks/BATCH.md)")
    ap.add_argument("--overwrite", action="store_true", help="replace the --write file")
    a = ap.parse_args(list(argv) if argv is not None else None)
    if a.write and Path(a.write).exists() and not a.overwrite:
        raise OutputExistsError(f"{a.write} exists; pass --overwrite to replace it")
    counts = [int(x) for x in a.workers.split(",") if x.strip()]
    load_before = _load()
    with tempfile.TemporaryDirectory(prefix="bsv-batch-bench-") as tmp:
        root = Path(tmp)
        (root / "in").mkdir()
        t = time.perf_counter()
        paths = make_items(root / "in", a.items)
        print(f"made {len(paths)} items in {time.perf_counter() - t:.1f} s", flush=True)
        rows = [measure(paths, w, a.noop, root) for w in counts]
    text = markdown(rows, load_before, _load(), a.items, a.noop)
    print(text)
    if a.write:
        tmp_file = Path(f"{a.write}.partial")
        tmp_file.write_text(text)
        os.replace(tmp_file, a.write)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

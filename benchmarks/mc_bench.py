#!/usr/bin/env python3
"""Calibration Monte Carlo benchmark: the prepared path of :func:`bsv.uncertainty.calibration_spread` (the
mesh prepared once, every draw re-measured in one parallel Rust call) against the per-draw path it
replaced (the moved mesh built per draw and measured with :func:`bsv.volumes` on a thread pool, kept here
only as the peer), in the same run.

Input: the default template (``bsv.default_template()``) and two cameras (front and back, 2 m away, the
paper's covariance, as ``bsv.pipeline`` builds ``CameraSpread``s without a calibration covariance), the
default 200 draws and seed. Rounds are interleaved (peer, prepared, peer, prepared, ...) so that other
jobs on the machine hit both alike; each row gives the median and the min-max over the rounds, and the
ratio of the medians (> 1: the prepared path is faster). Also times one prepared evaluation
(``PreparedVolumes.volume_report``) against one ``bsv.volumes`` call, and checks that both paths give
the same spreads.

Usage: python benchmarks/mc_bench.py [--rounds N] [--samples S] [--out FILE.md]
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import time
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

import bsv
from bsv import _bsv
from bsv import uncertainty as unc


def rig() -> list[unc.CameraSpread]:
    """Front and back cameras 2 m from the body with the paper's covariance (``paper_covariance``)."""
    out = []
    for name, z in (("front", 2.0), ("back", -2.0)):
        fwd = np.array([0.0, 0.0, -np.sign(z)])
        down = np.array([0.0, -1.0, 0.0])
        rot = np.column_stack([np.cross(down, fwd), down, fwd])
        out.append(unc.CameraSpread(name, rot, np.array([0.0, 1.0, z]), unc.paper_covariance(name)))
    return out


def per_draw_spread(mesh: bsv.Mesh, cameras: Sequence[unc.CameraSpread], *, samples: int = unc.DEFAULT_SAMPLES,
                    seed: int = unc.DEFAULT_SEED, density: float = 1000.0) -> dict[str, float]:
    """The peer: ``calibration_spread`` as it was before the prepared path (``bsv.volumes`` per draw, the
    topology redone every time, on a thread pool)."""
    from bsv.bench.floor import CameraPose, camera_weights, vertex_normals

    covs = [unc.check_covariance(c.covariance, f"camera {c.name!r}") for c in cameras]
    nominal = unc.quantities(bsv.volumes(mesh, islands=True, density=density))
    w = camera_weights(vertex_normals(mesh.vertices, mesh.faces),
                       [CameraPose(c.name, c.rotation, c.translation, c.rotation, c.translation) for c in cameras])
    rng = np.random.default_rng(seed)
    names = sorted(nominal)
    draws = [[rng.multivariate_normal(np.zeros(6), cov, method="eigh") for cov in covs] for _ in range(samples)]

    def measure(deltas: list[np.ndarray]) -> dict[str, float]:
        """The quantities of the mesh moved by one draw's per-camera ``deltas`` (floor-weighted blend)."""
        moved = np.zeros_like(mesh.vertices)
        for k, (c, delta) in enumerate(zip(cameras, deltas, strict=True)):
            r_alt, t_alt = unc.perturb(c.rotation, c.translation, delta)
            moved += w[:, [k]] * CameraPose(c.name, c.rotation, c.translation, r_alt, t_alt).apply_error(mesh.vertices)
        return unc.quantities(bsv.volumes(bsv.Mesh(moved, mesh.faces, mesh.vertex_labels, mesh.face_labels),
                                          islands=True, density=density))

    with ThreadPoolExecutor(max_workers=max(1, min(4, os.cpu_count() or 1))) as pool:
        measured = list(pool.map(measure, draws))
    dev = np.full((samples, len(names)), np.nan)
    for s, q in enumerate(measured):
        for j, n in enumerate(names):
            if n in q:
                dev[s, j] = unc.transform(n, q[n]) - unc.transform(n, nominal[n])
    return {n: float(np.nanstd(dev[:, j], ddof=1)) for j, n in enumerate(names) if np.isfinite(dev[:, j]).sum() > 1}


def timed(fn: Callable[[], object], repeat: int = 1) -> float:
    """Seconds per call of ``fn`` (mean over ``repeat`` back-to-back calls)."""
    t = time.perf_counter()
    for _ in range(repeat):
        fn()
    return (time.perf_counter() - t) / repeat


def row(name: str, peer: list[float], new: list[float], unit: float, unit_name: str) -> str:
    """One Markdown table row for step ``name``: the median (min-max) of the ``peer`` and ``new`` timings
    (seconds, shown times ``unit`` in ``unit_name``) and the ratio of the medians (peer / new)."""
    mp, mn = statistics.median(peer), statistics.median(new)
    return (f"| {name} | {mp * unit:.2f} ({min(peer) * unit:.2f}-{max(peer) * unit:.2f}) {unit_name} "
            f"| {mn * unit:.3f} ({min(new) * unit:.3f}-{max(new) * unit:.3f}) {unit_name} | {mp / mn:.0f}x |")


def main() -> None:
    """Parses the options, checks that both paths give the same spreads, times them in interleaved rounds
    and prints the table (also written to ``--out`` when given)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=7, help="interleaved rounds (default 7)")
    ap.add_argument("--samples", type=int, default=unc.DEFAULT_SAMPLES, help="Monte Carlo draws (default 200)")
    ap.add_argument("--out", type=Path, default=None, help="also write the table to this Markdown file")
    args = ap.parse_args()

    mesh = bsv.default_template()
    cams = rig()
    prepared = _bsv.PreparedVolumes(mesh.vertices, mesh.faces, mesh.vertex_labels, mesh.face_labels, None, 1000.0,
                                    False, True)
    # Warm-up, and the check that both paths give the same spreads.
    a = unc.calibration_spread(mesh, cams, samples=args.samples)
    b = per_draw_spread(mesh, cams, samples=args.samples)
    assert list(a) == list(b)
    worst = max(abs(a[n] - b[n]) / abs(b[n]) for n in b if b[n] != 0)

    spread_peer: list[float] = []
    spread_new: list[float] = []
    one_peer: list[float] = []
    one_new: list[float] = []
    for _ in range(args.rounds):
        spread_peer.append(timed(lambda: per_draw_spread(mesh, cams, samples=args.samples)))
        spread_new.append(timed(lambda: unc.calibration_spread(mesh, cams, samples=args.samples)))
        one_peer.append(timed(lambda: bsv.volumes(mesh, islands=True), 20))
        one_new.append(timed(lambda: prepared.volume_report(mesh.vertices), 20))

    head = (f"Calibration Monte Carlo, default template ({len(mesh.vertices)} vertices, {len(mesh.faces)} faces), "
            f"2 cameras, {args.samples} draws; {args.rounds} interleaved rounds, median (min-max); "
            f"{os.cpu_count()} cores, {platform.processor() or platform.machine()}.")
    lines = [
        head,
        "",
        "| step | per-draw bsv.volumes (peer) | prepared (new) | ratio |",
        "|---|---|---|---|",
        row(f"calibration_spread, {args.samples} draws", spread_peer, spread_new, 1e3, "ms"),
        row("one evaluation (volumes report)", one_peer, one_new, 1e3, "ms"),
        "",
        f"Largest relative difference of the spreads (all {len(b)} quantities): {worst:.1e}.",
    ]
    text = "\n".join(lines)
    print(text)
    if args.out is not None:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(text + "\n")


if __name__ == "__main__":
    main()

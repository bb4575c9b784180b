#!/usr/bin/env python3
"""PLY I/O benchmark: bsv-core against trimesh and Open3D on the same files.

Runs the Rust example (``cargo run --release -p bsv-core --example io_bench -- --out DIR --json ...``),
which writes a 1M-point binary cloud (double xyz + rgb + label, as bsv writes it), the same cloud as
float xyz + rgb (as RealSense/Open3D tools write it) and a ~100k-triangle labelled mesh, and times its
own reads and writes. Then it times ``trimesh.load`` and ``open3d.io.read_point_cloud`` /
``read_triangle_mesh`` (and their writers) on the same files and prints a table of MB/s and of the
ratio bsv / other (> 1 means bsv is faster). Every number is the median of N runs with a warm page
cache. Libraries that are not installed are skipped with a message.

Usage: python benchmarks/io_bench.py [--out DIR] [--runs N] [--threads N] [--json FILE]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def median_time(fn, runs: int) -> float:
    times = []
    for _ in range(runs):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return statistics.median(times)


def run_rust(out: Path, runs: int, threads: int | None) -> dict:
    report = out / "bsv_io.json"
    cmd = ["cargo", "run", "--release", "-q", "-p", "bsv-core", "--example", "io_bench", "--",
           "--out", str(out), "--json", str(report), "--runs", str(runs)]
    env = dict(os.environ)
    if threads:
        env["RAYON_NUM_THREADS"] = str(threads)
    subprocess.run(cmd, cwd=ROOT, check=True, env=env)
    return json.loads(report.read_text())


def python_results(out: Path, runs: int) -> dict[tuple[str, str, str], float]:
    """Seconds per (library, file, op)."""
    files = {
        "cloud_1m": out / "cloud_1m.ply",
        "cloud_1m_float": out / "cloud_1m_float.ply",
        "mesh_100k": out / "mesh_100k.ply",
    }
    res: dict[tuple[str, str, str], float] = {}
    try:
        import trimesh
    except ImportError:
        print("trimesh is not installed: skipped (pip install trimesh)", file=sys.stderr)
    else:
        for name, path in files.items():
            res[("trimesh", name, "read")] = median_time(lambda p=path: trimesh.load(p, process=False), runs)
        cloud = trimesh.load(files["cloud_1m"], process=False)
        mesh = trimesh.load(files["mesh_100k"], process=False)
        res[("trimesh", "cloud_1m", "write")] = median_time(lambda: cloud.export(out / "trimesh_cloud_1m.ply"), runs)
        res[("trimesh", "mesh_100k", "write")] = median_time(lambda: mesh.export(out / "trimesh_mesh_100k.ply"), runs)
    try:
        import open3d as o3d
    except ImportError as e:  # no wheel for this Python, or missing system libraries
        print(f"open3d is not available ({e}): skipped", file=sys.stderr)
    else:
        for name in ("cloud_1m", "cloud_1m_float"):
            res[("open3d", name, "read")] = median_time(lambda p=files[name]: o3d.io.read_point_cloud(str(p)), runs)
        res[("open3d", "mesh_100k", "read")] = median_time(
            lambda: o3d.io.read_triangle_mesh(str(files["mesh_100k"])), runs)
        pcd = o3d.io.read_point_cloud(str(files["cloud_1m"]))
        tm = o3d.io.read_triangle_mesh(str(files["mesh_100k"]))
        res[("open3d", "cloud_1m", "write")] = median_time(
            lambda: o3d.io.write_point_cloud(str(out / "open3d_cloud_1m.ply"), pcd), runs)
        res[("open3d", "mesh_100k", "write")] = median_time(
            lambda: o3d.io.write_triangle_mesh(str(out / "open3d_mesh_100k.ply"), tm), runs)
    return res


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=None, help="directory for the benchmark files (default: a temp dir)")
    ap.add_argument("--runs", type=int, default=5, help="runs per measurement (median reported)")
    ap.add_argument("--threads", type=int, default=None, help="RAYON_NUM_THREADS for bsv (default: all cores)")
    ap.add_argument("--json", type=Path, default=None, help="also write the table as JSON here")
    args = ap.parse_args()
    out = args.out or Path(tempfile.mkdtemp(prefix="bsv_io_bench_"))
    out.mkdir(parents=True, exist_ok=True)

    rust = run_rust(out, args.runs, args.threads)
    bsv = {(r["file"], r["op"]): (r["seconds"], r["bytes"]) for r in rust["results"]}
    others = python_results(out, args.runs)
    libs = sorted({k[0] for k in others})

    print()
    print(f"PLY I/O, median of {args.runs} runs, warm page cache; bsv with {rust['threads']} thread(s); "
          f"mesh {rust['mesh_vertices']} vertices / {rust['mesh_triangles']} triangles")
    head = f"{'file':<16} {'op':<6} {'MB':>7} {'bsv MB/s':>9}"
    for lib in libs:
        head += f" {lib + ' MB/s':>13} {'bsv/' + lib:>12}"
    print(head)
    rows = []
    for (name, op), (sec, nbytes) in bsv.items():
        if op not in ("read", "write"):
            continue
        mb = nbytes / 1e6
        line = f"{name:<16} {op:<6} {mb:>7.2f} {mb / sec:>9.0f}"
        row = {"file": name, "op": op, "mb": mb, "bsv_s": sec}
        for lib in libs:
            other = others.get((lib, name, op))
            if other is None:
                line += f" {'-':>13} {'-':>12}"
            else:
                line += f" {mb / other:>13.0f} {other / sec:>11.1f}x"
                row[f"{lib}_s"] = other
        rows.append(row)
        print(line)
    extra = {(n, o): s for (n, o), (s, _) in bsv.items() if o not in ("read", "write")}
    if extra:
        print("bsv breakdown: " + ", ".join(f"{n} {o} {s * 1e3:.1f} ms" for (n, o), s in extra.items()))
    sizes = ", ".join(f"{p.name} {p.stat().st_size / 1e6:.2f} MB" for p in sorted(out.glob("*_*.ply"))
                      if p.name.startswith(("trimesh_", "open3d_")))
    print("write rows: each library writes its own layout of the same data (bsv: double xyz + rgb + label); "
          "MB/s uses bsv's file size for all, so the ratio column compares wall times. Their files: " + sizes)
    if args.json:
        args.json.write_text(json.dumps({"runs": args.runs, "threads": rust["threads"], "rows": rows}, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())

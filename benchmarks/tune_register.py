#!/usr/bin/env python
"""Fast inner loop for tuning the registration (bsv-register) on synthetic bodies.

N cohort subjects x conditions -> virtual scan (oracle labels, head/hands/feet dropped) -> register
-> per-segment signed volume error against the body's ground truth (the 9 trunk_limbs segments and
trunk_limbs; 'whole' is ignored, it includes head, hands and feet).

Scans are cached in ``--cache`` (npz per subject x condition), so repeated runs only register.
Several parameter sets can be compared in one run: ``--config NAME='{"alpha": 1e5}'`` (repeatable;
JSON passed to ``bsv.register``); ``--template default|fine|full|PATH``.

    .venv/bin/python benchmarks/tune_register.py --n 6 --conditions noer,l515
    .venv/bin/python benchmarks/tune_register.py --n 3 --config base='{}' --config soft='{"alpha": 1e5}'

The full benchmark with reports is ``bsv bench synth``; this script only prints tables.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

import numpy as np

SEGMENTS = ["torso", "upper_arm_l", "upper_arm_r", "forearm_l", "forearm_r",
            "thigh_l", "thigh_r", "shin_l", "shin_r", "trunk_limbs"]
KEEP_IDS = [2, 3, 4, 5, 6, 9, 10, 11, 12]


def scan_cached(cache: Path, seed: int, index: int, condition: str) -> tuple[dict, dict]:
    """(cloud arrays, truth volumes) of cohort subject ``index`` scanned in ``condition``."""
    import bsv
    from bsv.bodies import subject

    f = cache / f"s{seed}_i{index}_{condition}.npz"
    if f.is_file():
        d = np.load(f, allow_pickle=False)
        return ({"points": d["points"], "labels": d["labels"]}, json.loads(str(d["truth"])))
    s = subject(index, seed)
    truth = {k: float(v) for k, v in s.volumes_l().items()}
    raw = bsv.scan(s.body.mesh(), condition, seed * 1_000_003 + index)
    keep = np.isin(raw.labels, KEEP_IDS)
    cloud = {"points": np.ascontiguousarray(raw.points[keep]), "labels": np.ascontiguousarray(raw.labels[keep])}
    cache.mkdir(parents=True, exist_ok=True)
    np.savez(f, points=cloud["points"], labels=cloud["labels"], truth=json.dumps(truth))
    return cloud, truth


def load_template(name: str):
    """default / fine / full / a mesh path."""
    import bsv

    root = Path(__file__).resolve().parents[1] / "assets" / "template"
    if name == "default":
        return bsv.default_template()
    if name in ("fine", "full"):
        return bsv.read_mesh(root / f"template_{name}.ply")
    return bsv.read_mesh(name)


def run_config(name: str, params: dict, template, clouds: list, verbose: bool, both_labels: bool = False) -> dict:
    """Registers every cloud; returns errors[condition][segment] -> list of signed % and timings."""
    import bsv

    errs: dict[str, dict[str, list[float]]] = {}
    times: list[float] = []
    rms: list[float] = []
    yaws: list[float] = []
    for (idx, cond, cloud, truth) in clouds:
        t0 = time.perf_counter()
        reg = bsv.register(cloud["points"], cloud["labels"], template, **params)
        wall = time.perf_counter() - t0
        times.append(reg.seconds)
        rms.append(reg.volumes["registration"].get("rms_mesh_to_points_mm", float("nan")))
        yaws.append(reg.volumes["registration"].get("prealign", {}).get("yaw_deg", 0.0))
        variants = [(cond, reg.volumes["volumes_l"])]
        if both_labels and template.vertex_labels is not None:
            # The template's own labels on the fitted vertices (what labels="template" gives).
            from bsv.types import Mesh
            tl = Mesh(reg.mesh.vertices, template.faces, template.vertex_labels, template.face_labels)
            variants.append((cond + "/T", bsv.volumes(tl)["volumes_l"]))
        for key, est in variants:
            row = errs.setdefault(key, {s: [] for s in SEGMENTS})
            for s in SEGMENTS:
                row[s].append((est.get(s, 0.0) - truth[s]) / truth[s] * 100.0)
        row = errs[cond]
        if verbose:
            print(f"  [{name}] subject {idx} {cond}: trunk_limbs {row['trunk_limbs'][-1]:+.2f} %  "
                  + " ".join(f"{s[:6]}{s[-2:] if s[-2] == '_' else ''} {row[s][-1]:+.1f}" for s in SEGMENTS[:-1])
                  + f"  rms {rms[-1]:.2f} mm  reg {reg.seconds:.2f} s (wall {wall:.2f} s)", flush=True)
    return {"errors": errs, "seconds": times, "rms": rms, "yaw": yaws}


def print_table(name: str, res: dict) -> None:
    """Per condition: mean signed, mean |.|, max |.| per segment."""
    print(f"\n== {name}: registration {np.mean(res['seconds']):.3f} s mean "
          f"(max {np.max(res['seconds']):.3f}), rms m2p {np.mean(res['rms']):.2f} mm, "
          f"max |prealign yaw| {np.max(np.abs(res['yaw'])):.1f} deg")
    for cond, row in res["errors"].items():
        print(f"  {cond:5s} {'segment':12s} {'signed':>8s} {'abs':>7s} {'max|.|':>7s}")
        for s in SEGMENTS:
            a = np.array(row[s])
            print(f"  {'':5s} {s:12s} {a.mean():+8.2f} {np.abs(a).mean():7.2f} {np.abs(a).max():7.2f}")
        worst = max(np.abs(np.array(row[s])).mean() for s in SEGMENTS[:-1])
        print(f"  {'':5s} worst segment mean |.| {worst:.2f} %")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--n", type=int, default=3)
    ap.add_argument("--first", type=int, default=0, help="first subject index")
    ap.add_argument("--seed", type=int, default=5)
    ap.add_argument("--conditions", default="noer,l515")
    ap.add_argument("--template", default="default")
    ap.add_argument("--config", action="append", default=[], help="NAME=JSON params (repeatable)")
    ap.add_argument("--cache", default=os.environ.get("BSV_TUNE_CACHE", "/tmp/bsv_tune_cache"))
    ap.add_argument("--json", help="write all results here")
    ap.add_argument("-q", "--quiet", action="store_true")
    ap.add_argument("--template-labels", action="store_true",
                    help="also report the volumes with the template's own labels (rows COND/T)")
    args = ap.parse_args(argv)
    configs = []
    for c in args.config or ["default={}"]:
        name, _, js = c.partition("=")
        configs.append((name, json.loads(js or "{}")))
    template = load_template(args.template)
    clouds = []
    for i in range(args.first, args.first + args.n):
        for cond in args.conditions.split(","):
            cloud, truth = scan_cached(Path(args.cache), args.seed, i, cond)
            clouds.append((i, cond, cloud, truth))
    print(f"template {args.template}: {len(template.vertices)} vertices; {len(clouds)} clouds "
          f"({np.mean([len(c[2]['points']) for c in clouds]):.0f} points mean)", flush=True)
    out = {}
    for name, params in configs:
        res = run_config(name, params, template, clouds, not args.quiet, args.template_labels)
        print_table(name, res)
        out[name] = {"params": params, **res}
    if args.json:
        Path(args.json).write_text(json.dumps(out, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())

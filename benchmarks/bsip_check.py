#!/usr/bin/env python3
"""Body-segment inertial parameters against ground truth on the synthetic cohort.

For each subject: (1) the true labelled body -> ``bsv.bsip`` -> joint centres (boundary centroids)
against the MakeHuman rig's joints (mm); (2) a virtual two-camera capture (condition) -> registration
-> ``bsv.bsip`` of the fitted mesh -> per segment the mass error (% of the true segment's mass at the same
density) and the centre-of-mass distance (mm) against the true body's, and the fitted joint centres
against the rig. Prints mean / max tables (and writes them as JSON with ``--json``).

Usage: python benchmarks/bsip_check.py [--subjects 6] [--seed 0] [--condition noer] [--json FILE]
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
from tqdm import tqdm

import bsv
from bsv.bodies import subject
from bsv.bodies.joints import rig_joints


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--subjects", type=int, default=6)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--condition", default="noer", choices=("noer", "l515", "cali", "l5ca"))
    ap.add_argument("--json", type=Path)
    a = ap.parse_args()
    true_joint: dict[str, list[float]] = {}
    fit_joint: dict[str, list[float]] = {}
    mass_err: dict[str, list[float]] = {}
    com_err: dict[str, list[float]] = {}
    for i in tqdm(range(a.subjects), desc=f"subjects ({a.condition})"):
        s = subject(i, a.seed)
        rig = rig_joints(s.phenotype, s.pose)
        truth = bsv.bsip(s.body, sex=s.sex)
        for k, p in truth.joints.items():
            true_joint.setdefault(k, []).append(1e3 * float(np.linalg.norm(p - rig[k])))
        cloud = bsv.scan(s.body.mesh(), a.condition, a.seed + i)
        fit = bsv.bsip(bsv.register(cloud, progress=False), sex=s.sex)
        for k, p in fit.joints.items():
            fit_joint.setdefault(k, []).append(1e3 * float(np.linalg.norm(p - rig[k])))
        for name, seg in fit.segments.items():
            t = truth.segments[name]
            mass_err.setdefault(name, []).append(100.0 * (seg.mass_kg - t.mass_kg) / t.mass_kg)
            com_err.setdefault(name, []).append(1e3 * float(np.linalg.norm(seg.com - t.com)))

    def stats(d: dict[str, list[float]]) -> dict[str, tuple[float, float]]:
        return {k: (float(np.mean(v)), float(np.max(np.abs(v)))) for k, v in d.items()}

    out = {"condition": a.condition, "subjects": a.subjects, "seed": a.seed,
           "joint_error_true_mesh_mm": stats(true_joint), "joint_error_fitted_mm": stats(fit_joint),
           "mass_error_pct": stats(mass_err), "com_error_mm": stats(com_err)}
    print(f"\nJoint centres vs the rig, mm (mean / max over {a.subjects} subjects)")
    print(f"{'joint':<12}{'true mesh':>18}{'fitted (' + a.condition + ')':>20}")
    for k, (m, x) in out["joint_error_true_mesh_mm"].items():
        f = out["joint_error_fitted_mm"].get(k)
        print(f"{k:<12}{m:>10.1f} / {x:<6.1f}" + (f"{f[0]:>11.1f} / {f[1]:<6.1f}" if f else f"{'-':>12}"))
    print(f"\nFitted segment vs the true body, same densities (mean / max |.| over {a.subjects} subjects)")
    print(f"{'segment':<12}{'mass error %':>18}{'COM distance mm':>20}")
    for k, (m, x) in out["mass_error_pct"].items():
        c = out["com_error_mm"][k]
        print(f"{k:<12}{m:>+10.2f} / {x:<6.2f}{c[0]:>11.1f} / {c[1]:<6.1f}")
    if a.json:
        a.json.write_text(json.dumps(out, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

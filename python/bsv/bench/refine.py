"""How much of the calibration floor the floor-plane refinement removes (``python -m bsv.bench.refine``).

For each subject of the synthetic cohort, the virtual rig scans it inside the clinic room (so that both
cameras see the floor) in a calibrated condition (default l5ca: the paper's calibration error and L515
depth noise). Each camera's estimated extrinsics are refined with the floor it sees
(:func:`bsv.frontend.floorplane.refine_with_floor`, person pixels from the scanner's label image), and
the calibration floor (:mod:`bsv.bench.floor`: a perfect registration of that capture) is measured with
the estimated and with the refined extrinsics. Also reported: the remaining calibration error per
parameter (in units of the paper's standard deviations), which shows what the floor can and cannot fix.
"""

from __future__ import annotations

import argparse
import json
import tempfile
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import BenchError
from ..uncertainty import PAPER_STD, PARAMETERS, pose_delta
from .common import rve, signed_error
from .floor import CameraPose, floor_volumes, read_camera_poses
from .reference import CALIBRATED
from .synth import scan_seed

#: Volumes whose floor is reported.
REPORTED: tuple[str, ...] = ("trunk_limbs", "torso", "upper_arm_l", "upper_arm_r", "forearm_l", "forearm_r")


def refine_capture(capture: str | Path) -> tuple[list[CameraPose], list[CameraPose], dict[str, Any]]:
    """(poses as calibrated, poses refined by the floor, per-camera refinement figures) of a virtual capture."""
    import cv2

    from ..frontend.capture import read_capture
    from ..frontend.floorplane import refine_with_floor

    cams = read_camera_poses(capture)
    refined, info = [], {}
    for c in cams:
        d = Path(capture) / c.name
        cap = read_capture(d)
        labels = cv2.imread(str(d / "labels.png"), cv2.IMREAD_UNCHANGED)
        if labels is None:
            raise BenchError(f"{d}/labels.png missing: the refinement bench needs the scanner's label image")
        ref = refine_with_floor(c.est_rotation, c.est_translation, cap["depth_m"], cap["intrinsics"], labels > 0,
                                name=c.name)
        refined.append(CameraPose(c.name, c.true_rotation, c.true_translation, ref.rotation, ref.translation))
        std = np.asarray(PAPER_STD.get(c.name, PAPER_STD["back"]))
        before = pose_delta(c.true_rotation, c.true_translation, c.est_rotation, c.est_translation) / std
        after = pose_delta(c.true_rotation, c.true_translation, ref.rotation, ref.translation) / std
        info[c.name] = {"points": ref.points, "rms_mm": ref.rms_mm, "height_mm": ref.height_mm,
                        "error_before_sd": before.tolist(), "error_after_sd": after.tolist()}
    return cams, refined, info


def run_refine(n: int = 10, seed: int = 0, condition: str = "l5ca", progress: bool = True) -> list[dict[str, Any]]:
    """One row per subject: true volumes, floor before and after refinement, refinement figures."""
    from tqdm import tqdm

    from .. import bodies, scan, volumes

    if condition not in CALIBRATED:
        raise BenchError(f"--condition {condition}: the floor needs a calibrated condition ({', '.join(CALIBRATED)})")
    rows = []
    for i in tqdm(range(n), desc="refine", unit="subject", disable=not progress):
        mesh = bodies.subject(i, seed).body.mesh()
        truth = volumes(mesh)["volumes_l"]
        with tempfile.TemporaryDirectory(prefix="bsv-refine-") as tmp:
            scan(mesh, condition, scan_seed(seed, i), images=tmp, overwrite=True, room=True)
            cams, refined, info = refine_capture(tmp)
        before, after = floor_volumes(mesh, cams), floor_volumes(mesh, refined)
        rows.append({"subject": i, "truth_l": {k: truth[k] for k in REPORTED},
                     "before_l": {k: before[k] for k in REPORTED}, "after_l": {k: after[k] for k in REPORTED},
                     "cameras": info})
    return rows


def summary_markdown(rows: Sequence[dict[str, Any]], condition: str) -> str:
    """Mean floor RVE (and mean signed error) before and after, and the mean |error| per parameter."""
    lines = [(f"Floor (perfect registration) in {condition}, {len(rows)} subjects, clinic room: mean RVE % "
             "(mean signed %) with the calibrated and with the floor-refined extrinsics."), "",
             "| volume | as calibrated | refined by the floor |", "|---|---|---|"]
    for k in REPORTED:
        b = [rve(r["before_l"][k], r["truth_l"][k]) for r in rows]
        a = [rve(r["after_l"][k], r["truth_l"][k]) for r in rows]
        bs = [signed_error(r["before_l"][k], r["truth_l"][k]) for r in rows]
        as_ = [signed_error(r["after_l"][k], r["truth_l"][k]) for r in rows]
        lines.append(f"| {k} | {np.mean(b):.2f} ({np.mean(bs):+.2f}) | {np.mean(a):.2f} ({np.mean(as_):+.2f}) |")
    lines += ["", "Calibration error left per parameter, RMS in units of the paper's std (before -> after):", "",
              "| camera | " + " | ".join(PARAMETERS) + " |", "|---|" + "---|" * len(PARAMETERS)]
    for cam in rows[0]["cameras"] if rows else []:
        b = np.sqrt(np.mean([np.square(r["cameras"][cam]["error_before_sd"]) for r in rows], axis=0))
        a = np.sqrt(np.mean([np.square(r["cameras"][cam]["error_after_sd"]) for r in rows], axis=0))
        lines.append(f"| {cam} | " + " | ".join(f"{x:.2f} -> {y:.2f}" for x, y in zip(b, a, strict=True)) + " |")
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m bsv.bench.refine [--n 10] [--seed 0] [--out refine.json]``."""
    ap = argparse.ArgumentParser(prog="python -m bsv.bench.refine", description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, default=10)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--condition", default="l5ca", choices=CALIBRATED)
    ap.add_argument("--out", help="also write the rows as JSON here (refused if it exists)")
    ap.add_argument("--quiet", action="store_true")
    a = ap.parse_args(argv)
    if a.out and Path(a.out).exists():
        raise BenchError(f"{a.out} exists; choose another --out")
    rows = run_refine(a.n, a.seed, a.condition, progress=not a.quiet)
    print(summary_markdown(rows, a.condition))
    if a.out:
        tmp = Path(a.out).with_suffix(".tmp")
        tmp.write_text(json.dumps(rows, indent=1) + "\n")
        tmp.replace(a.out)
    return 0


if __name__ == "__main__":  # pragma: no cover
    from ..exitcodes import run_command

    raise SystemExit(run_command("python -m bsv.bench.refine", main))

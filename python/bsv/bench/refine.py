"""How much of the calibration floor the floor-plane and board-depth refinements remove, and what the
intervals become (``python -m bsv.bench.refine``).

For each subject of the synthetic cohort, the virtual rig scans it inside the clinic room (so that both
cameras see the floor) in a calibrated condition (default l5ca: the paper's calibration error and L515
depth noise). Each camera's estimated extrinsics are refined with the floor it sees
(:func:`bsv.frontend.floorplane.refine_with_floor`, person pixels from the scanner's label image), and
the calibration floor (:mod:`bsv.bench.floor`: a perfect registration of that capture) is measured with
the estimated and with the refined extrinsics. Also reported: the remaining calibration error per
parameter (in units of the paper's standard deviations), which shows what the floor can and cannot fix.

The board (``--board``, the default): the rig draws each camera's calibration error from the scan seed and
the camera only, so a scan of the calibration board alone (:func:`board_mesh`: a box of the board face's
size and thickness where :class:`bsv.frontend.marker.Board` stands) with the same condition and seed is
that capture's depth view of the board under the same error. Four extrinsics per capture: as calibrated,
refined by the floor, by the board (:func:`bsv.frontend.boardplane.refine_with_board`, the paper's
covariance as the prior) and by the board then the floor (what ``bsv calibrate --depth`` then ``bsv
process --refine-floor`` do), each with its covariance (paper's; conditioned on the floor; the board's
posterior; both). For each, the floor volumes and asymmetries against the truth, and the calibration-only
95 % interval of that floor estimate (:func:`calibration_interval`: the Monte Carlo of
:func:`bsv.uncertainty.calibration_spread` over the covariance) with its coverage of the truth; the
half-width of the full interval adds the packaged error model's SD of the condition's depth
(:data:`bsv.bench.coverage.DEPTH_OF_CONDITION`) in quadrature, as ``bsv process`` would.
"""

from __future__ import annotations

import argparse
import json
import math
import tempfile
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import BenchError
from ..frontend.marker import Board
from ..types import Mesh
from ..uncertainty import PAPER_STD, PARAMETERS, Z95, pose_delta, transform
from .common import rve, signed_error
from .floor import CameraPose, floor_mesh, floor_volumes, read_camera_poses
from .reference import CALIBRATED
from .synth import scan_seed

#: Volumes whose floor is reported.
REPORTED: tuple[str, ...] = ("trunk_limbs", "torso", "upper_arm_l", "upper_arm_r", "forearm_l", "forearm_r")
#: The extrinsics compared by the board bench, in order.
VARIANTS: tuple[str, ...] = ("calibrated", "floor", "board", "floor+board")
#: Asymmetries (percentage points) whose floor and intervals the board bench reports.
ASYMMETRIES: tuple[str, ...] = ("asymmetry_upper_arm_pct", "asymmetry_forearm_pct", "asymmetry_thigh_pct",
                                "asymmetry_shin_pct")
#: Calibration Monte Carlo draws per variant (as the synthetic benchmark's).
REFINE_SAMPLES: int = 100
#: Label of the board mesh (the scanner renders labelled meshes; any body label will do).
_BOARD_LABEL: int = 2


def board_mesh(board: Board | None = None) -> Mesh:
    """A closed box of the board face's size and ``board``'s thickness where the board stands (its marker
    centre at ``centre_height_m``, mid-plane at (x0, z0), faces toward +-Z), for the virtual rig."""
    b = board or Board()
    h, th = b.face_size_m / 2.0, b.thickness_m / 2.0
    v = np.array([[sx * h, sy * h, sz * th] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])
    v += np.array([b.x0_m, b.centre_height_m, b.z0_m])
    f = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1], [2, 3, 7], [2, 7, 6],
                  [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]])
    return Mesh(v, f, np.full(8, _BOARD_LABEL, np.uint8), np.full(12, _BOARD_LABEL, np.uint8))


def scan_board(condition: str, seed: int, images: str | Path, board: Board | None = None, *,
               room: bool = True) -> Path:
    """The virtual rig's view of the calibration board alone (:func:`board_mesh`) in ``condition`` under
    scan ``seed``, written to ``images`` (a capture folder): the rig draws each camera's calibration error
    from the seed and the camera only, so this is the board view (colour pose = the capture's estimated
    extrinsics, depth with the condition's noise) of every capture of that seed. ``room``: also the clinic
    room, whose floor each camera then sees around the board (what :func:`refine_calibration` refines
    with)."""
    from .. import scan

    scan(board_mesh(board), condition, seed, images=images, overwrite=True, room=room)
    return Path(images)


@dataclass(frozen=True)
class RefinedCamera:
    """One camera of a virtual capture after :func:`refine_calibration`: its true and refined extrinsics,
    the refined 6 x 6 covariance and its source, and the refinements' figures."""

    pose: CameraPose
    covariance: np.ndarray
    source: str
    board_depth: dict[str, Any]
    floor: dict[str, Any]


def refine_calibration(board_capture: str | Path, board: Board | None = None) -> list[RefinedCamera]:
    """What a user does with a capture's calibration, run on a virtual board capture (:func:`scan_board`
    with ``room=True``): ``bsv calibrate --depth`` (:func:`bsv.frontend.calibrate.refine_pose_with_depth`:
    the board face's depth refines the colour pose, the paper's covariance as the prior since one virtual
    view gives no frames' spread), then ``bsv process --refine-floor``
    (:func:`bsv.frontend.floorplane.refine_extrinsics`: the floor around the board, the board's pixels
    as the person mask). BenchError when the capture lacks its label images; the refinements' own typed
    errors (BoardDepthError, CalibrationError) otherwise."""
    import cv2

    from ..frontend.calibrate import refine_pose_with_depth
    from ..frontend.capture import read_capture
    from ..frontend.floorplane import refine_extrinsics
    from ..uncertainty import paper_covariance

    b = board or Board()
    out = []
    for c in read_camera_poses(board_capture):
        d = Path(board_capture) / c.name
        cap = read_capture(d)
        labels = cv2.imread(str(d / "labels.png"), cv2.IMREAD_UNCHANGED)
        if labels is None:
            raise BenchError(f"{d}/labels.png missing: the refinement needs the scanner's label image")
        r, t, cov, source, board_depth = refine_pose_with_depth(
            c.name, c.est_rotation, c.est_translation, paper_covariance(c.name), "paper default",
            [np.asarray(cap["depth_m"], dtype=np.float64)], cap["intrinsics"], b)
        ext, floor = refine_extrinsics(c.name, {"rotation": r, "translation": t, "covariance": cov,
                                                "covariance_source": source}, cap["depth_m"], cap["intrinsics"],
                                       labels > 0)
        pose = CameraPose(c.name, c.true_rotation, c.true_translation, np.asarray(ext["rotation"]),
                          np.asarray(ext["translation"]))
        out.append(RefinedCamera(pose, np.asarray(ext["covariance"]), str(ext["covariance_source"]), board_depth,
                                 {k: float(v) for k, v in floor.items()}))
    return out


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


def refine_variants(capture: str | Path, board_capture: str | Path, board: Board | None = None
                    ) -> tuple[dict[str, list[CameraPose]], dict[str, list[np.ndarray]], dict[str, Any]]:
    """Per variant of :data:`VARIANTS`: each camera's (true, refined) poses and its covariance, from a
    virtual capture in a room (the floor) and the board's capture under the same seed (module doc); and
    per camera the remaining error per parameter in paper SDs and the board fit's figures."""
    import cv2

    from ..frontend.boardplane import refine_with_board
    from ..frontend.capture import read_capture
    from ..frontend.floorplane import refine_with_floor
    from ..uncertainty import condition_on_floor, paper_covariance

    b = board or Board()
    cams = read_camera_poses(capture)
    board_cams = {c.name: c for c in read_camera_poses(board_capture)}
    poses: dict[str, list[CameraPose]] = {v: [] for v in VARIANTS}
    covs: dict[str, list[np.ndarray]] = {v: [] for v in VARIANTS}
    info: dict[str, Any] = {}
    for c in cams:
        bc = board_cams.get(c.name)
        if bc is None or not (np.allclose(bc.est_rotation, c.est_rotation) and
                              np.allclose(bc.est_translation, c.est_translation)):
            raise BenchError(f"{board_capture}: camera {c.name!r} is not calibrated as in {capture}; scan the board "
                             "with the same condition and seed")
        d = Path(capture) / c.name
        cap = read_capture(d)
        labels = cv2.imread(str(d / "labels.png"), cv2.IMREAD_UNCHANGED)
        if labels is None:
            raise BenchError(f"{d}/labels.png missing: the refinement bench needs the scanner's label image")
        bcap = read_capture(Path(board_capture) / c.name)
        cov0 = paper_covariance(c.name)

        def floor(r: np.ndarray, t: np.ndarray, cov: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
            ref = refine_with_floor(r, t, cap["depth_m"], cap["intrinsics"], labels > 0, name=c.name)  # noqa: B023
            return ref.rotation, ref.translation, condition_on_floor(cov, ref.rotation)

        brd = refine_with_board(c.est_rotation, c.est_translation, cov0, bcap["depth_m"], bcap["intrinsics"], b,
                                c.name)
        est = {"calibrated": (c.est_rotation, c.est_translation, cov0),
               "floor": floor(c.est_rotation, c.est_translation, cov0),
               "board": (brd.rotation, brd.translation, brd.covariance)}
        est["floor+board"] = floor(*est["board"])
        std = np.asarray(PAPER_STD.get(c.name, PAPER_STD["back"]))
        info[c.name] = {"board": brd.report(), "error_sd": {}, "posterior_sd": {}}
        for v in VARIANTS:
            r, t, cov = est[v]
            poses[v].append(CameraPose(c.name, c.true_rotation, c.true_translation, r, t))
            covs[v].append(cov)
            info[c.name]["error_sd"][v] = (pose_delta(c.true_rotation, c.true_translation, r, t) / std).tolist()
            info[c.name]["posterior_sd"][v] = (np.sqrt(np.diag(cov)) / std).tolist()
    return poses, covs, info


def calibration_interval(mesh: Mesh, poses: list[CameraPose], covs: list[np.ndarray], *,
                         samples: int = REFINE_SAMPLES) -> tuple[dict[str, float], dict[str, float]]:
    """(floor estimate, calibration SD in the comparison space) per quantity of a capture: the floor mesh
    of ``poses`` (what a perfect registration of the capture would measure) and the spread of
    :func:`bsv.uncertainty.calibration_spread` over ``covs`` at the refined extrinsics. The calibration-only
    95 % interval is ``T^-1(T(estimate) +- 1.96 sd)``."""
    from .. import volumes
    from ..uncertainty import CameraSpread, calibration_spread, quantities

    fm = floor_mesh(mesh, poses)
    est = quantities(volumes(fm, islands=True))
    spread = [CameraSpread(p.name, p.est_rotation, p.est_translation, cov, "bench") for p, cov in
              zip(poses, covs, strict=True)]
    return est, calibration_spread(fm, spread, samples=samples)


def run_board(n: int = 10, seed: int = 0, condition: str = "l5ca", progress: bool = True,
              board: Board | None = None, samples: int = REFINE_SAMPLES) -> list[dict[str, Any]]:
    """One row per subject: truth, and per variant of :data:`VARIANTS` the floor estimate and its
    calibration SD (:func:`calibration_interval`) for the reported volumes and asymmetries; the cameras'
    remaining errors (module doc)."""
    from tqdm import tqdm

    from .. import bodies, scan, volumes
    from ..uncertainty import quantities

    if condition not in CALIBRATED:
        raise BenchError(f"--condition {condition}: the floor needs a calibrated condition ({', '.join(CALIBRATED)})")
    b = board or Board()
    keys = (*REPORTED, *ASYMMETRIES)
    rows = []
    for i in tqdm(range(n), desc=f"board {condition}", unit="subject", disable=not progress):
        mesh = bodies.subject(i, seed).body.mesh()
        truth = quantities(volumes(mesh))
        with tempfile.TemporaryDirectory(prefix="bsv-refine-") as tmp:
            cap, bcap = Path(tmp) / "subject", Path(tmp) / "board"
            scan(mesh, condition, scan_seed(seed, i), images=cap, overwrite=True, room=True)
            scan_board(condition, scan_seed(seed, i), bcap, b, room=False)
            poses, covs, info = refine_variants(cap, bcap, b)
        row: dict[str, Any] = {"subject": i, "truth": {k: truth[k] for k in keys if k in truth}, "cameras": info}
        for v in VARIANTS:
            est, sd = calibration_interval(mesh, poses[v], covs[v], samples=samples)
            row[v] = {"estimate": {k: est[k] for k in keys if k in est}, "calibration_sd": {k: sd[k] for k in keys if k in sd}}
        rows.append(row)
    return rows


def _err(name: str, est: float, truth: float) -> float:
    """Signed error: percent for volumes, points for asymmetries."""
    return est - truth if name.startswith("asymmetry_") else signed_error(est, truth)


def board_markdown(rows: Sequence[dict[str, Any]], condition: str, seed: int) -> str:
    """The board bench's tables: floor errors (mean |error|, mean signed, worst subject), the remaining
    calibration error per parameter, and the intervals (half-widths, coverage of the floor estimate)."""
    from statistics import median

    from ..uncertainty import default_error_model
    from .coverage import DEPTH_OF_CONDITION

    model = default_error_model(DEPTH_OF_CONDITION.get(condition, "l515"))
    n = len(rows)
    head = f"{condition}, {n} subjects (cohort seed {seed}), clinic room; board {Board().face_size_m * 100:.0f} cm"
    out = [(f"Calibration floor (perfect registration) in {head}: mean |error| (mean signed; worst subject), "
           "percent for volumes, points for asymmetries."), "",
           "| quantity | " + " | ".join(VARIANTS) + " |", "|---|" + "---|" * len(VARIANTS)]
    for k in ("trunk_limbs", "torso", "forearm_l", "forearm_r", *ASYMMETRIES):
        cells = []
        for v in VARIANTS:
            e = np.array([_err(k, r[v]["estimate"][k], r["truth"][k]) for r in rows if k in r[v]["estimate"]])
            w = int(np.argmax(np.abs(e)))
            cells.append(f"{np.mean(np.abs(e)):.2f} ({np.mean(e):+.2f}; {e[w]:+.2f} s{rows[w]['subject']})")
        out.append(f"| {k} | " + " | ".join(cells) + " |")
    out += ["", "Calibration error left per parameter, RMS in units of the paper's SD "
            "(" + ", ".join(VARIANTS) + "):", "",
            "| camera | " + " | ".join(PARAMETERS) + " |", "|---|" + "---|" * len(PARAMETERS)]
    for cam in rows[0]["cameras"] if rows else []:
        rms = {v: np.sqrt(np.mean([np.square(r["cameras"][cam]["error_sd"][v]) for r in rows], axis=0))
               for v in VARIANTS}
        out.append(f"| {cam} | " + " | ".join(" / ".join(f"{rms[v][j]:.2f}" for v in VARIANTS)
                                               for j in range(len(PARAMETERS))) + " |")
    out += ["", ("Intervals with each variant's covariance: median half-width of the calibration-only interval "
            f"and of the full one (+ the packaged '{DEPTH_OF_CONDITION.get(condition, 'l515')}' error model's SD), "
            "and the calibration-only interval's coverage of the truth by the floor estimate."), "",
            ("| variant | trunk_limbs cal. half-width % | trunk_limbs full half-width % | limb asym. cal. half-width pts "
            "| limb asym. full half-width pts | forearm asym. full half-width pts | coverage volumes % "
            "| coverage asymmetries % |"), "|---|---|---|---|---|---|---|---|"]
    vols = ("trunk_limbs", "torso", "upper_arm_l", "upper_arm_r", "forearm_l", "forearm_r")
    for v in VARIANTS:
        hw_tl_c, hw_tl_f, hw_a_c, hw_a_f, hw_fa, in_v, in_a = [], [], [], [], [], [], []
        for r in rows:
            est, sd = r[v]["estimate"], r[v]["calibration_sd"]
            for k in (*vols, *ASYMMETRIES):
                if k not in est or k not in sd:
                    continue
                c = transform(k, est[k])
                tv = transform(k, r["truth"][k])
                inside = abs(tv - c) <= Z95 * sd[k]
                full = Z95 * float(np.hypot(sd[k], model.entries.get(k, (0.0, 0.0))[1]))
                if k.startswith("asymmetry_"):
                    in_a.append(inside)
                    hw_a_c.append(Z95 * sd[k])
                    hw_a_f.append(full)
                    if k == "asymmetry_forearm_pct":
                        hw_fa.append(full)
                else:
                    in_v.append(inside)
                    if k == "trunk_limbs":  # log half-width -> percent of the estimate
                        hw_tl_c.append((math.exp(Z95 * sd[k]) - math.exp(-Z95 * sd[k])) / 2.0 * 100.0)
                        hw_tl_f.append((math.exp(full) - math.exp(-full)) / 2.0 * 100.0)
        out.append(f"| {v} | {median(hw_tl_c):.2f} | {median(hw_tl_f):.2f} | {median(hw_a_c):.1f} | "
                   f"{median(hw_a_f):.1f} | {median(hw_fa):.1f} | {100.0 * np.mean(in_v):.1f} | "
                   f"{100.0 * np.mean(in_a):.1f} |")
    return "\n".join(out)


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
    """``python -m bsv.bench.refine [--n 10] [--seed 0] [--condition l5ca] [--floor-only] [--out rows.json]``."""
    ap = argparse.ArgumentParser(prog="python -m bsv.bench.refine", description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, default=10)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--condition", default="l5ca", choices=CALIBRATED)
    ap.add_argument("--out", help="also write the rows as JSON here (refused if it exists)")
    ap.add_argument("--quiet", action="store_true")
    ap.add_argument("--floor-only", action="store_true", help="the floor refinement alone (no board, no intervals)")
    a = ap.parse_args(argv)
    if a.out and Path(a.out).exists():
        raise BenchError(f"{a.out} exists; choose another --out")
    if a.floor_only:
        rows = run_refine(a.n, a.seed, a.condition, progress=not a.quiet)
        print(summary_markdown(rows, a.condition))
    else:
        rows = run_board(a.n, a.seed, a.condition, progress=not a.quiet)
        print(board_markdown(rows, a.condition, a.seed))
    if a.out:
        tmp = Path(a.out).with_suffix(".tmp")
        tmp.write_text(json.dumps(rows, indent=1) + "\n")
        tmp.replace(a.out)
    return 0


if __name__ == "__main__":  # pragma: no cover
    from ..exitcodes import run_command

    raise SystemExit(run_command("python -m bsv.bench.refine", main))

#!/usr/bin/env python3
"""Writes the example calibration images of the README (``examples/calib``): the double-sided ArUco board
(id 336, 16 cm, the ``bsv calibrate`` defaults: centre 1.0 m above the floor, 5 mm thick, where the subject
stands) as the virtual rig's two cameras see it, plus each camera's intrinsics file.

The rig is the one ``bsv-cli scan`` / :func:`bsv.scan` renders captures with: its cameras' true poses
(``true_camera_to_world``) and intrinsics are read from a noer scan of the default template written to a
temporary folder, so the images follow the rig if it changes. Each frame is
:func:`bsv.frontend.marker.render_view` of the board face the camera sees, plus Gaussian sensor noise
(a fixed seed per camera and frame: the same bytes on every run with the same libraries). Layout::

    examples/calib/front/frame_00.png ... frame_NN.png   grey, the rig's colour-stream size
    examples/calib/front/camera.json                     {"name": "front", "intrinsics": {...}}
    examples/calib/back/...

``bsv calibrate --images front=examples/calib/front back=examples/calib/back --intrinsics
front=examples/calib/front/camera.json back=examples/calib/back/camera.json`` recovers the rig's
extrinsics from them (tests/python/test_example_calibration.py).

Usage: python scripts/make_example_calibration.py [--out examples/calib] [--frames 3] [--noise 0.5] [--overwrite]
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
SIDES = ("front", "back")


@dataclass(frozen=True)
class RigCamera:
    """One camera of the virtual rig: its intrinsics (JSON form) and true camera-to-world pose."""

    name: str
    intrinsics: dict
    rotation: np.ndarray
    translation: np.ndarray


def rig_cameras() -> dict[str, RigCamera]:
    """The virtual rig's cameras, read from the camera.json files of an exact (noer) scan of the default
    template written to a temporary folder."""
    import bsv

    with tempfile.TemporaryDirectory(prefix="bsv-rig-") as tmp:
        bsv.scan(bsv.default_template(), "noer", 0, images=Path(tmp) / "capture")
        out = {}
        for side in SIDES:
            doc = json.loads((Path(tmp) / "capture" / side / "camera.json").read_text())
            pose = doc["true_camera_to_world"]
            out[side] = RigCamera(side, doc["intrinsics"], np.asarray(pose["rotation"], dtype=np.float64),
                                  np.asarray(pose["translation"], dtype=np.float64))
    return out


def render_frames(camera: RigCamera, frames: int, noise: float, seed: int) -> list[np.ndarray]:
    """``frames`` 8-bit grey images of the default board's face seen by ``camera`` (the marker's pose in the
    camera frame from the board's placement and the camera's true pose), each with its own area-sampling
    jitter and Gaussian noise of ``noise`` grey levels."""
    from bsv.frontend.intrinsics import Intrinsics
    from bsv.frontend.marker import Board, render_view

    board = Board()
    intr = Intrinsics.from_json(camera.intrinsics)
    r_wm, t_wm = board.marker_to_world(camera.name)
    r_cm = camera.rotation.T @ r_wm
    t_cm = camera.rotation.T @ (t_wm - camera.translation)
    rng = np.random.default_rng(seed)
    out = []
    for i in range(frames):
        clean = render_view(board.marker, intr, r_cm, t_cm, samples=16, seed=seed * 100 + i).astype(np.float64)
        out.append(np.clip(np.rint(clean + rng.normal(0.0, noise, clean.shape)), 0, 255).astype(np.uint8))
    return out


def write_examples(out: Path, frames: int = 3, noise: float = 0.5, overwrite: bool = False) -> list[Path]:
    """Renders and writes the example images and intrinsics files into ``out`` (refuses a folder that
    already holds them unless ``overwrite``); returns the written paths."""
    import cv2

    if frames < 1:
        raise SystemExit(f"--frames must be at least 1, got {frames}")
    for side in SIDES:
        d = out / side
        if d.exists() and any(d.iterdir()) and not overwrite:
            raise SystemExit(f"{d} is not empty; pass --overwrite to replace the example images")
    written = []
    for k, (side, cam) in enumerate(rig_cameras().items()):
        d = out / side
        d.mkdir(parents=True, exist_ok=True)
        for old in d.glob("frame_*.png"):
            old.unlink()
        for i, img in enumerate(render_frames(cam, frames, noise, seed=k + 1)):
            path = d / f"frame_{i:02d}.png"
            if not cv2.imwrite(str(path), img, [cv2.IMWRITE_PNG_COMPRESSION, 9]):
                raise SystemExit(f"could not write {path}")
            written.append(path)
        intr = d / "camera.json"
        intr.write_text(json.dumps({"name": side, "intrinsics": cam.intrinsics}, indent=1) + "\n")
        written.append(intr)
    return written


def main(argv: list[str] | None = None) -> int:
    """Command line: see the module docstring."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", type=Path, default=ROOT / "examples" / "calib")
    ap.add_argument("--frames", type=int, default=3, help="frames per camera (3: enough for a spread estimate)")
    ap.add_argument("--noise", type=float, default=0.5, help="sensor noise, grey levels (1 sd)")
    ap.add_argument("--overwrite", action="store_true")
    a = ap.parse_args(argv)
    paths = write_examples(a.out, a.frames, a.noise, a.overwrite)
    total = sum(p.stat().st_size for p in paths)
    print(f"wrote {len(paths)} files ({total / 1e6:.2f} MB) under {a.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

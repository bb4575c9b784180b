"""Makes the empty clinic room that MediaPipe sees behind every subject (bsv.frontend.background.BACKDROP_FILES).

The virtual rig renders ``--subjects`` bodies of cohort ``--seed`` in its clinic room, all with the look of one
scan seed (``--scan-seed``: its lights and their colour; the room is the same for every seed), front and back.
Each pixel of the backdrop is the median of that pixel over the renders in which no body covers it; the pixels
some body covers in every render (behind the trunk) are filled from around them (OpenCV's Telea inpainting at a
quarter of the resolution, scaled back up), where a subject's region will cover them again. Written as PNG
into ``python/bsv/data/`` (``--out``):

    .venv/bin/python benchmarks/make_backdrop.py
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import cv2
import numpy as np

import bsv
from bsv.bench.synth import scan_seed
from bsv.frontend.background import BACKDROP_FILES
from bsv.frontend.capture import read_capture

ROOT = Path(__file__).resolve().parent.parent


def backdrop(renders: list[tuple[np.ndarray, np.ndarray]]) -> np.ndarray:
    """The empty room of (colour RGB uint8, true labels) renders of one camera: the per-pixel median of the
    unlabelled pixels, the always-covered ones inpainted."""
    stack = np.stack([np.where(lab[..., None] > 0, np.nan, img.astype(np.float64)) for img, lab in renders])
    covered = np.isnan(stack).all(axis=0).any(axis=2)
    med = np.zeros(stack.shape[1:], dtype=np.float64)
    seen = ~covered
    med[seen] = np.nanmedian(stack[:, seen], axis=0)
    img = np.clip(np.rint(med), 0, 255).astype(np.uint8)
    small = cv2.resize(img, None, fx=0.25, fy=0.25, interpolation=cv2.INTER_AREA)
    hole = cv2.resize(covered.astype(np.uint8), (small.shape[1], small.shape[0]), interpolation=cv2.INTER_NEAREST)
    fill = cv2.inpaint(small, cv2.dilate(hole, np.ones((3, 3), np.uint8)), 15, cv2.INPAINT_TELEA)
    fill = cv2.resize(fill, (img.shape[1], img.shape[0]), interpolation=cv2.INTER_LINEAR)
    return np.where(covered[..., None], fill, img)


def main() -> None:
    """Renders, makes and writes both cameras' backdrops."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seed", type=int, default=5, help="cohort seed of the bodies (default 5)")
    ap.add_argument("--subjects", type=int, default=6, help="bodies rendered (default 6)")
    ap.add_argument("--scan-seed", type=int, default=scan_seed(0, 0), help="the look's scan seed (default the demo's)")
    ap.add_argument("--out", default=str(ROOT / "python" / "bsv" / "data"), help="folder of the PNGs")
    args = ap.parse_args()
    renders: dict[str, list[tuple[np.ndarray, np.ndarray]]] = {v: [] for v in BACKDROP_FILES}
    with tempfile.TemporaryDirectory(prefix="bsv-backdrop-") as tmp:
        for i in range(args.subjects):
            folder = Path(tmp) / f"s{i}"
            bsv.scan(bsv.bodies.subject(i, args.seed).body.mesh(), "noer", args.scan_seed, images=str(folder), room=True)
            for view in renders:
                cap = read_capture(folder / view)
                labels = cv2.imread(str(folder / view / "labels.png"), cv2.IMREAD_UNCHANGED)
                renders[view].append((cap["colour"], labels))
    for view, name in BACKDROP_FILES.items():
        path = Path(args.out) / name
        cv2.imwrite(str(path), backdrop(renders[view])[:, :, ::-1], [cv2.IMWRITE_PNG_COMPRESSION, 9])
        print(f"{view}: {path} ({path.stat().st_size // 1024} kB)")


if __name__ == "__main__":
    main()

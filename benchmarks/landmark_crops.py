"""Measures whether MediaPipe's heavy pose landmark model places the elbows and knees better when it sees the limb
at a finer scale: the model run by hand on crops tighter than MediaPipe's own region of interest (round 2, session 49).

MediaPipe shows its landmark model a 256 x 256 crop of a square about 1.25 times the body's extent, which it derives
from its own landmarks (the two auxiliary landmarks 33 and 34). This script renders room captures (noer) of cohort
subjects with the rig's true joints, runs the camera path's detection as shipped
(:func:`bsv.frontend.segment.detect`: image and mirror image averaged), and runs the same model file
(``pose_landmark_heavy.tflite``) through LiteRT on crops it builds itself, each on the image and its mirror image:

- ``std``: MediaPipe's region of interest (iterated three times from the model's own auxiliary landmarks; it
  reproduces the shipped elbow landmarks to within 2.5 px);
- ``arm<s>`` / ``leg<s>``: the same crop scaled by ``s`` (0.8, 0.65) and centred on the arms' (shoulders, elbows,
  wrists) or the legs' (hips, knees, ankles) landmarks: a finer view of the limb;
- each also without MediaPipe's refinement from the heatmap (``/raw``: the model's regression output).

It prints each landmark's error along its limb (mm at the joint's depth, against the rig's joint projected: per
view, mean / sd / robust sd, and per limb the two views' mean, sd), and the correlations of each view's error
with what the model says of its own certainty (visibility, presence, the heatmap's peak and spread, the
image-vs-mirror spread). Each run keeps its measurements in ``--out`` (``rows_<seeds>_n<n>.json``) and reports
over all of them there: two runs on disjoint seeds share the two cores. LiteRT is not a dependency of BSV::

    .venv/bin/pip install ai-edge-litert
    .venv/bin/python benchmarks/landmark_crops.py --seeds 0,2,20,21 --n 10 --out /tmp/crops
"""

from __future__ import annotations

import argparse
import json
import sys
from collections import defaultdict
from pathlib import Path
from typing import Any

import cv2
import numpy as np
from tqdm import tqdm

import bsv
from bsv.bench.synth import scan_seed
from bsv.bodies import subject
from bsv.bodies.joints import rig_joints
from bsv.errors import BsvError
from bsv.frontend.background import showing
from bsv.frontend.capture import read_capture
from bsv.frontend.landmarks import Camera
from bsv.frontend.pose_model import model_path
from bsv.frontend.segment import detect, view_params

INPUT = 256  # the model's input side (pixels)
HEATMAP = 64  # its heatmap's side
REFINE_KERNEL = 7  # MediaPipe's RefineLandmarksFromHeatmap: kernel size and the least confidence it refines at
REFINE_MIN_CONFIDENCE = 0.5
ROI_SCALE = 1.25  # MediaPipe's region of interest: twice the auxiliary landmarks' distance, times this
#: MediaPipe's left/right pose landmark pairs (swapped in the mirror image).
PAIRS = [(i, i + 1) for i in range(11, 33, 2)] + [(1, 4), (2, 5), (3, 6), (7, 8), (9, 10)]
ARM = [11, 12, 13, 14, 15, 16]
LEG = [23, 24, 25, 26, 27, 28]
#: joint: (left index, right index, proximal joint, distal joint) of the limb it is measured along.
JOINTS = {"elbow": (13, 14, "shoulder", "wrist"), "knee": (25, 26, "hip", "ankle")}
#: The crops: None for MediaPipe's own, else (scale, the landmarks it is centred on).
CROPS: dict[str, tuple[float, list[int]] | None] = {
    "std": None, "arm0.8": (0.8, ARM), "arm0.65": (0.65, ARM), "leg0.8": (0.8, LEG), "leg0.65": (0.65, LEG)}
#: The crops each joint is scored on (a crop centred on the arms leaves the knees out of it, and the reverse).
SCORED = {"elbow": ("std", "arm0.8", "arm0.65"), "knee": ("std", "leg0.8", "leg0.65")}


def sigmoid(x: np.ndarray) -> np.ndarray:
    return 1.0 / (1.0 + np.exp(-np.clip(x, -60.0, 60.0)))


class LandmarkModel:
    """The pose landmark model file run by LiteRT on a square crop of an image."""

    def __init__(self, path: Path) -> None:
        try:
            from ai_edge_litert.interpreter import Interpreter
        except ImportError:
            sys.exit("this script runs the model file through LiteRT: .venv/bin/pip install ai-edge-litert")
        self.it = Interpreter(model_path=str(path), num_threads=1)
        self.it.allocate_tensors()
        self.input = self.it.get_input_details()[0]["index"]
        self.outputs = {d["name"]: d["index"] for d in self.it.get_output_details()}

    def run(self, img: np.ndarray, centre: np.ndarray, size: float, theta: float) -> dict[str, np.ndarray]:
        """The 39 landmarks of the crop of ``img`` centred at ``centre`` (continuous pixels: a pixel's corner at
        integers), ``size`` pixels wide, turned by ``theta``: ``refined`` and ``raw`` (39, 2) in the image's
        pixel-centre coordinates, and per landmark ``vis``, ``pres``, the heatmap's ``peak`` and ``spread``
        (heatmap cells)."""
        c, s = np.cos(theta), np.sin(theta)
        rot = np.array([[c, -s], [s, c]])
        a = size / INPUT * rot
        b = centre - size * rot @ np.array([0.5, 0.5]) + a @ np.array([0.5, 0.5]) - 0.5
        crop = cv2.warpAffine(img, np.hstack([a, b[:, None]]), (INPUT, INPUT),
                              flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP, borderMode=cv2.BORDER_CONSTANT)
        self.it.set_tensor(self.input, (crop.astype(np.float32) / 255.0)[None])
        self.it.invoke()
        lm = self.it.get_tensor(self.outputs["Identity"]).reshape(39, 5)
        heat = sigmoid(self.it.get_tensor(self.outputs["Identity_3"])[0])
        raw = lm[:, :2] / INPUT
        refined = raw.copy()
        peak = np.zeros(39)
        spread = np.zeros(39)
        rows, cols = np.mgrid[0:HEATMAP, 0:HEATMAP]
        half = (REFINE_KERNEL - 1) // 2
        for k in range(39):
            w = heat[:, :, k]
            peak[k] = w.max()
            mx, my = (cols * w).sum() / w.sum(), (rows * w).sum() / w.sum()
            spread[k] = np.sqrt((((cols - mx) ** 2 + (rows - my) ** 2) * w).sum() / w.sum())
            col, row = int(raw[k, 0] * HEATMAP), int(raw[k, 1] * HEATMAP)
            if not (0 <= col < HEATMAP and 0 <= row < HEATMAP):
                continue
            win = (slice(max(0, row - half), min(HEATMAP, row + half + 1)),
                   slice(max(0, col - half), min(HEATMAP, col + half + 1)))
            ww = w[win]
            if ww.max() >= REFINE_MIN_CONFIDENCE:
                refined[k] = [(cols[win] * ww).sum() / ww.sum() / HEATMAP, (rows[win] * ww).sum() / ww.sum() / HEATMAP]

        def to_image(p: np.ndarray) -> np.ndarray:
            return centre[None, :] + size * ((p - 0.5) @ rot.T) - 0.5

        return {"refined": to_image(refined), "raw": to_image(raw), "vis": sigmoid(lm[:, 3]),
                "pres": sigmoid(lm[:, 4]), "peak": peak, "spread": spread}

    def detect(self, img: np.ndarray, pose: np.ndarray, crop: tuple[float, list[int]] | None) -> dict[str, np.ndarray]:
        """The model on MediaPipe's region of interest (started from the shipped ``pose``, then iterated from the
        model's auxiliary landmarks 33 and 34 as MediaPipe tracks), or on that region scaled and moved to the
        landmarks of ``crop``."""
        hips = (pose[23, :2] + pose[24, :2]) / 2 + 0.5
        up = (pose[11, :2] + pose[12, :2]) / 2 + 0.5 - hips
        centre, size, theta = hips, 2.6 * ROI_SCALE * float(np.hypot(*up)), float(np.arctan2(up[0], -up[1]))
        for _ in range(3):
            out = self.run(img, centre, size, theta)
            k0, k1 = out["refined"][33] + 0.5, out["refined"][34] + 0.5
            d = k1 - k0
            centre, size = k0, 2.0 * ROI_SCALE * float(np.hypot(*d))
            theta = float(np.pi / 2 - np.arctan2(-d[1], d[0]))
        out = self.run(img, centre, size, theta)
        if crop is None:
            return out
        scale, idx = crop
        return self.run(img, out["refined"][idx].mean(axis=0) + 0.5, size * scale, theta)


def mirrored(out: dict[str, np.ndarray], width: int) -> dict[str, np.ndarray]:
    """A detection of the mirror image mapped back to the image (x flipped, left and right swapped)."""
    res = {}
    for k, v in out.items():
        v = v.copy()
        if v.ndim == 2:
            v[:, 0] = width - 1 - v[:, 0]
        for a, b in PAIRS:
            v[[a, b]] = v[[b, a]]
        res[k] = v
    return res


def oriented(out: dict[str, np.ndarray], ref: np.ndarray) -> dict[str, np.ndarray]:
    """``out`` with each left/right pair named as in ``ref`` (the shipped pose, oriented to the subject)."""
    res = {k: v.copy() for k, v in out.items()}
    p = out["refined"]
    for a, b in PAIRS:
        keep = np.hypot(*(p[a] - ref[a, :2])) + np.hypot(*(p[b] - ref[b, :2]))
        swap = np.hypot(*(p[a] - ref[b, :2])) + np.hypot(*(p[b] - ref[a, :2]))
        if swap < keep:
            for v in res.values():
                v[[a, b]] = v[[b, a]]
    return res


def render(seed: int, index: int, folder: Path) -> None:
    """Cohort subject ``index`` of ``seed`` captured in the room (noer) into ``folder``, with its rig joints."""
    if (folder / "truth.json").exists():
        return
    s = subject(index, seed)
    bsv.scan(s.body.mesh(), "noer", scan_seed(seed, index), images=str(folder), overwrite=True, room=True)
    joints = rig_joints(s.phenotype, s.pose)
    (folder / "truth.json").write_text(json.dumps({k: np.asarray(v).tolist() for k, v in joints.items()}))


def measure(model: LandmarkModel, folder: Path) -> list[dict[str, Any]]:
    """Per view, joint, side, crop and output: the error along the limb (mm) and the model's own certainty."""
    truth = {k: np.asarray(v) for k, v in json.loads((folder / "truth.json").read_text()).items()}
    rows = []
    for view in ("front", "back"):
        cap = read_capture(folder / view)
        cam = Camera.from_json(cap["intrinsics"], cap["meta"]["camera_to_world"])
        img, depth = cap["colour"], cap["depth_m"]
        shown = showing(view_params(view).background, view, img.shape[:2], depth, cam).image(img)
        shipped = detect(img, view, depth=depth, camera=cam).pose
        width = img.shape[1]
        flipped = np.ascontiguousarray(shown[:, ::-1])
        ref_m = mirrored({"pose": shipped}, width)["pose"]
        runs = {}
        for name, crop in CROPS.items():
            first = oriented(model.detect(shown, shipped, crop), shipped)
            second = oriented(mirrored(model.detect(flipped, ref_m, crop), width), shipped)
            runs[name] = (first, second)
        for joint, (li, ri, prox, dist) in JOINTS.items():
            for side, idx in (("l", li), ("r", ri)):
                names = (f"{prox}_{side}", f"{joint}_{side}", f"{dist}_{side}")
                uv = cam.project(np.array([truth[n] for n in names]))
                along = (uv[2] - uv[0]) / np.linalg.norm(uv[2] - uv[0])
                mm = float((truth[names[1]] - cam.translation) @ cam.rotation[:, 2]) / cam.intrinsics.fx * 1000.0
                rows.append({"capture": folder.name, "view": view, "joint": joint, "side": side, "crop": "shipped",
                             "output": "refined", "error": float((shipped[idx, :2] - uv[1]) @ along * mm)})
                for name, (first, second) in runs.items():
                    if name not in SCORED[joint]:
                        continue
                    for output in ("refined", "raw"):
                        p = (first[output][idx] + second[output][idx]) / 2
                        rows.append({
                            "capture": folder.name, "view": view, "joint": joint, "side": side, "crop": name,
                            "output": output, "error": float((p - uv[1]) @ along * mm),
                            "mirror_spread": abs(float((first[output][idx] - second[output][idx]) @ along * mm)),
                            **{k: float((first[k][idx] + second[k][idx]) / 2) for k in ("vis", "pres", "peak", "spread")}})
    return rows


def robust_sd(x: np.ndarray) -> float:
    return float(1.4826 * np.median(np.abs(x - np.median(x))))


def report(rows: list[dict[str, Any]]) -> None:
    """The tables of the module's docstring."""
    groups: dict[tuple[str, str, str], list[dict[str, Any]]] = defaultdict(list)
    for r in rows:
        groups[(r["joint"], r["crop"], r["output"])].append(r)
    print("| joint | crop | output | views | per view mean / sd / robust sd mm | limbs | per limb (2 views) sd mm |")
    print("|---|---|---|---|---|---|---|")
    for (joint, crop, output), rr in sorted(groups.items()):
        e = np.array([r["error"] for r in rr])
        limbs: dict[tuple[str, str], list[float]] = defaultdict(list)
        for r in rr:
            limbs[(r["capture"], r["side"])].append(r["error"])
        both = np.array([np.mean(v) for v in limbs.values() if len(v) == 2])
        print(f"| {joint} | {crop} | {output} | {len(e)} | {e.mean():+.1f} / {e.std():.1f} / {robust_sd(e):.1f} | "
              f"{len(both)} | {both.std():.1f} |")
    print("\nCorrelation of each view's |error - median| with the model's own certainty (std crop, refined):")
    for joint in JOINTS:
        rr = groups[(joint, "std", "refined")]
        e = np.array([r["error"] for r in rr])
        dev = np.abs(e - np.median(e))
        cells = ", ".join(f"{k} {np.corrcoef(dev, [r[k] for r in rr])[0, 1]:+.2f}"
                          for k in ("vis", "pres", "peak", "spread", "mirror_spread"))
        print(f"- {joint}: {cells}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", default="0,2,20,21", help="cohort seeds, comma-separated")
    ap.add_argument("--n", type=int, default=10, help="subjects per seed")
    ap.add_argument("--out", required=True, type=Path, help="folder for the captures and the measurements")
    ap.add_argument("--report", action="store_true", help="only report the measurements already in --out")
    args = ap.parse_args()
    rows: list[dict[str, Any]] = []
    todo = [] if args.report else [(int(s), i) for s in args.seeds.split(",") for i in range(args.n)]
    if todo:
        model = LandmarkModel(model_path(2))
        for seed, i in tqdm(todo, desc="subjects"):
            folder = args.out / f"{seed}_{i}"
            render(seed, i, folder)
            try:
                rows += measure(model, folder)
            except BsvError as exc:  # a capture the camera path cannot read is left out, and said so
                tqdm.write(f"{folder}: left out ({exc})")
        (args.out / f"rows_{args.seeds.replace(',', '-')}_n{args.n}.json").write_text(json.dumps(rows))
    report([r for f in sorted(args.out.glob("rows_*.json")) for r in json.loads(f.read_text())])


if __name__ == "__main__":
    main()

"""Camera segmentation per look: the clinic-room renders of the virtual rig vary the subject's skin tone,
underwear (briefs or trunks, six colours) and hair with the scan seed; this script segments the front and
back images of synthetic subjects (bsv.frontend.landmarks.segment_views, as `bsv process` does) and
compares the labels with the rig's true label images, grouped by look.

The look is read from the render (the rig does not export it): the skin tone from the luminance Y of the
true forearm pixels of the lit front image (lighter: Y >= 90, the rig's four lighter tones; darker: its
three darker ones) and the underwear cut from how far below the crotch the thighs have the crotch's
colour (trunks: more than 6 cm).

Per segment group the signed boundary error is the percent difference between the predicted and the true
pixel counts over the pixels that both call "person" (so mask errors do not count): + = the segment grows.
Same subjects and scan seeds as `bsv bench synth --segmentation camera --seed SEED` (scan seed =
seed * 1000003 + index), so the volume errors of that run can be read next to this table.

    .venv/bin/python benchmarks/appearance_check.py --n 6 --seed 0
"""

from __future__ import annotations

import argparse
import json
import tempfile
from collections import defaultdict
from pathlib import Path

import numpy as np
from PIL import Image
from tqdm import tqdm

import bsv
from bsv.bench.joints import camera_segmentations
from bsv.bench.synth import scan_seed
from bsv.frontend.segment import SEGMENT_IDS, VIEWS

GROUPS = {"torso": ("torso",), "upper_arms": ("upper_arm_l", "upper_arm_r"), "forearms": ("forearm_l", "forearm_r"),
          "thighs": ("thigh_l", "thigh_r"), "shins": ("shin_l", "shin_r")}


def look(colour: np.ndarray, truth: np.ndarray, px_per_m: float) -> tuple[str, str, float]:
    """(skin class, underwear cut, skin luminance) of a front render, from its true labels; ``px_per_m``:
    image pixels per metre at the subject."""
    lum = colour.astype(float) @ np.array([0.2126, 0.7152, 0.0722])
    fore = np.isin(truth, [SEGMENT_IDS["forearm_l"], SEGMENT_IDS["forearm_r"]])
    y = float(np.median(lum[fore]))
    skin_rgb = np.median(colour[fore], axis=0)
    torso = truth == SEGMENT_IDS["torso"]
    rows = np.nonzero(torso.any(axis=1))[0]
    crotch = int(rows.max())
    low = torso & (np.arange(truth.shape[0])[:, None] >= crotch - 0.04 * (crotch - rows.min()))
    under_rgb = np.median(colour[low], axis=0)
    thigh = np.isin(truth, [SEGMENT_IDS["thigh_l"], SEGMENT_IDS["thigh_r"]])
    near = (np.linalg.norm(colour.astype(float) - under_rgb, axis=2)
            < np.linalg.norm(colour.astype(float) - skin_rgb, axis=2)) & thigh
    share = near.sum(axis=1) / np.maximum(thigh.sum(axis=1), 1)
    covered = [r for r in range(crotch, truth.shape[0]) if thigh[r].any() and share[r] > 0.3]
    drop_m = ((max(covered) - crotch) / px_per_m) if covered else 0.0
    cut = "?" if np.linalg.norm(under_rgb - skin_rgb) < 25 else ("trunks" if drop_m > 0.06 else "briefs")
    tone = "lighter" if y >= 90 else "darker"
    return tone, cut, y


def signed_errors(pred: np.ndarray, truth: np.ndarray) -> dict[str, float]:
    """Per group: (predicted - true pixel count) / true count %, over pixels both call person."""
    both = (pred > 0) & (truth > 0)
    out = {}
    for g, names in GROUPS.items():
        ids = [SEGMENT_IDS[n] for n in names]
        t = int(np.isin(truth[both], ids).sum())
        p = int(np.isin(pred[both], ids).sum())
        out[g] = 100.0 * (p - t) / t if t else float("nan")
    out["accuracy"] = 100.0 * float((pred[both] == truth[both]).mean())
    return out


def main() -> None:
    """Command line: segment n subjects in the room, print the per-look table."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=6)
    ap.add_argument("--seed", type=int, default=0)
    a = ap.parse_args()
    rows = []
    for i in tqdm(range(a.n), desc="subjects"):
        s = bsv.bodies.subject(i, a.seed)
        with tempfile.TemporaryDirectory(prefix="bsv-look-") as tmp:
            bsv.scan(s.body.mesh(), "noer", scan_seed(a.seed, i), images=tmp, overwrite=True, room=True)
            segs, _ = camera_segmentations(tmp)
            errs: dict[str, list[float]] = defaultdict(list)
            for v in VIEWS:
                truth = np.asarray(Image.open(f"{tmp}/{v}/labels.png"))
                for k, e in signed_errors(segs[v].labels, truth).items():
                    errs[k].append(e)
                if v == "front":
                    meta = json.loads(Path(f"{tmp}/{v}/camera.json").read_text())
                    ppm = meta["intrinsics"]["fy"] / abs(meta["camera_to_world"]["translation"][2])
                    tone, cut, y = look(np.asarray(Image.open(f"{tmp}/{v}/color.png").convert("RGB")), truth, ppm)
        rows.append((f"subject_{i:03d}", tone, cut, y, {k: float(np.mean(e)) for k, e in errs.items()}))
    head = ["subject", "skin", "underwear", "Y", *GROUPS, "accuracy"]
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    for name, tone, cut, y, e in rows:
        print(f"| {name} | {tone} | {cut} | {y:.0f} | " + " | ".join(f"{e[g]:+.1f}" for g in GROUPS)
              + f" | {e['accuracy']:.1f} |")
    print("\nmean signed pixel error % by look (n subjects)")
    for key, idx in (("skin", 1), ("underwear", 2)):
        for val in sorted({r[idx] for r in rows}):
            sel = [r[4] for r in rows if r[idx] == val]
            print(f"| {key}={val} ({len(sel)}) | " + " | ".join(f"{np.mean([e[g] for e in sel]):+.1f}" for g in GROUPS)
                  + f" | {np.mean([e['accuracy'] for e in sel]):.1f} |")


if __name__ == "__main__":
    main()

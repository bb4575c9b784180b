"""Camera segmentation per look: the clinic-room renders of the virtual rig vary the subject's skin tone,
underwear (briefs or trunks, six colours) and hair, and the room's light (four set-ups, three colours)
with the scan seed; this script segments the front and back images of synthetic subjects
(bsv.frontend.landmarks.segment_views, as `bsv process` does) and compares the labels with the rig's true
label images, grouped by look.

The look is what the rig drew, read from the capture's scan.json (bsv.bench.looks.read_look: light
set-up, light colour, skin tone lighter or darker, underwear cut).

Per segment group the signed boundary error is the percent difference between the predicted and the true
pixel counts over the pixels that both call "person" (so mask errors do not count): + = the segment grows;
"mask IoU" is the person mask's against the truth's. Same subjects and scan seeds as
`bsv bench synth --segmentation camera --seed SEED` (scan seed = seed * 1000003 + index), so the volume
errors of that run (its report.md has them by look too) can be read next to this table.

    .venv/bin/python benchmarks/appearance_check.py --n 6 --seed 0
"""

from __future__ import annotations

import argparse
import tempfile
from collections import defaultdict

import numpy as np
from PIL import Image
from tqdm import tqdm

import bsv
from bsv.bench.joints import camera_segmentations
from bsv.bench.looks import FACTORS, read_look
from bsv.bench.synth import scan_seed
from bsv.frontend.segment import SEGMENT_IDS, VIEWS

GROUPS = {"torso": ("torso",), "upper_arms": ("upper_arm_l", "upper_arm_r"), "forearms": ("forearm_l", "forearm_r"),
          "thighs": ("thigh_l", "thigh_r"), "shins": ("shin_l", "shin_r")}


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
    rows: list[tuple[str, dict[str, str], dict[str, float]]] = []
    for i in tqdm(range(a.n), desc="subjects"):
        s = bsv.bodies.subject(i, a.seed)
        with tempfile.TemporaryDirectory(prefix="bsv-look-") as tmp:
            bsv.scan(s.body.mesh(), "noer", scan_seed(a.seed, i), images=tmp, overwrite=True, room=True)
            look = read_look(tmp) or {}
            segs, _ = camera_segmentations(tmp)
            errs: dict[str, list[float]] = defaultdict(list)
            for v in VIEWS:
                truth = np.asarray(Image.open(f"{tmp}/{v}/labels.png"))
                for k, err in signed_errors(segs[v].labels, truth).items():
                    errs[k].append(err)
                errs["mask_iou"].append(100.0 * float((segs[v].mask & (truth > 0)).sum() / (segs[v].mask | (truth > 0)).sum()))
        rows.append((f"subject_{i:03d}", look, {k: float(np.mean(x)) for k, x in errs.items()}))
    head = ["subject", *FACTORS, *GROUPS, "accuracy", "mask IoU"]
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    for name, look, e in rows:
        print(f"| {name} | " + " | ".join(look.get(f, "?") for f in FACTORS) + " | "
              + " | ".join(f"{e[g]:+.1f}" for g in GROUPS) + f" | {e['accuracy']:.1f} | {e['mask_iou']:.1f} |")
    print("\nmean signed pixel error % by look (n subjects)")
    for factor in FACTORS:
        for val in sorted({r[1].get(factor, "?") for r in rows}):
            sel = [r[2] for r in rows if r[1].get(factor, "?") == val]
            print(f"| {factor}={val} ({len(sel)}) | " + " | ".join(f"{np.mean([e[g] for e in sel]):+.1f}" for g in GROUPS)
                  + f" | {np.mean([e['accuracy'] for e in sel]):.1f} | {np.mean([e['mask_iou'] for e in sel]):.1f} |")


if __name__ == "__main__":
    main()

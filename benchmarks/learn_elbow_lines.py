"""Learns bsv.frontend.elbowlines.ELBOW_RADIUS_M (how far each view's upper-arm / forearm line must move along the arm
as the elbow bends) on synthetic cohorts and evaluates it on others.

Every subject of the training cohorts (``--train-seeds``) and the evaluation cohorts (``--eval-seeds``) is captured
by the virtual rig in a room (noer) twice: with the cohort's elbows (bent 0-20 deg) and bent 20 deg more
(bsv.bodies.FLEXED_ELBOW_RANGE_DEG draws the same numbers shifted). The camera path segments both views
(bsv.bench.joints.camera_segmentations) and measures the joint centres. Per view and side, the line the view draws
(bsv.frontend.segment.elbow_line, before any move) is compared with the rig's true upper-arm / forearm boundary: the
median distance of the true boundary's pixels past the line along its normal, in mm at the elbow's depth. What the
line must move is that distance's change from the same body with the cohort's elbows to the body bent more; the
model's move per metre of radius is bsv.frontend.elbowlines.flexion_shift_mm's change between the two captures for
a radius of 1 m. ELBOW_RADIUS_M holds, per view, the least-squares slope through the origin of the first on the
second. The script prints the table and, on the evaluation cohorts, the distance's change (mm, mean and rms) left
with the lines as drawn, with the learned radii and with the shipped ones.

    .venv/bin/python benchmarks/learn_elbow_lines.py --train-seeds 0 --eval-seeds 1 --n 6

``--cache FILE`` keeps the measurements (JSON) so that a second run re-learns without MediaPipe; ``--only-measure``
fills the cache and stops (two such runs on disjoint seeds can share the two cores).
"""

from __future__ import annotations

import tempfile

import cv2
import numpy as np
from learning import learn
from tqdm import tqdm

import bsv
from bsv.bench.joints import camera_segmentations, capture_views_geometry
from bsv.frontend import segment as sg
from bsv.frontend.elbowlines import ELBOW_RADIUS_M, flexion_shift_mm
from bsv.types import SEGMENT_IDS

SIDES = (("left", "l"), ("right", "r"))


def boundary_past_line_px(seg: sg.Segmentation, truth: np.ndarray, side: str, sid: str,
                          prm: sg.SegmentParams) -> float | None:
    """The median distance (pixels, + towards the wrist) of the rig's true upper-arm / forearm boundary past the
    line :func:`bsv.frontend.segment.elbow_line` draws; None with fewer than 5 boundary pixels."""
    assert seg.pose is not None
    point, normal = sg.elbow_line(seg.pose, side, prm)
    upper, fore = truth == SEGMENT_IDS[f"upper_arm_{sid}"], truth == SEGMENT_IDS[f"forearm_{sid}"]
    near = np.roll(fore, 1, 0) | np.roll(fore, -1, 0) | np.roll(fore, 1, 1) | np.roll(fore, -1, 1)
    ys, xs = np.nonzero(upper & near)
    if len(xs) < 5 or not np.all(np.isfinite(point)):
        return None
    return float(np.median((np.column_stack([xs, ys]) - point) @ normal))


def capture(seed: int, index: int, flexed: bool) -> dict:
    """Per "view_side": [the true boundary past the line (mm at the elbow's depth), the model's shift for a 1-m
    radius (mm)] of one capture, or None where not measured."""
    s = bsv.bodies.subject(index, seed, elbow_range=bsv.bodies.FLEXED_ELBOW_RANGE_DEG if flexed
                           else bsv.bodies.ELBOW_RANGE_DEG)
    out: dict = {"elbows": [s.pose.elbow_l, s.pose.elbow_r]}
    with tempfile.TemporaryDirectory(prefix="bsv-elbow-") as tmp:
        bsv.scan(s.body.mesh(), "noer", seed * 1_000_003 + index, images=tmp, overwrite=True, room=True)
        segs, joints = camera_segmentations(tmp)
        _, cams = capture_views_geometry(tmp)
        for v, seg in segs.items():
            truth = cv2.imread(f"{tmp}/{v}/labels.png", cv2.IMREAD_UNCHANGED)
            prm = sg.drawn_params(seg)
            cam = cams[v]
            for side, sid in SIDES:
                names = (f"shoulder_{sid}", f"elbow_{sid}", f"wrist_{sid}")
                past = boundary_past_line_px(seg, truth, side, sid, prm)
                if past is None or not all(n in joints for n in names):
                    out[f"{v}_{sid}"] = None
                    continue
                sh, el, wr = (np.asarray(joints[n].xyz, dtype=np.float64) for n in names)
                depth = float((el - cam.translation) @ cam.rotation[:, 2])
                out[f"{v}_{sid}"] = [past * depth / cam.intrinsics.fx * 1000.0,  # per metre, from 1 cm: never clipped
                                     flexion_shift_mm(sh, el, wr, cam.translation, 0.01) / 0.01]
    return out


def measure(n: int, seed: int, cache: dict) -> list[tuple[str, float, float]]:
    """(view, the model's change for a 1-m radius, the change of the true boundary past the line; mm) of every
    side of the first ``n`` subjects of a cohort seed, bent more against the cohort's elbows (read from and added
    to ``cache``: key "seed/index/flexed")."""
    rows = []
    for i in tqdm(range(n), desc=f"seed {seed}", unit="subject"):
        got = {}
        for flexed in (False, True):
            key = f"{seed}/{i}/{int(flexed)}"
            if key not in cache:
                cache[key] = capture(seed, i, flexed)
            got[flexed] = cache[key]
        for v in ("front", "back"):
            for _, sid in SIDES:
                a, b = got[False].get(f"{v}_{sid}"), got[True].get(f"{v}_{sid}")
                if a is not None and b is not None:
                    rows.append((v, b[1] - a[1], b[0] - a[0]))
    return rows


def fit(rows: list[tuple[str, float, float]]) -> dict[str, float]:
    """ELBOW_RADIUS_M fitted to ``rows``: per view, the slope through the origin of the boundary's change on the
    model's, never negative (a view whose line follows the bend keeps it)."""
    out = {}
    for v in ("front", "back"):
        m = np.array([r[1] for r in rows if r[0] == v])
        d = np.array([r[2] for r in rows if r[0] == v])
        out[v] = round(max(float(m @ d / (m @ m)), 0.0), 3) if len(m) and m @ m > 0 else 0.0
    return out


def evaluate(name: str, radii: dict[str, float] | None, rows: list[tuple[str, float, float]]) -> None:
    """Prints what the lines leave of the boundary's change (mm) per view with ``radii`` (None: as drawn)."""
    for v in ("front", "back"):
        err = np.array([d - (0.0 if radii is None else radii[v] * m) for w, m, d in rows if w == v])
        if len(err):
            print(f"  {name:8s} {v:5s}: {len(err)} sides, mean {err.mean():+.2f} mm, rms {np.sqrt(np.mean(err ** 2)):.2f}")


def main() -> None:
    """Command line: measure, learn ELBOW_RADIUS_M on the training seeds, evaluate (as drawn, learned, shipped)
    on both sets."""

    def both(radii: dict[str, float], rows: list[tuple[str, float, float]]) -> None:
        evaluate("as drawn", None, rows)
        evaluate("learned", radii, rows)
        evaluate("shipped", ELBOW_RADIUS_M, rows)

    learn(__doc__, "0", "1", 6, measure, fit, "ELBOW_RADIUS_M", both)


if __name__ == "__main__":
    main()

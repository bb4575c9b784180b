"""Learns the shin / foot plane of the camera path (bsv.frontend.landmarks.ANKLE_PLANE) from the rig's true
labels.

The body's shin / foot boundary (MakeHuman's: the ankle loop of bsv.anatomy) is, on every body of the cohort,
nearly the same plane around the ankle: a loop whose centroid lies 91 +- 4 mm above the floor (the stature and
the sex together place it within 2 mm), rising towards the toes by about 13 deg. The 2-D line that cut the
camera clouds' shins from the feet (through MediaPipe's ankle, placed at a fraction of the stature) put the
cloud's shin end 10 mm (sd) off that loop, and the fitted shin's end followed it. So the camera path cuts the
shins from the feet in 3-D: a point of a leg below the plane is foot
(bsv.frontend.landmarks.cut_feet_at_ankle_plane).

For every subject of the given cohort seeds (bodies only, no rendering) and each leg, this script fits a plane
``y = h + s * (z - z_c) + t * (x - x_c)`` to the true loop's edge midpoints ((x_c, z_c) their centroid) and
records ``h``, the forward slope ``s``, the centroid's forward offset from the rig's ankle joint ``z_c -
z_ankle``, the stature and the sex score (1 - 2 x MakeHuman's gender). It prints the plane's mean and the
height's sd, and the height fitted as ``a + b x stature`` and as ``a + b x stature + c x sex`` with their
residual sd left out one seed at a time, next to the constant's. ANKLE_PLANE holds the second fit (learned on
seeds 11-18, checked on 0-7: 160 legs, the height's error sd 4.3 mm for the constant, 4.2 mm for the stature
line, 1.9 mm with the sex; round 2 session 29).

    .venv/bin/python benchmarks/learn_ankle_plane.py --seeds 11,12,13,14,15,16,17,18 --n 10
"""

from __future__ import annotations

import argparse

import numpy as np
from tqdm import tqdm

from bsv.bench.boundaries import loop_edges
from bsv.bodies import subject
from bsv.bodies.joints import rig_joints
from bsv.types import SEGMENT_IDS

#: One leg's row: seed, stature (m), the loop plane's height at its centroid (m), forward slope, lateral
#: slope, the centroid's forward offset from the rig's ankle joint (m), the ankle joint's height (m).
COLUMNS = ("seed", "stature", "height", "forward_slope", "lateral_slope", "forward_offset", "ankle_height", "sex")


def leg_plane(vertices: np.ndarray, faces: np.ndarray, face_labels: np.ndarray, side: str) -> tuple[float, float, float, np.ndarray]:
    """The true shin / foot loop of one leg fitted by a plane ``y = h + s (z - z_c) + t (x - x_c)``: (h, s, t,
    the loop's centroid (3,))."""
    sfx = "_l" if side == "l" else "_r"
    e = loop_edges(faces, face_labels, SEGMENT_IDS["shin" + sfx], SEGMENT_IDS["foot" + sfx])
    if len(e) < 3:
        raise ValueError(f"no shin / foot loop on the {side} leg")
    mid = 0.5 * (vertices[e[:, 0]] + vertices[e[:, 1]])
    length = np.linalg.norm(vertices[e[:, 0]] - vertices[e[:, 1]], axis=1)
    c = (mid * length[:, None]).sum(axis=0) / length.sum()
    a = np.column_stack([np.ones(len(mid)), mid[:, 2] - c[2], mid[:, 0] - c[0]])
    coef, *_ = np.linalg.lstsq(a * length[:, None], (mid[:, 1] - c[1]) * length, rcond=None)
    return float(c[1] + coef[0]), float(coef[1]), float(coef[2]), c


def rows_for(seeds: list[int], n: int) -> np.ndarray:
    """One row (:data:`COLUMNS`) per leg of every subject of the cohort ``seeds``."""
    out = []
    for seed in tqdm(seeds, desc="seeds"):
        for i in range(n):
            s = subject(i, seed)
            mesh = s.body.mesh()
            v = np.asarray(mesh.vertices)
            floor = float(v[:, 1].min())
            joints = rig_joints(s.phenotype, s.pose)
            for side in ("l", "r"):
                h, fwd, lat, c = leg_plane(v, np.asarray(mesh.faces), np.asarray(mesh.face_labels), side)
                ankle = np.asarray(joints[f"ankle_{side}"], dtype=np.float64)
                out.append([seed, s.body.stature, h - floor, fwd, lat, c[2] - ankle[2], ankle[1] - floor,
                            1.0 - 2.0 * s.phenotype.gender])
    return np.asarray(out)


def main() -> None:
    """Prints the plane learned on ``--seeds`` and how well stature predicts its height, seed left out."""
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seeds", default="11,12,13,14,15,16,17,18", help="cohort seeds (comma-separated)")
    ap.add_argument("--check", default="0,1,2,3,4,5,6,7", help="held-out seeds to score the learned plane on ('' = none)")
    ap.add_argument("--n", type=int, default=10, help="subjects per seed")
    a = ap.parse_args()
    train = rows_for([int(s) for s in a.seeds.split(",")], a.n)
    col = {k: i for i, k in enumerate(COLUMNS)}
    h = train[:, col["height"]]

    def design(rows: np.ndarray, sex: bool) -> np.ndarray:
        cols = [np.ones(len(rows)), rows[:, col["stature"]]] + ([rows[:, col["sex"]]] if sex else [])
        return np.column_stack(cols)

    print(f"{len(h)} legs of seeds {a.seeds}")
    print(f"  height at the loop's centroid: mean {1000 * h.mean():.1f} mm, sd {1000 * h.std():.1f} mm")
    coefs = {}
    for sex in (False, True):
        d = design(train, sex)
        coef, *_ = np.linalg.lstsq(d, h, rcond=None)
        coefs[sex] = coef
        left_out = []
        for seed in np.unique(train[:, 0]):
            keep = train[:, 0] != seed
            c, *_ = np.linalg.lstsq(d[keep], h[keep], rcond=None)
            left_out.append(h[~keep] - d[~keep] @ c)
        terms = f"{1000 * coef[0]:.1f} mm + {coef[1]:.4f} x stature" + (f" + {1000 * coef[2]:.2f} mm x sex" if sex else "")
        print(f"  height = {terms}: residual sd {1000 * np.std(h - d @ coef):.1f} mm, left out one seed at a time "
              f"{1000 * np.std(np.concatenate(left_out)):.1f} mm")
    print(f"  forward slope {train[:, col['forward_slope']].mean():.3f} (sd {train[:, col['forward_slope']].std():.3f}; "
          f"{np.degrees(np.arctan(train[:, col['forward_slope']].mean())):.1f} deg), lateral slope "
          f"{train[:, col['lateral_slope']].mean():+.3f} (sd {train[:, col['lateral_slope']].std():.3f})")
    print(f"  centroid forward of the rig's ankle joint: {1000 * train[:, col['forward_offset']].mean():.1f} mm "
          f"(sd {1000 * train[:, col['forward_offset']].std():.1f}); ankle joint height "
          f"{1000 * train[:, col['ankle_height']].mean():.1f} mm (sd {1000 * train[:, col['ankle_height']].std():.1f})")
    if a.check:
        held = rows_for([int(s) for s in a.check.split(",")], a.n)
        hh = held[:, col["height"]]
        const = hh - h.mean()
        lin = hh - design(held, False) @ coefs[False]
        both = hh - design(held, True) @ coefs[True]
        print(f"held out, {len(hh)} legs of seeds {a.check}: the constant's error mean {1000 * const.mean():+.1f} sd "
              f"{1000 * const.std():.1f} mm; the stature line's mean {1000 * lin.mean():+.1f} sd {1000 * lin.std():.1f} mm; "
              f"stature and sex: mean {1000 * both.mean():+.1f} sd {1000 * both.std():.1f} mm")

if __name__ == "__main__":
    main()

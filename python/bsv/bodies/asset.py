"""Loading the vendored MakeHuman asset (``assets/makehuman/body.npz``, CC0) built by scripts/make_assets.py."""

from __future__ import annotations

import os
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from ..errors import AssetError


def asset_path() -> Path:
    """Where body.npz is: $BSV_MAKEHUMAN_NPZ, else the package data dir, else the repository's assets/."""
    env = os.environ.get("BSV_MAKEHUMAN_NPZ")
    if env:
        return Path(env)
    here = Path(__file__).resolve()
    candidates = [here.parent.parent / "data" / "makehuman" / "body.npz",
                  here.parents[3] / "assets" / "makehuman" / "body.npz"]
    for c in candidates:
        if c.is_file():
            return c
    return candidates[-1]


@dataclass(frozen=True)
class Asset:
    """The arrays of body.npz (metres, BSV world frame) plus name lookups."""

    vertices: np.ndarray          # (13380, 3) float64 rest body, base phenotype
    faces: np.ndarray             # (26756, 3) int64 outward triangles
    bone_names: tuple[str, ...]   # 163 bones of the MakeHuman default rig
    bone_parent: np.ndarray       # (163,) parent index, -1 for root
    joints_rest: np.ndarray       # (163, 2, 3) head/tail of each bone, base phenotype
    skin_vertex: np.ndarray       # sparse skinning weights: vertex index
    skin_bone: np.ndarray         # bone index
    skin_weight: np.ndarray       # weight (sums to 1 per vertex)
    target_names: tuple[str, ...]
    target_offsets: np.ndarray
    target_indices: np.ndarray
    target_deltas: np.ndarray     # float64 metres
    target_joint_deltas: np.ndarray  # (n_targets, 163, 2, 3)

    def target_id(self, name: str) -> int:
        """Index of a target by its path under targets/ (e.g. 'macrodetails/universal-male-young-...')."""
        try:
            return self._ids[name]  # type: ignore[attr-defined]
        except KeyError:
            raise AssetError(f"target {name!r} is not in {asset_path()}; rebuild it with "
                             "scripts/make_assets.py if the list changed") from None

    def bone(self, name: str) -> int:
        """Index of a rig bone by name (e.g. 'upperarm01.L')."""
        return self._bones[name]  # type: ignore[attr-defined]


@lru_cache(maxsize=2)
def load_asset(path: str | None = None) -> Asset:
    """Load body.npz once (cached). Raises AssetError naming the file if it is missing or incomplete."""
    p = Path(path) if path else asset_path()
    if not p.is_file():
        raise AssetError(f"{p}: MakeHuman asset not found; run `python scripts/make_assets.py` "
                         "or set BSV_MAKEHUMAN_NPZ")
    try:
        with np.load(p, allow_pickle=False) as d:
            a = Asset(
                vertices=d["vertices"].astype(np.float64),
                faces=d["faces"].astype(np.int64),
                bone_names=tuple(str(s) for s in d["bone_names"]),
                bone_parent=d["bone_parent"].astype(np.int64),
                joints_rest=d["joints_rest"].astype(np.float64),
                skin_vertex=d["skin_vertex"].astype(np.int64),
                skin_bone=d["skin_bone"].astype(np.int64),
                skin_weight=d["skin_weight"].astype(np.float64),
                target_names=tuple(str(s) for s in d["target_names"]),
                target_offsets=d["target_offsets"].astype(np.int64),
                target_indices=d["target_indices"].astype(np.int64),
                target_deltas=d["target_deltas"].astype(np.float64),
                target_joint_deltas=d["target_joint_deltas"].astype(np.float64),
            )
    except (KeyError, ValueError, OSError) as e:
        raise AssetError(f"{p}: not a valid MakeHuman asset ({e}); regenerate it with "
                         "scripts/make_assets.py") from e
    return _with_lookups(a)


def _with_lookups(a: Asset) -> Asset:
    """``a`` with its name lookups (targets, bones) attached."""
    object.__setattr__(a, "_ids", {n: i for i, n in enumerate(a.target_names)})
    object.__setattr__(a, "_bones", {n: i for i, n in enumerate(a.bone_names)})
    return a


def rig_asset(vertices: np.ndarray, faces: np.ndarray, bone_names: tuple[str, ...], bone_parent: np.ndarray,
              joints_rest: np.ndarray, skin_vertex: np.ndarray, skin_bone: np.ndarray, skin_weight: np.ndarray) -> Asset:
    """An :class:`Asset` of one rest body and its rig, without shape targets: enough to pose that body
    (:func:`bsv.bodies.pose.pose_vertices`), as :mod:`bsv.posed_template` does with the templates' rig."""
    no_targets = np.zeros((0, 3), dtype=np.float64)
    return _with_lookups(Asset(
        vertices=np.asarray(vertices, dtype=np.float64), faces=np.asarray(faces, dtype=np.int64),
        bone_names=tuple(bone_names), bone_parent=np.asarray(bone_parent, dtype=np.int64),
        joints_rest=np.asarray(joints_rest, dtype=np.float64), skin_vertex=np.asarray(skin_vertex, dtype=np.int64),
        skin_bone=np.asarray(skin_bone, dtype=np.int64), skin_weight=np.asarray(skin_weight, dtype=np.float64),
        target_names=(), target_offsets=np.zeros(1, dtype=np.int64), target_indices=np.zeros(0, dtype=np.int64),
        target_deltas=no_targets, target_joint_deltas=np.zeros((0, len(bone_names), 2, 3))))

"""The calibration error floor: what a perfect registration of a miscalibrated cloud would measure.

A calibration error moves everything one camera sees by that camera's rigid error
``T_c = E_est o E_true^-1`` (world frame). The floor mesh is the true mesh with every vertex moved by
the error of the camera that sees it: vertex weights come from the (area-weighted) vertex normal's
component toward each camera, ``s = n . d_c`` (``d_c`` = unit vector from the subject toward camera c,
minus its optical axis), passed through a smoothstep over ``[-band, band]`` and normalised, so a
vertex facing the front camera follows the front error, one facing the back camera the back error,
and the lateral band that neither sees (|n_z| < band for the paper's rig) blends the two smoothly.
Its segment volumes, measured with :func:`bsv.volumes` exactly like an estimate, give the floor.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .. import _bsv
from .. import volumes as _volumes
from ..errors import FloorError
from ..types import Mesh

#: Half-width of the blending band in n . d (0.3: the blend spans normals within ~17 deg of lateral).
DEFAULT_BAND: float = 0.3



@dataclass(frozen=True)
class CameraPose:
    """One camera of a virtual capture: true and estimated camera-to-world (R, t), metres."""

    name: str
    true_rotation: np.ndarray
    true_translation: np.ndarray
    est_rotation: np.ndarray
    est_translation: np.ndarray

    @property
    def toward_camera(self) -> np.ndarray:
        """Unit world direction from the scene toward the camera (minus its optical axis)."""
        return -self.true_rotation[:, 2]

    def error_transform(self) -> tuple[np.ndarray, np.ndarray]:
        """World-frame rigid map (R, t) that the calibration error applies to what this camera sees."""
        r = self.est_rotation @ self.true_rotation.T
        return r, self.est_translation - r @ self.true_translation

    def apply_error(self, points: np.ndarray) -> np.ndarray:
        """Points as this miscalibrated camera would report them."""
        r, t = self.error_transform()
        return points @ r.T + t


def _extrinsics(doc: Mapping[str, Any], key: str, where: Path) -> tuple[np.ndarray, np.ndarray]:
    try:
        e = doc[key]
        r = np.asarray(e["rotation"], dtype=np.float64)
        t = np.asarray(e["translation"], dtype=np.float64)
    except (KeyError, TypeError) as exc:
        raise FloorError(f"{where}: no '{key}' with rotation and translation ({exc}); "
                         "write the capture with bsv.scan(..., images=DIR)") from exc
    if r.shape != (3, 3) or t.shape != (3,) or not (np.isfinite(r).all() and np.isfinite(t).all()):
        raise FloorError(f"{where}: '{key}' must hold a finite 3x3 rotation and a 3-vector translation")
    return r, t


def read_camera_poses(capture_dir: str | Path) -> list[CameraPose]:
    """Per-camera true and estimated extrinsics from a virtual capture (``<camera>/camera.json``)."""
    d = Path(capture_dir)
    files = sorted(d.glob("*/camera.json"))
    if not files:
        raise FloorError(f"{d}: no <camera>/camera.json; write the capture with bsv.scan(..., images=DIR)")
    cams = []
    for f in files:
        try:
            doc = json.loads(f.read_text())
        except (OSError, json.JSONDecodeError) as exc:
            raise FloorError(f"{f}: cannot read camera JSON ({exc})") from exc
        rt, tt = _extrinsics(doc, "true_camera_to_world", f)
        re, te = _extrinsics(doc, "camera_to_world", f)
        cams.append(CameraPose(str(doc.get("name", f.parent.name)), rt, tt, re, te))
    return cams


def vertex_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Area-weighted unit vertex normals (Rust's ``bsv_core::geometry::vertex_normals``)."""
    return _bsv.vertex_normals(vertices, faces)


def _smoothstep(x: np.ndarray) -> np.ndarray:
    x = np.clip(x, 0.0, 1.0)
    return x * x * (3.0 - 2.0 * x)


def camera_weights(normals: np.ndarray, cameras: list[CameraPose], band: float = DEFAULT_BAND) -> np.ndarray:
    """(N, C) weights summing to 1: how much each camera's error moves each vertex."""
    if not cameras:
        raise FloorError("no camera given")
    if not band > 0:
        raise FloorError(f"blending band {band}: must be > 0")
    facing = np.stack([normals @ c.toward_camera for c in cameras], axis=1)
    w = _smoothstep((facing + band) / (2.0 * band))
    total = w.sum(axis=1, keepdims=True)
    return np.where(total > 0, w / np.where(total > 0, total, 1.0), 1.0 / len(cameras))


def floor_mesh(mesh: Mesh, cameras: list[CameraPose], band: float = DEFAULT_BAND) -> Mesh:
    """The true mesh with each part moved by the error of the camera that sees it (labels kept)."""
    w = camera_weights(vertex_normals(mesh.vertices, mesh.faces), cameras, band)
    moved = sum(w[:, [k]] * c.apply_error(mesh.vertices) for k, c in enumerate(cameras))
    return Mesh(np.asarray(moved), mesh.faces, mesh.vertex_labels, mesh.face_labels)


def floor_volumes(mesh: Mesh, cameras: list[CameraPose], band: float = DEFAULT_BAND) -> dict[str, float]:
    """Segment and aggregate volumes (litres) of the floor mesh, measured with :func:`bsv.volumes`."""
    return dict(_volumes(floor_mesh(mesh, cameras, band))["volumes_l"])

"""Plain numpy containers for meshes and point clouds, and the segment table of DESIGN.md."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Optional

import numpy as np
import numpy.typing as npt

#: Segment id -> canonical name (DESIGN.md "Conventions").
SEGMENT_NAMES: dict[int, str] = {
    0: "unlabelled",
    1: "head",
    2: "torso",
    3: "upper_arm_l",
    4: "upper_arm_r",
    5: "forearm_l",
    6: "forearm_r",
    7: "hand_l",
    8: "hand_r",
    9: "thigh_l",
    10: "thigh_r",
    11: "shin_l",
    12: "shin_r",
    13: "foot_l",
    14: "foot_r",
}
#: Canonical name -> segment id.
SEGMENT_IDS: dict[str, int] = {v: k for k, v in SEGMENT_NAMES.items()}
#: The nine segments of ``trunk_limbs``.
TRUNK_LIMBS: tuple[str, ...] = (
    "torso", "upper_arm_l", "upper_arm_r", "forearm_l", "forearm_r",
    "thigh_l", "thigh_r", "shin_l", "shin_r",
)

def checked_labels(labels: object, what: str) -> npt.NDArray[np.uint8]:
    """``labels`` as contiguous uint8 segment ids, refusing values outside 0..14 before any cast
    (so that 270 is an error, not a silently wrapped 14)."""
    from ._bsv import InputError

    arr = np.asarray(labels)
    if arr.ndim != 1:
        raise InputError(f"{what} must be a 1-D array of segment ids, got shape {arr.shape}")
    if arr.size:
        if not np.issubdtype(arr.dtype, np.integer):
            if not np.all(np.isfinite(arr)) or not np.all(arr == np.round(arr)):
                raise InputError(f"{what} must hold whole segment ids 0..14, got {arr.dtype} values")
        lo, hi = arr.min(), arr.max()
        if lo < 0 or hi > 14:
            raise InputError(f"{what} must be segment ids 0..14, got values in [{lo}, {hi}]")
    return np.ascontiguousarray(arr, dtype=np.uint8)


def checked_points(points: object, what: str) -> npt.NDArray[np.float64]:
    """``points`` as a contiguous (N, 3) float64 array, or an InputError naming the shape."""
    from ._bsv import InputError

    arr = np.asarray(points, dtype=np.float64)
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise InputError(f"{what} must have shape (N, 3) (x, y, z in metres), got {arr.shape}")
    return np.ascontiguousarray(arr)


FloatArray = npt.NDArray[np.float64]
IndexArray = npt.NDArray[np.int64]
LabelArray = npt.NDArray[np.uint8]


@dataclass
class Mesh:
    """A triangle mesh in metres: ``vertices`` (N, 3) float64, ``faces`` (M, 3) int64, optional uint8 labels."""

    vertices: FloatArray
    faces: IndexArray
    vertex_labels: Optional[LabelArray] = None
    face_labels: Optional[LabelArray] = None

    def __post_init__(self) -> None:
        from ._bsv import InputError

        self.vertices = checked_points(self.vertices, "vertices")
        faces = np.asarray(self.faces)
        if faces.ndim != 2 or faces.shape[1] != 3 or (faces.size and not np.issubdtype(faces.dtype, np.integer)):
            raise InputError(f"faces must be an (M, 3) integer array of vertex indices, got {faces.dtype} {faces.shape}")
        self.faces = np.ascontiguousarray(faces, dtype=np.int64)
        if self.vertex_labels is not None:
            self.vertex_labels = checked_labels(self.vertex_labels, "vertex_labels")
        if self.face_labels is not None:
            self.face_labels = checked_labels(self.face_labels, "face_labels")

    def to_trimesh(self):  # type: ignore[no-untyped-def]
        """A ``trimesh.Trimesh`` of this mesh (requires trimesh)."""
        import trimesh

        return trimesh.Trimesh(self.vertices, self.faces, process=False)


@dataclass
class PointCloud:
    """A point cloud in metres: ``points`` (N, 3) float64 with optional normals, uint8 colours and labels."""

    points: FloatArray
    normals: Optional[FloatArray] = None
    colors: Optional[npt.NDArray[np.uint8]] = None
    labels: Optional[LabelArray] = None

    def __post_init__(self) -> None:
        self.points = checked_points(self.points, "points")
        if self.normals is not None:
            self.normals = checked_points(self.normals, "normals")
        if self.colors is not None:
            self.colors = np.ascontiguousarray(self.colors, dtype=np.uint8)
        if self.labels is not None:
            self.labels = checked_labels(self.labels, "labels")

    def __len__(self) -> int:
        return int(self.points.shape[0])


@dataclass
class Registration:
    """The result of :func:`bsv.register`: the fitted mesh, its volumes and the per-iteration log."""

    mesh: Mesh
    volumes: dict
    log: list[dict] = field(default_factory=list)
    seconds: float = 0.0

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
        self.vertices = np.ascontiguousarray(self.vertices, dtype=np.float64)
        self.faces = np.ascontiguousarray(self.faces, dtype=np.int64)
        if self.vertex_labels is not None:
            self.vertex_labels = np.ascontiguousarray(self.vertex_labels, dtype=np.uint8)
        if self.face_labels is not None:
            self.face_labels = np.ascontiguousarray(self.face_labels, dtype=np.uint8)

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
        self.points = np.ascontiguousarray(self.points, dtype=np.float64)
        if self.normals is not None:
            self.normals = np.ascontiguousarray(self.normals, dtype=np.float64)
        if self.colors is not None:
            self.colors = np.ascontiguousarray(self.colors, dtype=np.uint8)
        if self.labels is not None:
            self.labels = np.ascontiguousarray(self.labels, dtype=np.uint8)

    def __len__(self) -> int:
        return int(self.points.shape[0])


@dataclass
class Registration:
    """The result of :func:`bsv.register`: the fitted mesh, its volumes and the per-iteration log."""

    mesh: Mesh
    volumes: dict
    log: list[dict] = field(default_factory=list)
    seconds: float = 0.0

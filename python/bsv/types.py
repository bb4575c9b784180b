"""Plain numpy containers for meshes and point clouds, and the segment table of DESIGN.md.

The containers hold arrays as given (``numpy.asarray``); the extension checks them (shapes, dtypes,
index ranges, segment ids: one validation layer, ``bsv._bsv`` convert.rs) when they are used, and
raises :class:`bsv.InputError` naming the argument."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt

from . import _bsv

#: Segment id -> canonical name (the table of ``bsv_core::Segment``, exported by the extension).
SEGMENT_NAMES: dict[int, str] = dict(enumerate(_bsv.SEGMENT_NAMES))
#: Canonical name -> segment id.
SEGMENT_IDS: dict[str, int] = {v: k for k, v in SEGMENT_NAMES.items()}
#: The nine segments of ``trunk_limbs``.
TRUNK_LIMBS: tuple[str, ...] = tuple(SEGMENT_NAMES[i] for i in _bsv.TRUNK_LIMBS)
#: Head, hands and feet (dropped before a registration, not measured).
EXTREMITIES: tuple[str, ...] = tuple(SEGMENT_NAMES[i] for i in _bsv.EXTREMITIES)
#: Palette colour (sRGB) per segment id, what the Rust writers put in PLY files: (15, 3) uint8.
PALETTE: npt.NDArray[np.uint8] = np.array(_bsv.PALETTE, dtype=np.uint8)
#: A subject's sex as the sexed templates (:func:`bsv.default_template`) and de Leva's inertial parameters
#: (:mod:`bsv.biomech`) take it.
SEXES: tuple[str, ...] = ("male", "female")


FloatArray = npt.NDArray[np.float64]
IndexArray = npt.NDArray[np.int64]
LabelArray = npt.NDArray[np.uint8]


def _segments_text(labels: Any) -> str:
    """", 9 segments" for labels, "" without."""
    if labels is None:
        return ""
    ids = {int(i) for i in np.unique(np.asarray(labels))} - {0}
    return f", {len(ids)} segments"


@dataclass(repr=False)
class Mesh:
    """A triangle mesh in metres: ``vertices`` (N, 3) float64, ``faces`` (M, 3) int64, optional uint8 labels
    and optional (N, 3) uint8 sRGB vertex colours (what the object it came from carried)."""

    vertices: FloatArray
    faces: IndexArray
    vertex_labels: LabelArray | None = None
    face_labels: LabelArray | None = None
    vertex_colors: npt.NDArray[np.uint8] | None = None

    def __post_init__(self) -> None:
        self.vertices = np.asarray(self.vertices)
        self.faces = np.asarray(self.faces)
        if self.vertex_labels is not None:
            self.vertex_labels = np.asarray(self.vertex_labels)
        if self.face_labels is not None:
            self.face_labels = np.asarray(self.face_labels)
        if self.vertex_colors is not None:
            self.vertex_colors = np.asarray(self.vertex_colors)

    def __repr__(self) -> str:
        labels = self.vertex_labels if self.vertex_labels is not None else self.face_labels
        return f"Mesh({len(self.vertices)} vertices, {len(self.faces)} faces{_segments_text(labels)})"

    def to_trimesh(self) -> Any:
        """A ``trimesh.Trimesh`` (vertex order kept) with the labels as ``vertex_attributes["label"]`` /
        ``face_attributes["label"]`` and vertex colours (own, else the segment palette). Needs the
        ``interop`` extra."""
        from .interop import mesh_to_trimesh

        return mesh_to_trimesh(self)

    def to_open3d(self, legacy: bool = False) -> Any:
        """An Open3D tensor ``TriangleMesh`` with ``vertex.label`` / ``triangle.label`` and colours, or with
        ``legacy=True`` an ``open3d.geometry.TriangleMesh`` (no labels). Needs the ``interop`` extra."""
        from .interop import mesh_to_open3d

        return mesh_to_open3d(self, legacy)


@dataclass(repr=False)
class PointCloud:
    """A point cloud in metres: ``points`` (N, 3) float64 with optional normals, uint8 colours and labels."""

    points: FloatArray
    normals: FloatArray | None = None
    colors: npt.NDArray[np.uint8] | None = None
    labels: LabelArray | None = None

    def __post_init__(self) -> None:
        self.points = np.asarray(self.points)
        if self.normals is not None:
            self.normals = np.asarray(self.normals)
        if self.colors is not None:
            self.colors = np.asarray(self.colors)
        if self.labels is not None:
            self.labels = np.asarray(self.labels)

    def __len__(self) -> int:
        return int(self.points.shape[0])

    def __repr__(self) -> str:
        extra = [name for name in ("normals", "colors") if getattr(self, name) is not None]
        return (f"PointCloud({len(self)} points{_segments_text(self.labels)}"
                f"{''.join(', ' + e for e in extra)})")

    def to_trimesh(self) -> Any:
        """A ``trimesh.PointCloud`` with colours (own, else the segment palette) and ``metadata["label"]``,
        ``metadata["normals"]``. Needs the ``interop`` extra."""
        from .interop import cloud_to_trimesh

        return cloud_to_trimesh(self)

    def to_open3d(self, legacy: bool = False) -> Any:
        """An Open3D tensor ``PointCloud`` with ``point.normals`` / ``colors`` / ``label``, or with
        ``legacy=True`` an ``open3d.geometry.PointCloud`` (no labels). Needs the ``interop`` extra."""
        from .interop import cloud_to_open3d

        return cloud_to_open3d(self, legacy)


@dataclass(frozen=True)
class SegmentQuality:
    """How well one segment was fitted (``bsv_register::SegmentQuality``, rule in ``quality.rs``):
    ``rms_mm`` RMS distance to the cloud of the vertices not in a lateral gap and within 30 mm of it, ``coverage`` fraction of
    vertices with a cloud point within 10 mm, ``gap_fraction`` fraction in the lateral gaps,
    ``exposed_uncovered`` fraction facing a camera yet far from the cloud, ``folded`` fraction on a fold
    (the fit turned over itself where the template is smooth; NaN in results written before it was
    measured), ``doubtful`` the flag."""

    vertices: int
    rms_mm: float
    coverage: float
    gap_fraction: float
    exposed_uncovered: float
    doubtful: bool
    folded: float = math.nan


@dataclass(repr=False)
class Registration:
    """The result of :func:`bsv.register`: the fitted mesh, its volumes (the report dict with
    ``volumes["registration"]``, the summary), the per-iteration log, the parameters used and the
    typed volume report."""

    mesh: Mesh
    volumes: dict[str, Any]
    log: list[dict[str, Any]] = field(default_factory=list)
    seconds: float = 0.0
    params: _bsv.RegisterParams | None = None
    report: _bsv.VolumeReport | None = None

    @property
    def summary(self) -> dict[str, Any]:
        """The registration summary (``volumes["registration"]``)."""
        summary: dict[str, Any] = self.volumes.get("registration") or {}
        return summary

    @property
    def quality(self) -> dict[str, SegmentQuality]:
        """Per-segment quality figures of the fit (``summary["quality"]``), by segment name."""
        raw: dict[str, dict[str, Any]] = self.summary.get("quality") or {}
        return {name: SegmentQuality(**q) for name, q in raw.items()}

    def __repr__(self) -> str:
        s = self.summary
        rms = s.get("rms_mesh_to_points_mm", float("nan"))
        whole = self.volumes.get("volumes_l", {}).get("trunk_limbs")
        vol = "" if whole is None else f", trunk_limbs={whole:.3f} L"
        return (f"Registration({len(self.mesh.vertices)} vertices, {len(self.log)} iterations, "
                f"rms_mesh_to_points_mm={rms:.2f}{vol}, {self.seconds:.2f} s)")

    def _repr_html_(self) -> str:
        """Notebook display: a small table of the volumes and the fit, and a thumbnail of the segmented body."""
        from .display import registration_html

        return registration_html(self)

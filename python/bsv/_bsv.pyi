# Type stubs of the Rust extension ``bsv._bsv`` (thin: Python arrays <-> core types, one validation
# layer; Rust errors -> the classes of :mod:`bsv.errors`). Kept in sync with the extension by
# tests/python/test_stubs.py (every name, every function's parameters and defaults).

from collections.abc import Callable, Sequence
from typing import Any, TypeAlias

import numpy as np
import numpy.typing as npt

F64: TypeAlias = npt.NDArray[np.float64]
I64: TypeAlias = npt.NDArray[np.int64]
U8: TypeAlias = npt.NDArray[np.uint8]
MeshTuple: TypeAlias = tuple[F64, I64, U8 | None, U8 | None]
CloudTuple: TypeAlias = tuple[F64, F64 | None, U8 | None, U8 | None]
#: Any array-like the extension converts (numpy array of any numeric dtype, nested lists).
ArrayLike: TypeAlias = Any

__version__: str
#: Segment name by id (0 = "unlabelled"), from ``bsv_core::Segment``.
SEGMENT_NAMES: tuple[str, ...]
#: Palette colour (r, g, b) by segment id.
PALETTE: tuple[tuple[int, int, int], ...]
#: Ids of the nine trunk-and-limb segments.
TRUNK_LIMBS: tuple[int, ...]
#: Ids of head, hands and feet.
EXTREMITIES: tuple[int, ...]
#: Aggregate name -> member segment ids (empty for "whole": every segment present).
AGGREGATES: dict[str, tuple[int, ...]]
#: Names of the 6 extrinsic parameters of a covariance, from ``bsv_capture::scanner::COVARIANCE_PARAMETERS``.
COVARIANCE_PARAMETERS: tuple[str, ...]
#: Their parameterisation, from ``bsv_capture::scanner::COVARIANCE_FRAME``.
COVARIANCE_FRAME: str
#: Camera name -> the paper's calibration repeatability (6 standard deviations, metres and radians): the
#: virtual rig's calibration sigmas (``bsv_capture::scanner::Rig::paper_default``).
PAPER_CALIBRATION_STD: dict[str, tuple[float, ...]]
#: The limits beyond which a fitted segment is doubtful (``bsv_register::DOUBT_*``): ``rms_mm`` (above),
#: ``exposed_uncovered`` (above), ``coverage`` (below), ``folded`` (above).
QUALITY_LIMITS: dict[str, float]

class RegisterParams:
    # Registration parameters (``bsv_register::RegisterParams``); unknown names, wrong types and
    # out-of-range values raise ``RegistrationParameterError`` naming the parameter.
    # Room outliers (floor/wall spill labelled like a limb, mixed pixels): ``detached_voxel_m``
    # (float, default 0.015; 0 = off) and ``detached_min_fraction`` (float in [0, 1], default 0.25)
    # drop the detached pieces of a segment; ``bbox_max_outlier_distance_m`` (float > 0, default
    # 0.3; inf = off) leaves far sparse points out of the pre-alignment box.
    # ``check_plausible`` (bool, default True): with a labelled human template, refuse a cloud that is
    # not a standing person in the world frame (``ImplausibleCloudError``).

    def __init__(self, **kwargs: Any) -> None: ...
    def to_dict(self) -> dict[str, Any]: ...
    def __getattr__(self, name: str) -> Any: ...

class VolumeReport:
    # The volumes report (DESIGN.md "Formats"); ``to_dict()`` is what ``bsv.volumes`` returns.

    def to_dict(self) -> dict[str, Any]: ...
    def __getitem__(self, key: str) -> Any: ...
    @property
    def volumes_l(self) -> dict[str, float]: ...
    @property
    def ratios(self) -> dict[str, float]: ...
    @property
    def mass_kg(self) -> float: ...
    @property
    def density_kg_m3(self) -> float: ...
    @property
    def notes(self) -> list[str]: ...

class PreparedVolumes:
    # A labelled closed mesh prepared once for re-measuring at many vertex positions
    # (``bsv_volume::PreparedSegments``): the arguments of ``volumes``; validation, labels, island
    # merging (on these vertices) and the caps between segments are fixed, only positions change.
    # Raises ``VolumeError`` / ``InputError`` as ``volumes`` does on the same mesh.
    # ``n_vertices``: the vertex count every call must pass; ``density_kg_m3``: the reports' density.
    # ``volume_report(vertices)``: the report ``volumes`` gives on the mesh with its (N, 3) vertices at
    # ``vertices``.
    # ``quantities(vertices)``: for each quantity of the reports (``VolumeReport::quantities``: the finite
    # entries of ``volumes_l`` then ``ratios``; first-seen order), an (S,) array over the S vertex arrays
    # of ``vertices`` ((S, N, 3), N = ``n_vertices``): the values ``bsv.uncertainty.quantities(volumes(moved
    # mesh))`` gives, NaN where a draw has none; copied, then evaluated in parallel with the GIL released.
    # A wrong N is a ``VolumeError`` (also for S = 0), a wrong shape an ``InputError``.

    def __init__(
        self,
        vertices: ArrayLike,
        faces: ArrayLike,
        vertex_labels: ArrayLike | None = None,
        face_labels: ArrayLike | None = None,
        labels: ArrayLike | None = None,
        density: float = 1000.0,
        close_holes: bool = False,
        islands: bool = False,
    ) -> None: ...
    @property
    def n_vertices(self) -> int: ...
    @property
    def density_kg_m3(self) -> float: ...
    def volume_report(self, vertices: ArrayLike) -> VolumeReport: ...
    def quantities(self, vertices: ArrayLike) -> dict[str, F64]: ...

class RegistrationResult:
    # What ``register`` returns: fitted vertices and labels (faces: the template's), the volume
    # report of the fitted mesh, the summary, the per-iteration log and the parameters used.

    @property
    def vertices(self) -> F64: ...
    @property
    def vertex_labels(self) -> U8 | None: ...
    @property
    def report(self) -> VolumeReport: ...
    @property
    def summary(self) -> dict[str, Any]: ...
    @property
    def log(self) -> list[dict[str, Any]]: ...
    @property
    def params(self) -> RegisterParams: ...
    @property
    def seconds(self) -> float: ...

def read_mesh(path: str) -> MeshTuple: ...
def read_point_cloud(path: str) -> CloudTuple: ...
def write_mesh(
    path: str,
    vertices: ArrayLike,
    faces: ArrayLike,
    vertex_labels: ArrayLike | None = None,
    face_labels: ArrayLike | None = None,
    ascii: bool = False,
) -> None: ...
def write_point_cloud(
    path: str,
    points: ArrayLike,
    normals: ArrayLike | None = None,
    colors: ArrayLike | None = None,
    labels: ArrayLike | None = None,
    ascii: bool = False,
) -> None: ...
def check_mesh(vertices: ArrayLike, faces: ArrayLike) -> dict[str, Any]: ...
def volumes(
    vertices: ArrayLike,
    faces: ArrayLike,
    vertex_labels: ArrayLike | None = None,
    face_labels: ArrayLike | None = None,
    labels: ArrayLike | None = None,
    density: float = 1000.0,
    close_holes: bool = False,
    islands: bool = False,
) -> VolumeReport: ...
def mass_properties(
    vertices: ArrayLike,
    faces: ArrayLike,
    vertex_labels: ArrayLike | None = None,
    face_labels: ArrayLike | None = None,
    close_holes: bool = False,
    islands: bool = False,
) -> dict[str, Any]: ...
def default_template(full: bool = False, kind: str | None = None) -> MeshTuple: ...
def register(
    template_vertices: ArrayLike,
    template_faces: ArrayLike,
    template_vertex_labels: ArrayLike | None,
    template_face_labels: ArrayLike | None,
    points: ArrayLike,
    normals: ArrayLike | None,
    labels: ArrayLike | None,
    params: RegisterParams,
    density: float = 1000.0,
    progress: Callable[[dict[str, Any]], object] | None = None,
    keypoints: Sequence[tuple[str, Sequence[float], float, Sequence[float] | None]] | None = None,
    joint_rings: Sequence[tuple[str, Sequence[int], Sequence[float]]] | None = None,
) -> RegistrationResult: ...
def template_joints(kind: str) -> list[tuple[str, list[int], list[float], tuple[float, float, float]]]: ...
def scan(
    vertices: ArrayLike,
    faces: ArrayLike,
    vertex_labels: ArrayLike | None = None,
    face_labels: ArrayLike | None = None,
    condition: str = "noer",
    seed: int = 0,
    images_dir: str | None = None,
    room: bool | dict[str, Any] | None = None,
    look: dict[str, Any] | None = None,
) -> CloudTuple: ...
def surface_distances(points: ArrayLike, vertices: ArrayLike, faces: ArrayLike) -> F64: ...
def surface_nearest(points: ArrayLike, vertices: ArrayLike, faces: ArrayLike) -> tuple[F64, npt.NDArray[np.uint32]]: ...
def nearest_segment_distances(points: ArrayLike, segments: ArrayLike) -> F64: ...
def face_labels_from_vertices(faces: ArrayLike, vertex_labels: ArrayLike) -> U8: ...
def vertex_labels_from_faces(n_vertices: int, faces: ArrayLike, face_labels: ArrayLike) -> U8: ...
def vertex_normals(vertices: ArrayLike, faces: ArrayLike) -> F64: ...
def build_cloud(
    views: list[dict[str, Any]], params: dict[str, Any] | None = None
) -> tuple[F64, F64 | None, U8 | None, U8 | None, dict[str, Any]]:
    # Merged labelled world cloud from per-camera dicts {name, intrinsics (dict), camera_to_world
    # {rotation, translation}, depth (H, W) uint16 + depth_scale or float32 metres, labels (H, W) uint8,
    # colors (H, W, 3) uint8 optional} and ``FuseParams`` keywords: (points, normals, colors, labels, report).
    # Only the person is kept (remove_floor, isolate_person: on by default); the report dict holds per view
    # ``floor`` (the calibration check), ``cleaning`` (points removed), ``warnings``, and in total
    # ``floor_agreement`` and ``warnings``. Raises PersonIsolationError when the person cannot be isolated.
    ...

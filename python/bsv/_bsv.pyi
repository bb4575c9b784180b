"""Type stubs of the Rust extension ``bsv._bsv`` (thin: Python arrays <-> core types, one validation
layer; Rust errors -> the classes of :mod:`bsv.errors`). Kept in sync with the extension by
tests/python/test_stubs.py (every name, every function's parameters and defaults)."""

from typing import Any, Callable, Optional

import numpy as np
import numpy.typing as npt

F64 = npt.NDArray[np.float64]
I64 = npt.NDArray[np.int64]
U8 = npt.NDArray[np.uint8]
MeshTuple = tuple[F64, I64, Optional[U8], Optional[U8]]
CloudTuple = tuple[F64, Optional[F64], Optional[U8], Optional[U8]]
#: Any array-like the extension converts (numpy array of any numeric dtype, nested lists).
ArrayLike = Any

__version__: str
#: Segment name by id (0 = "unlabelled"), from ``bsv_core::Segment``.
SEGMENT_NAMES: tuple[str, ...]
#: Palette colour (r, g, b) by segment id.
PALETTE: tuple[tuple[int, int, int], ...]
#: Ids of the nine trunk-and-limb segments.
TRUNK_LIMBS: tuple[int, ...]
#: Ids of head, hands and feet.
EXTREMITIES: tuple[int, ...]

class RegisterParams:
    """Registration parameters (``bsv_register::RegisterParams``); unknown names, wrong types and
    out-of-range values raise ``RegistrationParameterError`` naming the parameter."""

    def __init__(self, **kwargs: Any) -> None: ...
    def to_dict(self) -> dict[str, Any]: ...
    def __getattr__(self, name: str) -> Any: ...

class VolumeReport:
    """The volumes report (DESIGN.md "Formats"); ``to_dict()`` is what ``bsv.volumes`` returns."""

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

class RegistrationResult:
    """What ``register`` returns: fitted vertices and labels (faces: the template's), the volume
    report of the fitted mesh, the summary, the per-iteration log and the parameters used."""

    @property
    def vertices(self) -> F64: ...
    @property
    def vertex_labels(self) -> Optional[U8]: ...
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
    vertex_labels: Optional[ArrayLike] = None,
    face_labels: Optional[ArrayLike] = None,
    ascii: bool = False,
) -> None: ...
def write_point_cloud(
    path: str,
    points: ArrayLike,
    normals: Optional[ArrayLike] = None,
    colors: Optional[ArrayLike] = None,
    labels: Optional[ArrayLike] = None,
    ascii: bool = False,
) -> None: ...
def check_mesh(vertices: ArrayLike, faces: ArrayLike) -> dict[str, Any]: ...
def volumes(
    vertices: ArrayLike,
    faces: ArrayLike,
    vertex_labels: Optional[ArrayLike] = None,
    face_labels: Optional[ArrayLike] = None,
    labels: Optional[ArrayLike] = None,
    density: float = 1000.0,
    close_holes: bool = False,
    islands: bool = False,
) -> VolumeReport: ...
def default_template(full: bool = False) -> MeshTuple: ...
def register(
    template_vertices: ArrayLike,
    template_faces: ArrayLike,
    template_vertex_labels: Optional[ArrayLike],
    template_face_labels: Optional[ArrayLike],
    points: ArrayLike,
    normals: Optional[ArrayLike],
    labels: Optional[ArrayLike],
    params: RegisterParams,
    density: float = 1000.0,
    progress: Optional[Callable[[dict[str, Any]], object]] = None,
) -> RegistrationResult: ...
def scan(
    vertices: ArrayLike,
    faces: ArrayLike,
    vertex_labels: Optional[ArrayLike] = None,
    face_labels: Optional[ArrayLike] = None,
    condition: str = "noer",
    seed: int = 0,
    images_dir: Optional[str] = None,
) -> CloudTuple: ...
def face_labels_from_vertices(faces: ArrayLike, vertex_labels: ArrayLike) -> U8: ...
def vertex_labels_from_faces(n_vertices: int, faces: ArrayLike, face_labels: ArrayLike) -> U8: ...
def vertex_normals(vertices: ArrayLike, faces: ArrayLike) -> F64: ...
def build_cloud(
    views: list[dict[str, Any]], params: Optional[dict[str, Any]] = None
) -> tuple[F64, Optional[F64], Optional[U8], Optional[U8], dict[str, Any]]:
    """Merged labelled world cloud from per-camera dicts {name, intrinsics (dict), camera_to_world
    {rotation, translation}, depth (H, W) uint16 + depth_scale or float32 metres, labels (H, W) uint8,
    colors (H, W, 3) uint8 optional} and ``FuseParams`` keywords: (points, normals, colors, labels, report)."""
    ...

"""Type stubs of the Rust extension ``bsv._bsv`` (thin: numpy <-> core types; errors -> exceptions)."""

from typing import Callable, Optional

import numpy as np
import numpy.typing as npt

F64 = npt.NDArray[np.float64]
I64 = npt.NDArray[np.int64]
U8 = npt.NDArray[np.uint8]
MeshTuple = tuple[F64, I64, Optional[U8], Optional[U8]]
CloudTuple = tuple[F64, Optional[F64], Optional[U8], Optional[U8]]

__version__: str

class BsvError(Exception): ...
class FormatError(BsvError): ...
class WriteError(BsvError): ...
class InputError(BsvError): ...
class MeshError(BsvError): ...
class VolumeError(BsvError): ...
class RegistrationError(BsvError): ...
class ScanError(BsvError): ...

def read_mesh(path: str) -> MeshTuple: ...
def read_point_cloud(path: str) -> CloudTuple: ...
def write_mesh(
    path: str, vertices: F64, faces: I64, vertex_labels: Optional[U8], face_labels: Optional[U8], ascii: bool
) -> None: ...
def write_point_cloud(
    path: str, points: F64, normals: Optional[F64], colors: Optional[U8], labels: Optional[U8], ascii: bool
) -> None: ...
def check_mesh(vertices: F64, faces: I64) -> str: ...
def volumes(
    vertices: F64,
    faces: I64,
    vertex_labels: Optional[U8],
    face_labels: Optional[U8],
    density: float,
    close_holes: bool,
    islands: bool = False,
) -> str: ...
def default_template(full: bool) -> MeshTuple: ...
def register(
    template_vertices: F64,
    template_faces: I64,
    template_vertex_labels: Optional[U8],
    template_face_labels: Optional[U8],
    points: F64,
    normals: Optional[F64],
    labels: Optional[U8],
    params_json: str,
    progress: Optional[Callable[[str], None]] = None,
) -> tuple[F64, Optional[U8], str]: ...
def scan(
    vertices: F64,
    faces: I64,
    vertex_labels: Optional[U8],
    face_labels: Optional[U8],
    condition: str,
    seed: int,
    images_dir: Optional[str],
) -> CloudTuple: ...
def build_cloud(
    views: list[dict], params_json: str
) -> tuple[F64, Optional[F64], Optional[U8], Optional[U8], str]:
    """Merged labelled world cloud from per-camera dicts {name, intrinsics (dict), camera_to_world
    {rotation, translation}, depth (H, W) uint16 + depth_scale or float32 metres, labels (H, W) uint8,
    colors (H, W, 3) uint8 optional}: (points, normals, colors, labels, report_json)."""
    ...

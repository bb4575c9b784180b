"""BSV: body segment volumes from two RGB-D cameras.

numpy in, numpy out. Every length is in metres, every volume in litres. The heavy lifting (file I/O,
mesh checks, volumes, the virtual scanner, the ARAP registration) runs in the Rust extension
``bsv._bsv``; this package converts, orchestrates and draws.
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any, Union

import numpy as np
import numpy.typing as npt

from . import _bsv
from ._bsv import RegisterParams, VolumeReport
from .errors import (
    BsvError,
    BsvWarning,
    FormatError,
    ImplausibleCloudError,
    InputError,
    MeshError,
    MissingExtraError,
    OutputExistsError,
    PersonIsolationError,
    RegistrationError,
    RegistrationInputError,
    RegistrationNumericError,
    RegistrationParameterError,
    RegistrationResourceError,
    RegistrationStopped,
    ScanError,
    VolumeError,
    WriteError,
)
from .interop import as_cloud, as_mesh, missing_labels_hint
from .types import SEGMENT_IDS, SEGMENT_NAMES, SEXES, TRUNK_LIMBS, Mesh, PointCloud, Registration

__version__: str = _bsv.__version__

PathLike = Union[str, "os.PathLike[str]"]


def __getattr__(name: str) -> Any:
    """Lazy submodules: ``bsv.bodies`` (synthetic MakeHuman bodies) and the others load on first use."""
    import importlib

    if name in _LAZY_SUBMODULES:
        return importlib.import_module(f".{name}", __name__)
    raise AttributeError(f"module 'bsv' has no attribute {name!r}")


_LAZY_SUBMODULES = ("bodies", "frontend", "bench", "report", "cli", "biomech")


def _out_path(path: PathLike, overwrite: bool) -> str:
    """The checked output path: never a folder, never an existing file or link unless ``overwrite``
    (the file is then replaced atomically by the Rust writer)."""
    p = Path(path)
    if p.is_dir():
        raise OutputExistsError(f"{p} is a folder; give a file path")
    if (p.exists() or p.is_symlink()) and not overwrite:
        raise OutputExistsError(f"{p} already exists; pass overwrite=True to replace it")
    return str(p)


def read_mesh(path: PathLike) -> Mesh:
    """Reads a PLY or OBJ triangle mesh (polygons are triangulated, OBJ groups become face labels)."""
    v, f, vl, fl = _bsv.read_mesh(str(path))
    return Mesh(v, f, vl, fl)


def read_point_cloud(path: PathLike) -> PointCloud:
    """Reads a PLY point cloud (x, y, z and optional normals, colours and ``label``)."""
    p, n, c, lab = _bsv.read_point_cloud(str(path))
    return PointCloud(p, n, c, lab)


def write_mesh(
    path: PathLike,
    mesh: Any,
    faces: Any = None,
    *,
    vertex_labels: Any = None,
    face_labels: Any = None,
    ascii: bool = False,
    overwrite: bool = False,
) -> None:
    """Writes a mesh as PLY (binary little-endian unless ``ascii``, labels + palette colours) or OBJ."""
    m = as_mesh(mesh, faces, vertex_labels, face_labels)
    _bsv.write_mesh(_out_path(path, overwrite), m.vertices, m.faces, m.vertex_labels, m.face_labels, ascii)


def write_point_cloud(
    path: PathLike,
    cloud: Any,
    *,
    normals: Any = None,
    colors: Any = None,
    labels: Any = None,
    ascii: bool = False,
    overwrite: bool = False,
) -> None:
    """Writes a point cloud as PLY (binary little-endian unless ``ascii``)."""
    c = as_cloud(cloud, labels=labels, normals=normals, colors=colors)
    _bsv.write_point_cloud(_out_path(path, overwrite), c.points, c.normals, c.colors, c.labels, ascii)


def check_mesh(mesh: Any, faces: Any = None) -> dict[str, Any]:
    """The mesh-check report: degenerate/duplicate faces, boundary and non-manifold edges, orientation, ..."""
    m = as_mesh(mesh, faces)
    return _bsv.check_mesh(m.vertices, m.faces)


def volumes(
    mesh: Any,
    faces: Any = None,
    labels: Any = None,
    *,
    density: float = 1000.0,
    close_holes: bool = False,
    islands: bool = False,
) -> dict[str, Any]:
    """Segment volumes (litres), aggregates, ratios and mass of a closed mesh.

    ``labels`` are per-vertex segment ids (or per-face when their length equals the face count);
    without labels only ``whole`` is reported. ``islands``: merge small stray label patches first (what
    :func:`register` does for fitted meshes). Returns the volumes JSON of DESIGN.md as a dict.
    """
    return volume_report(mesh, faces, labels, density=density, close_holes=close_holes, islands=islands).to_dict()


def volume_report(
    mesh: Any,
    faces: Any = None,
    labels: Any = None,
    *,
    density: float = 1000.0,
    close_holes: bool = False,
    islands: bool = False,
) -> VolumeReport:
    """:func:`volumes` as the typed :class:`bsv.VolumeReport` (``.to_dict()`` is what :func:`volumes` returns)."""
    m = as_mesh(mesh, faces)
    return _bsv.volumes(
        m.vertices, m.faces, m.vertex_labels, m.face_labels, labels, float(density), bool(close_holes), bool(islands)
    )


def default_template(full: bool = False, sex: str | None = None) -> Mesh:
    """The embedded MakeHuman template: 9 segments (head, hands, feet removed), or all 14 with ``full``.
    ``sex`` ("female" or "male"): the 9-segment template at MakeHuman's female or male end of the gender
    macro (same vertices order, faces and segments, that sex's shape: on the synthetic cohort the torso and
    thighs of the camera path fit better, see ``docs/DESIGN.md``); None, the average body."""
    if sex is None:
        v, f, vl, fl = _bsv.default_template(bool(full))
        return Mesh(v, f, vl, fl)
    if sex not in SEXES:
        err = InputError(f"sex {sex!r}: give one of {', '.join(SEXES)}, or None for the average template")
        err.argument = "sex"
        raise err
    if full:
        err = InputError("the sexed templates have 9 segments (no head, hands or feet): pass full=False with sex")
        err.argument = "full"
        raise err
    v, f, vl, fl = _bsv.default_template(kind=sex)
    return Mesh(v, f, vl, fl)


def register(
    points: Any,
    labels: Any = None,
    template: Any = None,
    *,
    progress: bool | Callable[[dict[str, Any]], None] = False,
    density: float = 1000.0,
    label_source: str | None = None,
    keypoints: Mapping[str, Any] | None = None,
    **params: Any,
) -> Registration:
    """Fits the template to a point cloud by regularized ARAP and measures the segment volumes.

    ``points``: (N, 3) metres, a bsv.PointCloud, a dict of arrays, or a trimesh/Open3D cloud (its labels,
    normals and colours are kept, :mod:`bsv.interop`); ``labels``: per-point segment ids (optional:
    without them the template's labels are used, with a :class:`bsv.BsvWarning`); ``template``: a mesh
    (default: the embedded template). Cloud normals, when present, must point outward: they are used
    as oriented (correspondence pruning, point-to-plane data term); unoriented normals (Open3D's
    ``estimate_normals`` without ``orient_normals_*``) cost 2-3 % of trunk_limbs. A cloud without
    normals gets unoriented PCA normals in the registration. ``params``: alpha, cell_weight, data_weight, schedule (default
    "m2p:5,p2m:5,m2p:4,p2m:2"; the paper's "m2p:5,p2m:5,m2p:10"), prealign ("isotropic", "per_axis", "auto"), threads, ... (see
    ``bsv-cli register --help``). ``label_source``: "cloud" (each fitted vertex takes its nearest cloud
    point's label, the paper; default for labelled clouds) or "template" (the template's own labels).
    The GIL is released while the solver runs.

    With the default (labelled human) template the cloud must be a standing person in the world frame
    (Y up, facing +Z, left on +X, metres): otherwise :class:`bsv.ImplausibleCloudError` says what is wrong
    and how to fix it (``check_plausible=False`` skips the check). ``volumes["registration"]["quality"]``
    and :attr:`Registration.quality` hold per-segment fit quality figures with a ``doubtful`` flag.

    ``keypoints``: measured joint centres ``{name: position}`` (names of
    :data:`bsv.frontend.landmarks.JOINTS`: ``shoulder_l``, ``elbow_r``, ``hip_l``, ``knee_r``, ...; a
    position is xyz in metres, ``(xyz, confidence)``, a ``{"xyz", "confidence"}`` dict or a
    :class:`~bsv.frontend.landmarks.JointCentre`) that pull the template's own joint centres (the
    keypoint term; parameters ``keypoint_weight``, ``keypoint_robust_m``). Only the embedded templates
    (and those :func:`bsv.posed_template.posed_template` poses) carry joints; the fitted-to-measured distances are in ``volumes["registration"]["keypoints"]``.
    A measured segment boundary of :data:`bsv.keypoints.BOUNDARY_RINGS` (``hip_loop_l``, ``hip_loop_r``: the
    centre of a thigh's boundary with the torso, :mod:`bsv.frontend.groin`) pulls the ring the template's
    labels give it (:func:`bsv.keypoints.boundary_rings`). A keypoint with a ``direction`` (a
    :class:`bsv.frontend.groin.LoopTarget`, or a dict's ``"direction"``) is pulled along that direction alone.
    """
    cloud = as_cloud(points, labels=labels)
    tmpl = default_template() if template is None else as_mesh(template)
    measured = rings = None
    if keypoints is not None:
        from .keypoints import BOUNDARY_RINGS, JOINT_NAMES, as_keypoints, boundary_rings, joint_rings

        measured = as_keypoints(keypoints)
        rings = joint_rings(tmpl)
        loops = [m[0] for m in measured if m[0] in BOUNDARY_RINGS]
        if rings is not None and loops:  # the segment boundaries measured too: rings of the template's labels
            rings += boundary_rings(tmpl, loops)
        if rings is None and measured:
            err = InputError("keypoints need a template that carries joint centres: the embedded templates "
                             "(template=None, bsv.default_template(), the 'fine', 'full' and sexed ones, and a "
                             "bsv.posed_template.posed_template) do; this one "
                             "does not, so fit it without keypoints")
            err.argument = "keypoints"
            raise err
        if rings is not None:  # joints this template does not reach (ankles without feet) are not pulled
            carried = {r[0] for r in rings}
            measured = [m for m in measured if m[0] in carried or m[0] not in JOINT_NAMES]
    callback: Callable[[dict[str, Any]], None] | None
    if progress is True:
        callback = _print_iteration
    elif callable(progress):
        callback = progress
    else:
        callback = None
    if label_source is None and "labels" in params:  # the registration parameter's name for it
        label_source = str(params.pop("labels"))
    if label_source is None:
        label_source = "cloud" if cloud.labels is not None else "template"
        if cloud.labels is None:
            warnings.warn(
                f"the cloud has no segment labels ({missing_labels_hint(points)}): the fitted mesh takes the "
                "template's labels, so segment volumes follow the template's cut lines, not the capture's; pass "
                "labels= (or a cloud with a 'label' attribute), or label_source='template' to silence this",
                BsvWarning,
                stacklevel=2,
            )
    params["labels"] = label_source
    result = _bsv.register(
        tmpl.vertices,
        tmpl.faces,
        tmpl.vertex_labels,
        tmpl.face_labels,
        cloud.points,
        cloud.normals,
        cloud.labels,
        RegisterParams(**params),
        float(density),
        callback,
        measured,
        rings,
    )
    fitted = Mesh(result.vertices, tmpl.faces, result.vertex_labels, None)
    vols = result.report.to_dict()
    vols["registration"] = result.summary
    return Registration(
        mesh=fitted, volumes=vols, log=result.log, seconds=result.seconds, params=result.params, report=result.report
    )


def _print_iteration(it: dict[str, Any]) -> None:
    p2m = it.get("rms_points_to_mesh_mm")
    p2m_text = "" if p2m is None else f"  p->m {p2m:.2f} mm"
    print(
        f"  [{it['stage']}:{it['kind']} {it['iteration']:>2}] m->p {it['rms_mesh_to_points_mm']:.2f} mm"
        f"{p2m_text}  E={it['energy']['total']:.4g}  moved {it['motion_mm']:.2f} mm",
        flush=True,
    )


def scan(
    mesh: Any,
    condition: str = "noer",
    seed: int = 0,
    *,
    images: PathLike | None = None,
    overwrite: bool = False,
    room: bool | Mapping[str, Any] = False,
    look: Mapping[str, Any] | None = None,
) -> PointCloud:
    """Virtual two-camera capture (DESIGN.md rig) of a labelled mesh: a merged, labelled cloud.

    ``condition``: "noer", "l515", "cali" or "l5ca". With ``images``, also writes per-camera depth and
    colour PNGs and camera JSON into that folder, as a real capture would, and its calibration.json with
    each camera's ``extrinsics_covariance`` (:mod:`bsv.uncertainty`): zero in noer and l515 (exact
    extrinsics), the paper's repeatability the rig draws its errors from in cali and l5ca.

    ``room``: ``True`` puts the rig in a clinic room (a floor, walls 0.6 m behind each camera, side
    walls, a ceiling; distances varied by ``seed``) and paints a varied subject (skin tone, underwear,
    hair, the lights: four set-ups, three colours; chosen by ``seed``); a dict of room keys (``floor_width``, ``floor_length``,
    ``back_wall_z``, ``front_wall_z``, ``side_wall_x``, ``wall_height``, ``ceiling``, ``objects``)
    sets that room exactly (missing keys: the clinic's). The room shows in the images (depth, label 0,
    colour); the returned cloud holds the body's points only. A bad value raises
    :class:`bsv.ScanError` whose ``parameter`` names it (``"room.back_wall_z"``); an unknown key or a
    wrong type raises :class:`bsv.InputError`.

    ``look`` (with a room): looks beyond what ``seed`` draws, keeping its other draws: ``{"long_hair": True}``
    hangs a subject's hair (not a bald one's) 0.30-0.45 m below the top of the head, over the neck and the
    upper back (the back camera's view); ``{"top": True}`` dresses the chest in a top of the underwear's
    colour (0.38-0.56 of the height from the crotch to the top of the head); ``{"smooth_shading": True}``
    lights the body with normals interpolated from the mesh's vertex normals, as skin looks and most renderers
    draw a mesh, instead of the faceted default (depth and labels unchanged); ``{"colour_sensor": True}`` records
    the colour as a camera's sensor does, blurred (a Gaussian of 0.7 px) and noisy (shot and read noise, about 3
    levels at mid-grey; deterministic for ``seed``). Unknown keys raise
    :class:`bsv.InputError`.
    """
    m = as_mesh(mesh)
    if not 0 <= int(seed) < 2**64:
        raise InputError(f"seed must be a whole number in 0 .. 2**64 - 1, got {seed}")
    if not isinstance(room, (bool, Mapping)):
        raise InputError(f"room must be True, False or a dict of room keys, got {type(room).__name__}")
    if look is not None and not isinstance(look, Mapping):
        raise InputError(f"look must be None or a dict of look keys (long_hair, top, smooth_shading, colour_sensor), got {type(look).__name__}")
    img = None if images is None else str(images)
    if img is not None and Path(img).exists():
        if not Path(img).is_dir():
            raise OutputExistsError(f"{img} is a file; images= needs a folder")
        if any(Path(img).iterdir()) and not overwrite:
            raise OutputExistsError(f"{img} is not empty; pass overwrite=True to write into it")
    rm: bool | dict[str, Any] = dict(room) if isinstance(room, Mapping) else bool(room)
    lk = None if look is None else dict(look)
    p, n, c, lab = _bsv.scan(m.vertices, m.faces, m.vertex_labels, m.face_labels, condition, int(seed), img, rm, lk)
    return PointCloud(p, n, c, lab)


def surface_distances(points: Any, mesh: Any) -> npt.NDArray[np.float64]:
    """Exact distance (metres) from every point (an (n, 3) array or a :class:`PointCloud`) to the
    surface of ``mesh`` (point-to-triangle; a point inside a closed mesh gets its distance to the
    surface). Benchmarks count cloud points more than 2 cm from the true body with it."""
    pts = points.points if isinstance(points, PointCloud) else np.asarray(points, dtype=np.float64)
    m = as_mesh(mesh)
    return _bsv.surface_distances(np.ascontiguousarray(pts, dtype=np.float64).reshape(-1, 3), m.vertices, m.faces)


def bsip(
    mesh: Any,
    density: float | Mapping[str, float] | None = None,
    *,
    sex: str = "male",
    out_dir: PathLike | None = None,
    overwrite: bool = False,
) -> Any:
    """Body-segment inertial parameters of a labelled closed mesh (a :class:`Mesh`, a :class:`Registration`
    or ``bsv process`` result, a synthetic ``bsv.bodies.Body``, a trimesh/Open3D mesh with labels): per
    segment the mass (segment densities, default Dempster 1955 via Winter 2009 Table 4.1; ``density`` one
    number in kg/m^3, or a mapping by segment name or kind over the table), centre of mass, inertia tensor
    about it, the joint centres (centroids of the boundaries segments share) and the segment lengths,
    beside de Leva's (1996) regression values for ``sex``. Returns a :class:`bsv.biomech.BSIP` (``.table()``
    prints a readable table); with ``out_dir`` also writes bsip.json, bsip.csv and model.osim (OpenSim)."""
    from .biomech import FILES, check_output, compute, write_all

    if out_dir is not None:  # the outputs are checked before the work
        for name in FILES:
            check_output(Path(out_dir) / name, overwrite)
    result = compute(mesh, density, sex=sex)
    if out_dir is not None:
        write_all(result, Path(out_dir), overwrite=overwrite)
    return result


__all__ = [
    "SEGMENT_IDS",
    "SEGMENT_NAMES",
    "SEXES",
    "TRUNK_LIMBS",
    "BsvError",
    "BsvWarning",
    "FormatError",
    "ImplausibleCloudError",
    "InputError",
    "Mesh",
    "MeshError",
    "MissingExtraError",
    "OutputExistsError",
    "PersonIsolationError",
    "PointCloud",
    "RegisterParams",
    "Registration",
    "RegistrationError",
    "RegistrationInputError",
    "RegistrationNumericError",
    "RegistrationParameterError",
    "RegistrationResourceError",
    "RegistrationStopped",
    "ScanError",
    "VolumeError",
    "VolumeReport",
    "WriteError",
    "bsip",
    "check_mesh",
    "default_template",
    "read_mesh",
    "read_point_cloud",
    "register",
    "scan",
    "surface_distances",
    "volume_report",
    "volumes",
    "write_mesh",
    "write_point_cloud",
]

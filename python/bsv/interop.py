"""Conversion of the objects a user holds to the bsv containers and back, keeping labels, normals and colours.

Accepted everywhere a mesh or a cloud is (``bsv.volumes``, ``bsv.register``, ``bsv.write_*``, ...):

=============================================  ===========================================================
object                                         where labels / normals / colours are read from
=============================================  ===========================================================
``bsv.Mesh`` / ``bsv.PointCloud``              their fields
``numpy`` arrays                               the ``labels=`` / ``normals=`` / ``colors=`` arguments
``dict`` of arrays                             the keys named like the fields of :class:`bsv.Mesh`
                                               (``vertices``, ``faces``, ``vertex_labels``,
                                               ``face_labels``, ``vertex_colors``) or of
                                               :class:`bsv.PointCloud` (``points``, ``normals``,
                                               ``colors``, ``labels``); an unknown key is an error
``trimesh.Trimesh``                            ``vertex_attributes["label"]`` / ``face_attributes["label"]``,
                                               else the ``label`` property of the PLY it was loaded from
                                               (``metadata["_ply_raw"]``); vertex colours when
                                               ``visual.kind == "vertex"``
``trimesh.PointCloud``                         ``metadata["label"]`` / ``metadata["normals"]``, else the
                                               PLY's ``label`` / ``nx ny nz``; ``colors``
Open3D ``geometry.PointCloud`` (legacy)        ``normals``, ``colors`` (0..1 floats); no labels possible
Open3D ``geometry.TriangleMesh`` (legacy)      ``vertex_colors``; no labels possible
Open3D ``t.geometry.PointCloud`` (tensor)      ``point.positions`` / ``normals`` / ``colors`` / ``label``
Open3D ``t.geometry.TriangleMesh`` (tensor)    ``vertex.positions`` / ``colors`` / ``label``,
                                               ``triangle.indices`` / ``label``
=============================================  ===========================================================

Open3D 0.20 keeps a ``label`` property through its tensor point-cloud PLY I/O (``open3d.t.io``) but not
through its mesh I/O (legacy or tensor), and reads mesh positions as float32; trimesh writes PLY
positions as float32 and keeps ``label`` (``include_attributes``, its default). Explicit arguments win
over what the object carries. ``label`` is the attribute name everywhere (the
PLY property of DESIGN.md "Formats"); an attribute that looks like labels under another name
(``labels``, ``segment``, ...) gives a :class:`bsv.errors.BsvWarning`, never a silent drop.
:func:`mesh_to_trimesh`, :func:`mesh_to_open3d`, :func:`cloud_to_trimesh` and :func:`cloud_to_open3d`
go the other way (``Mesh.to_trimesh()`` and friends call them) and put labels and colours where the
readers above find them, so a round trip keeps everything.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from dataclasses import fields, replace
from typing import Any, TypeVar

import numpy as np

from .errors import BsvWarning, InputError
from .extras import require
from .types import PALETTE, FloatArray, IndexArray, LabelArray, Mesh, PointCloud

_Container = TypeVar("_Container", Mesh, PointCloud)

#: The name of the label attribute in every library (and the PLY property).
LABEL = "label"
#: Attribute names that hold labels under another name: found, they are reported, not used.
LABEL_LOOKALIKES = ("labels", "segment", "segments", "segment_id", "segment_ids", "segmentation", "class", "classes")


# ----------------------------------------------------------------------------------------------------
# What an object is (by its type's module, not by attribute guesses: trimesh's Trimesh has a
# ``triangles`` attribute too).


def _library(obj: Any) -> str:
    module = type(obj).__module__ or ""
    if module.startswith("open3d"):
        return "open3d"
    if module.startswith("trimesh"):
        return "trimesh"
    return ""


def _is_open3d_tensor(obj: Any) -> bool:
    return _library(obj) == "open3d" and (hasattr(obj, "point") or hasattr(obj, "triangle"))


def _keep_unless_given(obj: _Container, **given: Any) -> _Container:
    """``obj`` with each field named in ``given`` replaced by its value unless that is None (explicit
    arguments win over what the object carries); ``obj`` itself when nothing is given."""
    new = {name: value for name, value in given.items() if value is not None}
    return replace(obj, **new) if new else obj


def _tensor_attr(tmap: Any, name: str) -> np.ndarray | None:
    """``tmap[name]`` of an Open3D TensorMap as numpy, or None."""
    return tmap[name].numpy() if name in tmap else None


def _tensor_keys(tmap: Any) -> list[str]:
    """The attribute names of an Open3D TensorMap (it has no ``keys()``)."""
    return [str(k) for k, _ in tmap.items()]


def _flat(labels: np.ndarray | None) -> np.ndarray | None:
    """(N, 1) label columns (Open3D tensor attributes) as (N,)."""
    if labels is None:
        return None
    a = np.asarray(labels)
    return a.reshape(-1) if a.ndim == 2 and a.shape[1] == 1 else a


def _colours_u8(colours: Any) -> np.ndarray | None:
    """RGB(A) colours as (N, 3) uint8: floats are read as 0..1 (Open3D), integers as 0..255; an empty
    array (trimesh's "no colours") is None."""
    if colours is None:
        return None
    c = np.asarray(colours)
    if c.size == 0:
        return None
    if c.ndim == 2 and c.shape[1] == 4:
        c = c[:, :3]
    if np.issubdtype(c.dtype, np.floating):
        if c.size and (np.nanmin(c) < 0.0 or np.nanmax(c) > 1.0):
            raise InputError(
                f"colors: floating-point colours must lie in 0..1 (Open3D's convention), got {np.nanmin(c)} .. "
                f"{np.nanmax(c)}; pass 0..255 integers instead"
            )
        return np.asarray(np.rint(c * 255.0), dtype=np.uint8)
    return c


def _warn_lookalikes(names: Any, where: str) -> None:
    odd = [n for n in names if isinstance(n, str) and n.lower() in LABEL_LOOKALIKES]
    if odd:
        warnings.warn(
            f"{where} has {', '.join(repr(n) for n in odd)} but no {LABEL!r}: it is not read as segment labels; "
            f"name the attribute {LABEL!r} or pass labels= explicitly",
            BsvWarning,
            stacklevel=4,
        )


def _ply_raw(obj: Any, element: str) -> np.ndarray | None:
    """The structured array of a PLY element that trimesh kept in ``metadata['_ply_raw']``, or None."""
    raw = getattr(obj, "metadata", {}).get("_ply_raw")
    if not isinstance(raw, Mapping) or element not in raw:
        return None
    data = raw[element].get("data") if isinstance(raw[element], Mapping) else None
    return data if isinstance(data, np.ndarray) and data.dtype.names else None


def _ply_field(obj: Any, element: str, name: str) -> np.ndarray | None:
    data = _ply_raw(obj, element)
    if data is None or data.dtype.names is None or name not in data.dtype.names:
        return None
    return np.asarray(data[name]).reshape(len(data))


def _ply_normals(obj: Any) -> np.ndarray | None:
    data = _ply_raw(obj, "vertex")
    if data is None or data.dtype.names is None or not {"nx", "ny", "nz"} <= set(data.dtype.names):
        return None
    return np.stack([data["nx"], data["ny"], data["nz"]], axis=1).astype(np.float64)


def _dict_fields(d: Mapping[str, Any], cls: type, what: str) -> dict[str, Any]:
    names = {f.name for f in fields(cls)}
    unknown = sorted(set(d) - names)
    if unknown:
        raise InputError(f"{what}: unknown key(s) {unknown}; the keys are the fields of bsv.{cls.__name__}: {sorted(names)}")
    return dict(d)


# ----------------------------------------------------------------------------------------------------
# Meshes


def as_mesh(
    obj: Any,
    faces: Any = None,
    vertex_labels: Any = None,
    face_labels: Any = None,
    vertex_colors: Any = None,
) -> Mesh:
    """A :class:`Mesh` from a Mesh, (vertices, faces) arrays, a dict of arrays, a ``trimesh.Trimesh`` or an
    Open3D TriangleMesh (legacy or tensor), with the labels and colours the object carries (module
    docstring); explicit arguments win."""
    if faces is not None:
        return Mesh(np.asarray(obj), np.asarray(faces), vertex_labels, face_labels, vertex_colors)
    if isinstance(obj, Mesh):
        m = obj
    elif isinstance(obj, Mapping):
        d = _dict_fields(obj, Mesh, "mesh dict")
        if "vertices" not in d or "faces" not in d:
            raise InputError("mesh dict: needs 'vertices' and 'faces' arrays")
        m = Mesh(**d)
    elif _is_open3d_tensor(obj):
        m = _open3d_tensor_mesh(obj)
    elif _library(obj) == "open3d" and hasattr(obj, "triangles"):
        m = Mesh(
            np.asarray(obj.vertices),
            np.asarray(obj.triangles),
            vertex_colors=_colours_u8(np.asarray(obj.vertex_colors)) if obj.has_vertex_colors() else None,
        )
    elif hasattr(obj, "faces") and hasattr(obj, "vertices"):  # trimesh.Trimesh, or any look-alike
        m = _trimesh_mesh(obj)
    else:
        raise TypeError(
            f"cannot read a mesh from {type(obj).__name__}: pass (vertices, faces) arrays, a dict of them, a "
            "bsv.Mesh, a trimesh.Trimesh or an Open3D TriangleMesh (open3d.geometry or open3d.t.geometry)"
        )
    return _keep_unless_given(m, vertex_labels=vertex_labels, face_labels=face_labels, vertex_colors=vertex_colors)


def _trimesh_mesh(obj: Any) -> Mesh:
    va = getattr(obj, "vertex_attributes", None) or {}
    fa = getattr(obj, "face_attributes", None) or {}
    vl = va.get(LABEL)
    fl = fa.get(LABEL)
    if vl is None and fl is None:
        vl = _ply_field(obj, "vertex", LABEL)
        fl = _ply_field(obj, "face", LABEL)
        if vl is None and fl is None:
            _warn_lookalikes(list(va) + list(fa), f"{type(obj).__name__} attributes")
    visual = getattr(obj, "visual", None)
    colours = None
    if visual is not None and getattr(visual, "kind", None) == "vertex":
        colours = _colours_u8(visual.vertex_colors)
    return Mesh(np.asarray(obj.vertices), np.asarray(obj.faces), _flat(vl), _flat(fl), colours)


def _open3d_tensor_mesh(obj: Any) -> Mesh:
    if "positions" not in obj.vertex or "indices" not in obj.triangle:
        raise InputError(f"{type(obj).__name__}: an Open3D tensor mesh needs vertex.positions and triangle.indices")
    vl = _flat(_tensor_attr(obj.vertex, LABEL))
    fl = _flat(_tensor_attr(obj.triangle, LABEL))
    if vl is None and fl is None:
        _warn_lookalikes(_tensor_keys(obj.vertex) + _tensor_keys(obj.triangle), "Open3D tensor mesh")
    return Mesh(
        np.asarray(obj.vertex.positions.numpy(), dtype=np.float64),
        obj.triangle.indices.numpy(),
        vl,
        fl,
        _colours_u8(_tensor_attr(obj.vertex, "colors")),
    )


def _palette_colours(labels: np.ndarray | None, colours: np.ndarray | None, n: int) -> np.ndarray | None:
    """The colours to export: the mesh's own, else the segment palette of its labels (what the PLY writer
    puts in files), else None."""
    if colours is not None:
        return np.asarray(colours, dtype=np.uint8)
    if labels is not None and len(labels) == n:
        return PALETTE[np.clip(np.asarray(labels, dtype=np.int64), 0, len(PALETTE) - 1)]
    return None


def mesh_to_trimesh(mesh: Mesh) -> Any:
    """A ``trimesh.Trimesh`` (``process=False``: vertex order kept) with ``vertex_attributes["label"]`` /
    ``face_attributes["label"]`` and vertex colours (the mesh's own, else the segment palette).
    trimesh's PLY export (``include_attributes=True``) writes the labels as a ``label`` property."""
    trimesh = require("trimesh")
    colours = _palette_colours(mesh.vertex_labels, mesh.vertex_colors, len(mesh.vertices))
    tm = trimesh.Trimesh(
        np.asarray(mesh.vertices, dtype=np.float64), np.asarray(mesh.faces, dtype=np.int64), process=False,
        vertex_colors=colours,
    )
    if mesh.vertex_labels is not None:
        tm.vertex_attributes[LABEL] = np.asarray(mesh.vertex_labels, dtype=np.uint8)
    if mesh.face_labels is not None:
        tm.face_attributes[LABEL] = np.asarray(mesh.face_labels, dtype=np.uint8)
    return tm


def mesh_to_open3d(mesh: Mesh, legacy: bool = False) -> Any:
    """An Open3D tensor ``t.geometry.TriangleMesh`` (float64 positions, int64 indices, ``vertex.label`` /
    ``triangle.label`` uint8 (N, 1), ``vertex.colors`` float32 0..1). Open3D 0.20's mesh PLY writer keeps
    positions and colours but drops the labels: write labelled meshes with :func:`bsv.write_mesh`.
    ``legacy=True``: an ``open3d.geometry.TriangleMesh`` (colours as 0..1 floats), which cannot
    hold labels (a :class:`bsv.errors.BsvWarning` says so when the mesh has some)."""
    o3d = require("open3d")
    v = np.asarray(mesh.vertices, dtype=np.float64)
    f = np.asarray(mesh.faces, dtype=np.int64)
    colours = _palette_colours(mesh.vertex_labels, mesh.vertex_colors, len(v))
    if legacy:
        lm = o3d.geometry.TriangleMesh(o3d.utility.Vector3dVector(v), o3d.utility.Vector3iVector(f.astype(np.int32)))
        if colours is not None:
            lm.vertex_colors = o3d.utility.Vector3dVector(colours.astype(np.float64) / 255.0)
        if mesh.vertex_labels is not None or mesh.face_labels is not None:
            warnings.warn(
                "Open3D's legacy TriangleMesh cannot hold labels: they are dropped (the colours keep the palette); "
                "use to_open3d() (the tensor API) to keep them",
                BsvWarning,
                stacklevel=3,
            )
        return lm
    core = o3d.core
    tm = o3d.t.geometry.TriangleMesh()
    tm.vertex.positions = core.Tensor(np.ascontiguousarray(v))
    tm.triangle.indices = core.Tensor(np.ascontiguousarray(f))
    if colours is not None:  # meshes take 0..1 colours (Open3D's mesh writer clamps uint8 ones to white)
        tm.vertex.colors = core.Tensor(np.ascontiguousarray(colours, dtype=np.float32) / np.float32(255.0))
    if mesh.vertex_labels is not None:
        tm.vertex[LABEL] = core.Tensor(np.asarray(mesh.vertex_labels, dtype=np.uint8).reshape(-1, 1))
    if mesh.face_labels is not None:
        tm.triangle[LABEL] = core.Tensor(np.asarray(mesh.face_labels, dtype=np.uint8).reshape(-1, 1))
    return tm


# ----------------------------------------------------------------------------------------------------
# Point clouds


def as_cloud(obj: Any, labels: Any = None, normals: Any = None, colors: Any = None) -> PointCloud:
    """A :class:`PointCloud` from a PointCloud, an (N, 3) array, a dict of arrays, a ``trimesh.PointCloud``
    (or the vertices of a Trimesh) or an Open3D PointCloud (legacy or tensor), with the labels, normals
    and colours the object carries (module docstring); explicit arguments win."""
    if isinstance(obj, PointCloud):
        c = obj
    elif isinstance(obj, Mapping):
        d = _dict_fields(obj, PointCloud, "cloud dict")
        if "points" not in d:
            raise InputError("cloud dict: needs a 'points' array")
        c = PointCloud(**d)
    elif _is_open3d_tensor(obj):
        c = _open3d_tensor_cloud(obj)
    elif _library(obj) == "open3d" and hasattr(obj, "points"):
        c = PointCloud(
            np.asarray(obj.points),
            np.asarray(obj.normals) if obj.has_normals() else None,
            _colours_u8(np.asarray(obj.colors)) if obj.has_colors() else None,
        )
    elif _library(obj) == "trimesh" and hasattr(obj, "vertices") and not hasattr(obj, "faces"):
        c = _trimesh_cloud(obj)
    elif hasattr(obj, "vertices") and not isinstance(obj, np.ndarray):  # a Trimesh: its vertices
        m = as_mesh(obj)
        c = PointCloud(m.vertices, None, m.vertex_colors, m.vertex_labels)
    else:
        c = PointCloud(np.asarray(obj))
    return _keep_unless_given(c, normals=normals, colors=colors, labels=labels)


def _trimesh_cloud(obj: Any) -> PointCloud:
    meta = getattr(obj, "metadata", None) or {}
    labels = meta.get(LABEL)
    if labels is None:
        labels = _ply_field(obj, "vertex", LABEL)
        if labels is None:
            _warn_lookalikes(list(meta), "trimesh.PointCloud metadata")
    normals = meta.get("normals")
    if normals is None:
        normals = _ply_normals(obj)
    return PointCloud(np.asarray(obj.vertices), normals, _colours_u8(getattr(obj, "colors", None)), _flat(labels))


def _open3d_tensor_cloud(obj: Any) -> PointCloud:
    if "positions" not in obj.point:
        raise InputError(f"{type(obj).__name__}: an Open3D tensor cloud needs point.positions")
    labels = _flat(_tensor_attr(obj.point, LABEL))
    if labels is None:
        _warn_lookalikes(_tensor_keys(obj.point), "Open3D tensor cloud")
    normals = _tensor_attr(obj.point, "normals")
    return PointCloud(
        np.asarray(obj.point.positions.numpy(), dtype=np.float64),
        None if normals is None else np.asarray(normals, dtype=np.float64),
        _colours_u8(_tensor_attr(obj.point, "colors")),
        labels,
    )


def cloud_to_trimesh(cloud: PointCloud) -> Any:
    """A ``trimesh.PointCloud`` with the colours (the cloud's own, else the segment palette of its labels),
    and ``metadata["label"]`` / ``metadata["normals"]`` (trimesh's PointCloud has no per-point attributes;
    :func:`as_cloud` reads them back from there)."""
    trimesh = require("trimesh")
    colours = _palette_colours(cloud.labels, cloud.colors, len(cloud))
    pc = trimesh.PointCloud(np.asarray(cloud.points, dtype=np.float64), colors=colours)
    if cloud.labels is not None:
        pc.metadata[LABEL] = np.asarray(cloud.labels, dtype=np.uint8)
    if cloud.normals is not None:
        pc.metadata["normals"] = np.asarray(cloud.normals, dtype=np.float64)
    return pc


def cloud_to_open3d(cloud: PointCloud, legacy: bool = False) -> Any:
    """An Open3D tensor ``t.geometry.PointCloud`` (float64 ``point.positions``, ``normals``, uint8 ``colors``
    and ``label`` (N, 1): ``open3d.t.io.write_point_cloud`` keeps them all in a PLY); ``legacy=True``: an
    ``open3d.geometry.PointCloud`` (no labels: a :class:`bsv.errors.BsvWarning` says so when there are some)."""
    o3d = require("open3d")
    pts = np.ascontiguousarray(cloud.points, dtype=np.float64)
    colours = cloud.colors
    if legacy:
        pc = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(pts))
        if cloud.normals is not None:
            pc.normals = o3d.utility.Vector3dVector(np.asarray(cloud.normals, dtype=np.float64))
        shown = _palette_colours(cloud.labels, colours, len(pts))
        if shown is not None:
            pc.colors = o3d.utility.Vector3dVector(shown.astype(np.float64) / 255.0)
        if cloud.labels is not None:
            warnings.warn(
                "Open3D's legacy PointCloud cannot hold labels: they are dropped (the colours keep the palette); "
                "use to_open3d() (the tensor API) to keep them",
                BsvWarning,
                stacklevel=3,
            )
        return pc
    core = o3d.core
    pc = o3d.t.geometry.PointCloud(core.Tensor(pts))
    if cloud.normals is not None:
        pc.point.normals = core.Tensor(np.ascontiguousarray(cloud.normals, dtype=np.float64))
    if colours is not None:
        pc.point.colors = core.Tensor(np.ascontiguousarray(colours, dtype=np.uint8))
    if cloud.labels is not None:
        pc.point[LABEL] = core.Tensor(np.asarray(cloud.labels, dtype=np.uint8).reshape(-1, 1))
    return pc


def missing_labels_hint(obj: Any) -> str:
    """Where :func:`as_cloud` looked for labels in ``obj`` (for the warning of an unlabelled cloud)."""
    if isinstance(obj, PointCloud):
        return "the bsv.PointCloud has labels=None"
    if isinstance(obj, Mapping):
        return "the dict has no 'labels' key"
    if _is_open3d_tensor(obj):
        return f"the Open3D tensor cloud has no point.{LABEL} attribute"
    if _library(obj) == "open3d":
        return "Open3D's legacy PointCloud cannot hold labels (use open3d.t.geometry.PointCloud with point.label)"
    if _library(obj) == "trimesh":
        return f"the trimesh object has no metadata[{LABEL!r}] / vertex_attributes[{LABEL!r}] nor a PLY 'label'"
    return "no labels= were given"


__all__ = [
    "LABEL",
    "FloatArray",
    "IndexArray",
    "LabelArray",
    "as_cloud",
    "as_mesh",
    "cloud_to_open3d",
    "cloud_to_trimesh",
    "mesh_to_open3d",
    "mesh_to_trimesh",
    "missing_labels_hint",
]

"""Duck-typed conversion of user objects (numpy, bsv containers, trimesh, Open3D) to numpy arrays."""

from __future__ import annotations

from typing import Any

import numpy as np

from .types import FloatArray, IndexArray, Mesh, PointCloud


def as_mesh(obj: Any, faces: Any = None, vertex_labels: Any = None, face_labels: Any = None) -> Mesh:
    """A :class:`Mesh` from a Mesh, (vertices, faces) arrays, a ``trimesh.Trimesh`` or an Open3D TriangleMesh."""
    if isinstance(obj, Mesh) and faces is None:
        return obj
    if faces is None:
        if hasattr(obj, "triangles") and hasattr(obj, "vertices"):  # Open3D TriangleMesh
            return Mesh(np.asarray(obj.vertices), np.asarray(obj.triangles), vertex_labels, face_labels)
        if hasattr(obj, "faces") and hasattr(obj, "vertices"):  # trimesh.Trimesh
            return Mesh(np.asarray(obj.vertices), np.asarray(obj.faces), vertex_labels, face_labels)
        raise TypeError(
            f"cannot read a mesh from {type(obj).__name__}: pass (vertices, faces) arrays, a bsv.Mesh, "
            "a trimesh.Trimesh or an open3d.geometry.TriangleMesh"
        )
    return Mesh(np.asarray(obj), np.asarray(faces), vertex_labels, face_labels)


def as_cloud(obj: Any, labels: Any = None, normals: Any = None, colors: Any = None) -> PointCloud:
    """A :class:`PointCloud` from a PointCloud, an (N, 3) array, a trimesh PointCloud or an Open3D PointCloud."""
    if isinstance(obj, PointCloud):
        if labels is None and normals is None and colors is None:
            return obj
        return PointCloud(
            obj.points,
            obj.normals if normals is None else normals,
            obj.colors if colors is None else colors,
            obj.labels if labels is None else labels,
        )
    if hasattr(obj, "points") and not isinstance(obj, np.ndarray):  # Open3D PointCloud
        pts = np.asarray(obj.points)
        if normals is None and getattr(obj, "has_normals", lambda: False)():
            normals = np.asarray(obj.normals)
        return PointCloud(pts, normals, colors, labels)
    if hasattr(obj, "vertices") and not isinstance(obj, np.ndarray):  # trimesh PointCloud / Trimesh
        return PointCloud(np.asarray(obj.vertices), normals, colors, labels)
    return PointCloud(np.asarray(obj), normals, colors, labels)


__all__ = ["FloatArray", "IndexArray", "as_cloud", "as_mesh"]

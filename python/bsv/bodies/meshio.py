"""Labelled mesh writers of the bodies' files (PLY binary little-endian with palette colours, OBJ with
segment groups), numpy bulk I/O.

Kept beside the Rust writers (``bsv.write_mesh``) on purpose: these are the exact bytes of the
committed templates and of the cohort (its determinism tests compare bytes), and the Rust PLY writer
has another header comment and per-face colours. Reading goes through the Rust reader."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from ..types import SEGMENT_NAMES
from .labels import PALETTE


def ply_bytes(vertices: np.ndarray, faces: np.ndarray, vertex_labels: np.ndarray | None = None,
              face_labels: np.ndarray | None = None) -> bytes:
    """Binary little-endian PLY: vertex x y z (double), red green blue, label; face vertex_indices, label."""
    v = np.asarray(vertices, dtype="<f8")
    f = np.asarray(faces, dtype="<i4")
    vl = np.zeros(len(v), np.uint8) if vertex_labels is None else np.asarray(vertex_labels, np.uint8)
    fl = np.zeros(len(f), np.uint8) if face_labels is None else np.asarray(face_labels, np.uint8)
    if f.ndim != 2 or f.shape[1] != 3 or (len(f) and (f.min() < 0 or f.max() >= len(v))):
        raise ValueError(f"faces: expected (M, 3) indices into {len(v)} vertices")
    vt = np.dtype([("x", "<f8"), ("y", "<f8"), ("z", "<f8"), ("red", "u1"), ("green", "u1"), ("blue", "u1"),
                   ("label", "u1")])
    va = np.empty(len(v), vt)
    va["x"], va["y"], va["z"] = v[:, 0], v[:, 1], v[:, 2]
    col = PALETTE[np.minimum(vl, len(PALETTE) - 1)]
    va["red"], va["green"], va["blue"], va["label"] = col[:, 0], col[:, 1], col[:, 2], vl
    ft = np.dtype([("n", "u1"), ("idx", "<i4", (3,)), ("label", "u1")])
    fa = np.empty(len(f), ft)
    fa["n"], fa["idx"], fa["label"] = 3, f, fl
    header = ("ply\nformat binary_little_endian 1.0\ncomment BSV labelled mesh, metres, Y up, faces +Z\n"
              f"element vertex {len(v)}\nproperty double x\nproperty double y\nproperty double z\n"
              "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar label\n"
              f"element face {len(f)}\nproperty list uchar int vertex_indices\nproperty uchar label\n"
              "end_header\n")
    return header.encode("ascii") + va.tobytes() + fa.tobytes()


def write_ply(path: str | Path, vertices: np.ndarray, faces: np.ndarray, vertex_labels: np.ndarray | None = None,
              face_labels: np.ndarray | None = None) -> None:
    """Write a labelled mesh as binary little-endian PLY (see ply_bytes)."""
    Path(path).write_bytes(ply_bytes(vertices, faces, vertex_labels, face_labels))


def read_ply(path: str | Path) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Read back a labelled PLY (the Rust reader, ``bsv.read_mesh``): (vertices, faces, vertex labels, face labels)."""
    from .. import read_mesh

    m = read_mesh(path)
    if m.vertex_labels is None or m.face_labels is None:
        raise ValueError(f"{path}: not a labelled PLY (vertex and face `label` properties)")
    return m.vertices, m.faces, m.vertex_labels, m.face_labels


def obj_text(vertices: np.ndarray, faces: np.ndarray, face_labels: np.ndarray, comment: str = "") -> str:
    """OBJ text: `v` lines, then faces grouped by segment (`g <segment name>`), 1-based indices."""
    buf = io.StringIO()
    if comment:
        buf.write("".join(f"# {line}\n" for line in comment.splitlines()))
    np.savetxt(buf, np.asarray(vertices, np.float64), fmt="v %.6f %.6f %.6f")
    fl = np.asarray(face_labels)
    for lab in np.unique(fl):
        buf.write(f"g {SEGMENT_NAMES[int(lab)]}\n")
        np.savetxt(buf, np.asarray(faces)[fl == lab] + 1, fmt="f %d %d %d")
    return buf.getvalue()


def write_obj(path: str | Path, vertices: np.ndarray, faces: np.ndarray, face_labels: np.ndarray,
              comment: str = "") -> None:
    """Write a labelled mesh as OBJ with one `g` group per segment."""
    Path(path).write_text(obj_text(vertices, faces, face_labels, comment))

"""``--segmentation camera``: the lab's path from a (virtual) capture folder to a labelled cloud.

Each camera folder (colour + depth PNGs + camera.json, written by :func:`bsv.scan` with ``images``) is
segmented by the MediaPipe front-end (:func:`bsv.frontend.segment.segment_capture`), and every depth
pixel inside a segment is deprojected with the intrinsics and moved to the world with the camera's
calibrated (estimated) extrinsics; front and back are merged. No outlier removal is applied (the
virtual rig's depth has no outliers besides L515 flying pixels, which registration pruning handles).
"""

from __future__ import annotations

from pathlib import Path
from typing import Mapping, Optional

import numpy as np

from ..types import PointCloud
from .common import BenchError

CAMERAS: tuple[str, ...] = ("front", "back")


def _segmenter():  # type: ignore[no-untyped-def]
    try:
        from ..frontend.segment import segment_capture
    except ImportError as exc:
        raise BenchError(
            "camera segmentation needs bsv.frontend.segment (the MediaPipe front-end), which is not available "
            f"in this installation ({exc}); use --segmentation oracle") from exc
    return segment_capture


def check_available() -> None:
    """Raise BenchError with what to do when the camera segmentation cannot run."""
    _segmenter()


def capture_cloud(capture_dir: str | Path, labels: Optional[Mapping[str, np.ndarray]] = None) -> PointCloud:
    """Merged world-frame cloud of a capture folder, each point labelled from its camera's label image.

    ``labels``: per camera a (height, width) uint8 segment-id image; default: the front-end's segmentation
    of the colour images (``--segmentation camera``). Pass the scanner's ``labels.png`` to get the oracle."""
    from ..frontend.capture import read_capture

    d = Path(capture_dir)
    if labels is None:
        seg = _segmenter()(d, cameras=CAMERAS, write=False)
        labels = {c: np.asarray(s.labels, dtype=np.uint8) for c, s in seg.items()}
    pts, labs = [], []
    for cam in CAMERAS:
        cap = read_capture(d / cam)
        depth = np.asarray(cap["depth_m"], dtype=np.float64)
        intr = cap["intrinsics"]
        if any(abs(float(k)) > 0 for k in intr.coeffs):
            raise BenchError(f"{d / cam}: distorted intrinsics are not supported by the benchmark's deprojection")
        lab = labels.get(cam)
        if lab is None or lab.shape != depth.shape:
            raise BenchError(f"{d / cam}: need a label image of shape {depth.shape} for camera {cam}")
        v, u = np.nonzero((depth > 0) & (lab > 0))
        z = depth[v, u]
        p_cam = np.stack([(u - intr.cx) * z / intr.fx, (v - intr.cy) * z / intr.fy, z], axis=1)
        e = cap["meta"]["camera_to_world"]
        r, t = np.asarray(e["rotation"], dtype=np.float64), np.asarray(e["translation"], dtype=np.float64)
        pts.append(p_cam @ r.T + t)
        labs.append(lab[v, u])
    return PointCloud(np.concatenate(pts), labels=np.concatenate(labs).astype(np.uint8))

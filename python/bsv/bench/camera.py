"""The lab's path from a (virtual) capture folder to a labelled cloud, used by ``--cloud lab`` (default)
and ``--segmentation camera``.

Each camera folder (colour + depth PNGs + camera.json, written by :func:`bsv.scan` with ``images``) is
labelled either by the scanner's own label image (``oracle``) or by the MediaPipe front-end
(``camera``: :func:`bsv.frontend.segment.segment_image` on the colour render), and the cloud is built
exactly as ``bsv process`` builds it by default (:func:`bsv.pipeline.build_cloud`: masked deprojection
with the calibrated extrinsics, per-camera floor removal and person isolation, merge, head, hands and
feet dropped; statistical outlier removal only when asked, ``--cloud-param sor=true``).

Like ``bsv process``, it only reads the capture folder: the camera segmentation is used in memory and
nothing is written into the capture (the benchmark's virtual captures live in a temporary folder).
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from ..types import PointCloud
from .common import BenchError

CAMERAS: tuple[str, ...] = ("front", "back")


def _segmenter():  # type: ignore[no-untyped-def]
    try:
        from ..frontend.segment import segment_image
    except ImportError as exc:
        raise BenchError(
            "camera segmentation needs bsv.frontend.segment (the MediaPipe front-end), which is not available "
            f"in this installation ({exc}); use --segmentation oracle") from exc
    return segment_image


def check_available() -> None:
    """Raise BenchError with what to do when the camera segmentation cannot run."""
    _segmenter()


def capture_cloud(capture_dir: str | Path, segmentation: str = "oracle",
                  labels: Mapping[str, np.ndarray] | None = None, **cloud_params: Any) -> tuple[PointCloud, dict[str, Any]]:
    """Merged, cleaned, labelled world cloud of a capture folder and the cloud builder's report.

    ``segmentation``: ``oracle`` (each camera's ``labels.png``) or ``camera`` (MediaPipe); ``labels``
    overrides both with per-camera (height, width) uint8 segment-id images; ``cloud_params``: keywords
    of :func:`bsv.pipeline.build_cloud` (default: ``bsv process``'s)."""
    return build_views_cloud(capture_views(capture_dir, segmentation, labels), capture_dir, **cloud_params)


def build_views_cloud(views: list[dict[str, Any]], capture_dir: str | Path = "",
                      **cloud_params: Any) -> tuple[PointCloud, dict[str, Any]]:
    """The cloud of :func:`capture_views`' views, built as ``bsv process`` builds it (``cloud_params``:
    keywords of :func:`bsv.pipeline.build_cloud` that differ from its defaults); failures become
    :class:`BenchError` naming ``capture_dir``."""
    from ..pipeline import build_cloud

    try:
        return build_cloud(views, **cloud_params)
    except Exception as exc:  # typed bsv errors carry the reason
        raise BenchError(f"{capture_dir}: building the cloud failed: {exc}") from exc


def capture_views(capture_dir: str | Path, segmentation: str = "oracle",
                  labels: Mapping[str, np.ndarray] | None = None) -> list[dict[str, Any]]:
    """Per-camera view dicts of :func:`bsv.pipeline.build_cloud` for a capture folder, labelled as
    :func:`capture_cloud` says (the segmentation runs once; build several clouds from the result)."""
    from PIL import Image

    from ..frontend.capture import read_capture

    d = Path(capture_dir)
    views = []
    for cam in CAMERAS:
        cap = read_capture(d / cam)
        depth = np.asarray(cap["depth_m"])
        if labels is not None and cam in labels:
            lab = np.asarray(labels[cam], dtype=np.uint8)
        elif segmentation == "oracle":
            try:
                lab = np.asarray(Image.open(d / cam / cap["meta"].get("labels", "labels.png")), dtype=np.uint8)
            except OSError as exc:
                raise BenchError(f"{d / cam}: no readable label image for oracle segmentation ({exc})") from exc
        elif segmentation == "camera":
            lab = np.asarray(_segmenter()(cap["colour"], view=cam, depth=depth).labels, dtype=np.uint8)
        else:
            raise BenchError(f"segmentation {segmentation!r}: use oracle or camera")
        if lab.shape != depth.shape:
            raise BenchError(f"{d / cam}: label image {lab.shape} and depth {depth.shape} differ in size")
        views.append({"name": cam, "intrinsics": cap["intrinsics"].to_json(),
                      "camera_to_world": cap["meta"]["camera_to_world"],
                      "depth": np.ascontiguousarray(depth, dtype=np.float32), "labels": lab,
                      "colors": np.ascontiguousarray(cap["colour"], dtype=np.uint8)})
    return views

"""The front-end a lab runs: ArUco calibration (:mod:`.calibrate`), RealSense capture (:mod:`.capture`) and
MediaPipe body segmentation (:mod:`.segment`). OpenCV, pyrealsense2 and MediaPipe are imported only by the
submodule that needs them (see requirements-frontend.txt)."""

from __future__ import annotations

import importlib
from typing import Any

from .errors import (
    BlurredImageError,
    CalibrationError,
    CalibrationFileError,
    CaptureError,
    FrontendError,
    LandmarkMissingError,
    LimbMissingError,
    MarkerNotFoundError,
    NoCameraError,
    PersonNotFoundError,
    RecordingError,
    SegmentationError,
    WrongMarkerError,
)
from .intrinsics import Intrinsics, load_intrinsics
from .marker import Board, MarkerSpec

_SUBMODULES = ("calibrate", "capture", "segment", "landmarks", "marker", "intrinsics", "errors")


def __getattr__(name: str) -> Any:
    """Submodules load on first use (they import OpenCV, pyrealsense2 or MediaPipe)."""
    if name in _SUBMODULES:
        return importlib.import_module(f".{name}", __name__)
    raise AttributeError(f"module 'bsv.frontend' has no attribute {name!r}")


__all__ = [
    "BlurredImageError",
    "Board",
    "CalibrationError",
    "CalibrationFileError",
    "CaptureError",
    "FrontendError",
    "Intrinsics",
    "LandmarkMissingError",
    "LimbMissingError",
    "MarkerNotFoundError",
    "MarkerSpec",
    "NoCameraError",
    "PersonNotFoundError",
    "RecordingError",
    "SegmentationError",
    "WrongMarkerError",
    "load_intrinsics",
]

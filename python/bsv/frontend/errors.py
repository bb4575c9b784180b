"""Typed errors of the front-end (calibration, capture, segmentation), under ``bsv.BsvError``.

Defined in :mod:`bsv.errors` (the one home of every BSV exception) and re-exported here.
"""

from __future__ import annotations

from ..errors import (
    BlurredImageError,
    BoardDepthError,
    BsvError,
    CalibrationError,
    CalibrationFileError,
    CaptureError,
    FrontendError,
    LandmarkMissingError,
    LimbMissingError,
    MarkerNotFoundError,
    NoCameraError,
    PersonNotFoundError,
    PoseTooSmallError,
    RecordingError,
    SegmentationError,
    WrongMarkerError,
)

__all__ = [
    "BlurredImageError",
    "BoardDepthError",
    "BsvError",
    "CalibrationError",
    "CalibrationFileError",
    "CaptureError",
    "FrontendError",
    "LandmarkMissingError",
    "LimbMissingError",
    "MarkerNotFoundError",
    "NoCameraError",
    "PersonNotFoundError",
    "PoseTooSmallError",
    "RecordingError",
    "SegmentationError",
    "WrongMarkerError",
]

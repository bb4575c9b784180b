"""Typed errors of the front-end (calibration, capture, segmentation), under ``bsv.BsvError``.

``BsvError`` comes from the Rust extension when it is built; without it a local stand-in base is used
so that the front-end stays importable (and testable) on its own.
"""

from __future__ import annotations

try:  # the extension's base class, so `except bsv.BsvError` catches front-end errors too
    from .._bsv import BsvError  # type: ignore[attr-defined]
except ImportError:  # pragma: no cover - exercised only when the extension is not built

    class BsvError(Exception):  # type: ignore[no-redef]
        """Stand-in for ``bsv._bsv.BsvError`` when the Rust extension is not built."""


class FrontendError(BsvError):
    """Base of every calibration, capture and segmentation error."""


class CalibrationError(FrontendError):
    """The ArUco calibration failed (see the subclasses)."""


class MarkerNotFoundError(CalibrationError):
    """No ArUco marker of the configured dictionary was found in an image."""


class WrongMarkerError(CalibrationError):
    """Markers were found, but none has the configured id."""


class BlurredImageError(CalibrationError):
    """The image (or the marker in it) is too blurred for an accurate pose."""


class CalibrationFileError(CalibrationError):
    """A calibration or intrinsics JSON file is missing or malformed."""


class CaptureError(FrontendError):
    """A RealSense capture or replay failed."""


class NoCameraError(CaptureError):
    """No RealSense camera is connected, or not the one with the requested serial number."""


class RecordingError(CaptureError):
    """A recording cannot be opened, holds no usable frames, or lacks a stream."""


class SegmentationError(FrontendError):
    """Body segmentation failed."""


class PersonNotFoundError(SegmentationError):
    """No person was detected in the colour image."""


class LandmarkMissingError(SegmentationError):
    """A landmark needed for the segmentation (an ankle, a wrist, ...) was not detected confidently."""


__all__ = [
    "BsvError", "FrontendError", "CalibrationError", "MarkerNotFoundError", "WrongMarkerError",
    "BlurredImageError", "CalibrationFileError", "CaptureError", "NoCameraError", "RecordingError",
    "SegmentationError", "PersonNotFoundError", "LandmarkMissingError",
]

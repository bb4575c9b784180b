"""Pinhole intrinsics with Brown-Conrady distortion, as RealSense reports them and calibration.json stores them.

JSON form (compatible with the Rust ``bsv_capture::camera::Intrinsics``, which reads the flat k1..k3 keys):
``{"width", "height", "fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2", "k3", "coeffs": [k1, k2, p1, p2, k3]}``.
Pixel-centre convention of OpenCV: the centre of the top-left pixel is (0, 0).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Union

import numpy as np

from .errors import CalibrationFileError

PathLike = Union[str, "Path"]


@dataclass(frozen=True)
class Intrinsics:
    """Image size (pixels), focal lengths and principal point (pixels), distortion (k1, k2, p1, p2, k3)."""

    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float
    coeffs: tuple[float, float, float, float, float] = field(default=(0.0, 0.0, 0.0, 0.0, 0.0))

    def __post_init__(self) -> None:
        vals = [self.fx, self.fy, self.cx, self.cy, *self.coeffs]
        if self.width <= 0 or self.height <= 0 or not all(math.isfinite(v) for v in vals) or self.fx <= 0 or self.fy <= 0:
            raise CalibrationFileError(
                f"invalid intrinsics {self}: width, height, fx, fy must be positive and every value finite"
            )
        if len(self.coeffs) != 5:
            raise CalibrationFileError(f"intrinsics need 5 distortion coefficients (k1, k2, p1, p2, k3), got {self.coeffs}")

    @classmethod
    def from_fov(cls, width: int, height: int, hfov_deg: float, vfov_deg: float) -> Intrinsics:
        """Ideal pinhole camera with the given fields of view and a centred principal point."""
        fx = width / 2.0 / math.tan(math.radians(hfov_deg) / 2.0)
        fy = height / 2.0 / math.tan(math.radians(vfov_deg) / 2.0)
        return cls(width, height, fx, fy, (width - 1) / 2.0, (height - 1) / 2.0)

    @property
    def matrix(self) -> np.ndarray:
        """The 3 x 3 camera matrix K."""
        return np.array([[self.fx, 0.0, self.cx], [0.0, self.fy, self.cy], [0.0, 0.0, 1.0]])

    @property
    def dist(self) -> np.ndarray:
        """OpenCV distortion vector (k1, k2, p1, p2, k3)."""
        return np.asarray(self.coeffs, dtype=np.float64)

    def scaled(self, width: int, height: int) -> Intrinsics:
        """The same camera at another resolution (same field of view, pixel-centre convention)."""
        sx, sy = width / self.width, height / self.height
        return Intrinsics(
            width, height, self.fx * sx, self.fy * sy, (self.cx + 0.5) * sx - 0.5, (self.cy + 0.5) * sy - 0.5, self.coeffs
        )

    def to_json(self) -> dict[str, Any]:
        """JSON-ready dict (flat k1..k3 for the Rust reader, plus ``coeffs``)."""
        k1, k2, p1, p2, k3 = (float(c) for c in self.coeffs)
        return {
            "width": int(self.width), "height": int(self.height),
            "fx": float(self.fx), "fy": float(self.fy), "cx": float(self.cx), "cy": float(self.cy),
            "k1": k1, "k2": k2, "p1": p1, "p2": p2, "k3": k3, "coeffs": [k1, k2, p1, p2, k3],
        }

    @classmethod
    def from_json(cls, d: Any, where: str = "intrinsics") -> Intrinsics:
        """Parses the JSON form (``coeffs`` or flat k1..k3; RealSense's ppx/ppy are accepted too)."""
        if not isinstance(d, dict):
            raise CalibrationFileError(f"{where}: expected an object with width, height, fx, fy, cx, cy; got {d!r:.80}")
        try:
            cx = d["cx"] if "cx" in d else d["ppx"]
            cy = d["cy"] if "cy" in d else d["ppy"]
            if "coeffs" in d:
                coeffs = tuple(float(c) for c in d["coeffs"])
            else:
                coeffs = tuple(float(d.get(k, 0.0)) for k in ("k1", "k2", "p1", "p2", "k3"))
            return cls(int(d["width"]), int(d["height"]), float(d["fx"]), float(d["fy"]), float(cx), float(cy),
                       coeffs)  # type: ignore[arg-type]
        except (KeyError, TypeError, ValueError) as e:
            raise CalibrationFileError(
                f"{where}: missing or malformed intrinsics field ({e}); expected width, height, fx, fy, cx, cy, coeffs"
            ) from e

    @classmethod
    def from_realsense(cls, intr: Any) -> Intrinsics:
        """From a ``pyrealsense2.intrinsics`` (ppx/ppy, Brown-Conrady coeffs; other models keep their coeffs)."""
        coeffs = tuple(float(c) for c in list(intr.coeffs)[:5])
        return cls(int(intr.width), int(intr.height), float(intr.fx), float(intr.fy), float(intr.ppx), float(intr.ppy),
                   coeffs)  # type: ignore[arg-type]


def load_intrinsics(path: PathLike, camera: str | None = None) -> Intrinsics:
    """Intrinsics from a JSON file: a bare intrinsics object, a capture ``intrinsics.json``/``camera.json``
    (``{"intrinsics": {...}}``), or a ``calibration.json`` (then ``camera`` names the entry)."""
    p = Path(path)
    try:
        doc = json.loads(p.read_text())
    except OSError as e:
        raise CalibrationFileError(f"cannot read intrinsics file {p}: {e}") from e
    except json.JSONDecodeError as e:
        raise CalibrationFileError(f"{p} is not valid JSON ({e}); expected an intrinsics object") from e
    if isinstance(doc, dict) and "cameras" in doc:
        if camera is None or camera not in doc["cameras"]:
            raise CalibrationFileError(f"{p} holds cameras {sorted(doc['cameras'])}; name one of them (got {camera!r})")
        doc = doc["cameras"][camera]
    if isinstance(doc, dict) and "intrinsics" in doc:
        doc = doc["intrinsics"]
    return Intrinsics.from_json(doc, where=str(p))

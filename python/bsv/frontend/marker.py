"""The calibration board: an ArUco marker printed on both faces of a flat board.

A marker seen from behind decodes as another id, so the board carries the same marker on its back face,
printed upright, so that the back camera reads it normally. The board stands where the subject will stand
(world x = z = 0 by default), upright, its front face toward the front camera.

Marker frame (OpenCV ArUco convention for ``SOLVEPNP_IPPE_SQUARE``): origin at the marker centre, +x to
the viewer's right, +y up, +z out of the face toward the viewer. In the world frame of DESIGN.md (Y up,
subject faces +Z, +X = subject's left):
- front face: x = +X, y = +Y, z = +Z, centre at (x0, height, z0 + thickness / 2);
- back face (the board turned 180 deg about the vertical): x = -X, y = +Y, z = -Z, centre at
  (x0, height, z0 - thickness / 2).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..extras import require
from .errors import CalibrationError

if TYPE_CHECKING:
    import cv2

    from .intrinsics import Intrinsics

#: Camera sides and the board face each one sees.
SIDES = ("front", "back")

#: White margin of the board around the printed marker on each side (metres): the board face is a square of
#: side ``marker size + 2 margin``.
BOARD_MARGIN_M: float = 0.03


@dataclass(frozen=True)
class MarkerSpec:
    """Which marker to look for: an OpenCV ArUco dictionary name, the marker id and its printed side (metres)."""

    dictionary: str = "DICT_ARUCO_ORIGINAL"
    marker_id: int = 336
    size_m: float = 0.16

    def __post_init__(self) -> None:
        if not (self.size_m > 0):
            raise CalibrationError(f"marker size must be positive metres, got {self.size_m}")
        if self.marker_id < 0:
            raise CalibrationError(f"marker id must be >= 0, got {self.marker_id}")

    def aruco_dictionary(self) -> cv2.aruco.Dictionary:
        """The ``cv2.aruco.Dictionary`` (raises CalibrationError for an unknown name or an id out of range)."""
        cv2 = require("cv2")

        code = getattr(cv2.aruco, self.dictionary, None)
        if not isinstance(code, int):
            raise CalibrationError(f"unknown ArUco dictionary {self.dictionary!r}; use a cv2.aruco.DICT_* name")
        d = cv2.aruco.getPredefinedDictionary(code)
        if self.marker_id >= d.bytesList.shape[0]:
            raise CalibrationError(
                f"marker id {self.marker_id} is out of range for {self.dictionary} ({d.bytesList.shape[0]} markers)"
            )
        return d

    def object_points(self) -> np.ndarray:
        """The 4 corners in the marker frame, in ArUco order (top-left, top-right, bottom-right, bottom-left)."""
        h = self.size_m / 2.0
        return np.array([[-h, h, 0.0], [h, h, 0.0], [h, -h, 0.0], [-h, -h, 0.0]])

    def image(self, pixels: int = 700, border_bits: int = 1) -> np.ndarray:
        """The printable marker (uint8, black modules on white), ``pixels`` wide including its black border."""
        cv2 = require("cv2")

        return cv2.aruco.generateImageMarker(self.aruco_dictionary(), self.marker_id, int(pixels), borderBits=border_bits)

    def mirrored_id(self) -> int | None:
        """The id this marker decodes as when seen mirrored (printed on the wrong side), if any."""
        cv2 = require("cv2")

        img = np.pad(self.image(280), 40, constant_values=255)
        det = cv2.aruco.ArucoDetector(self.aruco_dictionary(), cv2.aruco.DetectorParameters())
        _, ids, _ = det.detectMarkers(np.ascontiguousarray(img[:, ::-1]))
        return None if ids is None else int(ids.ravel()[0])


@dataclass(frozen=True)
class Board:
    """Placement of the double-sided board in the world: marker centre height above the floor, board
    thickness (the two faces are ``thickness`` apart), the board's mid-plane position (x0, z0) and its white
    margin around the marker (the face is a square of side ``marker.size_m + 2 margin_m``)."""

    marker: MarkerSpec = MarkerSpec()
    centre_height_m: float = 1.0
    thickness_m: float = 0.005
    x0_m: float = 0.0
    z0_m: float = 0.0
    margin_m: float = BOARD_MARGIN_M

    def __post_init__(self) -> None:
        vals = [self.centre_height_m, self.thickness_m, self.x0_m, self.z0_m, self.margin_m]
        if not np.isfinite(vals).all() or self.thickness_m < 0 or self.margin_m < 0:
            raise CalibrationError(f"invalid board placement {self}: finite values, thickness and margin >= 0 needed")

    @property
    def face_size_m(self) -> float:
        """Side of the (square) board face, metres."""
        return self.marker.size_m + 2.0 * self.margin_m

    def face_corners(self, side: str, inset_m: float = 0.0) -> np.ndarray:
        """World corners (4 x 3) of the board face seen by camera ``side``, moved ``inset_m`` inward."""
        r, t = self.marker_to_world(side)
        h = self.face_size_m / 2.0 - inset_m
        if h <= 0:
            raise CalibrationError(f"inset {inset_m} m leaves nothing of the {self.face_size_m} m board face")
        sq = np.array([[-h, h, 0.0], [h, h, 0.0], [h, -h, 0.0], [-h, -h, 0.0]])
        return sq @ r.T + t

    def marker_to_world(self, side: str) -> tuple[np.ndarray, np.ndarray]:
        """Rotation (3 x 3) and translation of the marker frame of the face seen by camera ``side``."""
        half = self.thickness_m / 2.0
        if side == "front":
            return np.eye(3), np.array([self.x0_m, self.centre_height_m, self.z0_m + half])
        if side == "back":
            return np.diag([-1.0, 1.0, -1.0]), np.array([self.x0_m, self.centre_height_m, self.z0_m - half])
        raise CalibrationError(f"unknown camera side {side!r}: the board has faces for {SIDES}")

    def to_json(self) -> dict:
        """JSON-ready description (stored in calibration.json under ``marker``)."""
        return {
            "dictionary": self.marker.dictionary, "id": self.marker.marker_id, "size_m": self.marker.size_m,
            "centre_height_m": self.centre_height_m, "board_thickness_m": self.thickness_m,
            "board_x_m": self.x0_m, "board_z_m": self.z0_m, "board_margin_m": self.margin_m,
            "faces": {s: {"rotation": r.tolist(), "translation": t.tolist()} for s in SIDES
                      for r, t in [self.marker_to_world(s)]},
        }


def render_view(
    marker: MarkerSpec,
    intrinsics: Intrinsics,
    rotation: np.ndarray,
    translation: np.ndarray,
    *,
    margin_m: float = BOARD_MARGIN_M,
    background: int = 110,
    samples: int = 8,
    seed: int = 0,
) -> np.ndarray:
    """Synthetic grey image of the marker on a white board ``margin_m`` wider on each side, seen by an
    undistorted pinhole camera with marker-to-camera pose (``rotation``, ``translation``); for tests and the
    demo. Each pixel near the board averages ``samples`` x ``samples`` stratified, randomly jittered point
    samples of the exact pattern (unbiased area sampling: edges land where the projection puts them)."""
    r = np.asarray(rotation, dtype=np.float64)
    t = np.asarray(translation, dtype=np.float64).reshape(3)
    k = intrinsics.matrix
    h = k @ np.column_stack([r[:, 0], r[:, 1], t])  # marker plane (X, Y, 1) -> image
    h_inv = np.linalg.inv(h)
    w_img, h_img = int(intrinsics.width), int(intrinsics.height)
    out = np.full((h_img, w_img), float(background))
    half_board = marker.size_m / 2.0 + margin_m
    bc = np.array([[-1, 1], [1, 1], [1, -1], [-1, -1]], dtype=np.float64) * half_board
    cam = (r[:, :2] @ bc.T).T + t
    if (cam[:, 2] <= 1e-6).any():
        raise CalibrationError("render_view: the board is (partly) behind the camera")
    proj = (k @ cam.T).T
    pix = proj[:, :2] / proj[:, 2:3]
    x0, y0 = np.floor(pix.min(axis=0)).astype(int) - 1
    x1, y1 = np.ceil(pix.max(axis=0)).astype(int) + 2
    x0, y0, x1, y1 = max(x0, 0), max(y0, 0), min(x1, w_img), min(y1, h_img)
    if x0 >= x1 or y0 >= y1:
        return np.clip(np.rint(out), 0, 255).astype(np.uint8)
    bits = (marker.image(7) > 127).astype(np.float64) * 255.0  # 7 x 7 modules incl. the black border
    rng = np.random.default_rng(seed)
    n = int(samples)
    ys, xs = np.mgrid[y0:y1, x0:x1]
    acc = np.zeros(xs.shape)
    module = marker.size_m / 7.0
    for i in range(n):
        for j in range(n):
            sx = xs + (j + rng.random(xs.shape)) / n - 0.5
            sy = ys + (i + rng.random(xs.shape)) / n - 0.5
            pw = h_inv[2, 0] * sx + h_inv[2, 1] * sy + h_inv[2, 2]
            px = (h_inv[0, 0] * sx + h_inv[0, 1] * sy + h_inv[0, 2]) / pw
            py = (h_inv[1, 0] * sx + h_inv[1, 1] * sy + h_inv[1, 2]) / pw
            col = np.floor((px + marker.size_m / 2.0) / module).astype(int)
            row = np.floor((marker.size_m / 2.0 - py) / module).astype(int)
            in_marker = (col >= 0) & (col < 7) & (row >= 0) & (row < 7)
            in_board = (np.abs(px) <= half_board) & (np.abs(py) <= half_board)
            val = np.where(in_board, 255.0, float(background))
            val[in_marker] = bits[row[in_marker], col[in_marker]]
            acc += val
    out[y0:y1, x0:x1] = acc / (n * n)
    return np.clip(np.rint(out), 0, 255).astype(np.uint8)

"""ArUco calibration of the two cameras: per-camera intrinsics and camera-to-world extrinsics.

Each camera sees one face of the double-sided board (see :mod:`bsv.frontend.marker`). Per frame the
marker is detected (``cv2.aruco.ArucoDetector``, sub-pixel corners) and its pose estimated with
``solvePnP(..., SOLVEPNP_IPPE_SQUARE)`` refined by Levenberg-Marquardt; the frames' poses are averaged
(rotation: the chordal mean, SVD of the summed matrices; translation: the mean) and turned into the
camera-to-world transform of DESIGN.md's world frame. ``calibration.json``::

    {"cameras": {"front": {"intrinsics": {...}, "camera_to_world": {"rotation": [[3x3 rows]],
     "translation": [x, y, z]}, "serial": ..., "frames": n, "reprojection_rms_px": ...,
     "spread": {...}, "extrinsics_covariance": {...}}, "back": {...}}, "marker": {...}}

``camera_to_world`` maps camera-frame points (OpenCV: +X right, +Y down, +Z forward) to the world:
``p_world = rotation @ p_cam + translation``.

``extrinsics_covariance`` (read by :mod:`bsv.uncertainty`; files without it are accepted) is the 6 x 6
covariance of the camera's extrinsics: ``{"parameters": ["tx_m", "ty_m", "tz_m", "rx_rad", "ry_rad",
"rz_rad"], "frame": ..., "matrix": [[6 x 6]], "source": "frames" | "paper default"}``. The parameters
are a small pose change in the camera frame composed on the right (``R' = R Rodrigues(r)``,
``t' = R t_delta + t``: :data:`bsv.uncertainty.FRAME`). With at least :data:`MIN_COVARIANCE_FRAMES`
frames it is the sample covariance of the per-frame poses about the result (the repeatability of one
frame: an upper bound for the frames' noise, a lower bound for a new session's board placement); with
fewer, the paper's standard deviations (:data:`bsv.uncertainty.PAPER_STD`).

With depth images of the board (aligned to colour, ``--depth front=DIR back=DIR``), each camera's pose is
then refined by the board face's plane in its depth (:mod:`bsv.frontend.boardplane`: distance to the
board and the two tilts about axes in the board plane), the covariance conditioned on it, its source
suffixed ``+board depth`` (``"frames+board depth"``: the update's prior was the frames' covariance plus
the paper's, since the frames' spread misses the systematic errors the depth corrects; ``"paper
default+board depth"``) and the refinement's figures written under ``board_depth``.
"""

from __future__ import annotations

import argparse
import json
import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import OutputExistsError
from ..extras import require
from .errors import (
    BlurredImageError,
    CalibrationError,
    CalibrationFileError,
    MarkerNotFoundError,
    WrongMarkerError,
)
from .intrinsics import Intrinsics, load_intrinsics
from .marker import BOARD_MARGIN_M, SIDES, Board, MarkerSpec

if TYPE_CHECKING:
    import cv2

PathLike = str | Path
ImageLike = np.ndarray | PathLike
#: A depth image: metres (float array) or raw 16-bit units (uint16 array or PNG path, times a depth scale).
DepthLike = np.ndarray | PathLike

#: Metres per unit of a 16-bit depth image when nothing says otherwise (the L515's default depth unit).
DEFAULT_DEPTH_SCALE: float = 0.00025
#: Suffix of the covariance source when the board's depth refined the extrinsics.
BOARD_DEPTH_SOURCE: str = "+board depth"

#: The default marker and board (frozen dataclasses, shared as argument defaults).
_DEFAULT_MARKER = MarkerSpec()
_DEFAULT_BOARD = Board()

#: Largest blur edge width (pixels) accepted for a marker; a sharp edge is about 1-2 px wide.
MAX_EDGE_WIDTH_PX = 4.0


# ----------------------------------------------------------------------------------------------------
# Detection and pose of one frame


def _read_unchanged(image: ImageLike, what: str) -> np.ndarray:
    """The array itself, or the file read as stored (bit depth and channels kept); CalibrationFileError
    names an unreadable file (``what``: "image", "depth image")."""
    if isinstance(image, (str, Path)):
        cv2 = require("cv2")
        img = cv2.imread(str(image), cv2.IMREAD_UNCHANGED)
        if img is None:
            raise CalibrationFileError(f"cannot read {what} {image}: missing file or not an image")
        return img
    return np.asarray(image)


def _gray(image: ImageLike) -> np.ndarray:
    cv2 = require("cv2")
    img = _read_unchanged(image, "image")
    if img.dtype != np.uint8:
        raise CalibrationError(f"expected an 8-bit image, got dtype {img.dtype}")
    if img.ndim == 3 and img.shape[2] == 4:
        img = cv2.cvtColor(img, cv2.COLOR_BGRA2GRAY)
    elif img.ndim == 3 and img.shape[2] == 3:
        img = cv2.cvtColor(img, cv2.COLOR_BGR2GRAY)
    elif img.ndim != 2:
        raise CalibrationError(f"expected a grey or colour image, got shape {img.shape}")
    return np.ascontiguousarray(img)


def edge_width_px(gray: np.ndarray, roi: tuple[int, int, int, int] | None = None) -> float:
    """Blur estimate: the contrast of the region divided by its steepest gradients (pixels). A sharp
    step edge is 1-2 px wide; a Gaussian blur of sigma s widens it to about 2.5 s. NaN when the region
    has no contrast to judge by. Without ``roi`` the extreme percentiles of the whole image are used (a
    marker fills only ~1 % of a frame)."""
    cv2 = require("cv2")

    g = gray if roi is None else gray[roi[1]:roi[3], roi[0]:roi[2]]
    if g.size < 9:
        return float("nan")
    f = g.astype(np.float32)
    gx = cv2.Sobel(f, cv2.CV_32F, 1, 0, ksize=3) / 8.0
    gy = cv2.Sobel(f, cv2.CV_32F, 0, 1, ksize=3) / 8.0
    mag = np.hypot(gx, gy)
    lo, hi, top = (2.0, 98.0, 99.5) if roi is not None else (0.1, 99.9, 99.97)
    contrast = float(np.percentile(f, hi) - np.percentile(f, lo))
    steep = float(np.percentile(mag, top))
    if contrast < 20.0 or steep <= 0.0:
        return float("nan")
    return contrast / steep


def _detector(marker: MarkerSpec) -> cv2.aruco.ArucoDetector:
    cv2 = require("cv2")

    params = cv2.aruco.DetectorParameters()
    params.cornerRefinementMethod = cv2.aruco.CORNER_REFINE_SUBPIX
    params.cornerRefinementWinSize = 5
    params.cornerRefinementMaxIterations = 100
    params.cornerRefinementMinAccuracy = 0.001
    return cv2.aruco.ArucoDetector(marker.aruco_dictionary(), params)


def detect_marker(image: ImageLike, marker: MarkerSpec = _DEFAULT_MARKER, *, name: str = "image",
                  max_edge_width_px: float = MAX_EDGE_WIDTH_PX, detector: Any = None) -> np.ndarray:
    """The 4 sub-pixel corners (4 x 2, ArUco order) of the configured marker in one image.

    Raises BlurredImageError (marker region, or the whole image when nothing is found, too blurred),
    WrongMarkerError (other ids only) or MarkerNotFoundError."""
    gray = _gray(image)
    det = detector if detector is not None else _detector(marker)
    corners, ids, rejected = det.detectMarkers(gray)
    found = [] if ids is None else [int(i) for i in ids.ravel()]
    if marker.marker_id not in found:
        width = edge_width_px(gray)
        if width > max_edge_width_px:  # NaN (no contrast at all) is not called blurred
            raise BlurredImageError(
                f"{name}: no marker {marker.marker_id} found and the image is blurred (edge width {width:.1f} px > "
                f"{max_edge_width_px} px): focus the camera, hold the board still, improve the light"
            )
        if found:
            mirrored = marker.mirrored_id()
            hint = (f" (id {mirrored} is marker {marker.marker_id} seen mirrored: the board face is printed "
                    "mirror-wise or seen through the paper)") if mirrored in found else ""
            raise WrongMarkerError(
                f"{name}: found {marker.dictionary} marker id(s) {sorted(set(found))} but not id {marker.marker_id}"
                f"{hint}; show the calibration board's marker {marker.marker_id} or configure its id"
            )
        raise MarkerNotFoundError(
            f"{name}: no {marker.dictionary} marker found ({len(rejected)} rejected candidates): put the "
            f"{marker.size_m * 100:.0f} cm marker id {marker.marker_id} in full view, flat, well lit"
        )
    k = found.index(marker.marker_id)
    if found.count(marker.marker_id) > 1:
        raise WrongMarkerError(f"{name}: marker {marker.marker_id} found {found.count(marker.marker_id)} times; "
                               "show a single board")
    c = np.asarray(corners[k], dtype=np.float64).reshape(4, 2)
    x0, y0 = np.floor(c.min(axis=0)).astype(int) - 4
    x1, y1 = np.ceil(c.max(axis=0)).astype(int) + 5
    roi = (max(int(x0), 0), max(int(y0), 0), min(int(x1), gray.shape[1]), min(int(y1), gray.shape[0]))
    width = edge_width_px(gray, roi)
    if width > max_edge_width_px:
        raise BlurredImageError(
            f"{name}: marker {marker.marker_id} is blurred (edge width {width:.1f} px > {max_edge_width_px} px): "
            "focus the camera, hold the board still, improve the light"
        )
    return refine_corners(gray, c, marker)


def _edge_line(img: np.ndarray, p0: np.ndarray, p1: np.ndarray, centre: np.ndarray, half: int, trim: float
               ) -> np.ndarray | None:
    """Sub-pixel line (homogeneous a x + b y + c = 0) of one outer marker edge from p0 to p1, white outside
    and black inside: along each row (or column) crossing the edge, the summed whiteness of a window
    across the edge is the distance from the window's outer end to the edge, exact for area-sampled
    (and symmetrically blurred) straight edges; a least-squares line through those edge points."""
    d = p1 - p0
    vertical = abs(d[1]) >= abs(d[0])
    ax = 1 if vertical else 0  # the coordinate we step along (y for vertical edges)
    ox = 1 - ax  # the coordinate across the edge
    lo, hi = sorted((p0[ax], p1[ax]))
    steps = np.arange(int(np.ceil(lo + trim)), int(np.floor(hi - trim)) + 1)
    if steps.size < 5:
        return None
    frac = (steps - p0[ax]) / d[ax]
    across = p0[ox] + frac * d[ox]
    out_sign = 1.0 if np.mean(across) > centre[ox] else -1.0  # which way is outside (white)
    start = np.rint(across).astype(int) - half
    offs = np.arange(2 * half + 1)
    idx = start[:, None] + offs[None, :]
    n_other = img.shape[1] if vertical else img.shape[0]
    n_step = img.shape[0] if vertical else img.shape[1]
    if idx.min() < 0 or idx.max() >= n_other or steps.min() < 0 or steps.max() >= n_step:
        return None
    prof = img[steps[:, None], idx] if vertical else img[idx, steps[:, None]]
    outer = prof[:, -2:] if out_sign > 0 else prof[:, :2]
    inner = prof[:, :2] if out_sign > 0 else prof[:, -2:]
    white, black = float(np.median(outer)), float(np.median(inner))
    if white - black < 20.0:
        return None
    f = (prof - black) / (white - black)
    s = f.sum(axis=1)
    edge = (idx[:, -1] + 0.5) - s if out_sign > 0 else (idx[:, 0] - 0.5) + s
    pts = np.column_stack([edge, steps]) if vertical else np.column_stack([steps, edge])
    # total least squares line through the edge points
    m = pts.mean(axis=0)
    _, _, vt = np.linalg.svd(pts - m)
    nrm = vt[1]
    return np.array([nrm[0], nrm[1], -nrm @ m])


def refine_corners(gray: np.ndarray, corners: np.ndarray, marker: MarkerSpec = _DEFAULT_MARKER, *,
                   max_move_px: float = 1.5) -> np.ndarray:
    """Sub-pixel refinement of the 4 outer corners as intersections of the 4 edge lines of the marker's
    black border, each fitted to area-integral edge points along its whole length (see ``_edge_line``):
    about ten times more accurate than corner-window refinement, which matters because a 16 cm marker at
    2 m spans only ~110 px and 0.01 px of corner error already tilts the pose by ~0.07 deg. Falls back to
    the given corners when the border is too small, touches the image edge or moves a corner too far."""
    c = np.asarray(corners, dtype=np.float64).reshape(4, 2)
    img = np.asarray(gray, dtype=np.float64)
    side_px = float(np.mean(np.linalg.norm(c - np.roll(c, 1, axis=0), axis=1)))
    module = side_px / 7.0
    half = int(np.clip(np.floor(module * 0.3), 3, 10))
    if module < 6.0:
        return c
    centre = c.mean(axis=0)
    lines = []
    for k in range(4):
        ln = _edge_line(img, c[k], c[(k + 1) % 4], centre, half, trim=3.0)
        if ln is None:
            return c
        lines.append(ln)
    out = np.empty_like(c)
    for k in range(4):
        x = np.cross(lines[(k - 1) % 4], lines[k])
        if abs(x[2]) < 1e-12:
            return c
        out[k] = x[:2] / x[2]
    if not np.isfinite(out).all() or np.abs(out - c).max() > max_move_px:
        return c
    return out


def marker_pose(corners: np.ndarray, intrinsics: Intrinsics, marker: MarkerSpec = _DEFAULT_MARKER
                ) -> tuple[np.ndarray, np.ndarray, float]:
    """Marker-to-camera rotation (3 x 3), translation (metres) and the reprojection RMS (pixels) from
    4 corners: IPPE square, then Levenberg-Marquardt refinement."""
    cv2 = require("cv2")

    obj = marker.object_points()
    img = np.asarray(corners, dtype=np.float64).reshape(4, 1, 2)
    ok, rvec, tvec = cv2.solvePnP(obj, img, intrinsics.matrix, intrinsics.dist, flags=cv2.SOLVEPNP_IPPE_SQUARE)
    if not ok:
        raise CalibrationError("solvePnP (IPPE square) found no marker pose from the detected corners")
    rvec, tvec = cv2.solvePnPRefineLM(obj, img, intrinsics.matrix, intrinsics.dist, rvec, tvec)
    proj, _ = cv2.projectPoints(obj, rvec, tvec, intrinsics.matrix, intrinsics.dist)
    rms = float(np.sqrt(np.mean(np.sum((proj.reshape(4, 2) - img.reshape(4, 2)) ** 2, axis=1))))
    r, _ = cv2.Rodrigues(rvec)
    return r, tvec.reshape(3), rms


# ----------------------------------------------------------------------------------------------------
# Averaging and frames


def nearest_rotation(m: np.ndarray) -> np.ndarray:
    """The rotation closest to a 3 x 3 matrix in the Frobenius norm (SVD, det forced to +1)."""
    u, _, vt = np.linalg.svd(m)
    d = np.sign(np.linalg.det(u @ vt)) or 1.0
    return u @ np.diag([1.0, 1.0, d]) @ vt


def rotation_angle_deg(a: np.ndarray, b: np.ndarray) -> float:
    """Angle (degrees) of the relative rotation a^T b: atan2 of its sine (the skew part) and cosine (the
    trace), exact to rounding at small angles too, where acos of the trace loses half the digits."""
    r = np.asarray(a).T @ np.asarray(b)
    c = (float(np.trace(r)) - 1.0) / 2.0
    s = float(np.linalg.norm([r[2, 1] - r[1, 2], r[0, 2] - r[2, 0], r[1, 0] - r[0, 1]])) / 2.0
    return math.degrees(math.atan2(s, c))


def average_poses(rotations: Sequence[np.ndarray], translations: Sequence[np.ndarray]
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Mean pose: chordal mean rotation (SVD of the sum of the matrices) and mean translation."""
    if len(rotations) == 0 or len(rotations) != len(translations):
        raise CalibrationError("no poses to average (or rotations and translations differ in number)")
    return nearest_rotation(np.sum(np.asarray(rotations, dtype=np.float64), axis=0)), np.mean(
        np.asarray(translations, dtype=np.float64), axis=0)


def camera_to_world(r_cm: np.ndarray, t_cm: np.ndarray, r_wm: np.ndarray, t_wm: np.ndarray
                    ) -> tuple[np.ndarray, np.ndarray]:
    """Camera-to-world transform from the marker-to-camera pose and the marker-to-world placement."""
    r_wc = np.asarray(r_wm) @ np.asarray(r_cm).T
    return r_wc, np.asarray(t_wm) - r_wc @ np.asarray(t_cm)


# ----------------------------------------------------------------------------------------------------
# Results


@dataclass
class CameraCalibration:
    """One camera's result: intrinsics, camera-to-world rotation/translation and quality figures."""

    name: str
    intrinsics: Intrinsics
    rotation: np.ndarray
    translation: np.ndarray
    serial: str | None = None
    frames: int = 0
    reprojection_rms_px: float = 0.0
    spread_mm: float = 0.0
    spread_deg: float = 0.0
    #: 6 x 6 covariance of the extrinsics (module doc); None when the file had none.
    covariance: np.ndarray | None = None
    #: Where the covariance comes from: "frames" or "paper default", suffixed "+board depth" when refined.
    covariance_source: str = ""
    #: The board-depth refinement's figures (:meth:`bsv.frontend.boardplane.BoardRefinement.report`), if any.
    board_depth: dict[str, Any] | None = None

    def to_json(self) -> dict[str, Any]:
        """JSON-ready entry of calibration.json."""
        cov = {} if self.covariance is None else {"extrinsics_covariance": covariance_json(
            self.covariance, self.covariance_source)}
        return {**cov,
            "intrinsics": self.intrinsics.to_json(),
            "camera_to_world": {"rotation": np.asarray(self.rotation).tolist(),
                                "translation": np.asarray(self.translation).tolist()},
            "serial": self.serial,
            "frames": int(self.frames),
            "reprojection_rms_px": float(self.reprojection_rms_px),
            "spread": {"translation_mm": float(self.spread_mm), "rotation_deg": float(self.spread_deg)},
            **({} if self.board_depth is None else {"board_depth": self.board_depth}),
        }


@dataclass
class Calibration:
    """Both cameras' calibrations and the board they were made with."""

    cameras: dict[str, CameraCalibration]
    board: Board = field(default_factory=Board)

    def to_json(self) -> dict[str, Any]:
        """The calibration.json document."""
        return {"cameras": {k: c.to_json() for k, c in self.cameras.items()}, "marker": self.board.to_json()}

    def write(self, path: PathLike, overwrite: bool = False) -> Path:
        """Writes calibration.json (refuses to replace an existing file unless ``overwrite``)."""
        p = Path(path)
        if p.exists() and not overwrite:
            raise OutputExistsError(f"{p} already exists; pass overwrite=True (--overwrite) to replace it")
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_text(json.dumps(self.to_json(), indent=2))
        return p


#: Fewest frames whose per-frame poses give the covariance; fewer frames get the paper's repeatability.
MIN_COVARIANCE_FRAMES = 3


def covariance_json(cov: np.ndarray, source: str) -> dict[str, Any]:
    """The ``extrinsics_covariance`` entry of calibration.json (module doc)."""
    from ..uncertainty import FRAME, PARAMETERS

    return {"parameters": list(PARAMETERS), "frame": FRAME, "matrix": np.asarray(cov, dtype=np.float64).tolist(),
            "source": source}


def _read_covariance(doc: Any, where: str) -> tuple[np.ndarray | None, str]:
    """(covariance, source) of an ``extrinsics_covariance`` entry; (None, "") when absent (older files)."""
    from ..errors import UncertaintyError
    from ..uncertainty import PARAMETERS, check_covariance

    if doc is None:
        return None, ""
    if not isinstance(doc, dict) or list(doc.get("parameters", PARAMETERS)) != list(PARAMETERS):
        raise CalibrationFileError(f"{where}: extrinsics_covariance must be {{'parameters': {list(PARAMETERS)}, "
                                   "'matrix': 6 x 6}; recalibrate with `bsv calibrate` or delete the entry")
    try:
        return check_covariance(doc.get("matrix"), f"{where} extrinsics_covariance"), str(doc.get("source", ""))
    except UncertaintyError as exc:
        raise CalibrationFileError(f"{exc}; recalibrate with `bsv calibrate` or delete the entry") from exc


def frames_covariance(side: str, rotations: Sequence[np.ndarray], translations: Sequence[np.ndarray],
                      r_ref: np.ndarray, t_ref: np.ndarray) -> tuple[np.ndarray, str]:
    """(covariance, source) of a camera's extrinsics: the sample covariance of the per-frame camera-to-world
    poses about the result (r_ref, t_ref) with at least :data:`MIN_COVARIANCE_FRAMES` frames, else the
    paper's repeatability for ``side``."""
    from ..uncertainty import paper_covariance, pose_delta

    if len(rotations) < MIN_COVARIANCE_FRAMES:
        return paper_covariance(side), "paper default"
    d = np.array([pose_delta(r_ref, t_ref, r, t) for r, t in zip(rotations, translations, strict=True)])
    d = d - d.mean(axis=0)
    cov = d.T @ d / (len(d) - 1)
    return (cov + cov.T) / 2.0, "frames"


def read_calibration(path: PathLike) -> Calibration:
    """Reads calibration.json (as written by :meth:`Calibration.write` or the virtual scanner)."""
    p = Path(path)
    try:
        doc = json.loads(p.read_text())
    except OSError as e:
        raise CalibrationFileError(f"cannot read calibration file {p}: {e}") from e
    except json.JSONDecodeError as e:
        raise CalibrationFileError(f"{p} is not valid JSON ({e}); run `bsv calibrate` to write it") from e
    if not isinstance(doc, dict) or not isinstance(doc.get("cameras"), dict):
        raise CalibrationFileError(f"{p}: expected {{\"cameras\": {{\"front\": ..., \"back\": ...}}}}")
    cams = {}
    for name, c in doc["cameras"].items():
        try:
            r = np.asarray(c["camera_to_world"]["rotation"], dtype=np.float64).reshape(3, 3)
            t = np.asarray(c["camera_to_world"]["translation"], dtype=np.float64).reshape(3)
        except (KeyError, TypeError, ValueError) as e:
            raise CalibrationFileError(f"{p}: camera {name!r} lacks a valid camera_to_world rotation/translation") from e
        if not np.isfinite(r).all() or abs(np.linalg.det(r) - 1.0) > 1e-3:
            raise CalibrationFileError(f"{p}: camera {name!r} rotation is not a rotation matrix")
        cov, source = _read_covariance(c.get("extrinsics_covariance"), f"{p} camera {name!r}")
        bd = c.get("board_depth")
        cams[name] = CameraCalibration(name, Intrinsics.from_json(c.get("intrinsics"), f"{p} camera {name!r}"), r, t,
                                       serial=c.get("serial"), frames=int(c.get("frames", 0)), covariance=cov,
                                       covariance_source=source, board_depth=bd if isinstance(bd, dict) else None)
    m = doc.get("marker") or {}
    board = Board(MarkerSpec(m.get("dictionary", "DICT_ARUCO_ORIGINAL"), int(m.get("id", 336)), float(m.get("size_m", 0.16))),
                  float(m.get("centre_height_m", 1.0)), float(m.get("board_thickness_m", 0.005)),
                  float(m.get("board_x_m", 0.0)), float(m.get("board_z_m", 0.0)),
                  float(m.get("board_margin_m", BOARD_MARGIN_M)))
    return Calibration(cams, board)


# ----------------------------------------------------------------------------------------------------
# Calibration from frames


#: Largest distance (mm) and angle (deg) of one frame's camera pose from the calibrated pose: a still
#: board seen by a still camera repeats to well under a millimetre and 0.05 deg per frame.
MAX_FRAME_MM = 15.0
MAX_FRAME_DEG = 1.0


def _check_frames_agree(side: str, centres: Sequence[np.ndarray], rotations: Sequence[np.ndarray], max_mm: float,
                        max_deg: float) -> None:
    """Raises CalibrationError naming the frames whose camera pose departs from the frames' robust centre
    (the component-wise median camera centre; the medoid rotation), which a few bad frames cannot move."""
    c = np.asarray(centres)
    dev_mm = np.linalg.norm(c - np.median(c, axis=0), axis=1) * 1000.0
    angles = np.array([[rotation_angle_deg(a, b) for b in rotations] for a in rotations])
    dev_deg = angles[int(np.argmin(angles.sum(axis=1)))]
    bad = [i for i in range(len(dev_mm)) if dev_mm[i] > max_mm or dev_deg[i] > max_deg]
    if bad:
        worst = max(bad, key=lambda i: dev_mm[i] / max_mm + dev_deg[i] / max_deg)
        raise CalibrationError(
            f"{side}: frame(s) {', '.join(map(str, bad))} disagree with the others (frame {worst}: the camera "
            f"{dev_mm[worst]:.1f} mm / {dev_deg[worst]:.2f} deg away; limits {max_mm:g} mm / {max_deg:g} deg): "
            "a frame of the other camera or a board or camera that moved; remove those frames and calibrate again")


def calibrate_camera(
    images: Iterable[ImageLike],
    intrinsics: Intrinsics,
    side: str,
    board: Board = _DEFAULT_BOARD,
    *,
    serial: str | None = None,
    average: str = "image",
    max_edge_width_px: float = MAX_EDGE_WIDTH_PX,
    max_frame_mm: float = MAX_FRAME_MM,
    max_frame_deg: float = MAX_FRAME_DEG,
    depth: Sequence[DepthLike] | None = None,
    depth_scale: float = DEFAULT_DEPTH_SCALE,
) -> CameraCalibration:
    """Calibrates one camera (``side`` "front" or "back") from frames of the still board; every frame must
    show the marker (a frame without it raises, naming the frame).

    ``average="image"`` (default) estimates the pose from the mean of the frames (sensor noise averaged
    before the non-linear pose estimate); ``"pose"`` averages the per-frame poses (chordal mean rotation,
    mean translation). Either way the per-frame poses give the reported spread, and a frame whose camera
    pose lies more than ``max_frame_mm`` / ``max_frame_deg`` from the result (a frame of the other camera,
    a board that moved) is an error naming it, never averaged in.

    ``depth``: depth frames of the same still board, aligned to the colour frames (metres, or 16-bit
    units times ``depth_scale``); their per-pixel median refines the pose and its covariance
    (:func:`bsv.frontend.boardplane.refine_with_board`; BoardDepthError when they do not show the board).
    The update's prior is the paper's covariance, plus the frames' when there are enough frames (the frames'
    spread alone misses the colour pose's systematic errors that the depth corrects)."""
    if side not in SIDES:
        raise CalibrationError(f"unknown camera side {side!r}; expected one of {SIDES}")
    if average not in ("image", "pose"):
        raise CalibrationError(f"average must be 'image' or 'pose', got {average!r}")
    det = _detector(board.marker)
    rs, ts, errs, grays = [], [], [], []
    for i, img in enumerate(images):
        name = f"{side} frame {i}" + (f" ({img})" if isinstance(img, (str, Path)) else "")
        gray = _gray(img)
        if (gray.shape[1], gray.shape[0]) != (intrinsics.width, intrinsics.height):
            raise CalibrationError(f"{name}: image is {gray.shape[1]} x {gray.shape[0]} but the intrinsics are "
                                   f"{intrinsics.width} x {intrinsics.height}; use the colour stream's intrinsics")
        c = detect_marker(gray, board.marker, name=name, max_edge_width_px=max_edge_width_px, detector=det)
        r, t, e = marker_pose(c, intrinsics, board.marker)
        rs.append(r)
        ts.append(t)
        errs.append(e)
        grays.append(gray)
    if not rs:
        raise CalibrationError(f"{side}: no frames given; capture at least one image of the board")
    if average == "image" and len(grays) > 1:
        mean = np.mean(np.asarray(grays, dtype=np.float32), axis=0)
        c = detect_marker(np.clip(np.rint(mean), 0, 255).astype(np.uint8), board.marker, name=f"{side} mean frame",
                          max_edge_width_px=max_edge_width_px, detector=det)
        c = refine_corners(mean, c, board.marker)
        r_cm, t_cm, _ = marker_pose(c, intrinsics, board.marker)
    else:
        r_cm, t_cm = average_poses(rs, ts)
    r_wm, t_wm = board.marker_to_world(side)
    r_wc, t_wc = camera_to_world(r_cm, t_cm, r_wm, t_wm)
    poses = [camera_to_world(r, t, r_wm, t_wm) for r, t in zip(rs, ts, strict=True)]
    centres = [p[1] for p in poses]
    _check_frames_agree(side, centres, rs, max_frame_mm, max_frame_deg)
    cov, cov_source = frames_covariance(side, [p[0] for p in poses], centres, r_wc, t_wc)
    spread_mm = float(np.sqrt(np.mean(np.sum((np.asarray(centres) - t_wc) ** 2, axis=1)))) * 1000.0
    spread_deg = float(np.sqrt(np.mean([rotation_angle_deg(r, r_cm) ** 2 for r in rs])))
    board_depth = None
    if depth is not None:
        r_wc, t_wc, cov, cov_source, board_depth = refine_pose_with_depth(
            side, r_wc, t_wc, cov, cov_source, depth, intrinsics, board, depth_scale)
    return CameraCalibration(side, intrinsics, r_wc, t_wc, serial=serial, frames=len(rs),
                             reprojection_rms_px=float(np.sqrt(np.mean(np.square(errs)))),
                             spread_mm=spread_mm, spread_deg=spread_deg, covariance=cov, covariance_source=cov_source,
                             board_depth=board_depth)


def refine_pose_with_depth(side: str, rotation: np.ndarray, translation: np.ndarray, covariance: np.ndarray,
                           covariance_source: str, depth: Sequence[DepthLike], intrinsics: Intrinsics,
                           board: Board = _DEFAULT_BOARD, depth_scale: float = DEFAULT_DEPTH_SCALE
                           ) -> tuple[np.ndarray, np.ndarray, np.ndarray, str, dict[str, Any]]:
    """``bsv calibrate --depth`` for one camera whose colour calibration is done: the per-pixel median of
    the ``depth`` frames of the still board refines the camera-to-world pose and its covariance
    (:func:`bsv.frontend.boardplane.refine_with_board`). The update's prior is ``covariance`` plus the
    paper's when ``covariance_source`` is "frames" (the frames' spread holds only the image noise, not the
    systematic errors of a colour pose that the depth is there to correct: intrinsics, print size, corner
    bias), else ``covariance`` itself. Returns (rotation, translation, covariance, source suffixed
    :data:`BOARD_DEPTH_SOURCE`, the ``board_depth`` report). BoardDepthError when the depth does not show
    the board."""
    from ..uncertainty import paper_covariance
    from .boardplane import median_depth, refine_with_board

    dm = median_depth([load_depth(d, depth_scale, f"{side} depth frame {i}") for i, d in enumerate(depth)])
    prior = covariance + paper_covariance(side) if covariance_source == "frames" else covariance
    ref = refine_with_board(rotation, translation, prior, dm, intrinsics, board, side)
    return (ref.rotation, ref.translation, ref.covariance, covariance_source + BOARD_DEPTH_SOURCE,
            {"frames": len(depth), **ref.report()})


def load_depth(depth: DepthLike, scale: float = DEFAULT_DEPTH_SCALE, name: str = "depth") -> np.ndarray:
    """A depth image in metres (float64, 0 = no depth): a float array is taken as metres, a uint16 array or
    a 16-bit PNG as units of ``scale`` metres. Raises CalibrationFileError for an unreadable or 8-bit file."""
    img = _read_unchanged(depth, "depth image")
    if img.ndim != 2:
        raise CalibrationFileError(f"{name}: a depth image has one channel, got shape {img.shape}")
    if img.dtype == np.uint16:
        if not 0 < scale < 1:
            raise CalibrationError(f"depth scale {scale} must be metres per depth unit, e.g. 0.00025 (L515)")
        return img.astype(np.float64) * scale
    if np.issubdtype(img.dtype, np.floating):
        return np.where(np.isfinite(img), img, 0.0).astype(np.float64)
    raise CalibrationFileError(f"{name}: depth must be 16-bit (PNG) or float metres, got {img.dtype}; save the "
                               "depth stream as 16-bit PNG")


def calibrate(
    images: Mapping[str, Iterable[ImageLike]],
    intrinsics: Mapping[str, Intrinsics],
    board: Board = _DEFAULT_BOARD,
    *,
    serials: Mapping[str, str] | None = None,
    out: PathLike | None = None,
    overwrite: bool = False,
    depth: Mapping[str, Sequence[DepthLike]] | None = None,
    depth_scale: Mapping[str, float] | None = None,
) -> Calibration:
    """Calibrates every camera of ``images`` ({"front": frames, "back": frames}) and optionally writes
    calibration.json to ``out`` (an existing file is refused before any work, :class:`bsv.errors.OutputExistsError`,
    unless ``overwrite``). ``depth``: per camera, depth frames of the board for the refinement
    (:func:`calibrate_camera`), in units of ``depth_scale[camera]`` (default :data:`DEFAULT_DEPTH_SCALE`)."""
    if out is not None and Path(out).exists() and not overwrite:
        raise OutputExistsError(f"{out} already exists; pass overwrite=True (--overwrite) to replace it")
    unknown = sorted(set(depth or {}) - set(images))
    if unknown:
        raise CalibrationError(f"depth given for camera(s) {unknown} without colour images of the board")
    cams = {}
    for side, frames in images.items():
        if side not in intrinsics:
            raise CalibrationError(f"no intrinsics given for camera {side!r}; pass them from the device or a file")
        cams[side] = calibrate_camera(frames, intrinsics[side], side, board,
                                      serial=None if serials is None else serials.get(side),
                                      depth=None if depth is None else depth.get(side),
                                      depth_scale=(depth_scale or {}).get(side, DEFAULT_DEPTH_SCALE))
    cal = Calibration(cams, board)
    if out is not None:
        cal.write(out, overwrite=overwrite)
    return cal


def image_files(folder: PathLike) -> list[Path]:
    """The PNG/JPEG images of a folder, sorted by name (raises if there are none)."""
    d = Path(folder)
    files = sorted(p for p in d.iterdir() if p.suffix.lower() in (".png", ".jpg", ".jpeg", ".bmp")) if d.is_dir() else []
    if not files:
        raise CalibrationFileError(f"{d}: no PNG/JPEG images of the calibration board found")
    return files


def depth_files(folder: PathLike, default_scale: float | None = None) -> tuple[list[Path], float]:
    """The 16-bit depth PNGs of a folder, sorted by name, and their depth scale: ``default_scale`` when
    given, else the folder's ``camera.json`` ``depth_scale`` (as ``bsv capture`` and the virtual rig write
    it), else :data:`DEFAULT_DEPTH_SCALE`. A capture folder's camera.json that names its ``depth`` image
    selects that one file. Raises CalibrationFileError when there are none."""
    d = Path(folder)
    doc: dict[str, Any] = {}
    meta = d / "camera.json"
    if meta.is_file():
        try:
            doc = json.loads(meta.read_text())
            if not isinstance(doc, dict):
                raise TypeError("not a JSON object")
        except (OSError, ValueError, TypeError) as e:
            raise CalibrationFileError(f"{meta}: unreadable ({e}); remove it or fix it") from e
    if isinstance(doc.get("depth"), str):
        files = [d / doc["depth"]]
    else:
        files = sorted(p for p in d.iterdir() if p.suffix.lower() == ".png") if d.is_dir() else []
    if not files:
        raise CalibrationFileError(f"{d}: no 16-bit depth PNGs of the calibration board found")
    scale = default_scale
    if scale is None and "depth_scale" in doc:
        try:
            scale = float(doc["depth_scale"])
        except (TypeError, ValueError) as e:
            raise CalibrationFileError(f"{meta}: depth_scale is not a number ({e}); pass --depth-scale") from e
    return files, DEFAULT_DEPTH_SCALE if scale is None else scale


# ----------------------------------------------------------------------------------------------------
# Live alignment


@dataclass(frozen=True)
class Alignment:
    """What a camera must still do to face the marker squarely (see :func:`alignment`)."""

    yaw_deg: float
    shift_m: float
    pitch_deg: float
    roll_deg: float
    distance_m: float
    height_m: float
    aligned: bool

    def lines(self) -> list[str]:
        """Human-readable instructions for the live window."""
        turn = "left" if self.yaw_deg > 0 else "right"
        move = "right" if self.shift_m > 0 else "left"
        out = [
            f"turn {turn} {abs(self.yaw_deg):.2f} deg (about the vertical)",
            f"move {move} {abs(self.shift_m) * 100:.1f} cm (transversal)",
            f"distance {self.distance_m:.3f} m  pitch {self.pitch_deg:+.2f} deg  roll {self.roll_deg:+.2f} deg",
        ]
        if self.aligned:
            out.append("ALIGNED")
        return out


def alignment(r_cm: np.ndarray, t_cm: np.ndarray, *, yaw_tol_deg: float = 0.5, shift_tol_m: float = 0.005) -> Alignment:
    """The rotation about the vertical and the transversal translation the camera must still undergo to
    face the marker (optical axis through the marker centre, perpendicular to it), from the marker-to-camera
    pose. Marker frame: x to the viewer's right, y up, z toward the viewer.

    ``yaw_deg`` > 0: turn left (counter-clockwise seen from above); ``shift_m`` > 0: move to the right (as
    seen from the camera), along the marker's horizontal axis. ``pitch_deg`` > 0: the camera looks up;
    ``roll_deg``: rotation about the optical axis; ``height_m``: camera height above the marker centre.
    ``aligned`` when |yaw| <= yaw_tol_deg and |shift| <= shift_tol_m."""
    r = np.asarray(r_cm, dtype=np.float64)
    t = np.asarray(t_cm, dtype=np.float64).reshape(3)
    centre = -r.T @ t  # camera centre in the marker frame
    axis = r.T @ np.array([0.0, 0.0, 1.0])  # optical axis in the marker frame
    down = r.T @ np.array([0.0, 1.0, 0.0])  # image down in the marker frame
    yaw = math.degrees(math.atan2(axis[0], -axis[2]))
    pitch = math.degrees(math.atan2(axis[1], math.hypot(axis[0], axis[2])))
    # roll: angle of the image-down direction from the marker's -y, seen along the optical axis.
    roll = math.degrees(math.atan2(down[0] * -axis[2] + down[2] * axis[0], -down[1])) if abs(axis[1]) < 0.99 else 0.0
    shift = -float(centre[0])
    return Alignment(yaw, shift, pitch, roll, float(np.linalg.norm(t)), float(centre[1]),
                     abs(yaw) <= yaw_tol_deg and abs(shift) <= shift_tol_m)


def draw_alignment(image: np.ndarray, corners: np.ndarray | None, info: Alignment | None, marker: MarkerSpec
                   ) -> np.ndarray:
    """Colour image with the detected marker outlined and the alignment instructions written on it."""
    cv2 = require("cv2")

    out = image.copy() if image.ndim == 3 else cv2.cvtColor(image, cv2.COLOR_GRAY2BGR)
    scale = max(out.shape[1] / 1000.0, 0.5)
    if corners is None or info is None:
        cv2.putText(out, f"marker {marker.marker_id} not found", (20, int(40 * scale)), cv2.FONT_HERSHEY_SIMPLEX,
                    scale, (0, 0, 255), 2)
        return out
    cv2.polylines(out, [np.round(corners).astype(np.int32).reshape(-1, 1, 2)], True, (0, 255, 0), 2)
    cv2.line(out, (out.shape[1] // 2, 0), (out.shape[1] // 2, out.shape[0]), (255, 255, 0), 1)
    for i, line in enumerate(info.lines()):
        colour = (0, 200, 0) if line == "ALIGNED" else (0, 255, 255)
        big = 2.0 if line == "ALIGNED" else 1.0
        cv2.putText(out, line, (20, int((40 + 40 * i) * scale * (1 if i < 3 else 1.2))), cv2.FONT_HERSHEY_SIMPLEX,
                    scale * big, colour, 2 if big == 1.0 else 4)
    return out


def live(serial: str | None = None, board: Board = _DEFAULT_BOARD, *, side: str = "front", width: int = 1920,
         height: int = 1080, fps: int = 30, yaw_tol_deg: float = 0.5, shift_tol_m: float = 0.005) -> None:
    """Live view of one RealSense camera's colour stream with the detected marker and the remaining yaw and
    transversal shift to face it, ALIGNED within tolerance; Esc or q quits. (Exercised by hand only.)"""
    cv2 = require("cv2")

    from .capture import import_realsense, open_colour_stream

    rs = import_realsense()
    pipe, intr = open_colour_stream(rs, serial, width, height, fps)
    det = _detector(board.marker)
    try:
        while True:
            frames = pipe.wait_for_frames()
            colour = np.asanyarray(frames.get_color_frame().get_data())
            bgr = cv2.cvtColor(colour, cv2.COLOR_RGB2BGR)
            try:
                c = detect_marker(bgr, board.marker, detector=det)
                r, t, _ = marker_pose(c, intr, board.marker)
                info: Alignment | None = alignment(r, t, yaw_tol_deg=yaw_tol_deg, shift_tol_m=shift_tol_m)
            except CalibrationError:
                c, info = None, None
            cv2.imshow(f"bsv calibrate --live ({side})", draw_alignment(bgr, c, info, board.marker))
            if cv2.waitKey(1) & 0xFF in (27, ord("q")):
                break
    finally:
        pipe.stop()
        cv2.destroyAllWindows()


# ----------------------------------------------------------------------------------------------------
# Command line


def _pairs(items: Sequence[str], what: str) -> dict[str, str]:
    out = {}
    for it in items:
        if "=" not in it:
            raise SystemExit(f"--{what} expects CAMERA=PATH (e.g. front=calib/front), got {it!r}")
        k, v = it.split("=", 1)
        out[k] = v
    return out


def main(argv: Sequence[str] | None = None) -> int:
    """``bsv calibrate``: offline from saved images (``--images front=DIR back=DIR --intrinsics ...``) or
    ``--live`` alignment view of one camera."""
    ap = argparse.ArgumentParser(prog="bsv calibrate", description=__doc__.split("\n")[0])
    ap.add_argument("--images", nargs="*", default=[], help="CAMERA=DIR of board images (offline mode)")
    ap.add_argument("--intrinsics", nargs="*", default=[], help="CAMERA=JSON intrinsics file (capture intrinsics.json, "
                    "camera.json or calibration.json)")
    ap.add_argument("--serial", nargs="*", default=[], help="CAMERA=SERIAL (stored; live mode uses it)")
    ap.add_argument("--dictionary", default="DICT_ARUCO_ORIGINAL")
    ap.add_argument("--marker-id", type=int, default=336)
    ap.add_argument("--marker-size", type=float, default=0.16, help="printed marker side, metres")
    ap.add_argument("--marker-height", type=float, default=1.0, help="marker centre height above the floor, metres")
    ap.add_argument("--board-thickness", type=float, default=0.005, help="metres")
    ap.add_argument("--depth", nargs="*", default=[], help="CAMERA=DIR of 16-bit depth PNGs of the board, aligned "
                    "to colour: refines each camera's pose and covariance with the board face's plane")
    ap.add_argument("--depth-scale", type=float, default=None, help="metres per depth unit (default: DIR/camera.json's "
                    f"depth_scale, else {DEFAULT_DEPTH_SCALE}, the L515's)")
    ap.add_argument("-o", "--out", default="calibration.json")
    ap.add_argument("--overwrite", action="store_true")
    ap.add_argument("--live", metavar="CAMERA", help="live alignment window for this camera (front/back)")
    a = ap.parse_args(argv)
    board = Board(MarkerSpec(a.dictionary, a.marker_id, a.marker_size), a.marker_height, a.board_thickness)
    serials = _pairs(a.serial, "serial")
    if a.live:
        live(serials.get(a.live), board, side=a.live)
        return 0
    dirs = _pairs(a.images, "images")
    if not dirs:
        raise SystemExit("give --images front=DIR back=DIR (offline) or --live CAMERA")
    files = {k: image_files(v) for k, v in dirs.items()}
    intr_files = _pairs(a.intrinsics, "intrinsics")
    intr = {k: load_intrinsics(intr_files[k], k) if k in intr_files else _missing(k) for k in files}
    depth_dirs = _pairs(a.depth, "depth")
    depth = {k: depth_files(v, a.depth_scale) for k, v in depth_dirs.items()}
    cal = calibrate(files, intr, board, serials=serials, out=a.out, overwrite=a.overwrite,
                    depth={k: f for k, (f, _) in depth.items()}, depth_scale={k: sc for k, (_, sc) in depth.items()})
    for k, c in cal.cameras.items():
        print(f"{k}: centre {np.round(c.translation, 4).tolist()} m, {c.frames} frames, reprojection "
              f"{c.reprojection_rms_px:.3f} px, spread {c.spread_mm:.2f} mm / {c.spread_deg:.3f} deg")
        if c.covariance is not None:
            sd = np.sqrt(np.diag(c.covariance))
            print(f"{k}: extrinsics covariance ({c.covariance_source}): 1 sd translation "
                  f"{np.round(sd[:3] * 1000, 3).tolist()} mm, rotation {np.round(np.degrees(sd[3:]), 3).tolist()} deg")
        if c.board_depth is not None:
            b = c.board_depth
            print(f"{k}: board depth: {b['points']} points, plane rms {b['rms_mm']:.2f} mm, colour pose off by "
                  f"{b['tilt_deg']:.3f} deg; moved {b['depth_mm']:+.2f} mm toward the board, turned "
                  f"{np.round(b['rotation_world_deg'], 3).tolist()} deg")
    print(f"wrote {a.out}")
    return 0


def _missing(k: str) -> Intrinsics:
    raise CalibrationFileError(f"no --intrinsics {k}=FILE given for camera {k!r}")


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())

"""Refining a camera's extrinsics with the depth it measures on the calibration board's face.

The colour calibration (:mod:`bsv.frontend.calibrate`: ArUco + solvePnP) is least certain along the
optical axis (the back camera's 3.4 mm depth SD of the paper) and in the two tilts about axes in the
board plane (its 0.28 deg yaw). The board is flat, of known size and thickness, and each camera sees
one face in its depth image (RealSense depth aligned to colour), so:

1. the board face's square (:meth:`bsv.frontend.marker.Board.face_corners`, moved :data:`EDGE_INSET_M`
   inward, clear of the edge's flying pixels) is projected with the colour pose into the depth image;
2. a plane is fitted to the camera-frame points of the valid depth pixels inside it by total least
   squares (started from the points near the region's median depth, :data:`START_BAND_MAD`), refitted
   on the points within max(3 robust sigmas, :data:`MIN_THRESHOLD_M`) of the last fit
   (the marker's print, flying pixels and a hand holding the board drop out); its covariance (two tilts
   and the offset) comes from the residuals;
3. the pose is updated so that the plane lands on the face's world plane (the face is ``thickness / 2``
   from the board's mid-plane, :class:`Board`): a Gaussian (iterated Kalman) update of the 6 extrinsic
   parameters with the calibration's covariance as the prior and the plane's covariance plus
   :data:`bsv.uncertainty.BOARD_STD` as the measurement noise, so the depth corrects what it measures
   better than the colour pose did (the back camera's depth and yaw) and no more.

That fixes the camera's distance to the board and its two tilts about axes in the board plane (for the
upright board: yaw and pitch); the rotation about the board normal and the translations in the board
plane stay from PnP (unless the prior correlates them with the measured ones). The covariance is the
update's posterior (:func:`bsv.uncertainty.condition`): only the constrained directions shrink. Combined with the floor (:mod:`bsv.frontend.floorplane`: height,
pitch, roll), only the lateral position is left as PnP measured it.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..extras import require
from .errors import BoardDepthError
from .intrinsics import Intrinsics
from .marker import Board

#: The depth pixels used stay this far inside the board face's edges (metres): the colour pose puts the
#: edges within a few pixels, and the silhouette's flying pixels sit there.
EDGE_INSET_M: float = 0.02
#: Fewest valid depth points on the board a refinement needs, and the least fraction of the board
#: region's pixels that must hold a valid depth.
MIN_BOARD_POINTS: int = 200
MIN_VALID_FRACTION: float = 0.5
#: Least inlier distance of the robust fit (metres): the L515's depth noise at 2 m is ~1-2 mm.
MIN_THRESHOLD_M: float = 0.003
#: The robust fit starts from the points within this many robust sigmas (1.4826 MAD) of the region's median
#: depth, and never a narrower band than :data:`START_BAND_MIN_M`: clear of far outliers (flying pixels,
#: the wall through a gap), wide enough for a noisy or tilted board (a 45 deg tilt spreads the face's depth
#: over +-8 cm, MAD ~4 cm).
START_BAND_MAD: float = 5.0
START_BAND_MIN_M: float = 0.02
#: Largest disagreement accepted between the depth plane and the colour (PnP) plane: a larger one means a
#: wrong depth scale, depth not aligned to colour, or another scene (PnP is good to a few mm / tenths of
#: a degree).
MAX_BOARD_OFFSET_M: float = 0.025
MAX_BOARD_TILT_DEG: float = 3.0


@dataclass(frozen=True)
class BoardPlane:
    """A plane fitted to a board face in a camera's depth: ``normal . p = offset_m`` (camera frame, the
    normal toward the camera, so ``offset_m`` < 0), with the 3 x 3 ``covariance`` of (tilt about
    ``basis[0]``, tilt about ``basis[1]`` (radians; the two unit vectors span the plane), offset (m))."""

    normal: np.ndarray
    offset_m: float
    basis: np.ndarray
    covariance: np.ndarray
    #: Inlier points of the final fit, valid depth pixels in the region, pixels in the region.
    points: int
    valid: int
    region: int
    #: RMS distance of the inliers to the plane (mm).
    rms_mm: float


@dataclass(frozen=True)
class BoardRefinement:
    """A camera's camera-to-world pose and extrinsics covariance refined by the board's depth."""

    rotation: np.ndarray
    translation: np.ndarray
    covariance: np.ndarray
    plane: BoardPlane
    #: How far the colour pose was off, as the depth says: the angle between the depth and the colour
    #: planes (deg); the applied correction: the camera's move along the board normal (mm, + toward the
    #: board's face) and its rotation as a world rotation vector (deg).
    tilt_deg: float
    depth_mm: float
    rotation_deg: tuple[float, float, float]

    def report(self) -> dict[str, Any]:
        """JSON-ready summary (calibration.json ``board_depth``)."""
        return {"points": self.plane.points, "valid_pixels": self.plane.valid, "region_pixels": self.plane.region,
                "rms_mm": self.plane.rms_mm, "tilt_deg": self.tilt_deg, "depth_mm": self.depth_mm,
                "rotation_world_deg": list(self.rotation_deg),
                "plane_sd": {"tilt_deg": [math.degrees(math.sqrt(self.plane.covariance[i, i])) for i in (0, 1)],
                             "offset_mm": math.sqrt(self.plane.covariance[2, 2]) * 1000.0}}


def board_region(rotation: np.ndarray, translation: np.ndarray, intrinsics: Intrinsics, board: Board, side: str,
                 inset_m: float = EDGE_INSET_M) -> np.ndarray:
    """Boolean (height, width) mask of the pixels inside the board face (moved ``inset_m`` inward) as the
    camera-to-world pose (``rotation``, ``translation``) projects it."""
    cv2 = require("cv2")

    r = np.asarray(rotation, dtype=np.float64)
    cam = (board.face_corners(side, inset_m) - np.asarray(translation, dtype=np.float64)) @ r
    if (cam[:, 2] <= 0.05).any():
        raise BoardDepthError(f"{side}: the calibrated pose puts the board face behind the camera; "
                              "the colour calibration is not of this camera")
    px, _ = cv2.projectPoints(cam, np.zeros(3), np.zeros(3), intrinsics.matrix, intrinsics.dist)
    mask = np.zeros((int(intrinsics.height), int(intrinsics.width)), np.uint8)
    cv2.fillConvexPoly(mask, np.round(px.reshape(-1, 2) * 16).astype(np.int32), 1, lineType=cv2.LINE_8, shift=4)
    return mask.astype(bool)


def _tangent_basis(n: np.ndarray) -> np.ndarray:
    """Two unit vectors spanning the plane perpendicular to ``n`` (2 x 3)."""
    a = np.eye(3)[int(np.argmin(np.abs(n)))]
    u1 = np.cross(n, a)
    u1 /= np.linalg.norm(u1)
    return np.array([u1, np.cross(n, u1)])


def fit_board_plane(depth_m: np.ndarray, intrinsics: Intrinsics, region: np.ndarray, *, name: str = "camera",
                    iterations: int = 8) -> BoardPlane:
    """Robust plane (module doc, step 2) of the depth pixels in ``region``. Raises BoardDepthError when the
    depth image does not match the intrinsics or too few valid pixels show the board."""
    from .floorplane import deproject

    d = np.asarray(depth_m, dtype=np.float64)
    if d.shape != (int(intrinsics.height), int(intrinsics.width)):
        raise BoardDepthError(f"{name}: depth image is {d.shape[1]} x {d.shape[0]} but the colour intrinsics are "
                              f"{intrinsics.width} x {intrinsics.height}; record depth aligned to colour")
    reg = np.asarray(region, dtype=bool)
    n_region = int(reg.sum())
    p = deproject(d, intrinsics, reg, step=1)
    need = max(MIN_BOARD_POINTS, math.ceil(MIN_VALID_FRACTION * n_region))
    if len(p) < need:
        raise BoardDepthError(
            f"{name}: only {len(p)} valid depth pixels on the board ({n_region} pixels in its region, need {need}): "
            "the depth image does not show the board; record depth aligned to colour, with the board in view "
            "and within the depth camera's range")
    # A total-least-squares start on every point is not robust: a few flying pixels far behind the board
    # (an L515's at the face's edge, toward a wall 2-3 m further) tilt the first plane by tens of degrees
    # and the trimming, scaled by that plane's residuals, never recovers. Start from the points near the
    # median depth instead (the board fills the region; its own depth spread, noise or tilt, sets the band).
    z = p[:, 2]
    med = float(np.median(z))
    keep = np.abs(z - med) <= max(START_BAND_MAD * 1.4826 * float(np.median(np.abs(z - med))), START_BAND_MIN_M)
    n, e = np.array([0.0, 0.0, -1.0]), 0.0
    for _ in range(iterations):
        if keep.sum() < MIN_BOARD_POINTS:
            break
        c = p[keep].mean(axis=0)
        _, _, vt = np.linalg.svd(p[keep] - c, full_matrices=False)
        n = vt[2] if vt[2] @ c < 0 else -vt[2]  # toward the camera
        e = float(n @ c)
        res = np.abs(p @ n - e)
        sigma = 1.4826 * float(np.median(res[keep]))
        new = res <= max(3.0 * sigma, MIN_THRESHOLD_M)
        if (new == keep).all():
            break
        keep = new
    k = int(keep.sum())
    if k < max(MIN_BOARD_POINTS, len(p) // 2):
        raise BoardDepthError(f"{name}: only {k} of {len(p)} depth points on the board lie on one plane; the depth "
                              "image does not show a flat board face there (something in front of it, or misaligned)")
    q = p[keep]
    basis = _tangent_basis(n)
    res = q @ n - e
    jac = np.column_stack([q @ basis[0], q @ basis[1], -np.ones(k)])
    s2 = float(res @ res) / max(k - 3, 1)
    cov = s2 * np.linalg.inv(jac.T @ jac)
    return BoardPlane(n, e, basis, (cov + cov.T) / 2.0, k, len(p), n_region,
                      float(np.sqrt(np.mean(res**2))) * 1000.0)


def plane_rows(rotation: np.ndarray, face_normal: np.ndarray, basis: np.ndarray,
               base_rotation: np.ndarray | None = None) -> np.ndarray:
    """The 3 x 6 rows of what a board plane measures, in :data:`bsv.uncertainty.PARAMETERS`: the plane's two
    tilts about ``basis`` (camera frame) depend on rotations about ``basis[k] x m`` and its offset on the
    translation along ``-m``, with ``m`` the face's world normal in the camera frame of ``rotation``; the
    translation part is in the frame of ``base_rotation`` (default ``rotation``), the pose that the
    parameters are composed on (``t' = R_base t_delta + t``)."""
    n = np.asarray(face_normal, dtype=np.float64)
    m = np.asarray(rotation, dtype=np.float64).T @ n
    a = np.zeros((3, 6))
    a[0, 3:] = np.cross(basis[0], m)
    a[1, 3:] = np.cross(basis[1], m)
    a[2, :3] = -(m if base_rotation is None else np.asarray(base_rotation, dtype=np.float64).T @ n)
    return a


def refine_with_board(rotation: np.ndarray, translation: np.ndarray, covariance: np.ndarray, depth_m: np.ndarray,
                      intrinsics: Intrinsics, board: Board, side: str, *, name: str | None = None,
                      inset_m: float = EDGE_INSET_M, std: Sequence[float] | None = None) -> BoardRefinement:
    """The camera-to-world pose and its 6 x 6 covariance refined by the board face seen in ``depth_m``
    (metres, aligned to the colour image of ``intrinsics``; module doc). ``std``: the systematic allowance
    (default :data:`bsv.uncertainty.BOARD_STD`). Raises BoardDepthError when the depth does not show the
    board or its plane is more than :data:`MAX_BOARD_TILT_DEG` / :data:`MAX_BOARD_OFFSET_M` from the
    colour pose's."""
    from ..uncertainty import BOARD_STD, check_covariance, condition, perturb, rotation_vector

    who = name or side
    r = np.asarray(rotation, dtype=np.float64)
    t = np.asarray(translation, dtype=np.float64)
    prior = check_covariance(covariance, f"{who} extrinsics")
    plane = fit_board_plane(depth_m, intrinsics, board_region(r, t, intrinsics, board, side, inset_m), name=who)
    r_wm, t_wm = board.marker_to_world(side)
    n_w = r_wm[:, 2]  # the face's outward normal, toward its camera
    e_w = float(n_w @ t_wm)
    # where the colour pose puts the face, in the camera frame
    m = r.T @ n_w
    e_pred = e_w - float(n_w @ t)
    tilt = math.degrees(math.acos(float(np.clip(m @ plane.normal, -1.0, 1.0))))
    off = plane.offset_m - e_pred
    if tilt > MAX_BOARD_TILT_DEG or abs(off) > MAX_BOARD_OFFSET_M:
        ratio = plane.offset_m / e_pred if e_pred != 0 else float("nan")
        hint = (f"; the depth says the board is {ratio:.2f} x as far as the colour does: a wrong depth scale?"
                if abs(ratio - 1.0) > 0.05 else "")
        raise BoardDepthError(
            f"{who}: the board plane in depth is {tilt:.2f} deg / {off * 1000:+.1f} mm from where the colour "
            f"calibration puts it (limits {MAX_BOARD_TILT_DEG} deg / {MAX_BOARD_OFFSET_M * 1000:.0f} mm): a wrong "
            f"depth scale, depth not aligned to colour, or a depth image of another scene{hint}")
    # Gaussian update of the pose (iterated: re-linearised at the updated pose) with the prior covariance
    # and the plane's: the depth wins where it is the more precise (the back camera's depth and yaw), the
    # colour pose where it is (a front camera's sub-0.03 deg tilts against a noisy depth image)
    noise = plane.covariance + np.diag(np.square(np.asarray(BOARD_STD if std is None else std, dtype=np.float64)))
    delta = np.zeros(6)
    for _ in range(4):
        r_k, t_k = perturb(r, t, delta)
        m_k = r_k.T @ n_w
        h = np.array([plane.basis[0] @ m_k, plane.basis[1] @ m_k, e_w - float(n_w @ t_k)])
        z = np.array([0.0, 0.0, plane.offset_m])  # the basis is perpendicular to the fitted normal
        a = plane_rows(r_k, n_w, plane.basis, r)
        gain, post = condition(prior, a, noise)
        delta = gain @ (z - h + a @ delta)
    r_new, t_new = perturb(r, t, delta)
    rv = np.degrees(rotation_vector(r_new @ r.T))
    return BoardRefinement(r_new, t_new, post, plane, tilt, float(n_w @ (t - t_new)) * 1000.0,
                           (float(rv[0]), float(rv[1]), float(rv[2])))


def median_depth(frames: Sequence[np.ndarray]) -> np.ndarray:
    """Per-pixel median (metres) of the valid values of several depth frames of a still board (0 where no
    frame has one): averages the sensor noise and drops a frame's flying pixels."""
    if not frames:
        raise BoardDepthError("no depth frames given")
    stack = np.asarray([np.asarray(f, dtype=np.float64) for f in frames])
    if stack.ndim != 3:
        raise BoardDepthError(f"depth frames must be 2-D images of one size, got shape {stack.shape}")
    if len(stack) == 1:
        return stack[0]
    stack[~(stack > 0) | ~np.isfinite(stack)] = np.nan
    valid = np.isfinite(stack).any(axis=0)
    out = np.zeros(stack.shape[1:])
    out[valid] = np.nanmedian(stack[:, valid], axis=0)
    return out

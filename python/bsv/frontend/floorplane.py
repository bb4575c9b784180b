"""Refining a camera's extrinsics with the floor it sees: the floor plane fixes pitch, roll and height.

The world floor is the plane y = 0 (DESIGN.md's world frame). A camera whose calibration is slightly off
sees the floor, through that calibration, as a plane tilted by its pitch/roll error and shifted by its
height error. :func:`refine_with_floor` deprojects the camera's depth image (OpenCV undistortion of the
pixel grid), keeps the non-person pixels that the current calibration puts near the floor, fits a plane
by least squares with iterative trimming (3 robust sigmas: the wall's base, feet shadows and flying pixels
drop out), and rotates the camera about its own centre so that the plane's normal becomes vertical, then
lifts it so that the plane becomes y = 0. Yaw and horizontal translation are not observable from a
horizontal plane and stay as calibrated.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from .errors import CalibrationError
from .intrinsics import Intrinsics

#: Pixels whose world height (current calibration) is within this band of y = 0 are floor candidates.
FLOOR_BAND_M: float = 0.05
#: Fewest floor points a refinement needs.
MIN_FLOOR_POINTS: int = 500
#: Largest correction accepted (a larger one means the floor fit found something else, or a bad calibration).
MAX_TILT_DEG: float = 2.0
MAX_HEIGHT_M: float = 0.03


@dataclass(frozen=True)
class FloorRefinement:
    """A camera's refined camera-to-world pose and the correction applied."""

    rotation: np.ndarray
    translation: np.ndarray
    #: Correction angles about the world x and z axes (degrees) and the lift (mm).
    tilt_x_deg: float
    tilt_z_deg: float
    height_mm: float
    #: Floor points used in the final fit and their RMS distance to the plane (mm).
    points: int
    rms_mm: float


def deproject(depth_m: np.ndarray, intrinsics: Intrinsics, keep: np.ndarray | None = None, step: int = 2) -> np.ndarray:
    """Camera-frame points (N, 3) of the valid depth pixels (every ``step``-th row and column, ``keep`` mask)."""
    import cv2

    d = np.asarray(depth_m, dtype=np.float64)
    vv, uu = np.mgrid[0:d.shape[0]:step, 0:d.shape[1]:step]
    z = d[vv, uu]
    ok = (z > 0) & np.isfinite(z)
    if keep is not None:
        ok &= np.asarray(keep, dtype=bool)[vv, uu]
    px = np.column_stack([uu[ok], vv[ok]]).astype(np.float64).reshape(-1, 1, 2)
    if len(px) == 0:
        return np.zeros((0, 3))
    norm = cv2.undistortPoints(px, intrinsics.matrix, intrinsics.dist).reshape(-1, 2)
    zz = z[ok]
    return np.column_stack([norm[:, 0] * zz, norm[:, 1] * zz, zz])


def fit_plane(points: np.ndarray, iterations: int = 6, min_threshold_m: float = 0.004) -> tuple[np.ndarray, float, np.ndarray]:
    """(unit normal n with n_y >= 0, offset d, inlier mask) of the plane ``n . p + d = 0``: total least
    squares (SVD), refitted on the points within max(3 robust sigmas, ``min_threshold_m``) of the last fit."""
    p = np.asarray(points, dtype=np.float64)
    keep = np.ones(len(p), dtype=bool)
    n, d = np.array([0.0, 1.0, 0.0]), 0.0
    for _ in range(iterations):
        if keep.sum() < 3:
            raise CalibrationError("floor plane: fewer than 3 points left to fit")
        c = p[keep].mean(axis=0)
        _, _, vt = np.linalg.svd(p[keep] - c, full_matrices=False)
        n = vt[2] if vt[2][1] >= 0 else -vt[2]
        d = -float(n @ c)
        r = np.abs(p @ n + d)
        sigma = 1.4826 * float(np.median(r[keep]))
        keep = r <= max(3.0 * sigma, min_threshold_m)
    return n, d, keep


def refine_with_floor(rotation: np.ndarray, translation: np.ndarray, depth_m: np.ndarray, intrinsics: Intrinsics,
                      person: np.ndarray | None = None, *, name: str = "camera") -> FloorRefinement:
    """The camera-to-world pose corrected by the floor the camera sees (module doc). ``person``: pixels to
    ignore (the person mask). Raises CalibrationError when the floor is not seen or the correction would
    exceed :data:`MAX_TILT_DEG` / :data:`MAX_HEIGHT_M`."""
    from ..uncertainty import rodrigues

    r = np.asarray(rotation, dtype=np.float64)
    t = np.asarray(translation, dtype=np.float64)
    keep = None if person is None else ~np.asarray(person, dtype=bool)
    world = deproject(depth_m, intrinsics, keep) @ r.T + t
    cand = world[np.abs(world[:, 1]) < FLOOR_BAND_M]
    if len(cand) < MIN_FLOOR_POINTS:
        raise CalibrationError(f"{name}: only {len(cand)} depth points near the floor (need {MIN_FLOOR_POINTS}); "
                               "the camera must see the floor in front of the subject to refine its calibration")
    n, d, inl = fit_plane(cand)
    axis = np.cross(n, [0.0, 1.0, 0.0])
    s = float(np.linalg.norm(axis))
    angle = math.atan2(s, float(n[1]))
    r_c = rodrigues(axis / s * angle) if s > 1e-15 else np.eye(3)
    lift = d + float(n @ t) - t[1]
    vec = axis / s * angle if s > 1e-15 else np.zeros(3)
    if math.degrees(angle) > MAX_TILT_DEG or abs(lift) > MAX_HEIGHT_M:
        raise CalibrationError(
            f"{name}: the floor says the calibration is off by {math.degrees(angle):.2f} deg / {lift * 1000:+.0f} mm "
            f"(limits {MAX_TILT_DEG} deg / {MAX_HEIGHT_M * 1000:.0f} mm): recalibrate, or check that the floor is level")
    rms = float(np.sqrt(np.mean((cand[inl] @ n + d) ** 2))) * 1000.0
    return FloorRefinement(r_c @ r, t + np.array([0.0, lift, 0.0]), math.degrees(vec[0]), math.degrees(vec[2]),
                           lift * 1000.0, int(inl.sum()), rms)


def refine_extrinsics(name: str, extrinsics: dict[str, Any], depth_m: np.ndarray, intrinsics: Intrinsics,
                      person: np.ndarray | None) -> tuple[dict[str, Any], dict[str, Any]]:
    """``bsv process --refine-floor`` for one camera: its extrinsics entry (rotation, translation,
    covariance; the paper's when none) refined by the floor, the covariance conditioned on what the floor
    measured (:func:`bsv.uncertainty.condition_on_floor`), and a JSON-ready report of the correction."""
    from ..uncertainty import condition_on_floor, paper_covariance

    ref = refine_with_floor(np.asarray(extrinsics["rotation"]), np.asarray(extrinsics["translation"]), depth_m,
                            intrinsics, person, name=name)
    cov = extrinsics.get("covariance")
    base = paper_covariance(name) if cov is None else np.asarray(cov)
    source = extrinsics.get("covariance_source") or "paper default (calibration.json has none)"
    out = {"rotation": ref.rotation.tolist(), "translation": ref.translation.tolist(),
           "covariance": condition_on_floor(base, ref.rotation), "covariance_source": f"{source}, refined by the floor"}
    report = {"tilt_x_deg": ref.tilt_x_deg, "tilt_z_deg": ref.tilt_z_deg, "height_mm": ref.height_mm,
              "floor_points": ref.points, "floor_rms_mm": ref.rms_mm}
    return out, report

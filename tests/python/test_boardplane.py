"""The board-depth refinement of the extrinsics (bsv.frontend.boardplane): a known calibration error is
recovered from a rendered depth view of the board face where the plane can see it (distance along the
board normal, yaw, pitch) and left where it cannot; the covariance shrinks in those directions only;
clear errors for a depth image that does not show the board; the calibrate path with depth frames."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

cv2 = pytest.importorskip("cv2")

from bsv.frontend import boardplane as bp  # noqa: E402
from bsv.frontend import calibrate as cal  # noqa: E402
from bsv.frontend import errors  # noqa: E402
from bsv.frontend.intrinsics import Intrinsics  # noqa: E402
from bsv.frontend.marker import Board, MarkerSpec, render_view  # noqa: E402
from bsv.uncertainty import BOARD_STD, paper_covariance, perturb, pose_delta  # noqa: E402

# The virtual rig's portrait L515 (768 x 1024, 55 x 70 deg), 2 m from a board 1 m up.
INTR = Intrinsics.from_fov(768, 1024, 55.0, 70.0)
BOARD = Board(MarkerSpec(), centre_height_m=1.0, thickness_m=0.012)
TRUE = {
    "front": (np.diag([1.0, -1.0, -1.0]), np.array([0.0, 1.0, 2.0])),
    "back": (np.diag([-1.0, -1.0, 1.0]), np.array([0.0, 1.0, -2.0])),
}
#: A calibration error (camera frame): tx, ty, tz (m), rx (pitch), ry (yaw), rz (roll) (rad): ~1-2 of the
#: paper's back-camera SDs in every parameter.
DELTA = np.array([0.0005, 0.002, 0.005, math.radians(0.15), math.radians(0.4), math.radians(0.12)])
MEASURED = [2, 3, 4]  # tz, rx, ry: what a plane facing the camera measures
UNMEASURED = [0, 1, 5]


def render_depth(r_wc: np.ndarray, t_wc: np.ndarray, side: str, board: Board = BOARD, intr: Intrinsics = INTR,
                 sigma: float = 0.0, seed: int = 0) -> np.ndarray:
    """Depth (metres, z along the optical axis, 0 = none) of the board face seen by the undistorted camera
    (r_wc, t_wc), with Gaussian depth noise ``sigma`` (metres)."""
    r_wm, t_wm = board.marker_to_world(side)
    n_c = r_wc.T @ r_wm[:, 2]
    e_c = float(r_wm[:, 2] @ (t_wm - t_wc))
    vv, uu = np.mgrid[0:intr.height, 0:intr.width].astype(np.float64)
    rays = np.stack([(uu - intr.cx) / intr.fx, (vv - intr.cy) / intr.fy, np.ones_like(uu)], axis=-1)
    z = e_c / (rays @ n_c)
    world = (rays * z[..., None]) @ r_wc.T + t_wc
    local = (world - t_wm) @ r_wm  # marker frame
    half = board.face_size_m / 2.0
    inside = (np.abs(local[..., 0]) <= half) & (np.abs(local[..., 1]) <= half) & (z > 0)
    rng = np.random.default_rng(seed)
    return np.where(inside, z + rng.normal(0.0, sigma, z.shape), 0.0)


@pytest.mark.parametrize("side", ["front", "back"])
def test_exact_depth_recovers_the_measured_error_and_keeps_the_rest(side: str) -> None:
    r_t, t_t = TRUE[side]
    r_e, t_e = perturb(r_t, t_t, DELTA)
    depth = render_depth(r_t, t_t, side)
    # a negligible allowance makes the depth decisive: the geometry (face at thickness/2) must be exact
    ref = bp.refine_with_board(r_e, t_e, paper_covariance("back"), depth, INTR, BOARD, side, std=(1e-9, 1e-9, 1e-9))
    left = pose_delta(r_t, t_t, ref.rotation, ref.translation)
    # the measured directions: to the fit's numerical precision (0.1 um, 1e-6 deg)
    assert np.abs(left[2]) < 1e-7 and np.abs(left[3:5]).max() < math.radians(1e-6)
    # the rest as the colour pose had it: in the colour pose's camera frame the correction has next to no
    # lateral, vertical or roll part (the board's normal is 0.15-0.4 deg off that frame's axis, which lets
    # the 5 mm depth correction leak ~(sd ratio)^2 x 5 mm x 0.003 = 3 um; 10 um / 1e-5 rad is 1/20 of the
    # paper's smallest SD of those parameters)
    moved = pose_delta(r_e, t_e, ref.rotation, ref.translation)
    assert np.abs(moved[UNMEASURED]).max() < 1e-5
    assert left[UNMEASURED] == pytest.approx(DELTA[UNMEASURED], abs=5e-5)
    assert ref.plane.rms_mm < 1e-6 and ref.tilt_deg == pytest.approx(math.degrees(math.hypot(DELTA[3], DELTA[4])),
                                                                     rel=1e-3)
    # the colour pose put the camera 5 mm along its optical axis, i.e. toward the board: moved back
    assert ref.depth_mm == pytest.approx(-DELTA[2] * 1000.0, rel=2e-3)
    # the board's thickness matters: a board said to be 2 cm thick puts the camera 4 mm elsewhere
    thick = Board(MarkerSpec(), centre_height_m=1.0, thickness_m=0.02)
    other = bp.refine_with_board(r_e, t_e, paper_covariance("back"), depth, INTR, thick, side, std=(1e-9,) * 3)
    assert abs(pose_delta(r_t, t_t, other.rotation, other.translation)[2]) == pytest.approx(0.004, abs=1e-6)


def test_noisy_depth_recovers_within_its_own_uncertainty() -> None:
    """The rig's L515 noise at 2 m (4.1 mm per pixel): the tolerance is the posterior's own SD (3 SD),
    which must itself be well under the prior (the paper's back camera: 3.4 mm, 0.11 / 0.28 deg)."""
    r_t, t_t = TRUE["back"]
    r_e, t_e = perturb(r_t, t_t, DELTA)
    prior = paper_covariance("back")
    worst = 0.0
    for seed in range(5):
        ref = bp.refine_with_board(r_e, t_e, prior, render_depth(r_t, t_t, "back", sigma=0.0041, seed=seed), INTR,
                                   BOARD, "back")
        left = pose_delta(r_t, t_t, ref.rotation, ref.translation)
        sd = np.sqrt(np.diag(ref.covariance))
        worst = max(worst, float(np.max(np.abs(left[MEASURED]) / sd[MEASURED])))
        assert ref.plane.rms_mm == pytest.approx(4.1, rel=0.1)
    assert worst < 3.0
    assert sd[2] < 0.2 * math.sqrt(prior[2, 2]) and sd[4] < 0.4 * math.sqrt(prior[4, 4])


def test_covariance_shrinks_in_the_measured_directions_only() -> None:
    r_t, t_t = TRUE["back"]
    prior = paper_covariance("back")
    ref = bp.refine_with_board(r_t, t_t, prior, render_depth(r_t, t_t, "back", sigma=0.0041), INTR, BOARD, "back")
    post = ref.covariance
    ratio = np.sqrt(np.diag(post) / np.diag(prior))
    # depth 3.4 mm -> 0.5 mm, yaw 0.28 -> ~0.06 deg; pitch 0.11 -> ~0.06 deg (the fit's tilt SD with
    # 4.1 mm noise on ~4500 pixels of an 18 cm square: 4.1 / sqrt(4500) / 52 mm = 0.06 deg)
    assert ratio[2] < 0.2 and ratio[4] < 0.3 and ratio[3] < 0.6
    assert ratio[UNMEASURED] == pytest.approx(1.0, abs=1e-6)
    # the depth's offset is never trusted beyond the systematic allowance
    assert math.sqrt(post[2, 2]) == pytest.approx(BOARD_STD[2], rel=0.1)
    assert np.linalg.eigvalsh(post).min() > 0 and np.allclose(post, post.T)


def test_depth_that_does_not_show_the_board_is_refused() -> None:
    r_t, t_t = TRUE["front"]
    depth = render_depth(r_t, t_t, "front", sigma=0.002)
    prior = paper_covariance("front")
    with pytest.raises(errors.BoardDepthError, match="valid depth pixels on the board"):
        bp.refine_with_board(r_t, t_t, prior, np.zeros_like(depth), INTR, BOARD, "front")
    with pytest.raises(errors.BoardDepthError, match="valid depth pixels on the board"):  # misaligned by 60 px
        bp.refine_with_board(r_t, t_t, prior, np.roll(depth, 60, axis=1), INTR, BOARD, "front")
    with pytest.raises(errors.BoardDepthError, match="wrong depth scale"):  # D4xx units read as an L515's
        bp.refine_with_board(r_t, t_t, prior, depth * 4.0, INTR, BOARD, "front")
    # another plane, turned 8 deg about the vertical (x = X/Z, so z' = z (1 + tan(8 deg) x) is a plane)
    x = (np.arange(INTR.width) - INTR.cx) / INTR.fx
    tilted = np.where(depth > 0, depth * (1.0 + math.tan(math.radians(8.0)) * x[None, :]), 0.0)
    with pytest.raises(errors.BoardDepthError, match=r"8\.\d\d deg / "):
        bp.refine_with_board(r_t, t_t, prior, tilted, INTR, BOARD, "front")
    with pytest.raises(errors.BoardDepthError, match="colour intrinsics are 768 x 1024"):
        bp.refine_with_board(r_t, t_t, prior, depth[:, :700], INTR, BOARD, "front")
    assert issubclass(errors.BoardDepthError, errors.CalibrationError)


def test_median_depth_drops_missing_pixels() -> None:
    a = np.array([[1.0, 0.0], [2.0, 0.0]])
    b = np.array([[3.0, 0.0], [0.0, 0.0]])
    c = np.array([[2.0, 5.0], [2.0, 0.0]])
    assert bp.median_depth([a, b, c]).tolist() == [[2.0, 5.0], [2.0, 0.0]]
    with pytest.raises(errors.BoardDepthError):
        bp.median_depth([])


# -- the calibrate path ----------------------------------------------------------------------------------------


def _frames(r_wc: np.ndarray, t_wc: np.ndarray, side: str, n: int = 3) -> list[np.ndarray]:
    r_wm, t_wm = BOARD.marker_to_world(side)
    r_cm, t_cm = r_wc.T @ r_wm, r_wc.T @ (t_wm - t_wc)
    rng = np.random.default_rng(1)
    out = []
    for i in range(n):
        base = render_view(BOARD.marker, INTR, r_cm, t_cm, samples=8, seed=i).astype(np.float64)
        out.append(np.clip(np.rint(base + rng.normal(0.0, 2.0, base.shape)), 0, 255).astype(np.uint8))
    return out


def test_calibrate_command_line_with_depth(tmp_path: Path) -> None:
    """Colour frames of the board plus 16-bit depth PNGs (L515 units, scale from camera.json): the written
    calibration.json has the refined pose (camera distance to the board from the depth, within 0.5 mm
    where the colour pose alone is off by more), the "+board depth" source and a narrower covariance
    along the optical axis."""
    scale = 0.00025
    args = []
    for side, (r, t) in TRUE.items():
        (tmp_path / side).mkdir()
        for i, f in enumerate(_frames(r, t, side)):
            cv2.imwrite(str(tmp_path / side / f"{i:03d}.png"), f)
        dd = tmp_path / f"{side}_depth"
        dd.mkdir()
        for i in range(2):
            d = render_depth(r, t, side, sigma=0.003, seed=i)
            cv2.imwrite(str(dd / f"{i:03d}.png"), np.rint(d / scale).astype(np.uint16))
        (dd / "camera.json").write_text(json.dumps({"depth_scale": scale}))
        (tmp_path / f"{side}_intr.json").write_text(json.dumps({"intrinsics": INTR.to_json()}))
        args += [side]
    base = ["--images", *(f"{s}={tmp_path / s}" for s in args), "--intrinsics",
            *(f"{s}={tmp_path / (s + '_intr.json')}" for s in args), "--board-thickness", "0.012"]
    assert cal.main([*base, "-o", str(tmp_path / "colour.json")]) == 0
    assert cal.main([*base, "--depth", *(f"{s}={tmp_path / (s + '_depth')}" for s in args),
                     "-o", str(tmp_path / "depth.json")]) == 0
    colour = cal.read_calibration(tmp_path / "colour.json")
    refined = cal.read_calibration(tmp_path / "depth.json")
    doc = json.loads((tmp_path / "depth.json").read_text())
    for side, (r, t) in TRUE.items():
        c0, c1 = colour.cameras[side], refined.cameras[side]
        e0 = pose_delta(r, t, c0.rotation, c0.translation)
        e1 = pose_delta(r, t, c1.rotation, c1.translation)
        # a 59 px marker at 2 m: the colour tilts are off by ~0.2 deg, the depth brings them within
        # 0.1 deg (2.5 x the posterior's SD of ~0.04 deg) and keeps the distance within 0.5 mm
        assert abs(e1[2]) < 0.0005, (side, e0, e1)
        assert np.abs(e1[3:5]).max() < math.radians(0.1) < np.abs(e0[3:5]).max(), (side, e0, e1)
        assert c1.covariance_source == f"{c0.covariance_source}+board depth"
        assert c1.covariance is not None and c0.covariance is not None
        prior = c0.covariance + paper_covariance(side)  # the update's prior for a frames covariance
        assert (np.diag(c1.covariance)[3:5] < 0.5 * np.diag(prior)[3:5]).all()
        assert c1.covariance[2, 2] <= prior[2, 2]
        # the roll about the optical axis is not measured (nor correlated with what is): kept; the lateral
        # shift may shrink too, through the colour pose's shift-yaw correlation that the frames show
        assert c1.covariance[5, 5] == pytest.approx(prior[5, 5], rel=0.05)
        assert doc["cameras"][side]["board_depth"]["frames"] == 2
    # a wrong depth scale on the command line is refused with the reason
    with pytest.raises(errors.BoardDepthError, match="wrong depth scale"):
        cal.main([*base, "--depth", f"front={tmp_path / 'front_depth'}", "--depth-scale", "0.001",
                  "-o", str(tmp_path / "bad.json")])
    with pytest.raises(errors.CalibrationFileError, match="no 16-bit depth PNGs"):
        cal.main([*base, "--depth", f"front={tmp_path / 'nowhere'}", "-o", str(tmp_path / "bad2.json")])
    with pytest.raises(errors.CalibrationFileError, match="16-bit"):
        cal.load_depth(np.zeros((4, 4), np.uint8))


def test_the_virtual_rigs_board_view_removes_its_own_calibration_error(tmp_path: Path) -> None:
    """The benchmark's path: the rig draws a camera's calibration error from (seed, camera) only, so a scan
    of the board (bench.refine.board_mesh) carries the error of any capture of that seed; in cali (exact
    depth) the board refinement removes the back camera's depth error and yaw to 2 % of the paper's SD
    (the update's weight: the 0.5 mm / 0.03 deg allowance against 3.4 mm / 0.28 deg), and leaves the
    parameters it cannot see as they were."""
    import bsv
    from bsv.bench.floor import read_camera_poses
    from bsv.bench.refine import board_mesh
    from bsv.frontend.capture import read_capture
    from bsv.uncertainty import PAPER_STD

    board = Board()
    bsv.scan(board_mesh(board), "cali", 7, images=tmp_path)
    for c in read_camera_poses(tmp_path):
        cap = read_capture(tmp_path / c.name)
        ref = bp.refine_with_board(c.est_rotation, c.est_translation, paper_covariance(c.name), cap["depth_m"],
                                   cap["intrinsics"], board, c.name)
        std = np.asarray(PAPER_STD[c.name])
        before = pose_delta(c.true_rotation, c.true_translation, c.est_rotation, c.est_translation) / std
        after = pose_delta(c.true_rotation, c.true_translation, ref.rotation, ref.translation) / std
        if c.name == "back":
            assert np.abs(after[[2, 4]]).max() < 0.05 * max(1.0, float(np.abs(before[[2, 4]]).max())), (before, after)
        assert np.abs(after[MEASURED]).max() <= np.abs(before[MEASURED]).max()
        np.testing.assert_allclose(after[UNMEASURED], before[UNMEASURED], atol=0.02)


def test_far_flying_pixels_on_the_board_do_not_tilt_its_plane() -> None:
    """An L515 in a room: a few pixels of the board region fly toward the wall 2-3 m behind it (measured on
    the rig's clinic room: 0.5 % of them, up to 4.3 m). A plain least-squares start fitted a plane 83 deg
    off and the refinement refused the capture; the median-depth start ignores them."""
    r_t, t_t = TRUE["back"]
    r_e, t_e = perturb(r_t, t_t, DELTA)
    depth = render_depth(r_t, t_t, "back", sigma=0.0041, seed=3)
    region = bp.board_region(r_e, t_e, INTR, BOARD, "back")
    rng = np.random.default_rng(1)
    vv, uu = np.nonzero(region)
    pick = rng.choice(len(vv), size=max(3, len(vv) // 200), replace=False)
    depth[vv[pick], uu[pick]] = rng.uniform(2.5, 4.4, size=len(pick))
    plane = bp.fit_board_plane(depth, INTR, region)
    assert plane.rms_mm == pytest.approx(4.1, rel=0.15)
    assert math.degrees(math.acos(min(1.0, abs(float(plane.normal[2]))))) < 1.0
    ref = bp.refine_with_board(r_e, t_e, paper_covariance("back"), depth, INTR, BOARD, "back")
    left = pose_delta(r_t, t_t, ref.rotation, ref.translation)
    assert abs(left[2]) < 0.0015 and abs(left[4]) < math.radians(0.1)

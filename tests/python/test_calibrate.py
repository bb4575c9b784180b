"""ArUco calibration: extrinsics recovered from rendered views of the double-sided board, clear errors
for missing, wrong, mirrored and blurred markers, the live-alignment numbers, the JSON files."""

from __future__ import annotations

import importlib
import json
import math
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]


def _import(name: str):
    """Imports from the installed bsv package (scripts/setup.sh builds its extension)."""
    return importlib.import_module(name)


cv2 = pytest.importorskip("cv2")
cal = _import("bsv.frontend.calibrate")
from bsv.frontend import errors  # noqa: E402
from bsv.frontend.intrinsics import Intrinsics, load_intrinsics  # noqa: E402
from bsv.frontend.marker import Board, MarkerSpec, render_view  # noqa: E402

# Portrait colour stream of an L515 (1920 x 1080 turned on its side), ~43 x 70 deg.
INTR = Intrinsics.from_fov(1080, 1920, 43.0, 70.0)
BOARD = Board(MarkerSpec(), centre_height_m=1.1, thickness_m=0.006)


def rig_pose(side: str, pos, yaw_deg: float, pitch_deg: float) -> tuple[np.ndarray, np.ndarray]:
    """Camera-to-world of a camera at ``pos`` looking at the board (front: toward -Z, back: toward +Z),
    turned by yaw about the world vertical and pitched about its own x axis."""
    if side == "front":
        base = np.column_stack([[1.0, 0, 0], [0, -1.0, 0], [0, 0, -1.0]])
    else:
        base = np.column_stack([[-1.0, 0, 0], [0, -1.0, 0], [0, 0, 1.0]])
    ry = cv2.Rodrigues(np.array([0.0, math.radians(yaw_deg), 0.0]))[0]
    rx = cv2.Rodrigues(np.array([math.radians(pitch_deg), 0.0, 0.0]))[0]
    return ry @ base @ rx, np.asarray(pos, dtype=np.float64)


def frames_for(r_wc, t_wc, side, board=BOARD, n=8, noise=2.0, seed=0, marker=None):
    """Noisy 8-bit renders of the board face seen by camera (r_wc, t_wc)."""
    r_wm, t_wm = board.marker_to_world(side)
    r_cm = r_wc.T @ r_wm
    t_cm = r_wc.T @ (t_wm - t_wc)
    rng = np.random.default_rng(seed)
    out = []
    for i in range(n):
        base = render_view(marker or board.marker, INTR, r_cm, t_cm, samples=16, seed=seed * 100 + i).astype(np.float64)
        out.append(np.clip(np.rint(base + rng.normal(0.0, noise, base.shape)), 0, 255).astype(np.uint8))
    return out


POSES = {
    "front": rig_pose("front", [0.03, 1.0, 2.0], 1.5, -2.0),
    "back": rig_pose("back", [-0.04, 1.02, -2.02], -1.0, 1.0),
}


@pytest.fixture(scope="module")
def frames():
    return {side: frames_for(*POSES[side], side, seed=k) for k, side in enumerate(POSES)}


def errors_of(c, side):
    r_true, t_true = POSES[side]
    return np.linalg.norm(c.translation - t_true) * 1000.0, cal.rotation_angle_deg(c.rotation, r_true)


def test_extrinsics_recovered_both_cameras(frames, tmp_path):
    out = tmp_path / "calibration.json"
    result = cal.calibrate(frames, {"front": INTR, "back": INTR}, BOARD, serials={"front": "f123", "back": "b456"},
                           out=out)
    for side in ("front", "back"):
        mm, deg = errors_of(result.cameras[side], side)
        print(f"{side}: {mm:.2f} mm, {deg:.4f} deg, reprojection {result.cameras[side].reprojection_rms_px:.4f} px")
        assert mm < 2.0 and deg < 0.2
    doc = json.loads(out.read_text())
    assert set(doc["cameras"]) == {"front", "back"}
    front = doc["cameras"]["front"]
    assert front["serial"] == "f123" and front["frames"] == 8
    assert set(front["intrinsics"]) >= {"width", "height", "fx", "fy", "cx", "cy", "coeffs", "k1"}
    assert np.asarray(front["camera_to_world"]["rotation"]).shape == (3, 3)
    assert doc["marker"]["id"] == 336 and doc["marker"]["board_thickness_m"] == 0.006
    # issue 13: the frames' repeatability as a 6 x 6 covariance (8 noisy frames of a still board: well
    # under a millimetre and 0.05 deg), read back with the calibration
    cov = front["extrinsics_covariance"]
    assert cov["source"] == "frames" and np.asarray(cov["matrix"]).shape == (6, 6)
    sd = np.sqrt(np.diag(cov["matrix"]))
    assert np.all(sd[:3] < 1e-3) and np.all(np.degrees(sd[3:]) < 0.05) and np.all(sd > 0)
    # the back camera really looks toward +Z, the front one toward -Z (world frame of DESIGN.md)
    assert np.asarray(doc["cameras"]["back"]["camera_to_world"]["rotation"])[2, 2] > 0.99
    assert np.asarray(front["camera_to_world"]["rotation"])[2, 2] < -0.99
    again = cal.read_calibration(out)
    np.testing.assert_allclose(again.cameras["back"].translation, result.cameras["back"].translation)
    np.testing.assert_allclose(again.cameras["back"].covariance, result.cameras["back"].covariance)
    assert again.board == BOARD
    from bsv.errors import OutputExistsError

    with pytest.raises(OutputExistsError, match="overwrite"):
        result.write(out)
    before = out.read_text()
    with pytest.raises(OutputExistsError, match="overwrite"):  # refused before calibrating again
        cal.calibrate({"front": []}, {"front": INTR}, BOARD, out=out)
    assert out.read_text() == before


def test_pose_averaging_mode(frames):
    c = cal.calibrate_camera(frames["front"], INTR, "front", BOARD, average="pose")
    mm, deg = errors_of(c, "front")
    assert mm < 3.0 and deg < 0.2
    assert c.spread_mm < 10.0 and c.frames == 8


def test_board_thickness_shifts_the_back_camera(frames):
    thin = Board(BOARD.marker, BOARD.centre_height_m, 0.0)
    c_thin = cal.calibrate_camera(frames["back"], INTR, "back", thin)
    c = cal.calibrate_camera(frames["back"], INTR, "back", BOARD)
    np.testing.assert_allclose(c.translation - c_thin.translation, [0.0, 0.0, -0.003], atol=1e-9)


def test_average_poses_is_the_chordal_mean():
    rng = np.random.default_rng(3)
    centre = cv2.Rodrigues(np.array([0.1, -0.4, 0.2]))[0]
    rs, ts = [], []
    for _ in range(6):
        d = rng.normal(0.0, 0.02, 3)
        for sgn in (1.0, -1.0):  # symmetric perturbations average back to the centre
            rs.append(centre @ cv2.Rodrigues(sgn * d)[0])
            ts.append(np.array([1.0, 2.0, 3.0]) + sgn * d)
    r, t = cal.average_poses(rs, ts)
    assert cal.rotation_angle_deg(r, centre) < 1e-6
    np.testing.assert_allclose(t, [1.0, 2.0, 3.0], atol=1e-12)
    with pytest.raises(errors.CalibrationError):
        cal.average_poses([], [])


def test_missing_marker_is_a_clear_error():
    rng = np.random.default_rng(0)
    img = np.clip(110 + rng.normal(0, 2, (INTR.height, INTR.width)), 0, 255).astype(np.uint8)
    cv2.rectangle(img, (200, 300), (600, 900), 200, -1)  # sharp, but no marker
    with pytest.raises(errors.MarkerNotFoundError, match="no DICT_ARUCO_ORIGINAL marker found"):
        cal.calibrate_camera([img], INTR, "front", BOARD)
    assert issubclass(errors.MarkerNotFoundError, errors.CalibrationError)
    assert issubclass(errors.CalibrationError, errors.BsvError)


def test_wrong_id_is_a_clear_error():
    other = frames_for(*POSES["front"], "front", n=1, marker=MarkerSpec(marker_id=337))
    with pytest.raises(errors.WrongMarkerError, match=r"\[337\] but not id 336"):
        cal.calibrate_camera(other, INTR, "front", BOARD)


def test_mirrored_marker_is_named(frames):
    mirrored = BOARD.marker.mirrored_id()
    assert mirrored is not None and mirrored != 336
    with pytest.raises(errors.WrongMarkerError, match="mirrored"):
        cal.detect_marker(np.ascontiguousarray(frames["front"][0][:, ::-1]), BOARD.marker)


def test_blurred_image_is_a_clear_error(frames):
    blurred = cv2.GaussianBlur(frames["front"][0], (0, 0), 3.0)
    with pytest.raises(errors.BlurredImageError, match="blurred"):
        cal.calibrate_camera([blurred], INTR, "front", BOARD)
    very = cv2.GaussianBlur(frames["front"][0], (0, 0), 12.0)
    with pytest.raises(errors.BlurredImageError):
        cal.detect_marker(very, BOARD.marker)


def test_wrong_image_size_and_side():
    with pytest.raises(errors.CalibrationError, match="intrinsics are 1080 x 1920"):
        cal.calibrate_camera([np.zeros((100, 100), np.uint8)], INTR, "front", BOARD)
    with pytest.raises(errors.CalibrationError, match="unknown camera side"):
        cal.calibrate_camera([], INTR, "left", BOARD)


def _marker_pose(side, pos, yaw, pitch):
    r_wc, t_wc = rig_pose(side, pos, yaw, pitch)
    r_wm, t_wm = BOARD.marker_to_world(side)
    return r_wc.T @ r_wm, r_wc.T @ (t_wm - t_wc)


def test_alignment_numbers():
    a = cal.alignment(*_marker_pose("front", [0.0, 1.1, 2.0], 0.0, 0.0))
    assert a.aligned and abs(a.yaw_deg) < 1e-9 and abs(a.shift_m) < 1e-9 and abs(a.distance_m - 1.997) < 1e-9
    # turned 2 deg to its left (counter-clockwise from above): must turn right 2 deg
    a = cal.alignment(*_marker_pose("front", [0.0, 1.1, 2.0], 2.0, 0.0))
    assert a.yaw_deg == pytest.approx(-2.0) and abs(a.shift_m) < 1e-9 and not a.aligned
    # 3 cm toward world +X = its right (front camera): must move 3 cm left
    a = cal.alignment(*_marker_pose("front", [0.03, 1.1, 2.0], 0.0, -1.0))
    assert a.shift_m == pytest.approx(-0.03) and a.yaw_deg == pytest.approx(0.0, abs=1e-9)
    assert a.pitch_deg == pytest.approx(-1.0) and abs(a.roll_deg) < 1e-9
    # back camera: world +X is its left, so 3 cm toward +X means move 3 cm right
    a = cal.alignment(*_marker_pose("back", [0.03, 0.9, -2.0], 0.3, 0.0))
    assert a.shift_m == pytest.approx(0.03) and a.yaw_deg == pytest.approx(-0.3)
    assert a.height_m == pytest.approx(-0.2)
    assert cal.alignment(*_marker_pose("back", [0.003, 1.1, -2.0], 0.3, 0.0)).aligned
    assert "ALIGNED" in cal.alignment(*_marker_pose("back", [0.0, 1.1, -2.0], 0.0, 0.0)).lines()
    # the window drawing is pure too
    img = np.zeros((200, 150, 3), np.uint8)
    drawn = cal.draw_alignment(img, np.array([[10, 10], [50, 10], [50, 50], [10, 50]], float), a, BOARD.marker)
    assert drawn.shape == img.shape and drawn.any()


def test_alignment_from_detected_marker(frames):
    c = cal.detect_marker(frames["front"][0], BOARD.marker)
    r, t, rms = cal.marker_pose(c, INTR, BOARD.marker)
    a = cal.alignment(r, t)
    assert a.yaw_deg == pytest.approx(-1.5, abs=0.1) and a.shift_m == pytest.approx(-0.03, abs=0.005)
    assert rms < 0.05


def test_offline_command_line(frames, tmp_path):
    for side in ("front", "back"):
        d = tmp_path / side
        d.mkdir()
        for i, f in enumerate(frames[side][:4]):
            cv2.imwrite(str(d / f"{i:03d}.png"), f)
        (tmp_path / f"{side}_intrinsics.json").write_text(json.dumps({"intrinsics": INTR.to_json()}))
    out = tmp_path / "calibration.json"
    rc = cal.main(["--images", f"front={tmp_path / 'front'}", f"back={tmp_path / 'back'}", "--intrinsics",
                   f"front={tmp_path / 'front_intrinsics.json'}", f"back={tmp_path / 'back_intrinsics.json'}",
                   "--marker-height", "1.1", "--board-thickness", "0.006", "-o", str(out)])
    assert rc == 0
    result = cal.read_calibration(out)
    for side in ("front", "back"):
        mm, deg = errors_of(result.cameras[side], side)
        assert mm < 2.5 and deg < 0.2
    assert load_intrinsics(out, "back") == INTR
    with pytest.raises(errors.CalibrationFileError, match="no PNG/JPEG images"):
        cal.image_files(tmp_path / "nowhere")


def test_intrinsics_json_round_trip_and_errors(tmp_path):
    d = INTR.to_json()
    assert Intrinsics.from_json(d) == INTR
    flat = {k: v for k, v in d.items() if k != "coeffs"}
    assert Intrinsics.from_json(flat) == INTR
    with pytest.raises(errors.CalibrationFileError, match="missing or malformed"):
        Intrinsics.from_json({"width": 10})
    with pytest.raises(errors.CalibrationFileError, match="must be positive"):
        Intrinsics(10, 10, -1.0, 1.0, 5.0, 5.0)
    bad = tmp_path / "bad.json"
    bad.write_text("{")
    with pytest.raises(errors.CalibrationFileError, match="not valid JSON"):
        load_intrinsics(bad)
    with pytest.raises(errors.CalibrationFileError, match="not valid JSON"):
        cal.read_calibration(bad)


def test_a_frame_of_the_other_camera_is_refused_not_averaged(frames):
    """Issue 14: a back-camera frame mixed into the front set moved the front camera by 17 cm with only a
    printed spread; now it is named and refused."""
    mixed = [*frames["front"], frames["back"][0]]
    with pytest.raises(errors.CalibrationError, match=r"frame\(s\) 8 disagree") as e:
        cal.calibrate_camera(mixed, INTR, "front", BOARD)
    assert "remove those frames" in str(e.value)
    for average in ("image", "pose"):  # genuine frames stay well inside the limits
        c = cal.calibrate_camera(frames["front"], INTR, "front", BOARD, average=average)
        assert c.spread_mm < cal.MAX_FRAME_MM / 3 and c.spread_deg < cal.MAX_FRAME_DEG / 3

"""RealSense capture: recordings written with rs.software_device from synthetic frames, replayed end to end
through the capture code (alignment to colour, settling, timed acquisition, temporal median, files)."""

from __future__ import annotations

import importlib
import json
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]


def _import(name: str):
    """Imports from the installed bsv package (scripts/setup.sh builds its extension)."""
    return importlib.import_module(name)


rs = pytest.importorskip("pyrealsense2", reason="pyrealsense2 not installed (pip install -r requirements-frontend.txt)")
cv2 = pytest.importorskip("cv2")
cap = _import("bsv.frontend.capture")
from bsv.frontend import errors  # noqa: E402
from bsv.frontend.intrinsics import Intrinsics  # noqa: E402
from bsv.frontend.recording import write_recording  # noqa: E402

SCALE = 0.00025
D_INTR = Intrinsics.from_fov(96, 72, 70.0, 55.0)
C_INTR = D_INTR.scaled(160, 120)
PLANE, BOX = 8000, 6000  # 2.0 m and 1.5 m in device units
BOX_ROWS, BOX_COLS = slice(20, 50), slice(30, 60)  # in depth pixels
N_FRAMES, FPS = 45, 30


def scene_frames(seed: int, shade: int):
    """Noisy depth (plane + box, 20 % dropouts) and colour frames whose red channel is the frame index."""
    rng = np.random.default_rng(seed)
    depth, colour = [], []
    for i in range(N_FRAMES):
        d = np.full((D_INTR.height, D_INTR.width), PLANE, np.int32)
        d[BOX_ROWS, BOX_COLS] = BOX
        d += rng.integers(-20, 21, d.shape)
        d[rng.random(d.shape) < 0.2] = 0
        depth.append(d.astype(np.uint16))
        c = np.zeros((C_INTR.height, C_INTR.width, 3), np.uint8)
        c[..., 0] = i
        c[..., 1] = shade
        colour.append(c)
    return depth, colour


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    root = tmp_path_factory.mktemp("capture")
    for k, (name, serial) in enumerate((("front", "111111111111"), ("back", "222222222222"))):
        d, c = scene_frames(k, 50 + k)
        write_recording(root / name / "recording.db3", d, c, D_INTR, C_INTR, depth_scale=SCALE, fps=FPS, serial=serial)
    return root


CONFIG = cap.CaptureConfig(settle_frames=5, duration_s=1.0, max_frames=50, timeout_ms=2000)


def test_replay_end_to_end(recorded):
    result = cap.capture(recorded, config=CONFIG, from_recording=True)
    assert set(result) == {"front", "back"}
    for k, (name, serial) in enumerate((("front", "111111111111"), ("back", "222222222222"))):
        r = result[name]
        assert r.serial == serial and r.frames == 30  # 1 s at 30 fps after 5 settling frames
        assert r.depth_scale == pytest.approx(SCALE, rel=1e-6)
        assert r.depth.shape == (C_INTR.height, C_INTR.width) and r.depth.dtype == np.uint16
        # depth aligned to the colour image: the box (depth pixels 30..59 x 20..49) scales by 160/96
        box = r.depth[int(21 * 5 / 3) + 2:int(49 * 5 / 3) - 2, int(31 * 5 / 3) + 2:int(59 * 5 / 3) - 2]
        plane = r.depth[5:25, 5:40]
        assert (box > 0).mean() > 0.98 and (plane > 0).mean() > 0.98
        err_box = np.abs(box[box > 0].astype(float) - BOX).mean()
        err_plane = np.abs(plane[plane > 0].astype(float) - PLANE).mean()
        print(f"{name}: median depth error box {err_box * SCALE * 1000:.2f} mm, plane {err_plane * SCALE * 1000:.2f} mm")
        assert err_box < 4.0 and err_plane < 4.0  # single frames: 10 units mean error plus dropouts
        bias = np.mean(np.concatenate([box[box > 0].astype(float) - BOX, plane[plane > 0].astype(float) - PLANE]))
        assert abs(bias) < 1.5  # per-frame alignment to the finer colour image would give about -7.5 units
        # the middle frame's colour (frame index 5 + 15)
        assert 18 <= int(np.median(r.colour[..., 0])) <= 22 and int(np.median(r.colour[..., 1])) == 50 + k
        meta = json.loads((recorded / name / "camera.json").read_text())
        got = Intrinsics.from_json(meta["intrinsics"])
        for f in ("width", "height"):
            assert getattr(got, f) == getattr(C_INTR, f)
        for f in ("fx", "fy", "cx", "cy"):
            assert getattr(got, f) == pytest.approx(getattr(C_INTR, f), rel=1e-6)
        assert Intrinsics.from_json(meta["depth_intrinsics"]).width == D_INTR.width
        assert meta["serial"] == serial and meta["frames"] == 30
        back = cap.read_capture(recorded / name)
        np.testing.assert_array_equal(back["depth_m"], r.depth * float(meta["depth_scale"]))
        np.testing.assert_array_equal(back["colour"], r.colour)


def test_replay_named_files_and_short_recordings(recorded, tmp_path):
    r = cap.capture(tmp_path / "out", config=CONFIG, from_recording={"front": recorded / "front" / "recording.db3"})
    assert set(r) == {"front"} and (tmp_path / "out" / "front" / "depth.png").exists()
    too_long_settle = cap.CaptureConfig(settle_frames=N_FRAMES + 5, duration_s=1.0, timeout_ms=1000)
    with pytest.raises(errors.RecordingError, match="no frames left"):
        cap.capture(tmp_path / "o2", config=too_long_settle, from_recording={"front": recorded / "front" / "recording.db3"})
    with pytest.raises(errors.RecordingError, match="no recording at"):
        cap.capture(tmp_path / "empty", config=CONFIG, from_recording=True)
    with pytest.raises(errors.RecordingError, match="does not exist"):
        cap.capture(tmp_path, config=CONFIG, from_recording={"front": tmp_path / "nope.db3"})


def test_replay_and_recording_do_not_overwrite(recorded, tmp_path):
    from bsv.errors import OutputExistsError

    rec = recorded / "front" / "recording.db3"
    out = tmp_path / "out"
    (out / "front").mkdir(parents=True)
    (out / "front" / "camera.json").write_text("{}")
    with pytest.raises(OutputExistsError, match=r"camera\.json"):
        cap.capture(out, config=CONFIG, from_recording={"front": rec})
    assert (out / "front" / "camera.json").read_text() == "{}" and not (out / "front" / "depth.png").exists()
    cap.capture(out, config=CONFIG, from_recording={"front": rec}, overwrite=True)
    assert json.loads((out / "front" / "camera.json").read_text())["frames"] == 30
    size = rec.stat().st_size
    d, c = scene_frames(0, 50)
    with pytest.raises(OutputExistsError, match="overwrite"):
        write_recording(rec, d[:2], c[:2], D_INTR, C_INTR)
    assert rec.stat().st_size == size
    other = write_recording(tmp_path / "r.db3", d[:2], c[:2], D_INTR, C_INTR)
    write_recording(other, d[:3], c[:3], D_INTR, C_INTR, overwrite=True)


def test_no_camera_is_a_clear_error(tmp_path):
    if rs.context().query_devices().size() > 0:
        pytest.skip("a RealSense camera is connected")
    with pytest.raises(errors.NoCameraError, match="no RealSense camera connected"):
        cap.capture(tmp_path, {"front": "123", "back": "456"})
    with pytest.raises(errors.NoCameraError):
        cap.capture(tmp_path)
    assert issubclass(errors.NoCameraError, errors.BsvError)


def test_align_depth_to_colour_with_offset_camera():
    """A plane at 2 m seen by a colour camera 5 cm to the right: the depth lands shifted by fx * 0.05 / 2 px."""
    d = np.full((D_INTR.height, D_INTR.width), PLANE, np.uint16)
    d[:, :10] = 0
    t_units = np.array([-0.05, 0.0, 0.0]) / SCALE  # colour camera at +5 cm: points move by -5 cm in its frame
    out = cap.align_depth_to_colour(d, D_INTR, C_INTR, np.eye(3), t_units)
    assert out.dtype == np.uint16 and out.shape == (C_INTR.height, C_INTR.width)
    row = out[60]
    first = int(np.argmax(row > 0))
    # depth column 9.5 (edge of the hole) at x = (9.5 - cx) / fx * 2 m, then -5 cm, projected
    x = (9.5 - D_INTR.cx) / D_INTR.fx * 2.0 - 0.05
    expect = x / 2.0 * C_INTR.fx + C_INTR.cx
    assert abs(first - expect) <= 1.0
    assert np.all(row[first:first + 100] == PLANE)
    assert np.all(cap.align_depth_to_colour(np.zeros_like(d), D_INTR, C_INTR, np.eye(3), np.zeros(3)) == 0)


def test_temporal_median_ignores_zeros():
    rng = np.random.default_rng(0)
    s = rng.integers(1, 1000, (7, 33, 20)).astype(np.uint16)
    s[rng.random(s.shape) < 0.3] = 0
    s[:, 0, 0] = 0
    f = s.astype(float)
    f[s == 0] = np.nan
    with np.errstate(all="ignore"), pytest.warns(RuntimeWarning):
        ref = np.nanmedian(f, axis=0)
    got = cap.temporal_median(s, chunk_rows=8)
    assert got[0, 0] == 0
    ok = ~np.isnan(ref)
    np.testing.assert_array_equal(got[ok], np.floor(ref[ok]).astype(np.uint16))
    with pytest.raises(errors.CaptureError):
        cap.temporal_median(np.zeros((0, 2, 2), np.uint16))


def test_write_recording_checks_its_input(tmp_path):
    with pytest.raises(errors.RecordingError, match=r"\.db3"):
        write_recording(tmp_path / "x.bag", [], [], D_INTR, C_INTR)
    with pytest.raises(errors.RecordingError, match="uint16"):
        write_recording(tmp_path / "x.db3", [np.zeros((2, 2), np.uint16)], [np.zeros((120, 160, 3), np.uint8)],
                        D_INTR, C_INTR)

"""RealSense capture of the two cameras (or replay of their recordings through the same code).

Per camera: depth and colour streams, ``settle_frames`` skipped for auto-exposure, then ``duration_s``
of still acquisition (timed by the frames' own timestamps, so a replay gives the same result); the depth
is reduced to its per-pixel temporal median (zeros = no data are ignored) and that median is aligned to
the colour image (:func:`align_depth_to_colour`, the pixel-footprint projection of ``rs.align``). Median
first, then align: aligning every noisy frame to a finer colour image (what ``rs.align`` per frame does)
keeps the nearest of the overlapping samples and biases the depth toward the camera by about one noise
sigma (measured: -1.9 mm with +-5 mm noise), which would thicken the body seen by two facing cameras.
Written per camera into ``OUT/<camera>/``:

- ``color.png`` (8-bit RGB, the middle frame of the acquisition), ``depth.png`` (16-bit, device units:
  metres = value x ``depth_scale``, 0 = none, aligned to the colour image),
- ``camera.json``: ``{"name", "serial", "intrinsics" (of the colour image, hence of the aligned depth),
  "depth_intrinsics", "depth_scale", "frames", "duration_s", "depth", "color", "recording"}`` (the
  layout of the virtual scanner's ``camera.json``, without extrinsics: those come from calibration.json),
- ``recording.db3``: the raw streams (live captures only).
"""

from __future__ import annotations

import contextlib
import json
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np

from ..errors import OutputExistsError
from ..extras import require
from .errors import CaptureError, NoCameraError, RecordingError
from .intrinsics import Intrinsics

PathLike = str | Path

#: Default camera names, in capture order.
CAMERAS = ("front", "back")


@dataclass(frozen=True)
class CaptureConfig:
    """Stream sizes (width, height) and rates, auto-exposure settling, acquisition length. Defaults: L515."""

    depth_size: tuple[int, int] = (1024, 768)
    colour_size: tuple[int, int] = (1920, 1080)
    fps: int = 30
    settle_frames: int = 30
    duration_s: float = 5.0
    max_frames: int = 50
    timeout_ms: int = 5000

    @classmethod
    def d4xx(cls, **kw: Any) -> CaptureConfig:
        """Defaults for D415/D435/D455 cameras (depth 848 x 480, colour 1280 x 720)."""
        return cls(depth_size=(848, 480), colour_size=(1280, 720), **kw)


@dataclass
class CameraCapture:
    """What one camera's capture wrote, with the arrays."""

    name: str
    serial: str
    colour: np.ndarray
    depth: np.ndarray
    depth_scale: float
    intrinsics: Intrinsics
    depth_intrinsics: Intrinsics | None
    frames: int
    folder: Path
    recording: Path | None = None
    extra: dict[str, Any] = field(default_factory=dict)


def import_realsense() -> ModuleType:
    """``pyrealsense2``, or a :class:`bsv.errors.MissingExtraError` naming the ``frontend`` extra."""
    return require("pyrealsense2")


def connected_serials() -> list[str]:
    """Serial numbers of the connected RealSense devices."""
    rs = import_realsense()
    return [d.get_info(rs.camera_info.serial_number) for d in rs.context().query_devices()]


def temporal_median(stack: np.ndarray, chunk_rows: int = 64) -> np.ndarray:
    """Per-pixel median over frames of a (frames, H, W) uint16 stack, ignoring zeros (no data); 0 where a
    pixel has no data in any frame. An even count takes the lower-upper mean, rounded down."""
    s = np.asarray(stack)
    if s.ndim != 3 or s.shape[0] == 0:
        raise CaptureError(f"temporal_median needs a (frames, H, W) stack, got shape {s.shape}")
    n_f, h, w = s.shape
    out = np.zeros((h, w), dtype=s.dtype)
    big = np.iinfo(s.dtype).max if np.issubdtype(s.dtype, np.integer) else np.inf
    for r0 in range(0, h, chunk_rows):
        blk = s[:, r0:r0 + chunk_rows]
        valid = blk != 0
        cnt = valid.sum(axis=0)
        srt = np.sort(np.where(valid, blk, big), axis=0)  # zeros sorted to the end
        lo = np.take_along_axis(srt, np.maximum(cnt - 1, 0)[None] // 2, axis=0)[0].astype(np.int64)
        hi = np.take_along_axis(srt, (cnt // 2)[None].clip(max=n_f - 1), axis=0)[0].astype(np.int64)
        med = (lo + hi) // 2
        out[r0:r0 + chunk_rows] = np.where(cnt > 0, med, 0).astype(s.dtype)
    return out


def align_depth_to_colour(depth: np.ndarray, depth_intr: Intrinsics, colour_intr: Intrinsics,
                          rotation: np.ndarray, translation_units: np.ndarray, max_footprint: int = 8) -> np.ndarray:
    """Depth image (uint16, device units) re-projected onto the colour image like ``rs.align``: each depth
    pixel's footprint (its two opposite corners deprojected at its depth, moved into the colour camera by
    ``rotation``/``translation_units`` (translation in depth units) and projected) is filled with the
    depth along the colour camera's axis, the nearest winning; 0 where no depth lands."""
    cv2 = require("cv2")

    d = np.asarray(depth)
    ys, xs = np.nonzero(d)
    z = d[ys, xs].astype(np.float64)
    out = np.full((colour_intr.height, colour_intr.width), np.iinfo(np.uint16).max, dtype=np.uint16)
    if z.size == 0:
        return np.zeros_like(out)
    r = np.asarray(rotation, dtype=np.float64)
    t = np.asarray(translation_units, dtype=np.float64).reshape(3)
    corners = []
    for off in (-0.5, 0.5):
        pix = np.column_stack([xs + off, ys + off]).astype(np.float64)
        if np.any(depth_intr.dist):
            n = cv2.undistortPoints(pix.reshape(-1, 1, 2), depth_intr.matrix, depth_intr.dist).reshape(-1, 2)
        else:
            n = np.column_stack([(pix[:, 0] - depth_intr.cx) / depth_intr.fx, (pix[:, 1] - depth_intr.cy) / depth_intr.fy])
        p = np.column_stack([n * z[:, None], z]) @ r.T + t
        if np.any(colour_intr.dist):
            uv, _ = cv2.projectPoints(p.reshape(-1, 1, 3), np.zeros(3), np.zeros(3), colour_intr.matrix, colour_intr.dist)
            uv = uv.reshape(-1, 2)
        else:
            uv = np.column_stack([p[:, 0] / p[:, 2] * colour_intr.fx + colour_intr.cx,
                                  p[:, 1] / p[:, 2] * colour_intr.fy + colour_intr.cy])
        corners.append((uv, p[:, 2]))
    (uv0, z0), (uv1, z1) = corners
    # colour pixels whose centre lies in the footprint [min, max): adjacent footprints tile the image,
    # so no pixel takes the nearer of two neighbours (which would bias the depth) and none is left empty
    u0 = np.ceil(np.minimum(uv0[:, 0], uv1[:, 0])).astype(np.int64)
    u1 = np.ceil(np.maximum(uv0[:, 0], uv1[:, 0])).astype(np.int64) - 1
    v0 = np.ceil(np.minimum(uv0[:, 1], uv1[:, 1])).astype(np.int64)
    v1 = np.ceil(np.maximum(uv0[:, 1], uv1[:, 1])).astype(np.int64) - 1
    zc = np.clip(np.rint((z0 + z1) / 2.0), 1, np.iinfo(np.uint16).max - 1).astype(np.uint16)
    flat = out.ravel()
    for dv in range(max_footprint):
        for du in range(max_footprint):
            u, v = u0 + du, v0 + dv
            ok = (u <= u1) & (v <= v1) & (u >= 0) & (v >= 0) & (u < colour_intr.width) & (v < colour_intr.height)
            if not ok.any():
                continue
            np.minimum.at(flat, v[ok] * colour_intr.width + u[ok], zc[ok])
    out[out == np.iinfo(np.uint16).max] = 0
    return out


def _stream_intrinsics(profile: Any, stream: Any) -> Intrinsics:
    return Intrinsics.from_realsense(profile.get_stream(stream).as_video_stream_profile().get_intrinsics())


def open_colour_stream(rs: ModuleType, serial: str | None, width: int, height: int,
                       fps: int) -> tuple[Any, Intrinsics]:
    """Starts a colour-only pipeline (RGB8) on the camera ``serial`` (or the only one); returns the
    pipeline and the colour intrinsics. Used by the live calibration view."""
    _check_devices(rs, [serial] if serial else None)
    pipe, cfg = rs.pipeline(), rs.config()
    if serial:
        cfg.enable_device(serial)
    cfg.enable_stream(rs.stream.color, width, height, rs.format.rgb8, fps)
    prof = pipe.start(cfg)
    return pipe, _stream_intrinsics(prof, rs.stream.color)


def _check_devices(rs: ModuleType, serials: list[str | None] | None) -> list[str]:
    found = [d.get_info(rs.camera_info.serial_number) for d in rs.context().query_devices()]
    if not found:
        raise NoCameraError("no RealSense camera connected: plug the cameras in (USB 3), or replay recordings "
                            "with from_recording")
    for s in serials or []:
        if s is not None and s not in found:
            raise NoCameraError(f"no RealSense camera with serial {s} connected (connected: {', '.join(found)})")
    return found


@dataclass
class _Frames:
    """What one camera delivered: stream facts and the (timestamp ms, array) frames of each stream."""

    name: str
    serial: str
    depth_scale: float
    intrinsics: Intrinsics
    depth_intrinsics: Intrinsics
    depth_to_colour: tuple[np.ndarray, np.ndarray]
    depth: list[tuple[float, np.ndarray]] = field(default_factory=list)
    colour: list[tuple[float, np.ndarray]] = field(default_factory=list)
    recording: Path | None = None


def _stream_facts(rs: ModuleType, name: str, dev: Any, profiles: Any, recording: Path | None) -> _Frames:
    by_type = {p.stream_type(): p for p in profiles}
    if rs.stream.depth not in by_type or rs.stream.color not in by_type:
        raise RecordingError(f"{name}: {recording or 'the camera'} lacks a depth or colour stream "
                             f"(has {sorted(str(s) for s in by_type)})")
    dp, cp = by_type[rs.stream.depth], by_type[rs.stream.color]
    scale = float(dev.first_depth_sensor().get_depth_scale())
    ext = dp.get_extrinsics_to(cp)
    serial = dev.get_info(rs.camera_info.serial_number) if dev.supports(rs.camera_info.serial_number) else ""
    return _Frames(name, serial, scale, Intrinsics.from_realsense(cp.as_video_stream_profile().get_intrinsics()),
                   Intrinsics.from_realsense(dp.as_video_stream_profile().get_intrinsics()),
                   (np.asarray(ext.rotation, dtype=np.float64).reshape(3, 3).T,  # librealsense: column-major
                    np.asarray(ext.translation, dtype=np.float64) / scale), recording=recording)


def _read_recording(rs: ModuleType, name: str, path: Path, config: CaptureConfig) -> _Frames:
    """Every frame of a recording, copied inside the sensor callbacks: non-real-time playback waits for
    a callback but drops frames a slow pipeline consumer has not taken yet (measured), so no pipeline."""
    import time

    try:
        dev = rs.context().load_device(str(path))
    except RuntimeError as e:
        raise RecordingError(f"{name}: cannot open recording {path}: {e}") from e
    pb = dev.as_playback()
    pb.set_real_time(False)
    sensors = dev.query_sensors()
    profiles = [p for s in sensors for p in s.get_stream_profiles()]
    frames = _stream_facts(rs, name, dev, profiles, path)

    def on_frame(f: Any) -> None:
        arr = np.asanyarray(f.get_data()).copy()
        st = f.get_profile().stream_type()
        if st == rs.stream.depth:
            frames.depth.append((f.get_timestamp(), arr))
        elif st == rs.stream.color:
            frames.colour.append((f.get_timestamp(), arr))

    for s in sensors:
        s.open(s.get_stream_profiles())
        s.start(on_frame)
    try:
        # the status reads "stopped" until playback has really started: wait for it to play first
        start = time.monotonic() + max(config.timeout_ms / 1000.0, 1.0)
        while (pb.current_status() != rs.playback_status.playing and not frames.depth and not frames.colour
               and time.monotonic() < start):
            time.sleep(0.002)
        deadline = time.monotonic() + max(config.timeout_ms / 1000.0, 1.0) * 60
        while pb.current_status() != rs.playback_status.stopped and time.monotonic() < deadline:
            time.sleep(0.005)
    finally:
        for s in sensors:
            try:
                s.stop()
                s.close()
            except RuntimeError:
                pass
    frames.depth.sort(key=lambda x: x[0])
    frames.colour.sort(key=lambda x: x[0])
    return frames


class _Live:
    """A live camera pipeline (recording to file) and the frames taken from it."""

    def __init__(self, rs: ModuleType, name: str, config: CaptureConfig, serial: str | None, recording: Path) -> None:
        self.config, self.name = config, name
        self.pipe = rs.pipeline()
        cfg = rs.config()
        if serial:
            cfg.enable_device(serial)
        cfg.enable_stream(rs.stream.depth, config.depth_size[0], config.depth_size[1], rs.format.z16, config.fps)
        cfg.enable_stream(rs.stream.color, config.colour_size[0], config.colour_size[1], rs.format.rgb8, config.fps)
        cfg.enable_record_to_file(str(recording))
        try:
            prof = self.pipe.start(cfg)
        except RuntimeError as e:
            raise CaptureError(f"{name}: cannot start camera {serial or '(any)'} with depth {config.depth_size} and "
                               f"colour {config.colour_size} at {config.fps} fps: {e}") from e
        self.frames = _stream_facts(rs, name, prof.get_device(), prof.get_streams(), recording)
        self.seen, self.t0, self.done = 0, None, False

    def poll(self) -> None:
        """Takes the next frameset; done after settling plus ``duration_s`` of frames."""
        ok, fs = self.pipe.try_wait_for_frames(self.config.timeout_ms)
        if not ok:
            raise CaptureError(f"{self.name}: no frames from camera {self.frames.serial} within "
                               f"{self.config.timeout_ms} ms (USB 3 port? cable?)")
        self.seen += 1
        d, c = fs.get_depth_frame(), fs.get_color_frame()
        if d:
            self.frames.depth.append((d.get_timestamp(), np.asanyarray(d.get_data()).copy()))
            if self.seen > self.config.settle_frames:
                self.t0 = d.get_timestamp() if self.t0 is None else self.t0
                self.done = d.get_timestamp() - self.t0 >= self.config.duration_s * 1000.0
        if c:
            self.frames.colour.append((c.get_timestamp(), np.asanyarray(c.get_data()).copy()))
        # keep memory bounded: only settling frames are dropped, acquisition frames are subsampled later
        if len(self.frames.depth) > self.config.settle_frames + 4 * self.config.fps * self.config.duration_s:
            raise CaptureError(f"{self.name}: frame timestamps do not advance; check the camera's clock")

    def stop(self) -> None:
        """Stops the pipeline (finishes the recording)."""
        with contextlib.suppress(RuntimeError):
            self.pipe.stop()


#: Files a capture writes into each ``OUT/<camera>/`` (besides the live recording).
CAPTURE_FILES = ("color.png", "depth.png", "camera.json")


def _reduce(frames: _Frames, config: CaptureConfig, folder: Path) -> CameraCapture:
    """Settling skip, acquisition window, subsampling, temporal median, alignment, files."""
    cv2 = require("cv2")

    where = f"recording {frames.recording}" if frames.recording else f"camera {frames.serial}"
    depth = frames.depth[config.settle_frames:]
    if not depth or not frames.colour:
        raise RecordingError(f"{frames.name}: no frames left from {where} after skipping {config.settle_frames} "
                             "settling frames; record longer or lower settle_frames")
    t0 = depth[0][0]
    window = [a for t, a in depth if t - t0 < config.duration_s * 1000.0]
    step = max(1, math.ceil(len(window) / max(config.max_frames, 1)))
    window = window[::step]
    t_mid = t0 + config.duration_s * 500.0
    t_mid = min(t_mid, (t0 + depth[min(len(depth), len(window) * step) - 1][0]) / 2.0)
    colour = min(frames.colour, key=lambda x: abs(x[0] - t_mid))[1]
    median = temporal_median(np.asarray(window))
    aligned = align_depth_to_colour(median, frames.depth_intrinsics, frames.intrinsics, *frames.depth_to_colour)
    folder.mkdir(parents=True, exist_ok=True)
    if not cv2.imwrite(str(folder / "depth.png"), aligned) or not cv2.imwrite(
            str(folder / "color.png"), cv2.cvtColor(colour, cv2.COLOR_RGB2BGR)):
        raise CaptureError(f"{frames.name}: cannot write images into {folder}")
    meta = {
        "name": frames.name, "serial": frames.serial, "intrinsics": frames.intrinsics.to_json(),
        "depth_intrinsics": frames.depth_intrinsics.to_json(), "depth_scale": frames.depth_scale,
        "frames": len(window), "duration_s": config.duration_s, "depth": "depth.png", "color": "color.png",
        "recording": None if frames.recording is None else str(frames.recording),
    }
    (folder / "camera.json").write_text(json.dumps(meta, indent=2))
    return CameraCapture(frames.name, frames.serial, colour, aligned, frames.depth_scale, frames.intrinsics,
                         frames.depth_intrinsics, len(window), folder, frames.recording)


def capture(
    out_dir: PathLike,
    serials: Mapping[str, str] | None = None,
    config: CaptureConfig = CaptureConfig(),
    *,
    from_recording: bool | Mapping[str, PathLike] = False,
    overwrite: bool = False,
) -> dict[str, CameraCapture]:
    """Captures every camera of ``serials`` ({"front": serial, "back": serial}) at once into
    ``out_dir/<camera>/`` (see the module doc), recording the raw streams.

    ``from_recording=True`` replays ``out_dir/<camera>/recording.db3`` (or ``.bag``) for the cameras of
    ``serials`` (default front and back); a mapping {camera: file} replays those files. Replays run through
    the same code, as fast as possible, without recording again.

    Nothing existing is replaced unless ``overwrite``: a live capture refuses a non-empty camera folder, a
    replay refuses a camera folder that already holds color.png, depth.png or camera.json
    (:class:`bsv.errors.OutputExistsError`)."""
    rs = import_realsense()
    out = Path(out_dir)
    replay = from_recording is not False
    if replay:
        if isinstance(from_recording, Mapping):
            files = {k: Path(v) for k, v in from_recording.items()}
        else:
            names = list(serials) if serials else list(CAMERAS)
            files = {}
            for k in names:
                cands = [out / k / "recording.db3", out / k / "recording.bag"]
                hit = next((c for c in cands if c.exists()), None)
                if hit is None:
                    raise RecordingError(f"{k}: no recording at {cands[0]} (or .bag); capture first or name the files")
                files[k] = hit
        for k, f in files.items():
            if not f.is_file():
                raise RecordingError(f"{k}: recording {f} does not exist")
        plan: dict[str, tuple[str | None, Path]] = {k: (None, f) for k, f in files.items()}
    else:
        if not serials:
            found = _check_devices(rs, None)
            if len(found) < 2:
                raise NoCameraError(f"need two RealSense cameras (front, back), found {len(found)}: {found}")
            serials = dict(zip(CAMERAS, sorted(found), strict=False))
        else:
            _check_devices(rs, list(serials.values()))
        plan = {k: (s, out / k / "recording.db3") for k, s in serials.items()}
    for k in plan:
        folder = out / k
        if not overwrite:
            if not replay and folder.exists() and any(folder.iterdir()):
                raise OutputExistsError(f"{folder} is not empty; pass overwrite=True (--overwrite) to replace the capture")
            existing = [n for n in CAPTURE_FILES if (folder / n).exists()]
            if replay and existing:
                raise OutputExistsError(f"{folder} already holds {', '.join(existing)} (a reduced capture); pass "
                                        "overwrite=True (--overwrite) to replace them from the recording")
        folder.mkdir(parents=True, exist_ok=True)
        if not replay:
            rec = folder / "recording.db3"
            if rec.exists():
                rec.unlink()
    if replay:
        return {k: _reduce(_read_recording(rs, k, rec, config), config, out / k) for k, (_, rec) in plan.items()}
    cams: list[_Live] = []
    try:
        for k, (s, rec) in plan.items():
            cams.append(_Live(rs, k, config, s, rec))
        while not all(c.done for c in cams):
            for c in cams:
                if not c.done:
                    c.poll()
    finally:
        for c in cams:
            c.stop()
    return {c.name: _reduce(c.frames, config, out / c.name) for c in cams}


def read_capture(folder: PathLike) -> dict[str, Any]:
    """Reads one camera folder (a capture's or the virtual scanner's): colour (RGB uint8), depth in metres
    (float64, 0 = none), its camera.json and the intrinsics."""
    cv2 = require("cv2")

    d = Path(folder)
    meta = _camera_meta(d)
    depth = cv2.imread(str(d / meta.get("depth", "depth.png")), cv2.IMREAD_UNCHANGED)
    colour = cv2.imread(str(d / meta.get("color", "color.png")), cv2.IMREAD_COLOR)
    if depth is None or colour is None or depth.dtype != np.uint16:
        raise CaptureError(f"{d}: missing colour PNG or 16-bit depth PNG")
    intrinsics = Intrinsics.from_json(meta["intrinsics"], f"{d}/camera.json")
    if depth.shape != (intrinsics.height, intrinsics.width) or colour.shape[:2] != depth.shape:
        raise CaptureError(f"{d}: depth {depth.shape[::-1]} and colour {colour.shape[1::-1]} images must both be "
                           f"{intrinsics.width} x {intrinsics.height} as camera.json's intrinsics say; capture again")
    return {"colour": cv2.cvtColor(colour, cv2.COLOR_BGR2RGB), "depth_m": depth.astype(np.float64) * meta["depth_scale"],
            "intrinsics": intrinsics, "meta": meta}


def _camera_meta(d: Path) -> dict[str, Any]:
    """The checked contents of ``d/camera.json``: an object with ``intrinsics`` and a positive numeric
    ``depth_scale``; image file names, when given, are strings."""
    where = d / "camera.json"
    try:
        meta = json.loads(where.read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as e:
        raise CaptureError(f"{d}: missing or malformed camera.json ({e}); capture or scan into it first") from e
    if not isinstance(meta, dict):
        raise CaptureError(f"{where}: expected a JSON object with intrinsics and depth_scale, got {type(meta).__name__}")
    missing = [k for k in ("intrinsics", "depth_scale") if k not in meta]
    if missing:
        raise CaptureError(f"{where}: missing {', '.join(missing)}; write it with bsv capture (or bsv.scan) again")
    scale = meta["depth_scale"]
    if isinstance(scale, bool) or not isinstance(scale, int | float) or not (0 < scale < 1):
        raise CaptureError(f"{where}: depth_scale {scale!r} must be a number of metres per depth unit, e.g. 0.00025 "
                           "(L515) or 0.001 (D4xx)")
    for key in ("depth", "color"):
        if key in meta and not isinstance(meta[key], str):
            raise CaptureError(f"{where}: {key} must be an image file name, got {meta[key]!r:.40}")
    return meta

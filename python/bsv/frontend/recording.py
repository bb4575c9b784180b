"""Writing RealSense recordings from synthetic frames (``rs.software_device`` + ``rs.recorder``), so that
the capture code can be exercised end to end with no camera (tests, the demo). This pyrealsense2 build
(2.59) writes ROS2 ``.db3`` recordings (``rs.recorder`` refuses other extensions); it plays ``.db3`` and
``.bag`` files back."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np

from ..errors import OutputExistsError
from ..extras import require
from .errors import RecordingError
from .intrinsics import Intrinsics

PathLike = str | Path


def _rs_intrinsics(rs: ModuleType, intr: Intrinsics) -> Any:
    ri = rs.intrinsics()
    ri.width, ri.height = int(intr.width), int(intr.height)
    ri.fx, ri.fy, ri.ppx, ri.ppy = float(intr.fx), float(intr.fy), float(intr.cx), float(intr.cy)
    ri.model = rs.distortion.brown_conrady
    ri.coeffs = [float(c) for c in intr.coeffs]
    return ri


def write_recording(
    path: PathLike,
    depth: Sequence[np.ndarray],
    colour: Sequence[np.ndarray],
    depth_intrinsics: Intrinsics,
    colour_intrinsics: Intrinsics,
    *,
    depth_scale: float = 0.00025,
    fps: int = 30,
    serial: str = "000000000000",
    name: str = "BSV software camera",
    depth_to_colour: tuple[np.ndarray, np.ndarray] | None = None,
    overwrite: bool = False,
) -> Path:
    """Records synthetic frames as a RealSense recording: ``depth`` uint16 (H x W, device units of
    ``depth_scale`` metres), ``colour`` uint8 RGB (H x W x 3), one pair per frame at ``fps``; the
    depth-to-colour extrinsics (rotation 3 x 3, translation metres) default to identity. An existing file
    is refused (:class:`bsv.errors.OutputExistsError`) unless ``overwrite``."""
    rs = require("pyrealsense2")

    p = Path(path)
    if p.suffix != ".db3":
        raise RecordingError(f"{p}: this pyrealsense2 build records only .db3 files; use a .db3 name")
    if len(depth) == 0 or len(depth) != len(colour):
        raise RecordingError(f"{p}: need as many depth as colour frames (and at least one), got {len(depth)} / {len(colour)}")
    for d in depth:
        if d.dtype != np.uint16 or d.shape != (depth_intrinsics.height, depth_intrinsics.width):
            raise RecordingError(f"{p}: depth frames must be uint16 {depth_intrinsics.height} x {depth_intrinsics.width}")
    for c in colour:
        if c.dtype != np.uint8 or c.shape != (colour_intrinsics.height, colour_intrinsics.width, 3):
            raise RecordingError(f"{p}: colour frames must be uint8 {colour_intrinsics.height} x {colour_intrinsics.width} x 3")
    if p.exists() and not overwrite:
        raise OutputExistsError(f"{p} already exists; pass overwrite=True to replace the recording")
    p.parent.mkdir(parents=True, exist_ok=True)
    if p.exists():
        p.unlink()
    dev = rs.software_device()
    ds = dev.add_sensor("Depth")
    cs = dev.add_sensor("Color")
    vs = rs.video_stream()
    vs.type, vs.index, vs.uid, vs.fps, vs.bpp, vs.fmt = rs.stream.depth, 0, 0, int(fps), 2, rs.format.z16
    vs.width, vs.height, vs.intrinsics = depth_intrinsics.width, depth_intrinsics.height, _rs_intrinsics(rs, depth_intrinsics)
    dp = ds.add_video_stream(vs, True)
    ds.add_read_only_option(rs.option.depth_units, float(depth_scale))
    cv = rs.video_stream()
    cv.type, cv.index, cv.uid, cv.fps, cv.bpp, cv.fmt = rs.stream.color, 0, 1, int(fps), 3, rs.format.rgb8
    cv.width, cv.height, cv.intrinsics = colour_intrinsics.width, colour_intrinsics.height, _rs_intrinsics(rs, colour_intrinsics)
    cp = cs.add_video_stream(cv, True)
    ext = rs.extrinsics()
    r, t = depth_to_colour if depth_to_colour is not None else (np.eye(3), np.zeros(3))
    ext.rotation = [float(v) for v in np.asarray(r, dtype=np.float64).T.ravel()]  # librealsense: column-major
    ext.translation = [float(v) for v in np.asarray(t, dtype=np.float64).ravel()]
    dp.register_extrinsics_to(cp, ext)
    dev.register_info(rs.camera_info.serial_number, str(serial))
    dev.register_info(rs.camera_info.name, str(name))
    dev.create_matcher(rs.matchers.default)
    recorder = rs.recorder(str(p), dev)
    q = rs.frame_queue(len(depth) * 2 + 4)
    ds.open(dp)
    cs.open(cp)
    ds.start(q)
    cs.start(q)
    try:
        for i, (d, c) in enumerate(zip(depth, colour, strict=True)):
            ts = i * 1000.0 / fps
            for sensor, prof, img, bpp in ((ds, dp, np.ascontiguousarray(d), 2), (cs, cp, np.ascontiguousarray(c), 3)):
                f = rs.software_video_frame()
                f.pixels, f.stride, f.bpp = img, img.shape[1] * bpp, bpp
                f.timestamp, f.domain, f.frame_number = ts, rs.timestamp_domain.hardware_clock, i
                f.profile = prof.as_video_stream_profile()
                sensor.on_video_frame(f)
    finally:
        ds.stop()
        cs.stop()
        ds.close()
        cs.close()
        del recorder
    return p

"""Capture sources of the station: the virtual rig (a synthetic subject of :mod:`bsv.bodies` rendered by
:func:`bsv.scan`, for training and tests), a replay of a RealSense recording, and the two live RealSense
cameras (both through :func:`bsv.frontend.capture.capture`), plus the check of an uploaded capture.

A swollen segment on the virtual rig uses MakeHuman's own local modifiers (``arms/l-lowerarm-fat`` and
the like, :class:`bsv.bodies.Phenotype` ``local``): at +1 the forearm of cohort subject 0 grows by 28 %,
the other segments by at most 1 %.
"""

from __future__ import annotations

import json
import zipfile
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from ..errors import CaptureError

#: Swellings the virtual rig can give its subject: the segment -> the local modifiers set to +1.
SWELLINGS: dict[str, dict[str, float]] = {
    "forearm_l": {"arms/l-lowerarm-fat": 1.0},
    "forearm_r": {"arms/r-lowerarm-fat": 1.0},
    "upper_arm_l": {"arms/l-upperarm-fat": 1.0},
    "upper_arm_r": {"arms/r-upperarm-fat": 1.0},
    "thigh_l": {"legs/l-upperleg-fat": 1.0},
    "thigh_r": {"legs/r-upperleg-fat": 1.0},
}
#: Capture sources (the form's choices).
SOURCES = ("virtual", "replay", "realsense")
#: Files a capture folder (or an uploaded zip) must hold, relative to its root.
CAPTURE_FILES = tuple(f"{cam}/{name}" for cam in ("front", "back") for name in ("color.png", "depth.png", "camera.json"))
#: The calibration file at the root of a virtual or uploaded capture.
CALIBRATION = "calibration.json"


def virtual_body(index: int, seed: int, swollen: str | None) -> tuple[Any, dict[str, float]]:
    """Cohort subject ``index`` of ``seed`` as a labelled mesh, with segment ``swollen`` (a key of
    :data:`SWELLINGS`) swollen, and its true volumes (L)."""
    from .. import bodies

    subj = bodies.subject(index, seed)
    body = subj.body
    if swollen:
        if swollen not in SWELLINGS:
            raise CaptureError(f"swollen segment {swollen!r} unknown; choose one of {sorted(SWELLINGS)}")
        ph = subj.phenotype.with_(local={**subj.phenotype.local, **SWELLINGS[swollen]})
        body = bodies.make_body(ph, subj.pose)
    return body.mesh(), body.volumes_l()


def render_virtual(out: Path, params: Mapping[str, Any]) -> dict[str, Any]:
    """Render a virtual-rig capture of ``params`` (index, seed, swollen, condition, rig_seed) into ``out``
    (which must not exist); returns the source information stored with the session."""
    from .. import scan

    mesh, truth = virtual_body(int(params.get("index", 0)), int(params.get("seed", 0)), params.get("swollen") or None)
    scan(mesh, str(params.get("condition", "l515")), int(params.get("rig_seed", 0)), images=out, room=True)
    return {"true_volumes_l": truth, **{k: params[k] for k in ("index", "seed", "swollen", "condition", "rig_seed")
                                         if k in params}}


def record(out: Path, source: str, params: Mapping[str, Any]) -> dict[str, Any]:
    """A replay (``params["recording_dir"]`` holding front/ and back/ recording.db3) or a live capture of
    both RealSense cameras into ``out``."""
    from ..frontend.capture import CaptureConfig, capture

    config = CaptureConfig(duration_s=float(params.get("seconds", 5.0)))
    if source == "replay":
        rec = Path(str(params.get("recording_dir", "")))
        files = {cam: rec / cam / "recording.db3" for cam in ("front", "back")}
        missing = [str(f) for f in files.values() if not f.is_file()]
        if missing:
            raise CaptureError(f"no recording at {', '.join(missing)}; give a folder with front/ and back/ "
                               "recording.db3 (written by bsv capture)")
        capture(out, None, config, from_recording=files)
        return {"recording_dir": "replay"}
    caps = capture(out, None, config)
    return {"serials": {k: str(getattr(v, "serial", "")) for k, v in caps.items()}}


def camera_status() -> dict[str, Any]:
    """The RealSense cameras connected (serial numbers), or why none can be listed."""
    try:
        from ..frontend.capture import connected_serials

        serials = connected_serials()
    except Exception as e:  # pyrealsense2 missing, libusb missing, USB errors: shown on the page
        return {"serials": [], "error": f"{type(e).__name__}: {e}"}
    return {"serials": serials, "error": ""}


def alignment_frame(camera: str, width: int = 1280, height: int = 720) -> bytes:
    """One colour frame of the ``camera`` RealSense ("front": the lowest serial, "back": the next, as
    :func:`bsv.frontend.capture.capture` assigns them) with the calibration marker outlined and the
    rotation and translation still to correct ("ALIGNED" within tolerance), as JPEG: the browser's live
    alignment guidance (:func:`bsv.frontend.calibrate.alignment`). Raises NoCameraError without cameras."""
    import cv2
    import numpy as np

    from ..errors import CalibrationError, NoCameraError
    from ..frontend.calibrate import alignment, detect_marker, draw_alignment, marker_pose
    from ..frontend.capture import connected_serials, import_realsense, open_colour_stream
    from ..frontend.marker import Board

    rs = import_realsense()
    serials = sorted(connected_serials())
    index = ("front", "back").index(camera)
    if len(serials) <= index:
        raise NoCameraError(f"no {camera} RealSense camera: {len(serials)} connected")
    pipe, intr = open_colour_stream(rs, serials[index], width, height, 30)
    try:
        frame = None
        for _ in range(10):  # let the auto-exposure settle
            frame = pipe.wait_for_frames().get_color_frame()
        colour = np.asanyarray(frame.get_data()) if frame is not None else None
    finally:
        pipe.stop()
    if colour is None:
        raise NoCameraError(f"the {camera} camera delivered no colour frame")
    bgr = cv2.cvtColor(colour, cv2.COLOR_RGB2BGR)
    marker = Board().marker
    try:
        corners = detect_marker(bgr, marker)
        r, t, _ = marker_pose(corners, intr, marker)
        info = alignment(r, t)
    except CalibrationError:
        corners, info = None, None
    ok, jpg = cv2.imencode(".jpg", draw_alignment(bgr, corners, info, marker))
    if not ok:
        raise CaptureError("the alignment frame could not be encoded")
    return bytes(jpg.tobytes())


def check_capture_zip(data: bytes, out: Path) -> None:
    """Unpack an uploaded capture (a zip of front/ and back/ color.png, depth.png, camera.json and
    calibration.json) into ``out`` after checking it; raises :class:`bsv.errors.CaptureError` naming what
    is missing or wrong. Only the expected files are extracted (no path from the archive is trusted)."""
    import io

    from ..frontend.capture import read_capture

    try:
        zf = zipfile.ZipFile(io.BytesIO(data))
    except zipfile.BadZipFile as e:
        raise CaptureError("the upload is not a zip archive; zip the capture folder (front/, back/, "
                           "calibration.json) and upload that") from e
    with zf:
        names = set(zf.namelist())
        prefix = ""
        if CALIBRATION not in names:
            roots = {n.split("/", 1)[0] + "/" for n in names if "/" in n}
            prefix = next((r for r in sorted(roots) if r + CALIBRATION in names), "")
        wanted = [*CAPTURE_FILES, CALIBRATION]
        missing = [n for n in wanted if prefix + n not in names]
        if missing:
            raise CaptureError(f"the upload is not a capture: missing {', '.join(missing)}")
        for n in wanted:
            info = zf.getinfo(prefix + n)
            if info.file_size > 200_000_000:
                raise CaptureError(f"the upload's {n} is larger than 200 MB")
        out.mkdir(parents=True)
        for n in wanted:
            dest = out / n
            dest.parent.mkdir(parents=True, exist_ok=True)
            dest.write_bytes(zf.read(prefix + n))
    for cam in ("front", "back"):
        read_capture(out / cam)
    try:
        cal = json.loads((out / CALIBRATION).read_text())
    except (UnicodeDecodeError, json.JSONDecodeError) as e:
        raise CaptureError(f"the upload's {CALIBRATION} is not JSON ({e})") from e
    if not isinstance(cal, dict) or "cameras" not in cal:
        raise CaptureError(f"the upload's {CALIBRATION} has no \"cameras\" section; write it with bsv calibrate")


__all__ = ["CALIBRATION", "CAPTURE_FILES", "SOURCES", "SWELLINGS", "alignment_frame", "camera_status", "check_capture_zip", "record",
           "render_virtual", "virtual_body"]

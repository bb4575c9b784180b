"""A capture folder's camera.json is checked when read: every malformed file is a CaptureError naming the
file and the field, never a KeyError/AttributeError/ValueError traceback."""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import pytest

import bsv
from bsv.errors import CaptureError

pytest.importorskip("cv2")
from bsv.frontend.capture import read_capture


@pytest.fixture(scope="module")
def capture(tmp_path_factory: pytest.TempPathFactory) -> Path:
    d = tmp_path_factory.mktemp("capture") / "cap"
    bsv.scan(bsv.default_template(), "noer", 0, images=d)
    return d / "front"


def _with_meta(src: Path, dst: Path, meta: Any) -> Path:
    dst.mkdir()
    for name in ("depth.png", "color.png"):
        (dst / name).write_bytes((src / name).read_bytes())
    (dst / "camera.json").write_text(json.dumps(meta))
    return dst


def test_a_good_capture_reads(capture: Path) -> None:
    data = read_capture(capture)
    assert data["depth_m"].shape == (data["intrinsics"].height, data["intrinsics"].width)
    assert data["depth_m"].max() > 1.0


@pytest.mark.parametrize(("edit", "message"), [
    (lambda m: [m], "expected a JSON object"),
    (lambda m: {k: v for k, v in m.items() if k != "depth_scale"}, "missing depth_scale"),
    (lambda m: {k: v for k, v in m.items() if k != "intrinsics"}, "missing intrinsics"),
    (lambda m: {**m, "depth_scale": "0.00025"}, "depth_scale '0.00025' must be a number"),
    (lambda m: {**m, "depth_scale": -1}, "depth_scale -1 must be a number"),
    (lambda m: {**m, "depth": 5}, "depth must be an image file name"),
    (lambda m: {**m, "intrinsics": {"width": 10}}, "missing or malformed intrinsics"),
    (lambda m: {**m, "intrinsics": {**m["intrinsics"], "width": 100}}, "as camera.json's intrinsics say"),
])
def test_malformed_camera_json_is_a_capture_error(capture: Path, tmp_path: Path, edit: Any, message: str) -> None:
    meta = json.loads((capture / "camera.json").read_text())
    folder = _with_meta(capture, tmp_path / "cam", edit(meta))
    with pytest.raises(bsv.BsvError, match=re.escape(message)) as info:
        read_capture(folder)
    assert "camera.json" in str(info.value)


def test_missing_or_unreadable_camera_json(capture: Path, tmp_path: Path) -> None:
    with pytest.raises(CaptureError, match=r"missing or malformed camera\.json"):
        read_capture(tmp_path)
    (tmp_path / "camera.json").write_bytes(b"\xff\xfe{")
    with pytest.raises(CaptureError, match=r"missing or malformed camera\.json"):
        read_capture(tmp_path)

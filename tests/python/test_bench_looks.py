"""bsv.bench.looks: the rig's record of a capture's look (scan.json) read into factors, and the camera
path's errors tabulated per factor level."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import bsv
from bsv.bench.common import Run
from bsv.bench.looks import INFO_KEY, look_of, looks_markdown, read_look, summarise
from bsv.bodies.variants import LIMB_SEGMENTS


def test_a_room_scan_records_its_look_and_a_plain_one_does_not(tmp_path: Path) -> None:
    body = bsv.bodies.make_body().mesh()
    bsv.scan(body, "noer", 3, images=tmp_path / "room", room=True)
    bsv.scan(body, "noer", 3, images=tmp_path / "plain")
    look = read_look(tmp_path / "room")
    assert look is not None and set(look) == {"lights", "light_colour", "skin", "underwear", "hair", "top",
                                                 "shading", "colour"}
    assert look["lights"] in {"key_front_left", "key_front_right", "overhead", "side"}
    assert read_look(tmp_path / "plain") is None
    assert read_look(tmp_path / "nowhere") is None
    # The same seed, the same look; the record is what the rig drew.
    appearance = json.loads((tmp_path / "room" / "scan.json").read_text())["appearance"]
    assert look == look_of(appearance)


def test_look_of_names_the_levels() -> None:
    rec = {"skin": [80, 52, 36], "tint": [1.0, 0.92, 0.78], "light_setup": "side", "underwear_style": "trunks"}
    assert look_of(rec) == {"lights": "side", "light_colour": "warm", "skin": "darker", "underwear": "trunks",
                            "hair": "none", "top": "none", "shading": "flat",
                            "colour": "exact"}
    rec = {"skin": [255, 224, 196], "tint": [0.88, 0.95, 1.05], "light_setup": "overhead", "underwear_style": "briefs"}
    assert look_of(rec)["light_colour"] == "cool" and look_of(rec)["skin"] == "lighter"
    rec["tint"] = [1.0, 1.0, 1.0]
    assert look_of(rec)["light_colour"] == "neutral"
    assert look_of(rec | {"hair_length_m": 0.06})["hair"] == "short"
    assert look_of(rec | {"hair_length_m": 0.06, "hair_down_m": 0.35})["hair"] == "long"
    assert look_of(rec | {"top": True})["top"] == "top"
    assert look_of(rec | {"smooth_shading": True})["shading"] == "smooth"
    assert look_of(rec | {"colour_sensor": True})["colour"] == "sensor"


def test_long_hair_is_drawn_on_the_back_view_only_when_asked(tmp_path: Path) -> None:
    body = bsv.bodies.make_body().mesh()
    seed = next(s for s in range(40) if _has_hair(tmp_path, body, s))
    bsv.scan(body, "noer", seed, images=tmp_path / "long", room=True, look={"long_hair": True})
    short, long = (json.loads((tmp_path / d / "scan.json").read_text())["appearance"] for d in (f"s{seed}", "long"))
    assert read_look(tmp_path / "long")["hair"] == "long" and read_look(tmp_path / f"s{seed}")["hair"] == "short"
    assert 0.30 <= long["hair_down_m"] <= 0.45 and short["hair_down_m"] == 0.0
    assert {k: v for k, v in long.items() if k != "hair_down_m"} == {k: v for k, v in short.items() if k != "hair_down_m"}
    # The back camera's image changes (hair over the neck and the upper back), the front camera's does not.
    from PIL import Image

    def pixels(folder: str, cam: str) -> np.ndarray:
        return np.asarray(Image.open(tmp_path / folder / cam / "color.png"))

    assert np.array_equal(pixels("long", "front"), pixels(f"s{seed}", "front"))
    changed = np.any(pixels("long", "back") != pixels(f"s{seed}", "back"), axis=2)
    assert changed.sum() > 500
    rows = np.nonzero(changed.any(axis=1))[0]
    assert rows.max() < pixels("long", "back").shape[0] * 0.45  # the upper body only
    with pytest.raises(bsv.InputError, match="look"):
        bsv.scan(body, "noer", seed, room=True, look={"long_hiar": True})
    # A top changes both views' chests.
    bsv.scan(body, "noer", seed, images=tmp_path / "top", room=True, look={"top": True})
    assert read_look(tmp_path / "top")["top"] == "top"
    for cam in ("front", "back"):
        assert np.any(pixels("top", cam) != pixels(f"s{seed}", cam))


def _has_hair(tmp_path: Path, body: Any, seed: int) -> bool:
    """Scans ``body`` in the room with seed ``seed`` into tmp_path/s<seed>; whether the subject has hair."""
    bsv.scan(body, "noer", seed, images=tmp_path / f"s{seed}", room=True)
    return json.loads((tmp_path / f"s{seed}" / "scan.json").read_text())["appearance"]["hair_length_m"] > 0


def _run(subject: str, error_pct: float, lights: str) -> Run:
    truth = dict.fromkeys((*LIMB_SEGMENTS, "trunk_limbs"), 1.0)
    est = dict.fromkeys(LIMB_SEGMENTS, 1.0 + error_pct / 100.0) | {"trunk_limbs": 1.0}
    est["shin_l"] = 1.0 - 2 * error_pct / 100.0
    look = {"lights": lights, "light_colour": "neutral", "skin": "lighter", "underwear": "briefs"}
    return Run(subject, "noer", "bsv", True, truth_l=truth, estimated_l=est, info={INFO_KEY: look})


def test_the_table_shows_the_look_that_is_worse() -> None:
    runs = [_run("s0", 1.0, "overhead"), _run("s1", 3.0, "side"), _run("s2", 1.0, "side"),
            Run("s3", "noer", "bsv", False), Run("s4", "noer", "trimesh", True)]
    table = summarise(runs)["noer"]
    side, overhead = table["lights"]["side"], table["lights"]["overhead"]
    assert side["n"] == 2 and overhead["n"] == 1
    # seven limbs +e %, one -2e %: mean RVE 9e/8
    assert overhead["limbs_rve"] == pytest.approx(9 / 8) and side["limbs_rve"] == pytest.approx((27 / 8 + 9 / 8) / 2)
    assert side["worst"] == pytest.approx(-6.0) and side["worst_subject"] == "s1 shin_l"
    assert table["skin"]["lighter"]["n"] == 3
    md = "\n".join(looks_markdown(runs))
    assert "| light set-up | side | 2 | 2.25 | 0.00 | -6.0 (s1 shin_l) |" in md
    assert looks_markdown([Run("s0", "noer", "bsv", True)]) == []


def _image(folder: Path, cam: str, name: str) -> np.ndarray:
    from PIL import Image

    return np.asarray(Image.open(folder / cam / name))


def _kinks(colour: np.ndarray, body_px: np.ndarray) -> float:
    """The share of body pixels whose brightness kinks (second difference along the row over 2 levels)."""
    y = colour.astype(np.float64).mean(axis=2)
    inner = body_px[:, 2:] & body_px[:, 1:-1] & body_px[:, :-2]
    return float((np.abs(np.diff(y, n=2, axis=1))[inner] > 2.0).mean())


def _scan_with_and_without(tmp_path: Path, look: str) -> tuple[Path, Path]:
    """The same body and seed scanned in the room as drawn and with ``look`` on; their folders, and each view's
    depth and labels checked equal (a look changes the colour only)."""
    body = bsv.bodies.make_body().mesh()
    plain, with_look = tmp_path / "plain", tmp_path / look
    bsv.scan(body, "noer", 4, images=plain, room=True)
    bsv.scan(body, "noer", 4, images=with_look, room=True, look={look: True})
    for cam in ("front", "back"):
        for name in ("depth.png", "labels.png"):
            assert np.array_equal(_image(plain, cam, name), _image(with_look, cam, name)), (cam, name)
    return plain, with_look


def test_smooth_shading_changes_the_skins_colour_only(tmp_path: Path) -> None:
    flat, smooth = _scan_with_and_without(tmp_path, "smooth_shading")
    assert read_look(smooth)["shading"] == "smooth" and read_look(flat)["shading"] == "flat"
    for cam in ("front", "back"):
        f, s = _image(flat, cam, "color.png"), _image(smooth, cam, "color.png")
        changed = np.any(f != s, axis=2)
        body_px = _image(flat, cam, "labels.png") > 0
        assert changed[body_px].mean() > 0.3  # the skin's shading moves on most of the body ...
        assert not changed[~body_px].any()  # ... and nothing else does
        # The facets' edges are gone: the brightness kinks between triangles of different normals.
        assert _kinks(s, body_px) < 0.5 * _kinks(f, body_px)


def test_the_colour_sensor_changes_the_colour_images_only(tmp_path: Path) -> None:
    exact, sensor = _scan_with_and_without(tmp_path, "colour_sensor")
    assert read_look(sensor)["colour"] == "sensor" and read_look(exact)["colour"] == "exact"
    for cam in ("front", "back"):
        diff = _image(sensor, cam, "color.png").astype(np.float64) - _image(exact, cam, "color.png")
        assert 1.5 < float(np.sqrt(np.mean(diff ** 2))) < 6.0  # a few levels of noise, and the blurred edges
        assert abs(float(diff.mean())) < 0.5  # no change of brightness

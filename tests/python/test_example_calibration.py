"""The README's example calibration images (``examples/calib``, written by
``scripts/make_example_calibration.py`` from the virtual rig): ``bsv calibrate`` on them recovers the rig's
true extrinsics to the tolerance of tests/python/test_calibrate.py, they are what the script makes from the
current rig, and they stay small."""

from __future__ import annotations

import importlib.util
import json
import sys
from pathlib import Path
from types import ModuleType

import numpy as np
import pytest

cv2 = pytest.importorskip("cv2")

import bsv  # noqa: E402
from bsv.frontend import calibrate as cal  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
CALIB = ROOT / "examples" / "calib"
SIDES = ("front", "back")
#: tests/python/test_calibrate.py: test_extrinsics_recovered_both_cameras
MAX_MM, MAX_DEG = 2.0, 0.2


def _script() -> ModuleType:
    spec = importlib.util.spec_from_file_location("make_example_calibration",
                                                  ROOT / "scripts" / "make_example_calibration.py")
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod  # its dataclass looks its module up
    spec.loader.exec_module(mod)
    return mod


@pytest.fixture(scope="module")
def rig(tmp_path_factory: pytest.TempPathFactory) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """The virtual rig's true camera-to-world poses, from a fresh exact scan's camera.json files."""
    cap = tmp_path_factory.mktemp("rig") / "capture"
    bsv.scan(bsv.default_template(), "noer", 0, images=cap)
    out = {}
    for side in SIDES:
        pose = json.loads((cap / side / "camera.json").read_text())["true_camera_to_world"]
        out[side] = (np.asarray(pose["rotation"]), np.asarray(pose["translation"]))
    return out


def test_bsv_calibrate_recovers_the_rig_from_the_examples(rig: dict, tmp_path: Path) -> None:
    out = tmp_path / "calibration.json"
    rc = cal.main(["--images", *(f"{s}={CALIB / s}" for s in SIDES),
                   "--intrinsics", *(f"{s}={CALIB / s / 'camera.json'}" for s in SIDES), "-o", str(out)])
    assert rc == 0
    result = cal.read_calibration(out)
    for side in SIDES:
        r_true, t_true = rig[side]
        c = result.cameras[side]
        mm = float(np.linalg.norm(c.translation - t_true)) * 1000.0
        deg = cal.rotation_angle_deg(c.rotation, r_true)
        print(f"{side}: {mm:.2f} mm, {deg:.4f} deg from the rig; {c.frames} frames")
        assert mm < MAX_MM and deg < MAX_DEG, (side, mm, deg)
        assert c.frames == len(list((CALIB / side).glob("*.png")))


def test_the_examples_are_what_the_script_makes_from_the_current_rig(tmp_path: Path) -> None:
    _script().write_examples(tmp_path)
    shipped = sorted(p.relative_to(CALIB) for p in CALIB.rglob("*") if p.is_file())
    made = sorted(p.relative_to(tmp_path) for p in tmp_path.rglob("*") if p.is_file())
    assert shipped == made
    for rel in shipped:
        if rel.suffix == ".png":  # pixels, not bytes: PNG encoders may differ between builds
            a = cv2.imread(str(CALIB / rel), cv2.IMREAD_UNCHANGED)
            b = cv2.imread(str(tmp_path / rel), cv2.IMREAD_UNCHANGED)
            assert a is not None and b is not None and a.shape == b.shape
            assert np.array_equal(a, b), f"{rel}: regenerate with python scripts/make_example_calibration.py --overwrite"
        else:
            assert json.loads((CALIB / rel).read_text()) == json.loads((tmp_path / rel).read_text()), rel


def test_the_examples_are_small() -> None:
    total = sum(p.stat().st_size for p in CALIB.rglob("*") if p.is_file())
    assert 0 < total < 3_000_000, f"examples/calib holds {total / 1e6:.2f} MB"

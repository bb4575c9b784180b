"""The rig with a room (``bsv.scan(..., room=...)``) and the ground-truth surface distances."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

import bsv


def test_scan_in_a_room_writes_the_floor_and_a_painted_render(tmp_path: Path) -> None:
    t = bsv.default_template()
    plain = bsv.scan(t, "noer", seed=1, images=tmp_path / "plain")
    roomed = bsv.scan(t, "noer", seed=1, images=tmp_path / "room", room=True)
    # The cloud is the person only: identical to the empty-background scan in noer.
    np.testing.assert_array_equal(plain.points, roomed.points)
    np.testing.assert_array_equal(plain.labels, roomed.labels)
    for cam in ("front", "back"):
        meta = json.loads((tmp_path / "room" / cam / "camera.json").read_text())
        depth = np.asarray(Image.open(tmp_path / "room" / cam / "depth.png")).astype(float) * meta["depth_scale"]
        labels = np.asarray(Image.open(tmp_path / "room" / cam / "labels.png"))
        old = np.asarray(Image.open(tmp_path / "plain" / cam / "depth.png"))
        # The bottom rows see the floor in front of the feet: depth where the plain scan had none, label 0.
        bottom = (slice(980, 1024), slice(0, 100))
        assert np.all(old[bottom] == 0) and np.all(depth[bottom] > 1.0) and np.all(labels[bottom] == 0)
        # The camera is 1 m above the floor: the bottom row's depth is the plane's, about 1 / tan(35 deg).
        assert abs(np.median(depth[1023, 300:468]) - 1.0 / np.tan(np.radians(35.0))) < 0.02
        colour = np.asarray(Image.open(tmp_path / "room" / cam / "color.png"))
        grey = np.asarray(Image.open(tmp_path / "plain" / cam / "color.png"))
        assert colour.shape == grey.shape and np.mean(np.any(colour != grey, axis=2)) > 0.5


def test_room_parameters_are_checked() -> None:
    t = bsv.default_template()
    with pytest.raises(bsv.ScanError, match="back_wall_z") as e:
        bsv.scan(t, room={"back_wall_z": -1.0})
    assert e.value.parameter == "room.back_wall_z"
    with pytest.raises(bsv.InputError, match="bak_wall_z"):
        bsv.scan(t, room={"bak_wall_z": -3.0})
    with pytest.raises(bsv.InputError, match="room"):
        bsv.scan(t, room="yes")  # type: ignore[arg-type]


def _uv_sphere(r: float, rings: int, segments: int) -> tuple[np.ndarray, np.ndarray]:
    th = np.linspace(0.0, np.pi, rings + 1)[1:-1]
    ph = np.linspace(0.0, 2 * np.pi, segments, endpoint=False)
    t, p = np.meshgrid(th, ph, indexing="ij")
    v = np.concatenate([[[0.0, 0.0, r]], np.stack([r * np.sin(t) * np.cos(p), r * np.sin(t) * np.sin(p),
                                                   r * np.cos(t)], axis=-1).reshape(-1, 3), [[0.0, 0.0, -r]]])
    ring = lambda k, s: 1 + k * segments + s % segments  # noqa: E731
    f = [[0, ring(0, s), ring(0, s + 1)] for s in range(segments)]
    for k in range(rings - 2):
        for s in range(segments):
            f += [[ring(k, s), ring(k + 1, s), ring(k + 1, s + 1)], [ring(k, s), ring(k + 1, s + 1), ring(k, s + 1)]]
    last = len(v) - 1
    f += [[last, ring(rings - 2, s + 1), ring(rings - 2, s)] for s in range(segments)]
    return v, np.asarray(f)


def test_surface_distances_to_a_sphere_and_a_box() -> None:
    v = np.array([[x, y, z] for z in (0, 1) for y in (0, 1) for x in (0, 1)], dtype=float)
    f = np.array([[0, 2, 3], [0, 3, 1], [4, 5, 7], [4, 7, 6], [0, 1, 5], [0, 5, 4],
                  [2, 6, 7], [2, 7, 3], [0, 4, 6], [0, 6, 2], [1, 3, 7], [1, 7, 5]])
    pts = np.array([[0.5, 0.5, 0.5], [2.0, 0.5, 0.5], [0.5, 0.5, 1.0], [2.0, 2.0, 0.5], [0.1, 0.5, 0.5]])
    d = bsv.surface_distances(pts, bsv.Mesh(v, f))
    np.testing.assert_allclose(d, [0.5, 1.0, 0.0, np.sqrt(2.0), 0.1], atol=1e-12)
    # A fine UV sphere of radius 0.5: distance = | |p| - r | up to the facets' sagitta (< 0.4 mm).
    sv, sf = _uv_sphere(0.5, 64, 128)
    rng = np.random.default_rng(0)
    q = rng.normal(size=(500, 3))
    q *= rng.uniform(0.1, 1.5, size=(500, 1)) / np.linalg.norm(q, axis=1, keepdims=True)
    d = bsv.surface_distances(q, bsv.Mesh(sv, sf))
    np.testing.assert_allclose(d, np.abs(np.linalg.norm(q, axis=1) - 0.5), atol=5e-4)
    with pytest.raises(bsv.InputError, match="non-finite") as e:
        bsv.surface_distances(np.array([[np.nan, 0.0, 0.0]]), bsv.Mesh(v, f))
    assert e.value.index == 0


def test_bench_renders_a_room_on_the_camera_path_and_reports_far_points() -> None:
    from bsv.bench.common import Run, cloud_far_pct
    from bsv.bench.main import parser
    from bsv.bench.synth import SynthConfig
    from bsv.bench.tables import CSV_COLUMNS, cloud_table, rows

    assert not SynthConfig().uses_room()
    assert SynthConfig(segmentation="camera").uses_room() and SynthConfig(cloud="lab").uses_room()
    assert not SynthConfig(cloud="lab", room=False).uses_room() and SynthConfig(room=True).uses_room()
    assert parser().parse_args(["synth", "--no-room"]).room is False
    assert parser().parse_args(["synth"]).room is None
    t = bsv.default_template()
    c = bsv.scan(t, "noer", seed=0)
    assert cloud_far_pct(c, t) == (0.0, 0.0)
    shifted = bsv.PointCloud(c.points + np.array([0.0, 0.0, 0.05]), labels=c.labels)
    f2, f10 = cloud_far_pct(shifted, t)
    assert 10.0 < f2 <= 100.0 and f10 == 0.0
    runs = [Run("s0", "noer", "bsv", True, truth_l={"torso": 30.0}, estimated_l={"torso": 31.0},
                cloud_far_2cm_pct=v, cloud_far_10cm_pct=v / 4) for v in (2.0, 4.0)]
    table = cloud_table(runs)
    assert "| noer | bsv | 2 | 3.00 (4.00) | 0.75 (1.00) | \u2013 | \u2013 |" in table
    assert "cloud_far_2cm_pct" in CSV_COLUMNS and rows(runs)[0]["cloud_far_10cm_pct"] == 0.5
    assert cloud_table([Run("s0", "noer", "bsv", True)]) == ""

"""The typed Python API over the Rust core: I/O round trips, checks, volumes, scan, and bad input."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import bsv


def unit_cube() -> tuple[np.ndarray, np.ndarray]:
    v = np.array([[x, y, z] for z in (0, 1) for y in (0, 1) for x in (0, 1)], dtype=float)
    f = np.array(
        [[0, 2, 3], [0, 3, 1], [4, 5, 7], [4, 7, 6], [0, 1, 5], [0, 5, 4],
         [2, 6, 7], [2, 7, 3], [0, 4, 6], [0, 6, 2], [1, 3, 7], [1, 7, 5]]
    )
    return v, f


def test_unit_cube_volume_and_check() -> None:
    v, f = unit_cube()
    rep = bsv.volumes(v, f)
    assert abs(rep["volumes_l"]["whole"] - 1000.0) < 1e-9
    chk = bsv.check_mesh(v, f)
    assert chk["boundary_edges"] == 0 and chk["non_manifold_edges"] == 0


def test_labelled_template_volumes_sum_to_whole() -> None:
    t = bsv.default_template()
    rep = bsv.volumes(t)["volumes_l"]
    segs = sum(rep[s] for s in bsv.TRUNK_LIMBS)
    assert abs(segs - rep["whole"]) < 1e-9 * rep["whole"]
    assert abs(rep["trunk_limbs"] - rep["whole"]) < 1e-9
    # Symmetric template: left and right agree.
    assert abs(rep["thigh_l"] - rep["thigh_r"]) < 1e-3 * rep["thigh_l"]
    full = bsv.default_template(full=True)
    assert set(np.unique(full.vertex_labels)) == set(range(1, 15))


def test_absent_segment_is_absent_not_zero() -> None:
    v, f = unit_cube()
    rep = bsv.volumes(v, f, labels=np.full(len(v), 2, dtype=np.uint8))
    assert "torso" in rep["volumes_l"] and "thigh_l" not in rep["volumes_l"]


@pytest.mark.parametrize("ascii", [False, True])
@pytest.mark.parametrize("ext", ["ply", "obj"])
def test_mesh_round_trip(tmp_path: Path, ascii: bool, ext: str) -> None:
    t = bsv.default_template()
    p = tmp_path / f"t.{ext}"
    bsv.write_mesh(p, t, ascii=ascii)
    r = bsv.read_mesh(p)
    tol = 0.0 if ext == "ply" else 1e-6
    assert np.abs(r.vertices - t.vertices).max() <= tol
    if ext == "ply":
        np.testing.assert_array_equal(r.faces, t.faces)
        np.testing.assert_array_equal(r.vertex_labels, t.vertex_labels)
    else:
        # OBJ: one group per segment, so the faces come back grouped by segment id (same faces and labels).
        assert r.face_labels is not None and t.face_labels is not None
        assert np.all(np.diff(r.face_labels.astype(int)) >= 0)
        assert p.read_text().count("\ng ") == len(np.unique(t.face_labels))
        back = sorted(zip(map(tuple, r.faces.tolist()), r.face_labels.tolist(), strict=True))
        want = sorted(zip(map(tuple, t.faces.tolist()), t.face_labels.tolist(), strict=True))
        assert back == want
        assert bsv.volumes(r)["volumes_l"] == pytest.approx(bsv.volumes(t)["volumes_l"], rel=1e-12)


def test_cloud_round_trip_and_no_overwrite(tmp_path: Path) -> None:
    rng = np.random.default_rng(0)
    pts = rng.normal(size=(1000, 3))
    lab = rng.integers(0, 15, size=1000).astype(np.uint8)
    p = tmp_path / "c.ply"
    bsv.write_point_cloud(p, pts, labels=lab)
    c = bsv.read_point_cloud(p)
    np.testing.assert_array_equal(c.points, pts)
    np.testing.assert_array_equal(c.labels, lab)
    with pytest.raises(bsv.OutputExistsError):
        bsv.write_point_cloud(p, pts)
    bsv.write_point_cloud(p, pts[:10], overwrite=True)
    assert len(bsv.read_point_cloud(p)) == 10


def test_bad_files_raise_typed_errors(tmp_path: Path) -> None:
    empty = tmp_path / "empty.ply"
    empty.write_bytes(b"")
    with pytest.raises(bsv.FormatError, match="empty"):
        bsv.read_point_cloud(empty)
    trunc = tmp_path / "trunc.ply"
    trunc.write_bytes(
        b"ply\nformat binary_little_endian 1.0\nelement vertex 10\nproperty float x\nproperty float y\n"
        b"property float z\nend_header\n" + bytes(20)
    )
    with pytest.raises(bsv.FormatError, match="vertex"):
        bsv.read_point_cloud(trunc)
    nan = tmp_path / "nan.ply"
    nan.write_text("ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
                   "property float z\nend_header\n0 0 0\nnan 1 1\n")
    with pytest.raises(bsv.FormatError, match="1"):
        bsv.read_point_cloud(nan)
    oob = tmp_path / "oob.obj"
    oob.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n")
    with pytest.raises(bsv.FormatError, match="7"):
        bsv.read_mesh(oob)
    assert issubclass(bsv.FormatError, bsv.BsvError)


def test_open_and_nonmanifold_meshes_are_volume_errors() -> None:
    v, f = unit_cube()
    with pytest.raises(bsv.VolumeError, match="loop"):
        bsv.volumes(v, f[:-1])
    assert abs(bsv.volumes(v, f[:-1], close_holes=True)["volumes_l"]["whole"] - 1000.0) < 1e-9
    f3 = np.vstack([f, [[0, 1, 6]]])
    with pytest.raises(bsv.VolumeError):
        bsv.volumes(v, f3)


def test_bad_arrays_raise_input_errors() -> None:
    v, f = unit_cube()
    with pytest.raises(bsv.InputError, match="vertex 99"):
        bsv.volumes(v, np.vstack([f, [[0, 1, 99]]]))
    with pytest.raises(bsv.InputError, match=r"\(N, 3\)"):
        bsv.volumes(v[:, :2], f)
    with pytest.raises(bsv.InputError, match="segment ids"):
        bsv.volumes(v, f, labels=np.full(len(v), 20))
    # 270 must not wrap to 14 (foot_r).
    with pytest.raises(bsv.InputError, match="270"):
        bsv.volumes(bsv.Mesh(v, f, np.full(len(v), 270)))
    with pytest.raises(bsv.InputError, match=r"\(N, 3\)"):
        bsv.register(np.zeros(30))
    with pytest.raises(bsv.InputError, match="faces"):
        bsv.volumes(v, f.astype(float) + 0.5)


def test_scan_sees_the_template_front_and_back(tmp_path: Path) -> None:
    t = bsv.default_template()
    c = bsv.scan(t, "noer", seed=0, images=tmp_path / "cap")
    assert len(c) > 50_000
    assert set(np.unique(c.labels)) <= set(range(2, 13))
    # Every point lies inside the template's bounding box (noer: exact depth and extrinsics).
    lo, hi = t.vertices.min(0) - 1e-6, t.vertices.max(0) + 1e-6
    assert np.all((c.points >= lo) & (c.points <= hi))
    assert (tmp_path / "cap" / "front").is_dir() and (tmp_path / "cap" / "back").is_dir()
    with pytest.raises(bsv.ScanError, match="condition"):
        bsv.scan(t, "sunny")


def test_interop_with_duck_typed_meshes() -> None:
    class TrimeshLike:
        def __init__(self, v: np.ndarray, f: np.ndarray) -> None:
            self.vertices, self.faces = v, f

    v, f = unit_cube()
    assert math.isclose(bsv.volumes(TrimeshLike(v * 2, f))["volumes_l"]["whole"], 8000.0)


def test_register_prints_progress(capsys: pytest.CaptureFixture[str]) -> None:
    t = bsv.default_template()
    c = bsv.scan(t, "noer", seed=0)
    fit = bsv.register(c, progress=True, schedule="m2p:2,p2m:1")
    out = capsys.readouterr().out
    assert "m->p" in out and "p->m" in out and len(fit.log) == 3
    assert abs(fit.volumes["volumes_l"]["trunk_limbs"] / bsv.volumes(t)["volumes_l"]["trunk_limbs"] - 1) < 0.03


def test_exceptions_pickle() -> None:
    import pickle

    e = pickle.loads(pickle.dumps(bsv.FormatError("bad file")))
    assert isinstance(e, bsv.BsvError) and str(e) == "bad file"

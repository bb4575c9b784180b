"""Interop with the objects a user holds (issue 15): trimesh, Open3D (legacy and tensor), numpy arrays and
dicts in; ``to_trimesh`` / ``to_open3d`` out. Every case is a round trip that asserts that labels (and
normals and colours where the library holds them) survive and that the volumes are unchanged: for meshes
``bsv.volumes``, for clouds a (short, deterministic) ``bsv.register``."""

from __future__ import annotations

import sys
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import bsv
from bsv.interop import as_cloud, as_mesh

trimesh = pytest.importorskip("trimesh", reason="trimesh not installed (pip install -r requirements-interop.txt)")
o3d = pytest.importorskip("open3d", reason="open3d not installed (pip install -r requirements-interop.txt)")

SCHEDULE = "m2p:2,p2m:1"


@pytest.fixture(scope="module")
def template() -> bsv.Mesh:
    return bsv.default_template()


@pytest.fixture(scope="module")
def cloud(template: bsv.Mesh) -> bsv.PointCloud:
    """A labelled scan with normals (the template's vertex normals at the nearest vertex) and colours."""
    c = bsv.scan(template, "noer", seed=0)
    assert c.colors is not None and c.labels is not None
    keep = slice(None, None, 4)  # 28k points: every case below runs a registration
    tm = trimesh.Trimesh(template.vertices, template.faces, process=False)
    nearest = tm.kdtree.query(c.points[keep])[1]
    normals = np.asarray(tm.vertex_normals[nearest], dtype=np.float64)
    return bsv.PointCloud(c.points[keep], normals, c.colors[keep], c.labels[keep])


@pytest.fixture(scope="module")
def reference_fit(cloud: bsv.PointCloud) -> dict[str, float]:
    return bsv.register(cloud, schedule=SCHEDULE).volumes["volumes_l"]


def _no_warnings(fn: Callable[[], Any]) -> Any:
    with warnings.catch_warnings():
        warnings.simplefilter("error", bsv.BsvWarning)
        return fn()


# ----------------------------------------------------------------------------------------------------
# Meshes


def _trimesh_ply(m: bsv.Mesh, tmp: Path) -> Any:
    path = tmp / "trimesh_mesh.ply"
    m.to_trimesh().export(path)
    return trimesh.load(path, process=False)


def _bsv_ply_into_trimesh(m: bsv.Mesh, tmp: Path) -> Any:
    path = tmp / "bsv_mesh.ply"
    bsv.write_mesh(path, m)
    return trimesh.load(path, process=False)


MESH_CASES: dict[str, Callable[[bsv.Mesh, Path], Any]] = {
    "trimesh.Trimesh": lambda m, _: m.to_trimesh(),
    "trimesh PLY export": _trimesh_ply,
    "bsv PLY loaded by trimesh": _bsv_ply_into_trimesh,
    "open3d tensor": lambda m, _: m.to_open3d(),
    "dict": lambda m, _: {"vertices": m.vertices, "faces": m.faces, "vertex_labels": m.vertex_labels,
                          "face_labels": m.face_labels},
    "bsv.Mesh": lambda m, _: bsv.Mesh(m.vertices, m.faces, m.vertex_labels, m.face_labels),
}


FLOAT32_CASES = ("trimesh PLY export",)


@pytest.mark.parametrize("case", list(MESH_CASES))
def test_mesh_round_trip_keeps_labels_and_volumes(case: str, template: bsv.Mesh, tmp_path: Path) -> None:
    obj = MESH_CASES[case](template, tmp_path)
    back = _no_warnings(lambda: as_mesh(obj))
    assert np.array_equal(back.faces, template.faces)
    assert back.vertex_labels is not None and np.array_equal(back.vertex_labels, template.vertex_labels)
    if back.face_labels is not None:
        assert np.array_equal(back.face_labels, template.face_labels)
    ref = bsv.volumes(template)["volumes_l"]
    got = bsv.volumes(obj)["volumes_l"]
    assert set(got) == set(ref)
    # trimesh writes PLY positions as float32: 1e-6 relative; every other path is exact.
    tol = 1e-6 if case in FLOAT32_CASES else 1e-12
    for name, v in ref.items():
        assert got[name] == pytest.approx(v, rel=tol), name


def test_numpy_mesh_arrays_with_labels(template: bsv.Mesh) -> None:
    # Per-face labels beside the arrays: the same volumes, exactly.
    assert bsv.volumes(template.vertices, template.faces, template.face_labels) == bsv.volumes(template)
    # Per-vertex labels: faces take the label of two corners (DESIGN.md label rules), close to the template's.
    got = bsv.volumes(template.vertices, template.faces, template.vertex_labels)["volumes_l"]
    assert got["thigh_l"] == pytest.approx(bsv.volumes(template)["volumes_l"]["thigh_l"], rel=0.02)
    assert set(got) >= set(bsv.TRUNK_LIMBS)
    back = as_mesh(template.vertices, template.faces, template.vertex_labels, template.face_labels)
    assert np.array_equal(back.vertex_labels, template.vertex_labels)


def test_exported_meshes_carry_palette_colours(template: bsv.Mesh) -> None:
    tm = template.to_trimesh()
    assert tm.visual.kind == "vertex"
    expected = bsv.types.PALETTE[template.vertex_labels]
    assert np.array_equal(tm.visual.vertex_colors[:, :3], expected)
    assert np.array_equal(as_mesh(template.to_open3d()).vertex_colors, expected)
    # Own colours win over the palette and survive the round trip.
    own = np.tile(np.array([[10, 20, 30]], np.uint8), (len(template.vertices), 1))
    coloured = bsv.Mesh(template.vertices, template.faces, template.vertex_labels, None, own)
    assert np.array_equal(as_mesh(coloured.to_trimesh()).vertex_colors, own)
    assert np.array_equal(as_mesh(coloured.to_open3d()).vertex_colors, own)


def test_open3d_mesh_files_keep_colours_and_labels_come_from_bsv_files(template: bsv.Mesh, tmp_path: Path) -> None:
    """Open3D's mesh PLY I/O drops custom properties (documented in bsv.interop): its colours survive, and a
    PLY written by bsv keeps the labels for bsv, trimesh and Open3D's tensor colours alike."""
    path = tmp_path / "o3d_mesh.ply"
    assert o3d.t.io.write_triangle_mesh(str(path), template.to_open3d())
    back = as_mesh(o3d.t.io.read_triangle_mesh(str(path)))
    assert np.array_equal(back.vertex_colors, bsv.types.PALETTE[template.vertex_labels])
    # Open3D reads mesh positions as float32: 1e-6 relative.
    ref = bsv.volumes(template)["volumes_l"]["whole"]
    assert bsv.volumes(back)["volumes_l"]["whole"] == pytest.approx(ref, rel=1e-6)


def test_open3d_legacy_mesh_keeps_colours_and_says_labels_are_dropped(template: bsv.Mesh) -> None:
    with pytest.warns(bsv.BsvWarning, match="cannot hold labels"):
        lm = template.to_open3d(legacy=True)
    back = as_mesh(lm)
    assert back.vertex_labels is None and back.vertex_colors is not None
    assert np.array_equal(back.vertex_colors, bsv.types.PALETTE[template.vertex_labels])
    ref = bsv.volumes(template)["volumes_l"]
    assert bsv.volumes(lm)["volumes_l"]["whole"] == pytest.approx(ref["whole"], rel=1e-12)
    # Labels given beside the object: the segment volumes come back.
    got = bsv.volumes(lm, labels=template.vertex_labels)["volumes_l"]
    assert got["torso"] == pytest.approx(bsv.volumes(template.vertices, template.faces,
                                                    template.vertex_labels)["volumes_l"]["torso"], rel=1e-12)


def test_trimesh_objects_are_not_mistaken_for_open3d(template: bsv.Mesh, cloud: bsv.PointCloud, tmp_path: Path) -> None:
    """The bug of issue 15: ``as_mesh`` tested ``.triangles`` first and took a Trimesh for an Open3D mesh."""
    tm = template.to_trimesh()
    assert bsv.volumes(tm)["volumes_l"]["trunk_limbs"] == pytest.approx(
        bsv.volumes(template)["volumes_l"]["trunk_limbs"], rel=1e-12)
    bsv.write_mesh(tmp_path / "t.ply", tm)
    assert np.array_equal(bsv.read_mesh(tmp_path / "t.ply").vertex_labels, template.vertex_labels)
    a = bsv.register(cloud, template=tm, schedule=SCHEDULE).volumes["volumes_l"]
    b = bsv.register(cloud, template=template, schedule=SCHEDULE).volumes["volumes_l"]
    assert a == b


def test_bad_dicts_and_objects_are_typed_errors(template: bsv.Mesh) -> None:
    with pytest.raises(bsv.InputError, match=r"unknown key.*'triangles'"):
        as_mesh({"vertices": template.vertices, "triangles": template.faces})
    with pytest.raises(bsv.InputError, match="'faces'"):
        as_mesh({"vertices": template.vertices})
    with pytest.raises(bsv.InputError, match=r"unknown key.*'label'"):
        as_cloud({"points": template.vertices, "label": template.vertex_labels})
    with pytest.raises(TypeError, match="cannot read a mesh from int"):
        as_mesh(3)
    with pytest.raises(bsv.InputError, match=r"0\.\.1"):
        o = o3d.t.geometry.PointCloud(o3d.core.Tensor(template.vertices))
        o.point.colors = o3d.core.Tensor(np.full((len(template.vertices), 3), 2.0))
        as_cloud(o)


# ----------------------------------------------------------------------------------------------------
# Point clouds


def _bsv_ply_into_trimesh_cloud(c: bsv.PointCloud, tmp: Path) -> Any:
    path = tmp / "bsv_cloud.ply"
    bsv.write_point_cloud(path, c)
    return trimesh.load(path)


def _bsv_ply_into_open3d_tensor(c: bsv.PointCloud, tmp: Path) -> Any:
    path = tmp / "bsv_cloud.ply"
    bsv.write_point_cloud(path, c)
    return o3d.t.io.read_point_cloud(str(path))


def _open3d_tensor_ply(c: bsv.PointCloud, tmp: Path) -> Any:
    path = tmp / "o3d_cloud.ply"
    assert o3d.t.io.write_point_cloud(str(path), c.to_open3d())
    return bsv.read_point_cloud(path)


CLOUD_CASES: dict[str, Callable[[bsv.PointCloud, Path], Any]] = {
    "trimesh.PointCloud": lambda c, _: c.to_trimesh(),
    "bsv PLY loaded by trimesh": _bsv_ply_into_trimesh_cloud,
    "open3d tensor": lambda c, _: c.to_open3d(),
    "bsv PLY loaded by open3d tensor": _bsv_ply_into_open3d_tensor,
    "open3d tensor PLY read by bsv": _open3d_tensor_ply,
    "dict": lambda c, _: {"points": c.points, "normals": c.normals, "colors": c.colors, "labels": c.labels},
    "bsv.PointCloud": lambda c, _: bsv.PointCloud(c.points, c.normals, c.colors, c.labels),
}


@pytest.mark.parametrize("case", list(CLOUD_CASES))
def test_cloud_round_trip_keeps_labels_normals_colours_and_volumes(
    case: str, cloud: bsv.PointCloud, reference_fit: dict[str, float], tmp_path: Path
) -> None:
    obj = CLOUD_CASES[case](cloud, tmp_path)
    back = _no_warnings(lambda: as_cloud(obj))
    assert np.array_equal(back.points, cloud.points)
    assert back.labels is not None and np.array_equal(back.labels, cloud.labels)
    assert back.colors is not None and np.array_equal(back.colors, cloud.colors)
    assert back.normals is not None and np.allclose(back.normals, cloud.normals, atol=1e-12)
    fit = _no_warnings(lambda: bsv.register(obj, schedule=SCHEDULE))
    assert fit.volumes["volumes_l"] == reference_fit


def test_numpy_cloud_arrays(cloud: bsv.PointCloud, reference_fit: dict[str, float]) -> None:
    got = _no_warnings(lambda: bsv.register(bsv.PointCloud(cloud.points, cloud.normals, None, cloud.labels),
                                            schedule=SCHEDULE))
    assert got.volumes["volumes_l"] == reference_fit
    arrays = as_cloud(cloud.points, labels=cloud.labels, normals=cloud.normals, colors=cloud.colors)
    assert np.array_equal(arrays.labels, cloud.labels) and np.array_equal(arrays.normals, cloud.normals)


def test_open3d_legacy_cloud_keeps_normals_and_colours_and_warns_about_labels(
    cloud: bsv.PointCloud, reference_fit: dict[str, float]
) -> None:
    with pytest.warns(bsv.BsvWarning, match="cannot hold labels"):
        legacy = cloud.to_open3d(legacy=True)
    back = as_cloud(legacy)
    assert back.labels is None
    assert np.array_equal(back.colors, cloud.colors) and np.allclose(back.normals, cloud.normals)
    # No label source: the fit says so instead of falling back silently ...
    with pytest.warns(bsv.BsvWarning, match="legacy PointCloud cannot hold labels"):
        unlabelled = bsv.register(legacy, schedule=SCHEDULE)
    assert unlabelled.volumes["volumes_l"] != reference_fit
    # ... and the labels given beside it give the reference volumes.
    fit = _no_warnings(lambda: bsv.register(legacy, cloud.labels, schedule=SCHEDULE))
    assert fit.volumes["volumes_l"] == reference_fit
    # Asking for the template's labels is no surprise: no warning.
    _no_warnings(lambda: bsv.register(legacy, schedule=SCHEDULE, label_source="template"))


@pytest.mark.parametrize("where", ["trimesh", "open3d tensor", "dict", "array"])
def test_an_unlabelled_cloud_warns(where: str, cloud: bsv.PointCloud) -> None:
    unlabelled = bsv.PointCloud(cloud.points[::20], None, None, None)
    obj: Any = {
        "trimesh": unlabelled.to_trimesh(), "open3d tensor": unlabelled.to_open3d(),
        "dict": {"points": unlabelled.points}, "array": unlabelled.points,
    }[where]
    with pytest.warns(bsv.BsvWarning, match="no segment labels"):
        bsv.register(obj, schedule="m2p:1")


def test_labels_under_another_name_are_reported(cloud: bsv.PointCloud) -> None:
    o = o3d.t.geometry.PointCloud(o3d.core.Tensor(cloud.points))
    o.point["labels"] = o3d.core.Tensor(cloud.labels.reshape(-1, 1))
    with pytest.warns(bsv.BsvWarning, match="'labels' but no 'label'"):
        assert as_cloud(o).labels is None
    t = bsv.default_template()
    tm = trimesh.Trimesh(t.vertices, t.faces, process=False)
    tm.vertex_attributes["segment"] = t.vertex_labels
    with pytest.warns(bsv.BsvWarning, match="'segment' but no 'label'"):
        assert as_mesh(tm).vertex_labels is None


# ----------------------------------------------------------------------------------------------------
# Notebook display and the extras


def test_reprs_are_short_and_html_has_a_table_and_a_thumbnail(cloud: bsv.PointCloud) -> None:
    fit = bsv.register(cloud, schedule=SCHEDULE)
    for text in (repr(fit), repr(fit.mesh), repr(cloud)):
        assert len(text) < 200 and "\n" not in text, text
    assert repr(fit.mesh) == "Mesh(4177 vertices, 8350 faces, 9 segments)"
    html = fit._repr_html_()
    assert "<table" in html and "trunk_limbs" in html and "data:image/png;base64," in html
    assert len(html) < 60_000
    # The result of bsv process / bsv demo: one line, and the table against the truth when it is known.
    from bsv.pipeline import ProcessResult

    truth = {name: v * 1.01 for name, v in fit.volumes["volumes_l"].items()}
    res = ProcessResult(Path("out"), cloud, fit, fit.volumes, {"points": 1}, {}, {}, truth=truth)
    assert len(repr(res)) < 200 and "\n" not in repr(res) and "trunk_limbs=" in repr(res)
    html = res._repr_html_()
    assert "error (%)" in html and "-0.99" in html and "data:image/png;base64," in html


def test_a_missing_frontend_package_names_the_extra(monkeypatch: pytest.MonkeyPatch, tmp_path: Path,
                                                    capsys: pytest.CaptureFixture[str]) -> None:
    from bsv.cli import main
    from bsv.extras import require

    bsv.scan(bsv.default_template(full=True), "noer", 0, images=tmp_path / "cap")
    monkeypatch.setitem(sys.modules, "cv2", None)  # as if opencv were not installed
    with pytest.raises(bsv.MissingExtraError) as e:
        require("cv2")
    assert e.value.extra == "frontend" and e.value.package == "opencv-contrib-python"
    assert isinstance(e.value, ImportError)
    assert main(["process", str(tmp_path / "cap"), "-o", str(tmp_path / "out"), "--quiet"]) == 1
    err = capsys.readouterr().err
    assert 'pip install "body-segment-volumes[frontend]"' in err and "Traceback" not in err
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())

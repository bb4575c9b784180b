"""The front-end chain: the cloud-building binding against the virtual scanner's own cloud, `bsv demo` end to
end (trunk_limbs RVE < 3 %, report files), overwrite protection and the clear errors of `bsv process`."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest

import bsv
from bsv import pipeline
from bsv.frontend.errors import (
    CalibrationFileError,
    CaptureError,
    MarkerNotFoundError,
    PersonNotFoundError,
    SegmentationError,
)
from bsv.types import Registration


def _has_mediapipe() -> bool:
    try:
        import mediapipe  # noqa: F401
    except ImportError:
        return False
    return True


@pytest.fixture(scope="module")
def subject():
    return bsv.bodies.subject(0, 0)


@pytest.fixture(scope="module")
def capture(tmp_path_factory, subject):
    """A virtual L515 capture of subject 0 and the scanner's own merged cloud."""
    d = tmp_path_factory.mktemp("capture")
    cloud = bsv.scan(subject.body.mesh(), "l515", 0, images=d, overwrite=True)
    return d, cloud


def _views(cap: Path, labels_from: str = "labels.png") -> list[dict]:
    import cv2

    cal = json.loads((cap / "calibration.json").read_text())["cameras"]
    views = []
    for cam in ("front", "back"):
        meta = json.loads((cap / cam / "camera.json").read_text())
        depth = cv2.imread(str(cap / cam / "depth.png"), cv2.IMREAD_UNCHANGED)
        labels = cv2.imread(str(cap / cam / labels_from), cv2.IMREAD_UNCHANGED)
        views.append({"name": cam, "intrinsics": meta["intrinsics"], "camera_to_world": cal[cam]["camera_to_world"],
                      "depth": depth, "depth_scale": meta["depth_scale"], "labels": labels})
    return views


def test_swapped_calibrations_are_an_implausible_capture(capture):
    from bsv.errors import ImplausibleCaptureError

    cap, _ = capture
    views = _views(cap)
    views[0]["camera_to_world"], views[1]["camera_to_world"] = views[1]["camera_to_world"], views[0]["camera_to_world"]
    with pytest.raises(ImplausibleCaptureError, match="swapped") as e:
        pipeline.build_cloud(views)
    assert e.value.camera in ("front", "back")


def test_binding_rebuilds_the_scanner_cloud(capture):
    cap, scanned = capture
    params = {"sor": False, "drop_labels": [], "normals": False, "isolate_person": False}
    pts, normals, colors, labels, report = bsv._bsv.build_cloud(_views(cap), params)
    assert normals is None and colors is not None
    assert pts.shape == scanned.points.shape
    np.testing.assert_array_equal(labels, scanned.labels)
    # 16-bit depth at 0.25 mm: half a unit along rays at most ~1.25x longer than their depth.
    assert np.abs(np.linalg.norm(pts - scanned.points, axis=1)).max() <= 0.5 * 0.00025 * 1.25
    rep = report
    assert rep["points"] == len(pts) and [v["name"] for v in rep["views"]] == ["front", "back"]


def test_cloud_with_sor_drops_extremities_and_outliers(capture):
    cap, scanned = capture
    cloud, rep = pipeline.build_cloud(_views(cap), sor=True)
    assert not np.isin(cloud.labels, pipeline.EXTREMITY_IDS).any()
    assert cloud.normals is None  # the registration estimates its own (build_cloud's doc)
    with_normals, _ = pipeline.build_cloud(_views(cap), sor=True, normals=True)
    assert with_normals.normals is not None and np.allclose(np.linalg.norm(with_normals.normals, axis=1), 1.0)
    kept_scanned = int((~np.isin(scanned.labels, pipeline.EXTREMITY_IDS)).sum())
    assert 0.5 * kept_scanned < len(cloud) < kept_scanned
    assert all(v["sor_removed"] > 0 and v["dropped"]["head"] > 0 for v in rep["views"])


def test_binding_errors_are_input_errors(capture):
    cap, _ = capture
    v = _views(cap)
    bad = [dict(v[0], labels=np.ascontiguousarray(v[0]["labels"].T)), v[1]]
    with pytest.raises(bsv.InputError, match="shape"):
        bsv._bsv.build_cloud(bad, {})
    with pytest.raises(bsv.InputError, match="depth_scale"):
        bsv._bsv.build_cloud([{k: x for k, x in v[0].items() if k != "depth_scale"}], {})
    with pytest.raises(bsv.InputError, match="no person"):
        bsv._bsv.build_cloud([dict(v[0], labels=np.zeros_like(v[0]["labels"]))], {})
    with pytest.raises(bsv.InputError, match="depth scale"):
        bsv._bsv.build_cloud([dict(v[0], depth_scale=0.0)], {})
    with pytest.raises(bsv.InputError, match="camera_to_world"):
        bsv._bsv.build_cloud([dict(v[0], camera_to_world={"rotation": [[1, 0], [0, 1]], "translation": [0, 0, 0]})], {})
    with pytest.raises(bsv.InputError, match="unknown field"):
        bsv._bsv.build_cloud(v, {"sor_kk": 3})


# ----------------------------------------------------------------------------------------------------
# Only the person (issue 11): a floor added under the virtual capture, the mask spilled onto it


def _with_floor_and_spill(views: list[dict], spill: int = 4) -> list[dict]:
    """The views with a floor at y = 0 in every background pixel that looks down (depth of the pixel
    ray's hit, 16-bit units) and the label image grown by ``spill`` pixels (a MediaPipe-like spill)."""
    import cv2

    out = []
    for v in views:
        k = v["intrinsics"]
        rot = np.asarray(v["camera_to_world"]["rotation"], dtype=np.float64)
        t = np.asarray(v["camera_to_world"]["translation"], dtype=np.float64)
        h, w = v["depth"].shape
        uu, vv = np.meshgrid(np.arange(w), np.arange(h))
        rays = np.stack([(uu - k["cx"]) / k["fx"], (vv - k["cy"]) / k["fy"], np.ones_like(uu, dtype=np.float64)], -1)
        dy = rays @ rot[1]
        with np.errstate(divide="ignore", invalid="ignore"):
            z = np.where(dy < -1e-6, -t[1] / dy, 0.0)
        depth = v["depth"].copy()
        floor = (depth == 0) & (z > 0) & (z < 6.0)
        depth[floor] = np.round(z[floor] / v["depth_scale"]).astype(np.uint16)
        grown = cv2.dilate(v["labels"], np.ones((2 * spill + 1, 2 * spill + 1), np.uint8))
        labels = np.where(v["labels"] > 0, v["labels"], grown).astype(np.uint8)
        out.append(dict(v, depth=depth, labels=labels))
    return out


def test_floor_spill_is_removed_and_reported(capture):
    from bsv.report import cleaning_html

    cap, _ = capture
    views = _with_floor_and_spill(_views(cap))
    dirty, _ = pipeline.build_cloud(views, remove_floor=False, isolate_person=False)
    cloud, rep = pipeline.build_cloud(views)
    low = lambda c: int((c.points[:, 1] < 0.02).sum())  # noqa: E731
    assert low(dirty) > 1000 and low(cloud) == 0, (low(dirty), low(cloud))
    for v in rep["views"]:
        assert v["floor"]["status"] == "seen" and v["floor"]["tilt_deg"] < 0.1 and abs(v["floor"]["height_mm"]) < 2
        assert v["cleaning"]["floor_removed"] > 0 and v["warnings"] == []
        assert set(v["cleaning"]) >= {"floor_removed", "edge_removed", "far_removed", "separate_removed"}
        assert "floor seen" in pipeline.cleaning_summary(v)
    assert len(rep["floor_agreement"]) == 1 and rep["warnings"] == []
    page = cleaning_html(rep)
    assert "Cloud cleaning" in page and "No calibration warning" in page
    # Without a floor in view nothing is removed as floor and the report says so; and the cleaned cloud
    # of the spilled capture is exactly the cloud of the unspilled one.
    unspilled, plain = pipeline.build_cloud(_views(cap))
    np.testing.assert_array_equal(cloud.points, unspilled.points)
    np.testing.assert_array_equal(cloud.labels, unspilled.labels)
    assert all(v["floor"]["status"] == "not_seen" and v["cleaning"]["floor_removed"] == 0 for v in plain["views"])
    assert "not seen" in cleaning_html(plain)


def test_a_tilted_camera_is_flagged_and_a_second_person_is_an_error(capture):
    from bsv.errors import PersonIsolationError
    from bsv.report import cleaning_html

    cap, _ = capture
    views = _with_floor_and_spill(_views(cap))
    c, s = np.cos(np.radians(1.0)), np.sin(np.radians(1.0))
    rot = np.asarray(views[1]["camera_to_world"]["rotation"]) @ np.array([[1, 0, 0], [0, c, -s], [0, s, c]])
    views[1] = dict(views[1], camera_to_world={"rotation": rot.tolist(),
                                               "translation": views[1]["camera_to_world"]["translation"]})
    _, rep = pipeline.build_cloud(views)
    assert rep["views"][0]["warnings"] == [] and any("tilts" in w for w in rep["views"][1]["warnings"])
    assert any("disagree" in w for w in rep["warnings"])
    assert 'class="warn"' in cleaning_html(rep)
    # A copy of the person 500 pixels to the side in the front view (its left part stays in the image):
    # dropped as a separate part, or an error when parts that large must not be dropped silently.
    front = dict(views[0])
    depth, labels = front["depth"].copy(), front["labels"].copy()
    person = labels > 0
    depth[:, 500:][person[:, :-500]] = front["depth"][:, :-500][person[:, :-500]]
    labels[:, 500:][person[:, :-500]] = front["labels"][:, :-500][person[:, :-500]]
    two = [dict(front, depth=depth, labels=labels), views[1]]
    _, rep = pipeline.build_cloud(two)
    assert rep["views"][0]["cleaning"]["separate_removed"] > 1000
    with pytest.raises(PersonIsolationError, match="isolate_person") as e:
        pipeline.build_cloud(two, second_part_ratio=0.02)
    assert e.value.camera == "front"


def test_process_cleaning_switches_reach_cloud_building(capture, tmp_path, capsys):
    cap, _ = capture
    args = [str(cap), "-c", str(cap / "calibration.json"), "-o", str(tmp_path / "out"), "--segmentation", "oracle",
            "--quiet", "--keep-floor", "--no-isolate"]
    assert pipeline.main_process([*args, "--cloud-param", "link_mm=3"]) == 2
    assert "link_mm" in capsys.readouterr().err
    assert pipeline.main_process([*args, "--cloud-param", "link_m=0"]) == 2
    assert "link_m" in capsys.readouterr().err


# ----------------------------------------------------------------------------------------------------
# process: errors come before any heavy work


def test_missing_calibration_is_a_clear_error(capture, tmp_path):
    cap, _ = capture
    with pytest.raises(CalibrationFileError, match="calibration"):
        pipeline.process(cap, None, tmp_path / "out", segmentation="oracle", progress=False)
    with pytest.raises(CalibrationFileError, match="the capture folder has one"):  # the scanner wrote one
        pipeline.process(cap, None, tmp_path / "out", segmentation="oracle", progress=False)
    with pytest.raises(CalibrationFileError, match="does not exist"):
        pipeline.process(cap, tmp_path / "nope.json", tmp_path / "out", segmentation="oracle", progress=False)
    assert pipeline.main_process([str(cap), "-o", str(tmp_path / "out2"), "--segmentation", "oracle", "--quiet"]) == 1


def test_a_missing_calibration_is_said_before_the_pdf_worker_and_mediapipe_start(capture, tmp_path, monkeypatch):
    import bsv.frontend.segment as seg
    import bsv.pdf

    started: list[str] = []
    monkeypatch.setattr(bsv.pdf.PdfRenderer, "start", lambda self: started.append("pdf"))

    monkeypatch.setattr(seg, "warming_up", lambda **kw: started.append("mediapipe"))
    cap, _ = capture
    with pytest.raises(CalibrationFileError, match="no calibration given"):
        pipeline.process(cap, None, tmp_path / "out", segmentation="camera", progress=False)
    with pytest.raises(CalibrationFileError, match="does not exist"):
        pipeline.process(cap, tmp_path / "nope.json", tmp_path / "out", segmentation="camera", progress=False)
    assert started == [] and not (tmp_path / "out").exists()


def test_empty_or_missing_capture_is_a_clear_error(tmp_path):
    (tmp_path / "empty").mkdir()
    with pytest.raises(CaptureError, match="no 'front' camera capture"):
        pipeline.process(tmp_path / "empty", tmp_path / "c.json", tmp_path / "out", progress=False)
    with pytest.raises(CaptureError, match="does not exist"):
        pipeline.process(tmp_path / "missing", tmp_path / "c.json", tmp_path / "out", progress=False)


def test_oracle_without_label_images_is_a_clear_error(capture, tmp_path):
    cap, _ = capture
    copy = tmp_path / "cap"
    shutil.copytree(cap, copy)
    (copy / "front" / "labels.png").unlink()
    with pytest.raises(SegmentationError, match=r"labels\.png"):
        pipeline.process(copy, copy / "calibration.json", tmp_path / "out", segmentation="oracle", progress=False)


def test_marker_not_found_in_calibration_images(capture, tmp_path):
    import cv2

    cap, _ = capture
    for cam in ("front", "back"):
        (tmp_path / "marker" / cam).mkdir(parents=True)
        cv2.imwrite(str(tmp_path / "marker" / cam / "0.png"), np.full((1024, 768, 3), 128, np.uint8))
    with pytest.raises(MarkerNotFoundError):
        pipeline.process(cap, tmp_path / "marker", tmp_path / "out", segmentation="oracle", progress=False)


@pytest.mark.skipif(not _has_mediapipe(), reason="mediapipe is not installed")
def test_no_person_found_is_a_clear_error(capture, tmp_path):
    """A colour image without a person in one view: the other view stands in for it, with a warning; in
    both views: a typed error, and nothing written."""
    import cv2

    cap, _ = capture
    copy = tmp_path / "cap"
    shutil.copytree(cap, copy)
    cv2.imwrite(str(copy / "front" / "color.png"), np.full((1024, 768, 3), 128, np.uint8))
    res = pipeline.process(copy, copy / "calibration.json", tmp_path / "one", segmentation="camera", progress=False)
    assert res.warnings[0].startswith("front image: no person found in it")
    cv2.imwrite(str(copy / "back" / "color.png"), np.full((1024, 768, 3), 128, np.uint8))
    with pytest.raises(PersonNotFoundError, match="no person found in either camera's image"):
        pipeline.process(copy, copy / "calibration.json", tmp_path / "out", segmentation="camera", progress=False)
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").rglob("*"))


def test_existing_outputs_are_not_overwritten(capture, tmp_path):
    cap, _ = capture
    out = tmp_path / "out"
    out.mkdir()
    (out / "volumes.json").write_text("{}")
    with pytest.raises(FileExistsError, match="overwrite"):
        pipeline.process(cap, cap / "calibration.json", out, segmentation="oracle", progress=False)
    with pytest.raises(FileExistsError, match="overwrite"):
        pipeline.demo(out, segmentation="oracle", progress=False)
    assert (out / "volumes.json").read_text() == "{}"


def test_every_output_blocks_a_rerun(capture, tmp_path):
    """demo.json and the saved segmentation count as outputs too; the refusal is a typed BSV error."""
    from bsv.errors import OutputExistsError

    cap, _ = capture
    assert "demo.json" in pipeline.output_files(demo=True) and "segmentation/back/mask.png" in pipeline.output_files()
    out = tmp_path / "demo_only"
    out.mkdir()
    (out / "demo.json").write_text("{}")
    with pytest.raises(OutputExistsError, match=r"demo\.json"):
        pipeline.demo(out, segmentation="oracle", progress=False)
    seg = tmp_path / "seg_only"
    (seg / "segmentation" / "front").mkdir(parents=True)
    (seg / "segmentation" / "front" / "landmarks.json").write_text("{}")
    with pytest.raises(OutputExistsError, match=r"landmarks\.json") as e:
        pipeline.process(cap, cap / "calibration.json", seg, segmentation="oracle", progress=False)
    assert isinstance(e.value, bsv.BsvError) and isinstance(e.value, FileExistsError)
    assert pipeline.main_process([str(cap), "-c", str(cap / "calibration.json"), "-o", str(seg),
                                  "--segmentation", "oracle", "--quiet"]) == 2
    assert (seg / "segmentation" / "front" / "landmarks.json").read_text() == "{}"


@pytest.mark.skipif(not _has_mediapipe(), reason="camera segmentation needs mediapipe")
def test_a_failed_camera_run_leaves_nothing_and_can_be_rerun(capture, subject, tmp_path):
    """The camera segmentation is saved with the other outputs, after the registration: a run that fails
    in between (here a registration parameter error) leaves OUT empty, and the same call then works."""
    from bsv.errors import RegistrationParameterError

    cap, _ = capture
    out = tmp_path / "out"
    with pytest.raises(RegistrationParameterError):
        pipeline.process(cap, cap / "calibration.json", out, segmentation="camera", progress=False,
                         schedule="m2p:0")
    assert not out.exists() or not any(out.rglob("*")), sorted(out.rglob("*"))
    res = pipeline.process(cap, cap / "calibration.json", out, segmentation="camera", progress=False, sex="female")
    assert (out / "segmentation" / "front" / "mask.png").exists() and (out / "volumes.json").exists()
    # the lines moved after the joints are recorded per view (the knee lines by the proportions, the elbow lines by
    # the elbows' bend): this subject's elbows are bent 16-17 deg, past the reference 10, so the back view's elbow
    # lines move towards the wrists; the front view's landmark follows the bend, its lines stay
    for view in ("front", "back"):
        assert "knee_line_shift_mm" in res.segmentation[view]
    assert res.segmentation["front"]["elbow_line_shift_mm"] is None
    assert all(0.0 < mm < 10.0 for mm in res.segmentation["back"]["elbow_line_shift_mm"])
    vols = json.loads((out / "volumes.json").read_text())
    # the camera path keeps the template's segments: the sex picks the template of that sex, posed like the
    # subject (bsv.posed_template): its angles are the synthetic subject's within a few degrees
    assert {k: vols["template"][k] for k in ("kind", "sex")} == {"kind": "female", "sex": "female"}
    pose = vols["template"]["pose"]
    assert set(pose) == set(bsv.bodies.Pose.RANGES)
    for name, measured in pose.items():
        # the palms are read from the hand model: palms forward read about 13 deg (bsv.frontend.palms)
        tolerance = 16.0 if name.startswith("palm_in") else 6.0
        assert measured == pytest.approx(getattr(subject.pose, name), abs=tolerance), name
    # the subject faced the front camera squarely (bsv.frontend.facing): measured so, no warning
    assert abs(vols["subject_turn_deg"]) < 3.0 and not any("turned" in w for w in vols["warnings"])
    relabelled = vols["cloud"]["upper_arm_points_relabelled_torso"]
    assert isinstance(relabelled, int) and relabelled >= 0  # keypoints.confine_upper_arms ran on the camera labels


# ----------------------------------------------------------------------------------------------------
# The report on a known labelled mesh (the subject's own body as the "fitted" mesh)


def test_report_files_from_a_known_mesh(capture, subject, tmp_path):
    from bsv.report import FILES, write_report

    cap, _ = capture
    cloud, rep = pipeline.build_cloud(_views(cap))
    mesh = subject.body.mesh()
    vols = bsv.volumes(mesh)
    reg = Registration(mesh=mesh, volumes=vols)
    res = pipeline.ProcessResult(tmp_path, cloud, reg, vols, rep, {"front": {"source": "oracle"}}, {"cloud": 1.0},
                                 truth=subject.volumes_l())
    files = write_report(res, tmp_path, title="known mesh")
    for f in FILES:
        assert (tmp_path / f).stat().st_size > 500, f
    html = files["report"].read_text()
    assert "Estimated mass" in html and "Left / right" in html and "Left upper arm" in html
    assert f"{vols['mass_kg']:.1f} kg" in html
    from bsv.errors import OutputExistsError

    with pytest.raises(OutputExistsError, match="overwrite"):
        write_report(res, tmp_path)


def test_python_palette_is_the_rust_palette(tmp_path):
    """The PLY colours the Rust writer gives each segment id equal bsv.bodies.labels.PALETTE (and the
    report's palette)."""
    from bsv.bodies.labels import PALETTE
    from bsv.report import palette

    verts = np.array([[i, 0.0, 0.0] for i in range(15)] + [[0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], dtype=np.float64)
    faces = np.array([[i, 15, 16] for i in range(15)], dtype=np.uint32)
    labels = np.array([*range(15), 2, 2], dtype=np.uint8)
    path = tmp_path / "labelled.ply"
    bsv.write_mesh(path, bsv.Mesh(verts, faces, labels))
    colors = bsv.read_point_cloud(path).colors
    assert colors is not None
    np.testing.assert_array_equal(np.asarray(colors)[:15], PALETTE)
    np.testing.assert_allclose(palette() * 255.0, PALETTE)
    assert PALETTE.shape == (15, 3) and len({tuple(c) for c in PALETTE}) == 15


# ----------------------------------------------------------------------------------------------------
# The demo chain end to end


@pytest.fixture(scope="module")
def demo_oracle(tmp_path_factory):
    out = tmp_path_factory.mktemp("demo_oracle")
    return pipeline.demo(out, seed=0, condition="l515", segmentation="oracle", progress=False)


def _rve(res: pipeline.ProcessResult, name: str) -> float:
    row = next(r for r in res.comparison if r["segment"] == name)
    return abs(row["error_pct"])


def test_demo_oracle_trunk_limbs_within_3_percent(demo_oracle):
    assert _rve(demo_oracle, "trunk_limbs") < 3.0, pipeline.comparison_table(demo_oracle.comparison)


def test_demo_writes_every_output(demo_oracle):
    from bsv.report import FILES

    out = demo_oracle.out_dir
    for f in (*pipeline.OUTPUTS, *FILES, "demo.json"):
        assert (out / f).is_file(), f
    vols = json.loads((out / "volumes.json").read_text())
    assert vols["units"] == {"length": "m", "volume": "L"}
    assert "registration" in vols and "trunk_limbs" in vols["volumes_l"]
    cloud = bsv.read_point_cloud(out / "cloud.ply")
    assert len(cloud) == len(demo_oracle.cloud) and not np.isin(cloud.labels, pipeline.EXTREMITY_IDS).any()
    fitted = bsv.read_mesh(out / "fitted.ply")
    assert fitted.vertex_labels is not None
    with pytest.raises(FileExistsError):
        pipeline.demo(out, segmentation="oracle", progress=False)


@pytest.mark.skipif(not _has_mediapipe(), reason="mediapipe is not installed")
def test_demo_camera_segmentation_trunk_limbs_within_3_percent(tmp_path, capsys):
    assert pipeline.main_demo(["-o", str(tmp_path / "demo"), "--quiet"]) == 0
    table = capsys.readouterr().out
    assert "trunk_limbs" in table
    doc = json.loads((tmp_path / "demo" / "demo.json").read_text())
    row = next(r for r in doc["comparison"] if r["segment"] == "trunk_limbs")
    assert abs(row["error_pct"]) < 3.0, table
    # the segmentation is saved in OUT, never into the (user's) capture folder
    for cam in ("front", "back"):
        for f in ("segmentation.png", "mask.png", "landmarks.json"):
            assert (tmp_path / "demo" / "segmentation" / cam / f).is_file(), (cam, f)
            assert not (tmp_path / "demo" / "capture" / cam / f).exists(), (cam, f)


@pytest.mark.parametrize(("key", "option"), [("pose_template", "--no-pose-template"), ("keypoints", "--no-keypoints")])
def test_a_process_option_given_as_a_registration_param_is_named(key, option, tmp_path, capsys):
    """``--param pose_template=false`` is not a registration parameter but an option of the command: a
    usage error naming the option (exit 2, no traceback), before any work."""
    out = tmp_path / "out"
    assert pipeline.main_process([str(tmp_path / "capture"), "-o", str(out), "--param", f"{key}=false"]) == 2
    err = capsys.readouterr().err
    assert option in err and "Traceback" not in err and not out.exists()

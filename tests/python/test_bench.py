"""bsv.bench: metric, tables and writers, the calibration floor, the cube template, the peer's
pre-alignment, the FAUST loader and command, and a reduced synthetic run as an accuracy regression guard."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

import bsv
from bsv.bench import main as bench_main
from bsv.bench.boxes import BOXES, box_mesh, cube_template, load_cube_template
from bsv.bench.common import BenchError, Run, keep_trunk_limbs, rve, signed_error
from bsv.bench.faust import choose_scans, list_scans, nearest_index, sample_surface
from bsv.bench.floor import CameraPose, camera_weights, floor_mesh, floor_volumes, read_camera_poses, vertex_normals
from bsv.bench.peer import prealign, robust_box
from bsv.bench.reference import P2PV_BUFF, PAPER
from bsv.bench.tables import (
    CSV_COLUMNS,
    bias_table,
    p2pv_table,
    paper_table,
    read_csv,
    rows,
    signed_table,
    summarise,
    target_check,
    worst_table,
    write_csv,
    write_json,
)

# ---------------------------------------------------------------- metric and tables

def test_rve_and_signed_error() -> None:
    assert rve(9.0, 10.0) == pytest.approx(10.0)
    assert signed_error(9.0, 10.0) == pytest.approx(-10.0)
    assert signed_error(10.5, 10.0) == pytest.approx(5.0)
    with pytest.raises(BenchError):
        rve(1.0, 0.0)


def _runs() -> list[Run]:
    """Two subjects, noer and l5ca; estimates at known relative errors."""
    out = []
    truth = {"torso": 30.0, "upper_arm_l": 1.5, "trunk_limbs": 50.0, "arm_l": 2.5}
    for i, (e_noer, e_cal) in enumerate([(0.01, -0.02), (-0.03, 0.04)]):
        s = f"subject_{i:03d}"
        out.append(Run(s, "noer", "bsv", True, truth, {k: v * (1 + e_noer) for k, v in truth.items()}, seconds=1.0 + i))
        floor = {k: v * (1 + e_cal / 2) for k, v in truth.items()}
        out.append(Run(s, "l5ca", "bsv", True, truth, {k: v * (1 + e_cal) for k, v in truth.items()}, floor, 2.0))
    out.append(Run("subject_002", "noer", "bsv", False, error="RegistrationError: boom"))
    return out


def test_rows_and_summary_statistics() -> None:
    table = rows(_runs())
    # failed run dropped; 2 subjects x 2 conditions x 4 segments present
    assert len(table) == 16
    s = summarise(table)
    tl = s["bsv"]["noer"]["trunk_limbs"]
    assert tl["rve_mean"] == pytest.approx(2.0)
    assert tl["rve_std"] == pytest.approx(np.std([1.0, 3.0], ddof=1))
    assert tl["signed_mean"] == pytest.approx(-1.0)
    assert "floor_rve_mean" not in tl
    cal = s["bsv"]["l5ca"]["torso"]
    assert cal["rve_mean"] == pytest.approx(3.0)
    assert cal["floor_rve_mean"] == pytest.approx(1.5)
    assert cal["excess_mean"] == pytest.approx(1.5)
    assert cal["floor_signed_mean"] == pytest.approx(0.5)


def test_markdown_tables_mark_only_like_for_like_comparisons() -> None:
    s = summarise(rows(_runs()))
    md = paper_table(s, like_for_like=True)  # a run on FAUST: compared with the paper's FAUST values
    lines = {ln.split("|")[1].strip(): ln for ln in md.splitlines()[2:]}
    synthetic = paper_table(s)  # synthetic bodies: the paper's value as context, never marked
    assert "(1.23)" in synthetic and "✓" not in synthetic and "✗" not in synthetic
    assert "2.00 ± 1.41 (1.23) ✗" in lines["trunk_limbs"]          # worse than the paper's 1.23
    assert "2.00 ± 1.41 (5.07) ✓" in lines["torso"]                # better than 5.07
    assert f"({PAPER['torso'][1]:.2f})" in lines["torso"]           # l5ca column uses L5Ca
    assert "floor 1.50, excess +1.50" in lines["torso"]
    assert lines["thigh_l"].count("\u2013") == 2                   # absent segment
    p2 = p2pv_table(s)
    arm = next(ln for ln in p2.splitlines() if ln.startswith("| arm_l"))
    assert "98.00" in arm and "✓" not in p2 and f"{P2PV_BUFF['arm_l']:.2f}" in arm  # other data sets: no marks
    assert "+1.00 ± 4.24" in bias_table(s)                          # l5ca signed: +4 and -2 -> mean +1
    checks = {name: ok for name, ok, _ in target_check(s)}
    assert checks["noer: trunk_limbs mean RVE <= 0.5 %"] is False
    assert checks["l5ca: trunk_limbs excess over floor <= 0.3 %"] is False
    assert "noer: no subject's segment worse than 6.0 %" in checks
    worst = worst_table(rows(_runs()))
    assert "| trunk_limbs |" in worst and "(" in worst                # the worst subject is named
    assert "| torso |" in signed_table(s)


def test_csv_and_json_writers_round_trip(tmp_path: Path) -> None:
    table = rows(_runs())
    write_csv(tmp_path / "r.csv", table)
    back = read_csv(tmp_path / "r.csv")
    assert list(back[0]) == list(CSV_COLUMNS)
    assert len(back) == len(table)
    for a, b in zip(table, back, strict=True):
        assert a["segment"] == b["segment"] and a["rve_pct"] == pytest.approx(b["rve_pct"], abs=1e-6)
        assert (a["floor_l"] is None) == (b["floor_l"] is None)
    write_json(tmp_path / "r.json", {"x": math.nan, "y": np.float64(2.5), "z": [np.int64(3)], "r": _runs()[0].to_json()})
    doc = json.loads((tmp_path / "r.json").read_text())
    assert doc["x"] is None and doc["y"] == 2.5 and doc["z"] == [3]
    assert Run.from_json(doc["r"]) == _runs()[0]


# ---------------------------------------------------------------- floor

def _pose(name: str, r_true: np.ndarray, t_true: np.ndarray, r_err: np.ndarray, t_err: np.ndarray) -> CameraPose:
    """A camera whose estimated extrinsics are the true ones followed by a world-frame error (r_err, t_err)."""
    return CameraPose(name, r_true, t_true, r_err @ r_true, r_err @ t_true + t_err)


def _rig(r_front: np.ndarray, t_front: np.ndarray, r_back: np.ndarray, t_back: np.ndarray) -> list[CameraPose]:
    front = _pose("front", np.diag([1.0, -1.0, -1.0]), np.array([0.0, 1.0, 2.0]), r_front, t_front)
    back = _pose("back", np.diag([-1.0, -1.0, 1.0]), np.array([0.0, 1.0, -2.0]), r_back, t_back)
    return [front, back]


def _rot_y(deg: float) -> np.ndarray:
    t = math.radians(deg)
    return np.array([[math.cos(t), 0, math.sin(t)], [0, 1, 0], [-math.sin(t), 0, math.cos(t)]])


@pytest.fixture(scope="module")
def body() -> bsv.Mesh:
    from bsv.bodies import subject

    return subject(1).body.mesh()


def test_floor_without_error_is_the_truth(body: bsv.Mesh) -> None:
    cams = _rig(np.eye(3), np.zeros(3), np.eye(3), np.zeros(3))
    fv = floor_volumes(body, cams)
    truth = bsv.volumes(body)["volumes_l"]
    for k in truth:
        assert fv[k] == pytest.approx(truth[k], rel=1e-12)


def test_floor_of_a_common_rigid_error_keeps_every_volume(body: bsv.Mesh) -> None:
    r, t = _rot_y(2.0), np.array([0.01, -0.02, 0.005])
    fm = floor_mesh(body, _rig(r, t, r, t))
    np.testing.assert_allclose(fm.vertices, body.vertices @ r.T + t, atol=1e-12)
    fv = floor_volumes(body, _rig(r, t, r, t))
    truth = bsv.volumes(body)["volumes_l"]
    for k in truth:
        assert fv[k] == pytest.approx(truth[k], rel=1e-9)


def test_floor_of_opposite_depth_shifts_thickens_the_body(body: bsv.Mesh) -> None:
    # front surface pushed 5 mm toward the front camera, back surface 5 mm toward the back camera:
    # the body gets ~1 cm thicker front to back; the torso's volume grows by about its frontal area x 1 cm
    d = 0.005
    cams = _rig(np.eye(3), np.array([0, 0, d]), np.eye(3), np.array([0, 0, -d]))
    fv, truth = floor_volumes(body, cams), bsv.volumes(body)["volumes_l"]
    fm = floor_mesh(body, cams)
    n = vertex_normals(body.vertices, body.faces)
    front = n[:, 2] > 0.5
    np.testing.assert_allclose(fm.vertices[front] - body.vertices[front], [[0, 0, d]] * int(front.sum()), atol=1e-12)
    torso = body.vertices[body.vertex_labels == 2]
    frontal_area = (np.ptp(torso[:, 0]) * np.ptp(torso[:, 1]))  # bounding rectangle: an upper bound
    grow = (fv["torso"] - truth["torso"]) * 1e-3
    assert 0.4 * frontal_area * 2 * d < grow < frontal_area * 2 * d
    assert all(fv[k] > truth[k] for k in ("torso", "thigh_l", "thigh_r", "trunk_limbs"))


def test_camera_weights_blend_across_the_lateral_band() -> None:
    cams = _rig(np.eye(3), np.zeros(3), np.eye(3), np.zeros(3))
    nz = np.linspace(-1, 1, 41)
    n = np.stack([np.sqrt(1 - nz ** 2), np.zeros_like(nz), nz], axis=1)
    w = camera_weights(n, cams)
    np.testing.assert_allclose(w.sum(axis=1), 1.0)
    assert np.all(np.diff(w[:, 0]) >= 0)                       # front weight grows with n_z
    assert w[-1, 0] == 1.0 and w[0, 1] == 1.0 and w[20, 0] == pytest.approx(0.5)


def test_floor_reads_a_virtual_capture_and_matches_its_cloud(body: bsv.Mesh, tmp_path: Path) -> None:
    cloud = bsv.scan(body, "cali", seed=2, images=tmp_path)
    cams = read_camera_poses(tmp_path)
    assert {c.name for c in cams} == {"front", "back"}
    # the true mesh moved by each camera's error coincides with that camera's points: the offset along
    # the normal from camera-facing vertices to their 8 nearest cloud points, before and after the move
    spatial = pytest.importorskip("scipy.spatial")
    tree = spatial.cKDTree(cloud.points)
    n = vertex_normals(body.vertices, body.faces)
    facing = np.abs(n[:, 2]) > 0.8

    def offset(v: np.ndarray) -> float:
        _, idx = tree.query(v[facing], k=8)
        d = np.einsum("ikj,ij->ik", cloud.points[idx] - v[facing][:, None, :], n[facing]).mean(axis=1)
        return float(np.median(np.abs(d)))

    before, after = offset(body.vertices), offset(floor_mesh(body, cams).vertices)
    assert after < 0.4e-3 and after < 0.5 * before, (before, after)
    with pytest.raises(Exception, match=r"camera\.json"):
        read_camera_poses(tmp_path / "front")


# ---------------------------------------------------------------- boxes, peer, helpers

def test_cube_template_and_boxes() -> None:
    c = cube_template(4)
    chk = bsv.check_mesh(c)
    assert chk["is_watertight"] and chk["is_consistently_oriented"]
    assert bsv.volumes(c)["volumes_l"]["whole"] == pytest.approx(1000.0)
    shipped = load_cube_template()
    assert bsv.volumes(shipped)["volumes_l"]["whole"] == pytest.approx(1000.0)
    assert set(np.unique(shipped.vertex_labels)) == {2}
    for b in BOXES:
        m = box_mesh(b)
        assert bsv.volumes(m)["volumes_l"]["whole"] == pytest.approx(b.volume_l, rel=1e-9)
        assert m.vertices[:, 1].min() == pytest.approx(0.0, abs=1e-12)
    with pytest.raises(BenchError):
        cube_template(0)


def test_peer_prealign_matches_the_boxes() -> None:
    rng = np.random.default_rng(0)
    pts = rng.uniform([-1, 0, -0.2], [1, 0.5, 0.2], size=(20000, 3))
    c = cube_template(2)
    moved, mode = prealign(c.vertices, pts, "per_axis")
    lo, hi = robust_box(pts)
    assert mode == "peraxis"
    np.testing.assert_allclose(moved.min(axis=0), lo, atol=1e-12)
    np.testing.assert_allclose(moved.max(axis=0), hi, atol=1e-12)
    iso, mode = prealign(c.vertices, pts, "isotropic")
    ext = iso.max(axis=0) - iso.min(axis=0)
    assert mode == "isotropic" and np.ptp(ext) < 1e-12
    assert np.linalg.norm(ext) == pytest.approx(np.linalg.norm(hi - lo))
    assert prealign(c.vertices, pts, "auto")[1] == "peraxis"     # 2 x 0.5 x 0.4 box is far from a cube
    with pytest.raises(BenchError):
        prealign(c.vertices, pts, "sideways")


def test_keep_trunk_limbs_drops_head_hands_feet() -> None:
    lab = np.arange(15, dtype=np.uint8)
    pc = bsv.PointCloud(np.zeros((15, 3)) + lab[:, None], labels=lab)
    kept = keep_trunk_limbs(pc)
    assert sorted(kept.labels.tolist()) == [2, 3, 4, 5, 6, 9, 10, 11, 12]
    np.testing.assert_array_equal(kept.points[:, 0], kept.labels)
    with pytest.raises(BenchError):
        keep_trunk_limbs(bsv.PointCloud(np.zeros((3, 3))))


def test_nearest_index_and_surface_samples() -> None:
    rng = np.random.default_rng(1)
    src = rng.normal(size=(500, 3))
    q = src[[3, 77, 499]] + 1e-6
    np.testing.assert_array_equal(nearest_index(src, q), [3, 77, 499])
    c = cube_template(2)
    s = sample_surface(c, 2000)
    assert np.allclose(np.abs(s).max(axis=1), 0.5)                # every sample on a cube face


def test_camera_segmentation_fails_clearly_without_the_front_end(tmp_path: Path, capsys, monkeypatch) -> None:
    import sys

    monkeypatch.setitem(sys.modules, "bsv.frontend.segment", None)    # makes the import fail
    code = bench_main(["synth", "--n", "1", "--segmentation", "camera", "--out", str(tmp_path), "--quiet"])
    assert code == 2
    assert "camera segmentation needs bsv.frontend.segment" in capsys.readouterr().err
    assert not (tmp_path / "results.json").exists()


def test_capture_cloud_with_the_true_label_images_is_the_scanner_cloud(body: bsv.Mesh, tmp_path: Path) -> None:
    from PIL import Image

    from bsv.bench.camera import capture_cloud

    cloud = bsv.scan(body, "cali", seed=1, images=tmp_path)
    labels = {c: np.asarray(Image.open(tmp_path / c / "labels.png")) for c in ("front", "back")}
    rebuilt, report = capture_cloud(tmp_path, labels=labels, sor=False)
    cloud = keep_trunk_limbs(cloud)                                 # the builder drops head, hands, feet
    assert len(rebuilt) == len(cloud) == report["points"]
    spatial = pytest.importorskip("scipy.spatial")
    d, i = spatial.cKDTree(cloud.points).query(rebuilt.points)
    assert d.max() < 0.3e-3                                         # 16-bit depth quantisation (0.25 mm)
    assert np.mean(cloud.labels[i] == rebuilt.labels) > 0.999


def test_hip_abduction_option_reaches_the_synth_config() -> None:
    from bsv.bench.main import parser, synth_config, synth_record
    from bsv.bodies import HIP_ABDUCTION_RANGE_DEG, NARROW_HIP_ABDUCTION_RANGE_DEG

    args = parser().parse_args(["synth", "--hip-abduction", "0,1.5"])
    cfg = synth_config(args)
    cfg.validate()
    assert cfg.leg_range == NARROW_HIP_ABDUCTION_RANGE_DEG == (0.0, 1.5)
    assert synth_record(cfg, args)["hip_abduction_deg"] == [0.0, 1.5]
    default = parser().parse_args(["synth"])
    assert synth_config(default).leg_range == HIP_ABDUCTION_RANGE_DEG
    with pytest.raises(SystemExit):
        parser().parse_args(["synth", "--hip-abduction", "3,1"])
    heavy = parser().parse_args(["synth", "--bmi-shift", "8"])
    assert synth_config(heavy).bmi_shift == 8.0 and synth_record(synth_config(heavy), heavy)["bmi_shift"] == 8.0
    assert synth_config(default).bmi_shift == 0.0
    with pytest.raises(SystemExit):
        parser().parse_args(["synth", "--bmi-shift", "40"])
    wide = parser().parse_args(["synth", "--macros", "wide"])
    assert synth_config(wide).macros == "wide" and synth_record(synth_config(wide), wide)["macros"] == "wide"
    assert synth_config(default).macros == "standard"
    with pytest.raises(SystemExit):
        parser().parse_args(["synth", "--macros", "extreme"])
    bad = synth_config(default)
    bad.macros = "extreme"
    with pytest.raises(BenchError, match="--macros"):
        bad.validate()


def test_arm_down_option_reaches_the_synth_config() -> None:
    from bsv.bench.main import parser, synth_config, synth_record
    from bsv.bodies import ARM_DOWN_RANGE_DEG, WIDE_ARM_DOWN_RANGE_DEG

    args = parser().parse_args(["synth", "--arm-down", "15,60"])
    cfg = synth_config(args)
    cfg.validate()
    assert cfg.arm_range == WIDE_ARM_DOWN_RANGE_DEG == (15.0, 60.0)
    assert synth_record(cfg, args)["arm_down_deg"] == [15.0, 60.0]
    default = parser().parse_args(["synth"])
    assert synth_config(default).arm_range == ARM_DOWN_RANGE_DEG
    assert synth_record(synth_config(default), default)["arm_down_deg"] == list(ARM_DOWN_RANGE_DEG)


@pytest.mark.parametrize(("option", "field", "record", "given", "default"), [
    ("--palm-in=0,120", "palm_range", "palm_in_deg", (0.0, 120.0), "PALM_IN_RANGE_DEG"),
    ("--turn=-10,10", "turn_range", "turn_deg", (-10.0, 10.0), "TURN_RANGE_DEG"),
    ("--elbow=20,40", "elbow_range", "elbow_deg", (20.0, 40.0), "ELBOW_RANGE_DEG"),
])
def test_pose_range_options_reach_the_synth_config(option, field, record, given, default) -> None:
    """--palm-in, --turn and --elbow reach the config and its record; the defaults keep the cohort as it was; a reversed
    range is a BenchError naming the option, one outside the limits a usage error."""
    import bsv.bodies as bodies
    from bsv.bench.main import parser, synth_config, synth_record

    args = parser().parse_args(["synth", option])
    cfg = synth_config(args)
    cfg.validate()
    assert getattr(cfg, field) == given
    assert synth_record(cfg, args)[record] == list(given)
    plain = synth_config(parser().parse_args(["synth"]))
    assert getattr(plain, field) == getattr(bodies, default)
    setattr(plain, field, (given[1], given[0]))
    with pytest.raises(BenchError, match=option.split("=")[0]):
        plain.validate()
    with pytest.raises(SystemExit):
        parser().parse_args(["synth", f"{option.split('=')[0]}=-90,0"])


def test_bad_options_are_usage_errors(tmp_path: Path, capsys) -> None:
    with pytest.raises(SystemExit):
        bench_main(["synth", "--conditions", "noer,foggy"])
    for bad in ("60,15", "15", "a,b", "10,90"):
        with pytest.raises(SystemExit):
            bench_main(["synth", "--arm-down", bad])
        assert "--arm-down" in capsys.readouterr().err
    for bad in ("120,0", "a,b", "-60,10"):
        with pytest.raises(SystemExit):
            bench_main(["synth", "--palm-in", bad])
        assert "--palm-in" in capsys.readouterr().err
    assert bench_main(["faust", "--root", str(tmp_path), "--out", str(tmp_path / "o"), "--quiet"]) == 2


def test_bench_errors_are_bsv_errors() -> None:
    from bsv.bench.floor import FloorError

    assert issubclass(BenchError, bsv.BsvError) and issubclass(BenchError, RuntimeError)
    assert issubclass(FloorError, bsv.BsvError) and issubclass(FloorError, ValueError)
    with pytest.raises(bsv.BsvError):
        rve(1.0, 0.0)


def test_existing_outputs_are_refused_without_overwrite(tmp_path: Path, capsys) -> None:
    from bsv.bench.output import check_outputs, write_outputs
    from bsv.errors import OutputExistsError

    (tmp_path / "report.md").write_text("mine")
    for cmd in (["synth", "--n", "1"], ["boxes", "--seeds", "1"], ["faust", "--root", str(tmp_path)]):
        assert bench_main([*cmd, "--out", str(tmp_path), "--quiet"]) == 2
        err = capsys.readouterr().err
        assert "report.md" in err and "--overwrite" in err, err
    assert (tmp_path / "report.md").read_text() == "mine"
    (tmp_path / "report.md").unlink()
    (tmp_path / "trunk_limbs_hist_bsv.png").write_bytes(b"png")
    with pytest.raises(OutputExistsError, match=r"trunk_limbs_hist_bsv\.png") as e:
        write_outputs(tmp_path, "t", {}, [], _runs(), 1.0)
    assert isinstance(e.value, bsv.BsvError) and isinstance(e.value, FileExistsError)
    assert (tmp_path / "trunk_limbs_hist_bsv.png").read_bytes() == b"png" and not (tmp_path / "results.json").exists()
    write_outputs(tmp_path, "t", {}, [], _runs(), 1.0, overwrite=True)
    assert (tmp_path / "results.json").is_file() and (tmp_path / "trunk_limbs_hist_bsv.png").stat().st_size > 100
    check_outputs(tmp_path / "new")                                 # a new folder is fine
    # --overwrite passes the check (the faust root has no scans: a usage error after the check)
    assert bench_main(["faust", "--root", str(tmp_path / "none"), "--out", str(tmp_path), "--overwrite", "--quiet"]) == 2
    assert "MPI-FAUST" in capsys.readouterr().err


# ---------------------------------------------------------------- FAUST

def _faust_folder(root: Path, poses: dict[int, bsv.Mesh]) -> None:
    (root / "training" / "scans").mkdir(parents=True)
    (root / "training" / "registrations").mkdir(parents=True)
    for n, m in poses.items():
        plain = bsv.Mesh(m.vertices, m.faces)
        bsv.write_mesh(root / "training" / "registrations" / f"tr_reg_{n:03d}.ply", plain)
        # the raw scan: the same surface with holes (a strip of faces removed) and no labels
        keep = np.ones(len(m.faces), bool)
        keep[:: 50] = False
        bsv.write_mesh(root / "training" / "scans" / f"tr_scan_{n:03d}.ply", bsv.Mesh(m.vertices, m.faces[keep]))


def test_faust_loader_and_scan_choice(tmp_path: Path, body: bsv.Mesh) -> None:
    crouch = bsv.Mesh(body.vertices * [1.0, 0.9, 1.0], body.faces)             # not upright
    narrow = bsv.Mesh(body.vertices * [0.6, 1.0, 1.0], body.faces)             # arms closer than an A-pose
    _faust_folder(tmp_path, {0: narrow, 1: body, 2: crouch, 10: body})
    (tmp_path / "training" / "scans" / "tr_scan_011.ply").write_text("no registration")
    items = list_scans(tmp_path)
    assert [it.number for it in items] == [0, 1, 2, 10]
    assert [(it.subject, it.pose) for it in items] == [(0, 0), (0, 1), (0, 2), (1, 0)]
    assert [it.number for it in choose_scans(items)] == [1, 10]
    assert [it.number for it in choose_scans(items, [2])] == [2]
    with pytest.raises(BenchError, match="--scans 42"):
        choose_scans(items, [42])
    with pytest.raises(BenchError, match="MPI-FAUST"):
        list_scans(tmp_path / "training")


@pytest.mark.slow
def test_faust_command_on_synthetic_bodies(tmp_path: Path) -> None:
    from bsv.bodies import subject

    subs = [subject(0), subject(1)]
    _faust_folder(tmp_path / "faust", {0: subs[0].body.mesh(), 10: subs[1].body.mesh()})
    out = tmp_path / "out"
    code = bench_main(["faust", "--root", str(tmp_path / "faust"), "--conditions", "noer", "--out", str(out), "--quiet"])
    assert code == 0
    doc = json.loads((out / "results.json").read_text())
    assert [r["subject"] for r in doc["runs"]] == ["tr_scan_000", "tr_scan_010"]
    for r, s in zip(doc["runs"], subs, strict=True):
        truth = s.volumes_l()
        # the template-labelled ground truth agrees with the bodies' own labels on the aggregate
        assert r["truth_l"]["trunk_limbs"] == pytest.approx(truth["trunk_limbs"], rel=0.025)
        assert r["truth_l"]["whole"] == pytest.approx(truth["whole"], rel=1e-6)
        # regression bound (measured 0.62 % and 0.35 %)
        assert rve(r["estimated_l"]["trunk_limbs"], r["truth_l"]["trunk_limbs"]) < 1.5
    md = (out / "report.md").read_text()
    assert md.count("tr_scan_0") >= 2
    assert "✓" in md or "✗" in md  # on FAUST, the paper's FAUST values are compared


# ---------------------------------------------------------------- regression guard (reduced synth run)

#: Bounds of the reduced run (2 subjects x noer, l5ca), set with margin (about 2x) over the values measured
#: with the current engine (label-aware, articulated, surface-corrected): noer trunk_limbs 0.59 %, worst
#: segment 1.8 % (forearm_l); l5ca excess over the floor 0.12 % trunk_limbs, worst segment 4.1 %
#: (forearm_l). Tighten them as accuracy improves.
BOUND_TRUNK_LIMBS_NOER = 1.2
BOUND_SEGMENT_NOER = 4.0
BOUND_EXCESS_TRUNK_LIMBS_L5CA = 1.0
BOUND_EXCESS_SEGMENT_L5CA = 8.0


@pytest.mark.slow
def test_reduced_synth_run_regression_guard(tmp_path: Path) -> None:
    code = bench_main(["synth", "--n", "2", "--conditions", "noer,l5ca", "--out", str(tmp_path), "--quiet"])
    assert code == 0
    for f in ("results.json", "results.csv", "report.md", "rve_per_segment.png", "trunk_limbs_hist_bsv.png"):
        assert (tmp_path / f).stat().st_size > 0
    md = (tmp_path / "report.md").read_text()
    assert "✓" not in md and "✗" not in md and "for context only" in md  # synthetic bodies vs the paper's FAUST
    doc = json.loads((tmp_path / "results.json").read_text())
    assert len(doc["runs"]) == 4 and not doc["failures"]
    s = doc["summary"]["bsv"]
    assert s["noer"]["trunk_limbs"]["rve_mean"] < BOUND_TRUNK_LIMBS_NOER
    segs = [k for k in PAPER if k != "trunk_limbs"]
    assert max(s["noer"][k]["rve_mean"] for k in segs) < BOUND_SEGMENT_NOER
    assert s["l5ca"]["trunk_limbs"]["excess_mean"] < BOUND_EXCESS_TRUNK_LIMBS_L5CA
    assert max(s["l5ca"][k]["excess_mean"] for k in segs) < BOUND_EXCESS_SEGMENT_L5CA
    table = read_csv(tmp_path / "results.csv")
    assert len(table) == 4 * 14
    assert {r["condition"] for r in table if r["floor_l"] is not None} == {"l5ca"}


#: Bounds of the reduced camera-path run (2 subjects, noer, MediaPipe on the rig's room renders, and the same
#: subjects in the studio: no floor or walls, a black background), set with margin over the values measured
#: with the current engine (template segments, rigid shoulders): trunk_limbs 0.02 %, worst
#: segment mean 3.8 % (thigh_l; 4.1 % upper_arm_l before), joint centres 7-8 mm median; in the studio (round 2
#: session 28) trunk_limbs 0.16 %, worst segment mean 2.6 % (thigh_r). trunk_limbs and the joints are held to the
#: landmarks issue's targets (0.8 %, 15 mm).
BOUND_CAMERA_TRUNK_LIMBS_NOER = 0.8
BOUND_CAMERA_SEGMENT_NOER = 6.0
BOUND_CAMERA_JOINT_MEDIAN_MM = 15.0
#: The eight limbs' mean RVE on the camera path at most this many points above the oracle labels' on the same two
#: bodies (``bsv bench compare``; issue 12's per-segment target, which their mean must meet a fortiori). Seed 0's
#: subjects 0-1 read +0.46 in round 2 session 46; over the held-out seeds 20-25 the eight limbs stand +0.65.
BOUND_CAMERA_LIMBS_GAP_NOER = 1.0


@pytest.mark.slow
@pytest.mark.parametrize("look", ["room", "studio", "realistic"])
def test_reduced_camera_path_regression_guard(tmp_path: Path, look: str) -> None:
    """The user's path on two subjects, in the clinic room, in the studio (the set-up of an independent
    renderer: nothing but the subject returns depth) and in the room rendered as a camera records it (smooth
    shading, the colour sensor's blur and noise), held to the bounds above."""
    pytest.importorskip("mediapipe", reason="the camera path needs the front-end extra (MediaPipe)")
    from bsv.bench.joints import summarise

    extra = {"room": [], "studio": ["--studio"], "realistic": ["--smooth-shading", "--colour-sensor"]}[look]
    code = bench_main(["synth", "--n", "2", "--conditions", "noer", "--segmentation", "camera",
                       *extra, "--out", str(tmp_path), "--quiet"])
    assert code == 0
    doc = json.loads((tmp_path / "results.json").read_text())
    assert len(doc["runs"]) == 2 and not doc["failures"]
    s = doc["summary"]["bsv"]["noer"]
    assert s["trunk_limbs"]["rve_mean"] < BOUND_CAMERA_TRUNK_LIMBS_NOER
    segs = [k for k in PAPER if k != "trunk_limbs"]
    assert max(s[k]["rve_mean"] for k in segs) < BOUND_CAMERA_SEGMENT_NOER
    runs = [Run(**{k: v for k, v in r.items() if k in Run.__dataclass_fields__}) for r in doc["runs"]]
    assert summarise(runs)["noer"]["all"]["median_mm"] < BOUND_CAMERA_JOINT_MEDIAN_MM
    # the sex was read from each capture (bsv.frontend.sex) and on the right side: subject 0 a woman, 1 a man
    truth = {s["subject"]: s["sex"] for s in doc["subjects"]}
    for r in doc["runs"]:
        read = r["info"]["sex"]
        assert read["source"] == "inferred" and (read["p_female"] > 0.5) == (truth[r["subject"]] == "female"), read
    if look == "room":  # the same bodies with the scanner's true labels: the camera path's gap to them
        oracle = tmp_path / "oracle"
        assert bench_main(["synth", "--n", "2", "--conditions", "noer", "--out", str(oracle), "--quiet"]) == 0
        assert bench_main(["compare", "--runs", str(tmp_path), "--against", str(oracle), "--out",
                           str(tmp_path / "compare")]) == 0
        rows = json.loads((tmp_path / "compare" / "compare.json").read_text())["conditions"]["noer"]["rows"]
        assert rows["limbs"]["n"] == 2 and rows["limbs"]["gap"] < BOUND_CAMERA_LIMBS_GAP_NOER, rows["limbs"]


#: The hard cohort's subject 0 of seed 0 has upper arms 1.44 x deeper and 0.85 x narrower than its build's
#: (``bsv.bodies.variants``, the deep upper arms class): on the camera path they came out -10.4 / -7.1 % until
#: round 2 session 32, when the articulated initialisation skipped such a short, deep cloud arm (elongation 1.96
#: < 2); -1.3 / +0.9 % since (-0.7 / +2.2 % since session 45).
BOUND_DEEP_UPPER_ARM_NOER = 4.0
#: A short, deep cloud upper arm reads under this elongation (a plain arm reads 3.3): this subject's read 1.95 /
#: 1.97 until round 2 session 45, 1.99 / 2.03 since (its elbows are bent 16-17 deg, so the back view's elbow line
#: moves towards the wrist, bsv.frontend.elbowlines, and the cloud arm is a little longer).
DEEP_ARM_MAX_ELONGATION = 2.1


@pytest.mark.slow
def test_deep_upper_arms_are_articulated_on_the_camera_path(tmp_path: Path) -> None:
    """A deep, short upper arm on the user's path is aligned and sized before the fit (its run records it in
    ``articulation``), and its volume holds."""
    pytest.importorskip("mediapipe", reason="the camera path needs the front-end extra (MediaPipe)")
    code = bench_main(["synth", "--n", "1", "--cohort", "hard", "--conditions", "noer", "--segmentation", "camera",
                       "--out", str(tmp_path), "--quiet"])
    assert code == 0
    doc = json.loads((tmp_path / "results.json").read_text())
    assert doc["subjects"][0]["variant"]["class"] == "deep_upper_arms"
    (run,) = [r for r in doc["runs"] if r["method"] == "bsv"]
    aligned = {a["label"]: a for a in run["info"]["articulation"]}
    for side, label in (("l", 3), ("r", 4)):
        assert label in aligned, f"upper_arm_{side} was not articulated: {sorted(aligned)}"
        assert aligned[label]["elongation"] < DEEP_ARM_MAX_ELONGATION and aligned[label]["depth_scale"] > 1.2, aligned[label]
        err = 100.0 * (run["estimated_l"][f"upper_arm_{side}"] / run["truth_l"][f"upper_arm_{side}"] - 1.0)
        assert abs(err) < BOUND_DEEP_UPPER_ARM_NOER, (side, err)


def test_the_bench_measures_what_bsv_process_measures(tmp_path: Path) -> None:
    """`bench synth --segmentation camera` is the user's path: on the same capture it registers the same
    cloud with the same template, joints and parameters as `bsv process`, so the volumes are the same. (Until
    session 15 the command fitted its cloud with the depth pixels' normals and the bench without: every
    segment of the command came out 1-3 % larger than the bench said.)"""
    pytest.importorskip("mediapipe", reason="the camera path needs the front-end extra (MediaPipe)")
    from bsv import pipeline
    from bsv.bench.synth import measure_condition

    subject = bsv.bodies.subject(1, 0)
    mesh, truth = subject.body.mesh(), subject.volumes_l()
    runs = measure_condition("s1", mesh, truth, "l515", 7, bsv.default_template(), ["bsv"], segmentation="camera",
                             room=True)
    assert len(runs) == 1 and runs[0].ok, runs[0].error
    bsv.scan(mesh, "l515", 7, images=tmp_path / "capture", overwrite=True, room=True)
    res = pipeline.process(tmp_path / "capture", tmp_path / "capture" / "calibration.json", tmp_path / "out",
                           progress=False)
    assert res.cloud.normals is None  # the registration estimates its own
    assert len(res.cloud) == runs[0].n_points
    for name, v in runs[0].estimated_l.items():
        assert res.volumes["volumes_l"][name] == pytest.approx(v, rel=1e-9), name


def test_timing_table_gives_the_median_and_the_peer_ratio_per_subject() -> None:
    from bsv.bench.tables import timing_table

    runs = [
        Run("s0", "noer", "bsv", True, seconds=0.5), Run("s0", "noer", "trimesh", True, seconds=10.0),
        Run("s1", "noer", "bsv", True, seconds=1.0), Run("s1", "noer", "trimesh", True, seconds=12.0),
        Run("s2", "noer", "bsv", True, seconds=0.4), Run("s2", "noer", "trimesh", False),
    ]
    lines = timing_table(runs).splitlines()
    median = next(line for line in lines if line.startswith("| **median**"))
    assert median.split("|")[2].strip() == "0.50" and median.split("|")[3].strip() == "11.00"
    ratio = next(line for line in lines if "trimesh / bsv" in line)
    # Subject s2's peer failed: the ratio is the median of 20x and 12x only.
    assert ratio.split("|")[3].strip() == "16.0x"


def test_the_sex_template_follows_each_subject() -> None:
    from bsv.bench.common import BenchError, load_template

    female = load_template("sex", "female")
    assert np.array_equal(female.vertices, bsv.default_template(sex="female").vertices)
    assert not np.array_equal(female.vertices, load_template("default").vertices)
    with pytest.raises(BenchError, match="needs the subject's sex"):
        load_template("sex")


def test_look_options_reach_the_scans() -> None:
    from bsv.bench.main import parser, synth_config, synth_record

    args = parser().parse_args(["synth", "--segmentation", "camera", "--long-hair", "--top"])
    cfg = synth_config(args)
    assert cfg.look_arg() == {"long_hair": True, "top": True}
    assert synth_record(cfg, args)["long_hair"] is True and synth_record(cfg, args)["top"] is True
    assert synth_config(parser().parse_args(["synth", "--segmentation", "camera"])).look_arg() is None
    args = parser().parse_args(["synth", "--segmentation", "camera", "--smooth-shading", "--colour-sensor"])
    cfg = synth_config(args)
    assert cfg.look_arg() == {"smooth_shading": True, "colour_sensor": True}
    assert synth_record(cfg, args)["smooth_shading"] is True and synth_record(cfg, args)["colour_sensor"] is True
    # without a room there is no look to draw
    assert synth_config(parser().parse_args(["synth", "--long-hair", "--no-room"])).look_arg() is None


def test_oracle_joints_need_the_camera_path_on_the_standard_cohort() -> None:
    from bsv.bench.main import parser, synth_config

    cfg = synth_config(parser().parse_args(["synth", "--param", "oracle_joints=elbow"]))
    with pytest.raises(BenchError, match=r"oracle_joints.*--segmentation camera and the standard cohort"):
        cfg.validate()  # the oracle labels' path has no measured joints to replace
    bad = synth_config(parser().parse_args(["synth", "--param", "oracle_joints=elbows"]))
    with pytest.raises(BenchError, match="unknown: elbows"):
        bad.validate()

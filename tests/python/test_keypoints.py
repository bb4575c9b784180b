"""The registration's keypoint term: template joint rings, measured joints pulling them, typed errors."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import bsv
from bsv import _bsv
from bsv.bodies.joints import rig_joints
from bsv.bodies.model import Phenotype
from bsv.bodies.template import TEMPLATE_GENDER, default_pose, templates
from bsv.bodies.template_joints import template_joints
from bsv.keypoints import as_keypoints, joint_rings, template_kind

ASSET = Path(__file__).resolve().parents[2] / "assets" / "template" / "template_joints.json"


@pytest.fixture(scope="module")
def template_scan() -> bsv.PointCloud:
    """The default template itself, scanned without error: its true joints are the rings' centres."""
    return bsv.scan(bsv.default_template(), "noer", 3)


def assert_same_json(a: object, b: object, where: str = "") -> None:
    """``a`` and ``b`` have the same structure, keys, strings and integers, and floats within 1e-12."""
    if isinstance(a, dict) and isinstance(b, dict):
        assert a.keys() == b.keys(), where
        for k in a:
            assert_same_json(a[k], b[k], f"{where}/{k}")
    elif isinstance(a, list) and isinstance(b, list):
        assert len(a) == len(b), where
        for i, (x, y) in enumerate(zip(a, b, strict=True)):
            assert_same_json(x, y, f"{where}[{i}]")
    elif isinstance(a, float) or isinstance(b, float):
        assert isinstance(a, (int, float)) and isinstance(b, (int, float)) and abs(a - b) <= 1e-12, where
    else:
        assert a == b, where


def test_embedded_rings_are_the_generator_output_and_hit_the_rig_joints() -> None:
    by_gender = {g: rig_joints(Phenotype(gender=g), default_pose()) for g in set(TEMPLATE_GENDER.values())}
    made = {name: template_joints(m, by_gender[TEMPLATE_GENDER[name]]) for name, m in templates().items()}
    centres = by_gender[0.5]
    # regenerate if this fails (numbers to 1e-12: numpy releases may round the last bit differently)
    assert_same_json(json.loads(ASSET.read_text())["templates"], json.loads(json.dumps(made)))
    t = bsv.default_template()
    assert template_kind(t) == "default"
    rings = joint_rings(t)
    assert rings is not None and {r[0] for r in rings} == {f"{j}_{s}" for s in "lr"
                                                            for j in ("shoulder", "elbow", "wrist", "hip", "knee")}
    for name, idx, w in rings:
        assert np.linalg.norm(np.asarray(w) @ t.vertices[idx] - centres[name]) < 1e-9, name
    moved = bsv.Mesh(t.vertices + 0.001, t.faces, t.vertex_labels, t.face_labels)
    assert template_kind(moved) is None and joint_rings(moved) is None


@pytest.mark.parametrize(("sex", "gender"), [("female", 0.0), ("male", 1.0)])
def test_the_sexed_templates_carry_their_own_rig_joints(sex: str, gender: float) -> None:
    t = bsv.default_template(sex=sex)
    assert template_kind(t) == sex
    rings = joint_rings(t)
    assert rings is not None and len(rings) == 10
    centres = rig_joints(Phenotype(gender=gender), default_pose())
    for name, idx, w in rings:
        assert np.linalg.norm(np.asarray(w) @ t.vertices[idx] - centres[name]) < 1e-9, name
    d = bsv.default_template()
    assert np.array_equal(t.faces, d.faces) and np.array_equal(t.vertex_labels, d.vertex_labels)
    with pytest.raises(bsv.InputError, match="sex 'other'"):
        bsv.default_template(sex="other")
    with pytest.raises(bsv.InputError, match="9 segments"):
        bsv.default_template(full=True, sex=sex)


def test_a_measured_knee_moves_the_template_knee(template_scan: bsv.PointCloud) -> None:
    rings = {r[0]: r for r in _bsv.template_joints("default")}
    t = bsv.default_template()
    knee = np.asarray(rings["knee_l"][3])
    hip = np.asarray(rings["hip_l"][3])
    axis = (knee - hip) / np.linalg.norm(knee - hip)
    target = knee + 0.03 * axis  # 3 cm lower along the thigh
    params = {"keypoint_iterations": 20, "keypoint_weight": 200.0}

    def fitted_knee(**kw: object) -> np.ndarray:
        r = bsv.register(template_scan, template=t, **params, **kw)  # type: ignore[arg-type]
        _, idx, w, _ = rings["knee_l"]
        return np.asarray(w) @ r.mesh.vertices[idx]

    free = fitted_knee()
    pulled = fitted_knee(keypoints={"knee_l": target})
    # pulled along the limb, most of the way from where the fit alone puts it
    assert np.dot(pulled - free, axis) > 0.015, (pulled - free)
    assert abs(np.dot(pulled - target, axis)) < 0.25 * abs(np.dot(free - target, axis))  # the pull is axial
    r = bsv.register(template_scan, template=t, keypoints={"knee_l": (target, 1.0)}, **params)
    res = {k["name"]: k for k in r.volumes["registration"]["keypoints"]}
    assert set(res) == {"knee_l"} and res["knee_l"]["distance_mm"] < 40.0


def test_zero_confidence_changes_nothing(template_scan: bsv.PointCloud) -> None:
    a = bsv.register(template_scan)
    b = bsv.register(template_scan, keypoints={"elbow_r": {"xyz": [0.0, 1.0, 0.0], "confidence": 0.0}})
    assert np.array_equal(a.mesh.vertices, b.mesh.vertices)


def test_joints_the_template_does_not_reach_are_not_pulled(template_scan: bsv.PointCloud) -> None:
    r = bsv.register(template_scan, keypoints={"ankle_l": [0.1, 0.07, 0.0], "knee_l": [0.1, 0.5, 0.0]})
    assert [k["name"] for k in r.volumes["registration"]["keypoints"]] == ["knee_l"]


def test_bad_keypoints_are_typed_errors(template_scan: bsv.PointCloud) -> None:
    with pytest.raises(bsv.InputError, match="nose"):
        bsv.register(template_scan, keypoints={"nose": [0.0, 1.6, 0.1]})
    with pytest.raises(bsv.InputError, match="confidence"):
        as_keypoints({"knee_l": ([0.0, 0.5, 0.0], 2.0)})
    with pytest.raises(bsv.InputError, match="finite"):
        as_keypoints({"knee_l": [0.0, np.nan, 0.0]})
    with pytest.raises(bsv.InputError, match="dict"):
        as_keypoints([("knee_l", [0.0, 0.5, 0.0])])  # type: ignore[arg-type]
    t = bsv.default_template()
    other = bsv.Mesh(t.vertices * 1.01, t.faces, t.vertex_labels, t.face_labels)
    with pytest.raises(bsv.InputError, match="template"):
        bsv.register(template_scan, template=other, keypoints={"knee_l": [0.1, 0.5, 0.0]})
    with pytest.raises(bsv.RegistrationParameterError, match="keypoint_weight"):
        bsv.register(template_scan, keypoint_weight=-1.0)


def _arm_patch() -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]:
    """A left upper arm (a 45 mm tube about shoulder-elbow) and a torso patch 111-167 mm to its side, all
    labelled upper_arm_l as a view that sees the arm over the torso would; a right arm without joints."""
    from bsv.types import SEGMENT_IDS

    rng = np.random.default_rng(0)
    shoulder, elbow = np.array([0.2, 1.4, 0.0]), np.array([0.3, 1.15, 0.0])
    t = rng.uniform(0, 1, 400)
    ang = rng.uniform(0, 2 * np.pi, 400)
    axis = (elbow - shoulder) / np.linalg.norm(elbow - shoulder)
    u = np.cross(axis, [0.0, 0.0, 1.0])
    u /= np.linalg.norm(u)
    v = np.cross(axis, u)
    arm = shoulder + t[:, None] * (elbow - shoulder) + 0.045 * (np.cos(ang)[:, None] * u + np.sin(ang)[:, None] * v)
    # 111-167 mm medial of the arm's axis
    torso = np.column_stack([np.full(100, 0.1), rng.uniform(1.2, 1.35, 100), rng.uniform(-0.05, 0.05, 100)])
    right = arm * np.array([-1.0, 1.0, 1.0]) + np.array([0.0, 0.0, 0.3])  # far from everything, no joints
    pts = np.vstack([arm, torso, right])
    lab = np.concatenate([np.full(500, SEGMENT_IDS["upper_arm_l"]), np.full(400, SEGMENT_IDS["upper_arm_r"])])
    return pts, lab.astype(np.uint8), {"shoulder_l": shoulder, "elbow_l": elbow}


def test_confine_upper_arms_relabels_the_torso_a_view_called_arm() -> None:
    from bsv.keypoints import confine_cloud_upper_arms, confine_upper_arms
    from bsv.types import SEGMENT_IDS

    pts, lab, joints = _arm_patch()
    out, changed = confine_upper_arms(pts, lab, joints)
    assert changed == 100
    assert (out[:400] == SEGMENT_IDS["upper_arm_l"]).all()  # the arm itself stays
    assert (out[400:500] == SEGMENT_IDS["torso"]).all()
    assert (out[500:] == SEGMENT_IDS["upper_arm_r"]).all()  # no right joints: untouched
    assert (lab[400:500] == SEGMENT_IDS["upper_arm_l"]).all()  # the input is not modified
    cloud = bsv.PointCloud(pts, None, None, lab)
    confined, n = confine_cloud_upper_arms(cloud, {k: {"xyz": v.tolist(), "confidence": 0.9} for k, v in joints.items()})
    assert n == 100 and np.array_equal(confined.labels, out) and confined.points is cloud.points
    assert confine_cloud_upper_arms(cloud, None) == (cloud, 0)
    bare = bsv.PointCloud(pts)
    assert confine_cloud_upper_arms(bare, joints)[0] is bare


def test_confine_upper_arms_refuses_bad_input() -> None:
    from bsv.errors import InputError
    from bsv.keypoints import confine_upper_arms

    pts, lab, joints = _arm_patch()
    with pytest.raises(InputError, match="max_distance_m"):
        confine_upper_arms(pts, lab, joints, max_distance_m=0.0)
    with pytest.raises(InputError, match="points must be"):
        confine_upper_arms(pts[:, :2], lab, joints)
    with pytest.raises(InputError, match="3 finite coordinates"):
        confine_upper_arms(pts, lab, {"shoulder_l": [np.nan, 0, 0], "elbow_l": joints["elbow_l"]})


def test_select_joints_and_the_camera_paths_default_joints(monkeypatch) -> None:
    """The camera path lets the shoulders, elbows, wrists and hips (and the thighs' loops) pull by default (not the
    knees); ``keypoints=true`` every joint, ``false`` none."""
    from bsv.bench import common
    from bsv.keypoints import CAMERA_KEYPOINT_KINDS, JOINT_NAMES, select_joints

    joints = {n: [0.0, 1.0, 0.0] for n in JOINT_NAMES}
    arms = select_joints(joints, CAMERA_KEYPOINT_KINDS)
    assert sorted(arms) == sorted(f"{j}_{s}" for j in ("shoulder", "elbow", "wrist", "hip") for s in "lr")
    assert select_joints(joints, None) == joints and select_joints(joints, ()) == {}
    loops = {"hip_loop_l": [0.1, 0.8, 0.0], "hip_loop_r": [-0.1, 0.8, 0.0]}  # the thighs' loops pull by default too
    assert select_joints({**joints, **loops}, CAMERA_KEYPOINT_KINDS) == {**arms, **loops}
    seen: list[object] = []

    class Stop(Exception):
        pass

    def fake_register(*args: object, keypoints: object = None, **kw: object) -> None:
        seen.append(keypoints)
        raise Stop

    monkeypatch.setattr(bsv, "register", fake_register)
    cloud = bsv.PointCloud(np.zeros((3, 3)), None, None, np.ones(3, dtype=np.uint8))
    for params in ({}, {"keypoints": "true"}, {"keypoints": "false"}, {"keypoint_joints": "knee"}):
        with pytest.raises(Stop):
            common.register_bsv(cloud, bsv.default_template(), params, keypoints=joints)
    assert seen[0] == arms and seen[1] == joints and seen[2] is None
    assert sorted(seen[3]) == ["knee_l", "knee_r"]  # type: ignore[arg-type]


def test_process_takes_a_sex_or_a_template_not_both(tmp_path: Path) -> None:
    from bsv import pipeline

    with pytest.raises(bsv.InputError, match="sex or template"):
        pipeline.process(tmp_path, None, tmp_path / "out", sex="female", template=bsv.default_template())
    with pytest.raises(bsv.InputError, match="sex 'x'"):
        pipeline.process(tmp_path, None, tmp_path / "out", sex="x")
    assert not (tmp_path / "out").exists()

"""Biomechanics outputs (bsv.bsip): exact masses, centres of mass, inertia and joint centre on an
analytic solid; densities; a synthetic subject against its rig; the OpenSim export; ``bsv demo --bsip``."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest

import bsv
from bsv.biomech import DE_LEVA, DEMPSTER_DENSITY_KG_M3, csv_text
from bsv.bodies import make_body
from bsv.bodies.joints import rig_joints
from bsv.errors import BsipError, OutputExistsError
from bsv.types import SEGMENT_IDS


def _rotation(axis: np.ndarray, angle: float) -> np.ndarray:
    a = axis / np.linalg.norm(axis)
    k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * k @ k


def _two_cubes(rot: np.ndarray, shift: np.ndarray) -> bsv.Mesh:
    """A 2 x 1 x 1 box from x = -1 to 1 with a ring of vertices at x = 0; faces at x < 0 are upper_arm_l,
    the others forearm_l: two unit cubes sharing the square x = 0 (the elbow at its centre, the origin)."""
    xs = (-1.0, 0.0, 1.0)
    v = np.array([[x, y, z] for x in xs for y in (-0.5, 0.5) for z in (-0.5, 0.5)])
    idx = {tuple(p): i for i, p in enumerate(v.tolist())}
    quads = []
    for x0, x1 in ((-1.0, 0.0), (0.0, 1.0)):
        for (y0, z0), (y1, z1) in (((-0.5, -0.5), (0.5, -0.5)), ((0.5, -0.5), (0.5, 0.5)),
                                   ((0.5, 0.5), (-0.5, 0.5)), ((-0.5, 0.5), (-0.5, -0.5))):
            quads.append([(x0, y0, z0), (x0, y1, z1), (x1, y1, z1), (x1, y0, z0)])
    for x in (-1.0, 1.0):
        quads.append([(x, -0.5, -0.5), (x, 0.5, -0.5), (x, 0.5, 0.5), (x, -0.5, 0.5)])
    faces, labels = [], []
    for q in quads:
        ids = [idx[p] for p in q]
        for t in ((ids[0], ids[1], ids[2]), (ids[0], ids[2], ids[3])):
            p = v[list(t)]
            n = np.cross(p[1] - p[0], p[2] - p[0])
            faces.append(t if n @ p.mean(axis=0) > 0 else (t[0], t[2], t[1]))  # outward (convex, centred)
            labels.append(SEGMENT_IDS["upper_arm_l"] if p[:, 0].mean() < 0 else SEGMENT_IDS["forearm_l"])
    return bsv.Mesh(v @ rot.T + shift, np.array(faces), None, np.array(labels, dtype=np.uint8))


@pytest.mark.parametrize("angle", [0.0, 0.8, 2.5])
def test_two_cubes_exact(angle: float) -> None:
    rot = _rotation(np.array([1.0, -2.0, 0.5]), angle)
    shift = np.array([0.3, 1.1, -4.0])
    r = bsv.bsip(_two_cubes(rot, shift), density=1000.0)
    unit_cube = np.eye(3) * (1.0 * (1 + 1) / 12)  # V (a^2 + b^2) / 12 per unit density, a = b = 1
    for name, cx in (("upper_arm_l", -0.5), ("forearm_l", 0.5)):
        s = r.segments[name]
        assert s.mass_kg == pytest.approx(1000.0, rel=1e-12)
        np.testing.assert_allclose(s.com, rot @ np.array([cx, 0.0, 0.0]) + shift, rtol=0, atol=1e-12)
        np.testing.assert_allclose(s.inertia_kg_m2, 1000.0 * rot @ unit_cube @ rot.T, rtol=0, atol=1e-9 * 1000 / 6)
        # radii of gyration of a cube: sqrt(1/6) about any axis
        assert max(abs(k / 100 * s.length_m - np.sqrt(1 / 6)) for k in s.radii_of_gyration_pct()) < 1e-9
    np.testing.assert_allclose(r.joints["elbow_l"], shift, atol=1e-12)
    assert r.body_mass_kg == pytest.approx(2000.0, rel=1e-12)
    np.testing.assert_allclose(r.com, shift, atol=1e-12)
    # the forearm runs from the elbow (joint) to its extent along the axis: the end face, length 1
    fa = r.segments["forearm_l"]
    assert (fa.origin.how, fa.other.how) == ("joint", "extent")
    assert fa.length_m == pytest.approx(1.0, rel=1e-12)
    assert fa.com_pct == pytest.approx(50.0, rel=1e-12)


def test_densities_table_and_overrides() -> None:
    mesh = _two_cubes(np.eye(3), np.zeros(3))
    r = bsv.bsip(mesh)
    assert r.segments["upper_arm_l"].density_kg_m3 == DEMPSTER_DENSITY_KG_M3["upper_arm"] == 1070.0
    assert r.segments["forearm_l"].mass_kg == pytest.approx(1130.0)
    r = bsv.bsip(mesh, {"forearm": 1000.0, "upper_arm_l": 1050.0})
    assert (r.segments["forearm_l"].density_kg_m3, r.segments["upper_arm_l"].density_kg_m3) == (1000.0, 1050.0)
    with pytest.raises(BsipError, match="unknown segment"):
        bsv.bsip(mesh, {"forarm": 1000.0})
    with pytest.raises(BsipError, match="kg/m\\^3"):
        bsv.bsip(mesh, 1.05)  # g/cm^3 by mistake
    with pytest.raises(BsipError, match="sex"):
        bsv.bsip(mesh, sex="x")
    with pytest.raises(BsipError, match="no segment labels"):
        bsv.bsip(bsv.Mesh(mesh.vertices, mesh.faces))


def test_de_leva_table_sums_to_the_whole_body() -> None:
    for sex, rows in DE_LEVA.items():
        total = sum(r.mass_pct * (1 if k in ("head", "torso") else 2) for k, r in rows.items())
        assert total == pytest.approx(100.0, abs=0.02), sex


@pytest.fixture(scope="module")
def subject() -> tuple[object, bsv.biomech.BSIP]:
    body = make_body()
    return body, bsv.bsip(body)


def test_synthetic_subject_masses_coms_and_joints(subject: tuple[object, bsv.biomech.BSIP]) -> None:
    body, r = subject
    truth = body.volumes_l()  # type: ignore[attr-defined]
    assert len(r.segments) == 14
    total = 0.0
    for name, s in r.segments.items():
        assert s.volume_l == pytest.approx(truth[name], rel=1e-9)
        assert s.mass_kg == pytest.approx(truth[name] * s.density_kg_m3 / 1000.0, rel=1e-9)
        total += s.mass_kg
        pts = body.vertices[body.vertex_labels == SEGMENT_IDS[name]]  # type: ignore[attr-defined]
        assert np.all(s.com >= pts.min(axis=0)) and np.all(s.com <= pts.max(axis=0)), name
        assert np.all(np.linalg.eigvalsh(s.inertia_kg_m2) > 0), name
    assert r.body_mass_kg == pytest.approx(total, rel=1e-12)
    # joint centres (boundary centroids) against the MakeHuman rig's joints, mm
    rig = rig_joints()
    err = {k: 1e3 * float(np.linalg.norm(p - rig[k])) for k, p in r.joints.items()}
    print("joint centre error vs rig (mm):", {k: round(v, 1) for k, v in err.items()})
    assert set(err) == set(rig)
    limits = {"hip": 60.0, "neck": 30.0}  # the thigh/torso boundary is the groin cut, below the hip joint
    for k, e in err.items():
        assert e < limits.get(k.split("_")[0], 30.0), (k, e)
    for seg, (a, b) in {"upper_arm_l": ("shoulder_l", "elbow_l"), "forearm_r": ("elbow_r", "wrist_r"),
                        "thigh_l": ("hip_l", "knee_l"), "shin_r": ("knee_r", "ankle_r")}.items():
        rig_len = float(np.linalg.norm(rig[b] - rig[a]))
        assert abs(r.segments[seg].length_m - rig_len) < 0.04, (seg, r.segments[seg].length_m, rig_len)


def test_opensim_model_loads_and_carries_the_masses(subject: tuple[object, bsv.biomech.BSIP], tmp_path: Path,
                                                    monkeypatch: pytest.MonkeyPatch) -> None:
    opensim = pytest.importorskip("opensim", reason="opensim (requirements-dev.txt) is not installed")
    _, r = subject
    monkeypatch.chdir(tmp_path)  # OpenSim must leave no opensim.log in the working folder
    files = bsv.biomech.write_all(r, tmp_path)
    model = opensim.Model(str(files["model.osim"]))
    state = model.initSystem()
    bodies = model.getBodySet()
    masses = {bodies.get(i).getName(): bodies.get(i).getMass() for i in range(bodies.getSize())}
    assert set(masses) == set(r.segments)
    assert sum(masses.values()) == pytest.approx(r.body_mass_kg, rel=1e-9)
    assert model.getTotalMass(state) == pytest.approx(r.body_mass_kg, rel=1e-9)
    # the whole-body centre of mass in the default pose = ours, in OpenSim axes (X forward, Y up, Z right)
    c = model.calcMassCenterPosition(state)
    np.testing.assert_allclose([c.get(0), c.get(1), c.get(2)], [r.com[2], r.com[1], -r.com[0]], atol=1e-6)
    # each body's inertia about its centre of mass = ours, rotated into OpenSim axes
    w2o = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])
    for i in range(bodies.getSize()):
        body = bodies.get(i)
        ours = w2o @ r.segments[body.getName()].inertia_kg_m2 @ w2o.T
        mom, prod = body.getInertia().getMoments(), body.getInertia().getProducts()
        got = [mom.get(0), mom.get(1), mom.get(2), prod.get(0), prod.get(1), prod.get(2)]
        want = [ours[0, 0], ours[1, 1], ours[2, 2], ours[0, 1], ours[0, 2], ours[1, 2]]
        np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-12 * max(want))
    with pytest.raises(OutputExistsError):
        bsv.biomech.write_all(r, tmp_path)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bsip.csv", "bsip.json", "bsip.png", "model.osim"]
    assert (tmp_path / "bsip.png").read_bytes()[:4] == b"\x89PNG"


def test_csv_layout(subject: tuple[object, bsv.biomech.BSIP]) -> None:
    _, r = subject
    rows = [row for row in csv.DictReader(csv_text(r).splitlines()) if row["segment"] and
            not row["segment"].startswith("#")]
    assert [row["segment"] for row in rows] == list(r.segments)
    thigh = next(row for row in rows if row["segment"] == "thigh_l")
    assert (thigh["origin"], thigh["other"]) == ("HJC", "KJC")
    assert float(thigh["de_leva_com_pct"]) == DE_LEVA["male"]["thigh"].com_pct
    assert sum(float(row["mass_pct"]) for row in rows) == pytest.approx(100.0, abs=0.05)
    assert sum(float(row["de_leva_mass_pct"]) for row in rows) == pytest.approx(100.0, abs=0.05)
    assert r._repr_html_().count("<tr>") == len(r.segments) + 1 and len(repr(r)) < 120


def test_demo_bsip_end_to_end(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from bsv.pipeline import main_demo

    out = tmp_path / "demo"
    # no --bsip-sex: de Leva's column follows the subject's sex (subject 0: female)
    args = ["-o", str(out), "--segmentation", "oracle", "--no-room", "--quiet", "--bsip"]
    assert main_demo(args) == 0
    text = capsys.readouterr().out
    assert "rg long %" in text and "body-mass estimate" in text
    data = json.loads((out / "bsip.json").read_text())
    assert data["sex"] == "female"
    # the demo enters the synthetic subject's sex (subject 0: female); with oracle labels (the cloud's) the
    # average template is kept
    assert json.loads((out / "volumes.json").read_text())["template"] == {"kind": "default", "sex": "female"}
    masses = [s["mass_kg"] for s in data["segments"].values()]
    assert sum(masses) == pytest.approx(data["body_mass_kg"], rel=1e-9)
    assert set(data["segments"]) == set(bsv.TRUNK_LIMBS)
    assert (out / "model.osim").read_text().lstrip().startswith("<?xml")
    before = (out / "bsip.csv").read_bytes()
    assert main_demo(args) != 0  # outputs exist: refused before any work, nothing replaced
    assert (out / "bsip.csv").read_bytes() == before
    # a lone bsip.csv in a fresh folder is refused too (the --bsip files are checked before the work)
    other = tmp_path / "other"
    other.mkdir()
    (other / "bsip.csv").write_text("mine\n")
    assert main_demo(["-o", str(other), "--segmentation", "oracle", "--no-room", "--quiet", "--bsip"]) != 0
    assert (other / "bsip.csv").read_text() == "mine\n"
    assert sorted(p.name for p in other.iterdir()) == ["bsip.csv"]

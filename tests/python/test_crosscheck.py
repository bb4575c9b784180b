"""The few Python re-implementations of Rust code that are kept on purpose (see their docstrings) are
declared independent checks: each is cross-checked against the Rust code here, so they cannot drift."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import bsv
from bsv import bodies
from bsv.bench import peer
from bsv.bodies import labels, meshio


@pytest.fixture(scope="module")
def body() -> bsv.Mesh:
    return bodies.make_body().mesh()


def test_meshio_writer_bytes_read_back_by_rust_exactly(body: bsv.Mesh, tmp_path: Path) -> None:
    p = tmp_path / "b.ply"
    meshio.write_ply(p, body.vertices, body.faces, body.vertex_labels, body.face_labels)
    back = bsv.read_mesh(p)
    assert np.array_equal(back.vertices, body.vertices) and np.array_equal(back.faces, body.faces)
    assert np.array_equal(back.vertex_labels, body.vertex_labels)
    assert np.array_equal(back.face_labels, body.face_labels)
    # The Rust writer stores the same mesh (other header comment and colours, same data).
    q = tmp_path / "r.ply"
    bsv.write_mesh(q, body)
    again = bsv.read_mesh(q)
    assert np.array_equal(again.vertices, back.vertices) and np.array_equal(again.face_labels, back.face_labels)


def test_meshio_obj_groups_read_back_by_rust(body: bsv.Mesh, tmp_path: Path) -> None:
    assert body.face_labels is not None
    p = tmp_path / "b.obj"
    meshio.write_obj(p, body.vertices, body.faces, body.face_labels)
    back = bsv.read_mesh(p)
    assert back.face_labels is not None
    # OBJ keeps 6 decimals (1 um) and writes the faces grouped by segment: compare face -> label maps.
    assert np.allclose(back.vertices, body.vertices, rtol=0, atol=1e-6)
    ours = {tuple(f): int(lab) for f, lab in zip(body.faces.tolist(), body.face_labels, strict=True)}
    rust = {tuple(f): int(lab) for f, lab in zip(back.faces.tolist(), back.face_labels, strict=True)}
    assert ours == rust


def test_numpy_volume_equals_the_rust_whole_volume(body: bsv.Mesh) -> None:
    ours = labels.volume(body.vertices, body.faces) * 1e3
    rust = bsv.volumes(body.vertices, body.faces)["volumes_l"]["whole"]
    assert ours == pytest.approx(rust, rel=1e-12)


def test_peer_prealignment_is_the_registration_similarity(body: bsv.Mesh) -> None:
    template = bsv.default_template()
    cloud = bsv.scan(body, "noer", seed=0)
    for mode in ("isotropic", "per_axis", "auto"):
        # The port reproduces the pre-alignment of the cloud it is given: no cleaning step before it
        # (extremities kept, no ray-parallel removal, which would change the box).
        fit = bsv.register(cloud, schedule="m2p:1", prealign=mode, prealign_yaw="off", articulate=False,
                           drop_extremities=False, ray_parallel_max_cos=0.0)
        sim = fit.volumes["registration"]["prealign"]
        rust = np.asarray(sim["cloud_center"]) + np.asarray(sim["scale"]) * (
            template.vertices - np.asarray(sim["template_center"]))
        ours, used = peer.prealign(template.vertices, cloud.points, mode)
        assert used == sim["mode"].replace("_", "")
        assert np.allclose(ours, rust, atol=1e-9), mode

"""The calibration Monte Carlo re-measures a prepared mesh (``_bsv.PreparedVolumes``): the same numbers as
:func:`bsv.volumes` on every moved mesh, and the same spread as the straightforward per-draw Monte Carlo."""

from __future__ import annotations

import math

import numpy as np
import pytest
from rigs import paper_rig

import bsv
from bsv import _bsv
from bsv import uncertainty as unc
from bsv.errors import BsvError, InputError, VolumeError


@pytest.fixture(scope="module")
def template() -> bsv.Mesh:
    return bsv.default_template()


def _reference_spread(mesh: bsv.Mesh, cameras: list[unc.CameraSpread], samples: int, seed: int,
                      density: float = 1000.0) -> dict[str, float]:
    """The Monte Carlo written out: per draw, each camera's pose perturbed, the mesh moved by
    ``CameraPose.apply_error`` blended with the floor weights, and :func:`bsv.volumes` on the moved mesh."""
    from bsv.bench.floor import CameraPose, camera_weights, vertex_normals

    covs = [c.covariance for c in cameras]
    nominal = unc.quantities(bsv.volumes(mesh, islands=True, density=density))
    w = camera_weights(vertex_normals(mesh.vertices, mesh.faces),
                       [CameraPose(c.name, c.rotation, c.translation, c.rotation, c.translation) for c in cameras])
    rng = np.random.default_rng(seed)
    draws = [[rng.multivariate_normal(np.zeros(6), cov, method="eigh") for cov in covs] for _ in range(samples)]
    names = sorted(nominal)
    dev = np.full((samples, len(names)), np.nan)
    for s, deltas in enumerate(draws):
        moved = np.zeros_like(mesh.vertices)
        for k, (c, delta) in enumerate(zip(cameras, deltas, strict=True)):
            r_alt, t_alt = unc.perturb(c.rotation, c.translation, delta)
            moved += w[:, [k]] * CameraPose(c.name, c.rotation, c.translation, r_alt, t_alt).apply_error(mesh.vertices)
        q = unc.quantities(bsv.volumes(bsv.Mesh(moved, mesh.faces, mesh.vertex_labels, mesh.face_labels),
                                       islands=True, density=density))
        for j, n in enumerate(names):
            if n in q:
                dev[s, j] = unc.transform(n, q[n]) - unc.transform(n, nominal[n])
    return {n: float(np.nanstd(dev[:, j], ddof=1)) for j, n in enumerate(names) if np.isfinite(dev[:, j]).sum() > 1}


def test_calibration_spread_equals_the_per_draw_monte_carlo(template):
    for samples, seed, density in ((5, unc.DEFAULT_SEED, 1000.0), (7, 3, 1010.0)):
        got = unc.calibration_spread(template, paper_rig(), samples=samples, seed=seed, density=density)
        want = _reference_spread(template, paper_rig(), samples, seed, density)
        assert list(got) == list(want)
        assert {"trunk_limbs", "whole", "torso", "asymmetry_forearm_pct", "shin_to_thigh_l"} <= set(got)
        for n, v in want.items():
            assert v > 0, n
            assert got[n] == pytest.approx(v, rel=1e-9, abs=1e-15), n


def test_moved_vertices_are_the_blended_camera_errors(template):
    from bsv.bench.floor import CameraPose

    rng = np.random.default_rng(5)
    cams = paper_rig()
    w = rng.uniform(0, 1, (len(template.vertices), 2))
    w /= w.sum(axis=1, keepdims=True)
    draws = np.stack([[rng.multivariate_normal(np.zeros(6), c.covariance) for c in cams] for _ in range(4)])
    draws[0, 0] = 0.0  # the exact identity branch of Rodrigues
    got = unc.moved_vertices(template.vertices, w, cams, draws)
    assert got.shape == (4, len(template.vertices), 3)
    for s in range(4):
        want = np.zeros_like(template.vertices)
        for k, c in enumerate(cams):
            r_alt, t_alt = unc.perturb(c.rotation, c.translation, draws[s, k])
            want += w[:, [k]] * CameraPose(c.name, c.rotation, c.translation, r_alt, t_alt).apply_error(
                template.vertices)
        np.testing.assert_allclose(got[s], want, rtol=0, atol=1e-14)


def test_prepared_volumes_equal_bsv_volumes_on_moved_meshes(template):
    m = template
    prepared = _bsv.PreparedVolumes(m.vertices, m.faces, m.vertex_labels, m.face_labels, None, 1010.0, False, True)
    assert prepared.n_vertices == len(m.vertices) and prepared.density_kg_m3 == 1010.0
    rng = np.random.default_rng(2)
    stack = np.stack([m.vertices, m.vertices * 1.1 + 0.2, m.vertices + rng.normal(0, 0.003, m.vertices.shape)])
    q = prepared.quantities(stack)
    for s, v in enumerate(stack):
        report = bsv.volumes(bsv.Mesh(v, m.faces, m.vertex_labels, m.face_labels), islands=True, density=1010.0)
        want = unc.quantities(report)
        assert list(q) == list(want)
        for n, x in want.items():
            assert q[n][s] == pytest.approx(x, rel=1e-12, abs=1e-12), (s, n)
            assert q[n].shape == (3,) and q[n].dtype == np.float64
        one = prepared.volume_report(v).to_dict()
        assert one["volumes_l"] == pytest.approx(report["volumes_l"], rel=1e-12)
        assert one["mass_kg"] == pytest.approx(report["mass_kg"], rel=1e-12)
    assert math.isclose(q["whole"][1] / q["whole"][0], 1.1**3, rel_tol=1e-12)


def test_prepared_volumes_labels_holes_and_errors():
    # A labelled box with its own (face) labels replaced by per-vertex labels, and an open box closed.
    v = np.array([[x, y, z] for x in (-0.2, 0.2) for y in (0.1, 1.7) for z in (-0.15, 0.15)], dtype=np.float64)
    f = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                  [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]], dtype=np.int64)
    labels = np.array([1, 1, 1, 1, 2, 2, 2, 2], dtype=np.uint8)
    moved = np.stack([v, v * 2.0])
    for faces, close in ((f, False), (f[1:], True)):
        p = _bsv.PreparedVolumes(v, faces, None, None, labels, 1000.0, close, False)
        q = p.quantities(moved)
        for s in range(2):
            want = unc.quantities(bsv.volumes(moved[s], faces, labels, close_holes=close))
            assert {n: float(q[n][s]) for n in want} == pytest.approx(want, rel=1e-12)
        assert q["whole"][1] == pytest.approx(8 * q["whole"][0], rel=1e-12)
    p = _bsv.PreparedVolumes(v, f, None, None, labels)
    assert p.quantities(np.empty((0, 8, 3))) == {}
    with pytest.raises(VolumeError, match=r"7 vertices but the prepared mesh has 8"):
        p.quantities(np.zeros((2, 7, 3)))
    with pytest.raises(InputError, match=r"\(S, N, 3\)"):
        p.quantities(v)
    with pytest.raises(VolumeError, match="non-finite"):
        p.quantities(np.stack([v, np.full_like(v, np.nan)]))
    with pytest.raises(VolumeError, match="density"):
        _bsv.PreparedVolumes(v, f, None, None, labels, -1.0)
    with pytest.raises(VolumeError, match="open"):
        _bsv.PreparedVolumes(v, f[1:], None, None, labels)


def test_wrong_vertex_counts_are_typed_errors_naming_vertices_even_for_no_draws():
    v = np.array([[x, y, z] for x in (-0.2, 0.2) for y in (0.1, 1.7) for z in (-0.15, 0.15)], dtype=np.float64)
    f = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                  [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]], dtype=np.int64)
    p = _bsv.PreparedVolumes(v, f, None, None, np.array([1, 1, 1, 1, 2, 2, 2, 2], dtype=np.uint8))
    for stack in (np.empty((0, 7, 3)), np.empty((0, 0, 3)), np.zeros((3, 9, 3))):
        with pytest.raises(VolumeError) as info:
            p.quantities(stack)
        assert isinstance(info.value, BsvError)
        text = str(info.value)
        assert "vertices" in text and f"{stack.shape[1]} vertices but the prepared mesh has 8" in text, text
    with pytest.raises(VolumeError, match=r"vertices.*prepared mesh has 8"):
        p.volume_report(v[:5])
    assert p.quantities(np.empty((0, 8, 3))) == {}


def test_prepared_quantities_equal_the_python_rule_on_the_template(template):
    # bsv.uncertainty.quantities (on report dicts) mirrors VolumeReport::quantities (used by
    # PreparedVolumes.quantities): the same names, in the same order, with the same values.
    m = template
    want = unc.quantities(bsv.volumes(m, islands=True))
    prepared = _bsv.PreparedVolumes(m.vertices, m.faces, m.vertex_labels, m.face_labels, None, 1000.0, False, True)
    got = prepared.quantities(np.asarray(m.vertices, dtype=np.float64)[None])
    assert list(got) == list(want)
    assert {n: float(a[0]) for n, a in got.items()} == want
    assert all(a.shape == (1,) for a in got.values())

"""The shipped default templates: watertight, outward, labelled, and identical to what the code builds."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
TEMPLATES = ROOT / "assets" / "template"


from meshcheck import edges_closed  # noqa: E402

from bsv import bodies  # noqa: E402
from bsv.bodies.meshio import ply_bytes, read_ply  # noqa: E402
from bsv.bodies.template import check_watertight, obj_text, templates  # noqa: E402
from bsv.errors import TemplateError  # noqa: E402


def signed_volume(v, f):
    return float(np.einsum("ij,ij->i", v[f[:, 0]], np.cross(v[f[:, 1]], v[f[:, 2]])).sum() / 6.0)


@pytest.fixture(scope="module")
def built():
    return templates()


@pytest.mark.parametrize("name,labels", [("template", {2, 3, 4, 5, 6, 9, 10, 11, 12}),
                                         ("template_fine", {2, 3, 4, 5, 6, 9, 10, 11, 12}),
                                         ("template_full", set(range(1, 15))),
                                         ("template_female", {2, 3, 4, 5, 6, 9, 10, 11, 12}),
                                         ("template_male", {2, 3, 4, 5, 6, 9, 10, 11, 12})])
def test_shipped_template_is_watertight_outward_labelled(name, labels):
    v, f, vl, fl = read_ply(TEMPLATES / f"{name}.ply")
    assert edges_closed(f)
    assert signed_volume(v, f) > 0.04
    assert set(np.unique(fl)) == labels
    assert set(np.unique(vl)) == labels
    # floor at y = 0 (the feet of the full body; the 9-segment templates keep the same placement)
    assert v[:, 1].min() == pytest.approx(0.0, abs=1e-9) if 13 in labels else 0.05 < v[:, 1].min() < 0.12


#: Largest coordinate difference (m) between a shipped template and the builder's: the builder's float
#: arithmetic may round differently in the last bit from one numpy release to the next (4e-16 m seen).
SAME_M = 1e-12


def assert_same_mesh(v, f, vl, fl, m, name):
    """The shipped arrays are the builder's mesh ``m``: the same topology and labels, coordinates to SAME_M."""
    assert np.abs(np.asarray(v) - m.vertices).max() <= SAME_M, name
    assert np.array_equal(f, m.faces) and np.array_equal(vl, m.vertex_labels) and np.array_equal(fl, m.face_labels), name


def obj_lines_match(text: str, built: str) -> bool:
    """Whether an OBJ text ends with ``built``: line by line, ``v`` lines to SAME_M, the others exactly."""
    mine, theirs = text.splitlines(), built.splitlines()
    if len(mine) < len(theirs):
        return False
    for a, b in zip(mine[len(mine) - len(theirs):], theirs, strict=True):
        if a.startswith("v ") and b.startswith("v "):
            if np.abs(np.array(a.split()[1:], float) - np.array(b.split()[1:], float)).max() > SAME_M:
                return False
        elif a != b:
            return False
    return True


def test_shipped_files_match_the_builder(built):
    for name, m in built.items():
        assert_same_mesh(*read_ply(TEMPLATES / f"{name}.ply"), m, name)
        assert len((TEMPLATES / f"{name}.ply").read_bytes()) == len(ply_bytes(m.vertices, m.faces, m.vertex_labels,
                                                                                 m.face_labels)), name
        assert obj_lines_match((TEMPLATES / f"{name}.obj").read_text(), obj_text(m.vertices, m.faces, m.face_labels))


def test_obj_groups_are_segment_names():
    text = (TEMPLATES / "template.obj").read_text()
    groups = {line.split()[1] for line in text.splitlines() if line.startswith("g ")}
    assert groups == {"torso", "upper_arm_l", "upper_arm_r", "forearm_l", "forearm_r", "thigh_l", "thigh_r",
                      "shin_l", "shin_r"}
    n_f = sum(1 for line in text.splitlines() if line.startswith("f "))
    n_v = sum(1 for line in text.splitlines() if line.startswith("v "))
    v, f, _, _ = read_ply(TEMPLATES / "template.ply")
    assert (n_v, n_f) == (len(v), len(f))


def test_template_segments_equal_the_full_body_segments(built):
    trunk = bodies.segment_volumes(built["template"].vertices, built["template"].faces,
                                   built["template"].face_labels)
    full = bodies.segment_volumes(built["template_full"].vertices, built["template_full"].faces,
                                  built["template_full"].face_labels)
    fine = bodies.segment_volumes(built["template_fine"].vertices, built["template_fine"].faces,
                                  built["template_fine"].face_labels)
    for k, vol in trunk.items():
        assert vol == pytest.approx(full[k], rel=1e-6)
        assert fine[k] == pytest.approx(vol, rel=1e-9)
    assert sum(trunk.values()) == pytest.approx(bodies.volume(built["template"].vertices,
                                                              built["template"].faces), rel=1e-12)


def test_watertight_check_rejects_an_open_mesh(built):
    m = built["template"]
    with pytest.raises(TemplateError):
        check_watertight(m.vertices, m.faces[1:])
    with pytest.raises(TemplateError):
        check_watertight(m.vertices, m.faces[:, ::-1])


def test_write_templates_does_not_overwrite(tmp_path, capsys):
    from bsv.bodies.errors import OutputExistsError
    from bsv.bodies.template import main as template_main
    from bsv.bodies.template import write_templates

    (tmp_path / "template_fine.obj").write_text("mine")
    with pytest.raises(OutputExistsError, match=r"template_fine\.obj"):
        write_templates(tmp_path)
    assert template_main([str(tmp_path)]) == 2 and "--overwrite" in capsys.readouterr().err
    assert (tmp_path / "template_fine.obj").read_text() == "mine" and not (tmp_path / "template.ply").exists()
    assert template_main([str(tmp_path), "--overwrite"]) == 0
    v, f, vl, fl = read_ply(tmp_path / "template.ply")
    sv, sf, svl, sfl = read_ply(TEMPLATES / "template.ply")
    assert np.abs(v - sv).max() <= SAME_M and np.array_equal(f, sf) and np.array_equal(vl, svl)
    assert np.array_equal(fl, sfl)

"""Exports of the body-segment inertial parameters: ``bsip.json``, ``bsip.csv`` (the layout of the de Leva /
Zatsiorsky tables, de Leva's values beside ours) and ``model.osim`` (an OpenSim model whose bodies carry
each segment's mass, centre of mass and inertia). Every file is written to a temporary file in the same
folder and renamed (a failed write leaves nothing half-written), and never over an existing file unless
``overwrite``."""

from __future__ import annotations

import csv
import io
import json
import os
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import BsipError, OutputExistsError
from .compute import BSIP
from .tables import DE_LEVA_SOURCE, JOINTS

#: Files written by :func:`write_all` (and by ``bsv process --bsip``).
FILES = ("bsip.json", "bsip.csv", "model.osim", "bsip.png")

#: The kinematic tree of the OpenSim model: segment -> (parent segment, the joint between them), from
#: :data:`bsv.biomech.tables.JOINTS` (each joint's first segment is the parent).
TREE: dict[str, tuple[str, str]] = {child: (parent, joint) for joint, (parent, child) in JOINTS.items()}

#: World (Y up, X the subject's left, Z forward) -> OpenSim (X forward, Y up, Z the subject's right).
WORLD_TO_OSIM = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])


def check_output(path: Path, overwrite: bool) -> None:
    """Refuses a folder, and an existing file or link unless ``overwrite`` (checked before any work)."""
    if path.is_dir():
        raise OutputExistsError(f"{path} is a folder; give a file path")
    if (path.exists() or path.is_symlink()) and not overwrite:
        raise OutputExistsError(f"{path} already exists; pass overwrite=True (--overwrite) to replace it")


def _write_atomic(path: Path, write: Any, overwrite: bool) -> None:
    """Calls ``write(tmp_path)`` on a temporary file beside ``path``, then renames it onto ``path``."""
    check_output(path, overwrite)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.close(fd)
    try:
        write(Path(tmp))
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def csv_text(b: BSIP) -> str:
    """The segments in the layout of de Leva's Table 4: mass (% of the body-mass estimate), centre of
    mass (% of the length from the first endpoint), radii of gyration (% of the length) about the
    sagittal (antero-posterior), transverse (medio-lateral) and longitudinal axes; de Leva's values
    beside ours, with the SI values a model needs."""
    out = io.StringIO()
    w = csv.writer(out, lineterminator="\n")
    w.writerow(["segment", "origin", "other", "length_mm", "density_kg_m3", "mass_kg", "mass_pct", "de_leva_mass_pct",
                "com_pct", "de_leva_com_pct", "rg_sagittal_pct", "de_leva_rg_sagittal_pct", "rg_transverse_pct",
                "de_leva_rg_transverse_pct", "rg_longitudinal_pct", "de_leva_rg_longitudinal_pct", "com_x_m",
                "com_y_m", "com_z_m", "ixx_kg_m2", "iyy_kg_m2", "izz_kg_m2", "ixy_kg_m2", "ixz_kg_m2", "iyz_kg_m2"])
    for s in b.segments.values():
        r = s.reference
        rg = s.radii_of_gyration_pct()
        i = s.inertia_kg_m2
        ref = (r.mass_pct, r.com_pct, r.rg_sagittal_pct, r.rg_transverse_pct, r.rg_longitudinal_pct) if r else (
            float("nan"),) * 5
        w.writerow([s.name, s.origin.name, s.other.name, f"{s.length_m * 1e3:.1f}", f"{s.density_kg_m3:.0f}",
                    f"{s.mass_kg:.4f}", f"{s.mass_pct:.2f}", f"{ref[0]:.2f}", f"{s.com_pct:.2f}", f"{ref[1]:.2f}",
                    f"{rg[0]:.2f}", f"{ref[2]:.2f}", f"{rg[1]:.2f}", f"{ref[3]:.2f}", f"{rg[2]:.2f}", f"{ref[4]:.2f}",
                    *(f"{x:.5f}" for x in s.com), *(f"{x:.6e}" for x in (i[0, 0], i[1, 1], i[2, 2], i[0, 1], i[0, 2],
                                                                     i[1, 2]))])
    w.writerow([])
    w.writerow([f"# body-mass estimate {b.body_mass_kg:.3f} kg; mass % of {b.mass_basis}"])
    w.writerow([f"# densities: {b.density_source}; regression values: {DE_LEVA_SOURCE}, {b.sex}"])
    w.writerow(["# world frame: Y up, X the subject's left, Z forward; inertia about each centre of mass"])
    return out.getvalue()


def _opensim() -> Any:
    try:
        import opensim  # type: ignore[import-untyped]
    except ImportError as e:  # pragma: no cover - depends on the environment
        raise BsipError("model.osim needs the OpenSim Python package: pip install opensim==4.6 "
                        "(or the project's requirements-dev.txt)") from e
    # OpenSim logs into ./opensim.log and prints [info] lines by default: neither belongs in a user's folder
    opensim.Logger.removeFileSink()
    opensim.Logger.setLevelString("Warn")
    return opensim


def osim_model(b: BSIP, name: str = "bsv_subject") -> Any:
    """An OpenSim model of the segments: one body per segment with its mass, centre of mass and inertia
    (about the centre of mass, OpenSim axes: X forward, Y up, Z right); the torso hangs from ground by a
    free joint at the mid-hip, every other segment from its parent by a ball joint at their shared joint
    centre. Each body's origin is its proximal joint centre."""
    osim = _opensim()
    m = osim.Model()
    m.setName(name)
    origins: dict[str, np.ndarray] = {}
    for s in b.segments.values():
        parent = TREE.get(s.name)
        joint_pt = b.joints.get(parent[1]) if parent else None
        origins[s.name] = joint_pt if joint_pt is not None else s.origin.point
        if s.name == "torso":
            origins[s.name] = s.other.point  # MIDH
    bodies = {}
    for s in b.segments.values():
        com = WORLD_TO_OSIM @ (s.com - origins[s.name])
        i = WORLD_TO_OSIM @ s.inertia_kg_m2 @ WORLD_TO_OSIM.T
        body = osim.Body(s.name, s.mass_kg, osim.Vec3(*com),
                         osim.Inertia(i[0, 0], i[1, 1], i[2, 2], i[0, 1], i[0, 2], i[1, 2]))
        m.addBody(body)
        bodies[s.name] = body
    for s in b.segments.values():
        parent = TREE.get(s.name)
        child = bodies[s.name]
        zero = osim.Vec3(0.0, 0.0, 0.0)
        if parent is None or parent[0] not in bodies:
            loc = WORLD_TO_OSIM @ origins[s.name]
            j = osim.FreeJoint(f"ground_{s.name}", m.getGround(), osim.Vec3(*loc), zero, child, zero, zero)
        else:
            loc = WORLD_TO_OSIM @ (origins[s.name] - origins[parent[0]])
            j = osim.BallJoint(parent[1], bodies[parent[0]], osim.Vec3(*loc), zero, child, zero, zero)
        m.addJoint(j)
    m.finalizeConnections()
    return m


def write_json(b: BSIP, path: Path, overwrite: bool = False) -> None:
    """Writes ``bsip.json`` (:meth:`BSIP.to_dict`)."""
    text = json.dumps(b.to_dict(), indent=2) + "\n"
    _write_atomic(Path(path), lambda p: p.write_text(text), overwrite)


def write_csv(b: BSIP, path: Path, overwrite: bool = False) -> None:
    """Writes ``bsip.csv`` (:func:`csv_text`)."""
    text = csv_text(b)
    _write_atomic(Path(path), lambda p: p.write_text(text), overwrite)


def write_osim(b: BSIP, path: Path, overwrite: bool = False) -> None:
    """Writes the OpenSim model (:func:`osim_model`) as ``.osim`` XML."""
    model = osim_model(b, Path(path).stem)

    def write(p: Path) -> None:
        if not model.printToXML(str(p)):
            raise BsipError(f"OpenSim could not write {path}")
    _write_atomic(Path(path), write, overwrite)


def write_figure(b: BSIP, path: Path, overwrite: bool = False) -> None:
    """Writes ``bsip.png`` (:func:`bsv.biomech.figure.draw`) of a result that holds its mesh."""
    from .figure import draw

    if b.mesh is None:
        raise BsipError("this result holds no mesh to draw; compute it with bsv.bsip(mesh)")
    mesh = b.mesh
    _write_atomic(Path(path), lambda p: draw(b, mesh, p), overwrite)


def write_all(b: BSIP, out_dir: Path, overwrite: bool = False) -> dict[str, Path]:
    """Writes bsip.json, bsip.csv, model.osim and (when the result holds its mesh) bsip.png into
    ``out_dir`` (all checked first)."""
    out = Path(out_dir)
    paths = {n: out / n for n in FILES}
    for p in paths.values():
        check_output(p, overwrite)
    write_json(b, paths["bsip.json"], overwrite)
    write_csv(b, paths["bsip.csv"], overwrite)
    write_osim(b, paths["model.osim"], overwrite)
    if b.mesh is not None:
        write_figure(b, paths["bsip.png"], overwrite)
    else:
        del paths["bsip.png"]
    return paths

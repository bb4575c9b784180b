"""The default registration templates: the MakeHuman body of average characteristics (gender 0.5, other
macros at their defaults) in the default A-pose, with 14 segments (``full``) or with head, hands and feet
removed and every hole capped (the paper's template, 9 segments), a finer, midpoint-subdivided version of
the latter, and the 9-segment template at MakeHuman's female and male ends of the gender macro
(``template_female``, ``template_male``: chosen by ``bsv process --sex``). Written as labelled PLY and OBJ into assets/template/.

Run ``python -m bsv.bodies.template OUT_DIR --overwrite`` (or scripts/make_assets.py --templates) to regenerate.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import OutputExistsError, TemplateError
from ..types import SEGMENT_IDS, Mesh
from .asset import load_asset
from .body import make_body
from .joints import rig_joints
from .labels import body_labels, vertex_labels_from_faces
from .meshio import obj_text, ply_bytes
from .model import Phenotype, shape
from .pose import Pose
from .template_joints import template_joints

REMOVED = ("head", "hand_l", "hand_r", "foot_l", "foot_r")



def boundary_cycles(faces: np.ndarray) -> list[np.ndarray]:
    """Ordered boundary loops (vertex index cycles following the faces' edge direction) of a mesh."""
    e = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    key = e[:, 0].astype(np.int64) * (int(faces.max()) + 1) + e[:, 1]
    rev = e[:, 1].astype(np.int64) * (int(faces.max()) + 1) + e[:, 0]
    border = e[~np.isin(key, rev)]
    nxt = {}
    for a, b in border.tolist():
        if a in nxt:
            raise TemplateError(f"vertex {a} has two outgoing boundary edges (non-manifold boundary)")
        nxt[a] = b
    loops, seen = [], set()
    for start in sorted(nxt):
        if start in seen:
            continue
        cyc, v = [], start
        while v not in seen:
            seen.add(v)
            cyc.append(v)
            v = nxt[v]
        loops.append(np.array(cyc, dtype=np.int64))
    return loops


def cap_loop(vertices: np.ndarray, loop: np.ndarray, label: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Cap one boundary loop with concentric rings shrinking to its centroid (about square cells).

    ``loop`` follows the mesh's boundary edges (a -> b in a mesh face); cap faces use them reversed.
    Returns (new vertices, new faces indexing old+new vertices, face labels)."""
    n0 = len(vertices)
    p = vertices[loop]
    c = p.mean(axis=0)
    edge = np.linalg.norm(np.roll(p, -1, axis=0) - p, axis=1).mean()
    radius = np.linalg.norm(p - c, axis=1).mean()
    rings = max(1, round(radius / edge))
    k = len(loop)
    new_v = [c + s * (p - c) for s in (1.0 - np.arange(1, rings) / rings)]
    new_v.append(c[None, :])
    nv = np.concatenate(new_v) if new_v else np.zeros((0, 3))
    idx = [loop] + [n0 + r * k + np.arange(k) for r in range(rings - 1)]
    centre = n0 + (rings - 1) * k
    faces = []
    i = np.arange(k)
    j = (i + 1) % k
    for r in range(rings - 1):
        o, q = idx[r], idx[r + 1]
        faces.append(np.stack([o[j], o[i], q[i]], 1))
        faces.append(np.stack([o[j], q[i], q[j]], 1))
    o = idx[-1]
    faces.append(np.stack([o[j], o[i], np.full(k, centre)], 1))
    f = np.concatenate(faces)
    return nv, f, np.full(len(f), label, np.uint8)


def check_watertight(vertices: np.ndarray, faces: np.ndarray) -> None:
    """Raise TemplateError unless every directed edge has exactly one opposite twin and volume > 0."""
    e = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]).astype(np.int64)
    n = int(faces.max()) + 1
    key, rev = e[:, 0] * n + e[:, 1], e[:, 1] * n + e[:, 0]
    if len(np.unique(key)) != len(key) or not np.array_equal(np.sort(key), np.sort(rev)):
        raise TemplateError("mesh is not closed and consistently oriented")
    v = vertices[faces] - vertices.mean(axis=0)
    if np.einsum("ij,ij->i", v[:, 0], np.cross(v[:, 1], v[:, 2])).sum() <= 0:
        raise TemplateError("mesh is inward (negative volume)")


def _face_labels(m: Mesh) -> np.ndarray:
    """The face labels of a labelled mesh (TemplateError for an unlabelled one)."""
    if m.face_labels is None:
        raise TemplateError("mesh has no face labels")
    return m.face_labels


def trunk_limbs_mesh(full: Mesh) -> Mesh:
    """Remove head, hands and feet from a 14-segment body and cap every hole; labels of 9 segments."""
    labels = _face_labels(full)
    keep = ~np.isin(labels, [SEGMENT_IDS[n] for n in REMOVED])
    f = full.faces[keep]
    fl = labels[keep]
    used = np.unique(f)
    remap = np.full(len(full.vertices), -1, np.int64)
    remap[used] = np.arange(len(used))
    v = full.vertices[used]
    f = remap[f]
    # label of the face on each boundary edge, to label each cap
    edge_lab = {}
    for col in range(3):
        a, b = f[:, col], f[:, (col + 1) % 3]
        for x, y, lab in zip(a.tolist(), b.tolist(), fl.tolist(), strict=True):
            edge_lab[(x, y)] = lab
    new_f, new_l, verts = [f], [fl], [v]
    nv = len(v)
    for loop in boundary_cycles(f):
        lab = edge_lab[(int(loop[0]), int(loop[1]))]
        cv, cf, cl = cap_loop(np.concatenate(verts), loop, lab)
        verts.append(cv)
        new_f.append(cf)
        new_l.append(cl)
        nv += len(cv)
    v = np.concatenate(verts)
    f = np.concatenate(new_f)
    fl = np.concatenate(new_l)
    check_watertight(v, f)
    return Mesh(v, f, vertex_labels_from_faces(len(v), f, fl), fl)


def subdivide_midpoint(m: Mesh) -> Mesh:
    """Split each triangle into four at its edge midpoints (shape and volume unchanged), labels kept."""
    f = m.faces
    e = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    key = np.sort(e, axis=1)
    uniq, inv = np.unique(key, axis=0, return_inverse=True)
    inv = inv.reshape(3, -1).T
    n = len(m.vertices)
    mids = 0.5 * (m.vertices[uniq[:, 0]] + m.vertices[uniq[:, 1]])
    v = np.concatenate([m.vertices, mids])
    a, b, c = f.T
    ab, bc, ca = (n + inv[:, 0], n + inv[:, 1], n + inv[:, 2])
    nf = np.concatenate([np.stack([a, ab, ca], 1), np.stack([ab, b, bc], 1), np.stack([ca, bc, c], 1),
                         np.stack([ab, bc, ca], 1)])
    fl = np.tile(_face_labels(m), 4)
    return Mesh(v, nf, vertex_labels_from_faces(len(v), nf, fl), fl)


def default_pose() -> Pose:
    """The template's A-pose: arms 40 deg below horizontal, elbows 10 deg, hips 4 deg, palms forward."""
    return Pose()


#: MakeHuman's gender macro of each template (0 female, 1 male; every other macro at its default).
TEMPLATE_GENDER: dict[str, float] = {"template": 0.5, "template_full": 0.5, "template_fine": 0.5,
                                     "template_female": 0.0, "template_male": 1.0}


def templates() -> dict[str, Mesh]:
    """The default templates: 'template' (9 segments), 'template_full' (14), 'template_fine' (9, x4 faces),
    and the 9-segment 'template_female' and 'template_male' (the same mesh at MakeHuman's female and male
    ends of the gender macro: the same vertices, faces and labels, another shape)."""
    full = {g: make_body(Phenotype(gender=g), default_pose()).mesh() for g in sorted(set(TEMPLATE_GENDER.values()))}
    for m in full.values():
        check_watertight(m.vertices, m.faces)
    trunk = {g: trunk_limbs_mesh(m) for g, m in full.items()}
    return {"template": trunk[0.5], "template_full": full[0.5], "template_fine": subdivide_midpoint(trunk[0.5]),
            "template_female": trunk[0.0], "template_male": trunk[1.0]}


#: The rest bodies and rig of the 9-segment templates, to pose them (:mod:`bsv.posed_template`), written beside them.
RIG_FILE = "template_rig.npz"
#: The 9-segment templates that can be posed, by kind (``bsv.default_template(sex=...)``), and their file names.
POSABLE: dict[str, str] = {"default": "template", "female": "template_female", "male": "template_male"}


def rig_arrays() -> dict[str, np.ndarray]:
    """The arrays of :data:`RIG_FILE`: the MakeHuman body's faces and 14-segment face labels, the rig (bone
    names and parents) and its skinning weights, and per posable template kind its rest body
    (``rest_vertices_KIND``, ``rest_joints_KIND``: the shaped body before the A-pose)."""
    a = load_asset()
    out: dict[str, np.ndarray] = {
        "faces": a.faces.astype(np.int32), "face_labels": body_labels(a.faces, a)[1].astype(np.uint8),
        "bone_names": np.array(a.bone_names), "bone_parent": a.bone_parent.astype(np.int32),
        "skin_vertex": a.skin_vertex.astype(np.int32), "skin_bone": a.skin_bone.astype(np.int32),
        "skin_weight": a.skin_weight}
    for kind, name in POSABLE.items():
        v, j = shape(Phenotype(gender=TEMPLATE_GENDER[name]), a)
        out[f"rest_vertices_{kind}"], out[f"rest_joints_{kind}"] = v, j
    return out


#: Names of the default templates (each written as NAME.ply and NAME.obj).
TEMPLATE_NAMES = ("template", "template_full", "template_fine", "template_female", "template_male")
#: The joint rings of every template (:mod:`bsv.bodies.template_joints`), written beside them.
JOINTS_FILE = "template_joints.json"


def write_templates(out_dir: str | Path, overwrite: bool = False) -> dict[str, tuple[int, int]]:
    """Write every template as PLY and OBJ into out_dir; returns {name: (vertices, faces)}. Existing files
    are refused before any work (:class:`bsv.errors.OutputExistsError`) unless ``overwrite``."""
    out = Path(out_dir)
    existing = [f"{n}.{ext}" for n in TEMPLATE_NAMES for ext in ("ply", "obj") if (out / f"{n}.{ext}").exists()]
    existing += [f for f in (JOINTS_FILE, RIG_FILE) if (out / f).exists()]
    if existing and not overwrite:
        raise OutputExistsError(f"{out} already holds {', '.join(existing)}; pass overwrite=True "
                                "(python -m bsv.bodies.template OUT_DIR --overwrite) to regenerate them")
    built = templates()
    out.mkdir(parents=True, exist_ok=True)
    counts = {}
    for name, m in built.items():
        (out / f"{name}.ply").write_bytes(ply_bytes(m.vertices, m.faces, m.vertex_labels, m.face_labels))
        note = (f"BSV {name}: MakeHuman (CC0) gender {TEMPLATE_GENDER[name]:g}, default macros, A-pose; metres, Y up, "
                "faces +Z.\n"
                f"{len(m.vertices)} vertices, {len(m.faces)} triangles. Regenerate: python -m bsv.bodies.template")
        (out / f"{name}.obj").write_text(obj_text(m.vertices, m.faces, _face_labels(m), note))
        counts[name] = (len(m.vertices), len(m.faces))
    centres = {g: rig_joints(Phenotype(gender=g), default_pose()) for g in set(TEMPLATE_GENDER.values())}
    doc = {"about": "Joint centres of each template as convex combinations of its vertices (bsv.bodies.template_joints;"
                    " the MakeHuman rig's bone heads). Regenerate: python -m bsv.bodies.template",
           "templates": {name: template_joints(m, centres[TEMPLATE_GENDER[name]]) for name, m in built.items()}}
    (out / JOINTS_FILE).write_text(json.dumps(doc, indent=1) + "\n")
    arrays: dict[str, Any] = rig_arrays()
    part = out / (RIG_FILE + ".part")  # written whole, then renamed: an interrupted run leaves no torn file
    with part.open("wb") as fh:
        np.savez_compressed(fh, **arrays)
    part.replace(out / RIG_FILE)
    return counts


def main(argv: list[str] | None = None) -> int:
    """``python -m bsv.bodies.template [OUT_DIR] [--overwrite]`` (default: the repository's assets/template)."""
    import argparse

    ap = argparse.ArgumentParser(description="Write the default templates (PLY + OBJ).")
    ap.add_argument("out_dir", nargs="?", default=str(Path(__file__).resolve().parents[3] / "assets" / "template"))
    ap.add_argument("--overwrite", action="store_true", help="replace template files already in OUT_DIR")
    args = ap.parse_args(argv)
    from ..exitcodes import run_command

    def run() -> int:
        counts = write_templates(args.out_dir, overwrite=args.overwrite)
        for k, (nv, nf) in counts.items():
            print(f"{k}: {nv} vertices, {nf} triangles")
        return 0

    return run_command("bsv template", run)


if __name__ == "__main__":
    raise SystemExit(main())

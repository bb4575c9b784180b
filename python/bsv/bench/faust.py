"""``bench faust``: the paper's protocol on a real MPI-FAUST folder (licensed: never bundled; the user
points ``--root`` at their copy).

Layout read: ``ROOT/training/scans/tr_scan_NNN.ply`` (raw 3dMD scans: noisy, with holes) and
``ROOT/training/registrations/tr_reg_NNN.ply`` (watertight SMPL-topology registrations), scan NNN being
subject NNN // 10 in pose NNN % 10.

Scan choice: one A-pose-like scan per subject. The ten FAUST poses differ per subject, so the choice is
made from the data: among a subject's registrations, keep those standing upright (height >= 97 % of
the subject's tallest pose), then take the one whose width/height and depth/height ratios are closest
to the default template's (arms away from the body like the template's A-pose, no lunge or twist).
``--scans 0,10,...`` overrides the choice.

Ground truth: the registration mesh (complete, watertight) of the chosen scan, labelled by registering
the 14-segment template (``bsv.default_template(full=True)``) to points sampled on it (no gaps, so the
fit is as good as it gets) and giving each registration vertex the label of the nearest fitted template
vertex; its segment volumes (:func:`bsv.volumes`) are the truth. Label boundaries therefore follow the
template's anatomy, as they do for the estimate. The raw scan mesh takes the same labels (nearest
registration vertex) so that the virtual rig's oracle segmentation works, is scanned in every condition,
and the default template is registered to the cloud as in ``bench synth``. Both meshes are moved
together so the registration stands on the floor (y = 0) centred on the rig axis; FAUST is Y-up, metres,
facing +Z (``--facing -z`` turns the subject if a copy faces the other way).
"""

from __future__ import annotations

import re
import time
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..types import Mesh
from .common import BenchError, Run, surface_samples
from .reference import CONDITIONS

SCAN_RE = re.compile(r"tr_scan_(\d{3})\.ply$")


@dataclass(frozen=True)
class FaustItem:
    """One FAUST training scan: its number, subject, pose and the two files."""

    number: int
    scan: Path
    registration: Path

    @property
    def subject(self) -> int:
        """FAUST subject id (number // 10)."""
        return self.number // 10

    @property
    def pose(self) -> int:
        """FAUST pose id (number % 10)."""
        return self.number % 10

    @property
    def name(self) -> str:
        """Report name, e.g. ``tr_scan_010``."""
        return f"tr_scan_{self.number:03d}"


def list_scans(root: str | Path) -> list[FaustItem]:
    """Every training scan of a FAUST folder that has its registration, sorted by number."""
    r = Path(root)
    scans_dir, reg_dir = r / "training" / "scans", r / "training" / "registrations"
    if not scans_dir.is_dir() or not reg_dir.is_dir():
        raise BenchError(f"{r}: not an MPI-FAUST folder (need training/scans and training/registrations); "
                         "point --root at the folder that holds 'training'")
    items = []
    for p in sorted(scans_dir.iterdir()):
        m = SCAN_RE.search(p.name)
        if not m:
            continue
        n = int(m.group(1))
        reg = reg_dir / f"tr_reg_{n:03d}.ply"
        if reg.is_file():
            items.append(FaustItem(n, p, reg))
    if not items:
        raise BenchError(f"{scans_dir}: no tr_scan_NNN.ply with a matching registrations/tr_reg_NNN.ply")
    return items


def _box_ratios(v: np.ndarray) -> tuple[float, np.ndarray]:
    ext = v.max(axis=0) - v.min(axis=0)
    return float(ext[1]), np.array([ext[0] / ext[1], ext[2] / ext[1]])


def choose_scans(items: Sequence[FaustItem], numbers: Sequence[int] | None = None,
                 reference: np.ndarray | None = None) -> list[FaustItem]:
    """The scans to use: ``numbers`` when given (each must exist), else one A-pose-like scan per subject."""
    from .. import default_template, read_mesh

    by_number = {it.number: it for it in items}
    if numbers:
        missing = [n for n in numbers if n not in by_number]
        if missing:
            raise BenchError(f"--scans {','.join(map(str, missing))}: not found with a registration under the root")
        return [by_number[n] for n in numbers]
    ref = reference if reference is not None else default_template(full=True).vertices
    _, ref_ratio = _box_ratios(ref)
    chosen = []
    for subj in sorted({it.subject for it in items}):
        cands = [it for it in items if it.subject == subj]
        stats = [_box_ratios(read_mesh(it.registration).vertices) for it in cands]
        tallest = max(h for h, _ in stats)
        upright = [(it, r) for it, (h, r) in zip(cands, stats, strict=True) if h >= 0.97 * tallest]
        chosen.append(min(upright, key=lambda ir: float(np.abs(ir[1] - ref_ratio).sum()))[0])
    return chosen


def nearest_index(source: np.ndarray, queries: np.ndarray, chunk: int = 4096) -> np.ndarray:
    """Index of the nearest ``source`` point for each query (scipy's k-d tree, or chunked numpy)."""
    try:
        from scipy.spatial import cKDTree

        return np.asarray(cKDTree(source).query(queries)[1], dtype=np.int64)
    except ImportError:
        out = np.empty(len(queries), np.int64)
        s2 = (source ** 2).sum(axis=1)
        for i in range(0, len(queries), chunk):
            q = queries[i:i + chunk]
            d = s2[None, :] - 2.0 * q @ source.T
            out[i:i + chunk] = np.argmin(d, axis=1)
        return out


def sample_surface(mesh: Mesh, n: int, seed: int = 0) -> np.ndarray:
    """``n`` points uniformly distributed on the mesh surface (area-weighted, deterministic):
    :func:`bsv.bench.common.surface_samples` without their triangles."""
    return surface_samples(mesh, n, seed)[0]


def label_registration(reg: Mesh, params: dict[str, Any] | None = None, samples: int = 60_000) -> tuple[Mesh, dict]:
    """Ground-truth labels of a watertight registration mesh: the full 14-segment template registered to
    points sampled on it, each registration vertex labelled by the nearest fitted template vertex."""
    from .. import default_template, register

    tmpl = default_template(full=True)
    pts = sample_surface(reg, samples)
    # an unlabelled cloud: bsv.register keeps the template's labels (its params["labels"] = "template")
    fit = register(pts, None, tmpl, label_source="template", **dict(params or {}))
    if fit.mesh.vertex_labels is None:
        raise BenchError("the full template registration returned no labels")
    vl = fit.mesh.vertex_labels[nearest_index(fit.mesh.vertices, reg.vertices)]
    info = {"label_seconds": fit.seconds, **{k: v for k, v in (fit.volumes.get("registration") or {}).items()
                                             if k.startswith("rms")}}
    return Mesh(reg.vertices, reg.faces, vl, None), info


def place(reg: Mesh, scan: Mesh, facing: str = "+z") -> tuple[Mesh, Mesh]:
    """Move both meshes so the registration stands on y = 0 centred on x = z = 0 (turned if facing -z)."""
    v = reg.vertices
    shift = np.array([-(v[:, 0].min() + v[:, 0].max()) / 2, -v[:, 1].min(), -(v[:, 2].min() + v[:, 2].max()) / 2])
    flip = np.diag([-1.0, 1.0, -1.0]) if facing == "-z" else np.eye(3)
    return (Mesh((reg.vertices + shift) @ flip.T, reg.faces, reg.vertex_labels, reg.face_labels),
            Mesh((scan.vertices + shift) @ flip.T, scan.faces, scan.vertex_labels, scan.face_labels))


def faust_item(args: tuple[FaustItem, Sequence[str], int, Mesh, Sequence[str], dict[str, Any] | None, str]
               ) -> tuple[dict, list[Run]]:
    """One FAUST scan in every condition: (info, runs); failures are recorded in them, never raised.
    ``args``: (item, conditions, seed, template, methods, params, facing), one tuple so that it is one
    task on the ``bsv batch`` cluster."""
    from .. import read_mesh, volumes
    from .synth import measure_condition

    it, conditions, seed, tmpl, methods, params, facing = args
    try:
        reg_mesh, scan_mesh = place(read_mesh(it.registration), read_mesh(it.scan), facing)
        gt_mesh, info = label_registration(reg_mesh)
        truth = {k: float(v) for k, v in volumes(gt_mesh)["volumes_l"].items()}
        near = nearest_index(gt_mesh.vertices, scan_mesh.vertices)
        assert gt_mesh.vertex_labels is not None
        svl = gt_mesh.vertex_labels[near]
        centroids = scan_mesh.vertices[scan_mesh.faces].mean(axis=1)
        sfl = gt_mesh.vertex_labels[nearest_index(gt_mesh.vertices, centroids)]
        labelled_scan = Mesh(scan_mesh.vertices, scan_mesh.faces, svl, sfl)
    except Exception as exc:  # reported, the rest goes on
        err = f"{type(exc).__name__}: {exc}"
        return {"subject": it.name, "error": err}, [Run(it.name, c, m, False, error=err) for c in conditions
                                                    for m in methods]
    runs: list[Run] = []
    for c in conditions:
        try:
            runs += measure_condition(it.name, labelled_scan, truth, c, seed, tmpl, methods, "oracle",
                                      params, truth_mesh=gt_mesh)
        except Exception as exc:
            runs += [Run(it.name, c, m, False, truth_l=truth, error=f"{type(exc).__name__}: {exc}")
                     for m in methods]
    return {"subject": it.name, "faust_subject": it.subject, "pose": it.pose, "scan": str(it.scan),
            "registration": str(it.registration), **info}, runs


def run_faust(root: str | Path, out: str | Path, scans: Sequence[int] | None = None,
              conditions: Sequence[str] = CONDITIONS, seed: int = 0, methods: Sequence[str] = ("bsv",),
              params: dict[str, Any] | None = None, progress: bool = True, facing: str = "+z",
              template: str = "default", overwrite: bool = False, jobs: int = 1,
              scheduler: str | None = None) -> tuple[list[Run], dict]:
    """The FAUST benchmark; writes the same outputs as ``bench synth`` into ``out`` (existing outputs are
    refused before any work, :class:`bsv.errors.OutputExistsError`, unless ``overwrite``). ``jobs`` > 1 or
    a ``scheduler`` runs one scan per task on the ``bsv batch`` cluster (as ``bench synth``)."""
    from tqdm import tqdm

    from .common import load_template
    from .output import check_outputs, write_outputs

    if facing not in ("+z", "-z"):
        raise BenchError(f"--facing {facing}: use +z or -z")
    check_outputs(out, overwrite)
    items = choose_scans(list_scans(root), scans)
    tmpl = load_template(template)
    t0 = time.perf_counter()
    infos: list[dict] = []
    runs: list[Run] = []
    tasks = [(it, tuple(conditions), seed, tmpl, tuple(methods), params, facing) for it in items]
    with tqdm(total=len(items) * len(conditions), desc="bench faust", unit="scan", disable=not progress) as bar:
        if jobs <= 1 and scheduler is None:
            results: Iterable[tuple[int, Any]] = ((i, faust_item(t)) for i, t in enumerate(tasks))
        else:
            from ..batch.mapping import map_unordered

            results = map_unordered(faust_item, tasks, scheduler=scheduler, workers=max(1, jobs), announce=progress)
        for i, res in results:
            if isinstance(res, BaseException):  # the task itself failed (its workers died): recorded
                err = f"task failed: {type(res).__name__}: {res}"
                res = ({"subject": items[i].name, "error": err},
                       [Run(items[i].name, c, m, False, error=err) for c in conditions for m in methods])
            info, item_runs = res
            infos.append(info)
            runs += item_runs
            for r in item_runs:
                if not r.ok:
                    bar.write(f"FAILED {r.subject} {r.condition} {r.method}: {r.error}")
            bar.update(len(conditions))
    order = {it.name: k for k, it in enumerate(items)}  # the items' order, whatever order the tasks ended in
    infos.sort(key=lambda d: order.get(d["subject"], len(order)))
    runs.sort(key=lambda r: order.get(r.subject, len(order)))
    wall = time.perf_counter() - t0
    config = {"root": str(root), "scans": ",".join(str(i.number) for i in items), "conditions": ",".join(conditions),
              "seed": seed, "methods": ",".join(methods), "params": dict(params or {}), "facing": facing,
              "template": template}
    notes = [("Ground truth: FAUST registration meshes labelled by registering the 14-segment template to "
              "them (see bsv/bench/faust.py); the virtual rig scans the raw scans.")]
    summary = write_outputs(out, "BSV FAUST benchmark", config, infos, runs, wall, notes, overwrite=overwrite,
                            on_faust=True)
    return runs, summary

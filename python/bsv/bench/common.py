"""Shared pieces of the benchmarks: errors, the RVE metric, cloud preparation, templates, registration
with either method (BSV's ARAP or the trimesh peer), and the per-run record."""

from __future__ import annotations

import time
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import BenchError
from ..keypoints import camera_joints
from ..types import SEGMENT_IDS, TRUNK_LIMBS, Mesh, PointCloud

#: Segment ids a lab's cloud keeps (DESIGN.md data flow step 4 drops head, hands and feet).
KEEP_IDS: tuple[int, ...] = tuple(SEGMENT_IDS[n] for n in TRUNK_LIMBS)



def rve(estimated: float, true: float) -> float:
    """Relative volume error |V_est - V_gt| / V_gt in percent."""
    return abs(signed_error(estimated, true))


def signed_error(estimated: float, true: float) -> float:
    """Signed relative volume error (V_est - V_gt) / V_gt in percent (negative = shrinks)."""
    if not true > 0:
        raise BenchError(f"true volume {true} L: must be > 0 to compute a relative error")
    return (estimated - true) / true * 100.0


def keep_trunk_limbs(cloud: PointCloud) -> PointCloud:
    """The cloud without head, hand, foot and unlabelled points (what a lab registers)."""
    if cloud.labels is None:
        raise BenchError("the scanned cloud has no labels: oracle segmentation needs the scanner's labels")
    keep = np.isin(cloud.labels, KEEP_IDS)
    return PointCloud(
        cloud.points[keep],
        None if cloud.normals is None else cloud.normals[keep],
        None if cloud.colors is None else cloud.colors[keep],
        cloud.labels[keep],
    )


#: Distances (metres) of the cloud-quality columns: a point farther than this from the true body is
#: off the body (floor, wall, mask spill, flying pixel).
FAR_THRESHOLDS_M: tuple[float, float] = (0.02, 0.10)


def cloud_far_pct(cloud: PointCloud, truth: Mesh) -> tuple[float, float]:
    """Percent of ``cloud``'s points farther than 2 cm and than 10 cm from the surface of ``truth``
    (exact point-to-triangle distances, :func:`bsv.surface_distances`); (0, 0) for an empty cloud."""
    from .. import surface_distances

    if len(cloud) == 0:
        return 0.0, 0.0
    d = surface_distances(cloud.points, truth)
    near, far = FAR_THRESHOLDS_M
    return float(np.mean(d > near) * 100.0), float(np.mean(d > far) * 100.0)


def surface_samples(mesh: Mesh, n: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """``n`` points uniformly distributed on the mesh surface (area-weighted, deterministic for a seed)
    and the index of each one's triangle."""
    rng = np.random.default_rng(seed)
    tri = np.asarray(mesh.vertices, dtype=np.float64)[np.asarray(mesh.faces)]
    area = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
    if not area.sum() > 0:
        raise BenchError("mesh has zero area: cannot sample it")
    f = rng.choice(len(tri), size=n, p=area / area.sum())
    r1, r2 = rng.random(n), rng.random(n)
    s = np.sqrt(r1)
    w = np.stack([1 - s, s * (1 - r2), s * r2], axis=1)
    return np.einsum("ij,ijk->ik", w, tri[f]), f


#: ``--template`` value that takes each subject's sex's embedded template (:func:`bsv.default_template`).
SEX_TEMPLATE = "sex"


def load_template(name: str, sex: str | None = None) -> Mesh:
    """``default`` (9 segments, 4,177 vertices), ``fine`` (its midpoint subdivision), ``sex`` (the template of
    the subject's ``sex``, as ``bsv process --sex`` takes it) or a mesh file path."""
    from .. import default_template, read_mesh

    if name == "default":
        return default_template()
    if name == SEX_TEMPLATE:
        if sex is None:
            raise BenchError("--template sex needs the subject's sex")
        return default_template(sex=sex)
    if name == "fine":
        from ..bodies.template import subdivide_midpoint

        t = default_template()
        if t.face_labels is None:
            raise BenchError("the embedded template has no face labels; cannot subdivide it with labels")
        return subdivide_midpoint(t)
    p = Path(name)
    if not p.is_file():
        raise BenchError(f"template {name!r}: use 'default', 'fine', 'sex' or the path of a labelled PLY/OBJ mesh")
    return read_mesh(p)


@dataclass
class Fit:
    """One registration: the fitted labelled mesh, its volumes (litres), wall time and diagnostics."""

    method: str
    mesh: Mesh
    volumes_l: dict[str, float]
    seconds: float
    info: dict[str, Any] = field(default_factory=dict)


#: ``--param`` key of ``bench synth --segmentation camera``: the measured joint centres of these kinds (``+`` or
#: ``,`` separated, or ``all``) replaced by the rig's true ones (:func:`bsv.bench.joints.with_oracle_joints`)
#: everywhere the camera path uses them (the template's posing, the upper arms' confinement, the keypoint term),
#: the camera labels kept. A diagnostic, like the oracle labels: it measures what a joint's localisation costs
#: each segment (``benchmarks/BENCH.md``, round 2 session 37: in the room, held-out seeds 20-21, the true elbows
#: take the forearms from 2.0-2.3 % to 0.9-1.4 %). The run's joint errors stay those of the measured joints.
ORACLE_JOINTS_PARAM = "oracle_joints"

#: ``--param`` keys the bench itself reads (not registration parameters): the camera path's measured
#: joints pull the template's as in ``bsv process``: by default the shoulders, elbows, wrists and hips only
#: (:data:`bsv.keypoints.CAMERA_KEYPOINT_KINDS`), ``keypoints=true`` every joint (``--keypoints``),
#: ``keypoints=false`` none (``--no-keypoints``); ``keypoint_joints=elbow+knee`` keeps only those joints;
#: ``pose_template=false`` keeps the template's own A-pose on the camera path (``--no-pose-template``);
#: ``oracle_joints=elbow+knee`` (or ``all``) gives the camera path the rig's true joint centres of those kinds
#: (:data:`ORACLE_JOINTS_PARAM`, a diagnostic).
BENCH_ONLY_PARAMS: tuple[str, ...] = ("keypoints", "keypoint_joints", "pose_template", ORACLE_JOINTS_PARAM)


def register_bsv(cloud: PointCloud, template: Mesh, params: Mapping[str, Any] | None = None,
                 keypoints: Mapping[str, Any] | None = None) -> Fit:
    """BSV's regularized ARAP registration (:func:`bsv.register`) of ``template`` to the labelled cloud,
    with the measured joint centres ``keypoints`` when given (the shoulders', wrists' and hips' by default, every joint with
    ``--param keypoints=true``, none with ``keypoints=false``)."""
    from .. import register

    t0 = time.perf_counter()
    kw = dict(params or {})
    # `--param labels:template` is the registration's label source, not the cloud's per-point labels
    label_source = kw.pop("labels", None)
    which = str(kw.pop("keypoints", "default")).lower()
    kinds = kw.pop("keypoint_joints", None)  # e.g. --param keypoint_joints=elbow+knee
    choice = False if which in ("false", "0", "no", "off") else True if which in ("true", "1", "yes", "on") else None
    keypoints = camera_joints(keypoints, choice, str(kinds).replace("+", ",").split(",") if kinds else None)
    reg = register(cloud, None, template, label_source=label_source, keypoints=keypoints, **kw)  # as bsv process
    wall = time.perf_counter() - t0
    summary = dict(reg.volumes.get("registration", {}) or {})
    kept = ("rms_mesh_to_points_mm", "rms_points_to_mesh_mm", "iterations", "prealign", "articulation")
    info = {k: summary[k] for k in kept if k in summary}
    return Fit("bsv", reg.mesh, dict(reg.volumes["volumes_l"]), wall, info)


def register_method(method: str, cloud: PointCloud, template: Mesh,
                    params: Mapping[str, Any] | None = None, keypoints: Mapping[str, Any] | None = None) -> Fit:
    """Dispatch: ``bsv`` or ``trimesh`` (the peer, :mod:`bsv.bench.peer`; it takes no keypoints)."""
    if method == "bsv":
        return register_bsv(cloud, template, params, keypoints)
    if method == "trimesh":
        from .peer import register_trimesh

        return register_trimesh(cloud, template, params)
    raise BenchError(f"unknown registration method {method!r}: use bsv or trimesh")


@dataclass
class Run:
    """One registration of one subject (or box) in one condition, with everything the tables need."""

    subject: str
    condition: str
    method: str
    ok: bool
    truth_l: dict[str, float] = field(default_factory=dict)
    estimated_l: dict[str, float] = field(default_factory=dict)
    floor_l: dict[str, float] = field(default_factory=dict)
    seconds: float = 0.0
    n_points: int = 0
    #: Percent of the registered cloud's points farther than 2 cm / 10 cm from the true body surface
    #: (:func:`cloud_far_pct`); None when not measured.
    cloud_far_2cm_pct: float | None = None
    cloud_far_10cm_pct: float | None = None
    #: The same for the lab path's cloud before the statistical outlier removal (what the person mask let
    #: through: floor, wall, flying pixels); None on the raw path.
    unfiltered_far_2cm_pct: float | None = None
    unfiltered_far_10cm_pct: float | None = None
    error: str = ""
    info: dict[str, Any] = field(default_factory=dict)

    def to_json(self) -> dict[str, Any]:
        """A JSON-ready dict."""
        return asdict(self)

    @staticmethod
    def from_json(doc: Mapping[str, Any]) -> Run:
        """The inverse of :meth:`to_json`."""
        return Run(**{k: doc[k] for k in Run.__dataclass_fields__ if k in doc})

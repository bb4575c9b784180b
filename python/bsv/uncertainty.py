"""95 % intervals of every volume, aggregate, ratio and asymmetry of a fitted mesh.

Two independent sources are combined:

1. **Calibration** (Monte Carlo). Each camera's extrinsics carry a 6 x 6 covariance (``calibration.json``,
   or the paper's repeatability, :data:`PAPER_STD`). Parameterisation, shared with
   :mod:`bsv.frontend.calibrate`: ``delta = (tx, ty, tz, rx, ry, rz)`` in metres and radians, in the
   camera frame of OpenCV (+X right = transversal, +Y down = vertical, +Z optical axis = longitudinal),
   composed on the right: ``E_alt = E o delta``, i.e. ``R_alt = R Rodrigues(r)``, ``t_alt = R t_delta + t``
   (the Cali model of DESIGN.md; its "x vertical, y transversal" axes of the portrait sensor are our Y and
   X). Each draw moves every camera's part of the fitted surface rigidly by ``E_alt o E^-1`` with the
   blending weights of the calibration floor (:func:`bsv.bench.floor.camera_weights`) and re-measures it
   as :func:`bsv.volumes` would (the mesh prepared once, every draw re-measured in one parallel call): no
   new registration. A fixed seed makes it reproducible.
2. **Depth noise and registration** (an error model): per quantity, the bias and the prediction standard
   deviation of the registration error measured on a synthetic cohort (``bsv/data/noise_model.json``,
   derived by :mod:`bsv.bench.noisemodel`; its ``derivation`` says from which runs). The table has one
   model per depth sensor and segmentation (:func:`model_for`): ``l515`` (the L515's depth noise and
   flying pixels: what every real capture gets, :data:`DEFAULT_DEPTH`) and ``exact`` (noise-free depth,
   for the benchmark's noer and cali), each also as ``<depth>_camera`` for the MediaPipe segmentation.
   Gross registration failures (a segment missed by tens of percent, :data:`bsv.bench.noisemodel.GROSS_SIGMAS`)
   are left out of the model and counted in it: the intervals hold for fits without one.

Quantities are compared in a transformed space where errors are close to additive and normal: the
natural log of volumes, masses and ratios, the asymmetry itself (percentage points). With ``est`` the
measured value, the truth lies in ``T^-1(T(est) - bias +- 1.96 sqrt(sd_model^2 + sd_calibration^2))``.
An asymmetry whose interval contains 0 is "not distinguishable from symmetric" (:func:`asymmetry_text`).

On the camera path the error grows with the subject's build (:func:`bsv.frontend.sex.build_score`: the
heavier the body, the further its cut lines drift and the less of its hidden sides the fit sees): a camera
model may carry a :class:`BuildTerm`: per quantity a bias per unit of the build and a growth of the variance
per unit beyond its ``hinge``, for a capture whose build is known (:func:`combine`'s ``build_score``).
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from functools import lru_cache
from importlib import resources
from typing import Any

import numpy as np

from . import _bsv
from .errors import UncertaintyError
from .types import Mesh

#: Confidence level of every interval and its two-sided normal quantile.
LEVEL: float = 0.95
Z95: float = 1.959963984540054

#: Names of the 6 extrinsic parameters of a covariance (order of its rows and columns): the Rust rig's.
PARAMETERS: tuple[str, ...] = tuple(_bsv.COVARIANCE_PARAMETERS)
#: The parameterisation, written next to every covariance in calibration.json: the Rust rig's
#: ``"delta in the camera frame (OpenCV: +X right, +Y down, +Z optical axis), composed on the right:
#: R' = R Rodrigues(r), t' = R t_delta + t (camera_to_world)"``.
FRAME: str = _bsv.COVARIANCE_FRAME

#: The paper's calibration repeatability (DESIGN.md "Cali"), one standard deviation per parameter of
#: :data:`PARAMETERS` in our camera frame (paper x vertical -> our Y, paper y transversal -> our X):
#: the virtual rig's calibration sigmas (``bsv_capture::scanner::Rig::paper_default``), its one source.
PAPER_STD: dict[str, tuple[float, ...]] = {k: tuple(v) for k, v in _bsv.PAPER_CALIBRATION_STD.items()}

#: The error model of real captures (an L515's depth noise).
DEFAULT_DEPTH: str = "l515"

#: Monte Carlo draws of the calibration part and their seed (fixed: the same input gives the same interval).
DEFAULT_SAMPLES: int = 200
DEFAULT_SEED: int = 20_260_613


def paper_covariance(camera: str) -> np.ndarray:
    """Diagonal 6 x 6 covariance of the paper's repeatability for ``camera`` ("front"/"back"; any other
    name gets the larger of the two per parameter)."""
    std = PAPER_STD.get(camera) or tuple(max(a, b) for a, b in zip(PAPER_STD["front"], PAPER_STD["back"], strict=True))
    return np.diag(np.square(np.asarray(std, dtype=np.float64)))


def check_covariance(cov: Any, where: str) -> np.ndarray:
    """The covariance as a symmetric positive semi-definite 6 x 6 float array, or UncertaintyError naming ``where``."""
    try:
        c = np.asarray(cov, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise UncertaintyError(f"{where}: covariance is not a 6 x 6 array of numbers ({exc})") from exc
    if c.shape != (6, 6) or not np.isfinite(c).all():
        raise UncertaintyError(f"{where}: covariance must be a finite 6 x 6 matrix, got shape {c.shape}")
    if not np.allclose(c, c.T, rtol=1e-6, atol=1e-15):
        raise UncertaintyError(f"{where}: covariance is not symmetric")
    if np.linalg.eigvalsh(c).min() < -1e-12 * max(float(np.abs(c).max()), 1e-300):
        raise UncertaintyError(f"{where}: covariance is not positive semi-definite")
    return c


def rodrigues(r: np.ndarray) -> np.ndarray:
    """Rotation matrix of the rotation vector ``r`` (axis times angle, radians)."""
    r = np.asarray(r, dtype=np.float64)
    th = float(np.linalg.norm(r))
    k = np.array([[0.0, -r[2], r[1]], [r[2], 0.0, -r[0]], [-r[1], r[0], 0.0]])
    if th < 1e-12:
        return np.eye(3) + k
    k /= th
    return np.eye(3) + math.sin(th) * k + (1.0 - math.cos(th)) * (k @ k)


def rotation_vector(rot: np.ndarray) -> np.ndarray:
    """Rotation vector (radians) of a rotation matrix (the inverse of :func:`rodrigues` for angles < pi)."""
    c = float(np.clip((np.trace(rot) - 1.0) / 2.0, -1.0, 1.0))
    th = math.acos(c)
    w = np.array([rot[2, 1] - rot[1, 2], rot[0, 2] - rot[2, 0], rot[1, 0] - rot[0, 1]])
    if th < 1e-9:
        return w / 2.0
    return w * (th / (2.0 * math.sin(th)))


def pose_delta(r_ref: np.ndarray, t_ref: np.ndarray, r: np.ndarray, t: np.ndarray) -> np.ndarray:
    """The 6 parameters (:data:`PARAMETERS`) of pose (r, t) relative to (r_ref, t_ref): ``E = E_ref o delta``."""
    rd = np.asarray(r_ref).T @ np.asarray(r)
    td = np.asarray(r_ref).T @ (np.asarray(t) - np.asarray(t_ref))
    return np.concatenate([td, rotation_vector(rd)])


def perturb(r: np.ndarray, t: np.ndarray, delta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The pose ``E o delta`` (see :data:`FRAME`)."""
    return np.asarray(r) @ rodrigues(delta[3:]), np.asarray(r) @ np.asarray(delta[:3]) + np.asarray(t)


#: Precision of a floor-plane refinement (:mod:`bsv.frontend.floorplane`): height (m), tilts (rad); a
#: conservative allowance for real floors (the virtual rig's floor gives ~0.05 mm / 0.005 deg).
FLOOR_STD: tuple[float, float, float] = (0.001, math.radians(0.05), math.radians(0.05))

#: Systematic allowance of a board-depth refinement (:mod:`bsv.frontend.boardplane`), added to the plane
#: fit's own covariance: the two tilts of the board face (rad) and its offset along its normal (m). What
#: is common to both cameras (the board's placement, a bow of the board, the sensor's depth bias at the
#: board's distance, which the body shares) moves the whole reconstruction rigidly and does not enter a
#: volume; this covers what differs between the two faces: the board's thickness tolerance and flatness
#: (0.5 mm) and a face that is not a perfect plane in depth across its ~80 px (0.03 deg = 0.1 mm over the
#: 22 cm face). The virtual rig's board fit alone gives ~0.02 mm / 0.01 deg.
BOARD_STD: tuple[float, float, float] = (math.radians(0.03), math.radians(0.03), 0.0005)


def condition(cov: np.ndarray, rows: np.ndarray, noise: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Gaussian conditioning of the 6-parameter covariance ``cov`` on measurements ``rows @ delta`` with
    noise covariance ``noise``: (gain ``K = S A^T (A S A^T + N)^-1``, posterior ``S - K A S``)."""
    s = np.asarray(cov, dtype=np.float64)
    a = np.asarray(rows, dtype=np.float64)
    k = s @ a.T @ np.linalg.inv(a @ s @ a.T + np.asarray(noise, dtype=np.float64))
    out = s - k @ a @ s
    return k, (out + out.T) / 2.0


def condition_on_floor(cov: np.ndarray, rotation: np.ndarray, std: Sequence[float] = FLOOR_STD) -> np.ndarray:
    """The covariance after the floor has measured the camera's height and its tilts about the world's
    horizontal x and z axes with standard deviations ``std``: Gaussian conditioning (:func:`condition`),
    the rows being those three world quantities in :data:`PARAMETERS`."""
    r = np.asarray(rotation, dtype=np.float64)
    a = np.zeros((3, 6))
    a[0, :3] = r.T @ np.array([0.0, 1.0, 0.0])  # world height of the translation
    a[1, 3:] = r.T @ np.array([1.0, 0.0, 0.0])  # rotation about the world x axis
    a[2, 3:] = r.T @ np.array([0.0, 0.0, 1.0])  # rotation about the world z axis
    return condition(cov, a, np.diag(np.square(np.asarray(std, dtype=np.float64))))[1]


@dataclass(frozen=True)
class CameraSpread:
    """One camera's camera-to-world extrinsics and their 6 x 6 covariance (:data:`FRAME`)."""

    name: str
    rotation: np.ndarray
    translation: np.ndarray
    covariance: np.ndarray
    #: Where the covariance comes from ("frames", "paper default", ...).
    source: str = "paper default"


# ----------------------------------------------------------------------------------------------------
# Quantities and their transformed space


def is_additive(name: str) -> bool:
    """Whether quantity ``name`` is compared additively (asymmetries, in points) rather than in log."""
    return name.startswith("asymmetry_")


def quantities(volumes: Mapping[str, Any]) -> dict[str, float]:
    """The flat {name: value} of a volumes report's ``volumes_l`` then ``ratios`` (finite values only), for a
    report as a dict (e.g. read from a JSON file).

    It mirrors ``VolumeReport::quantities`` of bsv-volume, the one definition of the quantities the intervals
    model, which :meth:`bsv._bsv.PreparedVolumes.quantities` (and so :func:`calibration_spread`) uses;
    ``tests/python/test_uncertainty_prepared.py`` checks that the two give the same names and values."""
    out: dict[str, float] = {}
    for key in ("volumes_l", "ratios"):
        for k, v in (volumes.get(key) or {}).items():
            if v is not None and math.isfinite(float(v)):
                out[k] = float(v)
    return out


def transform(name: str, value: float) -> float:
    """The quantity in its comparison space: the value for asymmetries, its natural log otherwise."""
    if is_additive(name):
        return float(value)
    return math.log(value) if value > 0 else float("nan")


def untransform(name: str, value: float) -> float:
    """The inverse of :func:`transform`."""
    return float(value) if is_additive(name) else math.exp(value)


# ----------------------------------------------------------------------------------------------------
# Calibration part


def calibration_spread(mesh: Mesh, cameras: Sequence[CameraSpread], *, samples: int = DEFAULT_SAMPLES,
                       seed: int = DEFAULT_SEED, density: float = 1000.0) -> dict[str, float]:
    """Per quantity, the standard deviation (in the comparison space) of the re-measured fitted mesh over
    ``samples`` calibration draws: each camera's extrinsics perturbed within its covariance, its part of
    the surface moved rigidly (floor weights), the volumes of :func:`bsv.volumes` with the fitted mesh's
    settings. The mesh is prepared once (:class:`bsv._bsv.PreparedVolumes`: validation, labels, island
    merging and caps) and re-measured at every draw's vertices in one parallel call: the same numbers as
    :func:`bsv.volumes` on each moved mesh."""
    from .bench.floor import CameraPose, camera_weights, vertex_normals

    if samples < 2:
        raise UncertaintyError(f"samples={samples}: the calibration Monte Carlo needs at least 2 draws")
    if not cameras:
        return {}
    covs = [check_covariance(c.covariance, f"camera {c.name!r}") for c in cameras]
    prepared = _bsv.PreparedVolumes(mesh.vertices, mesh.faces, mesh.vertex_labels, mesh.face_labels, None,
                                    float(density), False, True)
    w = camera_weights(vertex_normals(mesh.vertices, mesh.faces),
                       [CameraPose(c.name, c.rotation, c.translation, c.rotation, c.translation) for c in cameras])
    # The draws first, in order (the same draws as ever for a seed), then every moved mesh at once.
    rng = np.random.default_rng(seed)
    draws = [[rng.multivariate_normal(np.zeros(6), cov, method="eigh") for cov in covs] for _ in range(samples)]
    vertices = np.asarray(mesh.vertices, dtype=np.float64)
    stack = np.empty((samples + 1, len(vertices), 3))
    stack[0] = vertices  # row 0: the nominal mesh
    moved_vertices(vertices, w, cameras, draws, out=stack[1:])
    measured = prepared.quantities(stack)
    nominal = {n: float(v[0]) for n, v in measured.items() if math.isfinite(float(v[0]))}
    names = sorted(nominal)
    out: dict[str, float] = {}
    for n in names:
        col = measured[n][1:]
        if is_additive(n):
            dev = col - nominal[n]
        else:
            dev = np.log(np.where(col > 0, col, np.nan)) - math.log(nominal[n]) if nominal[n] > 0 else col * np.nan
        if np.isfinite(dev).sum() > 1:
            out[n] = float(np.nanstd(dev, ddof=1))
    return out


def moved_vertices(vertices: np.ndarray, weights: np.ndarray, cameras: Sequence[CameraSpread],
                   draws: Sequence[Sequence[np.ndarray]], out: np.ndarray | None = None) -> np.ndarray:
    """The (S, N, 3) vertices of S calibration draws: in draw ``s`` camera ``k``'s extrinsics are perturbed by
    ``draws[s][k]`` (:func:`perturb`) and its rigid error ``E_alt o E^-1``
    (:meth:`bsv.bench.floor.CameraPose.error_transform`) moves the vertices, blended with the (N, C)
    ``weights``: ``sum_k weights[:, k] * (R_sk v + t_sk)``, one matrix product per draw."""
    from .bench.floor import CameraPose

    v = np.asarray(vertices, dtype=np.float64)
    w = np.asarray(weights, dtype=np.float64)
    rhs = np.empty((len(draws), 4 * len(cameras), 3))
    for s, deltas in enumerate(draws):
        for k, (c, delta) in enumerate(zip(cameras, deltas, strict=True)):
            r_alt, t_alt = perturb(c.rotation, c.translation, delta)
            r_err, t_err = CameraPose(c.name, c.rotation, c.translation, r_alt, t_alt).error_transform()
            rhs[s, 3 * k:3 * k + 3] = np.asarray(r_err).T
            rhs[s, 3 * len(cameras) + k] = t_err
    lhs = np.concatenate([w[:, [k]] * v for k in range(len(cameras))] + [w], axis=1)  # (N, 4C)
    return np.matmul(lhs, rhs, out=out)


# ----------------------------------------------------------------------------------------------------
# Depth-noise / registration error model


@dataclass(frozen=True)
class BuildTerm:
    """How a camera-path model's error drifts with the subject's build (:func:`bsv.frontend.sex.build_score`):
    for a build ``b``, a quantity's bias is the model's (its value at the hinge) plus ``bias[name] * (b -
    hinge)``, and its sd the model's times ``sqrt(1 + variance[name] * max(b - hinge, 0))`` (comparison
    space). An unknown build, or a quantity the term does not name, keeps the model's bias and sd."""

    #: The build score at which the model's own bias holds and beyond which its variance grows
    #: (:data:`bsv.bench.noisemodel.BUILD_HINGE`).
    hinge: float
    #: Per quantity: the bias per unit of the build (either side of the hinge).
    bias: dict[str, float]
    #: Per quantity: the variance's growth per unit of the build beyond the hinge, as a fraction of the
    #: model's (>= 0).
    variance: dict[str, float]

    def offset(self, build_score: float | None) -> float:
        """The build less the hinge (0 for an unknown or non-finite build)."""
        if build_score is None or not math.isfinite(build_score):
            return 0.0
        return float(build_score) - self.hinge

    def excess(self, build_score: float | None) -> float:
        """The build beyond the hinge (0 at or under it, or for an unknown or non-finite build)."""
        return max(self.offset(build_score), 0.0)

    def to_json(self) -> dict[str, Any]:
        """The model document's ``"build"`` record."""
        return {"hinge": self.hinge, "bias_per_unit": dict(self.bias), "variance_per_unit": dict(self.variance)}

    @staticmethod
    def from_json(doc: Mapping[str, Any], where: str = "error model") -> BuildTerm:
        """The inverse of :meth:`to_json`; :class:`UncertaintyError` naming ``where`` on a malformed record."""
        try:
            term = BuildTerm(float(doc["hinge"]), {str(k): float(v) for k, v in doc["bias_per_unit"].items()},
                             {str(k): float(v) for k, v in doc["variance_per_unit"].items()})
        except (KeyError, TypeError, ValueError, AttributeError) as exc:
            raise UncertaintyError(f"{where}: expected a build record {{'hinge', 'bias_per_unit', "
                                   f"'variance_per_unit'}} ({exc})") from exc
        bad = [k for k, v in term.bias.items() if not math.isfinite(v)]
        bad += [k for k, v in term.variance.items() if not (math.isfinite(v) and v >= 0)]
        if bad or not math.isfinite(term.hinge):
            raise UncertaintyError(f"{where}: the build record has a non-finite hinge or bias, or a negative "
                                   f"variance growth ({', '.join(bad) or 'hinge'})")
        return term


@dataclass(frozen=True)
class ErrorModel:
    """Per quantity ``bias`` and prediction ``sd`` of ``T(estimate) - T(truth)`` (comparison space), and for
    a camera-path model how they drift with the subject's build (``build``, None: they do not)."""

    entries: dict[str, tuple[float, float]]
    description: str = ""
    derivation: dict[str, Any] = field(default_factory=dict)
    build: BuildTerm | None = None

    def at(self, name: str, build_score: float | None = None) -> tuple[float, float] | None:
        """The (bias, sd) of quantity ``name`` for a subject of build ``build_score`` (None: unknown, the
        model's own); None when the model does not cover the quantity."""
        if name not in self.entries:
            return None
        bias, sd = self.entries[name]
        if self.build is None:
            return bias, sd
        return (bias + self.build.bias.get(name, 0.0) * self.build.offset(build_score),
                sd * math.sqrt(1.0 + self.build.variance.get(name, 0.0) * self.build.excess(build_score)))

    @staticmethod
    def from_json(doc: Mapping[str, Any], where: str = "error model") -> ErrorModel:
        """The model from its JSON form ``{"quantities": {name: {"bias": b, "sd": s, ...}}, "build": {...}}``
        (``build`` optional, :meth:`BuildTerm.to_json`)."""
        try:
            entries = {str(k): (float(v["bias"]), float(v["sd"])) for k, v in doc["quantities"].items()}
        except (KeyError, TypeError, ValueError, AttributeError) as exc:
            raise UncertaintyError(f"{where}: expected {{'quantities': {{name: {{'bias', 'sd'}}}}}} ({exc})") from exc
        bad = [k for k, (b, s) in entries.items() if not (math.isfinite(b) and math.isfinite(s) and s >= 0)]
        if bad:
            raise UncertaintyError(f"{where}: non-finite bias or negative sd for {', '.join(bad)}")
        build = BuildTerm.from_json(doc["build"], where) if doc.get("build") is not None else None
        return ErrorModel(entries, str(doc.get("description", "")), dict(doc.get("derivation", {})), build)


@lru_cache(maxsize=1)
def error_models() -> dict[str, ErrorModel]:
    """The packaged models by depth sensor (``bsv/data/noise_model.json``, see :mod:`bsv.bench.noisemodel`)."""
    path = resources.files("bsv") / "data" / "noise_model.json"
    try:
        doc = json.loads(path.read_text())
        models = doc["depth_models"]
        return {str(k): ErrorModel.from_json({**v, "derivation": doc.get("derivation", {})}, f"{path} [{k}]")
                for k, v in models.items()}
    except (OSError, json.JSONDecodeError, KeyError, TypeError, AttributeError) as exc:
        raise UncertaintyError(f"{path}: cannot read the packaged error model ({exc}); reinstall bsv") from exc


def model_for(depth: str = DEFAULT_DEPTH, segmentation: str = "oracle") -> str:
    """The name of the error model for a depth sensor and a segmentation: ``depth``, or ``depth_camera``
    for the camera (MediaPipe) segmentation, whose cut lines add their own error."""
    return f"{depth}_camera" if segmentation == "camera" else depth


def default_error_model(depth: str = DEFAULT_DEPTH) -> ErrorModel:
    """The packaged model of depth sensor ``depth`` ("l515" for real captures, "exact" for noise-free depth)."""
    models = error_models()
    if depth not in models:
        raise UncertaintyError(f"no error model for depth {depth!r}; the packaged ones: {sorted(models)}")
    return models[depth]


# ----------------------------------------------------------------------------------------------------
# Intervals


@dataclass(frozen=True)
class Intervals:
    """95 % intervals of a volumes report: ``volumes_l`` and ``ratios`` map names to (lo, hi)."""

    level: float
    method: str
    volumes_l: dict[str, tuple[float, float]]
    ratios: dict[str, tuple[float, float]]
    #: Seconds spent computing them.
    seconds: float = 0.0
    #: Mass intervals (kg): ``mass_trunk_limbs_kg`` = the trunk_limbs interval x density.
    mass_kg: dict[str, tuple[float, float]] = field(default_factory=dict)

    def get(self, name: str) -> tuple[float, float] | None:
        """The interval of a volume or ratio by name (None when it has none)."""
        return self.volumes_l.get(name) or self.ratios.get(name) or self.mass_kg.get(name)

    def distinguishable(self, name: str) -> bool | None:
        """For an asymmetry: whether its interval excludes 0 (None without an interval)."""
        iv = self.ratios.get(name)
        return None if iv is None else not (iv[0] <= 0.0 <= iv[1])

    def to_json(self) -> dict[str, Any]:
        """The ``"intervals"`` section of volumes.json."""
        return {"level": self.level, "method": self.method, "seconds": self.seconds,
                "volumes_l": {k: [lo, hi] for k, (lo, hi) in self.volumes_l.items()},
                "ratios": {k: [lo, hi] for k, (lo, hi) in self.ratios.items()},
                "mass_kg": {k: [lo, hi] for k, (lo, hi) in self.mass_kg.items()}}

    @staticmethod
    def from_json(doc: Mapping[str, Any]) -> Intervals:
        """The inverse of :meth:`to_json`."""
        def pairs(d: Mapping[str, Any] | None) -> dict[str, tuple[float, float]]:
            return {str(k): (float(v[0]), float(v[1])) for k, v in (d or {}).items()}

        return Intervals(float(doc.get("level", LEVEL)), str(doc.get("method", "")), pairs(doc.get("volumes_l")),
                         pairs(doc.get("ratios")), float(doc.get("seconds", 0.0)), pairs(doc.get("mass_kg")))


def combine(estimate: Mapping[str, float], model: ErrorModel, calibration_sd: Mapping[str, float] | None = None,
            extra_sd: Mapping[str, float] | None = None, build_score: float | None = None) -> dict[str, tuple[float, float]]:
    """Per quantity of ``estimate`` that the model covers: the 95 % interval of the truth (see module doc).
    ``extra_sd``: more sd per quantity in the comparison space (a degraded boundary of the capture's
    segmentation, :attr:`bsv.frontend.segment.Segmentation.extra_sd`), in quadrature with the others.
    ``build_score``: the subject's build (:func:`bsv.frontend.sex.build_score`), for a model with a
    :class:`BuildTerm` (None: the model's own bias and sd)."""
    cal = calibration_sd or {}
    extra = extra_sd or {}
    out: dict[str, tuple[float, float]] = {}
    for name, value in estimate.items():
        entry = model.at(name, build_score)
        if entry is None:
            continue
        bias, sd = entry
        centre = transform(name, value) - bias
        if not math.isfinite(centre):
            continue
        half = Z95 * math.hypot(sd, float(cal.get(name, 0.0)), float(extra.get(name, 0.0)))
        out[name] = (untransform(name, centre - half), untransform(name, centre + half))
    return out


def intervals(mesh: Mesh, volumes: Mapping[str, Any], cameras: Sequence[CameraSpread], *,
              model: ErrorModel | None = None, samples: int = DEFAULT_SAMPLES, seed: int = DEFAULT_SEED,
              density: float = 1000.0, note: str = "", extra_sd: Mapping[str, float] | None = None,
              build_score: float | None = None) -> Intervals:
    """The 95 % intervals of the fitted ``mesh``'s ``volumes`` report (as :func:`bsv.register` returns it),
    combining the calibration Monte Carlo over ``cameras`` and the error ``model`` (default: packaged), and
    ``extra_sd`` per quantity where the capture's segmentation was degraded, at the subject's ``build_score``
    when the model follows the build (:func:`combine`). ``note`` is appended to the method text (what the
    intervals do not cover)."""
    t0 = time.perf_counter()
    m = model or default_error_model()
    cal = calibration_spread(mesh, cameras, samples=samples, seed=seed, density=density)
    est = quantities(volumes)
    both = combine(est, m, cal, extra_sd, build_score)
    excess = m.build.excess(build_score) if m.build is not None else 0.0
    vol_keys = set((volumes.get("volumes_l") or {}).keys())
    sources = sorted({c.source for c in cameras})
    method = (f"calibration Monte Carlo ({samples} draws, seed {seed}, covariance: {', '.join(sources) or 'none'}) "
              f"+ depth-noise/registration error model ({m.description or 'bsv/data/noise_model.json'}), "
              "combined in quadrature, normal, centred on the measured value corrected for the error model's mean "
              "bias (a value the fit measures low on the cohort gets an interval above it, and may lie just outside "
              "its own interval); the error model leaves out gross registration failures (a "
              "segment missed by tens of percent), which the intervals do not cover"
              + (f"; widened where the segmentation was degraded (sd added for {', '.join(sorted(extra_sd))})"
                 if extra_sd else "")
              + (f"; moved for the subject's build ({build_score:.1f}) and widened by {excess:.1f} beyond the "
                 f"model's {m.build.hinge:g} (the camera path's error grows with the build)" if m.build is not None
                 and build_score is not None and math.isfinite(build_score) else "")
              + (f"; {note}" if note else ""))
    tl = both.get("trunk_limbs")
    mass = {} if tl is None else {"mass_trunk_limbs_kg": (tl[0] * density / 1000.0, tl[1] * density / 1000.0)}
    return Intervals(LEVEL, method, {k: v for k, v in both.items() if k in vol_keys},
                     {k: v for k, v in both.items() if k not in vol_keys}, time.perf_counter() - t0, mass)


def asymmetry_text(value: float, interval: tuple[float, float] | None) -> str:
    """How the report prints an asymmetry: with its interval, or "not distinguishable from symmetric"."""
    if interval is None:
        return f"{value:+.1f} % (no interval)"
    lo, hi = interval
    if lo <= 0.0 <= hi:
        return f"not distinguishable from symmetric ({value:+.1f} %, 95 % interval {lo:+.1f} to {hi:+.1f})"
    return f"{value:+.1f} % (95 % interval {lo:+.1f} to {hi:+.1f})"


__all__ = [
    "BOARD_STD",
    "DEFAULT_DEPTH",
    "DEFAULT_SAMPLES",
    "DEFAULT_SEED",
    "FLOOR_STD",
    "FRAME",
    "LEVEL",
    "PAPER_STD",
    "PARAMETERS",
    "BuildTerm",
    "CameraSpread",
    "ErrorModel",
    "Intervals",
    "asymmetry_text",
    "calibration_spread",
    "check_covariance",
    "combine",
    "condition",
    "condition_on_floor",
    "default_error_model",
    "error_models",
    "intervals",
    "is_additive",
    "model_for",
    "moved_vertices",
    "paper_covariance",
    "perturb",
    "pose_delta",
    "quantities",
    "rodrigues",
    "rotation_vector",
    "transform",
    "untransform",
]

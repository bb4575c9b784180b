"""A posed, labelled MakeHuman body with ground-truth segment volumes, and the stature/BMI solver."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np

from .. import _bsv
from ..errors import SolveError
from ..types import Mesh
from .asset import Asset, load_asset
from .joints import posed_rig_joints
from .labels import body_labels, volume
from .model import Phenotype, shape
from .pose import Pose, pose_vertices


@lru_cache(maxsize=1)
def _labels(asset_id: int) -> tuple[np.ndarray, np.ndarray]:
    a = load_asset()
    return body_labels(a.faces, a)


@dataclass
class Body:
    """A posed body in the world frame (floor y = 0, hips centred on x = z = 0), labelled with 14 segments."""

    vertices: np.ndarray
    faces: np.ndarray
    vertex_labels: np.ndarray
    face_labels: np.ndarray
    phenotype: Phenotype = field(default_factory=Phenotype)
    pose: Pose = field(default_factory=Pose)

    @property
    def stature(self) -> float:
        """Standing height (m): top of the head above the floor."""
        return float(self.vertices[:, 1].max() - self.vertices[:, 1].min())

    @property
    def volume_l(self) -> float:
        """Whole-body volume (litres)."""
        return volume(self.vertices, self.faces) * 1e3

    @property
    def bmi(self) -> float:
        """BMI-equivalent: volume x 1 kg/L / stature^2."""
        return self.volume_l / self.stature ** 2

    def volumes_l(self) -> dict[str, float]:
        """Ground-truth volumes (litres) of every segment and the aggregates of DESIGN.md."""
        volumes: dict[str, float] = _bsv.volumes(self.vertices, self.faces, None, self.face_labels).volumes_l
        return volumes

    def mesh(self) -> Mesh:
        """The body as a bsv.Mesh (vertex and face labels)."""
        return Mesh(self.vertices, self.faces, self.vertex_labels, self.face_labels)


def make_body(phenotype: Phenotype | None = None, pose: Pose | None = None, asset: Asset | None = None) -> Body:
    """Shape (macro + local modifiers), pose (dual-quaternion A-pose) and label a MakeHuman body."""
    a = asset or load_asset()
    ph = phenotype or Phenotype()
    po = pose or Pose()
    v, j = shape(ph, a)
    pv = posed_rig_joints(v, j, po, a)[0]
    vl, fl = _labels(id(a)) if asset is None else body_labels(a.faces, a)
    return Body(pv, a.faces.copy(), vl.copy(), fl.copy(), ph, po)


def _eval(ph: Phenotype, pose: Pose, a: Asset) -> tuple[float, float]:
    v, j = shape(ph, a)
    pv = pose_vertices(v, j, pose, a)
    st = float(pv[:, 1].max() - pv[:, 1].min())
    return st, volume(pv, a.faces) * 1e3 / st ** 2


def _control(c: float, m0: float) -> tuple[float, float]:
    """BMI control c in [0, 2] -> (weight, muscle): weight rises to 1, then muscle falls from m0 to 0."""
    if c <= 1.0:
        return c, m0
    return 1.0, m0 * (2.0 - c)


def _solve1d(f: Callable[[float], float], lo: float, hi: float, target: float, tol: float, what: str) -> float:
    """Root of the increasing function f(x) = target on [lo, hi] (Illinois regula falsi)."""
    flo, fhi = f(lo) - target, f(hi) - target
    if flo > 0 or fhi < 0:
        raise SolveError(f"{what}: target {target:.3f} is outside the reachable range "
                         f"[{flo + target:.3f}, {fhi + target:.3f}]", (flo + target, fhi + target))
    side = 0
    x = lo
    for _ in range(60):
        x = hi - fhi * (hi - lo) / (fhi - flo) if fhi != flo else 0.5 * (lo + hi)
        fx = f(x) - target
        if abs(fx) < tol or hi - lo < 1e-12:
            return x
        if fx > 0:
            hi, fhi = x, fx
            if side == -1:
                flo *= 0.5
            side = -1
        else:
            lo, flo = x, fx
            if side == 1:
                fhi *= 0.5
            side = 1
    return x


def solve_stature_bmi(stature: float, bmi: float, phenotype: Phenotype | None = None, pose: Pose | None = None,
                      asset: Asset | None = None, tol_m: float = 1e-4, tol_bmi: float = 0.01) -> Phenotype:
    """Set height and weight (lowering muscle when weight alone is not enough) so that the posed body
    stands ``stature`` metres tall with BMI-equivalent ``bmi`` (volume x 1 kg/L / stature^2).

    The other fields of ``phenotype`` (gender, age, proportions, local modifiers, muscle as the
    starting value) are kept. Raises SolveError when the target cannot be reached.
    """
    a = asset or load_asset()
    ph = phenotype or Phenotype()
    po = pose or Pose()
    if not (1.0 < stature < 2.6) or not (10.0 < bmi < 50.0):
        raise SolveError(f"stature {stature} m / BMI {bmi}: outside 1.0-2.6 m / 10-50")
    m0 = float(ph.muscle)
    h, c = ph.height, ph.weight

    def pheno(h_: float, c_: float) -> Phenotype:
        w, m = _control(c_, m0)
        return ph.with_(height=min(max(h_, 0.0), 1.0), weight=w, muscle=m)

    def stature_at(x: float) -> float:  # at the current weight c
        return _eval(pheno(x, c), po, a)[0]

    def bmi_at(x: float) -> float:  # at the current height h
        return _eval(pheno(h, x), po, a)[1]

    for _ in range(8):
        h = _solve1d(stature_at, 0.0, 1.0, stature, tol_m * 0.3, "stature")
        c = _solve1d(bmi_at, 0.0, 2.0, bmi, tol_bmi * 0.3, "BMI")
        st, b = _eval(pheno(h, c), po, a)
        if abs(st - stature) < tol_m and abs(b - bmi) < tol_bmi:
            return pheno(h, c)
    raise SolveError(f"stature/BMI solver did not converge for {stature} m / {bmi}")

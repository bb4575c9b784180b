"""Body-segment inertial parameters of a labelled closed mesh: per segment mass (segment densities),
centre of mass, inertia tensor, joint centres, segment length, and the de Leva comparison.

The geometry (volume, centre of mass and inertia tensor of each segment closed by the shared caps, and
the caps' centres) comes from the Rust extension (``bsv._bsv.mass_properties``, exact on polyhedra);
this module applies densities, finds each segment's endpoints and expresses the results in the layout
of the de Leva / Zatsiorsky tables.

Joint centres: the centroid of the boundary loop two segments share (the cap apex of the volumes), e.g.
the elbow is the centroid of the upper_arm/forearm boundary. An endpoint whose neighbour is absent (the
wrist of a mesh without hands, the top of the head) is the segment's extent: from the known joint along
the direction to the segment's centre of mass, as far as the segment's farthest vertex goes (the foot
uses its long principal axis, heel to toe).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .. import _bsv
from ..errors import BsipError
from ..interop import as_mesh
from ..types import SEGMENT_IDS, Mesh
from ..types import SEXES as TYPES_SEXES
from .tables import DE_LEVA, DE_LEVA_SOURCE, DEMPSTER_DENSITY_KG_M3, DENSITY_SOURCE, JOINTS, DeLeva, kind

#: Sexes of the de Leva table (one table for the package: :data:`bsv.types.SEXES`).
SEXES = TYPES_SEXES

Density = float | Mapping[str, float] | None


@dataclass
class Endpoint:
    """One end of a segment: a point (m, world frame), its de Leva landmark name and how it was found
    ("joint": a shared boundary's centroid; "extent": the segment's farthest point along its axis)."""

    name: str
    point: np.ndarray
    how: str


@dataclass
class SegmentBSIP:
    """Inertial parameters of one segment (SI units, world frame: Y up, X the subject's left, Z forward)."""

    name: str
    density_kg_m3: float
    volume_l: float
    mass_kg: float
    com: np.ndarray                 # (3,) m
    inertia_kg_m2: np.ndarray       # (3, 3) about the centre of mass, world axes
    origin: Endpoint                # de Leva's first endpoint (the proximal joint, or VERT / HEEL)
    other: Endpoint                 # de Leva's second endpoint
    axes: np.ndarray                # (3, 3) rows: sagittal, transverse, longitudinal unit axes
    mass_pct: float = float("nan")  # % of the body-mass estimate (see BSIP.mass_basis)
    reference: DeLeva | None = None

    @property
    def length_m(self) -> float:
        """Distance between the two endpoints (m)."""
        return float(np.linalg.norm(self.other.point - self.origin.point))

    @property
    def com_pct(self) -> float:
        """Centre of mass along the segment, % of the length from ``origin``."""
        d = self.other.point - self.origin.point
        return float(100.0 * (self.com - self.origin.point) @ d / (d @ d))

    def radii_of_gyration_pct(self) -> tuple[float, float, float]:
        """Radii of gyration about the centre of mass, % of the length: sagittal (antero-posterior axis),
        transverse (medio-lateral axis), longitudinal (along the segment)."""
        k = [float(np.sqrt(max(a @ self.inertia_kg_m2 @ a, 0.0) / self.mass_kg)) for a in self.axes]
        L = self.length_m
        return (100.0 * k[0] / L, 100.0 * k[1] / L, 100.0 * k[2] / L)

    def principal_moments_kg_m2(self) -> np.ndarray:
        """Principal moments of inertia (kg m^2, ascending)."""
        return np.linalg.eigvalsh(self.inertia_kg_m2)


@dataclass
class BSIP:
    """Body-segment inertial parameters of a subject: segments, joint centres and the body-mass estimate.

    ``mass_basis`` says what ``mass_pct`` is a percentage of: the sum of the measured segments, which is
    the whole body only when head, hands and feet were measured; the de Leva values beside ours are then
    renormalised to the same segments so that the comparison is like for like."""

    segments: dict[str, SegmentBSIP]
    joints: dict[str, np.ndarray]
    body_mass_kg: float
    com: np.ndarray
    sex: str
    density_source: str
    mass_basis: str
    notes: list[str] = field(default_factory=list)
    #: The labelled mesh measured (for the figure).
    mesh: Mesh | None = None

    def table(self) -> str:
        """A readable table: one row per segment, ours beside de Leva's (in brackets)."""
        head = (f"{'segment':<12} {'mass kg':>8} {'mass %':>14} {'length mm':>9} {'COM %':>14} "
                f"{'rg sag %':>13} {'rg trans %':>13} {'rg long %':>13}")
        lines = [head, "-" * len(head)]
        for s in self.segments.values():
            r = s.reference
            rg = s.radii_of_gyration_pct()
            ref = (r.mass_pct, r.com_pct, r.rg_sagittal_pct, r.rg_transverse_pct, r.rg_longitudinal_pct) if r else (
                float("nan"),) * 5

            def pair(x: float, y: float) -> str:
                return f"{x:5.1f} ({y:5.1f})"
            lines.append(f"{s.name:<12} {s.mass_kg:8.2f} {pair(s.mass_pct, ref[0]):>14} {s.length_m * 1e3:9.0f} "
                         f"{pair(s.com_pct, ref[1]):>14} {pair(rg[0], ref[2]):>13} {pair(rg[1], ref[3]):>13} "
                         f"{pair(rg[2], ref[4]):>13}")
        lines.append(f"body-mass estimate {self.body_mass_kg:.2f} kg ({self.mass_basis}); "
                     f"densities: {self.density_source}; (de Leva 1996, {self.sex})")
        return "\n".join(lines)

    def _repr_html_(self) -> str:
        """A notebook table: ours beside de Leva's (in brackets)."""
        import html

        head = ("segment", "mass kg", "mass %", "length mm", "COM %", "rg sag %", "rg trans %", "rg long %")
        rows = []
        for s in self.segments.values():
            r = s.reference
            rg = s.radii_of_gyration_pct()
            ref = (r.mass_pct, r.com_pct, r.rg_sagittal_pct, r.rg_transverse_pct, r.rg_longitudinal_pct) if r else (
                float("nan"),) * 5
            ours = (s.mass_pct, s.com_pct, *rg)
            cells = [html.escape(s.name), f"{s.mass_kg:.2f}", f"{ours[0]:.1f} ({ref[0]:.1f})", f"{s.length_m * 1e3:.0f}",
                     *(f"{x:.1f} ({y:.1f})" for x, y in zip(ours[1:], ref[1:], strict=True))]
            rows.append("<tr>" + "".join(f"<td>{c}</td>" for c in cells) + "</tr>")
        caption = html.escape(f"body-mass estimate {self.body_mass_kg:.2f} kg ({self.mass_basis}); "
                              f"in brackets de Leva (1996), {self.sex}; densities: {self.density_source}")
        return ("<table><caption>" + caption + "</caption><tr>" + "".join(f"<th>{h}</th>" for h in head) + "</tr>"
                + "".join(rows) + "</table>")

    def __repr__(self) -> str:
        return (f"BSIP({len(self.segments)} segments, {len(self.joints)} joints, "
                f"body mass {self.body_mass_kg:.2f} kg, sex={self.sex!r})")

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-ready values (SI units; the layout of ``bsip.json``)."""
        segs = {}
        for s in self.segments.values():
            rg = s.radii_of_gyration_pct()
            segs[s.name] = {
                "density_kg_m3": s.density_kg_m3, "volume_l": s.volume_l, "mass_kg": s.mass_kg,
                "mass_pct": s.mass_pct, "com_m": s.com.tolist(), "inertia_kg_m2": s.inertia_kg_m2.tolist(),
                "principal_moments_kg_m2": s.principal_moments_kg_m2().tolist(),
                "origin": {"landmark": s.origin.name, "how": s.origin.how, "point_m": s.origin.point.tolist()},
                "other": {"landmark": s.other.name, "how": s.other.how, "point_m": s.other.point.tolist()},
                "length_m": s.length_m, "com_pct": s.com_pct,
                "rg_sagittal_pct": rg[0], "rg_transverse_pct": rg[1], "rg_longitudinal_pct": rg[2],
                "de_leva": None if s.reference is None else vars(s.reference).copy(),
            }
        return {
            "units": {"length": "m", "mass": "kg", "inertia": "kg m^2", "volume": "L"},
            "frame": "world: Y up, X the subject's left, Z forward; inertia about each segment's centre of mass",
            "body_mass_kg": self.body_mass_kg, "mass_basis": self.mass_basis, "com_m": self.com.tolist(),
            "sex": self.sex, "density_source": self.density_source, "regression_source": DE_LEVA_SOURCE,
            "segments": segs, "joints_m": {k: v.tolist() for k, v in self.joints.items()}, "notes": list(self.notes),
        }


def densities(density: Density, segments: list[str]) -> tuple[dict[str, float], str]:
    """The density (kg/m^3) of each segment and its source: ``None`` the Dempster/Winter table, a number
    for every segment, or a mapping by segment name (``thigh_l``) or kind (``thigh``) over the table."""
    if density is None or isinstance(density, Mapping):
        given = dict(density or {})
        known = (set(SEGMENT_IDS) - {"unlabelled"}) | set(DEMPSTER_DENSITY_KG_M3)
        unknown = sorted(set(given) - known)
        if unknown:
            raise BsipError(f"density: unknown segment name(s) {unknown}; use segment names (torso, "
                            f"thigh_l, ...) or kinds ({', '.join(DEMPSTER_DENSITY_KG_M3)})")
        out = {s: float(given.get(s, given.get(kind(s), DEMPSTER_DENSITY_KG_M3[kind(s)]))) for s in segments}
        source = DENSITY_SOURCE + (f", overridden for {sorted(given)}" if given else "")
    else:
        out = {s: float(density) for s in segments}
        source = f"one density for every segment ({float(density):g} kg/m^3)"
    for s, d in out.items():
        if not np.isfinite(d) or not 200.0 <= d <= 3000.0:
            raise BsipError(f"density of {s} is {d} kg/m^3: give a body density in kg/m^3 (about 900-1200), "
                            "not g/cm^3 or kg/L")
    return out, source


def _unit(v: np.ndarray) -> np.ndarray:
    n = float(np.linalg.norm(v))
    return v / n if n > 0 else v


def _joints(interfaces: list[dict[str, Any]]) -> dict[str, np.ndarray]:
    """Joint centres: per joint, the centroid of the largest boundary piece its two segments share."""
    best: dict[frozenset[str], dict[str, Any]] = {}
    for i in interfaces:
        key = frozenset((i["a"], i["b"]))
        if key not in best or i["vertices"] > best[key]["vertices"]:
            best[key] = i
    out = {}
    for name, (a, b) in JOINTS.items():
        piece = best.get(frozenset((a, b)))
        if piece is not None:
            out[name] = np.asarray(piece["centroid"], dtype=float)
    return out


def _extent(points: np.ndarray, start: np.ndarray, toward: np.ndarray) -> np.ndarray:
    """The farthest point of ``points`` from ``start`` along the direction to ``toward``, on that line."""
    a = _unit(toward - start)
    return start + a * float(((points - start) @ a).max())


def _endpoints(name: str, com: np.ndarray, pts: np.ndarray, inertia: np.ndarray,
               joints: dict[str, np.ndarray]) -> tuple[Endpoint, Endpoint]:
    k = kind(name)
    ref = DE_LEVA["male"][k]
    if k in ("upper_arm", "forearm", "hand", "thigh", "shin"):  # proximal joint -> distal joint (or extent)
        p = next((joints.get(jn) for jn, (_, child) in JOINTS.items() if child == name), None)
        d = next((joints.get(jn) for jn, (parent, _) in JOINTS.items() if parent == name), None)
        if p is None and d is None:
            raise BsipError(f"{name}: no boundary with a neighbouring segment; its length cannot be measured")
        if p is None:
            assert d is not None
            return Endpoint(ref.origin, _extent(pts, d, com), "extent"), Endpoint(ref.other, d, "joint")
        if d is None:
            return Endpoint(ref.origin, p, "joint"), Endpoint(ref.other, _extent(pts, p, com), "extent")
        return Endpoint(ref.origin, p, "joint"), Endpoint(ref.other, d, "joint")
    if k == "head":
        neck = joints.get("neck")
        if neck is None:
            raise BsipError("head: no boundary with the torso; its length cannot be measured")
        return Endpoint(ref.origin, _extent(pts, neck, com), "extent"), Endpoint(ref.other, neck, "joint")
    if k == "torso":
        hips = [joints[h] for h in ("hip_l", "hip_r") if h in joints]
        neck = joints.get("neck")
        midh = np.mean(hips, axis=0) if len(hips) == 2 else None
        if midh is None and neck is None:
            raise BsipError("torso: neither the neck nor both hips were found; its length cannot be measured")
        top = neck if neck is not None else _extent(pts, midh, com)  # type: ignore[arg-type]
        bottom = midh if midh is not None else _extent(pts, top, com)
        return (Endpoint(ref.origin, top, "joint" if neck is not None else "extent"),
                Endpoint(ref.other, bottom, "joint" if midh is not None else "extent"))
    # foot: heel to toe along the long principal axis, pointing forward (+Z)
    w, v = np.linalg.eigh(inertia)
    a = v[:, int(np.argmin(w))]
    a = a if a[2] >= 0 else -a
    t = (pts - com) @ a
    return (Endpoint(ref.origin, com + a * float(t.min()), "extent"),
            Endpoint(ref.other, com + a * float(t.max()), "extent"))


def _axes(origin: np.ndarray, other: np.ndarray) -> np.ndarray:
    """Rows: sagittal (antero-posterior), transverse (medio-lateral), longitudinal unit axes."""
    lon = _unit(other - origin)
    x = np.array([1.0, 0.0, 0.0])
    if abs(lon @ x) > 0.95:
        x = np.array([0.0, 0.0, 1.0])
    trans = _unit(x - (x @ lon) * lon)
    sag = np.cross(trans, lon)
    return np.array([sag, trans, lon])


def _mesh_of(obj: Any) -> Mesh:
    """The labelled mesh of a Mesh, a Registration or process result (``.mesh``), a synthetic Body
    (``.mesh()``) or a trimesh/Open3D mesh."""
    if isinstance(obj, Mesh):
        return obj
    m = getattr(obj, "mesh", None)
    if callable(m):
        m = m()
    return m if isinstance(m, Mesh) else as_mesh(obj)


def compute(obj: Any, density: Density = None, *, sex: str = "male", islands: bool = True) -> BSIP:
    """The body-segment inertial parameters of a labelled closed mesh (a :class:`bsv.Mesh`, a
    :class:`bsv.Registration` (its fitted mesh), a trimesh/Open3D mesh with labels): see :func:`bsv.bsip`."""
    if sex not in SEXES:
        raise BsipError(f"sex must be one of {SEXES} (de Leva's table), got {sex!r}")
    mesh = _mesh_of(obj)
    if mesh.vertex_labels is None and mesh.face_labels is None:
        raise BsipError("the mesh has no segment labels (neither vertex nor face labels): segments cannot be found")
    mp = _bsv.mass_properties(mesh.vertices, mesh.faces, mesh.vertex_labels, mesh.face_labels, islands=islands)
    names = list(mp["segments"])
    if not names:
        raise BsipError("the mesh has no labelled segment")
    dens, source = densities(density, names)
    joints = _joints(mp["interfaces"])
    vl = mesh.vertex_labels if mesh.vertex_labels is not None else _bsv.vertex_labels_from_faces(
        len(mesh.vertices), mesh.faces, mesh.face_labels)
    notes = list(mp["notes"])
    segs: dict[str, SegmentBSIP] = {}
    for name in names:
        p = mp["segments"][name]
        if p["volume_m3"] <= 0:
            raise BsipError(f"segment {name} has a non-positive volume ({p['volume_m3'] * 1e3:.4f} L): its labels "
                            "are scattered; merge small islands (islands=True) or fix the labels")
        rho = dens[name]
        com = np.asarray(p["centroid"], dtype=float)
        inertia = np.asarray(p["inertia_m5"], dtype=float) * rho
        pts = np.asarray(mesh.vertices)[np.asarray(vl) == SEGMENT_IDS[name]]
        if len(pts) == 0:
            pts = com[None, :]
        origin, other = _endpoints(name, com, pts, inertia, joints)
        segs[name] = SegmentBSIP(name, rho, p["volume_m3"] * 1e3, p["volume_m3"] * rho, com, inertia, origin, other,
                                 _axes(origin.point, other.point))
    total = sum(s.mass_kg for s in segs.values())
    com_all = sum(s.mass_kg * s.com for s in segs.values()) / total
    kinds = {kind(n) for n in segs}
    all_kinds = set(DEMPSTER_DENSITY_KG_M3)
    table = DE_LEVA[sex]
    ref_total = sum(table[kind(n)].mass_pct for n in segs)
    for s in segs.values():
        s.mass_pct = 100.0 * s.mass_kg / total
        r = table[kind(s.name)]
        s.reference = DeLeva(r.origin, r.other, 100.0 * r.mass_pct / ref_total, r.com_pct, r.rg_sagittal_pct,
                             r.rg_transverse_pct, r.rg_longitudinal_pct)
    if kinds == all_kinds:
        basis = "the whole body (every segment measured)"
    else:
        missing = sorted(all_kinds - kinds)
        basis = f"the measured segments only (no {', '.join(missing)}); de Leva's mass % renormalised to them"
        notes.append(f"mass % is relative to the measured segments (no {', '.join(missing)}), and so are de Leva's")
    extents = [f"{s.name} {e.name}" for s in segs.values() for e in (s.origin, s.other) if e.how == "extent"]
    if extents:
        notes.append("endpoints taken as the segment's extent (no neighbouring segment): " + ", ".join(extents))
    return BSIP(segs, joints, float(total), np.asarray(com_all), sex, source, basis, notes, mesh)

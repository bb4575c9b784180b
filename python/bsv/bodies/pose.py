"""A-pose of the MakeHuman rig by dual-quaternion skinning (numpy).

Each posed bone gets a world-space rotation; a bone without one inherits its parent's. A bone's
transform is x -> R_b (x - h_b) + T_parent(h_b) (h_b its rest head), so joints stay connected.
Arms: abducted in the frontal plane to ``arm_down_deg`` below horizontal, forearm straightened onto the
upper-arm axis, twisted about it so that the palm faces forward, or turned ``palm_in_deg`` in from there
towards the body (the twist spread over lowerarm01, lowerarm02 and the wrist), then flexed forward at the
elbow by ``elbow_deg``. Legs: the hip->ankle axis abducted ``hip_abduction_deg`` from the vertical in the
frontal plane; feet kept level. Last, the whole body may be turned about the vertical through the midpoint
of the hip joints (``turn_deg``): a subject not squarely facing the front camera.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from ..errors import PoseError
from .asset import Asset, load_asset


@dataclass(frozen=True)
class Pose:
    """A-pose angles in degrees, per side (l = subject's left, +X)."""

    arm_down_l: float = 40.0
    arm_down_r: float = 40.0
    elbow_l: float = 10.0
    elbow_r: float = 10.0
    hip_abduction_l: float = 4.0
    hip_abduction_r: float = 4.0
    #: How far each palm is turned in from facing forward, about the forearm (degrees): 0 palms forward (the
    #: thumb on the arm's outer side), 90 palms facing the body (the thumb forward: MakeHuman's rest hand
    #: with no twist lies about there), 180 palms backward.
    palm_in_l: float = 0.0
    palm_in_r: float = 0.0
    #: The whole body turned about the vertical through the midpoint of the hip joints (degrees; + turns the
    #: subject's left backwards, seen from above counterclockwise): 0 faces the front camera squarely.
    turn_deg: float = 0.0

    @staticmethod
    def symmetric(arm_down: float = 40.0, elbow: float = 10.0, hip_abduction: float = 4.0) -> Pose:
        """The same angles on both sides."""
        return Pose(arm_down, arm_down, elbow, elbow, hip_abduction, hip_abduction)

    #: The plausible range (degrees) of each angle.
    RANGES: ClassVar[dict[str, tuple[float, float]]] = {
        "arm_down_l": (-10, 85), "arm_down_r": (-10, 85), "elbow_l": (0, 120), "elbow_r": (0, 120),
        "hip_abduction_l": (-5, 30), "hip_abduction_r": (-5, 30), "palm_in_l": (-30, 180),
        "palm_in_r": (-30, 180), "turn_deg": (-45, 45)}

    def validate(self) -> None:
        """Raise PoseError if an angle is implausible (outside :attr:`RANGES`)."""
        for name, (lo, hi) in self.RANGES.items():
            v = getattr(self, name)
            if not np.isfinite(v) or not lo <= v <= hi:
                raise PoseError(f"pose {name}={v} deg: must lie in [{lo}, {hi}]")


def _rot(axis: np.ndarray, ang: float) -> np.ndarray:
    """Rotation matrix about a unit axis by ang radians (Rodrigues)."""
    axis = axis / np.linalg.norm(axis)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(ang) * k + (1 - np.cos(ang)) * (k @ k)


def _align(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Minimal rotation taking direction a onto direction b."""
    a = a / np.linalg.norm(a)
    b = b / np.linalg.norm(b)
    ax = np.cross(a, b)
    s = np.linalg.norm(ax)
    if s < 1e-12:
        return np.eye(3)
    return _rot(ax, np.arctan2(s, float(a @ b)))


def _children(parent: np.ndarray) -> list[int]:
    """Bones in an order where each parent comes before its children."""
    order, seen = [], set()

    def visit(b: int) -> None:
        if b in seen:
            return
        if parent[b] >= 0:
            visit(int(parent[b]))
        seen.add(b)
        order.append(b)

    for b in range(len(parent)):
        visit(b)
    return order


def bone_transforms(joints: np.ndarray, pose: Pose, asset: Asset | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Global rotations (B, 3, 3) and translations (B, 3) of every bone for a pose: x' = R x + t."""
    a = asset or load_asset()
    pose.validate()
    head = joints[:, 0, :]
    nb = len(a.bone_names)
    rot: dict[int, np.ndarray] = {}
    z = np.array([0.0, 0.0, 1.0])
    b = a.bone
    for side, sx in (("L", 1.0), ("R", -1.0)):
        # arms
        sh, el, wr = head[b(f"upperarm01.{side}")], head[b(f"lowerarm01.{side}")], head[b(f"wrist.{side}")]
        ua = el - sh
        a0 = np.arctan2(-ua[1], sx * ua[0])
        want = np.radians(pose.arm_down_l if side == "L" else pose.arm_down_r)
        r_ua = _rot(z, sx * (a0 - want))
        for n in ("upperarm01", "upperarm02"):
            rot[b(f"{n}.{side}")] = r_ua
        u = r_ua @ ua
        u /= np.linalg.norm(u)
        r_al = _align(r_ua @ (wr - el), u) @ r_ua
        thumb = head[b(f"finger1-2.{side}")] - el
        p = r_al @ thumb
        p -= (p @ u) * u
        t = np.array([sx * np.sin(want), np.cos(want), 0.0])  # the thumb's way with the palm forward
        t -= (t @ u) * u
        turn = np.radians(pose.palm_in_l if side == "L" else pose.palm_in_r)
        t = np.cos(turn) * t + np.sin(turn) * np.array([0.0, 0.0, np.linalg.norm(t)])  # turned in: thumb forward
        phi = float(np.arctan2(u @ np.cross(p, t), p @ t))
        flex = np.radians(pose.elbow_l if side == "L" else pose.elbow_r)
        r_fl = _rot(np.cross(u, z), flex)
        for n, frac in (("lowerarm01", 1 / 3), ("lowerarm02", 2 / 3), ("wrist", 1.0)):
            rot[b(f"{n}.{side}")] = r_fl @ _rot(u, frac * phi) @ r_al
        # legs
        hip, ank = head[b(f"upperleg01.{side}")], head[b(f"foot.{side}")]
        leg = ank - hip
        th0 = np.arctan2(sx * leg[0], -leg[1])
        want_h = np.radians(pose.hip_abduction_l if side == "L" else pose.hip_abduction_r)
        r_leg = _rot(z, sx * (want_h - th0))
        for n in ("upperleg01", "upperleg02"):
            rot[b(f"{n}.{side}")] = r_leg
        rot[b(f"foot.{side}")] = np.eye(3)
    R = np.zeros((nb, 3, 3))
    T = np.zeros((nb, 3))
    for i in _children(a.bone_parent):
        par = int(a.bone_parent[i])
        pr, pt = (R[par], T[par]) if par >= 0 else (np.eye(3), np.zeros(3))
        R[i] = rot.get(i, pr)
        ph = pr @ head[i] + pt  # where the parent's transform takes this bone's rest head
        T[i] = ph - R[i] @ head[i]
    if pose.turn_deg:
        turn = _rot(np.array([0.0, 1.0, 0.0]), np.radians(pose.turn_deg))
        centre = (head[b("upperleg01.L")] + head[b("upperleg01.R")]) / 2  # the hips do not move in the A-pose
        R = turn @ R
        T = (T - centre) @ turn.T + centre
    return R, T


def _quat(R: np.ndarray) -> np.ndarray:
    """Unit quaternions (w, x, y, z) of rotation matrices (B, 3, 3)."""
    q = np.zeros((len(R), 4))
    for i, m in enumerate(R):
        tr = np.trace(m)
        if tr > 0:
            s = np.sqrt(tr + 1.0) * 2
            q[i] = [0.25 * s, (m[2, 1] - m[1, 2]) / s, (m[0, 2] - m[2, 0]) / s, (m[1, 0] - m[0, 1]) / s]
        else:
            k = int(np.argmax(np.diag(m)))
            if k == 0:
                s = np.sqrt(1.0 + m[0, 0] - m[1, 1] - m[2, 2]) * 2
                q[i] = [(m[2, 1] - m[1, 2]) / s, 0.25 * s, (m[0, 1] + m[1, 0]) / s, (m[0, 2] + m[2, 0]) / s]
            elif k == 1:
                s = np.sqrt(1.0 + m[1, 1] - m[0, 0] - m[2, 2]) * 2
                q[i] = [(m[0, 2] - m[2, 0]) / s, (m[0, 1] + m[1, 0]) / s, 0.25 * s, (m[1, 2] + m[2, 1]) / s]
            else:
                s = np.sqrt(1.0 + m[2, 2] - m[0, 0] - m[1, 1]) * 2
                q[i] = [(m[1, 0] - m[0, 1]) / s, (m[0, 2] + m[2, 0]) / s, (m[1, 2] + m[2, 1]) / s, 0.25 * s]
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def _qmul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product of quaternion arrays (..., 4)."""
    w1, x1, y1, z1 = np.moveaxis(a, -1, 0)
    w2, x2, y2, z2 = np.moveaxis(b, -1, 0)
    return np.stack([w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2, w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
                     w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2, w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2], -1)


def dq_skin(vertices: np.ndarray, R: np.ndarray, T: np.ndarray, asset: Asset | None = None) -> np.ndarray:
    """Dual-quaternion skinning of rest vertices with per-bone rigid transforms (R, T)."""
    a = asset or load_asset()
    n = len(vertices)
    q = _quat(R)
    tq = np.concatenate([np.zeros((len(T), 1)), T], axis=1)
    d = 0.5 * _qmul(tq, q)
    sv, sb, sw = a.skin_vertex, a.skin_bone, a.skin_weight
    # sign of each entry relative to the vertex's heaviest bone (antipodality)
    heaviest = np.zeros(n, dtype=np.int64)
    best = np.full(n, -1.0)
    order = np.argsort(sw, kind="stable")
    heaviest[sv[order]] = sb[order]
    best[sv[order]] = sw[order]
    sign = np.sign(np.einsum("ij,ij->i", q[sb], q[heaviest[sv]]))
    sign[sign == 0] = 1.0
    w = sw * sign
    qb = np.stack([np.bincount(sv, weights=w * q[sb, k], minlength=n) for k in range(4)], 1)
    db = np.stack([np.bincount(sv, weights=w * d[sb, k], minlength=n) for k in range(4)], 1)
    norm = np.linalg.norm(qb, axis=1, keepdims=True)
    qb = qb / norm  # (np.bincount is typed as returning integers; with weights it gives floats)
    db = db / norm
    w0, xyz = qb[:, :1], qb[:, 1:]
    v = vertices
    # rotate: v + 2 xyz x (xyz x v + w v)
    rv = v + 2.0 * np.cross(xyz, np.cross(xyz, v) + w0 * v)
    # translation 2 * d * conj(q)
    conj = qb * np.array([1.0, -1.0, -1.0, -1.0])
    tr = 2.0 * _qmul(db, conj)[:, 1:]
    return rv + tr


def pose_vertices(vertices: np.ndarray, joints: np.ndarray, pose: Pose,
                  asset: Asset | None = None) -> np.ndarray:
    """Posed vertices of a shaped rest body (dual-quaternion skinning)."""
    R, T = bone_transforms(joints, pose, asset)
    return dq_skin(vertices, R, T, asset)

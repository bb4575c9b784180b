"""The pose check of a processed capture, from the landmarks the segmentation wrote
(``segmentation/<camera>/landmarks.json``): every landmark the segmentation requires visible enough
(:data:`bsv.frontend.segment.REQUIRED_LANDMARKS`, ``SegmentParams.min_visibility``) and the A-pose of
the front view (each arm's abduction, shoulder -> wrist against the body's vertical axis, within
:data:`A_POSE_DEG`; the rig's cohort uses 25-50 degrees)."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

#: Accepted arm abduction (degrees) of an A-pose.
A_POSE_DEG = (15.0, 60.0)


def _angle(shoulder: list[float], wrist: list[float], hip_mid: list[float], shoulder_mid: list[float]) -> float:
    """Angle (deg) between shoulder -> wrist and the trunk's downward axis (shoulder centre -> hip centre)."""
    ax, ay = hip_mid[0] - shoulder_mid[0], hip_mid[1] - shoulder_mid[1]
    bx, by = wrist[0] - shoulder[0], wrist[1] - shoulder[1]
    na, nb = math.hypot(ax, ay), math.hypot(bx, by)
    if na == 0 or nb == 0:
        return math.nan
    c = max(-1.0, min(1.0, (ax * bx + ay * by) / (na * nb)))
    return math.degrees(math.acos(c))


def pose_check(result_dir: Path) -> dict[str, Any] | None:
    """Per camera: the lowest visibility of a required landmark and those under the threshold; for the
    front camera, the left and right arm abduction and whether it is an A-pose. None without landmarks."""
    from ..frontend.segment import REQUIRED_LANDMARKS, SegmentParams

    threshold = SegmentParams().min_visibility
    out: dict[str, Any] = {"threshold": threshold, "cameras": {}}
    for cam in ("front", "back"):
        path = result_dir / "segmentation" / cam / "landmarks.json"
        if not path.is_file():
            continue
        try:
            lm = json.loads(path.read_text()).get("landmarks_px", {})
        except (OSError, json.JSONDecodeError):
            continue
        vis = {n: float(lm[n][2]) for n in REQUIRED_LANDMARKS if n in lm}
        low = sorted(n for n, v in vis.items() if not v >= threshold)
        info: dict[str, Any] = {"min_visibility": min(vis.values()) if vis else math.nan, "low": low}
        if cam == "front" and all(n in lm for n in REQUIRED_LANDMARKS):
            sm = [(lm["left_shoulder"][i] + lm["right_shoulder"][i]) / 2 for i in (0, 1)]
            hm = [(lm["left_hip"][i] + lm["right_hip"][i]) / 2 for i in (0, 1)]
            arms = {side: _angle(lm[f"{side}_shoulder"], lm[f"{side}_wrist"], hm, sm) for side in ("left", "right")}
            info["abduction_deg"] = arms
            info["a_pose"] = all(A_POSE_DEG[0] <= a <= A_POSE_DEG[1] for a in arms.values())
        out["cameras"][cam] = info
    return out if out["cameras"] else None


__all__ = ["A_POSE_DEG", "pose_check"]

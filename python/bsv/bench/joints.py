"""Joint-centre accuracy of the camera path: the 3-D joint centres lifted from MediaPipe's landmarks of
both views (:func:`bsv.frontend.landmarks.joint_centres`) against the rig's true joint centres of the
synthetic body (:func:`bsv.bodies.joints.rig_joints`, the posed heads of the MakeHuman bones).

Errors are signed vectors in millimetres in the TRUE body frame (:func:`bsv.frontend.landmarks.body_frame`
of the true joints): lateral (toward the joint's own side, so left and right pool), up (hips to
shoulders), forward (the subject's facing direction). The tables give per joint kind (left and right
pooled) the median and 95th percentile of the 3-D distance, the median signed components and the worst
subject.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import BenchError
from .common import ORACLE_JOINTS_PARAM, Run
from .reference import ordered_conditions

#: Key of :attr:`Run.info` holding a run's joint errors ({joint: [lateral, up, forward] mm}).
INFO_KEY = "joint_errors_mm"
#: Key of :attr:`Run.info` holding the camera path's landmark warnings of the run's capture (one sentence per
#: landmark taken from the other view, the hand model or accepted at the lower threshold, as ``bsv process``
#: records them in its result).
WARNINGS_KEY = "landmark_warnings"
#: Joint kinds in table order.
KINDS: tuple[str, ...] = ("shoulder", "elbow", "wrist", "hip", "knee", "ankle")
#: The target of the landmarks issue: median 3-D error at most this (mm) over the six kinds.
TARGET_MEDIAN_MM = 15.0


def camera_segmentations(capture_dir: str | Path, correct: bool = True,
                         sex: str | None = None) -> tuple[dict[str, Any], dict[str, Any]]:
    """The camera path's segmentations of both views of a (virtual) capture folder, made together
    (:func:`bsv.frontend.landmarks.segment_views`, the cameras' calibrated ``camera_to_world`` of
    camera.json), and their joint centres; ``correct``: with the learned joint offsets, the knee lines moved by
    the body's proportions (:mod:`bsv.frontend.kneelines`) and the elbow lines by the elbows' flexion
    (:mod:`bsv.frontend.elbowlines`), as ``bsv process`` has them; ``sex``: the subject's
    sex as a user gives it (None: read from the capture, :mod:`bsv.frontend.sex`)."""
    from ..frontend.capture import read_capture
    from ..frontend.landmarks import Camera, joint_centres, segment_views
    from ..frontend.recut import lines_after_joints
    from ..frontend.segment import VIEWS

    d = Path(capture_dir)
    data = {v: read_capture(d / v) for v in VIEWS}
    cams = {v: Camera.from_json(data[v]["intrinsics"], data[v]["meta"]["camera_to_world"]) for v in VIEWS}
    from ..frontend.sex import SEX_SCORES

    params: dict[str, Any] = {} if sex is None else {"sex_score": SEX_SCORES[sex]}
    segs = segment_views({v: {"colour": data[v]["colour"], "depth_m": data[v]["depth_m"]} for v in VIEWS}, cams, **params)
    joints = joint_centres(segs, {v: data[v]["depth_m"] for v in VIEWS}, cams, correct=correct)
    if correct:  # as bsv process: the knee lines moved by the body's proportions, the elbow lines by the flexion
        segs = lines_after_joints(segs, joints, cams, **params)
    return segs, joints


def capture_views_geometry(capture_dir: str | Path) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
    """The depth images (metres) and calibrated cameras (camera.json's ``camera_to_world``) of both views of a
    (virtual) capture folder, as :func:`camera_segmentations` reads them."""
    from ..frontend.capture import read_capture
    from ..frontend.landmarks import Camera
    from ..frontend.segment import VIEWS

    d = Path(capture_dir)
    data = {v: read_capture(d / v) for v in VIEWS}
    return ({v: data[v]["depth_m"] for v in VIEWS},
            {v: Camera.from_json(data[v]["intrinsics"], data[v]["meta"]["camera_to_world"]) for v in VIEWS})


def capture_hip_loops(capture_dir: str | Path, segs: Mapping[str, Any], joints: Mapping[str, Any]) -> dict[str, Any]:
    """The thighs' loop targets of the camera path (:func:`bsv.frontend.groin.hip_loop_targets`, as ``bsv
    process`` makes them) of a capture folder segmented by :func:`camera_segmentations`."""
    from ..frontend.groin import hip_loop_targets

    depths, cameras = capture_views_geometry(capture_dir)
    return hip_loop_targets(segs, depths, cameras, joints)


def subject_segmentations(subject: Any, condition: str, scan_seed: int, correct: bool = True,
                          sex: str | None = None,
                          look: Mapping[str, Any] | None = None) -> tuple[dict[str, Any], dict[str, Any]]:
    """:func:`camera_segmentations` of a cohort ``subject`` (:func:`bsv.bodies.subject`) captured by the virtual
    rig in a clinic room (``condition``, ``scan_seed``, the ``look`` of :func:`bsv.scan`) into a temporary folder,
    removed afterwards."""
    import tempfile

    from .. import scan

    with tempfile.TemporaryDirectory(prefix="bsv-capture-") as tmp:
        scan(subject.body.mesh(), condition, scan_seed, images=tmp, overwrite=True, room=True, look=look)
        return camera_segmentations(tmp, correct=correct, sex=sex)


def joint_errors(estimated: Mapping[str, Any], truth: Mapping[str, np.ndarray]) -> dict[str, list[float]]:
    """{joint: [lateral, up, forward] mm} of the estimated joint centres (JointCentre or arrays, metres)
    against the true ones, in the true body frame; joints missing from either side are left out."""
    from ..frontend.landmarks import body_frame

    frame = body_frame(truth)
    if frame is None:
        return {}
    out = {}
    for name, est in estimated.items():
        if name not in truth:
            continue
        xyz = np.asarray(getattr(est, "xyz", est), dtype=np.float64)
        e = frame @ (xyz - np.asarray(truth[name], dtype=np.float64)) * 1000.0
        if name.endswith("_r"):
            e[0] = -e[0]
        out[name] = [round(float(c), 2) for c in e]
    return out


def oracle_joint_kinds(text: object) -> tuple[str, ...]:
    """The joint kinds of an ``oracle_joints`` value (``elbow+knee``, ``elbow,knee``, ``all``; empty or
    ``none``: none); :class:`bsv.errors.BenchError` naming the parameter and the known kinds otherwise."""
    value = str(text).strip()
    if value in ("", "none"):
        return ()
    if value == "all":
        return KINDS
    kinds = tuple(k.strip() for k in value.replace("+", ",").split(",") if k.strip())
    bad = [k for k in kinds if k not in KINDS]
    if bad or not kinds:
        raise BenchError(f"--param {ORACLE_JOINTS_PARAM}={value}: use all, none or joint kinds joined by + "
                         f"(of {', '.join(KINDS)}); unknown: {', '.join(bad) or value}")
    return kinds


def with_oracle_joints(joints: Mapping[str, Any], truth: Mapping[str, np.ndarray] | None,
                       kinds: Sequence[str]) -> dict[str, Any]:
    """``joints`` (name -> :class:`bsv.frontend.landmarks.JointCentre`) with the centres of ``kinds`` moved to
    the rig's true ones ``truth`` (metres; confidence kept, the source marked ``rig (oracle)``); a joint the
    camera path did not place stays missing. :class:`bsv.errors.BenchError` without the true joints (only the
    standard cohort knows them)."""
    if not kinds:
        return dict(joints)
    if truth is None:
        raise BenchError(f"--param {ORACLE_JOINTS_PARAM} needs the rig's true joint centres: the standard "
                         "cohort (--cohort standard) on the camera path (--segmentation camera)")
    out = {}
    for name, joint in joints.items():
        if name.rsplit("_", 1)[0] in kinds and name in truth:
            joint = dataclasses.replace(joint, xyz=np.asarray(truth[name], dtype=np.float64).copy(),
                                        source="rig (oracle)")
        out[name] = joint
    return out


def _collect(runs: Sequence[Run]) -> dict[tuple[str, str], list[tuple[str, np.ndarray]]]:
    """(condition, kind) -> [(subject, signed error vector)], one entry per subject, joint side and condition."""
    out: dict[tuple[str, str], list[tuple[str, np.ndarray]]] = {}
    seen = set()
    for r in runs:
        errs = (r.info or {}).get(INFO_KEY)
        if not errs or (r.subject, r.condition) in seen:
            continue  # one entry per scan, whatever the number of methods
        seen.add((r.subject, r.condition))
        for joint, e in errs.items():
            kind = joint.rsplit("_", 1)[0]
            out.setdefault((r.condition, kind), []).append((f"{r.subject} {joint[-1]}", np.asarray(e, dtype=float)))
    return out


def summarise(runs: Sequence[Run]) -> dict[str, dict[str, dict[str, Any]]]:
    """{condition: {kind or "all": {n, median_mm, p95_mm, signed_median_mm [lat, up, fwd], worst, worst_mm}}}."""
    table: dict[str, dict[str, dict[str, Any]]] = {}
    data = _collect(runs)
    for cond in ordered_conditions({c for c, _ in data}):
        rows: dict[str, dict[str, Any]] = {}
        everything: list[tuple[str, np.ndarray]] = []
        for kind in KINDS:
            items = data.get((cond, kind), [])
            everything += items
            if items:
                rows[kind] = _stats(items)
        if everything:
            rows["all"] = _stats(everything)
        table[cond] = rows
    return table


def _stats(items: Sequence[tuple[str, np.ndarray]]) -> dict[str, Any]:
    vecs = np.array([e for _, e in items])
    dist = np.linalg.norm(vecs, axis=1)
    w = int(np.argmax(dist))
    return {"n": len(items), "median_mm": float(np.median(dist)), "p95_mm": float(np.percentile(dist, 95)),
            "signed_median_mm": [float(c) for c in np.median(vecs, axis=0)], "worst": items[w][0],
            "worst_mm": float(dist[w])}


#: File name of the joint-error figure in a benchmark's output folder.
FIGURE = "joint_errors.png"


def joint_figure(runs: Sequence[Run], path: str | Path) -> Path | None:
    """Box plot of the 3-D joint-centre error (mm) per joint kind, one box per condition, with the target
    line; None (nothing written) when no run measured joints."""
    from .figures import kind_boxplot

    data = _collect(runs)
    conds = ordered_conditions({c for c, _ in data})
    if not conds:
        return None
    values = {c: [[float(np.linalg.norm(e)) for _, e in data.get((c, kind), [])] for kind in KINDS] for c in conds}
    return kind_boxplot(values, KINDS, path, ylabel="3-D joint-centre error (mm)",
                        title="Joint centres from the camera path against the rig",
                        line=(TARGET_MEDIAN_MM, f"target median {TARGET_MEDIAN_MM:.0f} mm"))


def degraded_captures(runs: Sequence[Run]) -> dict[str, dict[str, Any]]:
    """{condition: {captures, degraded (captures with a landmark warning), warnings, by_source {source: n}}}
    over the runs that recorded their landmark warnings (one entry per subject and condition)."""
    out: dict[str, dict[str, Any]] = {}
    seen = set()
    for r in runs:
        warns = (r.info or {}).get(WARNINGS_KEY)
        if warns is None or (r.subject, r.condition) in seen:
            continue
        seen.add((r.subject, r.condition))
        c = out.setdefault(r.condition, {"captures": 0, "degraded": 0, "warnings": 0, "by_source": {}})
        c["captures"] += 1
        c["degraded"] += bool(warns)
        c["warnings"] += len(warns)
        for w in warns:
            source = ("view stood in" if "no person found in it" in w
                      else "other view" if "other view" in w else "hand model" if "hand model" in w
                      else "lower threshold" if "lower threshold" in w
                      else "image brightened" if "brightness scaled" in w else "other")
            c["by_source"][source] = c["by_source"].get(source, 0) + 1
    return {k: out[k] for k in ordered_conditions(set(out))}


def joints_markdown(runs: Sequence[Run]) -> list[str]:
    """The report.md section of the joint-centre errors (empty when no run measured them)."""
    table = summarise(runs)
    if not table:
        return []
    md = ["## Joint centres: 3-D error against the rig (mm; camera path)", "",
          ("MediaPipe's landmarks of both views lifted to 3-D (bsv.frontend.landmarks) against the MakeHuman "
           "rig's joint centres (bsv.bodies.joints.rig_joints). Left and right pooled; signed median in the true "
           "body frame: lateral (+ = outward), up, forward. Target: median <= "
           f"{TARGET_MEDIAN_MM:.0f} mm. Figure: {FIGURE}."), ""]
    for cond, rows in table.items():
        md += [f"**{cond}**", "", "| joint | n | median | p95 | signed median lat / up / fwd | worst (subject side) |",
               "|---|---|---|---|---|---|"]
        for kind, s in rows.items():
            lat, up, fwd = s["signed_median_mm"]
            md.append(f"| {kind} | {s['n']} | {s['median_mm']:.1f} | {s['p95_mm']:.1f} | "
                      f"{lat:+.1f} / {up:+.1f} / {fwd:+.1f} | {s['worst_mm']:.1f} ({s['worst']}) |")
        md.append("")
    for cond, d in degraded_captures(runs).items():
        sources = ", ".join(f"{n} {k}" for k, n in sorted(d["by_source"].items()))
        md += [(f"Degraded landmarks, {cond}: {d['degraded']} of {d['captures']} captures kept with a landmark taken "
               f"from elsewhere, {d['warnings']} warnings in their results ({sources or 'none'}); no capture is "
               "thrown away for a landmark."), ""]
    return md


__all__ = [
    "FIGURE",
    "INFO_KEY",
    "KINDS",
    "ORACLE_JOINTS_PARAM",
    "TARGET_MEDIAN_MM",
    "WARNINGS_KEY",
    "camera_segmentations",
    "capture_hip_loops",
    "capture_views_geometry",
    "degraded_captures",
    "joint_errors",
    "joint_figure",
    "joints_markdown",
    "oracle_joint_kinds",
    "summarise",
    "with_oracle_joints",
]

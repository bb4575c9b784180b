"""``bench synth``: the synthetic cohort x the four error conditions of the virtual rig.

For each subject of :func:`bsv.bodies.cohort` (even indices women, odd men) and each condition, the
virtual two-camera rig scans the labelled body (:func:`bsv.scan`; the scan seed is the same for every
condition of a subject, so cali and l5ca share their calibration error and l515 and l5ca their depth
noise), the head, hand and foot points are dropped, the template is registered and its segment volumes
are compared with the body's ground truth. For cali and l5ca the error floor (:mod:`bsv.bench.floor`)
is measured from the capture's per-camera true and estimated extrinsics.

Room: the camera path (``--segmentation camera`` or ``--cloud lab``) renders the rig inside a clinic
room by default (floor, walls, ceiling, a subject with a skin tone, underwear and hair drawn from the
scan seed; :func:`bsv.scan` with ``room=True``), so that the person mask meets a floor and a wall as in
a real capture; ``room=False`` (``--no-room``) renders the body alone on grey. The oracle raw path
scans without a room. Every run records the percent of its registered cloud's points farther than 2 cm
and 10 cm from the true body surface (``cloud_far_2cm_pct``, ``cloud_far_10cm_pct``) and, on the lab
path, of the same cloud before the statistical outlier removal (``unfiltered_far_*``: what the person
mask let through).

Segmentation: ``oracle`` labels every point with the scanner's true face label (isolating registration
and volume error); ``camera`` runs the MediaPipe front-end on the rendered colour images and builds the cloud from the
depth images as a lab would (:mod:`bsv.bench.camera`; it needs ``bsv.frontend.segment`` and fails with
that message without it).
"""

from __future__ import annotations

import tempfile
import time
import traceback
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from typing import Any

from ..bodies.cohort import (
    ARM_DOWN_RANGE_DEG,
    ELBOW_RANGE_DEG,
    HIP_ABDUCTION_RANGE_DEG,
    PALM_IN_RANGE_DEG,
    TURN_RANGE_DEG,
    check_arm_range,
    check_bmi_shift,
    check_elbow_range,
    check_leg_range,
    check_macros,
    check_palm_range,
    check_turn_range,
)
from ..errors import BsvError, PoseError
from ..types import Mesh, PointCloud
from .common import SEX_TEMPLATE, BenchError, Run, keep_trunk_limbs, load_template, register_method
from .outliers import inject, split_request
from .reference import CALIBRATED, CONDITIONS

SEGMENTATIONS: tuple[str, ...] = ("oracle", "camera")
#: The cohorts of ``--cohort``: the plain synthetic adults, or the same reshaped into the registration's
#: hard classes (:func:`bsv.bodies.variants.hard_subject`).
COHORTS: tuple[str, ...] = ("standard", "hard")

#: The room of ``--studio``: the subject dressed and lit as in the clinic room (skin tone, underwear, hair,
#: two lights) but nothing else returns depth. Against the clinic room it isolates what the floor and the
#: walls do to the camera path from what the subject's appearance does.
STUDIO: dict[str, Any] = {"floor": False, "walls": False, "ceiling": False}


@dataclass
class SynthConfig:
    """Everything one synthetic run depends on (picklable: sent to worker processes)."""

    n: int = 10
    seed: int = 0
    conditions: tuple[str, ...] = CONDITIONS
    segmentation: str = "oracle"
    template: str = "default"
    methods: tuple[str, ...] = ("bsv",)
    params: dict[str, Any] = field(default_factory=dict)
    local: bool = True
    #: The arms' angle below the horizontal the subjects are drawn from (degrees; ``--arm-down``):
    #: :data:`bsv.bodies.cohort.ARM_DOWN_RANGE_DEG` by default, wider to test the pose's effect.
    arm_range: tuple[float, float] = ARM_DOWN_RANGE_DEG
    #: The hips' abduction the subjects are drawn from (degrees; ``--hip-abduction``):
    #: :data:`bsv.bodies.cohort.HIP_ABDUCTION_RANGE_DEG` by default, narrower for thighs that touch.
    leg_range: tuple[float, float] = HIP_ABDUCTION_RANGE_DEG
    #: The palms' turn in from facing forward the subjects are drawn from (degrees; ``--palm-in``):
    #: :data:`bsv.bodies.cohort.PALM_IN_RANGE_DEG` (forward) by default.
    palm_range: tuple[float, float] = PALM_IN_RANGE_DEG
    #: The body's turn about the vertical the subjects are drawn from (degrees; ``--turn``):
    #: :data:`bsv.bodies.cohort.TURN_RANGE_DEG` (facing the front camera squarely) by default.
    turn_range: tuple[float, float] = TURN_RANGE_DEG
    #: The elbows' flexion the subjects are drawn from (degrees; ``--elbow``):
    #: :data:`bsv.bodies.cohort.ELBOW_RANGE_DEG` (nearly straight) by default.
    elbow_range: tuple[float, float] = ELBOW_RANGE_DEG
    #: The BMI added to every subject's draw (``--bmi-shift``; :data:`bsv.bodies.cohort.HEAVY_BMI_SHIFT` for a
    #: heavier cohort).
    bmi_shift: float = 0.0
    #: The ranges MakeHuman's gender, muscle and proportions are drawn from (``--macros``:
    #: :data:`bsv.bodies.cohort.MACRO_RANGES`).
    macros: str = "standard"
    cloud: str = "raw"
    #: Cloud-building keywords for the lab path (``bsv process``'s defaults when empty), e.g. {"sor": True}.
    cloud_params: dict[str, Any] = field(default_factory=dict)
    #: Render the rig inside a room; None: yes on the camera path (camera segmentation or lab cloud), no on the raw path.
    room: bool | None = None
    #: With a room: a studio (:data:`STUDIO`), the room's appearance without its floor, walls or ceiling.
    studio: bool = False
    #: With a room: every subject with hair wears it long, down over the neck and the upper back
    #: (``--long-hair``; :func:`bsv.scan`'s ``look``).
    long_hair: bool = False
    #: With a room: every subject wears a top in the underwear's colour over the chest (``--top``).
    top: bool = False
    #: With a room: the subject shaded smoothly, normals interpolated from the vertex normals
    #: (``--smooth-shading``; :func:`bsv.scan`'s ``look``), instead of the rig's faceted default.
    smooth_shading: bool = False
    #: With a room: the colour images blurred and noisy as a sensor records them (``--colour-sensor``).
    colour_sensor: bool = False
    #: ``standard`` or ``hard`` (:data:`COHORTS`).
    cohort: str = "standard"
    #: In cali and l5ca, also refine each capture's calibration as a user would (``--refine-calibration``,
    #: :func:`refine_condition`) and register the cloud built with it: a second registration per
    #: calibrated condition and subject.
    refine_calibration: bool = False

    def room_arg(self) -> bool | dict[str, Any]:
        """The ``room`` argument of :func:`bsv.scan` for this configuration."""
        if not self.uses_room():
            return False
        return dict(STUDIO) if self.studio else True

    def look_arg(self) -> dict[str, Any] | None:
        """The ``look`` argument of :func:`bsv.scan` for this configuration."""
        look = {k: True for k, on in (("long_hair", self.long_hair), ("top", self.top),
                                      ("smooth_shading", self.smooth_shading),
                                      ("colour_sensor", self.colour_sensor)) if on}
        return look if look and self.uses_room() else None

    def uses_room(self) -> bool:
        """Whether the scans render a room (:attr:`room`, or its default for the path)."""
        if self.room is not None:
            return self.room
        return self.segmentation == "camera" or self.cloud == "lab"

    def validate(self) -> None:
        """Raise BenchError on an unknown condition, segmentation or method, or a bad count."""
        if self.n < 1:
            raise BenchError(f"--n {self.n}: need at least one subject")
        bad = [c for c in self.conditions if c not in CONDITIONS]
        if bad or not self.conditions:
            raise BenchError(f"--conditions {','.join(self.conditions)}: use a comma list of {','.join(CONDITIONS)}")
        checks: tuple[tuple[str, Callable[[Any], Any], Any], ...] = (
            ("--arm-down", check_arm_range, self.arm_range), ("--hip-abduction", check_leg_range, self.leg_range),
            ("--palm-in", check_palm_range, self.palm_range), ("--turn", check_turn_range, self.turn_range),
            ("--elbow", check_elbow_range, self.elbow_range),
            ("--bmi-shift", check_bmi_shift, self.bmi_shift), ("--macros", check_macros, self.macros))
        for option, check, value in checks:
            try:
                check(value)
            except PoseError as exc:
                raise BenchError(f"{option}: {exc}") from None
        if self.cohort not in COHORTS:
            raise BenchError(f"--cohort {self.cohort}: use one of {', '.join(COHORTS)}")
        if self.segmentation not in SEGMENTATIONS:
            raise BenchError(f"--segmentation {self.segmentation}: use oracle or camera")
        if self.cloud not in ("raw", "lab"):
            raise BenchError(f"--cloud {self.cloud}: use raw (the scanner's cloud) or lab (bsv process's cloud building)")
        from .joints import ORACLE_JOINTS_PARAM, oracle_joint_kinds

        if oracle_joint_kinds(self.params.get(ORACLE_JOINTS_PARAM, "")) and (
                self.segmentation != "camera" or self.cohort != "standard"):
            raise BenchError(f"--param {ORACLE_JOINTS_PARAM} replaces the camera path's measured joints with the "
                             "rig's: it needs --segmentation camera and the standard cohort")
        if self.segmentation == "camera":
            from .camera import check_available

            check_available()
        for m in self.methods:
            if m not in ("bsv", "trimesh"):
                raise BenchError(f"method {m!r}: use bsv (and --peer trimesh)")


def scan_seed(seed: int, index: int) -> int:
    """The scanner seed of subject ``index`` in the cohort of ``seed`` (shared by its conditions)."""
    return int(seed) * 1_000_003 + int(index)


def measure_condition(name: str, mesh: Mesh, truth: dict[str, float], condition: str, seed: int,
                      template: Mesh, methods: Iterable[str], segmentation: str = "oracle",
                      params: dict[str, Any] | None = None, truth_mesh: Mesh | None = None,
                      cloud_mode: str = "raw", room: bool | dict[str, Any] = False,
                      look: dict[str, Any] | None = None, cloud_params: dict[str, Any] | None = None,
                      truth_joints: dict[str, Any] | None = None, refine_calibration: bool = False,
                      sex: str | None = None) -> list[Run]:
    """Scan ``mesh`` in one condition, compute the floor if calibrated, register with every method.

    ``cloud_mode``: ``raw`` registers the scanner's cloud; ``lab`` (forced by camera segmentation) rebuilds
    it from the capture images like ``bsv process`` (its defaults, or ``cloud_params``).
    ``room``: scan inside a clinic room, or the room given as a dict (:func:`bsv.scan`); ``look``: looks
    beyond the seed's (:func:`bsv.scan`). The floor moves ``truth_mesh`` (default ``mesh``:
    it must be closed and labelled like the truth); the cloud's far-point percentages are measured against it.
    ``truth_joints``: the rig's joint centres; with camera segmentation each run's ``info`` records the
    joint-centre errors (:mod:`bsv.bench.joints`).
    ``refine_calibration`` (cali and l5ca): the bsv run's ``info["refined"]`` also holds the same capture
    with its calibration refined as a user would (:func:`refine_condition`), registered again.
    ``sex`` (camera segmentation): the subject's sex as ``bsv process --sex`` takes it; None: read from the
    capture (:mod:`bsv.frontend.sex`), as ``bsv process`` does without it. Each run's ``info["sex"]`` says
    which.
    Never raises for a failed registration: the Run carries ``ok=False`` and the error text."""
    from .. import scan
    from .common import cloud_far_pct
    from .floor import floor_volumes, read_camera_poses

    runs: list[Run] = []
    floor: dict[str, float] = {}
    truth_surface = mesh if truth_mesh is None else truth_mesh
    unfiltered: tuple[float | None, float | None] = (None, None)
    joint_errs: dict[str, list[float]] | None = None
    joints: dict[str, Any] | None = None
    loops: dict[str, Any] = {}  # the thighs' loop targets of the camera path (bsv.frontend.groin)
    extra_sd: dict[str, float] = {}  # the sd degraded boundaries add to the intervals, as bsv process adds it
    palms: tuple[float | None, float | None] | None = None  # the palms' turn read from the hand model
    palm_readings: dict[str, list[float | None]] = {}  # each view's readings of them (deg)
    turn: float | None = None  # the subject's turn from facing the front camera, measured (bsv.frontend.facing)
    lab = cloud_mode == "lab" or segmentation == "camera"
    need_files = condition in CALIBRATED or lab
    refined: Refined | None = None
    drawn: dict[str, str] | None = None  # the look the rig drew (scan.json)
    landmark_warnings: list[str] | None = None
    sex_estimate: Any = None
    with tempfile.TemporaryDirectory(prefix="bsv-bench-") as tmp:
        raw = scan(mesh, condition, seed, images=tmp if need_files else None, overwrite=True, room=room,
                   look=look)
        if need_files and room:
            from .looks import read_look

            drawn = read_look(tmp)
        cams = read_camera_poses(tmp) if condition in CALIBRATED else None
        if cams is not None:
            floor = floor_volumes(mesh if truth_mesh is None else truth_mesh, cams)
            if refine_calibration:
                refined = refine_condition(tmp, condition, seed, cams, truth_surface)
        if lab:
            from .camera import build_views_cloud, capture_views

            if segmentation == "camera":
                from .joints import camera_segmentations, capture_hip_loops, joint_errors

                segs, joints = camera_segmentations(tmp, sex=sex)
                loops = capture_hip_loops(tmp, segs, joints)
                views = capture_views(tmp, segmentation, labels={v: s.labels for v, s in segs.items()})
                from ..frontend.facing import turn_deg, turn_warning
                from ..pipeline import segmentation_extra_sd

                front = next(v["camera_to_world"]["translation"] for v in views if v["name"] == "front")
                turn = turn_deg(joints, front)
                extra_sd = segmentation_extra_sd(segs.values(), loops, turn)
                sex_estimate = segs["front"].sex
                from ..frontend.palms import palm_turns, view_readings

                readings = {v: view_readings(s) for v, s in segs.items()}
                palms = palm_turns(readings)
                palm_readings = {v: list(r) for v, r in readings.items()}
                landmark_warnings = [w for s in segs.values() for w in s.warnings]
                if (facing := turn_warning(turn)) is not None:
                    landmark_warnings.append(facing)
                joint_errs = joint_errors(joints, truth_joints) if truth_joints else None
            else:
                views = capture_views(tmp, segmentation)
            raw = build_views_cloud(views, tmp, **(cloud_params or {}))[0]
            if refined is not None and refined.ok:  # the same views, deprojected with the refined extrinsics
                refined.raw = build_views_cloud(refined.views(views), tmp, **(cloud_params or {}))[0]
            # The mask's own cloud, before any cleaning: what floor, wall and edge removal had to remove.
            uncleaned = build_views_cloud(views, tmp, sor=False, remove_floor=False, isolate_person=False)[0]
            unfiltered = cloud_far_pct(keep_trunk_limbs(uncleaned), truth_surface)
        elif refined is not None and refined.ok:
            refined.raw = refined.reexpress(raw, tmp)
    kinds, params = split_request(params)  # --param bench_outliers=floor,wall,mixed (bench/outliers.py)
    from .joints import ORACLE_JOINTS_PARAM, oracle_joint_kinds, with_oracle_joints

    oracle_joints = oracle_joint_kinds(params.pop(ORACLE_JOINTS_PARAM, ""))
    if oracle_joints:  # --param oracle_joints=elbow+knee: the rig's joints on the camera path (a diagnostic)
        joints = with_oracle_joints(joints or {}, truth_joints if segmentation == "camera" else None, oracle_joints)
    if segmentation == "camera" and "labels" not in params:  # the camera path's labels, as bsv process
        from ..pipeline import CAMERA_LABEL_SOURCE

        params = {**params, "labels": CAMERA_LABEL_SOURCE}
    cloud: PointCloud = inject(keep_trunk_limbs(raw), kinds, seed)
    if segmentation == "camera":  # as bsv process: the measured joints confine the upper arms' labels
        from ..keypoints import confine_cloud_upper_arms

        cloud = confine_cloud_upper_arms(cloud, joints)[0]
    posing = str(params.pop("pose_template", "true")).lower() not in ("false", "0", "no", "off")
    template_info: dict[str, Any] = {}
    if segmentation == "camera" and params.get("labels") == "template" and posing:
        from ..posed_template import camera_template, template_record

        try:  # as bsv process: the template posed like the subject
            from ..frontend.sex import template_gender

            posed, notes = camera_template(template, None, joints or {}, gender=template_gender(sex_estimate),
                                           palms=palms)
            template = posed or template
            template_info = {"template": template_record(template, None), "template_notes": notes,
                             "palm_readings": palm_readings}
        except BsvError as exc:  # the template's own pose, said in each run
            template_info = {"template_notes": [f"the template kept its own A-pose: {type(exc).__name__}: {exc}"]}
    far2, far10 = cloud_far_pct(cloud, truth_surface)
    pulls = {**(joints or {}), **loops} if loops else joints  # as bsv process: the joints and the thighs' loops
    for method in methods:
        run = Run(name, condition, method, False, truth_l=dict(truth), floor_l=dict(floor), n_points=len(cloud),
                  cloud_far_2cm_pct=far2, cloud_far_10cm_pct=far10, unfiltered_far_2cm_pct=unfiltered[0],
                  unfiltered_far_10cm_pct=unfiltered[1])
        try:
            fit = register_method(method, cloud, template, params, keypoints=pulls)
            run.estimated_l, run.seconds, run.info, run.ok = fit.volumes_l, fit.seconds, {**fit.info, **template_info}, True
            if method == "bsv":  # the intervals' ingredients (bench/coverage.py)
                from .coverage import record

                run.info["uncertainty"] = record(fit.mesh, truth_surface, cams, segmentation=segmentation,
                                                 extra_sd=extra_sd)
                from .boundaries import INFO_KEY, boundary_errors, end_errors

                try:  # a metric that cannot be read (a diverged fit) is said, the run keeps its volumes
                    run.info[INFO_KEY] = {**boundary_errors(fit.mesh, truth_surface), **end_errors(fit.mesh, truth_surface)}
                except (BsvError, ValueError) as exc:
                    run.info[INFO_KEY + "_error"] = f"{type(exc).__name__}: {exc}"
                if refined is not None:
                    run.info["refined"] = refined.register(kinds, seed, template, params, pulls, segmentation,
                                                           extra_sd)
        except Exception as exc:  # a failed registration is reported, the run goes on
            run.error = f"{type(exc).__name__}: {exc}"
            run.info = {"traceback": traceback.format_exc(limit=3)}
        if joint_errs:
            run.info["joint_errors_mm"] = joint_errs
        if oracle_joints:
            run.info[ORACLE_JOINTS_PARAM] = list(oracle_joints)
        if segmentation == "camera":
            run.info["hip_loops"] = {k: t.to_json() for k, t in loops.items()}
            run.info["turn_deg"] = None if turn is None else round(turn, 2)
        if landmark_warnings is not None:
            from .joints import WARNINGS_KEY

            run.info[WARNINGS_KEY] = landmark_warnings
        if sex_estimate is not None:
            run.info["sex"] = sex_estimate.to_json()
        if drawn is not None:
            from .looks import INFO_KEY as LOOK_KEY

            run.info[LOOK_KEY] = drawn
        runs.append(run)
    return runs


@dataclass
class Refined:
    """One calibrated capture with its calibration refined as a user would (:func:`refine_condition`):
    the refined cameras (or the refinement's ``error``), the floor with the refined extrinsics, and the
    capture's cloud rebuilt with them (``raw``, set by :func:`measure_condition`)."""

    cameras: list[Any] = field(default_factory=list)
    floor_l: dict[str, float] = field(default_factory=dict)
    error: str = ""
    seconds: float = 0.0
    raw: PointCloud | None = None
    #: The true surface the floor and the intervals' truth are measured on.
    truth: Mesh | None = None

    @property
    def ok(self) -> bool:
        """Whether the refinement succeeded."""
        return not self.error

    def views(self, views: list[dict[str, Any]]) -> list[dict[str, Any]]:
        """The lab path's per-camera views (:func:`bsv.bench.camera.capture_views`) with the refined extrinsics."""
        by = {c.pose.name: c.pose for c in self.cameras}
        return [{**v, "camera_to_world": {"rotation": by[v["name"]].est_rotation.tolist(),
                                          "translation": by[v["name"]].est_translation.tolist()}} for v in views]

    def reexpress(self, cloud: PointCloud, capture: str) -> PointCloud:
        """The scanner's merged cloud with each camera's points (``scan.json``'s ``camera_points``) moved
        from its calibrated to its refined extrinsics: the cloud the scanner would have deprojected with them."""
        import json
        from pathlib import Path

        import numpy as np

        from .floor import read_camera_poses

        try:
            ranges = json.loads((Path(capture) / "scan.json").read_text())["camera_points"]
        except (OSError, ValueError, KeyError) as exc:
            raise BenchError(f"{capture}/scan.json: no per-camera point ranges ({exc}); rebuild bsv") from exc
        calibrated = {c.name: c for c in read_camera_poses(capture)}
        pts = np.array(cloud.points, dtype=np.float64, copy=True)
        for c in self.cameras:
            lo, hi = (int(x) for x in ranges[c.pose.name])
            e = calibrated[c.pose.name]
            local = (pts[lo:hi] - e.est_translation) @ e.est_rotation  # camera frame
            pts[lo:hi] = local @ c.pose.est_rotation.T + c.pose.est_translation
        return PointCloud(pts, None, cloud.colors, cloud.labels)

    def register(self, kinds: Any, seed: int, template: Mesh, params: dict[str, Any],
                 joints: dict[str, Any] | None, segmentation: str,
                 extra_sd: dict[str, float] | None = None) -> dict[str, Any]:
        """The bsv registration of the refined cloud and what the refined intervals need (JSON-ready):
        ``estimated_l``, ``floor_l``, ``seconds``, per camera the refinements' figures and the remaining
        error in the paper's and in the posterior's SDs, ``uncertainty`` (:func:`bsv.bench.coverage.record`
        with the refined covariances and the capture's ``extra_sd``); or ``error``."""
        import numpy as np

        from ..uncertainty import PAPER_STD, pose_delta
        from .coverage import record

        if not self.ok or self.raw is None:
            return {"error": self.error or "no refined cloud"}
        cams: dict[str, Any] = {}
        for c in self.cameras:
            p = c.pose
            err = pose_delta(p.true_rotation, p.true_translation, p.est_rotation, p.est_translation)
            cams[p.name] = {"board_depth": c.board_depth, "floor": c.floor, "source": c.source,
                            "error_paper_sd": (err / np.asarray(PAPER_STD.get(p.name, PAPER_STD["back"]))).tolist(),
                            "error_posterior_sd": (err / np.sqrt(np.maximum(np.diag(c.covariance), 1e-30))).tolist()}
        cloud = inject(keep_trunk_limbs(self.raw), kinds, seed)
        if segmentation == "camera":
            from ..keypoints import confine_cloud_upper_arms

            cloud = confine_cloud_upper_arms(cloud, joints)[0]
        try:
            fit = register_method("bsv", cloud, template, params, keypoints=joints)
        except Exception as exc:  # reported with the run, never raised
            return {"error": f"{type(exc).__name__}: {exc}", "cameras": cams, "floor_l": self.floor_l}
        if self.truth is None:
            raise BenchError("refined capture without its true surface")
        unc = record(fit.mesh, self.truth, [c.pose for c in self.cameras], segmentation=segmentation,
                     covariances=[c.covariance for c in self.cameras], source=self.cameras[0].source,
                     extra_sd=extra_sd)
        return {"estimated_l": fit.volumes_l, "floor_l": self.floor_l, "seconds": fit.seconds,
                "refine_seconds": self.seconds, "cameras": cams, "uncertainty": unc}


def refine_condition(capture: str, condition: str, seed: int, cams: list[Any], truth: Mesh) -> Refined:
    """The calibration of a calibrated capture (``capture``, scan ``seed``) refined as a user would: the
    virtual rig's board view in the same condition and seed, in the clinic room
    (:func:`bsv.bench.refine.scan_board`), refined by the board's depth and then the floor
    (:func:`bsv.bench.refine.refine_calibration`); the floor of ``truth`` with the refined extrinsics.
    A refinement that fails (its typed error) is recorded in ``error``, never raised."""
    import numpy as np

    from .floor import floor_volumes, read_camera_poses
    from .refine import refine_calibration, scan_board

    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="bsv-board-") as bdir:
        scan_board(condition, seed, bdir, room=True)
        by = {c.name: c for c in read_camera_poses(bdir)}
        for c in cams:  # the rig draws the calibration error from the seed and the camera only
            b = by.get(c.name)
            if b is None or not (np.allclose(b.est_rotation, c.est_rotation) and
                                 np.allclose(b.est_translation, c.est_translation)):
                raise BenchError(f"{capture}: the board view's camera {c.name!r} is not calibrated as the capture's")
        try:
            cameras = refine_calibration(bdir)
        except Exception as exc:  # BoardDepthError, CalibrationError: recorded with the run
            return Refined(error=f"{type(exc).__name__}: {exc}", seconds=time.perf_counter() - t0)
    return Refined(cameras, floor_volumes(truth, [c.pose for c in cameras]), seconds=time.perf_counter() - t0,
                   truth=truth)


def subject_name(index: int) -> str:
    """Report name of cohort subject ``index``."""
    return f"subject_{index:03d}"


def run_subject(cfg: SynthConfig, index: int, on_condition: Callable[[], None] | None = None) -> tuple[dict, list[Run]]:
    """Every condition and method for cohort subject ``index``; failures are recorded, never raised."""
    from ..bodies import subject
    from ..bodies.variants import hard_subject

    name = subject_name(index)
    t0 = time.perf_counter()
    try:
        make = hard_subject if cfg.cohort == "hard" else subject
        s = make(index, cfg.seed, local=cfg.local, arm_range=cfg.arm_range, leg_range=cfg.leg_range,
                 bmi_shift=cfg.bmi_shift, macros=cfg.macros, palm_range=cfg.palm_range, turn_range=cfg.turn_range,
                 elbow_range=cfg.elbow_range)
    except Exception as exc:
        err = f"subject generation failed: {type(exc).__name__}: {exc}"
        runs: list[Run] = [Run(name, c, m, False, error=err) for c in cfg.conditions for m in cfg.methods]
        for _ in cfg.conditions:
            if on_condition:
                on_condition()
        return {"subject": name, "index": index, "error": err}, runs
    info = {"subject": name, **s.info()}
    info["body_seconds"] = time.perf_counter() - t0
    truth = {k: float(v) for k, v in s.volumes_l().items()}
    template = load_template(cfg.template, s.sex)
    mesh = s.body.mesh()
    from ..bodies.joints import rig_joints

    truth_joints = rig_joints(s.phenotype, s.pose) if cfg.segmentation == "camera" and cfg.cohort == "standard" else None
    runs = []
    for cond in cfg.conditions:
        try:
            runs += measure_condition(name, mesh, truth, cond, scan_seed(cfg.seed, index), template,
                                      cfg.methods, cfg.segmentation, cfg.params, cloud_mode=cfg.cloud,
                                      room=cfg.room_arg(), look=cfg.look_arg(), cloud_params=cfg.cloud_params,
                                      truth_joints=truth_joints,
                                      refine_calibration=cfg.refine_calibration,
                                      sex=s.sex if cfg.template == SEX_TEMPLATE else None)
        except Exception as exc:  # a failed scan/floor is reported, the run goes on
            runs += [Run(name, cond, m, False, truth_l=truth, error=f"{type(exc).__name__}: {exc}")
                     for m in cfg.methods]
        if on_condition:
            on_condition()
    info["seconds"] = time.perf_counter() - t0
    return info, runs


def _worker(args: tuple[SynthConfig, int]) -> tuple[dict, list[dict]]:
    cfg, index = args
    info, runs = run_subject(cfg, index)
    return info, [r.to_json() for r in runs]


def run_synth(cfg: SynthConfig, jobs: int = 1, progress: bool = True,
              scheduler: str | None = None) -> tuple[list[dict], list[Run], float]:
    """The whole cohort: (subject infos, runs, wall seconds). ``jobs`` > 1 or a ``scheduler`` ("local" or
    a Dask scheduler address) runs one subject per task on the ``bsv batch`` cluster
    (:func:`bsv.batch.mapping.map_unordered`; a LocalCluster of ``jobs`` workers for "local")."""
    from tqdm import tqdm

    cfg.validate()
    t0 = time.perf_counter()
    infos: list[dict] = []
    runs: list[Run] = []
    total = cfg.n * len(cfg.conditions)
    with tqdm(total=total, desc="bench synth", unit="scan", disable=not progress) as bar:
        if jobs <= 1 and scheduler is None:
            for i in range(cfg.n):
                info, rs = run_subject(cfg, i, on_condition=lambda: bar.update(1))
                infos.append(info)
                runs += rs
                _report_failures(rs, bar)
        else:
            from ..batch.mapping import map_unordered

            for i, out in map_unordered(_worker, [(cfg, i) for i in range(cfg.n)], scheduler=scheduler,
                                        workers=max(1, jobs), announce=progress):
                if isinstance(out, BaseException):  # the task itself failed (its workers died): recorded
                    err = f"task failed: {type(out).__name__}: {out}"
                    info, rs = {"subject": subject_name(i), "index": i, "error": err}, [
                        Run(subject_name(i), c, m, False, error=err) for c in cfg.conditions for m in cfg.methods]
                else:
                    info, rs = out[0], [Run.from_json(r) for r in out[1]]
                infos.append(info)
                runs += rs
                bar.update(len(cfg.conditions))
                _report_failures(rs, bar)
    infos.sort(key=lambda d: d["subject"])
    runs.sort(key=lambda r: (r.subject, CONDITIONS.index(r.condition), r.method))
    return infos, runs, time.perf_counter() - t0


def _report_failures(runs: list[Run], bar: Any) -> None:
    for r in runs:
        if not r.ok:
            bar.write(f"FAILED {r.subject} {r.condition} {r.method}: {r.error}")

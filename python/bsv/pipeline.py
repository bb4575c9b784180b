"""``bsv process`` and ``bsv demo``: the whole chain from a two-camera capture to volumes and a report.

process: per camera, segmentation of the colour image (MediaPipe, :mod:`bsv.frontend.segment`; or the
virtual scanner's own label image, "oracle") -> cloud building in Rust (``bsv._bsv.build_cloud``: masked
deprojection, calibration, only the person (each camera's floor fitted, checked against the calibration
and removed; depth-edge, far and separate pixels of the mask dropped), optional statistical outlier
removal, merge, head/hands/feet dropped) -> registration
(:func:`bsv.register`) -> volumes. Writes into OUT: ``cloud.ply`` (labelled), ``fitted.ply`` (labelled
fitted template), ``volumes.json`` (DESIGN.md "Formats" with the "registration" and "cloud" sections),
the report (:mod:`bsv.report`: a self-contained ``report.html``, ``report.pdf`` and ``volumes.csv``) and,
with camera segmentation, ``segmentation/<camera>/`` (segmentation.png, segmentation_preview.png, mask.png,
landmarks.json). Nothing is written into the
capture folder, and nothing existing in OUT is replaced unless asked (``overwrite``).

demo: a synthetic subject of :mod:`bsv.bodies` -> virtual two-camera capture images (:func:`bsv.scan`)
-> process -> estimated against true volumes. No camera needed.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from . import _bsv
from .argtypes import real, whole
from .argtypes import seed as seed_type
from .errors import BsipError, InputError, OutputExistsError, PersonIsolationError, ReportError
from .extras import require
from .frontend.errors import CalibrationFileError, CaptureError, SegmentationError
from .frontend.facing import turn_deg, turn_extra_sd, turn_warning
from .frontend.palms import palms_of
from .frontend.sex import SEX_SCORES, template_gender
from .interop import as_mesh
from .keypoints import CAMERA_KEYPOINT_KINDS, camera_joints, confine_cloud_upper_arms
from .posed_template import camera_template, template_record
from .types import SEGMENT_IDS, SEXES, TRUNK_LIMBS, Mesh, PointCloud, Registration

if TYPE_CHECKING:
    from .frontend.segment import Segmentation

PathLike = str | Path

#: Files that process writes into OUT (the report's files, report.html, report.pdf and volumes.csv, are listed
#: by :data:`bsv.report.FILES`).
OUTPUTS = ("cloud.ply", "fitted.ply", "volumes.json")
#: File that demo writes into OUT besides :data:`OUTPUTS`.
DEMO_OUTPUT = "demo.json"
#: Sub-folder of OUT holding the camera segmentation of each camera (``segmentation/<camera>/``).
SEGMENTATION_DIR = "segmentation"
#: Segmentation sources: MediaPipe on the colour image, or the scanner's ground-truth label image.
SEGMENTATIONS = ("camera", "oracle")
#: Segments dropped from the cloud unless ``keep_extremities`` (head, hands, feet).
EXTREMITY_IDS = (1, 7, 8, 13, 14)


@dataclass(repr=False)
class ProcessResult:
    """What :func:`process` produced: the cloud, the registration, the volumes report and the files."""

    out_dir: Path
    cloud: PointCloud
    registration: Registration
    volumes: dict[str, Any]
    cloud_report: dict[str, Any]
    segmentation: dict[str, dict[str, Any]]
    timings: dict[str, float]
    files: dict[str, Path] = field(default_factory=dict)
    #: Ground truth and comparison rows, filled by :func:`demo`.
    truth: dict[str, float] | None = None
    comparison: list[dict[str, Any]] = field(default_factory=list)
    #: Body-segment inertial parameters (:class:`bsv.biomech.BSIP`), with ``bsip=True``.
    bsip: Any = None
    #: Joint centres in 3-D (:class:`bsv.frontend.landmarks.JointCentre` by name), camera segmentation only.
    joints: dict[str, Any] = field(default_factory=dict)
    #: Warnings of the run (each landmark taken from another source than its own confident detection; the
    #: template's pose when an angle was clipped or a joint missing).
    warnings: list[str] = field(default_factory=list)

    @property
    def mesh(self) -> Mesh:
        """The fitted, labelled template."""
        return self.registration.mesh

    @property
    def intervals(self) -> Any:
        """The 95 % intervals of the volumes and ratios (:class:`bsv.uncertainty.Intervals`), or None."""
        from .uncertainty import Intervals

        doc = self.volumes.get("intervals")
        return None if doc is None else Intervals.from_json(doc)

    def __repr__(self) -> str:
        total = self.volumes.get("volumes_l", {}).get("trunk_limbs")
        vol = "" if total is None else f", trunk_limbs={total:.3f} L"
        return f"ProcessResult({self.out_dir}, {len(self.cloud)} points{vol}, {len(self.files)} files)"

    def _repr_html_(self) -> str:
        """Notebook display: the volumes (against the truth for a demo) and a thumbnail (:mod:`bsv.display`)."""
        from .display import registration_html

        return registration_html(self.registration, self.truth, title=f"bsv process -> {self.out_dir}")


class _Steps:
    """Prints each step with its wall time (or stays silent)."""

    def __init__(self, enabled: bool) -> None:
        self.enabled = enabled
        self.timings: dict[str, float] = {}
        self._t0 = time.perf_counter()

    def run(self, key: str, title: str, fn: Callable[[], Any]) -> Any:
        if self.enabled:
            print(f"[bsv] {title} ...", flush=True)
        t = time.perf_counter()
        out = fn()
        dt = time.perf_counter() - t
        self.timings[key] = dt
        if self.enabled:
            print(f"[bsv] {title}: {dt:.2f} s", flush=True)
        return out

    def total(self) -> float:
        return time.perf_counter() - self._t0


# ----------------------------------------------------------------------------------------------------
# Inputs


def _camera_dirs(capture_dir: Path, cameras: Sequence[str]) -> dict[str, Path]:
    if not capture_dir.is_dir():
        raise CaptureError(f"capture folder {capture_dir} does not exist; run `bsv capture {capture_dir}` first")
    dirs = {}
    for cam in cameras:
        d = capture_dir / cam
        if not (d / "camera.json").is_file():
            found = sorted(p.parent.name for p in capture_dir.glob("*/camera.json"))
            raise CaptureError(
                f"no {cam!r} camera capture in {capture_dir} (expected {d}/camera.json with color.png and depth.png; "
                f"found cameras: {found or 'none'}); run `bsv capture {capture_dir}` or check the folder"
            )
        dirs[cam] = d
    return dirs


def _calibration_source(calibration: PathLike | None, capture_dir: Path) -> Path:
    """The calibration.json to read, or the folder of marker images to calibrate from; a
    CalibrationFileError when there is none (checked before any work)."""
    if calibration is None:
        here = capture_dir / "calibration.json"
        hint = (f"; the capture folder has one: pass --calibration {here} to use it" if here.is_file() else "")
        raise CalibrationFileError(
            f"no calibration given for {capture_dir}: pass --calibration calibration.json (written by `bsv calibrate`)"
            + hint
        )
    p = Path(calibration)
    if p.is_dir() and not (p / "calibration.json").is_file():
        return p
    if p.is_dir():
        p = p / "calibration.json"
    if not p.is_file():
        raise CalibrationFileError(
            f"calibration file {p} does not exist: run `bsv calibrate` first, or pass the folder of marker images"
        )
    return p


def _calibration(calibration: PathLike | None, capture_dir: Path, cameras: Sequence[str],
                 intrinsics: dict[str, Any]) -> dict[str, dict[str, Any]]:
    """Camera-to-world extrinsics per camera from calibration.json, or by calibrating from a folder of
    marker images (``<folder>/<camera>/*.png``)."""
    from .frontend import calibrate as cal

    p = _calibration_source(calibration, capture_dir)
    if p.is_dir():
        images = {cam: [str(f) for f in cal.image_files(p / cam)] for cam in cameras}
        c = cal.calibrate(images, {cam: intrinsics[cam] for cam in cameras})
    else:
        c = cal.read_calibration(p)
    out = {}
    for cam in cameras:
        if cam not in c.cameras:
            raise CalibrationFileError(f"{p} has no camera {cam!r} (it has {sorted(c.cameras)}); calibrate that camera")
        cc = c.cameras[cam]
        out[cam] = {"rotation": np.asarray(cc.rotation, dtype=np.float64).tolist(),
                    "translation": np.asarray(cc.translation, dtype=np.float64).tolist(),
                    "covariance": cc.covariance, "covariance_source": cc.covariance_source}
    return out


def _intervals(reg: Registration, cameras: Sequence[Any], segmentation: str, density: float,
               extra_sd: Mapping[str, float] | None = None, build_score: float | None = None) -> Any:
    """The 95 % intervals (:func:`bsv.uncertainty.intervals`) with the error model of an L515 and this
    segmentation, widened by ``extra_sd`` (:func:`segmentation_extra_sd`) and, where the model follows the
    build, at the subject's ``build_score`` (:func:`segmentation_build_score`); without a packaged model for
    the segmentation, the true-label model, saying so."""
    from .uncertainty import error_models, intervals, model_for

    name = model_for("l515", segmentation)
    models = error_models()
    note = ""
    if name not in models:
        name, note = "l515", (f"not included: the error of the {segmentation} segmentation (no packaged model; the "
                              "true-label model is used), so the intervals are too narrow for it")
    return intervals(reg.mesh, reg.volumes, cameras, model=models[name], density=density, note=note,
                     extra_sd=extra_sd, build_score=build_score)


def segmentation_build_score(segmentations: Iterable[Segmentation]) -> float | None:
    """The subject's build score (:func:`bsv.frontend.sex.build_score`) as the camera segmentation read it from
    the capture (both views share one estimate; a sex the user gives is still measured); None when no view
    measured it."""
    from .frontend.sex import build_score

    for seg in segmentations:
        if seg.sex is not None and seg.sex.measurements:
            return build_score(seg.sex.measurements)
    return None


def segmentation_extra_sd(segmentations: Iterable[Segmentation],
                          hip_loops: Mapping[str, Any] | None = None, turn: float | None = None) -> dict[str, float]:
    """The sd the views' degraded boundaries add to each quantity
    (:attr:`bsv.frontend.segment.Segmentation.extra_sd`), the thighs' when the camera path found no hip-loop
    targets (``hip_loops`` given and empty: :func:`bsv.frontend.groin.hip_loop_extra_sd`) and a turned subject's
    (``turn``, degrees: :func:`bsv.frontend.facing.turn_extra_sd`): the largest per quantity (the two views of one
    capture, the crotch they place and the turn describe the same boundaries)."""
    from .frontend.groin import hip_loop_extra_sd

    out: dict[str, float] = {}
    extra = ([seg.extra_sd for seg in segmentations] + ([hip_loop_extra_sd(hip_loops)] if hip_loops is not None else [])
             + [turn_extra_sd(turn)])
    for sds in extra:
        for name, sd in sds.items():
            out[name] = max(out.get(name, 0.0), float(sd))
    return out


def _camera_spread(cam: str, extrinsics: dict[str, Any]) -> Any:
    """The camera's extrinsics and covariance for :func:`bsv.uncertainty.intervals` (the paper's
    repeatability when calibration.json has no covariance)."""
    from .uncertainty import CameraSpread, paper_covariance

    cov = extrinsics.get("covariance")
    return CameraSpread(cam, np.asarray(extrinsics["rotation"]), np.asarray(extrinsics["translation"]),
                        paper_covariance(cam) if cov is None else np.asarray(cov),
                        extrinsics.get("covariance_source") or "paper default (calibration.json has none)")


def _read_label_png(path: Path) -> np.ndarray:
    cv2 = require("cv2")

    img = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
    if img is None:
        raise SegmentationError(
            f"oracle segmentation needs the virtual scanner's label image {path}; it is missing (real captures have "
            "none: use segmentation='camera')"
        )
    return np.ascontiguousarray(img.astype(np.uint8))


def _segment_cameras(data: dict[str, dict[str, Any]], extrinsics: dict[str, dict[str, Any]], cameras: Sequence[str],
                     params: dict[str, Any]) -> tuple[dict[str, Any], dict[str, Any], dict[str, Any]]:
    """Both cameras segmented together (landmarks filled in across views, :mod:`bsv.frontend.landmarks`),
    the joint centres in 3-D, the knee lines moved by the body's proportions (:mod:`bsv.frontend.kneelines`),
    the elbow lines by the elbows' flexion (:mod:`bsv.frontend.elbowlines`) and the thighs' loop targets
    (:mod:`bsv.frontend.groin`); a single camera is segmented alone."""
    from .frontend.groin import hip_loop_targets
    from .frontend.landmarks import Camera, joint_centres, segment_views
    from .frontend.recut import lines_after_joints
    from .frontend.segment import segment_image

    if sorted(cameras) != ["back", "front"]:
        return ({c: segment_image(data[c]["colour"], view=c, depth=data[c]["depth_m"], **params) for c in cameras},
                {}, {})
    cams = {c: Camera.from_json(data[c]["intrinsics"], extrinsics[c]) for c in cameras}
    segs = segment_views({c: data[c] for c in cameras}, cams, **params)
    depths = {c: data[c]["depth_m"] for c in cameras}
    joints = joint_centres(segs, depths, cams)
    segs = lines_after_joints(segs, joints, cams, **params)
    return segs, joints, hip_loop_targets(segs, depths, cams, joints)


def _segment(cam: str, data: dict[str, Any], folder: Path, mode: str, params: dict[str, Any],
             seg_out: Path, seg: Any = None) -> tuple[np.ndarray, dict, Any]:
    """Per-pixel segment labels of one camera, a summary of the segmentation and the camera segmentation
    to save into ``seg_out`` (in the output folder, never into the capture ``folder``) once the whole run
    has succeeded (None for the oracle). ``seg``: the camera's segmentation, when already done."""
    if mode == "oracle":
        labels = _read_label_png(folder / data["meta"].get("labels", "labels.png"))
        summary = {"source": "oracle", "labelled_pixels": int((labels > 0).sum())}
    else:
        from .frontend.segment import segment_image

        if seg is None:
            seg = segment_image(data["colour"], view=cam, depth=data["depth_m"], **params)
        labels = seg.labels
        summary = {"source": "camera (MediaPipe Holistic)", "labelled_pixels": int((labels > 0).sum()),
                   "hands_found": list(seg.hands_found), "counts": seg.counts(), "files": str(seg_out),
                   "landmark_sources": dict(seg.sources), "warnings": list(seg.warnings),
                   "mediapipe_background": seg.background, "knee_line_shift_mm": seg.knee_line_shift_mm,
                   "elbow_line_shift_mm": None if seg.elbow_line_shift_mm is None else list(seg.elbow_line_shift_mm)}
    if labels.shape != data["depth_m"].shape:
        raise SegmentationError(
            f"{cam}: label image {labels.shape} and depth image {data['depth_m'].shape} differ in size; the depth must "
            "be aligned to the colour image"
        )
    return labels, summary, seg


def build_cloud(
    views: Sequence[dict[str, Any]],
    *,
    keep_extremities: bool = False,
    sor: bool = False,
    sor_k: int = 600,
    sor_std_ratio: float = 0.05,
    normals: bool = False,
    colors: str = "palette",
    remove_floor: bool = True,
    isolate_person: bool = True,
    **params: Any,
) -> tuple[PointCloud, dict[str, Any]]:
    """Merged labelled world cloud from camera views (dicts of ``bsv._bsv.build_cloud``) and its report.

    ``remove_floor``: drop the person points on and just above each camera's fitted floor (the floor is
    fitted and checked against the calibration either way). ``isolate_person``: drop mask pixels on depth
    edges, far behind the person and in 3-D parts separate from it; two comparable parts raise
    :class:`bsv.errors.PersonIsolationError`. Other keywords are ``FuseParams`` fields (thresholds:
    ``floor_margin_m``, ``edge_step_m``, ``far_m``, ``link_m``, ``second_part_ratio``, ...).

    ``normals``: also each point's normal from its neighbouring pixels (oriented toward its camera). Off by
    default, so the registration estimates its own (PCA over neighbours), as every benchmark does: fitted
    with these, the camera path's segments came out 1-3 % larger and trunk_limbs +0.6 to +1.1 %
    (benchmarks/BENCH.md, round 2 session 15); and cloud.ply without them gives ``bsv-cli register`` the fit
    ``bsv process`` made.

    The report (a dict) has per view ``floor`` (``status`` "seen"/"not_seen", ``tilt_deg``, ``pitch_deg``,
    ``roll_deg``, ``height_mm`` at the subject), ``cleaning`` (``floor_removed``, ``edge_removed``,
    ``far_removed``, ``separate_removed``, ...), ``sor_removed`` and ``warnings``; in total
    ``floor_agreement`` between cameras and every ``warnings`` string."""
    p = {"sor": bool(sor), "sor_k": int(sor_k), "sor_std_ratio": float(sor_std_ratio), "normals": bool(normals),
         "colors": colors, "drop_labels": [] if keep_extremities else list(EXTREMITY_IDS),
         "remove_floor": bool(remove_floor), "isolate_person": bool(isolate_person), **params}
    pts, nrm, col, lab, report = _bsv.build_cloud(list(views), p)
    return PointCloud(pts, nrm, col, lab), report


def cleaning_summary(view: dict[str, Any]) -> str:
    """One line of what cloud building removed from a camera's mask (a view of the report)."""
    c, f = view["cleaning"], view["floor"]
    floor = (f"floor seen (tilt {f['tilt_deg']:.2f} deg, {f['height_mm']:+.0f} mm)" if f["status"] == "seen"
             else "floor not seen")
    return (f"{view['name']} {view['kept']} kept: floor -{c['floor_removed']}, edges -{c['edge_removed']}, "
            f"far -{c['far_removed']}, separate -{c['separate_removed']}, SOR -{view['sor_removed']}; {floor}")


def _print_cloud(points: int, report: dict[str, Any]) -> None:
    print(f"[bsv]   {points} points", flush=True)
    for v in report["views"]:
        print(f"[bsv]   {cleaning_summary(v)}", flush=True)
    for w in report.get("warnings", []):
        print(f"[bsv]   warning: {w}", flush=True)


def output_files(cameras: Sequence[str] = ("front", "back"), demo: bool = False, bsip: bool = False) -> list[str]:
    """Paths (relative to OUT) that process (and demo, with ``demo``; the BSIP files with ``bsip``) may write."""
    from .biomech import FILES as BSIP_FILES
    from .frontend.segment import SEGMENTATION_FILES
    from .report import FILES as REPORT_FILES

    seg = [f"{SEGMENTATION_DIR}/{cam}/{n}" for cam in cameras for n in SEGMENTATION_FILES]
    return [*OUTPUTS, *REPORT_FILES, *seg, *((DEMO_OUTPUT,) if demo else ()), *(BSIP_FILES if bsip else ())]


def _check_outputs(out: Path, overwrite: bool, cameras: Sequence[str] = ("front", "back"), demo: bool = False,
                   bsip: bool = False) -> None:
    if out.exists() and not out.is_dir():
        raise OutputExistsError(f"{out} exists and is not a folder; choose another output folder")
    existing = [n for n in output_files(cameras, demo, bsip) if (out / n).exists()]
    if existing and not overwrite:
        raise OutputExistsError(
            f"{out} already holds {', '.join(existing)}; pass overwrite=True (--overwrite) to replace them")


# ----------------------------------------------------------------------------------------------------
# process


def _process_keywords() -> frozenset[str]:
    """The keywords of :func:`process` that are not registration parameters (from its signature)."""
    import inspect

    return frozenset(inspect.signature(process).parameters) - {"register_params"}


#: Where the fitted mesh takes its segments from on the camera path: the template's own (anatomical)
#: boundaries carried by the fit, not the 2-D cut lines of the colour images transferred from the cloud.
#: Measured (bench synth --segmentation camera, n 10, seed 0, noer / l515 mean RVE %): thighs 7.3 / 8.1
#: with the cloud's labels against 2.8 / 3.0 with the template's, torso 2.8 / 2.3 against 1.6 / 1.7.
CAMERA_LABEL_SOURCE = "template"


def process(
    capture_dir: PathLike,
    calibration: PathLike | None,
    out_dir: PathLike,
    *,
    segmentation: str = "camera",
    template: Any = None,
    progress: bool = True,
    overwrite: bool = False,
    cameras: Sequence[str] = ("front", "back"),
    keep_extremities: bool = False,
    sor: bool = False,
    sor_k: int = 600,
    sor_std_ratio: float = 0.05,
    remove_floor: bool = True,
    isolate_person: bool = True,
    cloud_params: dict[str, Any] | None = None,
    density: float = 1000.0,
    segment_params: dict[str, Any] | None = None,
    title: str = "BSV report",
    truth: dict[str, float] | None = None,
    bsip: bool = False,
    bsip_density: float | dict[str, float] | None = None,
    bsip_sex: str | None = None,
    sex: str | None = None,
    refine_floor: bool = False,
    keypoints: bool | None = None,
    pose_template: bool = True,
    **register_params: Any,
) -> ProcessResult:
    """Segmentation, cloud, registration and volumes of a capture folder (``CAPTURE_DIR/<camera>/`` with
    color.png, depth.png, camera.json); writes cloud.ply, fitted.ply, volumes.json and report.html into
    ``out_dir`` (nothing existing is replaced unless ``overwrite``). ``calibration``: calibration.json, or a
    folder of marker images per camera. ``segmentation``: "camera" (MediaPipe) or "oracle" (the virtual
    scanner's label image). Other keywords go to :func:`bsv.register`.

    ``sor``: the paper's k-NN statistical outlier removal (k = 600, std ratio 0.05) before merging. Off by
    default: with k = 600 it erodes the sparse, obliquely seen sides of each view (it removed 19-48 % of
    clean virtual scans and biased trunk_limbs by -3 to -5 % in the demo), while the registration's own
    voxel-density filter removes flying pixels without eroding (``bsv.register``'s ``outlier_voxel_m``).

    ``remove_floor`` / ``isolate_person`` (on by default; ``--keep-floor`` / ``--no-isolate`` for diagnosis)
    and ``cloud_params`` (more ``FuseParams`` thresholds): only the person reaches the registration, see
    :func:`build_cloud`. The floor check's warnings are printed and shown in the report.

    ``bsip``: also the body-segment inertial parameters of the fitted mesh (:func:`bsv.bsip`; densities
    ``bsip_density``, de Leva's values for ``bsip_sex``, default ``sex``, else male): bsip.json, bsip.csv
    and model.osim (OpenSim).

    ``sex`` ("female" or "male", ``--sex``): with camera segmentation the knee and hip cut lines of that sex
    (:mod:`bsv.frontend.sex`) and, when the result keeps the template's segments (the camera path), the
    embedded template of that sex (:func:`bsv.default_template`; the torso and thighs fit better,
    ``docs/DESIGN.md``); with the cloud's labels the average template still (it fits the limbs better
    there). None: the camera path reads the sex from the capture (a probability; the cut lines and the
    template's MakeHuman gender move by its score), other paths take the average template. volumes.json's
    ``sex`` and ``template`` say which was taken.

    ``refine_floor`` (``--refine-floor``): correct each camera's pitch, roll and height with the floor it
    sees (:func:`bsv.frontend.floorplane.refine_extrinsics`; the camera must see the floor) before building
    the cloud; the correction is in volumes.json's ``calibration_refinement``.

    Labels of the fitted mesh: with camera segmentation the template's own segments
    (:data:`CAMERA_LABEL_SOURCE`), with oracle labels the cloud's; ``labels="cloud"`` or
    ``labels="template"`` chooses. With camera segmentation, upper-arm points farther than 10 cm from the
    measured shoulder-elbow segment are relabelled torso before the registration
    (:func:`bsv.keypoints.confine_upper_arms`; counted in volumes.json's ``cloud``).
    ``keypoints`` (camera segmentation): the joint centres lifted from both views pull the template's
    joints in the first iterations (``bsv.register``'s keypoint term): None (the default) the shoulders,
    elbows, wrists and hips only, and the thighs' loops at the height the crotch in the depth images gives
    (:mod:`bsv.frontend.groin`; volumes.json's ``boundaries_m``) (:data:`bsv.keypoints.CAMERA_KEYPOINT_KINDS`,
    where the measurements on the synthetic cohort say why), True (``--keypoints``) every joint, False
    (``--no-keypoints``) none.
    ``pose_template`` (camera segmentation, the template's segments; ``--no-pose-template`` turns it off):
    the embedded template is first posed like the subject, its arm, elbow and hip angles read from the
    measured joint centres (:func:`bsv.posed_template.camera_template`); volumes.json's ``template`` holds
    the pose."""
    from . import default_template, write_mesh, write_point_cloud
    from . import register as bsv_register
    from .frontend.capture import read_capture
    from .frontend.segment import warming_up
    from .pdf import PdfRenderer
    from .report import mesh_figures, prepare_figures, render_report, write_rendered
    from .staging import staged_outputs

    if segmentation not in SEGMENTATIONS:
        raise SegmentationError(f"segmentation must be one of {SEGMENTATIONS}, got {segmentation!r}")
    if sex is not None and template is not None:
        err = InputError("sex chooses one of the embedded templates: give sex or template, not both")
        err.argument = "sex"
        raise err
    if sex is not None and sex not in SEXES:
        err = InputError(f"sex {sex!r}: give one of {', '.join(SEXES)}, or None for the average template")
        err.argument = "sex"
        raise err
    template = None if template is None else as_mesh(template)  # a bad template fails here, before any work
    bsip_sex = bsip_sex or sex or "male"
    _bsv.RegisterParams(**register_params)  # bad registration parameters fail here, before any work
    cap = Path(capture_dir)
    out = Path(out_dir)
    _check_outputs(out, overwrite, cameras, bsip=bsip)
    if bsip:
        from .biomech import densities

        if bsip_sex not in SEXES:
            raise BsipError(f"bsip_sex must be one of {SEXES}, got {bsip_sex!r}")
        densities(bsip_density, [n for n in SEGMENT_IDS if n != "unlabelled"])  # a bad density fails before the work
    # The capture folders and the calibration's source before the PDF worker and MediaPipe's warm-up, which
    # an error would wait for (a forgotten --calibration answers at once, not after a second); a missing
    # extra that reading the capture needs is named first.
    dirs = _camera_dirs(cap, cameras)
    try:
        _calibration_source(calibration, cap)
    except CalibrationFileError:
        require("cv2")
        raise
    # Timed from here. WeasyPrint loads in a worker process (bsv.pdf) while MediaPipe prepares on a thread of
    # this one and the capture is read (the worker first: MediaPipe's thread redirects stderr while it runs).
    steps = _Steps(progress)
    pdf_renderer = PdfRenderer()
    with contextlib.closing(pdf_renderer), contextlib.ExitStack() as stack:
        steps.run("prepare", "starting the report's worker process (figures, report.pdf)" if pdf_renderer.worker
                  else "loading the PDF renderer (report.pdf)", pdf_renderer.start)
        # the figures are drawn by the worker; without one, what they need loads while MediaPipe detects
        then = None if pdf_renderer.worker else prepare_figures
        if segmentation == "camera":
            stack.enter_context(warming_up(then=then, **(segment_params or {})))

        def read_all() -> dict[str, dict[str, Any]]:
            return {cam: read_capture(d) for cam, d in dirs.items()}

        data = steps.run("read", f"reading the capture {cap}", read_all)
        extrinsics = steps.run("calibration", "reading the calibration",
                               lambda: _calibration(calibration, cap, cameras, {c: d["intrinsics"] for c, d in data.items()}))

        seg_summary: dict[str, dict[str, Any]] = {}
        seg_files: dict[str, Any] = {}
        joints: dict[str, Any] = {}
        loops: dict[str, Any] = {}  # the thighs' loop targets (bsv.frontend.groin)
        camera_segs: dict[str, Any] = {}
        seg_params = dict(segment_params or {})
        if sex is not None and segmentation == "camera":  # the cut lines of that sex (bsv.frontend.sex)
            seg_params.setdefault("sex_score", SEX_SCORES[sex])
        if segmentation == "camera":
            camera_segs, joints, loops = steps.run("segment", "segmenting both cameras (MediaPipe) and their joint centres",
                                            lambda: _segment_cameras(data, extrinsics, cameras, seg_params))
        sex_estimate = next((s.sex for s in camera_segs.values() if s.sex is not None), None)
        refined: dict[str, dict[str, Any]] = {}
        views = []
        for cam in cameras:
            d = data[cam]

            def segment_camera(cam: str = cam, d: dict[str, Any] = d) -> tuple[np.ndarray, dict, Any]:
                return _segment(cam, d, dirs[cam], segmentation, seg_params, out / SEGMENTATION_DIR / cam,
                                camera_segs.get(cam))

            labels, summary, seg_files[cam] = (segment_camera() if camera_segs else
                                               steps.run(f"segment_{cam}", f"segmenting the {cam} camera ({segmentation})",
                                                         segment_camera))
            seg_summary[cam] = summary
            if refine_floor:
                from .frontend.floorplane import refine_extrinsics

                def refine_camera(cam: str = cam, d: dict[str, Any] = d, person: np.ndarray = labels > 0
                                  ) -> tuple[dict[str, Any], dict[str, Any]]:
                    return refine_extrinsics(cam, extrinsics[cam], d["depth_m"], d["intrinsics"], person)

                extrinsics[cam], refined[cam] = steps.run(
                    f"refine_{cam}", f"refining the {cam} camera's pitch, roll and height with the floor", refine_camera)
            views.append({"name": cam, "intrinsics": d["intrinsics"].to_json(), "camera_to_world": {k: extrinsics[cam][k] for k in ("rotation", "translation")},
                          "depth": np.ascontiguousarray(d["depth_m"], dtype=np.float32), "labels": labels,
                          "colors": np.ascontiguousarray(d["colour"], dtype=np.uint8)})
        pdf_renderer.check()  # a worker that could not load WeasyPrint (pango missing) says so before the fit
        landmark_warnings = [w for seg in camera_segs.values() for w in seg.warnings]
        turn = (turn_deg(joints, np.asarray(extrinsics["front"]["translation"], dtype=np.float64))
                if joints and "front" in extrinsics else None)
        if (facing := turn_warning(turn)) is not None:
            landmark_warnings.append(facing)
        if segmentation == "camera" and not loops:  # the thighs' boundaries from the colour labels alone
            from .frontend.groin import NO_TARGET_WARNING

            landmark_warnings.append(NO_TARGET_WARNING)
        if progress and sex_estimate is not None:
            print(f"[bsv]   {sex_estimate.sentence()}", flush=True)
        if progress:
            for w in landmark_warnings:
                print(f"[bsv]   warning: {w}", flush=True)

        cloud, cloud_report = steps.run(
            "cloud", "building the cloud (deprojection, only the person, merge)",
            lambda: build_cloud(views, keep_extremities=keep_extremities, sor=sor, sor_k=sor_k, sor_std_ratio=sor_std_ratio,
                                remove_floor=remove_floor, isolate_person=isolate_person, **(cloud_params or {})))
        if progress:
            _print_cloud(len(cloud), cloud_report)

        # Camera labels: an upper-arm patch far from the measured arm is the torso a hanging arm covers in one view.
        cloud, arm_relabelled = confine_cloud_upper_arms(cloud, joints if segmentation == "camera" else None)
        label_source = register_params.pop("labels", CAMERA_LABEL_SOURCE if segmentation == "camera" else None)
        if template is None and sex is not None and label_source == "template":
            # the template's own segments carried onto this sex's body; with the cloud's labels the average
            # template fits the limbs better (benchmarks/BENCH.md, round 2 session 11)
            template = default_template(sex=sex)
        template_notes: list[str] = []
        if segmentation == "camera" and label_source == "template" and pose_template:
            template, template_notes = steps.run(
                "pose", "posing the template like the subject (measured joint angles)",
                lambda: camera_template(template, sex, joints, gender=template_gender(sex_estimate),
                                        palms=palms_of(camera_segs) if camera_segs else None))
            if progress:
                for w in template_notes:
                    print(f"[bsv]   warning: {w}", flush=True)
        measured = camera_joints({**joints, **loops}, keypoints)
        pulled_loops = {name: t for name, t in loops.items() if measured and name in measured}  # the thighs' targets used
        reg: Registration = steps.run(
            "register", "registering the template (ARAP)",
            lambda: bsv_register(cloud, template=template, progress=False, density=density, label_source=label_source,
                                 keypoints=measured, **register_params))

        # the fitted mesh's figures, drawn by the PDF worker while the intervals are computed
        mesh_jobs = mesh_figures(reg.mesh, cloud)
        pdf_renderer.prepare(mesh_jobs)
        inertial = None
        if bsip:
            from .biomech import compute as compute_bsip

            inertial = steps.run("bsip", "segment masses, centres of mass, inertia (bsip)",
                                 lambda: compute_bsip(reg, bsip_density, sex=bsip_sex))
        vols = dict(reg.volumes)

        vols["intervals"] = steps.run(
            "intervals", "95 % intervals (calibration Monte Carlo + error model)",
            lambda: _intervals(reg, [_camera_spread(c, extrinsics[c]) for c in cameras], segmentation, density,
                               segmentation_extra_sd(camera_segs.values(), pulled_loops if segmentation == "camera" else None,
                                                     turn),
                               segmentation_build_score(camera_segs.values()))).to_json()
        if refined:
            vols["calibration_refinement"] = {"method": "floor plane (pitch, roll, height)", "cameras": refined}
        vols["cloud"] = {"points": len(cloud), "segmentation": segmentation, "report": cloud_report,
                         "upper_arm_points_relabelled_torso": arm_relabelled}
        vols["joints_m"] = {name: j.to_json() for name, j in joints.items()}
        if turn is not None:  # how squarely the subject faced the front camera (bsv.frontend.facing)
            vols["subject_turn_deg"] = round(turn, 1)
        if segmentation == "camera":
            vols["boundaries_m"] = {name: t.to_json() for name, t in pulled_loops.items()}
        vols["warnings"] = landmark_warnings + template_notes
        vols["template"] = template_record(template, sex)
        if sex_estimate is not None:
            vols["sex"] = sex_estimate.to_json()
        files = {"cloud": out / "cloud.ply", "fitted": out / "fitted.ply", "volumes": out / "volumes.json",
                 "report": out / "report.html"}

        def write_all(stage: Path) -> None:
            # Written only now, into a folder inside OUT moved into place at the end (bsv.staging): a run that
            # fails leaves nothing in OUT, and can be rerun as it was.
            for cam, seg in seg_files.items():
                if seg is not None:
                    from .frontend.segment import write_segmentation

                    write_segmentation(seg, stage / SEGMENTATION_DIR / cam)
            write_point_cloud(stage / files["cloud"].name, cloud)
            write_mesh(stage / files["fitted"].name, reg.mesh)
            (stage / files["volumes"].name).write_text(json.dumps(vols, indent=2) + "\n")
            if inertial is not None:
                from .biomech import write_all as write_bsip

                files.update({Path(n).stem + "_" + Path(n).suffix[1:]: out / p.name
                              for n, p in write_bsip(inertial, stage).items()})

        result = ProcessResult(out, cloud, reg, vols, cloud_report, seg_summary, steps.timings, files, truth=truth,
                               bsip=inertial, joints=joints, warnings=vols["warnings"])
        if truth is not None:
            result.comparison = compare(vols, truth)
        # volumes.csv here; the report (its documents, the figures to draw) goes to the PDF renderer, whose
        # worker process draws the figures and lays report.pdf out while this one writes the other files.
        rendered = steps.run("report", "composing the report (volumes.csv, report.html and report.pdf's documents)",
                             lambda: render_report(result, out, title=title, pdf_renderer=pdf_renderer,
                                                   segmentations={c: s.labels for c, s in seg_files.items()
                                                                  if s is not None}, mesh_jobs=mesh_jobs))

        def write_everything() -> None:
            with staged_outputs(out, overwrite) as stage:
                write_all(stage)
                write_rendered({k: (stage / p.name, data) for k, (p, data) in rendered.items()})
                report_html, report_pdf = pdf_renderer.report()
                if report_html is None:  # a ReportJob always brings report.html's document back
                    raise ReportError("report.html was not rendered with report.pdf")
                write_rendered({"report": (stage / "report.html", report_html.encode("utf-8"))})
                (stage / "report.pdf").write_bytes(report_pdf)
            files.update({k: out / p.name for k, (p, _) in rendered.items()}, report=out / "report.html",
                         report_pdf=out / "report.pdf")

        steps.run("write", "writing the segmentation, cloud.ply, fitted.ply, volumes.json and the report "
                  "(its figures drawn and report.pdf laid out meanwhile)", write_everything)
        result.timings["total"] = steps.total()
        if progress:
            print(f"[bsv] done in {result.timings['total']:.1f} s: {out}", flush=True)
        return result


# ----------------------------------------------------------------------------------------------------
# demo


def compare(volumes: dict[str, Any], truth: dict[str, float]) -> list[dict[str, Any]]:
    """Rows (segment, true_l, estimated_l, error_pct and, with intervals, interval_l) for the trunk-and-limb
    segments and their total."""
    est = volumes.get("volumes_l", {})
    bands = (volumes.get("intervals") or {}).get("volumes_l", {})
    rows = []
    for name in (*TRUNK_LIMBS, "trunk_limbs"):
        if name in truth and name in est:
            t, e = float(truth[name]), float(est[name])
            rows.append({"segment": name, "true_l": t, "estimated_l": e, "error_pct": (e - t) / t * 100.0,
                         **({"interval_l": list(bands[name])} if name in bands else {})})
    return rows


def comparison_table(rows: Sequence[dict[str, Any]]) -> str:
    """The comparison rows as a plain-text table (with the 95 % interval when the rows have one)."""
    lines = [f"{'segment':<14}{'true L':>9}{'estimated L':>13}{'error %':>9}{'95 % interval L':>20}"]
    for r in rows:
        b = r.get("interval_l")
        band = f"{b[0]:>9.3f} to {b[1]:.3f}" if b else ""
        lines.append(f"{r['segment']:<14}{r['true_l']:>9.3f}{r['estimated_l']:>13.3f}{r['error_pct']:>+9.2f}{band:>20}")
    return "\n".join(lines)


def demo(
    out_dir: PathLike,
    *,
    seed: int = 0,
    subject: int = 0,
    condition: str = "l515",
    segmentation: str = "camera",
    progress: bool = True,
    overwrite: bool = False,
    room: bool = True,
    **process_params: Any,
) -> ProcessResult:
    """The whole chain on synthetic subject ``subject`` of the cohort of ``seed``: virtual capture images in
    ``OUT/capture`` (condition "noer", "l515", "cali" or "l5ca") -> segmentation -> cloud -> registration ->
    report in OUT; prints estimated against true volumes and returns the result (``comparison`` rows).
    ``room``: the rig stands in a clinic room (floor, walls, a subject with skin tone, underwear and hair
    drawn from the seed; :func:`bsv.scan`), as a real capture sees it; False: the body alone on grey."""
    from . import bodies, scan

    out = Path(out_dir)
    _bsv.RegisterParams(**{k: v for k, v in process_params.items() if k not in _process_keywords()})
    _check_outputs(out, overwrite, process_params.get("cameras", ("front", "back")), demo=True,
                   bsip=bool(process_params.get("bsip", False)))
    cap = out / "capture"
    steps = _Steps(progress)
    subj = steps.run("subject", f"synthetic subject {subject} (cohort seed {seed})", lambda: bodies.subject(subject, seed))
    if progress:
        print(f"[bsv]   {subj.sex}, {subj.body.stature:.2f} m, {subj.body.volume_l:.1f} L", flush=True)
    where = " in a room" if room else ""
    steps.run("scan", f"virtual two-camera capture ({condition}{where}) into {cap}",
              lambda: scan(subj.body.mesh(), condition, seed, images=cap, overwrite=overwrite, room=room))
    truth = subj.volumes_l()
    if process_params.get("template") is None:  # the subject's sex, as a clinic enters it
        process_params.setdefault("sex", subj.sex)
    res = process(cap, cap / "calibration.json", out, segmentation=segmentation, progress=progress,
                  overwrite=overwrite, truth=truth,
                  title=f"BSV demo: synthetic subject {subject} (seed {seed}, {condition}, {segmentation} segmentation)",
                  **process_params)
    res.timings = {**steps.timings, **res.timings, "total": steps.total()}
    (out / "demo.json").write_text(json.dumps({"subject": subj.info(), "condition": condition, "room": room,
                                               "segmentation": segmentation, "true_volumes_l": truth,
                                               "comparison": res.comparison, "timings_s": res.timings}, indent=2) + "\n")
    res.files["demo"] = out / "demo.json"
    if progress:
        print()
        print(comparison_table(res.comparison))
        print("\n".join(asymmetry_lines(res.volumes)))
        print(f"\nreport: {res.files['report']}  (total {res.timings['total']:.1f} s)")
    return res


# ----------------------------------------------------------------------------------------------------
# Command line


def _register_args(values: Sequence[str], flag: str = "--param") -> dict[str, Any]:
    """``KEY=VALUE`` options as a dict (:func:`bsv.argtypes.key_value`); a malformed one is an InputError."""
    from .argtypes import key_value

    out: dict[str, Any] = {}
    for kv in values:
        try:
            k, v = key_value(kv)
        except argparse.ArgumentTypeError as e:
            raise InputError(f"{flag} {e}") from None
        out[k] = v
    return out


#: ``process`` keywords that have their own ``bsv process`` option, which a ``--param`` must not repeat.
_PROCESS_OPTIONS: dict[str, str] = {"keypoints": "--keypoints / --no-keypoints",
                                    "pose_template": "--pose-template / --no-pose-template"}


def _process_params(values: Sequence[str]) -> dict[str, Any]:
    """``bsv process --param KEY=VALUE`` options (registration parameters); a key that is one of the
    command's own options is an InputError naming that option."""
    out = _register_args(values)
    for key, option in _PROCESS_OPTIONS.items():
        if key in out:
            err = InputError(f"--param {key}=...: {key} is not a registration parameter; use {option}")
            err.argument = "param"
            raise err
    return out


def main_process(argv: Sequence[str] | None = None) -> int:
    """``bsv process CAPTURE_DIR --calibration calibration.json -o OUT``."""
    ap = argparse.ArgumentParser(prog="bsv process", description="Volumes and report of a two-camera capture.")
    ap.add_argument("capture_dir", help="capture folder with <camera>/color.png, depth.png, camera.json")
    ap.add_argument("--calibration", "-c", help="calibration.json (or a folder of marker images per camera)")
    ap.add_argument("-o", "--out", required=True, help="output folder (cloud.ply, fitted.ply, volumes.json, report.html)")
    ap.add_argument("--segmentation", choices=SEGMENTATIONS, default="camera",
                    help="camera: MediaPipe on the colour images (default); oracle: the virtual scanner's labels.png")
    which = ap.add_mutually_exclusive_group()
    which.add_argument("--template", help="template mesh (PLY/OBJ with segment labels); default: the embedded one")
    which.add_argument("--sex", choices=SEXES,
                       help="the subject's sex: with camera segmentation the knee and hip lines and the embedded "
                            "template of that sex (MakeHuman's female or male body) and, with --bsip, de Leva's "
                            "column; default: read from the capture (volumes.json's 'sex' says how sure)")
    ap.add_argument("--keep-extremities", action="store_true", help="keep head, hand and foot points in the cloud")
    ap.add_argument("--sor", action="store_true",
                    help="the paper's statistical outlier removal before merging (off by default: it erodes the "
                         "sparse sides; the registration removes flying pixels itself)")
    ap.add_argument("--sor-k", type=whole(1, 100_000, "--sor-k neighbours"), default=600, help="with --sor: neighbours (default 600, the paper)")
    ap.add_argument("--sor-std", type=real(0.0, 1e6, "--sor-std ratio"), default=0.05, help="with --sor: std ratio (default 0.05, the paper)")
    ap.add_argument("--keep-floor", action="store_true",
                    help="keep the person-mask points on the floor (diagnosis; the floor is still fitted and checked)")
    ap.add_argument("--no-isolate", action="store_true",
                    help="keep depth-edge, far and separate mask pixels, never fail on a second person (diagnosis)")
    ap.add_argument("--cloud-param", action="append", default=[], metavar="KEY=VALUE",
                    help="cloud-building parameter, e.g. floor_margin_m=0.03, link_m=0.03 (repeatable)")
    ap.add_argument("--param", action="append", default=[], metavar="KEY=VALUE", help="registration parameter (repeatable)")
    ap.add_argument("--refine-floor", action="store_true",
                    help="correct each camera's pitch, roll and height with the floor it sees (the cameras must see it)")
    ap.add_argument("--keypoints", action=argparse.BooleanOptionalAction, default=None,
                    help="camera segmentation: let the joint centres lifted from both views pull the template's "
                         f"joints; default: the {', '.join(k.replace('_', ' ') + 's' for k in CAMERA_KEYPOINT_KINDS)} only, "
                         "--keypoints: every joint, --no-keypoints: none")
    ap.add_argument("--pose-template", action=argparse.BooleanOptionalAction, default=True,
                    help="camera segmentation: pose the embedded template like the subject (arm, elbow and hip "
                         "angles from the measured joints) before the registration (default; --no-pose-template: "
                         "the template's own A-pose)")
    ap.add_argument("--overwrite", action="store_true", help="replace files already in OUT")
    _add_bsip_options(ap)
    ap.add_argument("--quiet", action="store_true", help="no progress output")
    a = ap.parse_args(list(argv) if argv is not None else None)
    from . import read_mesh
    from .exitcodes import run_command

    def run() -> int:
        try:
            return process_and_print()
        except PersonIsolationError as e:
            err = PersonIsolationError(f"{e} (command line: --no-isolate, --keep-floor)")
            err.camera = e.camera
            raise err from e

    def process_and_print() -> int:
        res = process(a.capture_dir, a.calibration, a.out, segmentation=a.segmentation,
                      template=read_mesh(a.template) if a.template else None, progress=not a.quiet,
                      overwrite=a.overwrite, keep_extremities=a.keep_extremities, sor=a.sor, sor_k=a.sor_k,
                      sor_std_ratio=a.sor_std, remove_floor=not a.keep_floor, isolate_person=not a.no_isolate,
                      cloud_params=_register_args(a.cloud_param, "--cloud-param"),
                      refine_floor=a.refine_floor, keypoints=a.keypoints, pose_template=a.pose_template, sex=a.sex,
                      **_bsip_args(a), **_process_params(a.param))
        _print_process(res)
        return 0

    return run_command("bsv process", run)


def _add_bsip_options(ap: argparse.ArgumentParser, sex_default: str = "--sex, else male") -> None:
    """``--bsip``, ``--bsip-density`` and ``--bsip-sex`` (``bsv process`` and ``bsv demo``; ``sex_default``
    says where ``--bsip-sex`` defaults from)."""
    ap.add_argument("--bsip", action="store_true",
                    help="also segment masses, centres of mass, inertia, joint centres and lengths: bsip.json, "
                         "bsip.csv (de Leva layout) and model.osim (OpenSim)")
    ap.add_argument("--bsip-density", metavar="KG_M3|JSON",
                    help="with --bsip: one density in kg/m^3, or a JSON mapping by segment or kind, e.g. "
                         "'{\"thigh\": 1060}' (default: Dempster 1955 via Winter 2009 Table 4.1)")
    ap.add_argument("--bsip-sex", choices=SEXES,
                    help=f"with --bsip: the column of de Leva's (1996) table to compare with (default: {sex_default})")


def _bsip_args(a: argparse.Namespace) -> dict[str, Any]:
    """The keywords of process for ``--bsip``, ``--bsip-density`` and ``--bsip-sex`` (none without --bsip)."""
    if not a.bsip:
        if a.bsip_density is not None:
            raise InputError("--bsip-density needs --bsip")
        return {}
    density = None
    if a.bsip_density is not None:
        bad = f"--bsip-density expects a number in kg/m^3 or a JSON mapping, got {a.bsip_density!r}"
        try:
            density = json.loads(a.bsip_density)
        except json.JSONDecodeError:
            raise InputError(bad) from None
        if not isinstance(density, (int, float, dict)) or isinstance(density, bool):
            raise InputError(bad)
    return {"bsip": True, "bsip_density": density, "bsip_sex": a.bsip_sex}


def asymmetry_lines(volumes: dict[str, Any]) -> list[str]:
    """One line per left/right asymmetry of a volumes report, with its 95 % interval or "not
    distinguishable from symmetric" (:func:`bsv.uncertainty.asymmetry_text`)."""
    from .uncertainty import Intervals, asymmetry_text

    iv = Intervals.from_json(volumes["intervals"]) if volumes.get("intervals") else None
    return [f"{name:<26}{asymmetry_text(value, iv.get(name) if iv else None)}"
            for name, value in (volumes.get("ratios") or {}).items() if name.startswith("asymmetry_") and value is not None]


def _print_process(res: Any) -> None:
    v = res.volumes.get("volumes_l", {})
    iv = res.intervals
    outside = False
    for name in (*TRUNK_LIMBS, "trunk_limbs"):
        if name in v:
            b = iv.get(name) if iv else None
            mark = "*" if b and not b[0] <= v[name] <= b[1] else ""
            outside = outside or bool(mark)
            print(f"{name:<14}{v[name]:>9.3f} L" + (f"  (95 % {b[0]:.3f} to {b[1]:.3f}){mark}" if b else ""))
    if outside:
        print("* the interval is corrected for the fit's known bias on the synthetic cohort, so the measured value "
              "lies outside it: the true volume is more likely inside the interval than at the measured value")
    print("\n".join(asymmetry_lines(res.volumes)))
    if res.bsip is not None:
        print(res.bsip.table())
    doubtful = [k for k, q in res.registration.quality.items() if q.doubtful]
    if doubtful:
        print(f"warning: doubtful fit of {', '.join(doubtful)} (see Fit quality in the report)")
    print(f"report: {res.files['report']}" + (f" (PDF: {res.files['report_pdf']}; spreadsheet: {res.files['volumes_csv']})"
                                              if "report_pdf" in res.files else ""))


def main_demo(argv: Sequence[str] | None = None) -> int:
    """``bsv demo [-o OUT] [--seed N] [--condition l515]``."""
    ap = argparse.ArgumentParser(prog="bsv demo", description="The whole chain on a synthetic subject, no camera.")
    ap.add_argument("-o", "--out", default="bsv-demo", help="output folder (default ./bsv-demo)")
    ap.add_argument("--seed", type=seed_type, default=0, help="cohort seed (default 0)")
    ap.add_argument("--subject", type=whole(0, 100_000, "--subject index"), default=0, help="subject index in the cohort (default 0)")
    ap.add_argument("--condition", choices=("noer", "l515", "cali", "l5ca"), default="l515",
                    help="virtual capture condition (default l515: depth noise)")
    ap.add_argument("--segmentation", choices=SEGMENTATIONS, default="camera",
                    help="camera: MediaPipe on the rendered colour images (default); oracle: the rendered labels")
    ap.add_argument("--param", action="append", default=[], metavar="KEY=VALUE", help="registration parameter (repeatable)")
    ap.add_argument("--no-room", action="store_true",
                    help="render the subject alone on grey instead of in a clinic room (floor, walls)")
    ap.add_argument("--overwrite", action="store_true", help="replace files already in OUT")
    _add_bsip_options(ap, "the synthetic subject's sex")
    ap.add_argument("--quiet", action="store_true", help="only the final table")
    a = ap.parse_args(list(argv) if argv is not None else None)
    from .exitcodes import run_command

    def run() -> int:
        res = demo(a.out, seed=a.seed, subject=a.subject, condition=a.condition, segmentation=a.segmentation,
                   progress=not a.quiet, overwrite=a.overwrite, room=not a.no_room, **_bsip_args(a),
                   **_register_args(a.param))
        if a.quiet:
            print(comparison_table(res.comparison))
            print("\n".join(asymmetry_lines(res.volumes)))
        if res.bsip is not None:
            print(res.bsip.table())
        return 0

    return run_command("bsv demo", run)


__all__ = [
    "DEMO_OUTPUT",
    "OUTPUTS",
    "SEGMENTATION_DIR",
    "ProcessResult",
    "asymmetry_lines",
    "build_cloud",
    "cleaning_summary",
    "compare",
    "comparison_table",
    "demo",
    "main_demo",
    "main_process",
    "output_files",
    "process",
    "segmentation_build_score",
    "segmentation_extra_sd",
]

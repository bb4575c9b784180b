"""Every BSV exception class, defined once here; every one derives from :class:`BsvError`.

The Rust extension ``bsv._bsv`` imports these classes (it defines none) and raises the one that its
error variant maps to, with the structured fields of the Rust error set as attributes (``path``,
``element``, ``line``, ``index``, ``argument``, ``parameter``, ``iteration``), so code can react to
the field, not parse the text. Other modules (``bsv.frontend.errors``, ``bsv.bodies``, ``bsv.bench``)
re-export the classes they raise.

This module imports nothing from the package (numpy-free, extension-free): the extension imports it
while it initialises.
"""

from __future__ import annotations

from collections.abc import Sequence


class BsvError(Exception):
    """Base class of every BSV error."""


# --- the core (raised by the Rust extension) ----------------------------------------------------


class FormatError(BsvError):
    """A file could not be read: missing, malformed, truncated or unsupported.

    ``path``: the file; ``element`` / ``line``: where in it (PLY element, OBJ or PLY header line),
    when the reader knows."""

    path: str | None = None
    element: str | None = None
    line: int | None = None


class WriteError(BsvError):
    """A file could not be written (``path``)."""

    path: str | None = None


class InputError(BsvError):
    """Arrays or parameters passed from Python are not valid.

    ``argument``: the argument at fault (``"points"``, ``"faces"``, ``"labels"``, ...);
    ``index``: the first bad row or entry, when there is one."""

    argument: str | None = None
    index: int | None = None


class MeshError(BsvError):
    """A mesh failed a check: open, non-manifold, degenerate."""


class VolumeError(BsvError):
    """Volumes could not be computed (open or non-manifold segments, bad labels or density).

    ``element`` (``"vertex"``, ``"face"``, ``"edge"``) and ``index`` locate the problem when known."""

    element: str | None = None
    index: int | None = None


class RegistrationError(BsvError):
    """The registration rejected its inputs or failed (see the subclasses per stage).

    ``parameter``: the registration parameter (keyword of :func:`bsv.register`) whose change is the
    remedy, when there is one."""

    parameter: str | None = None


class RegistrationInputError(RegistrationError, InputError):
    """The cloud, the template or their labels cannot be registered (empty, too few points, not in
    metres, non-manifold template, ...)."""


class ImplausibleCloudError(RegistrationInputError):
    """The cloud is not a standing person in the world frame (Y up, facing +Z, left on +X, metres): flat,
    compact (a sphere), not upright, facing another way or not of a person's size. The message says what
    was measured and the fix (rotate or turn the cloud, convert its units); ``parameter`` is
    ``"check_plausible"`` (``check_plausible=False`` skips the check). Only with a labelled human template."""


class RegistrationParameterError(RegistrationError, InputError):
    """A registration parameter is unknown, of the wrong type or out of range, or the schedule does
    not parse (``parameter`` names it)."""


class RegistrationNumericError(RegistrationError):
    """The fit failed numerically (no correspondence left, solver failure, divergence);
    ``iteration`` is the global iteration when known."""

    iteration: int | None = None


class RegistrationResourceError(RegistrationError):
    """A resource (the thread pool) could not be obtained."""


class RegistrationStopped(RegistrationError):
    """The fit was stopped by its progress callback (``iteration``: the last iteration run)."""

    iteration: int | None = None


class ScanError(BsvError):
    """The virtual scanner rejected its inputs or failed.

    ``parameter``: the rig parameter at fault (a noise parameter, or ``"room.<key>"`` for the room),
    when there is one."""

    parameter: str | None = None


class PersonIsolationError(BsvError):
    """Cloud building cannot keep only the person in a camera's view (``camera``): the person mask holds
    two comparable separate 3-D parts (a second person, a large object), or the cleaning left no point.
    Clear the scene or check the segmentation; ``isolate_person=False`` / ``remove_floor=False``
    (``--no-isolate`` / ``--keep-floor``) keep the points for diagnosis."""

    camera: str | None = None


class ImplausibleCaptureError(BsvError):
    """A camera's view cannot be a standing person seen from its own side (``camera``): its person has no
    depth relief (a flat wall behind the mask), or its left and right limbs lie on the wrong sides
    (swapped front/back calibrations or camera folders, mirrored extrinsics). Fix the capture or the
    calibration; ``check_plausible=False`` (``--cloud-param check_plausible=false``) skips the check."""

    camera: str | None = None


class MissingExtraError(BsvError, ImportError):
    """A package of an optional extra is not installed (``package``: the import name; ``extra``: the
    extra that brings it, as in ``pip install "body-segment-volumes[frontend]"``)."""

    def __init__(self, message: str, package: str | None = None, extra: str | None = None) -> None:
        super().__init__(message)
        self.package = package
        self.extra = extra

    def __reduce__(self) -> tuple[type, tuple[str, str | None, str | None]]:
        return (type(self), (str(self), self.package, self.extra))


class BsvWarning(BsvError, UserWarning):
    """A result was obtained, but not from what the user may expect: e.g. a point cloud without segment
    labels, so the fitted mesh takes the template's labels. Issued with ``warnings.warn`` (never raised
    unless warnings are errors); a BsvError like every BSV class. Filter with ``warnings.simplefilter``."""


class OutputExistsError(BsvError, FileExistsError):
    """An output file or folder exists and overwriting was not asked for (``overwrite=True``, ``--overwrite``)."""


# --- the front end (calibration, capture, segmentation) -----------------------------------------


class FrontendError(BsvError):
    """Base of every calibration, capture and segmentation error."""


class CalibrationError(FrontendError):
    """The ArUco calibration failed (see the subclasses)."""


class MarkerNotFoundError(CalibrationError):
    """No ArUco marker of the configured dictionary was found in an image."""


class WrongMarkerError(CalibrationError):
    """Markers were found, but none has the configured id."""


class BlurredImageError(CalibrationError):
    """The image (or the marker in it) is too blurred for an accurate pose."""


class BoardDepthError(CalibrationError):
    """The depth image of the calibration board cannot refine the extrinsics: too few valid depth pixels on
    the board, or a board plane too far from where the colour (PnP) pose puts it (a wrong depth scale,
    depth not aligned to colour, or a depth image of another scene)."""


class CalibrationFileError(CalibrationError):
    """A calibration or intrinsics JSON file is missing or malformed."""


class CaptureError(FrontendError):
    """A RealSense capture or replay failed."""


class NoCameraError(CaptureError):
    """No RealSense camera is connected, or not the one with the requested serial number."""


class RecordingError(CaptureError):
    """A recording cannot be opened, holds no usable frames, or lacks a stream."""


class SegmentationError(FrontendError):
    """Body segmentation failed."""


class PersonNotFoundError(SegmentationError):
    """No person was detected in the colour image."""


class PoseTooSmallError(PersonNotFoundError):
    """MediaPipe's pose of a view spans too little of the person the depth image shows (it found a part of the
    person, or something else): the view is treated as one with no person found."""

    #: The largest span found, as a share of the person's height in the depth image.
    span: float = 0.0

    def __init__(self, message: str, span: float) -> None:
        super().__init__(message)
        self.span = float(span)


class LandmarkMissingError(SegmentationError):
    """A landmark needed for the segmentation (an ankle, a wrist, ...) was not detected confidently."""

    #: The missing landmark names.
    missing: Sequence[str] = ()


class LimbMissingError(LandmarkMissingError):
    """A limb's landmark was found in neither view (nor the hand model, nor at the lower threshold): the
    message names the limb and says what to do (step back, open the arms, better light)."""

    #: The limbs concerned, e.g. ["left arm"].
    limbs: Sequence[str] = ()


# --- the synthetic bodies (bsv.bodies) -----------------------------------------------------------


class AssetError(BsvError, RuntimeError):
    """The MakeHuman asset is missing or malformed."""


class PhenotypeError(BsvError, ValueError):
    """A phenotype or local-modifier value is out of range or unknown."""


class PoseError(BsvError, ValueError):
    """A pose angle is out of its allowed range."""


class SolveError(BsvError, ValueError):
    """The stature/BMI solver cannot reach the requested values (``reachable``: the attainable range)."""

    def __init__(self, message: str, reachable: tuple[float, float] | None = None) -> None:
        super().__init__(message)
        self.reachable = reachable


class LabelError(BsvError, ValueError):
    """A labelled mesh cannot be split into closed segments."""


class TemplateError(BsvError, RuntimeError):
    """A template could not be built watertight."""


# --- the benchmarks (bsv.bench) ------------------------------------------------------------------


class BenchError(BsvError, RuntimeError):
    """A benchmark could not run as asked (bad option, missing data or dependency); says what to do."""


class FloorError(BsvError, ValueError):
    """A capture folder lacks the per-camera extrinsics the floor needs."""


# --- biomechanics outputs (bsv.bsip) ---------------------------------------------------------------


class BsipError(BsvError, ValueError):
    """Body-segment inertial parameters cannot be computed or exported as asked (a bad density, a segment
    without volume, a missing package); the message names the parameter or segment and what to do."""


# --- batch processing (bsv.batch) ----------------------------------------------------------------


class BatchInputError(InputError):
    """An input, manifest or option of ``bsv batch`` is not usable (names the file, column or option and
    what to do); the batch does not start."""


# --- BSV Station (bsv.station) ---------------------------------------------------------------------


class LoginRequired(BsvError):
    """BSV Station: the request needs a login (the station listens on an address other than localhost and
    the request carries no valid session); the app answers with the login page."""


# --- uncertainty (bsv.uncertainty) ------------------------------------------------------------------


class UncertaintyError(BsvError, ValueError):
    """An interval cannot be computed: a bad covariance, error-model table or sample count; says which."""


# --- report (bsv.report) ----------------------------------------------------------------------------


class ReportError(BsvError, RuntimeError):
    """The report cannot be made: WeasyPrint cannot load Debian's pango, or fails to render report.pdf; says
    what to install or what failed."""


__all__ = [
    "AssetError", "BatchInputError", "BenchError", "BlurredImageError", "BoardDepthError", "BsipError", "BsvError", "BsvWarning", "CalibrationError", "CalibrationFileError",
    "CaptureError", "FloorError", "FormatError", "FrontendError", "ImplausibleCaptureError", "ImplausibleCloudError", "InputError", "LabelError",
    "LandmarkMissingError", "LoginRequired", "MarkerNotFoundError", "MeshError", "MissingExtraError", "NoCameraError", "OutputExistsError",
    "PersonIsolationError", "PersonNotFoundError", "PhenotypeError", "PoseError", "PoseTooSmallError", "RecordingError", "RegistrationError",
    "RegistrationInputError", "RegistrationNumericError", "RegistrationParameterError",
    "RegistrationResourceError", "RegistrationStopped", "ReportError", "ScanError", "SegmentationError", "SolveError",
    "TemplateError", "UncertaintyError", "VolumeError", "WriteError", "WrongMarkerError",
]

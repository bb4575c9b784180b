"""MediaPipe's pose landmark models: which files there are, where they live, how the missing ones are installed.

The camera path runs BlazePose GHUM *heavy* (``SegmentParams.model_complexity`` 2), whose landmarks place the
joints and the segment boundaries better than the *full* model's (benchmarks/BENCH.md, round 2 session 27).
The mediapipe wheel ships only the full model and downloads the others from Google's storage on first use,
which fails offline. MediaPipe publishes the same three files on the npm registry in its ``@mediapipe/pose``
package (whose ``pose_landmark_full.tflite`` is byte-identical to the wheel's), so :func:`install_pose_models`
fetches that package's tarball from the registry once, checks the tarball and each model against the SHA-256
pinned here, and writes the lite and heavy models beside the wheel's full model, where MediaPipe's Holistic
graph loads them. ``scripts/setup.sh`` runs it; by hand::

    python -m bsv.frontend.pose_model            # installs the missing models, prints where they are
    python -m bsv.frontend.pose_model --check    # exit status 1 (and what to run) if one is missing

Nothing is downloaded while a capture is processed: a missing model is a
:class:`~bsv.errors.SegmentationError` that names this command (:func:`require_pose_model`).
"""

from __future__ import annotations

import argparse
import hashlib
import http.client
import io
import os
import sys
import tarfile
import tempfile
import urllib.error
import urllib.request
from pathlib import Path

from ..errors import SegmentationError

#: The model file of each MediaPipe model complexity (0 lite, 1 full, 2 heavy).
POSE_MODEL_FILES: dict[int, str] = {0: "pose_landmark_lite.tflite", 1: "pose_landmark_full.tflite",
                                    2: "pose_landmark_heavy.tflite"}
#: Size in bytes of each model file (a file of another size is a truncated or foreign one).
MODEL_SIZES: dict[int, int] = {0: 2_819_824, 1: 6_440_512, 2: 27_709_200}
#: SHA-256 of each model file (the full model's is the one the mediapipe 0.10.21 wheel ships).
MODEL_SHA256: dict[int, str] = {
    0: "f17bfbecadb61c3be1baa8b8d851cc6619c870a87167b32848ad20db306b9d61",
    1: "e9a5c5cb17f736fafd4c2ec1da3b3d331d6edbe8a0d32395855aeb2cdfd64b9f",
    2: "59e42d71bcd44cbdbabc419f0ff76686595fd265419566bd4009ef703ea8e1fe",
}
#: The npm package that publishes the three models and its version (the last ``@mediapipe/pose``).
NPM_PACKAGE: tuple[str, str] = ("@mediapipe/pose", "0.5.1675469404")
#: SHA-256 of that version's tarball.
TARBALL_SHA256 = "8bb349a7b3a3ba699df23be804ddd3b3eab810b50b15406894be257859388a84"
#: The registry the tarball is fetched from; the environment variable ``BSV_NPM_REGISTRY`` overrides it (a
#: mirror, or a ``file://`` folder holding the tarball under the registry's path).
NPM_REGISTRY = "https://registry.npmjs.org"
#: The install command a missing model's error names.
INSTALL_COMMAND = "python -m bsv.frontend.pose_model"
#: The complexities :func:`install_pose_models` fetches (the full model comes with the mediapipe wheel).
NPM_COMPLEXITIES: tuple[int, ...] = (0, 2)


def check_complexity(complexity: object) -> int:
    """``complexity`` if it is a model complexity of :data:`POSE_MODEL_FILES`, else a SegmentationError."""
    if isinstance(complexity, bool) or not isinstance(complexity, int) or complexity not in POSE_MODEL_FILES:
        raise SegmentationError(f"model_complexity must be 0, 1 or 2, got {complexity!r}")
    return complexity


def model_dir() -> Path:
    """The folder MediaPipe's Holistic graph loads the pose models from (``mediapipe/modules/pose_landmark``
    of the installed wheel). SegmentationError if mediapipe is not installed."""
    try:
        import mediapipe
    except ImportError as e:
        raise SegmentationError(
            f"mediapipe is not installed ({e}); install the front-end's packages "
            "(pip install -r requirements-frontend.txt, or bash scripts/setup.sh)") from e
    return Path(mediapipe.__file__).resolve().parent / "modules" / "pose_landmark"


def model_path(complexity: int) -> Path:
    """Where the model of ``complexity`` (0, 1 or 2) lives; SegmentationError for another complexity."""
    return model_dir() / POSE_MODEL_FILES[check_complexity(complexity)]


def require_pose_model(complexity: int) -> Path:
    """The model file of ``complexity`` if it is installed whole (its size is :data:`MODEL_SIZES`'), else a
    SegmentationError naming the file and what installs it: :data:`INSTALL_COMMAND` for the lite and heavy
    models, the mediapipe wheel for the full one."""
    path = model_path(complexity)
    remedy = (f"install it once with `{INSTALL_COMMAND}` (it fetches MediaPipe's @mediapipe/pose package from the "
              "npm registry; scripts/setup.sh does this)" if complexity in NPM_COMPLEXITIES else
              "reinstall the mediapipe wheel (pip install --force-reinstall -r requirements-frontend.txt)")
    if not path.is_file():
        raise SegmentationError(f"model_complexity={complexity} needs MediaPipe's {POSE_MODEL_FILES[complexity]}, "
                                f"which is not at {path}: {remedy}")
    if path.stat().st_size != MODEL_SIZES[complexity]:
        raise SegmentationError(f"{path} has {path.stat().st_size} bytes, not MediaPipe's {MODEL_SIZES[complexity]}: "
                                f"a truncated or foreign file; remove it and {remedy}")
    return path


def _sha256(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def tarball_url(registry: str | None = None) -> str:
    """The URL of :data:`NPM_PACKAGE`'s tarball on ``registry`` (default: ``BSV_NPM_REGISTRY`` or
    :data:`NPM_REGISTRY`)."""
    base = (registry or os.environ.get("BSV_NPM_REGISTRY") or NPM_REGISTRY).rstrip("/")
    name, version = NPM_PACKAGE
    return f"{base}/{name}/-/{name.split('/')[-1]}-{version}.tgz"


def _fetch(url: str, timeout_s: float) -> bytes:
    try:
        with urllib.request.urlopen(url, timeout=timeout_s) as response:
            data: bytes = response.read()
    except (urllib.error.URLError, OSError, ValueError, http.client.HTTPException) as e:
        raise SegmentationError(
            f"could not fetch {url} ({e}); check the connection to the npm registry, or set BSV_NPM_REGISTRY to "
            "a mirror that holds the package") from e
    return data


def _members(tarball: bytes, url: str, wanted: dict[int, str]) -> dict[int, bytes]:
    """The model files of ``wanted`` (complexity -> file name) read from the package's tarball, each checked
    against :data:`MODEL_SHA256`."""
    out: dict[int, bytes] = {}
    try:
        with tarfile.open(fileobj=io.BytesIO(tarball), mode="r:gz") as tar:
            for complexity, name in wanted.items():
                member = tar.extractfile(f"package/{name}")
                if member is None:
                    raise KeyError(name)
                out[complexity] = member.read()
    except (tarfile.TarError, KeyError, OSError) as e:
        raise SegmentationError(f"{url} is not the expected @mediapipe/pose package ({e!r}); if BSV_NPM_REGISTRY "
                                "points to a mirror, unset it to use the npm registry") from e
    for complexity, data in out.items():
        if _sha256(data) != MODEL_SHA256[complexity]:
            raise SegmentationError(
                f"{POSE_MODEL_FILES[complexity]} in {url} has SHA-256 {_sha256(data)}, not the pinned "
                f"{MODEL_SHA256[complexity]}: refusing to install it (if BSV_NPM_REGISTRY points to a mirror, unset it "
                "to use the npm registry)")
    return out


def _write_atomically(path: Path, data: bytes) -> None:
    """``data`` into ``path`` through a temporary file of its folder, synced, then renamed over it; a
    SegmentationError (and no file left behind) when the folder cannot be written."""
    tmp: str | None = None
    try:
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".part")
        with os.fdopen(fd, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        os.chmod(tmp, 0o644)  # mkstemp's 0600 would hide the model from other users of the environment
        os.replace(tmp, path)
    except OSError as e:
        raise SegmentationError(
            f"could not write {path} ({e}): run `{INSTALL_COMMAND}` as a user who may write to {path.parent} (the "
            "mediapipe package's folder), or install BSV into a virtual environment of your own") from e
    finally:
        if tmp is not None and os.path.exists(tmp):
            os.unlink(tmp)


def install_pose_models(complexities: tuple[int, ...] = NPM_COMPLEXITIES, *, registry: str | None = None,
                        target: Path | None = None, timeout_s: float = 120.0) -> dict[int, Path]:
    """Installs the pose models of ``complexities`` that are missing from ``target`` (default
    :func:`model_dir`) and returns where each one is. A model already there is checked, not replaced; one
    whose checksum differs from :data:`MODEL_SHA256` is a SegmentationError (remove it to re-install). The
    tarball and every file are checked before anything is written, and each file is written atomically."""
    folder = target if target is not None else model_dir()
    paths = {}
    wanted = {}
    for c in complexities:
        path = folder / POSE_MODEL_FILES[check_complexity(c)]
        paths[c] = path
        if path.is_file():
            try:
                digest = _sha256(path.read_bytes())
            except OSError as e:
                raise SegmentationError(f"could not read {path} ({e}); remove it and run `{INSTALL_COMMAND}` again") from e
            if digest != MODEL_SHA256[c]:
                raise SegmentationError(
                    f"{path} is not MediaPipe's {POSE_MODEL_FILES[c]} (its SHA-256 differs from the pinned one); "
                    f"remove it and run `{INSTALL_COMMAND}` again")
        else:
            wanted[c] = POSE_MODEL_FILES[c]
    if not wanted:
        return paths
    if not folder.is_dir():
        raise SegmentationError(f"{folder} is not a folder: is mediapipe installed?")
    url = tarball_url(registry)
    tarball = _fetch(url, timeout_s)
    if _sha256(tarball) != TARBALL_SHA256:
        raise SegmentationError(f"{url} has SHA-256 {_sha256(tarball)}, not the pinned {TARBALL_SHA256}: "
                                "refusing to install from it (if BSV_NPM_REGISTRY points to a mirror, unset it to use "
                                "the npm registry)")
    for c, data in _members(tarball, url, wanted).items():
        _write_atomically(paths[c], data)
    return paths


def main(argv: list[str] | None = None) -> int:
    """Command line: install the lite and heavy pose models (or ``--check`` that they are there)."""
    ap = argparse.ArgumentParser(prog=INSTALL_COMMAND, description="Installs MediaPipe's lite and heavy pose models "
                                 "from the npm registry (checked against pinned SHA-256s).")
    ap.add_argument("--check", action="store_true", help="only check; exit status 1 if a model is missing")
    ap.add_argument("--registry", help=f"npm registry (default: BSV_NPM_REGISTRY or {NPM_REGISTRY})")
    a = ap.parse_args(argv)
    try:
        if a.check:
            for c in POSE_MODEL_FILES:
                print(require_pose_model(c))
            return 0
        for c, path in sorted(install_pose_models(registry=a.registry).items()):
            print(f"{POSE_MODEL_FILES[c]}: {path}")
    except SegmentationError as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

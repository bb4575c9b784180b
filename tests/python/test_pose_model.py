"""bsv.frontend.pose_model: the heavy pose model is installed from a checked npm tarball, or its absence is a
clear error that names the command."""

from __future__ import annotations

import hashlib
import io
import tarfile
from pathlib import Path

import pytest

from bsv.errors import SegmentationError
from bsv.frontend import pose_model as pm


def _registry(root: Path, files: dict[str, bytes]) -> tuple[str, bytes]:
    """A file:// registry holding a tarball of ``files`` (under ``package/``) at the npm path; (url, tarball)."""
    buf = io.BytesIO()
    with tarfile.open(fileobj=buf, mode="w:gz") as tar:
        for name, data in files.items():
            info = tarfile.TarInfo(f"package/{name}")
            info.size = len(data)
            tar.addfile(info, io.BytesIO(data))
    blob = buf.getvalue()
    url = pm.tarball_url(f"file://{root}")
    path = Path(url.removeprefix("file://"))
    path.parent.mkdir(parents=True)
    path.write_bytes(blob)
    return f"file://{root}", blob


def _installable(tmp_path: Path, monkeypatch: pytest.MonkeyPatch, models: dict[str, bytes],
                 pin: bool = True) -> tuple[str, Path]:
    """A file:// registry holding ``models`` and an empty target folder; with ``pin`` the tarball's and the
    models' SHA-256s are the pinned ones for the test; (registry, target)."""
    registry, blob = _registry(tmp_path / "reg", models)
    if pin:
        monkeypatch.setattr(pm, "TARBALL_SHA256", hashlib.sha256(blob).hexdigest())
        for c, name in pm.POSE_MODEL_FILES.items():
            if name in models:
                monkeypatch.setitem(pm.MODEL_SHA256, c, hashlib.sha256(models[name]).hexdigest())
    target = tmp_path / "models"
    target.mkdir()
    return registry, target


def test_a_missing_model_names_the_install_command(tmp_path, monkeypatch):
    monkeypatch.setattr(pm, "model_dir", lambda: tmp_path)
    with pytest.raises(SegmentationError, match=r"pose_landmark_heavy\.tflite.*python -m bsv\.frontend\.pose_model"):
        pm.require_pose_model(2)
    with pytest.raises(SegmentationError, match=r"pose_landmark_full\.tflite.*reinstall the mediapipe wheel"):
        pm.require_pose_model(1)
    for bad in (3, "2", True, [2]):
        with pytest.raises(SegmentationError, match="model_complexity must be 0, 1 or 2"):
            pm.require_pose_model(bad)  # type: ignore[arg-type]
    # a truncated model (an interrupted download of another tool) is not taken for the model
    (tmp_path / "pose_landmark_heavy.tflite").write_bytes(b"truncated")
    with pytest.raises(SegmentationError, match="truncated or foreign file; remove it"):
        pm.require_pose_model(2)
    assert pm.main(["--check"]) == 1


def test_a_tarball_of_another_checksum_is_refused_and_nothing_is_written(tmp_path, monkeypatch):
    registry, target = _installable(tmp_path, monkeypatch, {"pose_landmark_heavy.tflite": b"not a model"}, pin=False)
    with pytest.raises(SegmentationError, match=f"not the pinned {pm.TARBALL_SHA256}: refusing to install from it"):
        pm.install_pose_models((2,), registry=registry, target=target)
    assert list(target.iterdir()) == []


def test_a_model_of_another_checksum_is_refused_and_nothing_is_written(tmp_path, monkeypatch):
    registry, target = _installable(tmp_path, monkeypatch, {"pose_landmark_heavy.tflite": b"not a model"})
    monkeypatch.setitem(pm.MODEL_SHA256, 2, pm.MODEL_SHA256[1])  # the tarball is pinned, its model is not
    with pytest.raises(SegmentationError, match=r"pose_landmark_heavy\.tflite .* refusing"):
        pm.install_pose_models((2,), registry=registry, target=target)
    assert list(target.iterdir()) == []


def test_a_checked_model_is_installed_once(tmp_path, monkeypatch):
    model = b"heavy model bytes"
    registry, target = _installable(tmp_path, monkeypatch, {"pose_landmark_heavy.tflite": model})
    paths = pm.install_pose_models((2,), registry=registry, target=target)
    assert paths[2].read_bytes() == model
    assert sorted(p.name for p in target.iterdir()) == ["pose_landmark_heavy.tflite"]  # no temporary left
    # installed: checked, not fetched again (the registry is gone)
    Path(pm.tarball_url(registry).removeprefix("file://")).unlink()
    assert pm.install_pose_models((2,), registry=registry, target=target) == paths
    # a file there that is not the model is reported, not overwritten
    paths[2].write_bytes(b"something else")
    with pytest.raises(SegmentationError, match="remove it"):
        pm.install_pose_models((2,), registry=registry, target=target)
    assert paths[2].read_bytes() == b"something else"


def test_an_unwritable_folder_is_a_clear_error_and_leaves_nothing(tmp_path, monkeypatch, capsys):
    models = {"pose_landmark_lite.tflite": b"lite model bytes", "pose_landmark_heavy.tflite": b"heavy model bytes"}
    registry, target = _installable(tmp_path, monkeypatch, models)

    def refuse(src: str, dst: object) -> None:  # what a read-only site-packages does to the rename
        raise PermissionError(13, "Permission denied", str(dst))

    monkeypatch.setattr(pm.os, "replace", refuse)
    with pytest.raises(SegmentationError, match=r"could not write .*may write to"):
        pm.install_pose_models((2,), registry=registry, target=target)
    assert list(target.iterdir()) == []  # the temporary file is gone too
    # the command line, the registry taken from the environment: the same clear error, exit status 1
    monkeypatch.setenv("BSV_NPM_REGISTRY", registry)
    monkeypatch.setattr(pm, "model_dir", lambda: target)
    capsys.readouterr()
    assert pm.main([]) == 1
    assert "error: could not write" in capsys.readouterr().err
    assert list(target.iterdir()) == []


def test_an_unreachable_registry_is_a_clear_error(tmp_path):
    with pytest.raises(SegmentationError, match=r"could not fetch .*BSV_NPM_REGISTRY"):
        pm.install_pose_models((2,), registry=f"file://{tmp_path / 'nowhere'}", target=tmp_path)


def test_the_installed_models_are_mediapipe_s():
    """scripts/setup.sh installed the lite and heavy models beside the wheel's full one, each the pinned file."""
    pytest.importorskip("mediapipe", reason="the front-end's packages are not installed")
    for complexity, digest in pm.MODEL_SHA256.items():
        path = pm.require_pose_model(complexity)
        assert hashlib.sha256(path.read_bytes()).hexdigest() == digest, path
    assert pm.main(["--check"]) == 0


def test_segmentation_without_the_model_names_the_command(tmp_path, monkeypatch):
    """The camera path's first detection, not a download, reports a missing heavy model."""
    pytest.importorskip("mediapipe", reason="the front-end's packages are not installed")
    import numpy as np

    from bsv.frontend import segment as seg

    monkeypatch.setattr(pm, "model_dir", lambda: tmp_path)
    img = np.zeros((64, 48, 3), np.uint8)
    # a detection confidence no other test uses: no graph of this process is reused
    with pytest.raises(SegmentationError, match=r"python -m bsv\.frontend\.pose_model"):
        seg.segment_image(img, "front", min_detection_confidence=0.613)

"""The variant-to-exception mapping: every BSV exception class is defined in bsv.errors, the
extension raises those classes (it defines none), with the structured fields as attributes."""

from __future__ import annotations

import inspect
import pickle
from pathlib import Path

import numpy as np
import pytest

import bsv
from bsv import _bsv, errors


def unit_cube() -> tuple[np.ndarray, np.ndarray]:
    v = np.array([[x, y, z] for z in (0, 1) for y in (0, 1) for x in (0, 1)], dtype=float)
    f = np.array([[0, 2, 3], [0, 3, 1], [4, 5, 7], [4, 7, 6], [0, 1, 5], [0, 5, 4],
                  [2, 6, 7], [2, 7, 3], [0, 4, 6], [0, 6, 2], [1, 3, 7], [1, 7, 5]])
    return v, f


def test_every_exception_class_is_defined_in_bsv_errors() -> None:
    import importlib
    import pkgutil

    for info in pkgutil.walk_packages(bsv.__path__, "bsv."):
        if info.name.endswith("__main__") or ".migrations." in info.name:
            continue  # scripts, and Alembic's migration scripts (run by Alembic, not importable on their own)
        try:
            mod = importlib.import_module(info.name)
        except ImportError:  # optional dependencies of a front-end module
            continue
        for _, obj in inspect.getmembers(mod, inspect.isclass):
            if issubclass(obj, BaseException) and obj.__module__.startswith("bsv"):
                assert obj.__module__ == "bsv.errors", f"{obj.__qualname__} is defined in {obj.__module__}"
                assert issubclass(obj, errors.BsvError)
    assert not any(isinstance(getattr(_bsv, n), type) and issubclass(getattr(_bsv, n), BaseException)
                   for n in dir(_bsv))
    # Re-exports are the same objects.
    from bsv.bodies import errors as body_errors
    from bsv.frontend import errors as fe

    assert fe.CalibrationError is errors.CalibrationError and fe.BsvError is bsv.BsvError
    assert body_errors.LabelError is errors.LabelError and bsv.bodies.SolveError is errors.SolveError


def test_unreadable_files_are_format_errors_with_the_path(tmp_path: Path) -> None:
    missing = tmp_path / "missing.ply"
    with pytest.raises(errors.FormatError) as e:
        bsv.read_mesh(missing)
    assert e.value.path == str(missing)
    trunc = tmp_path / "trunc.ply"
    trunc.write_bytes(b"ply\nformat binary_little_endian 1.0\nelement vertex 10\nproperty float x\n"
                      b"property float y\nproperty float z\nend_header\n" + bytes(20))
    with pytest.raises(errors.FormatError) as e:
        bsv.read_point_cloud(trunc)
    assert e.value.path == str(trunc) and e.value.element == "vertex"
    obj = tmp_path / "bad.obj"
    obj.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n")
    with pytest.raises(errors.FormatError) as e:
        bsv.read_mesh(obj)
    assert e.value.line == 4 and e.value.path == str(obj)


def test_unwritable_files_are_write_errors_with_the_path(tmp_path: Path) -> None:
    v, f = unit_cube()
    target = tmp_path / "no" / "such" / "dir" / "m.ply"
    with pytest.raises(errors.WriteError) as e:
        bsv.write_mesh(target, v, f)
    assert e.value.path == str(target)


def test_bad_arrays_are_input_errors_naming_the_argument() -> None:
    v, f = unit_cube()
    with pytest.raises(errors.InputError) as e:
        bsv.volumes(v, np.vstack([f, [[0, 1, 99]]]))
    assert e.value.argument == "faces" and e.value.index == 12
    with pytest.raises(errors.InputError) as e:
        bsv.volumes(v[:, :2], f)
    assert e.value.argument == "vertices"
    with pytest.raises(errors.InputError) as e:
        bsv.volumes(v, f, labels=np.full(len(v), 270))
    assert e.value.argument == "labels" and e.value.index == 0 and "270" in str(e.value)
    with pytest.raises(errors.InputError) as e:
        bsv.volumes(v, f, labels=np.full(len(v), 2.5))
    assert e.value.argument == "labels"
    with pytest.raises(errors.InputError) as e:
        bsv.register(np.zeros(30))
    assert e.value.argument == "points"
    with pytest.raises(errors.InputError) as e:
        bsv.write_point_cloud("/tmp/never.ply", np.zeros((4, 3)), normals=np.zeros((3, 3)), overwrite=True)
    assert e.value.argument == "normals"


def test_volume_errors_locate_the_problem() -> None:
    v, f = unit_cube()
    with pytest.raises(errors.VolumeError) as e:
        bsv.volumes(v, f[:-1])
    assert e.value.element == "edge"
    with pytest.raises(errors.VolumeError) as e:
        bsv.volumes(v, f, density=-1.0)
    assert "density" in str(e.value)


def test_registration_errors_per_stage_with_the_parameter() -> None:
    cloud = np.random.default_rng(0).normal(size=(500, 3)) * 0.3
    with pytest.raises(errors.RegistrationParameterError) as e:
        bsv.register(cloud, data_weight=-1.0)
    assert e.value.parameter == "data_weight" and isinstance(e.value, errors.InputError)
    with pytest.raises(errors.RegistrationParameterError) as e:
        bsv.register(cloud, schedule="m2p:x")
    assert e.value.parameter == "schedule"
    with pytest.raises(errors.RegistrationParameterError) as e:
        bsv.register(cloud, schedule="m2p:0")
    assert e.value.parameter == "schedule"
    with pytest.raises(errors.RegistrationParameterError, match="unknown field") as e:
        bsv.register(cloud, no_such_knob=3)
    assert e.value.parameter == "no_such_knob"
    with pytest.raises(errors.RegistrationParameterError) as e:
        bsv.register(cloud, alpha="big")
    assert e.value.parameter == "alpha"
    with pytest.raises(errors.RegistrationInputError) as e:
        bsv.register(cloud[:10])
    assert isinstance(e.value, errors.RegistrationError) and isinstance(e.value, errors.InputError)
    with pytest.raises(errors.RegistrationInputError, match="millimetres"):
        bsv.register(cloud * 1000.0)
    bad = cloud.copy()
    bad[7] = np.nan
    with pytest.raises(errors.RegistrationInputError) as e:
        bsv.register(bad)
    assert e.value.index == 7
    with pytest.raises(errors.RegistrationInputError) as e:
        bsv.register(cloud, label_source="template", template=bsv.Mesh(*unit_cube()))
    assert e.value.parameter == "labels"


def test_a_raising_progress_callback_stops_the_fit_and_propagates() -> None:
    t = bsv.default_template()
    c = bsv.scan(t, "noer", seed=0)
    calls: list[dict] = []

    def stop(it: dict) -> None:
        calls.append(it)
        raise KeyError("stop here")

    with pytest.raises(KeyError, match="stop here"):
        bsv.register(c, progress=stop, schedule="m2p:3")
    assert len(calls) == 1 and calls[0]["iteration"] == 0 and "energy" in calls[0]


def test_other_extension_errors() -> None:
    t = bsv.default_template()
    with pytest.raises(errors.ScanError, match="condition"):
        bsv.scan(t, "sunny")
    with pytest.raises(errors.InputError) as e:
        _bsv.build_cloud([], {"no_such": 1})
    assert e.value.parameter == "no_such"


def test_structured_attributes_survive_pickling(tmp_path: Path) -> None:
    with pytest.raises(errors.FormatError) as e:
        bsv.read_mesh(tmp_path / "x.ply")
    again = pickle.loads(pickle.dumps(e.value))
    assert type(again) is errors.FormatError and again.path == e.value.path and str(again) == str(e.value)

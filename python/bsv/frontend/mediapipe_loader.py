"""MediaPipe's Holistic solution, imported without the drawing helpers that BSV does not use.

``import mediapipe`` runs ``mediapipe.python.solutions``, which imports ``drawing_utils`` and ``drawing_styles``;
``drawing_utils`` imports ``matplotlib.pyplot``. In a fresh ``bsv process`` that is 0.5-0.7 s of the 0.8-0.9 s
the import costs, on the path to the first detection (the report draws later, without pyplot). It also runs
``mediapipe.tasks.python``, the Tasks API (audio, text, vision, genai; 0.09 s, PortAudio looked up for the
audio tasks), which the Holistic solution does not use.
:func:`holistic` first puts a stand-in for each of these modules in ``sys.modules``: a module that loads
the real one the first time one of its names is read. The Holistic graph never reads them; a caller who does
(``mediapipe.solutions.drawing_utils.draw_landmarks``, ``mediapipe.tasks.python.vision.PoseLandmarker``) gets
the real module, only later. The Tasks package's stand-in carries the package's ``__path__``, so that
``import mediapipe.tasks.python.vision`` imports that submodule as usual (once: the real package's own
``from . import vision`` then finds it imported).

With MediaPipe imported already, or a wheel laid out otherwise (other versions), the import is the plain one.
"""

from __future__ import annotations

import importlib
import importlib.util
import sys
import threading
from pathlib import Path
from types import ModuleType
from typing import Any

#: The solution BSV runs.
HOLISTIC_MODULE = "mediapipe.python.solutions.holistic"
#: The modules :func:`holistic` defers, with their files in the mediapipe wheel (a package's ``__init__.py``).
DEFERRED: dict[str, str] = {
    "mediapipe.python.solutions.drawing_utils": "python/solutions/drawing_utils.py",
    "mediapipe.python.solutions.drawing_styles": "python/solutions/drawing_styles.py",
    "mediapipe.tasks.python": "tasks/python/__init__.py",
}

#: Parent packages of :data:`DEFERRED` that the import of ``mediapipe`` would import only on the way to a
#: deferred module (:func:`_defer_unused` imports them itself), with their ``__init__.py``.
EMPTY_PARENTS: dict[str, str] = {"mediapipe.tasks": "tasks/__init__.py"}

_LOAD_LOCK = threading.Lock()


def _load_real(name: str, path: Path) -> ModuleType:
    """Imports module ``name`` from ``path`` in place of its stand-in (once) and returns it."""
    with _LOAD_LOCK:
        current = sys.modules.get(name)
        if current is not None and not getattr(current, "__bsv_deferred__", False):
            return current
        package = [str(path.parent)] if path.name == "__init__.py" else None
        spec = importlib.util.spec_from_file_location(name, path, submodule_search_locations=package)
        if spec is None or spec.loader is None:  # not a Python file any more: the plain import
            sys.modules.pop(name, None)
            return importlib.import_module(name)
        real = importlib.util.module_from_spec(spec)
        stand_in = sys.modules.get(name)
        if stand_in is not None:  # submodules imported through the stand-in's __path__ meanwhile
            for key, value in vars(stand_in).items():
                if isinstance(value, ModuleType) and not key.startswith("__"):
                    setattr(real, key, value)
        sys.modules[name] = real
        try:
            spec.loader.exec_module(real)
        except BaseException:
            if stand_in is not None:
                sys.modules[name] = stand_in
            else:
                sys.modules.pop(name, None)
            raise
        parent, _, child = name.rpartition(".")
        if parent in sys.modules:
            setattr(sys.modules[parent], child, real)
        return real


def _stand_in(name: str, path: Path) -> ModuleType:
    """A module named ``name`` whose every other name is read from the real module, loaded on first use."""
    mod = ModuleType(name, f"Stand-in for {name}, loaded from {path} on first use (bsv.frontend.mediapipe_loader).")
    mod.__file__ = str(path)
    if path.name == "__init__.py":  # a package: its submodules import as usual
        mod.__path__ = [str(path.parent)]
        mod.__package__ = name

    def __getattr__(attr: str) -> Any:  # PEP 562's module __getattr__
        if attr == "__path__":  # the import system asking whether a module is a package (a package's
            raise AttributeError(attr)  # stand-in has its own __path__)
        return getattr(_load_real(name, path), attr)

    def __dir__() -> list[str]:  # PEP 562's module __dir__
        return dir(_load_real(name, path))

    mod.__getattr__ = __getattr__  # type: ignore[method-assign]
    mod.__dir__ = __dir__  # type: ignore[method-assign]
    mod.__bsv_deferred__ = True  # type: ignore[attr-defined]
    return mod


def _defer_unused() -> dict[str, ModuleType]:
    """Puts the stand-ins of :data:`DEFERRED` and the packages of :data:`EMPTY_PARENTS` in ``sys.modules`` when
    mediapipe is not imported yet and its wheel has the files; returns them (empty otherwise)."""
    if "mediapipe" in sys.modules:
        return {}
    try:
        spec = importlib.util.find_spec("mediapipe")  # finds the package without running it
    except (ImportError, ValueError):
        return {}
    if spec is None or not spec.submodule_search_locations:
        return {}
    root = Path(next(iter(spec.submodule_search_locations)))
    paths = {name: root / rel for name, rel in DEFERRED.items()}
    if not all(p.is_file() for p in paths.values()):
        return {}
    stand_ins = {name: _stand_in(name, p) for name, p in paths.items() if name not in sys.modules}
    # A stand-in found in sys.modules is not imported, so neither is its parent package: ``mediapipe.tasks``
    # (an empty package, its docstring only) is imported here, before ``import mediapipe.tasks.python as
    # tasks`` in mediapipe's __init__ looks it up.
    parents: dict[str, ModuleType] = {}
    for parent, rel in EMPTY_PARENTS.items():
        if parent not in sys.modules:
            package = _empty_package(parent, root / rel)
            if package is None:  # not the empty package expected: the plain import
                return {}
            parents[parent] = package
    sys.modules.update(parents)
    sys.modules.update(stand_ins)
    return {**parents, **stand_ins}


def _empty_package(name: str, init: Path) -> ModuleType | None:
    """Package ``name`` from its ``__init__.py``, imported when that file imports nothing (the parent of a
    stand-in, see :func:`_defer_unused`); None otherwise."""
    import ast

    try:
        tree = ast.parse(init.read_text(encoding="utf-8"))
    except (OSError, SyntaxError, UnicodeDecodeError):
        return None
    if any(not (isinstance(n, ast.Expr) and isinstance(n.value, ast.Constant)) for n in tree.body):
        return None
    spec = importlib.util.spec_from_file_location(name, init, submodule_search_locations=[str(init.parent)])
    if spec is None or spec.loader is None:
        return None
    module = importlib.util.module_from_spec(spec)
    try:
        spec.loader.exec_module(module)
    except Exception:  # a docstring cannot fail; the plain import says what does
        return None
    return module


def holistic() -> ModuleType:
    """``mediapipe.python.solutions.holistic``, imported with the drawing helpers and the Tasks API deferred
    (module doc). ImportError as the plain import raises it."""
    stand_ins = _defer_unused()
    try:
        module = importlib.import_module(HOLISTIC_MODULE)
    except BaseException:
        for name, mod in stand_ins.items():  # leave nothing of ours behind a failed import
            if sys.modules.get(name) is mod:
                del sys.modules[name]
        raise
    for name, mod in stand_ins.items():  # ``mediapipe.solutions.drawing_utils`` as the plain import gives it
        parent, _, child = name.rpartition(".")
        if parent in sys.modules and sys.modules.get(name) is mod and not hasattr(sys.modules[parent], child):
            setattr(sys.modules[parent], child, mod)
    return module


__all__ = ["DEFERRED", "EMPTY_PARENTS", "HOLISTIC_MODULE", "holistic"]

"""Base classes of the bodies' errors: ``bsv.BsvError`` and ``bsv.errors.OutputExistsError``.

Both come from the Rust extension when it is built; without it local stand-ins are used, so that
``bsv.bodies`` (numpy only) stays importable on its own (as :mod:`bsv.frontend.errors` does).
"""

from __future__ import annotations

try:  # the extension's base class, so `except bsv.BsvError` catches the bodies' errors too
    from .._bsv import BsvError  # type: ignore[attr-defined]
except ImportError:  # pragma: no cover - exercised only when the extension is not built

    class BsvError(Exception):  # type: ignore[no-redef]
        """Stand-in for ``bsv._bsv.BsvError`` when the Rust extension is not built."""


try:
    from ..errors import OutputExistsError
except ImportError:  # pragma: no cover - exercised only when the extension is not built

    class OutputExistsError(BsvError, FileExistsError):  # type: ignore[no-redef]
        """Stand-in for ``bsv.errors.OutputExistsError``: an output exists and overwriting was not asked for."""


__all__ = ["BsvError", "OutputExistsError"]

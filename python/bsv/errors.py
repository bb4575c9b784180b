"""Python-side exception classes; every BSV error derives from :class:`bsv.BsvError`."""

from __future__ import annotations

from ._bsv import BsvError, InputError


class OutputExistsError(BsvError, FileExistsError):
    """An output file or folder exists and overwriting was not asked for (``overwrite=True``, ``--overwrite``)."""


__all__ = ["BsvError", "InputError", "OutputExistsError"]

"""The errors the bodies raise, re-exported from :mod:`bsv.errors` (where every BSV exception is defined)."""

from __future__ import annotations

from ..errors import (
    AssetError,
    BsvError,
    LabelError,
    OutputExistsError,
    PhenotypeError,
    PoseError,
    SolveError,
    TemplateError,
)

__all__ = [
    "AssetError", "BsvError", "LabelError", "OutputExistsError", "PhenotypeError", "PoseError", "SolveError",
    "TemplateError",
]

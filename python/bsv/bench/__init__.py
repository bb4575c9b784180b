"""BSV validation benchmarks (DESIGN.md "Validation protocol"): the synthetic cohort x four error
conditions (``synth``), the paper's two boxes (``boxes``), MPI-FAUST when the user has it (``faust``),
the calibration error floor and the trimesh peer. Command line: ``bsv bench ...`` (:func:`main`);
documentation: benchmarks/BENCH.md."""

from __future__ import annotations

from .common import BenchError, Fit, Run, rve, signed_error
from .main import main

__all__ = ["BenchError", "Fit", "Run", "main", "rve", "signed_error"]

"""``bsv batch INPUTS... --out DIR``: the command line of :mod:`bsv.batch`."""

from __future__ import annotations

import argparse
from collections.abc import Sequence

from .cluster import LOCAL
from .state import WHATS


def _positive(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not value > 0:
        raise argparse.ArgumentTypeError(f"{value} must be > 0")
    return value


def _check_installed() -> None:
    """A clear usage error when the batch extra is not installed (instead of an ImportError traceback)."""
    import importlib.util

    from ..errors import BatchInputError

    missing = [m for m in ("distributed", "pyarrow") if importlib.util.find_spec(m) is None]
    if missing:
        raise BatchInputError(f"bsv batch needs {' and '.join(missing)}: pip install 'bsv[batch]' "
                              "(or pip install -r requirements-batch.txt)")


def parser() -> argparse.ArgumentParser:
    """The argument parser of ``bsv batch``."""
    ap = argparse.ArgumentParser(prog="bsv batch", description=(
        "Process many captures or cloud files on Dask: one task per item, one results table "
        "(DIR/results.parquet and results.csv, one row per item x segment), per-item outputs in DIR/<item>/. "
        "Resumable: the same command skips the items already done with the same inputs and parameters."))
    ap.add_argument("inputs", nargs="+", help="capture folders, cloud files (.ply) or manifests (.csv/.parquet with a "
                    "'path' column; optional 'name', 'calibration')")
    ap.add_argument("--out", "-o", required=True, help="output folder (new, empty, or this batch's folder)")
    ap.add_argument("--scheduler", default=LOCAL, help="'local' (a LocalCluster on this machine, default) or the "
                    "address of a running Dask scheduler, e.g. tcp://head:8786 (Slurm: dask-jobqueue; Kubernetes: "
                    "dask-kubernetes)")
    ap.add_argument("--workers", type=int, default=2, help="with --scheduler local: worker processes, one thread "
                    "each (default 2)")
    ap.add_argument("--what", choices=WHATS, default="volumes", help="volumes: fitted.ply + volumes.json per item "
                    "(capture items always get bsv process's full outputs); report: also report.html for clouds")
    ap.add_argument("--calibration", help="calibration file of every capture item (default: each capture's own "
                    "calibration.json; a manifest's 'calibration' column wins)")
    ap.add_argument("--segmentation", choices=("camera", "oracle"), default="camera",
                    help="capture items: camera = MediaPipe (default); oracle = the virtual scanner's labels")
    ap.add_argument("--param", action="append", default=[], metavar="KEY=VALUE",
                    help="registration parameter (repeatable), e.g. --param schedule=m2p:5,p2m:5,m2p:10")
    ap.add_argument("--density", type=_positive, default=1000.0, help="body density kg/m^3 for the mass (default 1000)")
    ap.add_argument("--timeout", type=_positive, help="seconds one item may run; a task past it is cancelled and "
                    "recorded as failed (default: no limit)")
    ap.add_argument("--retries", type=int, default=1, help="re-runs of a task that raised an unexpected error "
                    "(default 1; a bad input is never retried, a dead worker's task always is)")
    ap.add_argument("--rerun-failed", action="store_true", help="run again the items whose recorded result is a "
                    "failure with the same inputs and parameters (default: skip them)")
    ap.add_argument("--no-dashboard", action="store_true", help="do not start the Dask dashboard")
    ap.add_argument("--quiet", action="store_true", help="no progress bar")
    return ap


def main(argv: Sequence[str] | None = None) -> int:
    """Runs ``bsv batch``; returns the exit status (0 all done, 1 some item failed, 2 fix the call)."""
    a = parser().parse_args(list(argv) if argv is not None else None)
    from ..exitcodes import run_command
    from ..pipeline import _register_args

    def run() -> int:
        _check_installed()
        from .items import collect_items
        from .runner import run_batch, summary_text
        from .state import Spec

        spec = Spec(what=a.what, segmentation=a.segmentation, density=a.density, params=_register_args(a.param))
        items = collect_items(a.inputs, a.calibration)
        res = run_batch(items, a.out, spec, scheduler=a.scheduler, workers=a.workers, timeout=a.timeout,
                        retries=max(0, a.retries), rerun_failed=a.rerun_failed, progress=not a.quiet,
                        dashboard=not a.no_dashboard)
        print(summary_text(res))
        return res.exit_code

    return run_command("bsv batch", run)


if __name__ == "__main__":
    raise SystemExit(main())

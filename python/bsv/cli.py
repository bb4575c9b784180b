"""The ``bsv`` console script: one entry point for the lab and benchmark workflows.

``bsv demo``, ``bsv process``, ``bsv calibrate``, ``bsv capture``, ``bsv bench``, ``bsv cohort``.
Single-file tools (info, volume, scan, register, template) are in the Rust binary ``bsv-cli``.
Each sub-command lives in its module; this file only routes.
"""

from __future__ import annotations

import argparse
import gc
import sys
from collections.abc import Callable
from typing import NoReturn

USAGE = """usage: bsv <command> [options]

commands:
  demo        the whole chain on a synthetic subject (virtual capture -> segmentation -> cloud ->
              registration -> report), no camera needed
  process     CAPTURE_DIR --calibration calibration.json -o OUT: volumes and report of a capture
  calibrate   per-camera extrinsics from ArUco marker images (or --live alignment window)
  capture     record both RealSense cameras (or replay recordings with --from-recording)
  bench       synth | boxes | faust: the validation benchmark tables and figures
  cohort      OUT N [SEED]: write a synthetic MakeHuman cohort (labelled PLY + ground truth)
  batch       INPUTS... --out DIR: many captures / cloud files on Dask, resumable, one results table
  station     the operator's web app: subjects, captures, follow-up comparison (--demo: virtual rig)

Run `bsv <command> --help` for the options of a command. Lengths are metres, volumes litres.
"""


def _capture_main(argv: list[str]) -> int:
    from .argtypes import real
    from .frontend.capture import CaptureConfig, capture

    ap = argparse.ArgumentParser(prog="bsv capture", description="Capture (or replay) the two RealSense cameras.")
    ap.add_argument("out_dir", help="folder receiving <camera>/color.png, depth.png, camera.json, recording.db3")
    ap.add_argument("--front", help="serial number of the front camera")
    ap.add_argument("--back", help="serial number of the back camera")
    ap.add_argument("--seconds", type=real(0.1, 3600.0, "--seconds"), default=5.0,
                    help="still acquisition time (default 5 s)")
    ap.add_argument("--d4xx", action="store_true", help="D4xx stream defaults instead of L515")
    ap.add_argument("--from-recording", action="store_true", help="replay OUT_DIR/<camera>/recording.db3")
    ap.add_argument("--overwrite", action="store_true", help="replace files already in OUT_DIR")
    a = ap.parse_args(argv)
    config = CaptureConfig.d4xx() if a.d4xx else CaptureConfig()
    config = type(config)(**{**config.__dict__, "duration_s": a.seconds})
    serials = None
    if a.front or a.back:
        serials = {k: v for k, v in (("front", a.front), ("back", a.back)) if v}
    caps = capture(a.out_dir, serials, config, from_recording=a.from_recording, overwrite=a.overwrite)
    for name, cam in caps.items():
        print(f"{name}: {cam}")
    return 0


def _cohort_main(argv: list[str]) -> int:
    from .bodies.cohort import main

    return main(argv)


def _route(name: str) -> Callable[[list[str]], int | None] | None:
    if name == "demo":
        from .pipeline import main_demo

        return main_demo
    if name == "process":
        from .pipeline import main_process

        return main_process
    if name == "calibrate":
        from .frontend.calibrate import main as calibrate_main

        return calibrate_main
    if name == "capture":
        return _capture_main
    if name == "bench":
        from .bench import main as bench_main

        return bench_main
    if name == "cohort":
        return _cohort_main
    if name == "batch":
        from .batch.main import main as batch_main

        return batch_main
    if name == "station":
        from .station.cli import main as station_main

        return station_main
    return None


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``bsv`` console script; returns the exit status."""
    args = list(sys.argv[1:] if argv is None else argv)
    if not args or args[0] in ("-h", "--help", "help"):
        print(USAGE)
        return 0
    if args[0] in ("-V", "--version"):
        from . import __version__

        print(f"bsv {__version__}")
        return 0
    handler = _route(args[0])
    if handler is None:
        print(f"bsv: unknown command {args[0]!r}\n\n{USAGE}", file=sys.stderr)
        return 2
    from .exitcodes import run_command

    return run_command(f"bsv {args[0]}", lambda: handler(args[1:]))


def console() -> NoReturn:
    """The ``bsv`` console script: :func:`main`, then exit with its status. What the command leaves in memory
    is moved out of the garbage collector's reach first (:func:`gc.freeze`): the process ends and the system
    reclaims it all, while the interpreter's collections at exit would walk MediaPipe's, matplotlib's and
    WeasyPrint's objects for 0.1-0.3 s. Every file is written and closed before :func:`main` returns."""
    status = main()
    gc.freeze()
    sys.exit(status)


if __name__ == "__main__":
    console()

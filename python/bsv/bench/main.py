"""``bsv bench synth|boxes|faust``: command-line entry point of the benchmarks (see benchmarks/BENCH.md)."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from typing import Any

from ..argtypes import key_value, seed, whole
from ..bodies.cohort import (
    ARM_DOWN_RANGE_DEG,
    ELBOW_RANGE_DEG,
    HEAVY_BMI_SHIFT,
    HIP_ABDUCTION_RANGE_DEG,
    MACRO_RANGES,
    PALM_IN_RANGE_DEG,
    TURN_RANGE_DEG,
    arm_down_help,
    arm_range_arg,
    bmi_shift_arg,
    elbow_help,
    elbow_range_arg,
    leg_range_arg,
    palm_in_help,
    palm_range_arg,
    turn_help,
    turn_range_arg,
)
from .compare import DEFAULT_MAX_GAP
from .reference import CONDITIONS
from .synth import COHORTS, SynthConfig


def _conditions(text: str) -> tuple[str, ...]:
    items = tuple(c.strip().lower() for c in text.split(",") if c.strip())
    bad = [c for c in items if c not in CONDITIONS]
    if bad or not items:
        raise argparse.ArgumentTypeError(f"{text!r}: use a comma list of {','.join(CONDITIONS)}")
    return items


def _ints(text: str) -> tuple[int, ...]:
    try:
        return tuple(int(x) for x in text.split(",") if x.strip())
    except ValueError as exc:
        raise argparse.ArgumentTypeError(f"{text!r}: use a comma list of integers, e.g. 0,10,20") from exc


_param = key_value


def _labels(text: str) -> tuple[str, str]:
    items = [t.strip() for t in text.split(",")]
    if len(items) != 2 or not all(items):
        raise argparse.ArgumentTypeError(f"{text!r}: give two names, e.g. camera,oracle")
    return items[0], items[1]


def _points(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not (value >= 0 and value < float("inf")):
        raise argparse.ArgumentTypeError(f"{text!r}: give a number of points >= 0, e.g. 1")
    return value


def dask_options(p: argparse.ArgumentParser, what: str) -> None:
    """``--scheduler`` and ``--jobs``: run the benchmark's items (``what``) as tasks on the ``bsv batch`` Dask cluster."""
    p.add_argument("--scheduler", default=None, help=f"run the {what} as Dask tasks: 'local' (a LocalCluster of "
                   "--jobs one-thread workers) or a running scheduler's address, e.g. tcp://head:8786 "
                   "(default: in this process, or a LocalCluster when --jobs > 1)")
    p.add_argument("--jobs", type=int, default=1, help=f"workers of the local Dask cluster over {what} (default 1: "
                   "no cluster unless --scheduler)")


def parser() -> argparse.ArgumentParser:
    """The argument parser of ``bsv bench``."""
    ap = argparse.ArgumentParser(prog="bsv bench", description=(
        "Validation benchmarks. Volumes in litres, RVE = |V_est - V_true| / V_true in %. "
        "Outputs: results.json, results.csv, report.md and PNG figures in --out."))
    sub = ap.add_subparsers(dest="command", required=True)

    def common(p: argparse.ArgumentParser, out: str) -> None:
        p.add_argument("--out", default=out, help=f"output folder (default {out}); existing outputs in it are "
                       "refused unless --overwrite")
        p.add_argument("--overwrite", action="store_true",
                       help="replace results.json, results.csv, report.md and figures already in --out")
        p.add_argument("--peer", choices=["trimesh"], help="also run trimesh.registration.nricp_amberg (pip install 'bsv[peer]')")
        p.add_argument("--param", action="append", type=_param, default=[], metavar="KEY=VALUE",
                       help="registration parameter passed to bsv.register (repeatable), e.g. --param alpha=1e6")
        p.add_argument("--quiet", action="store_true", help="no progress bar")

    s = sub.add_parser("synth", help="synthetic cohort x error conditions (the paper's protocol without FAUST)")
    s.add_argument("--n", type=whole(1, 100_000, "--n subjects"), default=10, help="cohort size (half female; default 10)")
    s.add_argument("--seed", type=seed, default=0, help="cohort seed (default 0)")
    s.add_argument("--conditions", type=_conditions, default=CONDITIONS, help="comma list of noer,l515,cali,l5ca")
    dask_options(s, "subjects")
    s.add_argument("--segmentation", choices=["oracle", "camera"], default="oracle",
                   help="oracle: scanner's true labels; camera: MediaPipe on the colour renders (needs bsv.frontend.segment)")
    s.add_argument("--cloud", choices=["raw", "lab"], default="raw",
                   help="raw: the scanner's cloud; lab: rebuilt from the capture images like bsv process (slower)")
    s.add_argument("--cloud-param", action="append", type=_param, default=[], metavar="KEY=VALUE",
                   help="cloud-building parameter of the lab/camera path (repeatable; default bsv process's), "
                   "e.g. --cloud-param sor=true or --cloud-param isolate_person=false")
    s.add_argument("--room", action=argparse.BooleanOptionalAction, default=None,
                   help="render the rig inside a clinic room (floor, walls, varied subject appearance); "
                   "default: on for --segmentation camera or --cloud lab, off for the raw oracle cloud")
    s.add_argument("--studio", action="store_true",
                   help="with a room: the subject dressed and lit as in the room but no floor, walls or ceiling "
                   "(compare with the room to see what the floor and walls do)")
    s.add_argument("--long-hair", action="store_true",
                   help="with a room: every subject with hair wears it long, down over the neck and the upper "
                   "back (the back camera's view; compare with the same seed without it)")
    s.add_argument("--top", action="store_true",
                   help="with a room: every subject wears a top in the underwear's colour over the chest")
    s.add_argument("--smooth-shading", action="store_true",
                   help="with a room: the subject's skin shaded smoothly (normals interpolated from the mesh's "
                   "vertex normals, as skin looks and most renderers draw it) instead of the rig's faceted "
                   "default (compare with the same seed without it: what the renderer does to the camera path)")
    s.add_argument("--colour-sensor", action="store_true",
                   help="with a room: the colour images blurred and noisy as a camera's sensor records them "
                   "(a Gaussian of 0.7 px, shot and read noise of about 3 levels at mid-grey) instead of the "
                   "render's exact pixels")
    s.add_argument("--refine-calibration", action="store_true",
                   help="in cali and l5ca, also refine each capture's calibration as a user would (the rig's "
                   "board view: bsv calibrate --depth; the floor: bsv process --refine-floor), register the "
                   "cloud built with it again and report the intervals with the refined covariance next to the "
                   "paper's, and the floor before and after (a board scan and a second registration per "
                   "calibrated run: ~1.5 s each)")
    s.add_argument("--template", default="default",
                   help="default, fine, sex (each subject's sex's template, as bsv process --sex) or a labelled "
                        "mesh path")
    s.add_argument("--no-local", action="store_true", help="cohort without MakeHuman local modifiers")
    s.add_argument("--arm-down", type=arm_range_arg, default=ARM_DOWN_RANGE_DEG, metavar="LOW,HIGH",
                   help=f"{arm_down_help()}; the camera path's shoulder boundary moves with the arms")
    s.add_argument("--palm-in", type=palm_range_arg, default=PALM_IN_RANGE_DEG, metavar="LOW,HIGH",
                   help=f"{palm_in_help()}; the camera path turns the template's forearms as it measures the palms")
    s.add_argument("--turn", type=turn_range_arg, default=TURN_RANGE_DEG, metavar="LOW,HIGH", help=turn_help())
    s.add_argument("--elbow", type=elbow_range_arg, default=ELBOW_RANGE_DEG, metavar="LOW,HIGH", help=elbow_help())
    lo, hi = HIP_ABDUCTION_RANGE_DEG
    s.add_argument("--hip-abduction", type=leg_range_arg, default=HIP_ABDUCTION_RANGE_DEG, metavar="LOW,HIGH",
                   help=f"the interval each thigh's angle outward of the vertical is drawn from, degrees (default "
                        f"{lo:g},{hi:g}; 0,1.5 for a narrow stance, where heavier subjects' thighs touch below the "
                        "crotch)")
    s.add_argument("--bmi-shift", type=bmi_shift_arg, default=0.0, metavar="KG_M2",
                   help=f"added to every subject's drawn BMI (default 0: 25 +- 4 within 18.5-35; {HEAVY_BMI_SHIFT:g} for a "
                        "heavier cohort)")
    s.add_argument("--macros", choices=tuple(MACRO_RANGES), default="standard",
                   help="the ranges MakeHuman's gender, muscle and proportions are drawn from (default standard: each "
                        "sex at its end of the gender scale, muscle 0.3-0.6, proportions 0.3-0.7; wide: gender anywhere "
                        "on the sex's half, androgynous bodies included, muscle and proportions 0.1-0.9)")
    s.add_argument("--cohort", choices=COHORTS, default="standard",
                   help="standard: bsv.bodies.cohort; hard: the same subjects reshaped into the registration's "
                   "hard classes (deep upper arms, bumps, a swollen segment, extreme segment modifiers; "
                   "bsv.bodies.variants.hard_subject)")
    common(s, "bench_synth")

    b = sub.add_parser("boxes", help="the paper's two boxes at 45 deg, noer and l5ca")
    b.add_argument("--seeds", type=whole(1, 10_000, "--seeds per box"), default=3, help="scan seeds per box and condition (default 3)")
    b.add_argument("--conditions", type=_conditions, default=("noer", "l5ca"), help="default noer,l5ca")
    common(b, "bench_boxes")

    f = sub.add_parser("faust", help="MPI-FAUST training scans (not bundled: point --root at your copy)")
    f.add_argument("--root", required=True, help="MPI-FAUST folder holding training/scans and training/registrations")
    f.add_argument("--scans", type=_ints, default=None, help="scan numbers (default: one A-pose-like scan per subject)")
    f.add_argument("--conditions", type=_conditions, default=CONDITIONS, help="comma list of noer,l515,cali,l5ca")
    f.add_argument("--seed", type=seed, default=0, help="scan seed (default 0)")
    dask_options(f, "scans")
    common(f, "bench_faust")

    c = sub.add_parser("compare", help="two sets of `bench synth` runs of the same bodies, segment by segment "
                       "(e.g. the camera path against the oracle labels)")
    c.add_argument("--runs", nargs="+", required=True, metavar="DIR",
                   help="--out folders of `bench synth` runs (one per cohort seed), e.g. the camera path's")
    c.add_argument("--against", nargs="+", required=True, metavar="DIR",
                   help="--out folders of runs of the same bodies to compare with, e.g. the oracle labels'")
    c.add_argument("--labels", type=_labels, default=None, metavar="FIRST,SECOND",
                   help="the two sets' names in the table (default: their segmentation when that differs, else "
                   "the first folder's name)")
    c.add_argument("--max-gap", type=_points, default=DEFAULT_MAX_GAP, metavar="POINTS",
                   help=f"mark a segment whose mean RVE is more than this above the second set's (default "
                   f"{DEFAULT_MAX_GAP:g}: issue 12's camera-path target)")
    c.add_argument("--out", default=None, help="also write compare.md, compare.json and compare.png into this "
                   "folder (refused if they exist, unless --overwrite)")
    c.add_argument("--overwrite", action="store_true", help="replace compare.* already in --out")
    return ap


def _methods(args: argparse.Namespace) -> tuple[str, ...]:
    return ("bsv",) + ((args.peer,) if args.peer else ())


def synth_config(args: argparse.Namespace) -> SynthConfig:
    """The :class:`SynthConfig` of parsed ``bsv bench synth`` arguments (:func:`parser`), not yet validated."""
    return SynthConfig(n=args.n, seed=args.seed, conditions=args.conditions, segmentation=args.segmentation,
                       template=args.template, methods=_methods(args), params=dict(args.param),
                       local=not args.no_local, cloud=args.cloud, room=args.room, studio=args.studio,
                       long_hair=args.long_hair, top=args.top, smooth_shading=args.smooth_shading,
                       colour_sensor=args.colour_sensor,
                       cloud_params=dict(args.cloud_param), cohort=args.cohort,
                       refine_calibration=args.refine_calibration, arm_range=args.arm_down,
                       leg_range=args.hip_abduction, bmi_shift=args.bmi_shift, macros=args.macros,
                       palm_range=args.palm_in, turn_range=args.turn, elbow_range=args.elbow)


def synth_record(cfg: SynthConfig, args: argparse.Namespace) -> dict[str, Any]:
    """The ``config`` block a ``bsv bench synth`` run writes to results.json and report.md: ``cfg``
    (:func:`synth_config`) plus the run's ``--jobs`` and ``--scheduler``."""
    return {"n": cfg.n, "seed": cfg.seed, "conditions": ",".join(cfg.conditions),
            "segmentation": cfg.segmentation, "cloud": cfg.cloud,
            "room": ("studio" if cfg.studio else "clinic") if cfg.uses_room() else False,
            "long_hair": cfg.long_hair and cfg.uses_room(), "top": cfg.top and cfg.uses_room(),
            "smooth_shading": cfg.smooth_shading and cfg.uses_room(),
            "colour_sensor": cfg.colour_sensor and cfg.uses_room(),
            "cloud_params": cfg.cloud_params, "template": cfg.template, "methods": ",".join(cfg.methods),
            "params": cfg.params, "local_modifiers": cfg.local, "jobs": args.jobs,
            "cohort": cfg.cohort, "arm_down_deg": list(cfg.arm_range),
            "hip_abduction_deg": list(cfg.leg_range), "palm_in_deg": list(cfg.palm_range),
            "turn_deg": list(cfg.turn_range), "elbow_deg": list(cfg.elbow_range),
            "bmi_shift": cfg.bmi_shift, "macros": cfg.macros,
            "scheduler": args.scheduler,
            "refine_calibration": cfg.refine_calibration}


def main(argv: Sequence[str] | None = None) -> int:
    """Runs ``bsv bench ...``; returns the process exit code (0 ok, 1 some run failed, 2 bad usage or
    outputs already in --out without --overwrite)."""
    args = parser().parse_args(list(sys.argv[1:] if argv is None else argv))
    from ..exitcodes import run_command

    if args.command == "compare":
        from .compare import main_compare

        return run_command("bsv bench compare", lambda: main_compare(args.runs, args.against, args.labels,
                                                                      args.max_gap, args.out, args.overwrite))
    params = dict(args.param)
    methods = _methods(args)

    def run() -> int:
        from .output import check_outputs

        check_outputs(args.out, args.overwrite)  # before any work: a run can take an hour
        from .. import RegisterParams
        from .common import BENCH_ONLY_PARAMS
        from .outliers import split_request

        RegisterParams(**{k: v for k, v in split_request(params)[1].items() if k not in BENCH_ONLY_PARAMS})  # a bad --param fails now, not in every run
        if args.command == "synth":
            from .output import write_outputs
            from .synth import run_synth

            cfg = synth_config(args)
            cfg.validate()
            infos, runs, wall = run_synth(cfg, jobs=max(1, args.jobs), progress=not args.quiet,
                                          scheduler=args.scheduler)
            summary = write_outputs(args.out, "BSV synthetic benchmark", synth_record(cfg, args), infos, runs, wall,
                                    overwrite=args.overwrite)
        elif args.command == "boxes":
            from .boxes import run_boxes

            runs, summary = run_boxes(args.out, seeds=args.seeds, conditions=args.conditions, methods=methods,
                                      params=params, progress=not args.quiet, overwrite=args.overwrite)
        else:
            from .faust import run_faust

            runs, summary = run_faust(args.root, args.out, scans=args.scans, conditions=args.conditions,
                                      seed=args.seed, methods=methods, params=params, progress=not args.quiet,
                                      overwrite=args.overwrite, jobs=max(1, args.jobs), scheduler=args.scheduler)
        _print_summary(summary)
        print(f"wrote {args.out}/report.md, results.json, results.csv")
        return 0 if all(r.ok for r in runs) else 1

    return run_command(f"bsv bench {args.command}", run)


def _print_summary(summary: dict) -> None:
    for m, conds in summary.items():
        for c, segs in conds.items():
            tl = segs.get("trunk_limbs")
            if tl is None:
                continue
            extra = f"  floor {tl['floor_rve_mean']:.2f} %" if "floor_rve_mean" in tl else ""
            print(f"{m:8s} {c:5s} trunk_limbs RVE {tl['rve_mean']:.2f} ± {tl['rve_std']:.2f} %  "
                  f"signed {tl['signed_mean']:+.2f} %{extra}")


if __name__ == "__main__":
    raise SystemExit(main())

"""A deterministic synthetic cohort of plausible adults with ground-truth segment volumes.

Subject i of seed s depends only on (s, i): even indices are women, odd indices men. Stature is drawn
from normal distributions (women 1.63 +- 0.065 m, men 1.77 +- 0.07 m, clipped at 2.5 sd), BMI from a
normal 25 +- 4 truncated to [18.5, 35], age 20-65 years, a muscle start value 0.3-0.6, proportions
0.3-0.7, random race mix; A-pose: arms 25-50 deg below horizontal (``arm_range``: 15-60 for wide A-poses), elbows 0-20 deg, hips 0-6 deg
(small left/right differences). MakeHuman LOCAL modifiers (stomach, buttocks, hip, pelvis, torso,
breast, arms, legs) are applied by default: each modifier with probability 1/2, value uniform in
+-0.6; left/right pairs share a value except with probability 1/5 (asymmetric). Height and weight
(then muscle) are solved for the drawn stature and BMI. A body whose arms enter the torso or thighs, or
whose thighs enter each other, has its arms raised / legs spread step by step until it is free.
"""

from __future__ import annotations

import json
from collections.abc import Iterator
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from ..errors import OutputExistsError
from .body import Body, SolveError, make_body, solve_stature_bmi
from .collide import penetrations
from .meshio import ply_bytes
from .model import Phenotype
from .pose import Pose, PoseError

LOCAL_CENTRAL = ("stomach/stomach-pregnant", "stomach/stomach-tone", "buttocks/buttocks-volume",
                 "hip/hip-scale-depth", "hip/hip-scale-horiz", "pelvis/pelvis-tone", "torso/torso-scale-depth",
                 "torso/torso-scale-horiz", "torso/torso-vshape", "torso/measure-waist-circ",
                 "torso/measure-bust-circ", "torso/torso-muscle-pectoral", "breast/breast-volume-vert",
                 "breast/breast-dist")
LOCAL_SIDED = ("arms/{s}-upperarm-fat", "arms/{s}-upperarm-muscle", "arms/{s}-lowerarm-fat",
               "arms/{s}-lowerarm-muscle", "legs/{s}-upperleg-fat", "legs/{s}-upperleg-muscle",
               "legs/{s}-lowerleg-fat", "legs/{s}-lowerleg-muscle")


@dataclass
class Subject:
    """One cohort member: its draws, the solved phenotype, the pose and the posed labelled body."""

    index: int
    seed: int
    sex: str
    stature_target: float
    bmi_target: float
    phenotype: Phenotype
    pose: Pose
    body: Body
    #: What :mod:`bsv.bodies.variants` changed on the body (empty for a plain cohort member).
    variant: dict = field(default_factory=dict)

    def volumes_l(self) -> dict[str, float]:
        """Ground-truth volumes (litres): 14 segments and aggregates."""
        return self.body.volumes_l()

    def info(self) -> dict:
        """JSON-ready description (draws, phenotype, pose, measured stature/BMI)."""
        return {"index": self.index, "seed": self.seed, "sex": self.sex,
                "stature_target_m": self.stature_target, "bmi_target": self.bmi_target,
                "stature_m": self.body.stature, "bmi": self.body.bmi, "volume_l": self.body.volume_l,
                "phenotype": asdict(self.phenotype), "pose": asdict(self.pose),
                **({"variant": self.variant} if self.variant else {})}


def _draw_local(rng: np.random.Generator) -> dict[str, float]:
    out: dict[str, float] = {}
    for name in LOCAL_CENTRAL:
        if rng.random() < 0.5:
            out[name] = round(float(rng.uniform(-0.6, 0.6)), 4)
        else:
            rng.uniform()  # keep the stream aligned
    for pat in LOCAL_SIDED:
        use, val, asym, val_r = rng.random(), rng.uniform(-0.6, 0.6), rng.random(), rng.uniform(-0.6, 0.6)
        if use < 0.5:
            out[pat.format(s="l")] = round(float(val), 4)
            out[pat.format(s="r")] = round(float(val_r if asym < 0.2 else val), 4)
    return out


def _solve(ph: Phenotype, stature: float, bmi: float, pose: Pose) -> tuple[Phenotype, float]:
    """Solve, shrinking an unreachable BMI into the reachable range."""
    try:
        return solve_stature_bmi(stature, bmi, ph, pose), bmi
    except SolveError as e:
        if e.reachable is None:
            raise
        lo, hi = e.reachable
        b2 = float(np.clip(bmi, lo + 0.2, hi - 0.2))
        return solve_stature_bmi(stature, b2, ph, pose), b2


#: The cohort's arm angle below the horizontal (degrees, both sides drawn around one value): the A-pose
#: range the standard cohort covers.
ARM_DOWN_RANGE_DEG: tuple[float, float] = (25.0, 50.0)
#: A wider A-pose range (``bsv bench synth --arm-down 15,60``): arms from nearly horizontal to close to
#: the body, where the camera path's shoulder boundary moves (BENCH.md, round 2 session 10).
WIDE_ARM_DOWN_RANGE_DEG: tuple[float, float] = (15.0, 60.0)


def check_arm_range(arm_range: tuple[float, float]) -> tuple[float, float]:
    """``arm_range`` as floats, or PoseError when it is not an increasing pair inside [0, 80] degrees
    (beyond, a collision-free A-pose cannot be kept: the arm meets the head or the torso)."""
    try:
        lo, hi = (float(x) for x in arm_range)
    except (TypeError, ValueError) as exc:
        raise PoseError(f"arm range {arm_range!r}: give two angles in degrees, e.g. (25, 50)") from exc
    if not (0.0 <= lo < hi <= 80.0):
        raise PoseError(f"arm range ({lo:g}, {hi:g}) deg: need 0 <= low < high <= 80 (degrees below the horizontal)")
    return lo, hi


def subject(index: int, seed: int = 0, local: bool = True, check: bool = True,
            arm_range: tuple[float, float] = ARM_DOWN_RANGE_DEG) -> Subject:
    """Subject ``index`` of the cohort of ``seed`` (deterministic). ``arm_range``: the interval (degrees
    below the horizontal) the arms' angle is drawn from; the default keeps the cohort as it always was, a
    wider one (:data:`WIDE_ARM_DOWN_RANGE_DEG`) draws the same random numbers, so every other draw stays."""
    lo, hi = check_arm_range(arm_range)
    rng = np.random.default_rng([int(seed), int(index)])
    female = index % 2 == 0
    mu, sd = (1.63, 0.065) if female else (1.77, 0.07)
    stature = float(mu + sd * np.clip(rng.standard_normal(), -2.5, 2.5))
    bmi = float(rng.normal(25.0, 4.0))
    while not 18.5 <= bmi <= 35.0:
        bmi = float(rng.normal(25.0, 4.0))
    years = float(rng.uniform(20.0, 65.0))
    race = rng.dirichlet([1.0, 1.0, 1.0])
    ph = Phenotype(gender=float(rng.uniform(0.0, 0.15) if female else rng.uniform(0.85, 1.0)),
                   age=Phenotype.age_from_years(years), muscle=float(rng.uniform(0.3, 0.6)),
                   proportions=float(rng.uniform(0.3, 0.7)), african=float(race[0]), asian=float(race[1]),
                   caucasian=float(race[2]))
    arm, elbow, hip = rng.uniform(lo, hi), rng.uniform(0, 20), rng.uniform(0, 6)
    d = rng.normal(0, 1.5, size=3)
    pose = Pose(float(np.clip(arm + d[0], lo, hi)), float(np.clip(arm - d[0], lo, hi)),
                float(np.clip(elbow + d[1], 0, 20)), float(np.clip(elbow - d[1], 0, 20)),
                float(np.clip(hip + d[2] / 3, 0, 6)), float(np.clip(hip - d[2] / 3, 0, 6)))
    loc = _draw_local(rng)
    if local:
        ph = ph.with_(local=loc)
    ph, bmi_used = _solve(ph, stature, bmi, pose)
    body = make_body(ph, pose)
    for _ in range(12 if check else 0):
        hits = penetrations(body.vertices, body.faces, body.face_labels)
        if not hits:
            break
        arms = {"l": 0.0, "r": 0.0}
        legs = 0.0
        for k in hits:
            part = k.split("/")[0]
            if part == "thigh_l":
                legs = 1.0
            else:
                arms[part[-1]] = 3.0
                if k.endswith(("thigh_l", "thigh_r")):
                    legs = 1.0
        pose = Pose(max(pose.arm_down_l - arms["l"], 10.0), max(pose.arm_down_r - arms["r"], 10.0),
                    pose.elbow_l, pose.elbow_r, pose.hip_abduction_l + legs, pose.hip_abduction_r + legs)
        ph, bmi_used = _solve(ph, stature, bmi_used, pose)
        body = make_body(ph, pose)
    else:
        if check and penetrations(body.vertices, body.faces, body.face_labels):
            raise SolveError(f"cohort subject {index} (seed {seed}) still self-intersects after pose changes")
    return Subject(index, int(seed), "female" if female else "male", stature, bmi_used, ph, pose, body)


def cohort(n: int, seed: int = 0, local: bool = True, check: bool = True,
           arm_range: tuple[float, float] = ARM_DOWN_RANGE_DEG) -> list[Subject]:
    """``n`` plausible adults (half female), deterministic for a seed; local modifiers on by default."""
    if n < 0:
        raise ValueError(f"cohort size {n}: must be >= 0")
    return list(iter_cohort(n, seed, local, check, arm_range))


def iter_cohort(n: int, seed: int = 0, local: bool = True, check: bool = True,
                arm_range: tuple[float, float] = ARM_DOWN_RANGE_DEG) -> Iterator[Subject]:
    """Like cohort() but yields subjects one at a time."""
    for i in range(n):
        yield subject(i, seed, local, check, arm_range)


def volumes_json(s: Subject) -> str:
    """The ground-truth volumes JSON of a subject (DESIGN.md volumes format plus a "subject" block)."""
    doc = {"units": {"length": "m", "volume": "L"},
           "volumes_l": {k: round(v, 6) for k, v in s.volumes_l().items()},
           "subject": s.info()}
    return json.dumps(doc, indent=1, sort_keys=True) + "\n"


def subject_files(index: int, out_dir: str | Path) -> tuple[Path, Path]:
    """Paths of subject ``index``'s mesh and volumes files in ``out_dir``."""
    out = Path(out_dir)
    return out / f"subject_{index:03d}.ply", out / f"subject_{index:03d}.json"


def _refuse_existing(paths: list[Path], overwrite: bool) -> None:
    existing = [str(p) for p in paths if p.exists()]
    if existing and not overwrite:
        raise OutputExistsError(f"{', '.join(existing)} already exist(s); pass overwrite=True (--overwrite) to "
                                "replace, or choose another output folder")


def write_subject(s: Subject, out_dir: str | Path, overwrite: bool = False) -> tuple[Path, Path]:
    """Write ``subject_NNN.ply`` (labelled, binary little-endian) and ``subject_NNN.json`` (volumes);
    existing files are refused (:class:`bsv.errors.OutputExistsError`) unless ``overwrite``."""
    out = Path(out_dir)
    ply, js = subject_files(s.index, out)
    _refuse_existing([ply, js], overwrite)
    out.mkdir(parents=True, exist_ok=True)
    b = s.body
    ply.write_bytes(ply_bytes(b.vertices, b.faces, b.vertex_labels, b.face_labels))
    js.write_text(volumes_json(s))
    return ply, js


def write_cohort(out_dir: str | Path, n: int, seed: int = 0, local: bool = True,
                 overwrite: bool = False) -> list[tuple[Path, Path]]:
    """Generate and write a cohort: one PLY + JSON per subject and ``cohort.json`` listing them. Any of
    these files already present is refused before anything is generated (:class:`bsv.errors.OutputExistsError`)
    unless ``overwrite``."""
    out = Path(out_dir)
    _refuse_existing([out / "cohort.json", *(p for i in range(max(n, 0)) for p in subject_files(i, out))], overwrite)
    paths = [write_subject(s, out, overwrite) for s in iter_cohort(n, seed, local)]
    index = {"seed": int(seed), "n": int(n), "local_modifiers": bool(local),
             "subjects": [{"mesh": p.name, "volumes": j.name} for p, j in paths]}
    (out / "cohort.json").write_text(json.dumps(index, indent=1) + "\n")
    return paths


def main(argv: list[str] | None = None) -> int:
    """``python -m bsv.bodies.cohort OUT_DIR N [SEED] [--no-local] [--overwrite]``: write a cohort; returns
    the exit status (2 and a message if files exist and --overwrite is not given, see bsv.exitcodes)."""
    import argparse

    from ..argtypes import seed, whole

    ap = argparse.ArgumentParser(description="Write a synthetic MakeHuman cohort (PLY + ground-truth JSON).")
    ap.add_argument("out_dir")
    ap.add_argument("n", type=whole(1, 100_000, "N subjects"))
    ap.add_argument("seed", type=seed, nargs="?", default=0)
    ap.add_argument("--no-local", action="store_true", help="macro phenotypes only (no local modifiers)")
    ap.add_argument("--overwrite", action="store_true", help="replace subject files and cohort.json already in OUT_DIR")
    args = ap.parse_args(argv)
    from ..exitcodes import run_command

    def run() -> int:
        written = write_cohort(args.out_dir, args.n, args.seed, not args.no_local, overwrite=args.overwrite)
        for ply, js in written:
            print(ply, js)
        return 0

    return run_command("bsv cohort", run)


if __name__ == "__main__":
    raise SystemExit(main())

"""The camera path's volume errors by the subject's look and the room's light.

With a room the virtual rig paints the subject (skin tone, underwear) and lights the scene (one of four
light set-ups, a neutral, warm or cool colour) from the scan seed, and writes what it drew into the
capture's ``scan.json`` (``appearance``). :func:`read_look` turns that into a few factors, ``bench synth``
keeps them in each run's ``info["look"]``, and :func:`looks_markdown` tabulates the errors per factor
level: a front-end tuned to one look shows here as one level far worse than the others.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ..bodies.variants import LIMB_SEGMENTS
from .common import Run, rve, signed_error
from .reference import ordered_conditions

#: Key of :attr:`Run.info` holding a run's look (:func:`read_look`).
INFO_KEY = "look"
#: The factors of a look, in table order, with their title.
FACTORS: dict[str, str] = {"lights": "light set-up", "light_colour": "light colour", "skin": "skin tone",
                           "underwear": "underwear", "hair": "hair", "top": "top",
                           "shading": "shading", "colour": "colour images"}
#: A skin albedo with at least this luminance (Rec. 709 Y of the sRGB values) is "lighter": the rig's four
#: lighter tones (Y 150-228) against its three darker ones (Y 57-114).
LIGHTER_SKIN_Y = 130.0


def look_of(appearance: Mapping[str, Any]) -> dict[str, str]:
    """The factors of :data:`FACTORS` of one ``scan.json`` ``appearance`` record."""
    skin_y = float(np.dot(np.asarray(appearance["skin"], dtype=np.float64), [0.2126, 0.7152, 0.0722]))
    tint = np.asarray(appearance["tint"], dtype=np.float64)
    colour = "neutral" if np.allclose(tint, 1.0) else ("warm" if tint[2] < tint[0] else "cool")
    hair = ("long" if float(appearance.get("hair_down_m", 0.0)) > 0.0 else
            "short" if float(appearance.get("hair_length_m", 0.0)) > 0.0 else "none")
    return {"lights": str(appearance["light_setup"]), "light_colour": colour,
            "skin": "lighter" if skin_y >= LIGHTER_SKIN_Y else "darker", "underwear": str(appearance["underwear_style"]),
            "hair": hair, "top": "top" if appearance.get("top") else "none",
            "shading": "smooth" if appearance.get("smooth_shading") else "flat",
            "colour": "sensor" if appearance.get("colour_sensor") else "exact"}


def read_look(capture_dir: str | Path) -> dict[str, str] | None:
    """The look of a virtual capture folder (its ``scan.json``), or None for a scan without a room or one
    written before the rig recorded it."""
    try:
        appearance = json.loads((Path(capture_dir) / "scan.json").read_text()).get("appearance")
    except (OSError, ValueError):
        return None
    if not isinstance(appearance, dict):
        return None
    try:
        return look_of(appearance)
    except (KeyError, TypeError, ValueError, IndexError):
        return None


def _limb_rve(run: Run) -> float:
    """Mean RVE (%) of the run's eight limb segments."""
    return float(np.mean([rve(run.estimated_l[k], run.truth_l[k]) for k in LIMB_SEGMENTS]))


def summarise(runs: Sequence[Run]) -> dict[str, dict[str, dict[str, dict[str, Any]]]]:
    """condition -> factor -> level -> {n, limbs_rve (mean RVE of the eight limbs, %, mean over runs),
    trunk_limbs_rve, worst (the worst limb's signed error %), worst_subject}; bsv runs with a look only."""
    out: dict[str, dict[str, dict[str, dict[str, Any]]]] = {}
    usable = [r for r in runs if r.method == "bsv" and r.ok and isinstance(r.info.get(INFO_KEY), dict)
              and all(k in r.estimated_l and r.truth_l.get(k) for k in (*LIMB_SEGMENTS, "trunk_limbs"))]
    for cond in ordered_conditions({r.condition for r in usable}):
        rows = [r for r in usable if r.condition == cond]
        out[cond] = {}
        for factor in FACTORS:
            levels: dict[str, dict[str, Any]] = {}
            for level in sorted({str(r.info[INFO_KEY].get(factor)) for r in rows}):
                sel = [r for r in rows if str(r.info[INFO_KEY].get(factor)) == level]
                signed = [(signed_error(r.estimated_l[k], r.truth_l[k]), r.subject, k) for r in sel for k in LIMB_SEGMENTS]
                worst = max(signed, key=lambda t: abs(t[0]))
                levels[level] = {
                    "n": len(sel), "limbs_rve": float(np.mean([_limb_rve(r) for r in sel])),
                    "trunk_limbs_rve": float(np.mean([rve(r.estimated_l["trunk_limbs"], r.truth_l["trunk_limbs"])
                                                      for r in sel])),
                    "worst": worst[0], "worst_subject": f"{worst[1]} {worst[2]}",
                }
            out[cond][factor] = levels
    return out


def looks_markdown(runs: Sequence[Run]) -> list[str]:
    """The report.md section of the errors by look (empty when no run recorded its look)."""
    table = summarise(runs)
    if not table:
        return []
    md = ["## By look: the subject's skin and underwear, the room's light (bsv)", "",
          ("Per level of each factor of the rig's colour render (bsv.bench.looks; from each capture's scan.json): "
           "runs, the mean RVE of the eight limb segments and of trunk_limbs (%), and the worst limb's signed "
           "error. A level far worse than its factor's others is a look the camera path is tuned against."), ""]
    for cond, factors in table.items():
        md += [f"**{cond}**", "", "| factor | level | runs | limbs mean RVE % | trunk_limbs mean RVE % | worst limb signed % |",
               "|---|---|---|---|---|---|"]
        for factor, levels in factors.items():
            for level, s in levels.items():
                md.append(f"| {FACTORS[factor]} | {level} | {s['n']} | {s['limbs_rve']:.2f} | {s['trunk_limbs_rve']:.2f} | "
                          f"{s['worst']:+.1f} ({s['worst_subject']}) |")
        md.append("")
    return md


__all__ = ["FACTORS", "INFO_KEY", "LIGHTER_SKIN_Y", "look_of", "looks_markdown", "read_look", "summarise"]

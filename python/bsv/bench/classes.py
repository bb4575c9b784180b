"""The hard cohort's volume errors by class (``bench synth --cohort hard``).

:func:`bsv.bodies.variants.hard_subject` reshapes each subject into one of the registration's hard classes
(deep upper arms, bumps, a swollen segment, extreme segment modifiers) and records it in the subject's
``variant``. :func:`classes_markdown` tabulates the errors per class, and for the classes that change
named segments, the error of those segments themselves: a class the fit cannot follow shows as one row far
worse than the others, and a swollen segment measured too small as its own column.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from ..bodies.variants import HARD_CLASSES, LIMB_SEGMENTS
from .common import Run, rve, signed_error
from .reference import ordered_conditions


def changed_segments(variant: Mapping[str, Any]) -> tuple[str, ...]:
    """The limb segments a hard variant reshaped itself (the swollen one, both upper arms of the deep class);
    empty for the classes that touch every segment (bumps, extreme modifiers) or none."""
    kind = variant.get("class")
    if kind == "swollen" and variant.get("segment") in LIMB_SEGMENTS:
        return (str(variant["segment"]),)
    if kind == "deep_upper_arms":
        return ("upper_arm_l", "upper_arm_r")
    return ()


def summarise(infos: Sequence[Mapping[str, Any]], runs: Sequence[Run]) -> dict[str, dict[str, dict[str, Any]]]:
    """condition -> class -> {n (runs), limbs_rve (mean RVE of the eight limbs, %), trunk_limbs_rve,
    changed_signed (mean signed error of the segments the class reshaped, % or None), worst (the worst limb's
    signed error %), worst_subject}; bsv runs of subjects with a ``variant`` class only."""
    variants = {str(i.get("subject")): i["variant"] for i in infos if isinstance(i.get("variant"), Mapping)}
    usable = [r for r in runs if r.method == "bsv" and r.ok and r.subject in variants
              and all(k in r.estimated_l and r.truth_l.get(k) for k in (*LIMB_SEGMENTS, "trunk_limbs"))]
    out: dict[str, dict[str, dict[str, Any]]] = {}
    for cond in ordered_conditions({r.condition for r in usable}):
        rows = [r for r in usable if r.condition == cond]
        out[cond] = {}
        present = {str(variants[r.subject].get("class")) for r in rows}
        for kind in [k for k in HARD_CLASSES if k in present] + sorted(present - set(HARD_CLASSES)):
            sel = [r for r in rows if str(variants[r.subject].get("class")) == kind]
            signed = [(signed_error(r.estimated_l[k], r.truth_l[k]), r.subject, k) for r in sel for k in LIMB_SEGMENTS]
            changed = [signed_error(r.estimated_l[k], r.truth_l[k]) for r in sel
                       for k in changed_segments(variants[r.subject])]
            worst = max(signed, key=lambda t: abs(t[0]))
            out[cond][kind] = {
                "n": len(sel),
                "limbs_rve": float(np.mean([rve(r.estimated_l[k], r.truth_l[k]) for r in sel for k in LIMB_SEGMENTS])),
                "trunk_limbs_rve": float(np.mean([rve(r.estimated_l["trunk_limbs"], r.truth_l["trunk_limbs"])
                                                  for r in sel])),
                "changed_signed": float(np.mean(changed)) if changed else None,
                "worst": worst[0], "worst_subject": f"{worst[1]} {worst[2]}",
            }
    return out


def classes_markdown(infos: Sequence[Mapping[str, Any]], runs: Sequence[Run]) -> list[str]:
    """The report.md section of the errors by hard class (empty unless the subjects carry a variant)."""
    table = summarise(infos, runs)
    if not table:
        return []
    md = ["## By hard class (bsv)", "",
          ("Per class of the hard cohort (bsv.bodies.variants.hard_subject): runs, the mean RVE of the eight limb "
           "segments and of trunk_limbs (%), the mean signed error of the segments the class reshaped (the swollen "
           "one; both upper arms of the deep class) and the worst limb's signed error. The extreme segment "
           "modifiers slide the arm's surface, and its labelled elbow boundary, 4-5 cm along the bone against the "
           "rig's elbow (6-12 mm on the plain cohort): a fit whose boundaries follow the joints (the template's "
           "segments of the camera path) cannot follow them there."), ""]
    for cond, classes in table.items():
        md += [f"**{cond}**", "", ("| class | runs | limbs mean RVE % | trunk_limbs mean RVE % | "
               "reshaped segments' signed % | worst limb signed % |"), "|---|---|---|---|---|---|"]
        for kind, s in classes.items():
            changed = "-" if s["changed_signed"] is None else f"{s['changed_signed']:+.2f}"
            md.append(f"| {kind} | {s['n']} | {s['limbs_rve']:.2f} | {s['trunk_limbs_rve']:.2f} | {changed} | "
                      f"{s['worst']:+.1f} ({s['worst_subject']}) |")
        md.append("")
    return md


__all__ = ["changed_segments", "classes_markdown", "summarise"]

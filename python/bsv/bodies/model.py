"""MakeHuman macro phenotype blending and local modifiers (numpy, on the vendored CC0 asset).

The macro targets are combined as MakeHuman does: every target's weight is the product of the weights
of the macro values in its file name (race-gender-age; universal-gender-age-muscle-weight;
height/...-minheight|maxheight; proportions/...-uncommonproportions|idealproportions), each macro
value split linearly between its anchors (age: child 0.1875, young 0.5, old 1; muscle and weight:
min 0, average 0.5, max 1; height and proportions: 0.5 is neutral and carries no target).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from ..errors import PhenotypeError
from .asset import Asset, AssetError, load_asset

GENDERS = ("female", "male")
AGES = ("child", "young", "old")
RACES = ("african", "asian", "caucasian")
LEVELS = ("min", "average", "max")



@dataclass(frozen=True)
class Phenotype:
    """MakeHuman macro values in [0, 1] (age 0.5 = 25 years, 1 = 90 years) and local modifiers in [-1, 1].

    ``local`` maps a modifier name (``Phenotype.local_modifier_names()``) to its value; a negative value
    applies the modifier's decr/down target, a positive one its incr/up target.
    """

    gender: float = 0.5
    age: float = 0.5
    muscle: float = 0.5
    weight: float = 0.5
    height: float = 0.5
    proportions: float = 0.5
    african: float = 1.0 / 3.0
    asian: float = 1.0 / 3.0
    caucasian: float = 1.0 / 3.0
    local: dict = field(default_factory=dict)

    def with_(self, **kw: Any) -> Phenotype:
        """A copy with some fields replaced."""
        return replace(self, **kw)

    @staticmethod
    def age_from_years(years: float) -> float:
        """MakeHuman age value of an age in years (11..90 years; 25 years -> 0.5)."""
        if years < 11.0 or years > 90.0:
            raise PhenotypeError(f"age {years} years: the vendored asset covers 11 to 90 years")
        if years <= 25.0:
            return 0.1875 + (years - 11.0) / 14.0 * 0.3125
        return 0.5 + (years - 25.0) / 65.0 * 0.5

    @staticmethod
    def local_modifier_names(asset: Asset | None = None) -> list[str]:
        """Names of the local modifiers available in the asset (e.g. 'stomach/stomach-pregnant')."""
        return sorted(_local_pairs(asset or load_asset()))


def _split3(x: float) -> tuple[float, float, float]:
    """(min, average, max) weights of a value in [0, 1] (MakeHuman muscle/weight)."""
    lo = max(0.0, 1.0 - 2.0 * x)
    hi = max(0.0, 2.0 * x - 1.0)
    return lo, 1.0 - lo - hi, hi


def _age_weights(age: float) -> tuple[float, float, float]:
    """(child, young, old) weights of a MakeHuman age value in [0.1875, 1]."""
    if age < 0.5:
        young = (age - 0.1875) / 0.3125
        return 1.0 - young, young, 0.0
    old = 2.0 * age - 1.0
    return 0.0, 1.0 - old, old


def _check(name: str, v: float, lo: float, hi: float) -> float:
    v = float(v)
    if not np.isfinite(v) or v < lo - 1e-12 or v > hi + 1e-12:
        raise PhenotypeError(f"phenotype {name}={v}: must lie in [{lo}, {hi}]")
    return min(max(v, lo), hi)


def _local_pairs(asset: Asset) -> dict[str, tuple[int, int]]:
    """Modifier name -> (negative target id, positive target id), from the asset's target names."""
    pairs: dict[str, list[int]] = {}
    for i, n in enumerate(asset.target_names):
        if n.startswith("macrodetails/"):
            continue
        for neg, pos in (("-decr", "-incr"), ("-down", "-up")):
            if n.endswith(neg):
                pairs.setdefault(n[: -len(neg)], [-1, -1])[0] = i
            elif n.endswith(pos):
                pairs.setdefault(n[: -len(pos)], [-1, -1])[1] = i
    return {k: (v[0], v[1]) for k, v in pairs.items() if v[0] >= 0 and v[1] >= 0}


def target_weights(p: Phenotype, asset: Asset | None = None) -> dict[int, float]:
    """Target id -> blend weight for a phenotype (only non-zero weights)."""
    a = asset or load_asset()
    g = _check("gender", p.gender, 0, 1)
    age = _check("age", p.age, 0.1875, 1)
    mus = _split3(_check("muscle", p.muscle, 0, 1))
    wei = _split3(_check("weight", p.weight, 0, 1))
    h = _check("height", p.height, 0, 1)
    pr = _check("proportions", p.proportions, 0, 1)
    race = np.array([_check(r, getattr(p, r), 0, 1) for r in RACES])
    race = race / race.sum() if race.sum() > 0 else np.full(3, 1.0 / 3.0)
    gw = {"female": 1.0 - g, "male": g}
    aw = dict(zip(AGES, _age_weights(age), strict=True))
    mw = dict(zip(LEVELS, mus, strict=True))
    ww = dict(zip(LEVELS, wei, strict=True))
    hw = {"minheight": max(0.0, 1.0 - 2.0 * h), "maxheight": max(0.0, 2.0 * h - 1.0)}
    pw = {"uncommonproportions": max(0.0, 1.0 - 2.0 * pr), "idealproportions": max(0.0, 2.0 * pr - 1.0)}
    out: dict[int, float] = {}

    def add(name: str, w: float) -> None:
        if w > 0.0:
            out[a.target_id("macrodetails/" + name)] = out.get(a.target_id("macrodetails/" + name), 0.0) + w

    for gn, gv in gw.items():
        for an, av in aw.items():
            base = gv * av
            if base <= 0:
                continue
            for ri, rn in enumerate(RACES):
                add(f"{rn}-{gn}-{an}", base * race[ri])
            for mn, mv in mw.items():
                for wn, wv in ww.items():
                    w4 = base * mv * wv
                    if w4 <= 0:
                        continue
                    stem = f"{gn}-{an}-{mn}muscle-{wn}weight"
                    add(f"universal-{stem}", w4)
                    for hn, hv in hw.items():
                        add(f"height/{stem}-{hn}", w4 * hv)
                    for pn, pv in pw.items():
                        add(f"proportions/{stem}-{pn}", w4 * pv)
    pairs = _local_pairs(a)
    for name, v in p.local.items():
        if name not in pairs:
            raise PhenotypeError(f"local modifier {name!r} unknown; available: {sorted(pairs)}")
        v = _check(name, v, -1, 1)
        if v != 0.0:
            tid = pairs[name][1] if v > 0 else pairs[name][0]
            out[tid] = out.get(tid, 0.0) + abs(v)
    return out


def shape(p: Phenotype, asset: Asset | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Rest-pose vertices (N, 3) and rig joints (bones, 2, 3) of a phenotype, metres, world axes."""
    a = asset or load_asset()
    v = a.vertices.copy()
    j = a.joints_rest.copy()
    for tid, w in sorted(target_weights(p, a).items()):
        s, e = a.target_offsets[tid], a.target_offsets[tid + 1]
        v[a.target_indices[s:e]] += w * a.target_deltas[s:e]  # indices unique within a target
        j += w * a.target_joint_deltas[tid]
    return v, j


__all__ = ["AssetError", "Phenotype", "PhenotypeError", "shape", "target_weights"]

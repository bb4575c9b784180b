"""The literature tables of the biomechanics outputs, in one place: segment densities and the de Leva
(1996) body-segment inertial parameters.

Densities: Dempster (1955), "Space requirements of the seated operator", WADC TR 55-159, as tabulated in
Winter (2009), *Biomechanics and Motor Control of Human Movement*, 4th ed., Wiley, Table 4.1 (column
"density", g/cm^3): hand 1.16, forearm 1.13, upper arm 1.07, foot 1.10, leg (shank) 1.09, thigh 1.05,
head and neck 1.11, trunk 1.03.

Regression values: de Leva P (1996), "Adjustments to Zatsiorsky-Seluyanov's segment inertia parameters",
J Biomech 29(9):1223-1230, Table 4, for endpoints at joint centres where the paper gives them: head
VERT-CERV, trunk CERV-MIDH, upper arm SJC-EJC, forearm EJC-WJC, hand WJC-DAC3, thigh HJC-KJC, shank
KJC-AJC, foot HEEL-TTIP (VERT vertex, CERV cervicale, MIDH mid-hip joint centres, DAC3 tip of the third
finger, TTIP tip of the longest toe, *JC joint centres).
"""

from __future__ import annotations

from dataclasses import dataclass

#: Segment density (kg/m^3) by segment kind, Dempster (1955) via Winter (2009) Table 4.1.
DEMPSTER_DENSITY_KG_M3: dict[str, float] = {
    "head": 1110.0,
    "torso": 1030.0,
    "upper_arm": 1070.0,
    "forearm": 1130.0,
    "hand": 1160.0,
    "thigh": 1050.0,
    "shin": 1090.0,
    "foot": 1100.0,
}

#: Citation of :data:`DEMPSTER_DENSITY_KG_M3`, written into every output that uses it.
DENSITY_SOURCE = "Dempster (1955) segment densities, as tabulated in Winter (2009) Table 4.1"

#: Citation of :data:`DE_LEVA`.
DE_LEVA_SOURCE = "de Leva (1996) J Biomech 29(9):1223-1230, Table 4 (adjusted Zatsiorsky-Seluyanov)"


@dataclass(frozen=True)
class DeLeva:
    """One row of de Leva's Table 4 for one sex: mass (% of body mass), centre of mass (% of the
    length from ``origin``) and radii of gyration (% of the length) about the sagittal
    (antero-posterior), transverse (medio-lateral) and longitudinal axes."""

    origin: str
    other: str
    mass_pct: float
    com_pct: float
    rg_sagittal_pct: float
    rg_transverse_pct: float
    rg_longitudinal_pct: float


#: de Leva (1996) Table 4 by sex and segment kind (this project's segment names).
DE_LEVA: dict[str, dict[str, DeLeva]] = {
    "female": {
        "head": DeLeva("VERT", "CERV", 6.68, 48.41, 27.1, 29.5, 26.1),
        "torso": DeLeva("CERV", "MIDH", 42.57, 49.64, 30.7, 29.2, 14.7),
        "upper_arm": DeLeva("SJC", "EJC", 2.55, 57.54, 27.8, 26.0, 14.8),
        "forearm": DeLeva("EJC", "WJC", 1.38, 45.59, 26.1, 25.7, 9.4),
        "hand": DeLeva("WJC", "DAC3", 0.56, 34.27, 24.4, 20.8, 15.4),
        "thigh": DeLeva("HJC", "KJC", 14.78, 36.12, 36.9, 36.4, 16.2),
        "shin": DeLeva("KJC", "AJC", 4.81, 43.52, 26.7, 26.3, 9.2),
        "foot": DeLeva("HEEL", "TTIP", 1.29, 40.14, 29.9, 27.9, 13.9),
    },
    "male": {
        "head": DeLeva("VERT", "CERV", 6.94, 50.02, 30.3, 31.5, 26.1),
        "torso": DeLeva("CERV", "MIDH", 43.46, 51.38, 32.8, 30.6, 16.9),
        "upper_arm": DeLeva("SJC", "EJC", 2.71, 57.72, 28.5, 26.9, 15.8),
        "forearm": DeLeva("EJC", "WJC", 1.62, 45.74, 27.6, 26.5, 12.1),
        "hand": DeLeva("WJC", "DAC3", 0.61, 36.24, 28.8, 23.5, 18.4),
        "thigh": DeLeva("HJC", "KJC", 14.16, 40.95, 32.9, 32.9, 14.9),
        "shin": DeLeva("KJC", "AJC", 4.33, 43.95, 25.1, 24.6, 10.2),
        "foot": DeLeva("HEEL", "TTIP", 1.37, 44.15, 25.7, 24.5, 12.4),
    },
}

#: The joints found on a labelled mesh: name -> the two segments whose shared boundary it is.
JOINTS: dict[str, tuple[str, str]] = {
    "neck": ("head", "torso"),
    **{f"{j}_{s}": (a + ("" if a == "torso" else f"_{s}"), b + f"_{s}")
       for s in ("l", "r")
       for j, a, b in (("shoulder", "torso", "upper_arm"), ("elbow", "upper_arm", "forearm"),
                       ("wrist", "forearm", "hand"), ("hip", "torso", "thigh"), ("knee", "thigh", "shin"),
                       ("ankle", "shin", "foot"))},
}


def kind(segment: str) -> str:
    """The segment kind of a segment name (``upper_arm_l`` -> ``upper_arm``, ``torso`` -> ``torso``)."""
    return segment[:-2] if segment.endswith(("_l", "_r")) else segment

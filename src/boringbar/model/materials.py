"""Named materials for bars, balls and plugs: Young's modulus, density and Poisson's
ratio, with where the values come from (docs/systems.md lists them).

The published study's values are kept exactly (steel 200 GPa and 7850 kg/m^3 for
the bar; 14,700 kg/m^3 for the carbide ball).  The others are typical handbook
values: a real grade may differ by 5-10 %, and a user who knows their grade
gives E and density in the system file instead of a name.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Material:
    """``youngs_modulus`` (Pa), ``density`` (kg/m^3), ``source`` (where they come
    from) and ``poisson_ratio`` (a Hertz contact's modulus, model/contact.py)."""

    youngs_modulus: float
    density: float
    source: str
    poisson_ratio: float = 0.29


MATERIALS: dict[str, Material] = {
    "steel": Material(200e9, 7850.0, "the published bar's values; structural and tool "
                      "steels (e.g. AISI 4140) are 200-210 GPa and 7850 kg/m^3; Poisson's ratio "
                      "0.27-0.30"),
    "carbide": Material(580e9, 14_700.0, "cemented tungsten carbide, WC with 6-10 % Co: "
                        "E 550-650 GPa, 14,300-15,000 kg/m^3 (manufacturers' grade "
                        "sheets); 14,700 kg/m^3 is the published ball's; Poisson's ratio 0.21-0.24",
                        0.22),
    "heavy-metal": Material(360e9, 18_000.0, "tungsten heavy alloy, about 95 % W (ASTM "
                            "B777 class 3: 17,750-18,350 kg/m^3), E about 360 GPa, Poisson's ratio "
                            "about 0.28", 0.28),
    "tungsten": Material(411e9, 19_300.0, "pure tungsten (handbook values: E 411 GPa, "
                         "19,300 kg/m^3, Poisson's ratio 0.28)", 0.28),
}

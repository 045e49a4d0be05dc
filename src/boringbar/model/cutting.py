"""Cutting-force laws and workpiece materials (docs/model.md, section 4.3).

The force the model applies acts in the bar's bending direction (radial, docs/model.md,
section 4.2).  Two laws give it from the chip thickness h and the depth of cut b:

- linear, F = Kr b h, with the published study's Kr = 850 MPa (aluminium);
- Kienzle's, F = K b h (h / h_ref)^(-m_c), h_ref = 1 mm: the catalogues' main-force law
  F_c = kc1.1 b h^(1 - m_c) (h in mm, kc1.1 in N/mm^2) written in SI, with
  K = r kc1.1 the radial force's share of it (:data:`RADIAL_RATIO`).

:data:`WORKPIECES` holds the catalogue constants kc1.1 and m_c of a few workpiece
materials, and the cutting speeds of carbide inserts in them (given in the catalogues'
m/min, held in m/s), each with its source.
A user who has measured constants gives them (``CuttingLaw.kienzle(kc11_pa=...,
mc=...)``); with radial (passive) force constants of their own, as König and Klocke
tabulate them, they give those with ``radial_ratio=1``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from boringbar._validate import ParameterError, check_choice, check_range

#: Kienzle's reference chip thickness (m): the catalogues give kc1.1 at h = 1 mm.
H_REF_M = 1e-3
#: The published study's radial coefficient (Pa), aluminium (docs/model.md, section 4.2).
KR_ALUMINIUM = 850e6
#: The radial force as a fraction of the main (tangential) force in boring: "about 25
#: to 30 percent of the tangential force" (Boring Basics, Erie Industrial Supply,
#: eisc.com/?p=1190; the feed force, 50-60 %, lies along the bar and does not bend it).
#: The upper end is taken: the larger force gives the smaller, safer limit.
RADIAL_RATIO = 0.3
#: Bounds that keep the kernels' arithmetic finite (a force of 1e300 N overflows the
#: energy sums): a specific force (Pa) and Kienzle's m_c (1: a force independent of h).
MAX_SPECIFIC_FORCE = 1e12
MAX_MC = 1.0
LAWS = ("linear", "kienzle")

_ISCAR = ("ISCAR turning catalogue (2017), 'Material groups according to DIN/ISO 513 and "
          "VDI 3323', kc1 (N/mm^2, for a chip 1 mm thick) and mc")
_SPEEDS = ("typical cutting speeds of coated carbide inserts by ISO material group, "
           "toward the low end of turning catalogues' ranges as a bar's overhang asks; "
           "approximate: where to look for lobes, not cutting data")


@dataclass(frozen=True)
class Workpiece:
    """A workpiece material: Kienzle's constants of the main force, ``kc11_pa`` (Pa) and
    ``mc``, and the cutting speeds ``cutting_speed_m_s`` (low, high; m/s) of carbide
    inserts in it, each with its ``source`` and ``speed_source``."""

    kc11_pa: float
    mc: float
    cutting_speed_m_s: tuple[float, float]
    source: str
    speed_source: str = _SPEEDS


#: Workpiece materials by name (docs/model.md, section 4.3 lists them); cutting speeds
#: as the catalogues give them, m/min, over 60.
WORKPIECES: dict[str, Workpiece] = {
    "steel": Workpiece(
        1500e6, 0.22, (150.0 / 60, 300.0 / 60),
        f"{_ISCAR}: group 2, non-alloy steel >= 0.25 % C, annealed (C45, 650 N/mm^2)"),
    "alloy-steel": Workpiece(
        1725e6, 0.24, (120.0 / 60, 250.0 / 60),
        f"{_ISCAR}: group 8, low-alloy steel, quenched and tempered to 1000 N/mm^2 "
        "(42CrMo4)"),
    "aluminium": Workpiece(
        800e6, 0.25, (300.0 / 60, 1000.0 / 60),
        f"{_ISCAR}: group 22, wrought aluminium alloy, age-hardened (6061-T6, 7075-T6)"),
    "cast-iron": Workpiece(
        1150e6, 0.20, (100.0 / 60, 250.0 / 60),
        f"{_ISCAR}: group 15, grey cast iron, ferritic/pearlitic (EN-GJL-250)"),
    "titanium": Workpiece(
        2110e6, 0.22, (40.0 / 60, 80.0 / 60),
        f"{_ISCAR}: group 37, alpha+beta titanium alloy, aged, 1050 N/mm^2 (Ti-6Al-4V); "
        "ISCAR's boring catalogue (2022) lists 1245 N/mm^2, mc 0.24 for the same group"),
}
#: Cutting speeds (m/s) when no workpiece is named, 100-300 m/min: steel's and cast
#: iron's together, the materials bored most.
DEFAULT_CUTTING_SPEED_M_S = (100.0 / 60, 300.0 / 60)


def workpiece_material(name: str) -> Workpiece:
    """The material ``name`` of :data:`WORKPIECES` (a ParameterError lists the known)."""
    if not isinstance(name, str) or name not in WORKPIECES:
        raise ParameterError(f"workpiece = {name!r} is not a known material; the known ones "
                             f"are {', '.join(WORKPIECES)}")
    return WORKPIECES[name]


@dataclass(frozen=True)
class CuttingLaw:
    """The cutting force in the bar's bending (radial) direction as a function of the chip
    thickness h (docs/model.md, section 4.3).

    ``law`` "linear": F = ``kr_pa`` b h.  ``law`` "kienzle":
    F = K b h (h / 1 mm)^(-``mc``), K = ``radial_ratio`` ``kc11_pa``, with kc1.1 (Pa) and
    m_c the main force's constants; ``workpiece`` names the material they come from
    (None: your own) and ``source`` where they come from.  Build one with
    :meth:`linear` or :meth:`kienzle`.
    """

    law: str = "linear"
    kr_pa: float | None = KR_ALUMINIUM
    kc11_pa: float | None = None
    mc: float = 0.0
    radial_ratio: float = RADIAL_RATIO
    workpiece: str | None = None
    source: str = ""

    def __post_init__(self):
        check_choice("law", self.law, LAWS)
        if self.law == "linear":
            check_range("kr_pa", self.kr_pa, 0.0, MAX_SPECIFIC_FORCE, lo_open=True, unit="Pa")
            if self.kc11_pa is not None or self.mc != 0.0 or self.workpiece is not None:
                raise ParameterError(f"the linear law takes kr_pa alone (got kc11_pa = "
                                     f"{self.kc11_pa!r}, mc = {self.mc!r}, workpiece = "
                                     f"{self.workpiece!r}): use CuttingLaw.kienzle")
            return
        check_range("kc11_pa", self.kc11_pa, 0.0, MAX_SPECIFIC_FORCE, lo_open=True, unit="Pa")
        check_range("mc", self.mc, 0.0, MAX_MC, hi_open=True)
        check_range("radial_ratio", self.radial_ratio, 0.0, 10.0, lo_open=True)
        if self.workpiece is not None:
            workpiece_material(self.workpiece)

    @classmethod
    def linear(cls, kr_pa: float = KR_ALUMINIUM) -> CuttingLaw:
        """F = Kr b h, ``kr_pa`` = Kr (Pa; default the published 850 MPa)."""
        return cls("linear", kr_pa)

    @classmethod
    def kienzle(cls, workpiece: str | None = None, *, kc11_pa: float | None = None,
                mc: float | None = None, radial_ratio: float = RADIAL_RATIO) -> CuttingLaw:
        """Kienzle's law of a material of :data:`WORKPIECES` (``workpiece``), or with
        your own main-force constants ``kc11_pa`` (Pa: N/mm^2 x 1e6) and ``mc``;
        ``radial_ratio``: the radial force over the main force (1 for radial-force
        constants)."""
        if workpiece is not None:
            if kc11_pa is not None or mc is not None:
                raise ParameterError(f"workpiece = {workpiece!r} brings its own kc11_pa "
                                     f"and mc (got kc11_pa = {kc11_pa!r}, mc = {mc!r}): give "
                                     "a material or the constants")
            w = workpiece_material(workpiece)
            return cls("kienzle", None, w.kc11_pa, w.mc, radial_ratio, workpiece, w.source)
        if kc11_pa is None or mc is None:
            raise ParameterError(f"Kienzle's law needs a workpiece material or both kc11_pa "
                                 f"and mc (got kc11_pa = {kc11_pa!r}, mc = {mc!r})")
        return cls("kienzle", None, kc11_pa, mc, radial_ratio, None, "given")

    @property
    def linear_law(self) -> bool:
        """Whether the force is linear in h (the exact integrator needs it)."""
        return self.law == "linear"

    @property
    def coefficient_pa(self) -> float:
        """K (Pa): the radial force per unit chip area at h = 1 mm (linear: Kr)."""
        return self.kr_pa if self.linear_law else self.radial_ratio * self.kc11_pa

    @property
    def exponent(self) -> float:
        """m_c: F grows as h^(1 - m_c) (0 for the linear law)."""
        return 0.0 if self.linear_law else self.mc

    def force_n(self, depth_m, h_m):
        """F (N) at depth of cut ``depth_m`` (m) and chip thickness ``h_m`` (m; 0 where
        h <= 0); numbers or arrays."""
        h = np.maximum(np.asarray(h_m, dtype=float), 0.0)
        if self.linear_law:
            f = self.kr_pa * np.asarray(depth_m, dtype=float) * h
        else:
            scaled = np.power(h / H_REF_M, -self.mc, out=np.zeros_like(h), where=h > 0.0)
            f = self.coefficient_pa * np.asarray(depth_m, dtype=float) * h * scaled
        return float(f) if f.ndim == 0 else f

    def linear_coefficient_pa(self, feed_m: float) -> float:
        """dF/dh / b (Pa) at the mean chip thickness h_m = ``feed_m`` (m): the law
        linearised about the steady cut, which the analytic (frequency-domain) lobes
        take for Kr (docs/model.md, section 4.3).  Kienzle: (1 - m_c) K (h_m / 1 mm)^(-m_c);
        linear: Kr."""
        if self.linear_law:
            return self.kr_pa
        h = check_range("feed_m", feed_m, 0.0, math.inf, lo_open=True, hi_open=True, unit="m")
        return (1.0 - self.mc) * self.coefficient_pa * (h / H_REF_M) ** (-self.mc)

    def kernel_coefficient(self, depth_m: float) -> float:
        """The core's KR_B: K b (1 mm)^m_c, so that F = KR_B h^(1 - m_c) (the linear law:
        the product Kr b alone, whose bits the published runs have)."""
        if self.linear_law:
            return self.kr_pa * depth_m
        return self.coefficient_pa * depth_m * H_REF_M**self.mc

    def describe(self) -> str:
        """The law in words, for messages and figures."""
        if self.linear_law:
            return f"linear law, Kr = {self.kr_pa / 1e6:g} MPa"
        what = self.workpiece or "given constants"
        return (f"Kienzle's law ({what}: kc1.1 = {self.kc11_pa / 1e6:g} N/mm^2, mc = "
                f"{self.mc:g}, radial ratio {self.radial_ratio:g})")

    def to_dict(self) -> dict:
        if self.linear_law:
            return {"law": "linear", "kr_pa": self.kr_pa}
        return {"law": "kienzle", "workpiece": self.workpiece, "kc11_pa": self.kc11_pa,
                "mc": self.mc, "radial_ratio": self.radial_ratio, "source": self.source}


def cutting_law(kr_pa: float = KR_ALUMINIUM,
                workpiece_or_law: str | CuttingLaw | None = None) -> CuttingLaw:
    """The law of a cut described by ``kr_pa`` (the linear law's Kr, Pa) and a workpiece:
    a material of :data:`WORKPIECES` (Kienzle's law with its constants) or a
    :class:`CuttingLaw`; without one, the linear law with ``kr_pa``.  A workpiece with
    ``kr_pa`` other than the default 850 MPa is refused: the two name different laws."""
    if workpiece_or_law is None:
        return CuttingLaw.linear(kr_pa)
    if kr_pa != KR_ALUMINIUM:
        raise ParameterError(f"kr_pa = {kr_pa!r} Pa (the linear law) and workpiece = "
                             f"{_name(workpiece_or_law)} (its own law): give one")
    if isinstance(workpiece_or_law, CuttingLaw):
        return workpiece_or_law
    return CuttingLaw.kienzle(workpiece_or_law)


class CutLawFields:
    """The law of an options class with ``kr_pa``, ``workpiece`` and ``feed_m`` fields
    (lobes, chatter maps): one reading of those three fields everywhere."""

    @property
    def law(self) -> CuttingLaw:
        """The cut's law (linear with ``kr_pa``, or the ``workpiece``'s)."""
        return cutting_law(self.kr_pa, self.workpiece)

    @property
    def analytic_kr_pa(self) -> float:
        """The Kr of the analytic limits: the law's dF/dh / b at the feed (Pa)."""
        return self.law.linear_coefficient_pa(self.feed_m)


def _name(workpiece_or_law) -> str:
    if isinstance(workpiece_or_law, CuttingLaw):
        return workpiece_or_law.describe()
    return repr(workpiece_or_law)


def cutting_speed_range_m_s(workpiece_or_law: str | CuttingLaw | None = None
                            ) -> tuple[float, float]:
    """Cutting speeds (low, high; m/s) of carbide inserts in a material of
    :data:`WORKPIECES` (a CuttingLaw: its workpiece's), or
    :data:`DEFAULT_CUTTING_SPEED_M_S`."""
    name = (workpiece_or_law.workpiece if isinstance(workpiece_or_law, CuttingLaw)
            else workpiece_or_law)
    return (DEFAULT_CUTTING_SPEED_M_S if name is None
            else workpiece_material(name).cutting_speed_m_s)

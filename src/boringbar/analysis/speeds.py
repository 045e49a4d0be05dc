"""The spindle speeds a lobe study takes when none are given: a boring job's (the cutting
speeds of carbide inserts over the bar's bore) for a bar with a diameter, else the
speeds that draw the first lobes of its first frequency (docs/model.md, section 4.5).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from boringbar._validate import ParameterError, check_int, check_values
from boringbar.analysis.cases import Case
from boringbar.model.cutting import CuttingLaw, cutting_speed_range_m_s
from boringbar.model.forcing import MIN_LOBE_RPM
from boringbar.model.system import System
from boringbar.model.system_file import SystemSpec

#: The default speeds span these lobe numbers k = 60 f1 / rpm: past the pocket of
#: lobe 1 at 60 f1 rpm on the fast side, to the pocket of lobe 6 on the slow side, so
#: lobes 1 to 5 are drawn whole.
LOBE_NUMBERS = (0.9, 6.1)
#: Default speeds per lobe (per unit of k): each lobe drawn with its falling and
#: its rising flank, not as one straight line between two speeds.
SPEEDS_PER_LOBE = 10


def check_speeds(name: str, rpm) -> tuple[float, ...]:
    """Spindle speeds (rev/min): at least :data:`MIN_LOBE_RPM` and increasing, each once."""
    speeds = check_values(name, np.atleast_1d(rpm).tolist(), MIN_LOBE_RPM, math.inf,
                          unit="rev/min")
    if np.any(np.diff(speeds) <= 0):
        raise ParameterError(f"{name} = {speeds} must increase, each speed once (a "
                             "lobe diagram runs along the speed axis)")
    return speeds


def lobe_speeds(frequencies_hz, numbers: tuple[float, float] = LOBE_NUMBERS,
                per_lobe: int = SPEEDS_PER_LOBE) -> tuple[float, ...]:
    """Spindle speeds (rev/min, whole, increasing) that draw the lobes of bars whose
    first natural frequencies are ``frequencies_hz``.

    A one-tooth cut regenerates once a revolution, so lobe k's pocket sits near
    60 f1 / k rpm (the chatter frequency is a little above f1).  The speeds run
    from 60 f1 / numbers[1] (the lowest f1) to 60 f1 / numbers[0] (the highest),
    evenly spaced in k = 60 f1 / rpm, ``per_lobe`` of them per unit of k for the
    highest f1: a lobe is as wide in k as every other, so each gets as many speeds.
    """
    f = np.asarray(check_values("frequencies_hz", frequencies_hz, 0.0, math.inf,
                                lo_open=True, unit="Hz"))
    lo, hi = 60.0 * f.min() / numbers[1], 60.0 * f.max() / numbers[0]
    n = math.ceil((1.0 / lo - 1.0 / hi) * 60.0 * f.max() * per_lobe) + 1
    speeds = np.unique(np.round(1.0 / np.linspace(1.0 / hi, 1.0 / lo, n)))
    return tuple(float(r) for r in speeds)


#: The bore a boring bar works in: its largest diameter times this.  A bar of diameter d
#: enters bores from about 1.25 d with its insert (manufacturers' minimum bore
#: diameters, e.g. 32 mm for a 25 mm bar).
BORE_RATIO = 1.25
#: Speeds :func:`boring_speeds` gives by default.
BORING_SPEEDS = 60
#: A boring job's default lobe grid: speeds a lobe at least, and at most this many.
JOB_SPEEDS_PER_LOBE = 4
MAX_DEFAULT_SPEEDS = 200


@dataclass(frozen=True)
class BoringSpeeds:
    """Spindle speeds of a boring job: ``rpm`` (rev/min, whole, increasing), the cutting
    speed of each at the bore, ``cutting_speed_m_s`` (m/s; x 60 for the catalogues'
    m/min), the bore's diameter ``bore_diameter_m`` (m) and the cutting speeds
    ``cutting_speed_range_m_s`` (low, high; m/s) the speeds span."""

    rpm: tuple[float, ...]
    cutting_speed_m_s: tuple[float, ...]
    bore_diameter_m: float
    cutting_speed_range_m_s: tuple[float, float]


def boring_speeds(system_or_spec, workpiece: str | CuttingLaw | None = None,
                  n: int = BORING_SPEEDS) -> BoringSpeeds:
    """Spindle speeds at which a carbide insert bores ``workpiece`` (a material of
    :data:`~boringbar.model.cutting.WORKPIECES`, a CuttingLaw naming one, or None: the
    default range) with the bar of ``system_or_spec`` (a System or a SystemSpec).

    The bore is :data:`BORE_RATIO` times the bar's largest diameter, D; the material's
    cutting speeds v_c (docs/model.md, section 4.5) give rpm = 60 v_c / (pi D) (v_c in
    m/s; the catalogues' 1000 v_c / (pi D) with v_c in m/min, D in mm), ``n`` speeds
    evenly spaced in 1/rpm (the lobe number's axis).  A bar known only by its modes (a
    modal fit of a measured FRF, a tap test) has no diameter: a ParameterError says
    so (:func:`lobe_speeds` serves it).
    """
    check_int("n", n, 2, 100_000)
    bore = BORE_RATIO * _largest_diameter_m(system_or_spec)
    low, high = cutting_speed_range_m_s(workpiece)
    per_m_s = 60.0 / (math.pi * bore)  # rpm per m/s of cutting speed
    inverse = np.linspace(1.0 / (low * per_m_s), 1.0 / (high * per_m_s), n)
    rpm = np.unique(np.round(1.0 / inverse))
    return BoringSpeeds(tuple(float(r) for r in rpm), tuple(float(r / per_m_s) for r in rpm),
                        bore, (low, high))


def _largest_diameter_m(system_or_spec) -> float:
    """The largest outer diameter (m) of the bar a System or SystemSpec describes."""
    if isinstance(system_or_spec, System):
        if not system_or_spec.bar.source.startswith("fe") or system_or_spec.spec is None:
            raise ParameterError(f"this bar's modal model comes from "
                                 f"{system_or_spec.bar.source!r}, without a diameter: give "
                                 "speeds, or lobe_speeds of its first frequency")
        system_or_spec = system_or_spec.spec
    if not isinstance(system_or_spec, SystemSpec):
        raise ParameterError(f"system_or_spec = {system_or_spec!r} must be a System or a "
                             "SystemSpec (a system file)")
    return max(s.diameter_m for s in system_or_spec.bar.sections)


def has_diameter(system: System) -> bool:
    """Whether the bar of ``system`` comes from a system file's sections (so its bore, and
    a boring job's speeds, are known)."""
    return system.bar.source.startswith("fe") and system.spec is not None


def default_speeds(cases: list[Case], workpiece: str | CuttingLaw | None = None
                   ) -> tuple[float, ...]:
    """The speeds a lobe study of ``cases`` takes by default.

    Bars of system files: a boring job's (:func:`boring_speeds` of each bar and
    ``workpiece``, spanning all their bores), evenly spaced in 1/rpm, at least
    :data:`JOB_SPEEDS_PER_LOBE` a lobe of the highest first frequency (at a boring job's
    speeds the lobes crowd: lobe numbers 10-30 are usual), at least
    :data:`BORING_SPEEDS` and at most :data:`MAX_DEFAULT_SPEEDS`.  A bar known only by
    its modes (a measured FRF, a tap test): :func:`lobe_speeds`, its lobes 1 to 5."""
    f1 = [c.system.reference_frequency_rad_s / (2 * math.pi) for c in cases]
    if not all(has_diameter(c.system) for c in cases):
        return lobe_speeds(f1)
    jobs = [boring_speeds(c.system, workpiece, 2) for c in cases]
    lo, hi = min(j.rpm[0] for j in jobs), max(j.rpm[-1] for j in jobs)
    spanned = 60.0 * max(f1) * (1.0 / lo - 1.0 / hi)
    n = int(np.clip(math.ceil(JOB_SPEEDS_PER_LOBE * spanned), BORING_SPEEDS,
                    MAX_DEFAULT_SPEEDS))
    speeds = np.unique(np.round(1.0 / np.linspace(1.0 / lo, 1.0 / hi, n)))
    return tuple(float(r) for r in speeds)

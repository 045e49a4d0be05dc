"""Forcing at the cutting end (docs/model.md, section 4)."""

from __future__ import annotations

import math
from dataclasses import dataclass

from boringbar._validate import ParameterError, check_int, check_positive, check_range
from boringbar.model.cutting import (
    KR_ALUMINIUM,
    MAX_SPECIFIC_FORCE,
    CuttingLaw,
    cutting_law,
)

#: Upper bounds that no machining needs but that keep the kernels' arithmetic
#: finite (a force of 1e300 N overflows the energy sums): force amplitude (N),
#: depth of cut (m), feed per revolution (m), specific cutting force (Pa).
MAX_FORCE = 1e6
MAX_DEPTH = 1.0
MAX_FEED = 0.1
MAX_KR = MAX_SPECIFIC_FORCE
#: The cut's force noise: its relative standard deviation is below 1 (a force that
#: changes sign is no cut), its seed an integer a float64 slot of the core holds exactly.
MAX_NOISE_STD = 1.0
MAX_NOISE_SEED = 2**53
#: The noise's default interval (s): shorter than the period of every mode a boring bar's
#: model keeps (the published bar's third mode: 0.2 ms), so the noise excites them all,
#: and 100 steps of the default 1 us, over which the force is constant.
NOISE_INTERVAL_S = 1e-4
MAX_NOISE_INTERVAL_S = 1e3
#: Largest Omega / omega_n and forcing frequency (Hz) of harmonic forcing (the
#: published sweeps: 0.95 to 1.05); above, no step resolves the forcing anyway.
MAX_RATIO = 100.0
MAX_FREQUENCY_HZ = 1e6


def check_force(force: float, name: str = "--force-n") -> float:
    """A harmonic force amplitude in N, [0, MAX_FORCE] (``name``: how the caller calls it;
    the command line and the design page share these checks)."""
    return check_range(name, force, 0, MAX_FORCE, unit="N")


def check_ratio(ratio: float, name: str = "--ratio") -> float:
    """A forcing frequency ratio, (0, MAX_RATIO]."""
    return check_range(name, ratio, 0, MAX_RATIO, lo_open=True)


def check_depth(depth_mm: float, name: str) -> float:
    """A depth of cut in mm, (0, MAX_DEPTH]."""
    return check_range(name, depth_mm, 0, MAX_DEPTH * 1e3, lo_open=True, unit="mm")


@dataclass(frozen=True)
class Harmonic:
    """f(t) = F0 sin(Omega t) at the tip, F0 = ``amplitude_n`` (N).

    Give the frequency as ``ratio`` = Omega / omega_n of the host bar (docs/model.md,
    section 6: the ball-cavity bar for the ball damper, the solid bar for the
    solid and TMD bars) or as ``frequency_hz``, not both.
    """

    amplitude_n: float = 10.0  #: F0 (N)
    ratio: float | None = 1.0
    frequency_hz: float | None = None

    def __post_init__(self):
        check_range("amplitude_n", self.amplitude_n, 0.0, MAX_FORCE, unit="N")
        if (self.ratio is None) == (self.frequency_hz is None):
            raise ParameterError("harmonic forcing: give exactly one of ratio "
                                 "(Omega/omega_n) or frequency_hz")
        if self.ratio is not None:
            check_range("ratio (Omega/omega_n)", self.ratio, 0.0, MAX_RATIO, lo_open=True)
        else:
            check_range("frequency_hz", self.frequency_hz, 0.0, MAX_FREQUENCY_HZ, lo_open=True,
                        unit="Hz")

    def omega(self, reference_rad_s: float) -> float:
        """Omega (rad/s), with ``reference_rad_s`` = omega_n of the host bar (rad/s)."""
        if self.ratio is not None:
            return self.ratio * reference_rad_s
        return 2.0 * math.pi * self.frequency_hz

    def to_dict(self) -> dict:
        return {"type": "harmonic", "amplitude_n": self.amplitude_n, "ratio": self.ratio,
                "frequency_hz": self.frequency_hz}


INTERPOLATIONS = ("cubic", "linear")
STARTS = ("rest", "static")


@dataclass(frozen=True)
class Regenerative:
    """Regenerative turning/boring, radial direction (docs/model.md, section 4).

    f(t) = F(h(t)) (1 + eps(t)), h(t) = max(0, min_{k=1..N} [k h_m + W(t - k tau)] - W(t)),
    tau = 60 / rpm, F the cutting law: Kr b h (linear, ``kr_pa`` = Kr, the default) or,
    with a ``workpiece``, Kienzle's K b h (h / 1 mm)^(-m_c) (section 4.3; ``workpiece``: a
    material of :data:`~boringbar.model.cutting.WORKPIECES`, or a
    :class:`~boringbar.model.cutting.CuttingLaw` with your own constants; ``kr_pa`` then
    stays at its default).  The surface before the cut started is W = 0 (``start =
    "rest"``, as published: the mean force arrives as a step) or the static
    deflection under the mean force (``start = "static"``, a steady cut).
    The delayed W at RK4 stages is interpolated from the stored history
    with a cubic Hermite from W and W' (4th order, default) or linearly.
    ``depth_m`` b (m), ``rpm`` (rev/min), ``kr_pa`` the specific radial cutting force
    (Pa), ``feed_m`` h_m per revolution (m), ``revolutions`` N of the minimum;
    ``interpolation``: "cubic" or "linear".
    ``stop_at_zero`` ends the run at the first h = 0 (a lobe search needs no
    more); ``bounded_fraction``: the amplitude criterion's threshold, as a
    fraction of h_m.  ``force_noise``: the relative standard deviation of eps, in
    [0, 1) (0, the default: none); eps is drawn anew every ``noise_interval_s`` (s,
    rounded to whole steps) from the stream ``noise_seed`` (section 4.4; rk4 only).
    """

    depth_m: float  #: b, depth of cut (m)
    rpm: float  #: spindle speed (rev/min)
    kr_pa: float = KR_ALUMINIUM  #: specific radial cutting force of the linear law (Pa)
    feed_m: float = 0.1e-3  #: h_m, feed per revolution (m)
    revolutions: int = 3  #: N, past revolutions in the chip-thickness minimum
    interpolation: str = "cubic"
    start: str = "rest"
    stop_at_zero: bool = False
    bounded_fraction: float = 0.1
    workpiece: str | CuttingLaw | None = None  #: Kienzle's law of this material (or law)
    force_noise: float = 0.0  #: relative std of the force noise eps
    noise_interval_s: float = NOISE_INTERVAL_S  #: eps is constant this long (s)
    noise_seed: int = 0  #: the noise's stream

    def __post_init__(self):
        check_range("depth_m (depth of cut)", self.depth_m, 0.0, MAX_DEPTH, unit="m")
        check_positive("rpm", self.rpm)
        check_range("kr_pa", self.kr_pa, 0.0, MAX_KR, lo_open=True, unit="Pa")
        check_range("feed_m", self.feed_m, 0.0, MAX_FEED, lo_open=True, unit="m")
        if isinstance(self.revolutions, float):  # 3.0 is not accepted: a count
            raise ParameterError(f"revolutions = {self.revolutions!r} is not a whole number "
                                 "(allowed range [1, 50])")
        check_int("revolutions", self.revolutions, 1, 50)
        if self.interpolation not in INTERPOLATIONS:
            raise ParameterError(f"interpolation = {self.interpolation!r} is not one of "
                                 f"{', '.join(INTERPOLATIONS)}")
        if self.start not in STARTS:
            raise ParameterError(f"start = {self.start!r} is not one of {', '.join(STARTS)}")
        check_positive("bounded_fraction", self.bounded_fraction)
        cutting_law(self.kr_pa, self.workpiece)
        check_range("force_noise", self.force_noise, 0.0, MAX_NOISE_STD, hi_open=True)
        check_range("noise_interval_s", self.noise_interval_s, 0.0, MAX_NOISE_INTERVAL_S,
                    lo_open=True, unit="s")
        if isinstance(self.noise_seed, float):  # a stream's number, not a quantity
            raise ParameterError(f"noise_seed = {self.noise_seed!r} is not a whole number "
                                 f"(allowed range [0, {MAX_NOISE_SEED}])")
        check_int("noise_seed", self.noise_seed, 0, MAX_NOISE_SEED)

    @property
    def tau_s(self) -> float:
        """Delay: one spindle revolution (s)."""
        return 60.0 / self.rpm

    @property
    def law(self) -> CuttingLaw:
        """The cutting law: linear with ``kr_pa``, or the ``workpiece``'s."""
        return cutting_law(self.kr_pa, self.workpiece)

    @property
    def mean_force_n(self) -> float:
        """F(h_m) (N): the law at the feed (linear: Kr b h_m)."""
        return self.law.force_n(self.depth_m, self.feed_m)

    @property
    def linear_coefficient_pa(self) -> float:
        """The law's dF/dh / b at h_m (Pa): the Kr of the analytic lobes (section 4.3)."""
        return self.law.linear_coefficient_pa(self.feed_m)

    def to_dict(self) -> dict:
        linear = self.law.linear_law
        return {"type": "regenerative", "depth_m": self.depth_m, "rpm": self.rpm,
                "kr_pa": self.kr_pa if linear else None, "feed_m": self.feed_m,
                "revolutions": self.revolutions, "interpolation": self.interpolation,
                "start": self.start, "stop_at_zero": self.stop_at_zero,
                "bounded_fraction": self.bounded_fraction, "cutting_law": self.law.to_dict(),
                "force_noise": self.force_noise, "noise_interval_s": self.noise_interval_s,
                "noise_seed": self.noise_seed}


#: The lowest spindle speed (rev/min) whose lobes are computed.  Below it the lobe number
#: 60 f / rpm runs into the thousands, where process damping (which this linear model of
#: regeneration leaves out) decides stability, and the crossings to search grow as 1 / rpm:
#: at 10 rev/min one speed of the published bar takes about a minute and 2.5 GB.
MIN_LOBE_RPM = 10.0


def check_lobe_speed(name: str, rpm: float) -> float:
    """A spindle speed (rev/min) whose lobes can be computed: at least :data:`MIN_LOBE_RPM`."""
    return check_range(name, rpm, MIN_LOBE_RPM, math.inf, unit="rev/min",
                       why="below it process damping, left out here, decides; and the "
                           "lobes to search grow as 1 / rpm")

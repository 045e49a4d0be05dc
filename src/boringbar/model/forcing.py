"""Forcing at the cutting end (docs/model.md, section 4)."""

from __future__ import annotations

import math
from dataclasses import dataclass

from boringbar._validate import ParameterError, check_int, check_positive, check_range

#: Upper bounds that no machining needs but that keep the kernels' arithmetic
#: finite (a force of 1e300 N overflows the energy sums): force amplitude (N),
#: depth of cut (m), feed per revolution (m), specific cutting force (Pa).
MAX_FORCE = 1e6
MAX_DEPTH = 1.0
MAX_FEED = 0.1
MAX_KR = 1e12
#: Largest Omega / omega_n and forcing frequency (Hz) of harmonic forcing (the
#: published sweeps: 0.95 to 1.05); above, no step resolves the forcing anyway.
MAX_RATIO = 100.0
MAX_FREQUENCY_HZ = 1e6


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
#: Aluminium, docs/model.md, section 4.
KR_ALUMINIUM = 850e6


@dataclass(frozen=True)
class Regenerative:
    """Regenerative turning/boring, radial direction (docs/model.md, section 4).

    f(t) = Kr b h(t), h(t) = max(0, min_{k=1..N} [k h_m + W(t - k tau)] - W(t)),
    tau = 60 / rpm; the surface before the cut started is W = 0 (``start =
    "rest"``, as published: the mean force arrives as a step) or the static
    deflection under the mean force (``start = "static"``, a steady cut).
    The delayed W at RK4 stages is interpolated from the stored history
    with a cubic Hermite from W and W' (4th order, default) or linearly.
    ``depth_m`` b (m), ``rpm`` (rev/min), ``kr_pa`` the specific radial cutting force
    (Pa), ``feed_m`` h_m per revolution (m), ``revolutions`` N of the minimum;
    ``interpolation``: "cubic" or "linear".
    ``stop_at_zero`` ends the run at the first h = 0 (a lobe search needs no
    more); ``bounded_fraction``: the amplitude criterion's threshold, as a
    fraction of h_m.
    """

    depth_m: float  #: b, depth of cut (m)
    rpm: float  #: spindle speed (rev/min)
    kr_pa: float = KR_ALUMINIUM  #: specific radial cutting force (Pa)
    feed_m: float = 0.1e-3  #: h_m, feed per revolution (m)
    revolutions: int = 3  #: N, past revolutions in the chip-thickness minimum
    interpolation: str = "cubic"
    start: str = "rest"
    stop_at_zero: bool = False
    bounded_fraction: float = 0.1

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

    @property
    def tau_s(self) -> float:
        """Delay: one spindle revolution (s)."""
        return 60.0 / self.rpm

    @property
    def mean_force_n(self) -> float:
        """Kr b h_m (N)."""
        return self.kr_pa * self.depth_m * self.feed_m

    def to_dict(self) -> dict:
        return {"type": "regenerative", "depth_m": self.depth_m, "rpm": self.rpm,
                "kr_pa": self.kr_pa, "feed_m": self.feed_m, "revolutions": self.revolutions,
                "interpolation": self.interpolation, "start": self.start,
                "stop_at_zero": self.stop_at_zero, "bounded_fraction": self.bounded_fraction}

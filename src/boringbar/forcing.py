"""Forcing at the cutting end (MODEL.md section 4)."""

from __future__ import annotations

import math
from dataclasses import dataclass

from boringbar._validate import ParameterError, check_nonnegative, check_positive


@dataclass(frozen=True)
class Harmonic:
    """f(t) = amplitude sin(Omega t) at the tip.

    Give the frequency as ``ratio`` = Omega / omega_n of the host bar (MODEL.md
    section 6: the ball-cavity bar for the ball damper, the solid bar for the
    solid and TMD bars) or as ``frequency_hz``, not both.
    """

    amplitude: float = 10.0  #: F0 (N)
    ratio: float | None = 1.0
    frequency_hz: float | None = None

    def __post_init__(self):
        check_nonnegative("force amplitude", self.amplitude, "N")
        if (self.ratio is None) == (self.frequency_hz is None):
            raise ParameterError("harmonic forcing: give exactly one of ratio "
                                 "(Omega/omega_n) or frequency_hz")
        if self.ratio is not None:
            check_positive("ratio (Omega/omega_n)", self.ratio)
        else:
            check_positive("frequency_hz", self.frequency_hz, "Hz")

    def omega(self, reference: float) -> float:
        """Omega (rad/s), with ``reference`` = omega_n of the host bar."""
        if self.ratio is not None:
            return self.ratio * reference
        return 2.0 * math.pi * self.frequency_hz

    def to_dict(self) -> dict:
        return {"type": "harmonic", "amplitude_n": self.amplitude, "ratio": self.ratio,
                "frequency_hz": self.frequency_hz}

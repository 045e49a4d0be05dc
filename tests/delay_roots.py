"""The rightmost characteristic root of a one-mode bar's regenerative cut,
m s^2 + c s + k + psi^2 Kr b (1 - exp(-s tau)) = 0, by Newton's method from starts along
the imaginary axis about the natural frequency: a truth that does not come from the
simulation (tests/test_verdict.py, tests/test_stick_law.py)."""

from __future__ import annotations

import cmath

import numpy as np


def rightmost_root(m: float, c: float, k: float, psi2: float, kb: float, tau: float) -> complex:
    """The root with the largest real part among those found from 26 starts between 0.8
    and 1.3 of sqrt(k / m)."""

    def f(s):
        return m * s * s + c * s + k + psi2 * kb * (1 - cmath.exp(-s * tau))

    def df(s):
        return 2 * m * s + c + psi2 * kb * tau * cmath.exp(-s * tau)

    roots = []
    for w in np.linspace(0.8, 1.3, 26) * np.sqrt(k / m):
        s = complex(0.0, w)
        for _ in range(100):
            s -= f(s) / df(s)
        if abs(f(s)) < 1e-8 * k:
            roots.append(s)
    return max(roots, key=lambda r: r.real)

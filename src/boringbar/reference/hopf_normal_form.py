"""The leading-order branch of chatter orbits at the Hopf point of a one-mode cut with a
smooth nonlinear cutting force.

T. Kalmár-Nagy, G. Stépán and F. C. Moon, "Subcritical Hopf bifurcation in the delay
equation model for machine tool vibrations", Nonlinear Dynamics 26 (2001) 121-142, study
one degree of freedom in the cut,

    x'' + 2 zeta w_n x' + w_n^2 x = (k_1 / m) (Delta + a_2 Delta^2 + a_3 Delta^3),
    Delta = x(t - tau) - x(t),

the right side the 3/4 power law of the chip thickness f = f_0 + Delta expanded to cubic
order about the feed f_0 (k_1 = dF/df at f_0, proportional to the chip width).  They
reduce the delay equation to its two-dimensional centre manifold (their equation (24),
approximated to second order through their equations (28)-(34)) and bring the reduced
system to the Hopf normal form (their section 6): the periodic orbit born at the linear
stability limit has an amplitude growing as the square root of the distance from it, on
the stable side (subcritical: an unstable orbit around the stable cut).

This module computes the same leading order for any cubic force (coefficients a_2, a_3)
by harmonic balance about the Hopf point (Lyapunov-Schmidt).  It is not the paper's
algebra, and the paper's closed form is not transcribed here, but to this order the two
must agree: the normal form's coefficients are unique.  Time is w_n t and
p = k_1 / (m w_n^2):

    D(W, p) = 1 - W^2 + 2 i zeta W + p (1 - e^{-i W T}),      T = w_n tau,

the Hopf point (p_c, W_c) the root of D with the smallest p (:func:`hopf_point`), and the
orbit x = A cos(W t) + O(A^2) with p = p_c + p_2 A^2 + O(A^4), where

    E_1 = e^{-i W_c T} - 1,    E_2 = e^{-2 i W_c T} - 1,    D_2 = D(2 W_c, p_c),
    R   = p_c |E_1|^2 E_1 (p_c a_2^2 E_2 / (2 D_2) + 3 a_3 / 4),
    p_2 = Im(R conj(D_W)) / Im(-E_1 conj(D_W)),
    D_W = dD/dW = -2 W_c + 2 i zeta + i T p_c e^{-i W_c T}.

The orbit is unstable where it lies below the Hopf point: its one multiplier off the unit
circle (the normal form's) is 1 - 2 Re(lambda'(p_c)) (p - p_c) 2 pi / W_c + O(A^4), with
lambda'(p_c) = -(1 - e^{-i W_c T}) / (2 i W_c + 2 zeta + p_c T e^{-i W_c T}) the critical
root's speed (:func:`root_speed`), Re lambda' > 0.

(The O(A^2) mean shift of x drops out of Delta; the second harmonic 2 W_c, through the
quadratic term, does not.)  For a boring bar's first mode, M u'' + C u' + K u =
psi F(b, h) with the tip displacement y = psi u (the code's W): x = y - y_static,
m = M / psi^2, k_1 = dF/dh at h_m, and the depth b is proportional to p,
so (b - b_H) / b_H = (p_2 / p_c) A^2 with A the tip's amplitude (half its peak-to-peak
to this order).  For Kienzle's law F = K b h (h / 1 mm)^(-m_c), a power q = 1 - m_c:
a_2 = (q - 1) / (2 h_m), a_3 = (q - 1)(q - 2) / (6 h_m^2) (:func:`power_law_coefficients`);
q = 3/4 is the paper's law, a_2 = -1 / (8 h_m), a_3 = 5 / (96 h_m^2).
"""

from __future__ import annotations

import cmath
import math
from dataclasses import dataclass

import numpy as np
import scipy.optimize

from boringbar._validate import check_positive, check_range

#: Lobes searched for the lowest Hopf point.
LOBES = 200


@dataclass(frozen=True)
class HopfPoint:
    """A root of the characteristic function: ``p`` = k_1 / (m w_n^2), ``omega`` = W the
    chatter frequency over w_n, ``lobe`` j (W T = 2 pi (j + 1) - 2 atan((W^2 - 1) / (2 zeta W)))."""

    p: float
    omega: float
    lobe: int


def characteristic(zeta: float, tau: float, omega, p) -> complex:
    """D(W, p) = 1 - W^2 + 2 i zeta W + p (1 - e^{-i W T}), ``tau`` = T = w_n tau."""
    return 1.0 - omega * omega + 2j * zeta * omega + p * (1.0 - np.exp(-1j * omega * tau))


def hopf_point(zeta: float, tau: float) -> HopfPoint:
    """The lowest Hopf point at the dimensionless delay ``tau`` = w_n tau (one mode,
    damping ratio ``zeta``): on lobe j, W > 1 solves
    W T = 2 pi (j + 1) - 2 atan((W^2 - 1) / (2 zeta W)) and p = ((W^2 - 1)^2
    + 4 zeta^2 W^2) / (2 (W^2 - 1))."""
    check_range("zeta", zeta, 0.0, 1.0, lo_open=True, hi_open=True)
    check_positive("tau", tau)

    def phase(w, j):
        return w * tau - 2.0 * math.pi * (j + 1) + 2.0 * math.atan((w * w - 1.0) / (2 * zeta * w))

    best = None
    for j in range(LOBES):
        # phase() rises with W; lobe j reaches this delay where it is negative at W = 1
        lo, hi = 1.0 + 1e-12, 2.0
        if phase(lo, j) >= 0.0:
            continue
        while phase(hi, j) < 0.0:
            hi *= 2.0
        w = scipy.optimize.brentq(phase, lo, hi, args=(j,), xtol=1e-15, rtol=1e-15)
        p = ((w * w - 1.0) ** 2 + 4.0 * zeta**2 * w * w) / (2.0 * (w * w - 1.0))
        if best is None or p < best.p:
            best = HopfPoint(p, w, j)
    return best


def depth_curvature(zeta: float, tau: float, a2: float, a3: float,
                    hopf: HopfPoint | None = None) -> float:
    """p_2 / p_c: the relative distance of the orbit's parameter from the Hopf point per
    squared amplitude, (p - p_c) / p_c = (p_2 / p_c) A^2 to leading order (units of
    1 / a_2^2).  Negative: subcritical (the orbits lie below the stability limit)."""
    h = hopf_point(zeta, tau) if hopf is None else hopf
    w, p = h.omega, h.p
    e1 = cmath.exp(-1j * w * tau) - 1.0
    e2 = cmath.exp(-2j * w * tau) - 1.0
    d2 = characteristic(zeta, tau, 2.0 * w, p)
    dw = -2.0 * w + 2j * zeta + 1j * tau * p * cmath.exp(-1j * w * tau)
    r = p * abs(e1) ** 2 * e1 * (p * a2 * a2 * e2 / (2.0 * d2) + 0.75 * a3)
    p2 = (r * dw.conjugate()).imag / (-e1 * dw.conjugate()).imag
    return p2 / p


def root_speed(zeta: float, tau: float, hopf: HopfPoint | None = None) -> complex:
    """d lambda / d p of the critical root lambda = i W_c at the Hopf point (units of w_n)."""
    h = hopf_point(zeta, tau) if hopf is None else hopf
    e = cmath.exp(-1j * h.omega * tau)
    return -(1.0 - e) / (2j * h.omega + 2.0 * zeta + h.p * tau * e)


def power_law_coefficients(exponent: float, feed: float) -> tuple[float, float]:
    """(a_2, a_3) of F = c h^q expanded about h = ``feed``: F(h_m + d) = F(h_m)
    + F'(h_m) (d + a_2 d^2 + a_3 d^3 + ...), q = ``exponent`` (1 - m_c for Kienzle)."""
    check_positive("feed", feed)
    q = exponent
    return (q - 1.0) / (2.0 * feed), (q - 1.0) * (q - 2.0) / (6.0 * feed**2)


def depth_shift(zeta: float, tau: float, exponent: float, feed: float,
                amplitude) -> np.ndarray:
    """(b - b_H) / b_H of the chatter orbit of tip amplitude ``amplitude`` (m) for the
    power law F proportional to b h^``exponent`` at the feed ``feed`` (m), leading order."""
    a2, a3 = power_law_coefficients(exponent, feed)
    return depth_curvature(zeta, tau, a2, a3) * np.asarray(amplitude, dtype=float) ** 2


def amplitude(zeta: float, tau: float, exponent: float, feed: float, depth_ratio) -> np.ndarray:
    """The leading-order tip amplitude (m) of the orbit at the depth ``depth_ratio`` =
    b / b_H: A = sqrt((b / b_H - 1) / (p_2 / p_c)), nan where the orbit is on the other side."""
    a2, a3 = power_law_coefficients(exponent, feed)
    c = depth_curvature(zeta, tau, a2, a3)
    x = (np.asarray(depth_ratio, dtype=float) - 1.0) / c
    return np.sqrt(np.where(x >= 0.0, x, np.nan))

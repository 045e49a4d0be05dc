"""Compliant contact of the ball with the cavity's plugs (docs/model.md, section 2.6).

Hertz's law between a sphere of radius R and a flat plug, F = K d^1.5 with
K = 4/3 E* sqrt(R) and 1/E* = (1 - nu_1^2)/E_1 + (1 - nu_2^2)/E_2, and Hunt and
Crossley's damping, F = K d^1.5 (1 + chi d'), with chi = alpha / v_in set per contact
from the speed v_in it begins with.  The restitution of such a contact depends on
alpha = chi v_in alone: with d = L X, t = T s, L / T = v_in and m L / T^2 = K L^1.5 the
equation m d'' = -K d^1.5 (1 + chi d') becomes X'' = -X^1.5 (1 + alpha X'), X(0) = 0,
X'(0) = 1, and e = -X' where X returns to 0.  The compiled core inverts that relation
numerically (``boringbar.simulate.kernels.hunt_crossley_alpha``), so that every contact
of a free two-body impact restores exactly the restitution e the ball is given.

The closed forms of an elastic Hertz impact (Johnson, *Contact Mechanics*, 1985,
section 11.4) are the truths the tests hold the kernel to:
d_max = (5 m v^2 / (4 K))^(2/5), F_max = K d_max^1.5 and the contact time
t_c = (4/5) B(2/5, 1/2) d_max / v = 2.9432 d_max / v.
"""

from __future__ import annotations

import math

from boringbar._validate import ParameterError, check_positive

#: The contact laws of a ball: today's instantaneous impact law, or Hertz's compliant one.
CONTACT_LAWS = ("impact", "hertz")
#: The least restitution a Hunt-Crossley contact can be given: below it alpha grows
#: without bound (e -> 0 as alpha -> infinity) and the contact's damping stiffens the
#: step; the impact law takes any e in [0, 1].
HERTZ_MIN_RESTITUTION = 0.05
#: (4/5) B(2/5, 1/2): an elastic Hertz impact lasts this many d_max / v.
HERTZ_TIME_FACTOR = 0.8 * math.gamma(0.4) * math.gamma(0.5) / math.gamma(0.9)


def effective_modulus_pa(e1_pa: float, nu1: float, e2_pa: float, nu2: float) -> float:
    """E* (Pa) of two bodies of Young's moduli ``e1_pa``, ``e2_pa`` (Pa) and Poisson's
    ratios ``nu1``, ``nu2``."""
    return 1.0 / ((1.0 - nu1**2) / e1_pa + (1.0 - nu2**2) / e2_pa)


def hertz_stiffness_n_m1_5(radius_m: float, modulus_pa: float) -> float:
    """K (N/m^1.5) of a sphere of ``radius_m`` (m) on a flat, E* = ``modulus_pa`` (Pa)."""
    return 4.0 / 3.0 * modulus_pa * math.sqrt(radius_m)


def hertz_max_indentation_m(mass_kg: float, stiffness_n_m1_5: float, speed_m_s: float) -> float:
    """d_max (m) of an elastic impact of ``mass_kg`` (kg, the pair's effective mass) at
    ``speed_m_s`` (m/s) through K = ``stiffness_n_m1_5``."""
    return (5.0 * mass_kg * speed_m_s**2 / (4.0 * stiffness_n_m1_5)) ** 0.4


def hertz_contact_time_s(mass_kg: float, stiffness_n_m1_5: float, speed_m_s: float) -> float:
    """The duration (s) of an elastic Hertz impact (module docstring)."""
    d = hertz_max_indentation_m(mass_kg, stiffness_n_m1_5, speed_m_s)
    return HERTZ_TIME_FACTOR * d / speed_m_s


def hertz_peak_force_n(mass_kg: float, stiffness_n_m1_5: float, speed_m_s: float) -> float:
    """The largest force (N) of an elastic Hertz impact: K d_max^1.5."""
    return stiffness_n_m1_5 * hertz_max_indentation_m(mass_kg, stiffness_n_m1_5,
                                                      speed_m_s) ** 1.5


def check_hertz_restitution(restitution) -> float:
    """The restitution e a Hertz contact can be given, in [HERTZ_MIN_RESTITUTION, 1]."""
    e = restitution
    if not (isinstance(e, int | float) and HERTZ_MIN_RESTITUTION <= e <= 1.0):
        raise ParameterError(f"restitution = {e!r} is outside the range a Hertz contact "
                             f"allows, [{HERTZ_MIN_RESTITUTION}, 1] (Hunt-Crossley's damping "
                             "grows without bound as e -> 0); use contact = 'impact'")
    return float(e)


def check_contact_stiffness(value) -> float:
    """A contact stiffness K (N/m^1.5), finite and > 0."""
    return check_positive("contact_stiffness_n_m1_5", value, "N/m^1.5")

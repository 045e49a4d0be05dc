"""The chatter branch of a power-law cut near its Hopf point against the Hopf normal form
of the one-degree-of-freedom delay equation (Kalmár-Nagy, Stépán and Moon, Nonlinear
Dynamics 26 (2001) 121-142; boringbar.reference.hopf_normal_form), to leading order.

One mode of the carbide bar in the cut of a steel workpiece (Kienzle, m_c = 0.22, a power
q = 0.78 of the chip) and of a law with m_c = 1/4 (q = 3/4, the paper's), one revolution of
memory (the paper's single delay), at two speeds (lobes 12 and 3):

- the Hopf point (depth, frequency) is the root of the one-mode characteristic function;
- (b - b_H) / b_H of the orbits of tip amplitude A = 4, 2, 1 % of h_m is the normal form's
  (p_2 / p_c) A^2 to a relative 2e-3, and the difference falls as A^2 (the next term of the
  normal form, A^4, over the first);
- the traced branch leaves the Hopf point to smaller depths (subcritical), the tool in the
  cut, each orbit unstable, its multiplier off the unit circle the normal form's
  1 - 2 Re(lambda') (p - p_c) T.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import boringbar as bb
from boringbar.orbits import cut_branch as cb
from boringbar.orbits import cut_orbits as co
from boringbar.reference import hopf_normal_form as nf

CARBIDE = "examples/systems/carbide_ld10_tungsten.toml"
FEED = 0.1e-3
PAPER_LAW = bb.CuttingLaw.kienzle(kc11_pa=1700e6, mc=0.25, radial_ratio=1.0)
LAWS = {"steel": "steel", "q=3/4": PAPER_LAW}
SPEEDS = (1200.0, 4321.0)


@pytest.fixture(scope="module")
def one_mode():
    bar = bb.variants(bb.load_system(CARBIDE))["solid"].bar.truncated(1)
    return bb.System(bar)


def _forcing(law, rpm):
    return bb.Regenerative(depth_m=1e-5, rpm=rpm, workpiece=LAWS[law], feed_m=FEED,
                           revolutions=1)


def _dimensionless(system, rpm):
    bar = system.bar
    wn = float(bar.omegas_rad_s[0])
    return float(bar.damping_ratio[0]), wn * 60.0 / rpm, wn


def _tip_amplitude(model, o):
    w = o.x @ model.c
    return 0.5 * float(w.max() - w.min())


def test_the_power_law_expands_as_the_code_cuts():
    """a_2, a_3 against the law's own force: the paper's 3/4 law gives -1/(8 h_m) and
    5/(96 h_m^2)."""
    a2, a3 = nf.power_law_coefficients(0.75, FEED)
    assert a2 == pytest.approx(-1.0 / (8.0 * FEED), rel=1e-12)
    assert a3 == pytest.approx(5.0 / (96.0 * FEED**2), rel=1e-12)
    for law in (PAPER_LAW, bb.CuttingLaw.kienzle("steel")):
        a2, a3 = nf.power_law_coefficients(1.0 - law.mc, FEED)
        d = np.array([-2e-6, -1e-6, 1e-6, 2e-6])
        f0 = float(law.force_n(1e-3, FEED))
        k1 = law.linear_coefficient_pa(FEED) * 1e-3
        cubic = f0 + k1 * (d + a2 * d**2 + a3 * d**3)
        exact = np.array([float(law.force_n(1e-3, FEED + x)) for x in d])
        err = np.abs(exact - cubic)
        assert np.max(err) < 1e-8 * f0
        assert 12.0 < err[0] / err[1] < 20.0 and 12.0 < err[3] / err[2] < 20.0  # O(d^4)


@pytest.mark.parametrize("law", list(LAWS))
@pytest.mark.parametrize("rpm", SPEEDS)
def test_the_branch_leaves_the_hopf_point_as_the_normal_form(one_mode, law, rpm):
    forcing = _forcing(law, rpm)
    model = co.cut_model(one_mode, forcing)
    zeta, tau, wn = _dimensionless(one_mode, rpm)
    hopf = cb.hopf_orbit(one_mode, forcing, model, None)
    h = nf.hopf_point(zeta, tau)
    bar = one_mode.bar
    k1_per_depth = model.law.linear_coefficient_pa(FEED)
    depth = h.p * bar.stiffness_n_m[0] / bar.psi_tip[0] ** 2 / k1_per_depth
    assert hopf.depth == pytest.approx(depth, rel=1e-6)
    assert 2.0 * math.pi / hopf.period == pytest.approx(h.omega * wn, rel=1e-6)

    q = 1.0 - model.law.mc
    errors = []
    for frac in (0.04, 0.02, 0.01):
        o, _ = cb.fixed_amplitude(model, hopf, frac * FEED)
        amp = _tip_amplitude(model, o)
        shift = (o.depth - hopf.depth) / hopf.depth
        predicted = float(nf.depth_shift(zeta, tau, q, FEED, amp))
        assert shift < 0.0 and predicted < 0.0
        errors.append(abs(shift / predicted - 1.0))
    assert errors[0] < 2e-3, errors
    # leading order: the relative difference falls with the amplitude, here as A^2
    assert errors[0] / errors[1] > 3.0 and errors[1] / errors[2] > 3.0, errors


@pytest.mark.parametrize("law", list(LAWS))
def test_the_traced_branch_is_subcritical_and_unstable(one_mode, law):
    rpm = SPEEDS[0]
    forcing = _forcing(law, rpm)
    br = cb.trace(one_mode, forcing, (0.0, 1e-3), max_points=4)
    assert br.events[0].kind == "hopf"
    hopf = br.events[0].depth
    zeta, tau, _ = _dimensionless(one_mode, rpm)
    h = nf.hopf_point(zeta, tau)
    speed = nf.root_speed(zeta, tau, h)
    assert speed.real > 0.0
    q = 1.0 - (0.22 if law == "steel" else 0.25)
    depths = [p.orbit.depth for p in br.points]
    assert all(b < a for a, b in zip([hopf, *depths], depths, strict=False)), depths
    for p in br.points:
        assert 0.0 < p.amplitude < 0.11 * FEED and p.min_chip > 0.8 * FEED
        shift = (p.orbit.depth - hopf) / hopf
        assert shift == pytest.approx(float(nf.depth_shift(zeta, tau, q, FEED, p.amplitude)),
                                      rel=1e-2)
        mu = np.abs(cb.nontrivial(p.multipliers)).max()
        expected = -2.0 * speed.real * h.p * shift * 2.0 * math.pi / h.omega
        assert mu - 1.0 == pytest.approx(expected, rel=2e-2)
    assert all(p.unstable == 1 for p in br.points[1:])  # the first is within NEUTRAL of 1

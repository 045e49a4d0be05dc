"""Simulations against truths that do not come from the kernel: the analytic
frequency response of the linear bars and the closed-form two-impact orbit."""

import math

import numpy as np
import pytest

from boringbar import Harmonic, State, make_system, simulate
from boringbar.reference.linear import tip_frf
from boringbar.reference.masri_caughey import two_impact_orbit

RATIOS = np.round(np.arange(0.95, 1.05 + 1e-9, 0.01), 2)


@pytest.mark.parametrize("preset", ["physical", "paper"])
@pytest.mark.parametrize("bar", ["solid", "tmd"])
def test_linear_bars_match_analytic_frequency_response(bar, preset):
    system = make_system(bar, preset)
    tmd = system.damper
    worst = 0.0
    for r in RATIOS:
        run = simulate(system, Harmonic(10.0, float(r)), duration_s=1.0)
        omega = r * system.reference_frequency_rad_s
        g = tip_frf(system.bar, np.array([omega]), tmd=tmd)[0]
        expected = 10.0 * abs(g) / math.sqrt(2.0)  # RMS of a sinusoid
        worst = max(worst, abs(run.rms_tip_m / expected - 1.0))
    # 1 % is the bar; the sampled RMS over a non-integer number of
    # periods and the 0.2 s of decayed transient leave far less than that
    assert worst < 1e-3, worst


def _orbit_state(orbit, t):
    """x = [u, u', y, y'] on the closed-form orbit at time t (between impacts)."""
    sys = orbit.system
    sign = orbit._split(t)[0]
    u = float(orbit.modal_displacement(t))
    v = float(orbit.modal_velocity(t))
    y = float(orbit.relative_displacement(t))
    ud_dot = -float(sign) * orbit.ball_speed  # after a + wall impact the ball moves to -
    return np.array([u, v, y, ud_dot - sys.psi_ball * v])


def test_ball_damper_matches_masri_caughey_two_impact_orbit():
    """One mode, no friction: the published scheme converges (first order in dt,
    from late impact detection) to the closed-form symmetric orbit."""
    system = make_system("ball", "physical", n_modes=1, friction=False, gap_m=0.5e-3)
    b, d = system.bar, system.damper
    omega = system.reference_frequency_rad_s
    orbits = two_impact_orbit(b.mass_kg[0], b.stiffness_n_m[0], b.damping_n_s_m[0], b.psi_tip[0],
                              b.psi_damper[0], d.mass_kg, d.gap_m, d.restitution, 30.0, omega)
    (orbit,) = [o for o in orbits if o.admissible and o.stable]
    x0 = _orbit_state(orbit, 0.0)
    errors = []
    for dt in (2e-6, 1e-6, 5e-7):
        run = simulate(system, Harmonic(30.0, 1.0), duration_s=0.1, dt_s=dt,
                       initial=State(x0, 0.0), integrator="rk4")
        assert run.pattern.name == "2 symmetric"
        plus = run.impacts[run.impacts[:, 1] > 0, 0]
        phase = np.mod(omega * plus, 2 * np.pi)
        assert np.all(np.abs(phase - orbit.phase) < 4 * omega * dt + 1e-9)
        errors.append(abs(run.rms_tip_m / orbit.rms_tip() - 1.0))
    assert errors[1] < 2e-3
    assert errors[2] < errors[0]


def test_poincare_strobe_of_linear_bar_is_the_analytic_steady_state():
    """At Omega t = 0 mod 2 pi the steady W = F0 Im G and W' = F0 Omega Re G."""
    system = make_system("solid", "physical")
    run = simulate(system, Harmonic(10.0, 1.01), duration_s=0.8, strobe=True)
    omega = 1.01 * system.reference_frequency_rad_s
    g = tip_frf(system.bar, np.array([omega]), tmd=None)[0]
    late = run.strobe[run.strobe[:, 0] > 0.6]  # transient decayed by exp(-19)
    assert len(late) > 50
    assert np.allclose(np.mod(omega * late[:, 0] + 1e-9, 2 * np.pi), 1e-9, atol=1e-8)
    assert np.allclose(late[:, 1], 10.0 * g.imag, rtol=0, atol=1e-6 * 10.0 * abs(g))
    assert np.allclose(late[:, 2], 10.0 * omega * g.real, rtol=0,
                       atol=1e-6 * 10.0 * omega * abs(g))

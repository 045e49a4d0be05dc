"""The closed-form two-impact orbit (boringbar.reference.masri_caughey).

The reference is independent of the closed form: the same model integrated
with scipy's DOP853 from impact to impact (terminal events at the walls,
the impact law applied, restart), as in docs/model.md, section 2.

Case: the published ball-cavity bar, one mode, carbide ball 26 g, gap
0.5 mm, e = 0.7, Omega = omega_n.  At the published F0 = 10 N no symmetric
two-impact orbit exists (sqrt(a^2 + b^2) = 0.80 delta < delta in the phase
equation), so the comparison runs at F0 = 30 N, where one admissible,
stable orbit exists (largest multiplier 0.915 per half period).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import boringbar as bb
from boringbar._validate import ParameterError
from boringbar.model.bar import published_bar
from boringbar.orbits.shooting import make_flow, multipliers, periodic_orbit
from boringbar.reference.masri_caughey import (
    ImpactSystem,
    phase_equation,
    two_impact_orbit,
)

BALL, GAP, E = 0.026, 0.5e-3, 0.7


def published_args(force: float, ratio: float, bar=None) -> tuple:
    bar = published_bar(True, 1) if bar is None else bar
    return (
        bar.mass_kg[0],
        bar.stiffness_n_m[0],
        bar.damping_n_s_m[0],
        bar.psi_tip[0],
        bar.psi_damper[0],
        BALL,
        GAP,
        E,
        force,
        ratio * bar.natural_frequency_rad_s,
    )


def admissible(orbits):
    return [o for o in orbits if o.admissible]


# --- the reference: event-driven integration -----------------------------------------
def integrate(sys: ImpactSystem, state, t0: float, n_periods: float):
    """Integrate (u, u', u_d, u_d', int W^2 dt) from t0; returns (impacts, state, t).

    impacts: list of (time, wall = +1 or -1).  Impact law of docs/model.md, section 2:
    y'+ = -e y'-,  u'+ = u'- + (1 + e) mu psi_d y'- / (1 + mu psi_d^2).
    """
    mu = sys.ball_mass / sys.mass
    pl, pd, half = sys.psi_tip, sys.psi_ball, 0.5 * sys.gap

    def rhs(t, x):
        u, v, _, w, _ = x
        force = pl * sys.force * math.sin(sys.omega * t)
        return [v, (force - sys.damping * v - sys.stiffness * u) / sys.mass, w, 0.0, (pl * u) ** 2]

    def plus_wall(t, x):
        return x[2] - pd * x[0] - half

    def minus_wall(t, x):
        return x[2] - pd * x[0] + half

    plus_wall.terminal = minus_wall.terminal = True
    plus_wall.direction, minus_wall.direction = 1, -1
    atol = 1e-16 * np.array([1e-3, 1.0, 1e-3, 1.0, 1e-8]) * 100
    t_end = t0 + n_periods * 2 * math.pi / sys.omega
    x, t, impacts = np.array(state, dtype=float), t0, []
    while t < t_end:
        sol = solve_ivp(
            rhs,
            (t, t_end),
            x,
            method="DOP853",
            rtol=1e-10,
            atol=atol,
            events=(plus_wall, minus_wall),
        )
        t, x = sol.t[-1], sol.y[:, -1].copy()
        if sol.status == 1:
            wall = 1 if sol.t_events[0].size else -1
            approach = x[3] - pd * x[1]
            x[1] += (1 + E) * mu * pd * approach / (1 + mu * pd**2)
            x[3] = pd * x[1] - E * approach
            x[2] = pd * x[0] + wall * half  # exactly on the wall
            impacts.append((t, wall))
    return impacts, x, t


def start_near(orbit, rel: float):
    """The state just after a + wall impact on ``orbit``, u perturbed by ``rel``."""
    sys = orbit.system
    t0 = orbit.impact_time
    u0 = float(orbit.modal_displacement(t0))
    v0 = orbit.bar_velocity_after / sys.psi_ball
    state = [u0 * (1 + rel), v0, sys.psi_ball * u0 + 0.5 * sys.gap, -orbit.ball_speed, 0.0]
    return state, t0 + 1e-12


def wrapped(x):
    return (np.asarray(x) + math.pi) % (2 * math.pi) - math.pi


# --- existence ----------------------------------------------------------------------
def test_published_10_newton_case_has_no_two_impact_orbit():
    sys = ImpactSystem(*published_args(10.0, 1.0))
    a, b, c = phase_equation(sys)
    assert math.hypot(a, b) / c == pytest.approx(0.80, abs=0.01)
    assert two_impact_orbit(*published_args(10.0, 1.0)) == []


def test_no_forcing_no_orbit_and_bad_damping_is_refused():
    assert two_impact_orbit(*published_args(0.0, 1.0)) == []
    args = list(published_args(30.0, 1.0))
    args[2] = 2 * math.sqrt(args[0] * args[1])  # critically damped
    with pytest.raises(ParameterError, match="modal damping C"):
        two_impact_orbit(*args)
    args[2] = 0.0  # undamped and forced at resonance, or at omega_n / 3
    args[-1] = math.sqrt(args[1] / args[0])
    with pytest.raises(ParameterError, match="resonance"):
        two_impact_orbit(*args)
    args[-1] /= 3
    with pytest.raises(ParameterError, match="resonance"):
        two_impact_orbit(*args)


def test_30_newton_case_has_one_admissible_stable_orbit():
    orbits = two_impact_orbit(*published_args(30.0, 1.0))
    assert len(orbits) == 2
    good = admissible(orbits)
    assert len(good) == 1 and good[0].stable
    bad = [o for o in orbits if not o.admissible][0]
    assert "ball speed" in bad.message and bad.ball_speed < 0 and bad.stable is None
    assert max(abs(np.array(good[0].multipliers))) == pytest.approx(0.915, abs=0.005)


# --- against direct integration -------------------------------------------------------------
def test_closed_form_orbit_is_the_integrated_steady_state():
    orbit = admissible(two_impact_orbit(*published_args(30.0, 1.0)))[0]
    sys = orbit.system
    state, t0 = start_near(orbit, 1e-3)
    impacts, x, t = integrate(sys, state, t0, 150)
    walls = np.array([w for _, w in impacts])
    assert np.all(walls[1:] == -walls[:-1])  # alternating walls throughout
    times = np.array([ti for ti, _ in impacts[-20:]])
    phases = wrapped(sys.omega * times - orbit.phase - np.where(walls[-20:] > 0, 0, math.pi))
    assert np.max(np.abs(phases)) < 1e-8  # achieved: 2e-11 rad
    # RMS of W over the next 10 periods, integrated as a fifth state
    _, x2, t2 = integrate(sys, list(x[:4]) + [0.0], t, 10)
    rms = math.sqrt(x2[4] / (t2 - t))
    assert rms == pytest.approx(orbit.rms_tip(), rel=1e-8)  # achieved: 2e-10


def test_an_orbit_flagged_unstable_is_left_by_the_integration():
    """20 N at Omega = omega_n: the admissible orbit has a multiplier of 4.15."""
    orbit = admissible(two_impact_orbit(*published_args(20.0, 1.0)))[0]
    assert orbit.stable is False
    state, t0 = start_near(orbit, 1e-7)
    impacts, _, _ = integrate(orbit.system, state, t0, 40)
    plus = np.array([ti for ti, w in impacts if w == 1])
    drift = np.abs(wrapped(orbit.system.omega * plus - orbit.phase))
    assert drift[0] < 1e-5 and drift.max() > 1e-2


# --- the closed form's own consistency -----------------------------------------------------
@pytest.fixture(scope="module")
def orbit():
    return admissible(two_impact_orbit(*published_args(30.0, 1.0)))[0]


def test_orbit_meets_the_walls_and_is_antisymmetric(orbit):
    sys, t0, th = orbit.system, orbit.impact_time, orbit.system.half_period
    assert float(orbit.relative_displacement(t0)) == pytest.approx(GAP / 2, rel=1e-10)
    assert float(orbit.relative_displacement(t0 + th)) == pytest.approx(-GAP / 2, rel=1e-10)
    t = t0 + np.linspace(0.01, 0.99, 50) * th
    u = orbit.modal_displacement(t)
    # round-off: 1e-12 of the orbit's amplitude (a value near a zero crossing has no
    # relative digits to keep)
    np.testing.assert_allclose(
        orbit.modal_displacement(t + th), -u, rtol=1e-12, atol=1e-12 * np.abs(u).max()
    )
    tip = orbit.tip(t)
    np.testing.assert_allclose(orbit.tip(t + 2 * th), tip, rtol=1e-12,
                               atol=1e-12 * np.abs(tip).max())
    assert np.all(np.abs(orbit.relative_displacement(t)) < GAP / 2)
    assert sys.psi_tip * float(orbit.modal_displacement(t0)) == float(orbit.tip(t0))


def test_impact_conserves_momentum_and_obeys_restitution(orbit):
    sys = orbit.system
    v_minus = orbit.bar_velocity_before / sys.psi_ball  # modal
    v_plus = orbit.bar_velocity_after / sys.psi_ball
    w_minus, w_plus = orbit.ball_speed, -orbit.ball_speed
    # (M / psi_d) u' + m u_d' is conserved across the impact
    before = sys.mass / sys.psi_ball * v_minus + sys.ball_mass * w_minus
    after = sys.mass / sys.psi_ball * v_plus + sys.ball_mass * w_plus
    assert after == pytest.approx(before, abs=1e-12 * abs(before))
    approach = w_minus - orbit.bar_velocity_before
    assert approach > 0 and orbit.impulse < 0
    assert w_plus - orbit.bar_velocity_after == pytest.approx(-E * approach, rel=1e-12)
    # the closed-form velocity just after matches the time history
    assert float(orbit.modal_velocity(orbit.impact_time)) == pytest.approx(v_plus, rel=1e-10)


def test_orbit_obeys_the_bar_equation_between_impacts(orbit):
    sys, t0, th = orbit.system, orbit.impact_time, orbit.system.half_period
    t = t0 + np.linspace(0.1, 0.9, 9) * th
    h = 1e-3 * th
    u = orbit.modal_displacement
    acc = (u(t + h) - 2 * u(t) + u(t - h)) / h**2
    vel = orbit.modal_velocity(t)
    np.testing.assert_allclose(vel, (u(t + h) - u(t - h)) / (2 * h), rtol=1e-5, atol=1e-9)
    residual = (
        sys.mass * acc
        + sys.damping * vel
        + sys.stiffness * u(t)
        - sys.psi_tip * sys.force * np.sin(sys.omega * t)
    )
    assert np.max(np.abs(residual)) < 1e-5 * sys.stiffness * np.max(np.abs(u(t)))


def test_energy_balance_over_a_period(orbit):
    """Work of the force = viscous loss + 2 impacts x (1 - e^2)/2 m_eff y'-^2."""
    sys, t0, th = orbit.system, orbit.impact_time, orbit.system.half_period
    x, wq = np.polynomial.legendre.leggauss(200)
    t = t0 + 0.5 * th * (x + 1)  # Gauss nodes inside one smooth half period
    vel = orbit.modal_velocity(t)
    work = 0.5 * th * np.sum(wq * sys.psi_tip * sys.force * np.sin(sys.omega * t) * vel)
    viscous = 0.5 * th * np.sum(wq * sys.damping * vel**2)
    m_eff = sys.ball_mass / (1 + sys.effective_ratio)
    approach = orbit.ball_speed - orbit.bar_velocity_before
    impact = 0.5 * (1 - E**2) * m_eff * approach**2
    assert 2 * work == pytest.approx(2 * viscous + 2 * impact, rel=1e-9)


def test_rms_and_amplitude_match_sampling(orbit):
    period = 2 * orbit.system.half_period
    t = orbit.impact_time + np.arange(200_000) / 200_000 * period
    w = orbit.tip(t)
    assert orbit.rms_tip() == pytest.approx(math.sqrt(np.mean(w**2)), rel=1e-8)
    assert orbit.tip_amplitude() == pytest.approx(np.max(np.abs(w)), rel=1e-8)
    assert orbit.tip_amplitude() >= np.max(np.abs(w))


def test_orbit_does_not_depend_on_the_mode_normalisation(orbit):
    bar = published_bar(True, 1)
    ref = admissible(two_impact_orbit(*published_args(30.0, 1.0, bar)))
    other = admissible(two_impact_orbit(*published_args(30.0, 1.0, bar.normalised([-3.0]))))
    assert len(ref) == len(other) == 1
    a, b = ref[0], other[0]
    assert b.phase == pytest.approx(a.phase, abs=1e-12)
    for name in ("ball_speed", "impulse", "bar_velocity_before", "bar_velocity_after"):
        assert getattr(b, name) == pytest.approx(getattr(a, name), rel=1e-10)
    assert b.rms_tip() == pytest.approx(a.rms_tip(), rel=1e-10)


def test_undamped_bar_has_orbits_that_balance_energy_without_viscous_loss():
    args = list(published_args(30.0, 0.9))  # off resonance: C = 0 has no response at 1.0
    args[2] = 0.0
    good = admissible(two_impact_orbit(*args))
    assert good
    o = good[0]
    sys, t0, th = o.system, o.impact_time, o.system.half_period
    x, wq = np.polynomial.legendre.leggauss(200)
    t = t0 + 0.5 * th * (x + 1)
    work = 0.5 * th * np.sum(wq * sys.force * np.sin(sys.omega * t) * o.modal_velocity(t))
    m_eff = sys.ball_mass / (1 + sys.effective_ratio)
    impact = 0.5 * (1 - E**2) * m_eff * (o.ball_speed - o.bar_velocity_before) ** 2
    assert work == pytest.approx(impact, rel=1e-9)


# --- the gallery's figure (docs/validation.md): their orbit against our exact integrator ---
#: the gallery's bar: the physical preset, one mode, frictionless ball, gap 0.5 mm
GALLERY = {"n_modes": 1, "friction": False, "gap_m": GAP}
#: forcing periods run from the start near the orbit, the last half read as the steady state
SETTLE_PERIODS = 300


def gallery_system():
    return bb.make_system("ball", "physical", **GALLERY)


def closed_form(system, force: float, ratio: float) -> list:
    """The admissible symmetric two-impact orbits of ``system`` at F0 = ``force``,
    Omega = ``ratio`` omega_n (Masri and Caughey's closed form)."""
    b, d = system.bar, system.damper
    return admissible(two_impact_orbit(
        b.mass_kg[0], b.stiffness_n_m[0], b.damping_n_s_m[0], b.psi_tip[0], b.psi_damper[0],
        d.mass_kg, d.gap_m, d.restitution, force, ratio * system.reference_frequency_rad_s))


def start_on(orbit, rel: float = 1e-3) -> bb.State:
    """The state just after the orbit's + wall impact, [u, u', y, y'], u off by ``rel``."""
    sys = orbit.system
    u0 = float(orbit.modal_displacement(orbit.impact_time))
    v0 = orbit.bar_velocity_after / sys.psi_ball
    y_dot = -orbit.ball_speed - orbit.bar_velocity_after
    return bb.State(np.array([u0 * (1 + rel), v0, sys.gap / 2, y_dot]), orbit.impact_time)


def settle(system, orbit, force: float, ratio: float, rel: float = 1e-3):
    """Our exact integrator from ``start_on(orbit, rel)``: SETTLE_PERIODS periods, the last
    half steady.  (run, its steady RMS of W, the mean |y'-| of its steady impacts)."""
    period = 2 * orbit.system.half_period
    run = bb.simulate(system, bb.Harmonic(force, ratio), duration_s=SETTLE_PERIODS * period,
                      dt_s=period / 2000, initial=start_on(orbit, rel), steady_fraction=0.5,
                      integrator="exact", record_every=0)
    steady = run.impacts[run.impacts[:, 0] >= run.steady_start_s]
    return run, run.rms_tip_m, float(np.mean(np.abs(steady[:, 2])))


def shooting_multiplier(system, orbit, force: float, ratio: float) -> float:
    """The largest |Floquet multiplier| of the orbit by our shooting (boringbar.orbits),
    Newton started from the closed form's state at phase 0."""
    fl = make_flow(system, bb.Harmonic(force, ratio))
    h = 1e-9
    dy0 = float(orbit.relative_displacement(h) - orbit.relative_displacement(-h)) / (2 * h)
    x0 = np.array([float(orbit.modal_displacement(0.0)), float(orbit.modal_velocity(0.0)),
                   float(orbit.relative_displacement(0.0)), dy0])
    _, period = periodic_orbit(fl, x0, rms=False)
    return float(np.abs(multipliers(period)[0]))


def impact_speed(orbit) -> float:
    """|y'-| at each impact of the orbit (m/s): the ball's approach to the wall."""
    return orbit.ball_speed - orbit.bar_velocity_before


@pytest.mark.parametrize("force,ratio", [(30.0, 1.0), (40.0, 1.0), (30.0, 0.9)])
def test_exact_integrator_settles_on_their_orbit_where_our_shooting_finds_it_stable(
        force, ratio):
    """The gallery's stable points: our shooting's largest multiplier is the square of the
    closed form's half-period impact map's (1e-6: its finite differences) and below 1, and
    the exact integrator, started 1e-3 off, ends on their orbit: RMS of W and impact speed
    to 1e-9 (measured: 1e-11)."""
    system = gallery_system()
    orbit = next(o for o in closed_form(system, force, ratio) if o.stable)
    mult = shooting_multiplier(system, orbit, force, ratio)
    assert mult == pytest.approx(max(np.abs(orbit.multipliers)) ** 2, rel=1e-6) and mult < 1
    run, rms, speed = settle(system, orbit, force, ratio)
    assert run.pattern.name == "2 symmetric"
    assert rms == pytest.approx(orbit.rms_tip(), rel=1e-9, abs=0)  # W ~ 1e-4 m
    assert speed == pytest.approx(impact_speed(orbit), rel=1e-9, abs=0)


@pytest.mark.parametrize("force,ratio", [(20.0, 1.0), (30.0, 1.05), (50.0, 1.0)])
def test_exact_integrator_leaves_their_orbit_where_our_shooting_finds_it_unstable(
        force, ratio):
    """Where their orbit is unstable (a multiplier above 1 by our shooting) ours, started
    1e-3 off it, ends elsewhere: the steady RMS of W differs from theirs by over 5 %."""
    system = gallery_system()
    orbit = closed_form(system, force, ratio)[-1]
    assert not orbit.stable and shooting_multiplier(system, orbit, force, ratio) > 1
    _, rms, _ = settle(system, orbit, force, ratio)
    assert abs(rms / orbit.rms_tip() - 1) > 0.05

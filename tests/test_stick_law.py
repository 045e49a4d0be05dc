"""RK4's stick law (``stick_law = "hold"``, docs/model.md, section 5): a ball that its
friction can hold moves with the bar exactly, as the exact integrator's stick mode has it,
where the published sgn() law's chatter about y' = 0 holds it only to first order in the
step.  Truths: the locked bar (a held ball is part of the bar), the locked bar's
characteristic root in a cut, the energy balance, and the exact integrator's stick-slip.
"""

from __future__ import annotations

import numpy as np
import pytest
from delay_roots import rightmost_root

import boringbar as bb
from boringbar import Harmonic, Initial, make_system
from boringbar._validate import ParameterError
from boringbar.analysis.verdict import VerdictOptions, window_steps
from boringbar.reference.stability import KR_ALUMINIUM, limit_at_speeds
from boringbar.simulate import CutStepper, knocked_cut, simulate
from boringbar.simulate import layout as L
from boringbar.simulate.kernels import regime_matrix


def test_a_held_ball_moves_with_the_bar_as_the_locked_bar_does():
    """A small force at resonance (3 mN): the carrying force stays below F_c, so the held
    ball's bar is the locked bar to round-off; the sgn() law's is not (at 10 mN the
    ball slips)."""
    ball = make_system("ball", "physical", n_modes=2, friction=True)
    locked = ball.linear_host()
    assert locked.kind == "locked"
    forcing = Harmonic(0.003, 1.0)
    ref = simulate(locked, forcing, duration_s=0.2, integrator="rk4", record_every=20)
    scale = np.max(np.abs(ref.history[:, 1]))
    err = {}
    for law in ("hold", "sgn"):
        run = simulate(ball, forcing, duration_s=0.2, integrator="rk4", record_every=20,
                       stick_law=law)
        err[law] = np.max(np.abs(run.history[:, 1] - ref.history[:, 1])) / scale
        assert run.config()["stick_law"] == law
    hold = simulate(ball, forcing, duration_s=0.2, integrator="rk4", record_every=20,
                    stick_law="hold")
    assert np.all(hold.history[:, 3] == 0.0) and np.all(hold.history[:, 4] == 0.0)
    assert err["hold"] < 1e-12  # measured: 1.1e-14
    assert err["sgn"] > 1e-4  # measured: 2.8e-3


def locked_root(system: bb.System, depth: float, rpm: float) -> complex:
    """The rightmost characteristic root of a one-mode bar's cut with its ball locked in
    it (modal mass M + m psi_d^2)."""
    bar = system.bar
    m = bar.mass_kg[0] + system.damper.mass_kg * bar.psi_damper[0] ** 2
    return rightmost_root(m, bar.damping_n_s_m[0], bar.stiffness_n_m[0], bar.psi_tip[0] ** 2,
                          KR_ALUMINIUM * depth, 60.0 / rpm)


def held_growth(system, cut, dt, law) -> float:
    stepper = CutStepper(system, cut, dt_s=dt, window_steps=window_steps(system, cut, dt),
                         initial=knocked_cut(system, cut, 1e-8), stick_law=law)
    windows = [stepper.advance() for _ in range(60)][20:]
    t = np.array([w.t_end_s for w in windows])
    return float(np.polyfit(t, np.log([w.half_pp_m for w in windows]), 1)[0])


def test_a_friction_held_vibration_grows_at_the_locked_bar_s_root_whatever_the_step():
    """5 % above the locked bar's limit, knocked by 10 nm (the ball held throughout):
    the vibration grows at the root's real part at 1e-6 and 5e-6 s.  The sgn() law's
    chatter damps it, by an amount that depends on the step (at 5e-6 s it decays)."""
    system = make_system("ball", "physical", n_modes=1, friction=True)
    rpm = 1200.0
    depth = 1.05 * float(limit_at_speeds(system.linear_host(), [rpm])[0])
    cut = bb.Regenerative(depth_m=depth, rpm=rpm, start="static")
    root = locked_root(system, depth, rpm).real
    assert root > 0
    for dt in (1e-6, 5e-6):
        assert held_growth(system, cut, dt, "hold") == pytest.approx(root, rel=0.01)  # 1e-4
    assert held_growth(system, cut, 1e-6, "sgn") < 0.2 * root  # measured: 0.06 root
    assert held_growth(system, cut, 5e-6, "sgn") < 0  # measured: -1.3 root


def test_the_energy_balance_closes_where_the_sgn_law_leaves_a_first_order_residue():
    """The paper's 20.4 N holds the ball most of the run (reciprocal reaction): the held
    steps do no friction work and the impulses that end a slide are booked as friction's."""
    system = make_system("ball", "paper", gap_m=0.1e-3, friction_reaction="reciprocal")
    res, fric = {}, {}
    for law in ("hold", "sgn"):
        run = simulate(system, Harmonic(10.0, 1.0), duration_s=0.1, dt_s=1e-6,
                       initial=Initial(ball_velocity_m_s=0.5), integrator="rk4", stick_law=law)
        assert run.metrics["stick_time_s"] > 0.05  # measured: 0.064 s of 0.08 s
        res[law] = abs(run.energy["balance_relative"])
        fric[law] = run.energy["dissipated_friction_j"]
    assert res["hold"] < 1e-10  # measured: 1.1e-12
    assert res["sgn"] > 1e-4  # measured: 2.4e-3
    exact = simulate(system, Harmonic(10.0, 1.0), duration_s=0.1, dt_s=1e-6,
                     initial=Initial(ball_velocity_m_s=0.5), integrator="exact")
    e = exact.energy["dissipated_friction_j"]
    assert fric["hold"] == pytest.approx(e, rel=1e-3)  # measured: 1.8e-4
    assert abs(fric["sgn"] - e) > 10 * abs(fric["hold"] - e)


def test_true_stick_slip_matches_the_exact_integrator():
    """F_s = 2 F_c, which the sgn() law refuses: the ball sticks and slips each cycle
    without reaching a wall.  Measured at 1e-6 s: RMS within 1e-4, friction's
    dissipation within 0.16 %, stick time within 5 % (the RK4 bookkeeping's band)."""
    system = make_system("ball", "paper", gap_m=1e-3, friction_reaction="reciprocal",
                         static_ratio=2.0)
    forcing = Harmonic(20.0, 1.0)
    exact = simulate(system, forcing, duration_s=0.5, integrator="exact")
    hold = simulate(system, forcing, duration_s=0.5, integrator="rk4", stick_law="hold")
    assert exact.metrics["impacts_total"] == hold.metrics["impacts_total"] == 0
    assert 0.02 < exact.metrics["stick_time_s"] < 0.2  # sticks and slips: measured 0.048 s
    assert hold.metrics["rms_tip_m"] == pytest.approx(exact.metrics["rms_tip_m"], rel=1e-3)
    assert hold.energy["dissipated_friction_j"] == pytest.approx(
        exact.energy["dissipated_friction_j"], rel=0.01)
    assert hold.metrics["stick_time_s"] == pytest.approx(exact.metrics["stick_time_s"],
                                                         rel=0.1)
    with pytest.raises(ParameterError, match="static_ratio"):
        simulate(system, forcing, duration_s=1e-3, integrator="rk4", stick_law="sgn")


def test_the_converged_verdict_holds_and_names_its_law():
    assert VerdictOptions().stick_law == "hold"
    assert VerdictOptions().to_dict()["stick_law"] == "hold"
    assert bb.Integration().stick_law == "sgn"
    assert bb.Integration(stick_law="hold").kwargs()["stick_law"] == "hold"


def test_bad_stick_laws_are_refused():
    system = make_system("ball", "physical")
    for make in (lambda: simulate(system, Harmonic(1.0, 1.0), duration_s=1e-3,
                                  stick_law="karnopp"),
                 lambda: bb.Integration(stick_law="karnopp"),
                 lambda: VerdictOptions(stick_law="karnopp")):
        with pytest.raises(ParameterError, match="stick_law.*karnopp"):
            make()


def test_a_regime_matrix_is_the_sliding_law_s():
    """The core's regime matrices are the sliding law's of a direction; a parameter
    vector with the stick law's band is refused, not read as a held regime."""
    from boringbar.simulate import pack
    system = make_system("ball", "physical")
    p = pack(system, 1.0, 1.0, 1e-6, "hold")
    assert p[L.STICK_BAND] > 0
    with pytest.raises(ValueError, match="STICK_BAND"):
        regime_matrix(p, 1.0)
    regime_matrix(pack(system, 1.0, 1.0, 1e-6), 1.0)


def held_windows(system: bb.System, cut: bb.Regenerative, knock: float, n: int) -> list:
    """``n`` windows of ``cut`` knocked by ``knock`` with the ball at rest on the bar
    (held from the start)."""
    x = knocked_cut(system, cut, knock).x
    x[2 * system.bar.n_modes + 1] = 0.0
    stepper = CutStepper(system, cut, dt_s=2e-6, window_steps=window_steps(system, cut, 2e-6),
                         initial=bb.State(x, 0.0), stick_law="hold")
    return [stepper.advance() for _ in range(n)]


def test_the_force_that_holds_the_ball_is_linear_in_the_vibration():
    """A held ball is part of the locked bar, a linear system: twice the knock, twice the
    force that holds it, in every window (to round-off), and below F_s throughout.  The
    sgn() law never holds the ball, so its windows are never held."""
    system = make_system("ball", "physical")
    cut = bb.Regenerative(depth_m=3.5e-5, rpm=900.0, start="static", stop_at_zero=False)
    small, large = (held_windows(system, cut, k, 4) for k in (2e-9, 4e-9))
    fs = system.damper.friction_force_n * system.damper.friction.static_ratio
    for a, b in zip(small, large, strict=True):
        assert a.held and b.held
        assert 0 < b.max_hold_n < fs
        assert b.max_hold_n / a.max_hold_n == pytest.approx(2.0, rel=1e-8)  # 6e-11
    stepper = CutStepper(system, cut, dt_s=2e-6, window_steps=window_steps(system, cut, 2e-6),
                         initial=knocked_cut(system, cut, 2e-9), stick_law="sgn")
    assert not any(stepper.advance().held for _ in range(3))


def test_a_held_growth_jumps_ahead_to_the_same_settled_vibration(monkeypatch):
    """Just above the published ball bar's onset at 900 rpm a 1 um knock makes the ball
    slip once; then it is held while the vibration grows at 0.057 1/s until the force
    that holds it reaches F_s, where the vibration settles: 15 s of cut.  Scaled ahead
    while it is held (verdict.fast_forward), the run settles at the same peak-to-peak
    (measured: within 0.6 %) in a sixth of the cut."""
    from boringbar.analysis import verdict

    system = make_system("ball", "physical")
    cut = bb.Regenerative(depth_m=3.5241e-5, rpm=900.0)
    options = VerdictOptions(settle_cap_s=160.0)
    jumped = verdict.judge(system, cut, options)
    linear = verdict.fast_forward

    def frictionless_only(stepper, windows, opts):
        return stepper.system.damper.friction_force_n == 0 and linear(stepper, windows, opts)

    monkeypatch.setattr(verdict, "fast_forward", frictionless_only)
    waited = verdict.judge(system, cut, options)
    assert jumped.onset == waited.onset == "chatter"
    assert jumped.chatter_free and waited.chatter_free
    assert [s.status for s in jumped.settled] == [s.status for s in waited.settled] == ["settled"]
    assert jumped.settled_pp_m == pytest.approx(waited.settled_pp_m, rel=0.02)
    assert waited.duration_s > 10.0  # measured: 14.8 s
    assert jumped.duration_s < waited.duration_s / 3  # measured: 2.4 s

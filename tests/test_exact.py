"""The exact event-driven integrator (boringbar.simulate.kernels.run_exact).

Tiers: linear cases against closed forms (round-off); the Masri-Caughey
two-impact orbit (round-off); the energy ledger (impact losses from the
recorded impacts, the balance to 1e-9); true stick-slip (F_s = F_c is the
limit of the sgn() law's chatter as dt shrinks; F_s > F_c differs); a Zeno
sequence ending in contact with bounded work; the published RK4 scheme
converging to the exact answer at first order; refusals.  Measured values
are quoted beside each tolerance.
"""

from __future__ import annotations

import dataclasses
import math
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

from boringbar import Harmonic, Initial, State, make_system, simulate
from boringbar._validate import ParameterError
from boringbar.model.dampers import Friction
from boringbar.orbits import shooting as sh
from boringbar.reference.linear import tip_frf
from boringbar.reference.masri_caughey import two_impact_orbit
from boringbar.simulate import layout as L
from boringbar.simulate import setup_run
from boringbar.simulate.kernels import Records, Steps, prepare, run_exact
from boringbar.simulate.regimes import SYSTEM_CACHE_SIZE, setup_fields, system_regimes


# --- linear cases: closed forms ----------------------------------------------------------
@pytest.mark.parametrize("duration,dt,every,tol", [(0.02, 1e-5, 7, 1e-11),
                                                   (2.0, 1e-6, 100, 3e-12)])
def test_solid_bar_transient_from_rest_is_the_closed_form(duration, dt, every, tol):
    """One mode from rest under F0 sin(Omega t): particular + damped free solution.

    Over 2 s the history's 20000 rows come by recurrence (a complex product a row, the
    closed form's own every 64th row): they stay within 3e-12 of the amplitude (achieved
    8.5e-13, the anchors' 4.6e-13, the formula's own rounding of Omega t near 1e4 rad).
    """
    s = make_system("solid", "paper")
    bar = s.bar
    M, K, C, pl = bar.mass_kg[0], bar.stiffness_n_m[0], bar.damping_n_s_m[0], bar.psi_tip[0]
    om = 0.93 * bar.natural_frequency_rad_s
    run = simulate(s, Harmonic(10.0, 0.93), duration_s=duration, dt_s=dt, record_every=every,
                   integrator="exact")
    t = run.history[:, 0]
    H = 1.0 / complex(K - M * om**2, C * om)
    a = pl * 10.0 * H  # u_p = Im(a e^{i om t})
    sig, wd = C / (2 * M), math.sqrt(K / M - (C / (2 * M)) ** 2)
    u0, v0 = -a.imag, -(1j * om * a).imag  # the free part cancels u_p(0), u_p'(0)
    A, B = u0, (v0 + sig * u0) / wd
    u = (a * np.exp(1j * om * t)).imag + np.exp(-sig * t) * (A * np.cos(wd * t)
                                                              + B * np.sin(wd * t))
    w_ref = pl * u
    scale = np.max(np.abs(w_ref))
    assert np.max(np.abs(run.history[:, 1] - w_ref)) < tol * scale  # achieved: 1.3e-14
    assert run.energy["balance_relative"] == pytest.approx(0.0, abs=1e-12)


@pytest.mark.parametrize("bar,ratio", [("solid", 0.97), ("tmd", 1.0), ("locked", 1.02)])
def test_steady_amplitude_is_the_frequency_response(bar, ratio):
    """After the transient (e^-58 at 2 s) max |W| is |G(i Omega)| F0, G from tip_frf."""
    s = make_system("ball", "physical", locked=True) if bar == "locked" else \
        make_system(bar, "physical")
    om = ratio * s.reference_frequency_rad_s
    run = simulate(s, Harmonic(10.0, ratio), duration_s=2.0, steady_fraction=0.1,
                   integrator="exact")
    kw = {"tmd": s.damper} if bar == "tmd" else {}
    if bar == "locked":
        kw = {"added_mass_kg": s.damper.mass_kg}
    g = abs(complex(tip_frf(s.bar, om, **kw)))
    assert run.metrics["max_abs_tip_m"] == pytest.approx(10.0 * g, rel=1e-10)  # 1e-13
    assert run.energy["balance_relative"] == pytest.approx(0.0, abs=1e-12)


@pytest.mark.parametrize("bar", ["solid", "tmd"])
def test_the_dashpots_dissipate_the_steady_work_of_the_force(bar):
    """The core's dashpot rows (core.dashpots: each mode's on u_i', the absorber's on x_a'
    - psi_a . u') dissipate, over k settled periods, what the force puts in: -pi F0^2
    Im G(i Omega) a period, G the tip's closed-form FRF (the transient is e^-58 at 2 s)."""
    s = make_system(bar, "physical")
    om = s.reference_frequency_rad_s
    f0, k = 10.0, 20
    kw = {"tmd": s.damper} if bar == "tmd" else {}
    per_period = -math.pi * f0 ** 2 * complex(tip_frf(s.bar, om, **kw)).imag
    period = 2 * math.pi / om  # whole periods of whole steps
    t1 = period * round(2.0 / period)
    lost = [simulate(s, Harmonic(f0, 1.0), duration_s=t, dt_s=period / 1000,
                     integrator="exact").energy["dissipated_viscous_j"]
            for t in (t1, t1 + k * period)]
    # measured 1.6e-14 and 6e-15; the absorber's row without -psi_a: -0.41
    assert (lost[1] - lost[0]) / k == pytest.approx(per_period, rel=1e-9)


def test_overdamped_absorber_mode_is_integrated_without_conjugate_pairs():
    """A TMD damped at 3x its critical value has two real eigenvalues beside the complex
    pairs, so prepare does not pair them (kstep 1) and the segment integrals may not use
    the conjugate symmetry of a paired basis (a complex lambda - i Omega is then not
    the conjugate of lambda + i Omega): max |W| is the frequency response, the energy
    balance closes.  (With that symmetry wrongly applied it was off by 5.0e-5.)"""
    s = make_system("tmd", "physical")
    d = s.damper
    s = dataclasses.replace(s, damper=dataclasses.replace(
        d, damping_n_s_m=3.0 * 2.0 * math.sqrt(d.stiffness_n_m * d.mass_kg)))
    f = Harmonic(10.0, 1.0)
    prep = prepare(setup_run(s, f, 0.01, 1e-6, None, 0, 0.8, False, "exact").p)
    assert list(prep.kstep) == [1] and np.any(prep.lam[0].imag != 0.0)
    run = simulate(s, f, duration_s=2.0, steady_fraction=0.1, integrator="exact")
    g = abs(complex(tip_frf(s.bar, s.reference_frequency_rad_s, tmd=s.damper)))
    assert run.metrics["max_abs_tip_m"] == pytest.approx(10.0 * g, rel=1e-10)  # 3e-16
    assert run.energy["balance_relative"] == pytest.approx(0.0, abs=1e-12)  # 3.4e-15


# --- the Masri-Caughey orbit ---------------------------------------------------------------
@pytest.fixture(scope="module")
def orbit_case():
    """The 30 N stable symmetric orbit (tests/test_masri_caughey.py) of the 1-mode bar."""
    s = make_system("ball", "physical", n_modes=1, friction=False, gap_m=0.5e-3)
    bar, d = s.bar, s.damper
    om = s.reference_frequency_rad_s
    orbits = [o for o in two_impact_orbit(bar.mass_kg[0], bar.stiffness_n_m[0],
                                          bar.damping_n_s_m[0],
                                          bar.psi_tip[0], bar.psi_damper[0], d.mass_kg, d.gap_m,
                                          d.restitution, 30.0, om) if o.admissible]
    assert len(orbits) == 1
    o = orbits[0]
    t0 = o.impact_time
    u0 = float(o.modal_displacement(t0))
    v0 = o.bar_velocity_after / bar.psi_damper[0]
    y_dot = -o.ball_speed - o.bar_velocity_after  # relative velocity just after the + impact
    x = np.array([u0, v0, d.gap_m / 2, y_dot])
    return s, o, State(x, t0)


def test_exact_integrator_follows_the_masri_caughey_orbit(orbit_case):
    s, o, start = orbit_case
    period = 2 * o.system.half_period
    n_per = 20
    run = simulate(s, Harmonic(30.0, 1.0), duration_s=n_per * period, dt_s=period / 2000,
                   initial=start, steady_fraction=1.0, integrator="exact")
    imp = run.impacts
    # one + and one - impact per period; the last falls on t_end (in or out by round-off)
    assert len(imp) in (2 * n_per - 1, 2 * n_per)
    walls = imp[:, 1]
    assert np.all(walls[1:] == -walls[:-1]) and walls[0] == -1
    k = np.arange(1, len(imp) + 1)
    t_ref = start.t_s + k * o.system.half_period
    assert np.max(np.abs(imp[:, 0] - t_ref)) < 1e-13  # achieved: 2e-17 s
    assert run.rms_tip_m == pytest.approx(o.rms_tip(), rel=1e-11)  # achieved: 5e-14
    approach = o.ball_speed - o.bar_velocity_before
    np.testing.assert_allclose(np.abs(imp[:, 2]), approach, rtol=1e-10)  # 1.4e-14


def test_orbit_stays_when_the_steady_window_starts_at_an_impact(orbit_case):
    """1050 periods (about 2 s; benchmarks/bench_exact.py), the steady window's start
    on an impact: the segment after it is a few ulp long and ends a few ulp past
    the wall with the ball moving inward.  That is not a wall contact; the ball
    was once captured there and left the orbit (RMS 3.3x the orbit's, balance
    3.3e-4; 10-200 periods were not affected)."""
    s, o, start = orbit_case
    period = 2 * o.system.half_period
    run = simulate(s, Harmonic(30.0, 1.0), duration_s=1050 * period, dt_s=period / 2000,
                   initial=start, integrator="exact")
    assert run.rms_tip_m == pytest.approx(o.rms_tip(), rel=1e-11)  # measured: 3e-13
    assert abs(run.energy["balance_relative"]) < 1e-12  # measured: 1.2e-15


def test_rk4_converges_to_the_exact_impact_times_at_first_order(orbit_case):
    """The published scheme detects impacts up to a step late: first order."""
    s, o, start = orbit_case
    period = 2 * o.system.half_period
    dur = 10 * period
    ref = simulate(s, Harmonic(30.0, 1.0), duration_s=dur, dt_s=period / 2000, initial=start,
                   steady_fraction=1.0, integrator="exact")
    errors = []
    dts = [period / 500, period / 1000, period / 2000, period / 4000]
    for dt in dts:
        run = simulate(s, Harmonic(30.0, 1.0), duration_s=dur, dt_s=dt, initial=start,
                       steady_fraction=1.0, integrator="rk4")
        m = min(len(run.impacts), len(ref.impacts)) - 1
        errors.append(np.max(np.abs(run.impacts[:m, 0] - ref.impacts[:m, 0])))
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(errors[-1] < np.array(errors[:-1]))
    assert 0.7 < np.mean(orders) < 1.5  # achieved: about 1


# --- the energy ledger -----------------------------------------------------------------------
@pytest.mark.parametrize("preset,kw,force", [
    ("physical", {"gap_m": 0.5e-3}, 10.0),  # 0.02 N friction, reciprocal
    ("paper", {"gap_m": 0.5e-3}, 10.0),  # 20.4 N friction with the printed reaction
    ("physical", {"gap_m": 0.1e-3, "friction": False}, 20.0),
    ("physical", {"gap_m": 0.5e-3, "friction_force_n": 2.0, "static_ratio": 1.5}, 20.0),
])
def test_energy_balance_closes_to_1e9(preset, kw, force):
    s = make_system("ball", preset, **kw)
    run = simulate(s, Harmonic(force, 1.0), duration_s=0.3, steady_fraction=1.0,
                   integrator="exact")
    assert abs(run.energy["balance_relative"]) < 1e-9  # achieved: 1e-13
    m = run.metrics
    if m["micro_impacts"] == 0:
        # every impact is recorded: the ledger's impact loss is the sum of the drops
        e, d = s.damper.restitution, s.damper
        bar = s.bar
        meff = 1 / (1 / d.mass_kg + np.sum(bar.psi_damper**2 / bar.mass_kg))
        drop = 0.5 * (1 - e * e) * meff * np.sum(run.impacts[:, 2] ** 2)
        assert run.energy["dissipated_impacts_j"] == pytest.approx(drop, rel=1e-12)
    if s.damper.friction.reaction == "printed":
        assert abs(run.energy["work_nonreciprocal_friction_j"]) > 0


# --- friction laws -----------------------------------------------------------------------------
def _stick_case(static_ratio=1.0):
    """The paper preset's 20.4 N friction (printed reaction), gap 0.5 mm: at 10 N the ball
    sticks for about 3/4 of the time and slips for the rest."""
    return make_system("ball", "paper", gap_m=0.5e-3, static_ratio=static_ratio)


def test_static_limit_equal_to_coulomb_is_the_limit_of_the_sgn_law():
    """F_s = F_c: the exact stick-slip is what RK4's sgn() chatter converges to."""
    s = _stick_case()
    args = (s, Harmonic(10.0, 1.0))
    kw = {"duration_s": 0.1, "steady_fraction": 0.5}
    exact = simulate(*args, integrator="exact", **kw)
    assert 0.01 < exact.metrics["stick_time_s"] < 0.049  # stick and slip: 0.038 of 0.05 s
    errors = []
    for dt in (4e-6, 2e-6, 1e-6):
        run = simulate(*args, dt_s=dt, **kw)
        errors.append(abs(run.rms_tip_m - exact.rms_tip_m) / exact.rms_tip_m)
    assert errors[2] < errors[1] < errors[0]  # achieved: 2.6e-2, 1.2e-2, 6.8e-3
    assert errors[2] < 1e-2
    # a higher static limit sticks longer and moves the answer by more than that
    higher = simulate(_stick_case(2.0), Harmonic(10.0, 1.0), integrator="exact", **kw)
    assert higher.metrics["stick_time_s"] > exact.metrics["stick_time_s"]
    assert abs(higher.rms_tip_m - exact.rms_tip_m) / exact.rms_tip_m > 5 * errors[2]


def test_zeno_sequence_ends_in_contact_without_stalling():
    """Ball 1 um from the + wall, bar released from +0.2 mm: the bar's acceleration
    throws the ball onto the wall; with e = 0.3 the rebounds shrink geometrically and
    end in contact (a capture below the impact threshold), then the ball is released."""
    s = make_system("ball", "physical", gap_m=0.5e-3, friction=False, restitution=0.3)
    half = s.damper.gap_m / 2
    run = simulate(s, Harmonic(0.0, 1.0), duration_s=5e-3, steady_fraction=1.0,
                   initial=Initial(tip_displacement_m=2e-4, ball_position_m=half - 1e-6),
                   record_every=10, integrator="exact")
    m = run.metrics
    assert m["micro_impacts"] >= 1  # the captures
    assert m["contact_time_s"] > 1e-5
    assert m["events"] < 200  # bounded work: achieved about 40
    assert abs(run.energy["balance_relative"]) < 1e-9
    assert np.all(np.abs(run.history[:, 3]) <= half * (1 + 1e-12))


def test_refusals():
    s = make_system("ball", "physical")
    with pytest.raises(ParameterError, match="integrator"):
        simulate(s, Harmonic(10.0, 1.0), duration_s=1e-3, integrator="euler")
    with pytest.raises(ParameterError, match="static_ratio"):
        Friction(static_ratio=0.5)
    with pytest.raises(ParameterError, match="static_ratio"):
        simulate(_stick_case(1.5), Harmonic(10.0, 1.0), duration_s=1e-3, integrator="rk4")


@pytest.mark.parametrize("bar", ["solid", "ball"])
def test_an_undamped_resonance_is_refused_not_run(bar):
    """A bar without damping forced at a natural frequency of one of its regimes has no
    steady closed form (its response grows as t): refused by name, where it ran into a
    singular solve (solid) or stalled on events (ball); a little off it, it runs and
    balances, and RK4 takes the resonance itself."""
    host = make_system("solid", n_modes=2).bar
    undamped = dataclasses.replace(host, damping_ratio=np.zeros(2))
    system = make_system(bar, modal=undamped, friction=False)
    with pytest.raises(ParameterError, match="undamped .* integrator = 'rk4'"):
        simulate(system, Harmonic(10.0, 1.0), duration_s=0.01, integrator="exact")
    near = simulate(system, Harmonic(10.0, 1.001), duration_s=0.01, integrator="exact")
    assert abs(near.energy["balance_relative"]) < 1e-9
    assert simulate(system, Harmonic(10.0, 1.0), duration_s=0.01,
                    integrator="rk4").metrics["rms_tip_m"] > 0


def test_a_run_that_cannot_finish_is_one_line_from_the_command_line(tmp_path, capsys,
                                                                      monkeypatch):
    """The exact integrator's IntegrationError (an event cap, a stall) ends the command
    with one line and exit code 1, not a traceback."""
    import boringbar.cli.simulate as cli_simulate
    from boringbar.cli.main import main
    from boringbar.simulate import IntegrationError

    def fails(*args, **kwargs):
        raise IntegrationError(1, 500000, 0.25)

    monkeypatch.setattr(cli_simulate, "simulate", fails)
    assert main(["simulate", "--out", str(tmp_path / "x")]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("boringbar: error: exact integrator: the event")


def test_run_records_its_integrator():
    s = make_system("ball", "paper")
    run = simulate(s, Harmonic(10.0, 1.0), duration_s=1e-2, integrator="exact")
    assert run.config()["integrator"] == "exact"
    assert run.summary()["integrator"] == "exact"
    assert simulate(s, Harmonic(10.0, 1.0), duration_s=5e-3).summary()["integrator"] == "rk4"


# --- the command line ----------------------------------------------------------------------------
def test_cli_simulate_exact_end_to_end(tmp_path, capsys):
    import json

    import xarray as xr
    from cli_output import json_out

    from boringbar.cli.main import main

    out = tmp_path / "run"
    rc = main(["simulate", "--bar", "ball", "--gap-mm", "0.1", "--force-n", "20",
               "--duration-s", "0.05", "--integrator", "exact", "--static-ratio", "1.5",
               "--out", str(out), "--json"])
    assert rc == 0
    s = json_out(capsys)
    assert s["integrator"] == "exact" and s["rms_tip_m"] > 0
    assert 0 < s["max_abs_rel_disp_m"] <= 0.05e-3 * (1 + 1e-12)
    assert abs(s["energy"]["balance_relative"]) < 1e-9
    with xr.open_dataset(out / "run.nc") as ds:
        config = json.loads(ds.attrs["config"])
        assert config["integrator"] == "exact"
        assert config["system"]["damper"]["friction"]["static_ratio"] == 1.5
        assert ds.sizes["time_s"] > 1000


def test_cli_refuses_what_the_integrators_cannot_do(tmp_path, capsys):
    from cli_output import assert_one_line_error

    from boringbar.cli.main import main

    out = tmp_path / "x"
    assert_one_line_error(main, ["simulate", "--static-ratio", "2", "--integrator", "rk4",
                                 "--duration-s", "0.01", "--out", str(out)], out,
                          "static_ratio", capsys)


def test_sweep_records_its_integrator():
    from boringbar.analysis.cases import published_cases
    from boringbar.analysis.sweep import SweepOptions, sweep
    from boringbar.execute import Execution
    from boringbar.simulate import Integration

    cases = published_cases(("ball",), gaps_m=(0.1e-3,), frictions=(False,))
    ds = sweep(cases, SweepOptions([1.0], [20.0]), execution=Execution(workers=1),
               integration=Integration(duration_s=0.05, integrator="exact"))
    assert ds.attrs["integrator"] == "exact"
    assert float(ds["energy_balance_relative"].max()) < 1e-9


@pytest.mark.slow
@pytest.mark.parametrize("preset", ["paper", "physical"])
def test_published_sweep_runs_exactly_and_balances_energy(preset):
    """Every published case, both forces, 11 ratios: no stall, balance to 1e-9, and the
    linear bars equal to RK4's sampled RMS to its O(dt^2) (achieved: 3e-7)."""
    from boringbar.analysis.cases import published_cases
    from boringbar.analysis.sweep import SweepOptions, sweep
    from boringbar.simulate import Integration

    cases = published_cases(preset=preset)
    ratios = np.round(np.arange(0.95, 1.05 + 1e-9, 0.01), 2)
    ex = sweep(cases, SweepOptions(ratios, (10.0, 20.0)),
               integration=Integration(integrator="exact"))
    assert np.nanmax(np.abs(ex["energy_balance_relative"].values)) < 1e-9  # 6e-12
    rk = sweep(cases[:2], SweepOptions(ratios, (10.0, 20.0)))  # solid and TMD
    rel = np.abs(ex["rms_tip_m"].values[:2] / rk["rms_tip_m"].values - 1)
    assert np.max(rel) < 1e-6


def test_random_cases_keep_the_ball_inside_and_balance_energy():
    """Random presets, gaps, restitutions (0 to 1), friction laws, forcing and initial
    states: the ball never passes a wall in the 1 us history (a missed impact would),
    the energy balance closes, no run stalls.  (300 such cases found three
    missed-impact paths, now guarded: a wall crossing and return inside the grid step
    that ends in a friction switch; a return to the wall just left, hidden by a y(0) a
    few ulp past it; a crossing and return inside one step, now caught by the bound
    on y^(4).)"""
    rng = np.random.default_rng(2)
    for _ in range(40):
        preset = str(rng.choice(["paper", "physical"]))
        gap = float(rng.choice([0.1e-3, 0.5e-3]))
        kw = {"gap_m": gap, "restitution": float(rng.choice([0.0, 0.3, 0.7, 1.0]))}
        friction = rng.choice(["off", "preset", "force"])
        if friction == "off":
            kw["friction"] = False
        elif friction == "force":
            kw["friction_force_n"] = float(rng.uniform(0.5, 30.0))
        kw["static_ratio"] = float(rng.choice([1.0, 1.0, 1.5, 3.0]))
        s = make_system("ball", preset, **kw)
        ini = Initial(float(rng.uniform(-1e-3, 1e-3)), float(rng.uniform(-1, 1)),
                      float(rng.uniform(-gap / 2, gap / 2)), float(rng.uniform(-0.5, 0.5)))
        run = simulate(s, Harmonic(float(rng.uniform(0, 40)), float(rng.uniform(0.8, 1.2))),
                       duration_s=0.1, initial=ini, record_every=1, integrator="exact")
        assert np.max(np.abs(run.history[:, 3])) <= gap / 2 * (1 + 1e-9), (kw, ini)
        assert abs(run.energy["balance_relative"]) < 1e-9  # achieved: 5e-13
        assert run.metrics["events"] < 20_000


def test_a_graze_inside_one_grid_step_is_found():
    """Regression: a slow rebound (e = 0.3) off the + wall while the bar's second mode
    (2.5 kHz) swings the wall back: the ball meets the wall again 2-6 us later and is
    inside again at the end of the 25 us grid step.  Missed, the ball passed the wall
    by 5 nm.  (The path is chaotic, so round-off decides whether a run meets this graze;
    it did in the run where it was found, before the y^(4) bound.)"""
    s = make_system("ball", "physical", gap_m=1e-4, restitution=0.3, friction=False)
    ini = Initial(tip_displacement_m=0.0009977593537743258, tip_velocity_m_s=-0.4006448667760163,
                  ball_position_m=-3.1476997076005373e-06, ball_velocity_m_s=0.1274508828630837)
    run = simulate(s, Harmonic(27.334895166275178, 0.8848664733799202), duration_s=0.2,
                   initial=ini, record_every=1, integrator="exact")
    assert np.max(np.abs(run.history[:, 3])) <= 0.5e-4 * (1 + 1e-9)


def test_a_sliding_ball_that_stops_and_turns_back_inside_a_grid_step_is_seen():
    """A sliding ball with friction (physical preset, gap 0.2 mm, e = 0.417, mu = 1,
    26.75 N at ratio 0.9665; the state that a run from rest reaches at 36.82 ms): its y'
    rises through 0 and falls back 21 us later, inside one grid step (116 us).  Shooting,
    whose event search is its own (orbits/events.py), finds the two reversals; the exact
    integrator, whose step ends both show the ball sliding the same way, finds them by the
    bound on y^(4) (stop_may_turn), and the two agree to round-off (measured 3.1e-15).
    Missed, the friction kept its sign through the excursion: no event and 4.5e-5 off."""
    system = make_system("ball", "physical", gap_m=0.2e-3, restitution=0.4169567761417031,
                         friction_number=1.0, n_modes=1)
    forcing = Harmonic(26.748730937015008, ratio=0.9665219247361284)
    t0, window = 0.03682, 1e-4
    x0 = np.array([4.8810812737720564e-05, -1.3142786371141275e+00,
                   9.3743259175220646e-05, -6.8673652179780387e-03])
    fl = sh.make_flow(system, forcing)
    fl = dataclasses.replace(fl, phase=fl.omega * t0)
    shot = sh.advance(fl, x0, duration=window)
    assert [k for _, k in shot.events] == ["reversal", "reversal"]
    (t1, _), (t2, _) = shot.events
    # 21 us apart, in a window shorter than the exact integrator's grid step (116 us)
    assert t0 < t1 < t2 < t0 + window and t2 - t1 < 0.25 * window
    run = simulate(system, forcing, duration_s=window, dt_s=window / 100,
                   initial=State(x0, t0), steady_fraction=1.0, integrator="exact")
    assert run.metrics["events"] == 2
    assert np.max(np.abs(run.final.x - shot.x)) <= 1e-12 * np.max(np.abs(shot.x))


def test_a_sticking_orbit_with_short_reversals_is_what_rk4_converges_to():
    """The paper preset's ball at gap 0.1 mm, 10 N, ratio 1.02 sticks twice a period, and
    between its impacts its y' comes to zero and back within a grid step.  RK4 (the stick
    law) converges to the exact integrator's RMS at first order: 2.1e-5, 9.6e-6, 4.0e-6
    off at dt = 250, 125 and 62.5 ns, with the same pattern (2 impacts a period).  When
    the exact integrator missed those reversals its RMS was 9.0e-4 above RK4's limit and its
    pattern repeated over 5 periods."""
    system = make_system("ball", "paper", gap_m=0.1e-3)
    forcing = Harmonic(10.0, ratio=1.02)
    exact = simulate(system, forcing, duration_s=1.0, integrator="exact", record_every=0)
    assert (exact.pattern.n, exact.pattern.k) == (2, 1)
    off = []
    for dt in (1.25e-7, 6.25e-8):
        run = simulate(system, forcing, duration_s=1.0, dt_s=dt, integrator="rk4",
                       stick_law="hold", record_every=0)
        assert (run.pattern.n, run.pattern.k) == (2, 1)
        off.append(abs(run.rms_tip_m / exact.rms_tip_m - 1.0))
    assert off[1] < 0.6 * off[0]
    assert off[1] < 1e-5


# --- a free ball: longer grid steps where they are proven safe; int y^2 in closed form ------
def _steady_path(system, force, dur, dt=5e-8):
    """An exact run of ``dur`` s at Omega/omega_n = 1 recording every step of ``dt``, and
    its history's rows over the steady half (from dur / 2 on)."""
    run = simulate(system, Harmonic(force, 1.0), duration_s=dur, dt_s=dt, record_every=1,
                   steady_fraction=0.5, integrator="exact")
    h = run.history
    h = h[h[:, 0] >= 0.5 * dur - 0.5 * dt]
    assert h[0, 0] == pytest.approx(0.5 * dur) and h[-1, 0] == pytest.approx(dur)
    return run, h


def _hermite_quad(t, f, fd):
    """int f dt by the trapezoid with its Hermite end correction, from f and f' at t."""
    hh = np.diff(t)
    return np.sum(0.5 * hh * (f[:-1] + f[1:]) + hh ** 2 / 12.0 * (fd[:-1] - fd[1:]))


@pytest.mark.parametrize("preset,kw,force", [
    ("paper", {"gap_m": 0.1e-3, "friction": False}, 10.0),
    ("physical", {"gap_m": 0.1e-3, "friction": False}, 20.0),
    ("physical", {"gap_m": 0.5e-3}, 30.0),  # friction on: sliding segments (F_b constant)
])
def test_ball_mean_square_is_the_integral_of_its_path(preset, kw, force):
    """The ball's steady mean square (rms_aux^2) is int y^2 dt in closed form per segment;
    against the Hermite-corrected trapezoid of the exact y, y' recorded every 5e-8 s (O(dt^2)
    at the impacts, where y' jumps) it agrees to 1e-8.  (The grid quadrature it replaced
    was 8.5e-4 off on the paper case.)"""
    dur = 0.05
    run, h = _steady_path(make_system("ball", preset, **kw), force, dur)
    t, y, yd = h[:, 0], h[:, 3], h[:, 4]
    quad = _hermite_quad(t, y * y, 2.0 * y * yd)
    assert len(run.impacts) > 5
    assert run.metrics["rms_aux_m"] ** 2 * 0.5 * dur == pytest.approx(quad, rel=1e-8)  # 1.3e-9


@pytest.mark.parametrize("bar, preset, kw, force, tol", [
    ("tmd", "physical", {}, 20.0, 1e-12),  # the sizes of any bar (nz = 2n + 2): 1.3e-15
    ("tmd", "paper", {}, 20.0, 1e-12),  # 1.2e-15
    ("ball", "physical", {"gap_m": 0.5e-3}, 30.0, 1e-9),  # two modes, sliding: 2.6e-13
    ("ball", "paper", {"gap_m": 0.1e-3, "friction": False}, 20.0, 1e-9),  # impacts: 3.8e-11
    ("ball", "physical", {"gap_m": 0.1e-3, "n_modes": 3}, 20.0, 1e-9),  # 3 modes: 6.4e-11
])
def test_tip_mean_square_and_mean_are_the_integrals_of_its_path(bar, preset, kw, force, tol):
    """The steady int W^2 and int W (rms_tip_m, mean_tip_m), summed per segment from the
    regime's tables (core/exact/flows.hpp), against the Hermite-corrected trapezoid of the
    exact W, W' recorded every 5e-8 s (O(dt^2) where an impact makes W' jump)."""
    dur = 0.02
    run, h = _steady_path(make_system(bar, preset, **kw), force, dur)
    t, w, wd = h[:, 0], h[:, 1], h[:, 2]
    w2 = _hermite_quad(t, w * w, 2.0 * w * wd)
    assert run.metrics["rms_tip_m"] ** 2 * 0.5 * dur == pytest.approx(w2, rel=tol)
    # the mean is near zero: against the mean square's scale
    scale = math.sqrt(w2 * 0.5 * dur)
    assert abs(run.metrics["mean_tip_m"] * 0.5 * dur - _hermite_quad(t, w, wd)) <= tol * scale


def test_a_run_of_one_step_from_rest_has_a_finite_rms():
    """Over 1 us from rest the tip's int W^2 dt is below the round-off of the closed form's
    cancelling terms, and came out at -5e-35 m^2 s: the RMS is a number between 0 and the
    path's largest |W| there (0 over 1 us), not a math domain error."""
    system = make_system("ball", "physical", n_modes=2)
    for duration in (1e-6, 2e-6, 5e-6):
        run = simulate(system, Harmonic(0.1, 0.9), duration_s=duration, integrator="exact",
                       record_every=1)
        w = run.history[:, 1]
        assert 0.0 <= run.metrics["rms_tip_m"] <= np.max(np.abs(w)) + 1e-14


def test_longer_steps_of_a_two_mode_ball_change_no_event():
    """The free 2-mode ball steps 2 h and 4 h where Taylor bounds prove no event and no new
    extremum can fall in the step (prepare's levmax = 2: mode 2 is 4.8x faster than mode 1).
    On its periodic attractor (the chaotic transient would amplify round-off) the run
    with h alone gives the same impacts, max |W| and integrals to round-off."""
    s = make_system("ball", "physical", gap_m=0.1e-3, friction=False)
    f = Harmonic(20.0, 1.0)
    init = simulate(s, f, duration_s=1.0, integrator="exact").final
    out = []
    for levels in ("prepared", "h only"):
        su = setup_run(s, f, 0.2, 1e-6, init, 0, 1.0, False, "exact")
        prep = prepare(su.p)
        if levels == "h only":
            prep.levmax = np.zeros_like(prep.levmax)
        else:
            assert prep.levmax[0] == 2
        run_exact(su.p, su.x, Steps(su.t0, su.dt, su.n_steps, 0),
                  Records(su.rec, su.imp, su.stick, su.stb, su.met), prep=prep)
        out.append((su.met.copy(), su.imp[:int(su.met[L.N_IMP_REC])].copy()))
    (m1, i1), (m0, i0) = out
    assert len(i1) == len(i0) > 100
    assert np.max(np.abs(i1[:, 0] - i0[:, 0])) < 1e-12  # 4.7e-15 s
    assert m1[L.N_EVENTS] == m0[L.N_EVENTS]
    for k in (L.SUM_W2, L.SUM_AUX2, L.MAX_ABS_W, L.STEADY_MIN_W, L.MAX_ABS_AUX):
        assert m1[k] == pytest.approx(m0[k], rel=1e-10)  # 8e-13


# --- the per-system part of prepare, kept ------------------------------------------------
def _same_bits(a, b) -> bool:
    a, b = np.asarray(a), np.asarray(b)
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


def test_prepare_keeps_one_read_only_part_per_system_and_computes_the_forcing_part():
    """Two forcings of one system share the system's arrays (read-only: every run of the
    system gets them) and each gets its own Z; a third forcing above every |lambda| (the
    paper preset's one mode at 1.05 omega_n) its own grid exponentials.  The memo is
    bounded, and a result equals the one computed with the memo emptied, bit for bit."""
    s = make_system("ball", "paper", gap_m=0.5e-3, friction=True)
    ps = [setup_run(s, Harmonic(force, ratio), 0.01, 1e-6, None, 0, 0.8, False, "exact").p
          for force, ratio in ((10.0, 0.95), (20.0, 1.0), (10.0, 1.05))]
    system_regimes.cache_clear()
    a, b, c = (setup_fields(prepare(p)) for p in ps)
    assert system_regimes.cache_info().currsize == 1
    assert system_regimes.cache_info().maxsize == SYSTEM_CACHE_SIZE
    for key in ("lam", "V", "Vi", "Vh", "kstep", "D", "bq", "lvis", "cvis"):
        assert a[key] is b[key] is c[key] and not a[key].flags.writeable
    assert a["eh"] is b["eh"] and c["eh"] is not a["eh"] and c["h"] < a["h"]
    assert not _same_bits(a["Z"], b["Z"]) and not _same_bits(a["isum"], b["isum"])
    system_regimes.cache_clear()
    fresh = setup_fields(prepare(ps[1]))
    assert all(_same_bits(fresh[k], b[k]) for k in b)


def test_prepare_from_threads_gives_the_same_bits():
    """The analyses run simulate on a thread pool: prepare from 4 threads at once, the
    memo emptied first, gives each forcing's result of one thread, bit for bit."""
    s = make_system("ball", "physical", gap_m=0.1e-3, friction=True)
    ps = [setup_run(s, Harmonic(10.0, r), 0.01, 1e-6, None, 0, 0.8, False, "exact").p
          for r in (0.95, 1.0, 1.05)]
    ref = [setup_fields(prepare(p)) for p in ps]
    system_regimes.cache_clear()
    with ThreadPoolExecutor(4) as pool:
        got = [setup_fields(g) for g in pool.map(prepare, ps * 8)]
    for i, out in enumerate(got):
        assert all(_same_bits(out[k], ref[i % 3][k]) for k in out)

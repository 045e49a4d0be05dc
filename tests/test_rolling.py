"""A rolling ball (docs/model.md, section 2.7): its spin a state of both integrators' runs.

Truths, for RK4 and the exact integrator: a ball rolling on a floor that accelerates at
A moves at 2/7 A, so relative to the bar at 5/7 of a frictionless sliding ball's rate
(I = 2/5 m r^2); as the floor's friction vanishes the rolling ball is the frictionless
sliding one; with no friction at all no spin is excited and the run is the sliding run,
and the closed-form Masri-Caughey orbit stays an orbit; the energy balances with the
spin's (1/5) m (r omega)^2 (the exact integrator's to round-off); RK4 converges to the
exact integrator's rolling ball at first order in dt (the roll/slip switches); and
rolling without slip carries 2/7 of the ball with the bar, so a rolling ball's simulated
chatter limit is the closed form of the bar with 2/7 of the ball fixed at the cavity.
"""

from __future__ import annotations

import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest
from cli_output import assert_one_line_error

import boringbar as bb
from boringbar import core
from boringbar._validate import ParameterError
from boringbar.cli.main import main
from boringbar.model.bar import ModalModel
from boringbar.model.dampers import NO_FRICTION, Friction, ImpactDamper
from boringbar.model.system import System, make_system
from boringbar.model.system_file import SystemFileError, parse_system, published_file_text
from boringbar.plot import plot_run
from boringbar.reference.stability import limit_at_speeds
from boringbar.simulate import setup_run, simulate_batch

sys.path.insert(0, str(Path(__file__).parent))
from test_bifurcation import masri_caughey_start  # noqa: E402
from test_exact_regen import rk4_cut_errors  # noqa: E402
from test_verdict import first_five_lobes, worst_error  # noqa: E402

#: a 20 Hz mode of 1000 kg at the tip: the ball's reaction barely moves it, and the
#: floor's acceleration (about 1 m/s^2) needs far less friction than mu_s m g
HEAVY = ModalModel.from_tap_test(20.0, 0.01, tip_mass_kg=1000.0, damper_ratio=0.6)


INTEGRATORS = ["rk4", "exact"]


def run(motion, *, mu=1.0, friction=NO_FRICTION, bar=HEAVY, force=30.0, gap=2e-3,
        duration=0.1, integrator="rk4"):
    ball = ImpactDamper.ball("carbide", gap_m=gap, friction=friction, motion=motion,
                             mu_static=mu, mu_kinetic=mu)
    return bb.simulate(System(bar, ball, "physical"), bb.Harmonic(amplitude_n=force),
                       duration_s=duration, record_every=1, steady_fraction=1.0,
                       integrator=integrator)


@pytest.mark.parametrize("integrator", INTEGRATORS)
def test_a_rolling_ball_moves_at_five_sevenths_of_a_sliding_one(integrator):
    slide, roll = run("slide", integrator=integrator), run("roll", integrator=integrator)
    assert roll.integrator == integrator and roll.metrics["impacts_total"] == 0
    y_slide, y_roll = slide.history[:, 3], roll.history[:, 3]
    scale = np.abs(y_slide).max()
    assert scale > 1e-6
    assert np.abs(y_roll - 5 / 7 * y_slide).max() < 1e-5 * scale
    # rolling without slip: the spin r omega is y'
    assert roll.final.x[-1] == roll.final.x[-2]


@pytest.mark.parametrize("integrator", INTEGRATORS)
def test_the_sliding_ball_is_the_limit_of_a_vanishing_friction(integrator):
    slide = run("slide", integrator=integrator)
    errors = [np.abs(run("roll", mu=mu, integrator=integrator).history[:, 3]
                     - slide.history[:, 3]).max()
              for mu in (1e-5, 1e-6, 1e-7)]
    # slipping nearly throughout, the floor's friction mu m g is what differs: first order
    # in mu (measured: 9.58 and 9.96 a decade, with either integrator)
    ratios = np.array(errors[:-1]) / errors[1:]
    assert np.all((ratios > 9.0) & (ratios < 11.0)), ratios


@pytest.mark.parametrize(("integrator", "rel"), [("rk4", 1e-12), ("exact", 1e-9)])
def test_with_no_friction_no_spin_is_excited_and_the_run_is_the_sliding_one(integrator, rel):
    """The published bar, impacts and all (the Masri-Caughey regime): the same run, to
    ``rel`` of its peak.  The exact integrator's rolling ball has regimes of its own (a
    state of 2n + 3), diagonalised apart from the sliding ball's, so the two runs' setups
    agree to LAPACK's roundings, which depend on the CPU (OpenBLAS picks its kernels by
    it), and 0.05 s of impacts amplifies them: 2.5e-13 of the peak apart with the Haswell
    kernels, 5e-11 with SkylakeX's; its rolling ball starts a segment of its own as it
    leaves rest, with a spin of round-off, 4e-17 m/s, where it did."""
    bar = make_system("ball").bar
    kw = dict(mu=0.0, bar=bar, force=20.0, gap=0.5e-3, duration=0.05, integrator=integrator)
    slide, roll = run("slide", **kw), run("roll", **kw)
    assert roll.metrics["impacts_total"] == slide.metrics["impacts_total"] > 10
    assert abs(roll.final.x[-1]) <= 1e-15
    np.testing.assert_allclose(roll.history[:, 1], slide.history[:, 1], rtol=0,
                               atol=rel * np.abs(slide.history[:, 1]).max())


@pytest.mark.parametrize("integrator, rel", [("rk4", 1e-3), ("exact", 1e-11)])
def test_the_masri_caughey_orbit_is_unchanged_where_no_spin_is_excited(integrator, rel):
    """A rolling ball without friction (mu_s = mu_k = 0, no rolling resistance), started
    on the closed-form symmetric two-impact orbit of the one-mode bar at 30 N with no
    spin: the floor cannot spin it, and the impact law leaves the spin, so it stays on
    the orbit: two symmetric impacts a period, the strobe at the orbit's tip (RK4 1.3e-4
    off, the published scheme's step; the exact integrator 4.6e-13 off; a rolling ball
    with mu_s = 0.2 is 6.7e-3 off with either and spins), and no spin."""
    ball = ImpactDamper.ball("carbide", gap_m=0.5e-3, friction=NO_FRICTION, motion="roll",
                             mu_static=0.0, mu_kinetic=0.0)
    system = System(make_system("ball", "physical", n_modes=1).bar, ball, "physical")
    orbit, x0 = masri_caughey_start(system, 30.0)
    r = bb.simulate(system, bb.Harmonic(30.0, 1.0), duration_s=0.3, integrator=integrator,
                    initial=bb.State(np.append(x0, 0.0), 0.0), strobe=True)
    assert r.pattern.name == "2 symmetric"
    assert r.final.x[-1] == 0.0
    assert r.strobe[-1, 1] == pytest.approx(float(orbit.tip(0.0)), rel=rel)


@pytest.mark.parametrize("integrator, tol", [("rk4", 1e-9), ("exact", 1e-12)])
def test_the_energy_balances_with_the_spin(integrator, tol):
    """Rolling, slipping, rolling resistance, sticks and impacts on the published bar (the
    exact integrator's balance: 5e-15)."""
    bar = make_system("ball").bar
    r = run("roll", mu=0.25, friction=Friction("rolling", 0.6e-3), bar=bar, force=20.0,
            gap=0.5e-3, duration=0.1, integrator=integrator)
    assert r.metrics["impacts_total"] > 10 and r.energy["dissipated_friction_j"] > 0
    assert abs(r.energy["balance_relative"]) < tol


@pytest.mark.parametrize("force", [0.05, 2.0, 20.0])
def test_the_exact_rolling_ball_s_energy_balances_to_round_off(force):
    """The physical preset at a force where the ball rolls and slips in turn (0.05 N),
    rolls and slips each half period (2 N) and rattles (20 N): every roll/slip switch an
    event, the spin's energy and the floor's friction counted (measured 1e-13 to 1e-15)."""
    r = bb.simulate(make_system("ball", "physical", motion="roll"), bb.Harmonic(force, 1.0),
                    duration_s=0.2, integrator="exact", record_every=0)
    assert r.metrics["events"] > 300 and r.energy["dissipated_friction_j"] > 0
    assert abs(r.energy["balance_relative"]) < 1e-12


def test_rk4_converges_to_the_exact_rolling_ball_at_first_order():
    """A ball that rolls and slips each half period (physical preset, 2 N, 20 ms): RK4's
    RMS goes to the exact integrator's as dt (measured 6.2e-5, 1.55e-5, 3.9e-6 at dt = 1,
    1/4 and 1/16 us: ratios 4.00 and 4.01), its roll law switching within a step of the
    exact switch."""
    system = make_system("ball", "physical", motion="roll")
    forcing = bb.Harmonic(2.0, 1.0)
    exact = bb.simulate(system, forcing, duration_s=0.02, integrator="exact", record_every=0)
    errors = [abs(bb.simulate(system, forcing, duration_s=0.02, dt_s=dt, integrator="rk4",
                              record_every=0).metrics["rms_tip_m"]
                  / exact.metrics["rms_tip_m"] - 1) for dt in (1e-6, 2.5e-7, 6.25e-8)]
    ratios = np.array(errors[:-1]) / errors[1:]
    assert errors[0] < 1e-4 and np.all((ratios > 3.5) & (ratios < 4.5)), (errors, ratios)


@pytest.mark.parametrize("force, ball_speed, kind", [(20.0, 0.3, "slips"),
                                                       (0.05, 0.0, "rolls")])
def test_the_rolling_ball_s_maps_are_its_stages_step(force, ball_speed, kind):
    """A step where the ball slips at every stage (constant floor friction) or rolls at
    every stage (the spin its y') is affine, and the kernel takes it as a map
    (core/linmap.hpp); simulate_stage_loop takes the four stages every step.  Over
    20 ms they agree to round-off in the state with its spin, the impacts and every
    energy flow, and they are two computations."""
    from boringbar.simulate import simulate_stage_loop
    system = bb.make_system("ball", motion="roll")
    kw = dict(duration_s=0.02, initial=bb.Initial(tip_velocity_m_s=0.05 * force / 20.0,
                                                  ball_velocity_m_s=ball_speed))
    a = bb.simulate(system, bb.Harmonic(force, 1.0), integrator="rk4", **kw)
    b = simulate_stage_loop(system, bb.Harmonic(force, 1.0), **kw)
    x, y = a.final.x, b.final.x
    n = system.bar.n_modes
    assert len(x) == 2 * n + 3
    for sl in (slice(0, n), slice(n, 2 * n), slice(2 * n, 2 * n + 1), slice(2 * n + 1, None)):
        scale = max(np.max(np.abs(x[sl])), 1e-30)
        assert np.max(np.abs(x[sl] - y[sl])) <= 1e-11 * scale
    assert not np.array_equal(x, y)
    np.testing.assert_array_equal(a.impacts[:, 1], b.impacts[:, 1])
    total = a.energy["work_force_j"]
    for k in ("work_force_j", "dissipated_viscous_j", "dissipated_impacts_j",
              "dissipated_friction_j"):
        assert abs(a.energy[k] - b.energy[k]) <= 1e-10 * abs(total), k
    spin = x[2 * n + 2]
    assert (spin == x[2 * n + 1]) == (kind == "rolls")  # rolling, the spin is y'


@pytest.mark.parametrize("mu_static, mu_kinetic, n_modes", [
    (0.2, 0.15, 2), (0.002, 0.001, 2),
    (0.2, 0.15, 4),  # the kernel of a run-time shape
])
def test_a_rolling_ball_s_turning_steps_are_maps_equal_to_the_stage_loop(mu_static,
                                                                        mu_kinetic, n_modes):
    """At 0.05 N the rolling resistance's sgn() law holds the rolling ball: its y'
    chatters, changing sign from stage to stage, and each sign pattern's step is a map
    too (core/linmap.hpp), rolled or, with a floor that barely grips, slipping with the
    floor's friction beside F_b.  Over 20 ms from rest the maps and the stage loop agree
    to round-off in the state with its spin and in every energy flow, and they are two
    computations: a kernel that took these steps by stages gave the stage loop's bits
    (measured with 2 and 4 modes on the floor that grips)."""
    from boringbar.simulate import simulate_stage_loop
    system = bb.make_system("ball", motion="roll", mu_static=mu_static, mu_kinetic=mu_kinetic,
                            n_modes=n_modes)
    forcing = bb.Harmonic(0.05, 1.0)
    a = bb.simulate(system, forcing, duration_s=0.02, integrator="rk4")
    b = simulate_stage_loop(system, forcing, duration_s=0.02)
    x, y = a.final.x, b.final.x
    n = system.bar.n_modes
    for sl in (list(range(n)) + [2 * n], list(range(n, 2 * n)) + [2 * n + 1, 2 * n + 2]):
        assert np.max(np.abs(x[sl] - y[sl])) <= 1e-11 * np.max(np.abs(x[sl]))
    assert not np.array_equal(x, y)
    assert a.pattern.name == b.pattern.name == "no impact with sticking"
    total = a.energy["work_force_j"]
    for k in ("work_force_j", "dissipated_viscous_j", "dissipated_friction_j"):
        assert abs(a.energy[k] - b.energy[k]) <= 1e-10 * abs(total), k  # measured: <= 8e-14


def test_a_rolling_ball_s_limit_is_the_bar_carrying_two_sevenths_of_it():
    system = make_system("ball", friction=False, motion="roll", mu_static=1.0, mu_kinetic=0.8)
    host = system.linear_host().damper
    assert host.locked and host.mass_kg == pytest.approx(system.damper.mass_kg * 2 / 7)
    err, rpm = worst_error(system, first_five_lobes(system)[::6])
    assert err <= 0.01, f"{err:.2%} at {rpm:g} rpm"


# --- where it applies, and bad input ------------------------------------------------------
def test_a_batch_of_rolling_balls_is_its_single_runs_bit_for_bit():
    """simulate_batch takes rolling balls (their states one entry longer), each run
    the single run bit for bit; a rolling ball and a sliding one cannot share a batch."""
    system = make_system("ball", motion="roll")
    runs = [(system, bb.Harmonic(f, r), bb.Initial(ball_velocity_m_s=v))
            for f, r, v in ((20.0, 1.0, 0.3), (0.05, 1.01, 0.0), (5.0, 0.98, -0.1))]
    batch = simulate_batch(runs, duration_s=0.05)
    for (s, f, ini), b in zip(runs, batch, strict=True):
        one = bb.simulate(s, f, duration_s=0.05, initial=ini, record_every=0,
                          integrator="rk4")
        assert len(b.final.x) == 2 * s.bar.n_modes + 3
        np.testing.assert_array_equal(b.final.x, one.final.x)
        np.testing.assert_array_equal(b.impacts, one.impacts)
        assert b.energy == one.energy
    with pytest.raises(ParameterError, match="a rolling ball"):
        simulate_batch([runs[0], (make_system("ball"), bb.Harmonic(20.0), None)],
                       duration_s=0.01)


def test_the_exact_rolling_ball_s_cut_is_the_bar_carrying_two_sevenths_of_it():
    """In a cut, a ball that rolls without slip and meets no wall (2 mm gap, mu_s = 1, a
    steady cut knocked at 0.1 mm/s) leaves the bar's tip where the bar carrying 2/7 of
    it puts it, to round-off (measured 3.8e-14 of the largest W below and above the
    host's limit): the rolled regime with the cut's term in its matrix."""
    system = make_system("ball", friction=False, motion="roll", mu_static=1.0,
                         mu_kinetic=0.8, gap_m=2e-3)
    host = system.linear_host()
    limit = float(limit_at_speeds(host.bar, [1200.0])[0])
    for factor in (0.9, 1.1):
        runs = [bb.simulate(s, bb.Regenerative(depth_m=factor * limit, rpm=1200.0,
                                               start="static"),
                            duration_s=0.3, dt_s=2e-6, integrator="exact", record_every=5,
                            initial=bb.Initial(tip_velocity_m_s=1e-4))
                for s in (system, host)]
        roll, locked = (r.history[:, 1] for r in runs)
        assert runs[0].integrator == "exact" and runs[0].metrics["impacts_total"] == 0
        assert np.max(np.abs(roll - locked)) <= 1e-12 * np.max(np.abs(locked))
        assert abs(runs[0].energy["balance_relative"]) < 1e-9


@pytest.fixture(scope="module")
def rolling_cuts():
    """A rolling ball in a 10 um gap at 3 x the bare bar's limit (1200 rpm): the start's
    transient throws it at the walls 7 times in 20 ms, rolling and slipping between."""
    system = make_system("ball", gap_m=10e-6, motion="roll")
    cut = bb.Regenerative(depth_m=3.0 * float(limit_at_speeds(system.bar, [1200.0])[0]),
                          rpm=1200.0)
    return {key: bb.simulate(system, cut, duration_s=0.02, dt_s=key[1], integrator=key[0],
                             steady_fraction=1.0)
            for key in (("exact", 1e-6), ("exact", 2e-6), ("rk4", 2.5e-7), ("rk4", 6.25e-8))}


def test_the_exact_rolling_ball_s_cut_is_independent_of_the_history_step(rolling_cuts):
    """Impacts and roll/slip switches are events, whatever H: measured 1e-15 s apart
    between H = 1 and 2 us, the balance with the spin 4e-12."""
    a, b = rolling_cuts["exact", 1e-6], rolling_cuts["exact", 2e-6]
    assert a.metrics["impacts_total"] == b.metrics["impacts_total"] == 7
    assert np.max(np.abs(a.impacts[:, 0] - b.impacts[:, 0])) < 1e-10
    for r in (a, b):
        assert abs(r.energy["balance_relative"]) < 1e-9
        assert r.metrics["events"] > 7  # impacts and roll/slip switches


def test_rk4_converges_to_the_exact_rolling_ball_s_cut(rolling_cuts):
    """RK4 finds impacts at step ends and renders the rolling resistance by the sgn()
    law: its impact times, impact loss and RMS of W go to the exact integrator's as dt
    falls (measured at 0.25 and 0.0625 us: 7.5e-5 and 8.2e-6 s, 4.7e-3 and 3.0e-4 of the
    loss, 7.0e-4 and 2.8e-5 of the RMS)."""
    (t1, d1, r1), (t2, d2, r2) = rk4_cut_errors(rolling_cuts)
    assert t2 < 2e-5 and d2 < 1e-3 and r2 < 1e-4
    assert t2 < t1 and d2 < d1 and r2 < r1


def test_a_rolling_ball_s_integrator_and_its_bad_friction():
    """Both integrators take a rolling ball in a cut; "auto" chooses RK4 there, as for a
    sliding ball, and the exact integrator under harmonic forcing."""
    system = make_system("ball", motion="roll")
    cut = bb.Regenerative(depth_m=0.2e-3, rpm=1200.0)
    assert bb.simulate(system, cut, duration_s=0.002).integrator == "rk4"  # auto
    assert bb.simulate(system, cut, duration_s=0.002,
                       integrator="exact").integrator == "exact"
    assert bb.simulate(system, bb.Harmonic(amplitude_n=10.0),
                       duration_s=0.002).integrator == "exact"  # auto
    with pytest.raises(ParameterError, match="mu_static"):
        ImpactDamper(motion="roll", mu_static=0.1, mu_kinetic=0.2)


def test_rk4_s_stick_law_is_refused_for_a_rolling_ball_and_its_judged_cuts_say_so():
    """RK4's stick law holds a sliding ball only: asked of a rolling one it is refused,
    not ignored, and the verdict's cuts take the sgn() law for it and name it."""
    system = make_system("ball", motion="roll")
    with pytest.raises(ParameterError, match="stick_law = 'hold' with a rolling ball"):
        bb.simulate(system, bb.Harmonic(amplitude_n=0.01), duration_s=0.01,
                    integrator="rk4", stick_law="hold")
    ds = bb.lobes({"roll": system}, bb.LobesOptions(rpm=(1200.0,)))
    assert "a rolling ball's by the sgn() law" in ds.attrs["method_text"]
    sliding = bb.lobes({"slide": make_system("ball")}, bb.LobesOptions(rpm=(1200.0,)))
    assert "rolling" not in sliding.attrs["method_text"]


@pytest.mark.parametrize("argv, name", [
    (["--mu-static", "0.1", "--mu-kinetic", "0.2"], "--mu-static"),
    (["--mu-kinetic", "-1"], "--mu-kinetic"),
    (["--ball-motion", "spin"], "--ball-motion"),
    (["--ball-motion", "roll", "--integrator", "rk4", "--stick-law", "hold"], "stick_law"),
    (["--mu-static", "0.3"], "mu_static = 0.3 is a rolling ball's"),
    (["--ball-motion", "slide", "--mu-kinetic", "0.1"], "mu_kinetic = 0.1 is a rolling ball's"),
])
def test_the_command_line_refuses_a_bad_roll(argv, name, tmp_path, capsys):
    out = tmp_path / "out"
    assert_one_line_error(main, ["simulate", *argv, "--out", str(out)], out, name, capsys)


def test_a_rolling_ball_from_the_command_line_and_a_system_file(tmp_path, capsys):
    out = tmp_path / "roll"
    assert main(["simulate", "--ball-motion", "roll", "--duration-s", "0.05", "--out",
                 str(out)]) == 0
    assert main(["simulate", "--ball-motion", "roll", "--integrator", "exact",
                 "--duration-s", "0.05", "--out", str(tmp_path / "exact")]) == 0
    assert "integrator         exact" in capsys.readouterr().out
    d = tomllib.loads(published_file_text())
    d["ball"].update(motion="roll", mu_static=0.3, mu_kinetic=0.2)
    system = make_system("ball", spec=parse_system(d))
    assert system.damper.motion == "roll" and system.damper.mu_static == 0.3
    assert System.from_dict(system.to_dict()).damper == system.damper
    d["ball"].update(mu_static=0.1)
    with pytest.raises(SystemFileError, match="ball.mu_static"):
        parse_system(d)


def test_the_rolled_regime_is_the_bar_carrying_two_sevenths_of_the_ball():
    """The exact integrator's rolled regime (core.regime_stack's fourth), built from the
    roll law: a one-mode bar rolling its ball has omega^2 = K / (M + 2/7 m psi_d^2)."""
    system = make_system("ball", "physical", n_modes=1, motion="roll")
    su = setup_run(system, bb.Harmonic(1.0, 1.0), 1e-3, 1e-6, None, 0, 0.5, False, "exact")
    A, _, _, nreg = core.regime_stack(su.p)
    assert nreg == 4
    bar, m = system.bar, system.damper.mass_kg
    M, K, C, psi = (bar.mass_kg[0], bar.stiffness_n_m[0], bar.damping_n_s_m[0],
                    bar.psi_damper[0])
    Me = M + 2 / 7 * m * psi**2
    lam = np.linalg.eigvals(A[3])
    assert np.abs(lam) ** 2 == pytest.approx([K / Me] * 2, rel=1e-12)
    assert -2 * lam.real == pytest.approx([C / Me] * 2, rel=1e-12)


@pytest.mark.parametrize("integrator", INTEGRATORS)
def test_the_history_records_the_spin(integrator, tmp_path):
    """A rolling ball's history has its spin last (a sliding ball's has none): the final
    state's at the last row, y' wherever it rolls (at 0.05 N throughout), and the same
    spin from both integrators (measured 3e-4 of its largest at 2 N, RK4 at 0.1 us)."""
    system = make_system("ball", motion="roll")
    runs = {force: bb.simulate(system, bb.Harmonic(force, 1.0), duration_s=0.05,
                               integrator=integrator, dt_s=1e-7 if integrator == "rk4" else 1e-6,
                               record_every=10 if integrator == "rk4" else 1)
            for force in (2.0, 0.05)}
    for r in runs.values():
        assert r.history.shape[1] == 7 and r.history[-1, 0] == pytest.approx(0.05)
        assert r.history[-1, 6] == pytest.approx(r.final.x[-1], rel=1e-12, abs=1e-15)
    rolls = runs[0.05].history
    np.testing.assert_array_equal(rolls[:, 6], rolls[:, 4])
    spin = runs[2.0].history[:, 6]
    assert np.ptp(spin) > 1e-3 and np.mean(spin == runs[2.0].history[:, 4]) < 0.1  # slips
    other = "exact" if integrator == "rk4" else "rk4"
    ref = bb.simulate(system, bb.Harmonic(2.0, 1.0), duration_s=0.05, integrator=other,
                      dt_s=1e-7 if other == "rk4" else 1e-6,
                      record_every=10 if other == "rk4" else 1).history[:, 6]
    assert np.max(np.abs(spin - ref)) < 1e-3 * np.max(np.abs(ref))
    ds = runs[2.0].to_xarray()
    np.testing.assert_array_equal(ds["ball_spin_m_s"].values, spin)
    sliding = bb.simulate(make_system("ball"), bb.Harmonic(2.0), duration_s=0.01,
                          integrator=integrator)
    assert sliding.history.shape[1] == 6 and "ball_spin_m_s" not in sliding.to_xarray()


def test_a_rolling_ball_s_run_figure_shows_its_spin():
    """run.png of a rolling ball has a third row, its y' and spin, read from the run's
    file as from the run; a sliding ball's has two."""
    roll = bb.simulate(make_system("ball", motion="roll"), bb.Harmonic(2.0), duration_s=0.05)
    for source in (roll, roll.to_xarray()):
        fig = plot_run(source)
        lower = fig.axes[4]
        assert len(fig.axes) == 6 and "spin" in lower.get_ylabel()
        np.testing.assert_array_equal(lower.lines[1].get_ydata(), roll.history[:, 6] * 1e3)
        assert "rolling ball (mu_s 0.2, mu_k 0.15)" in "".join(t.get_text() for t in fig.texts)
    slide = bb.simulate(make_system("ball"), bb.Harmonic(2.0), duration_s=0.05)
    assert len(plot_run(slide).axes) == 4

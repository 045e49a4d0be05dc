"""Shooting for periodic orbits (boringbar.orbits.shooting): the saltation monodromy against
central finite differences, the map against the kernel, and the linear bar's truths."""

import dataclasses
import json
import math

import numpy as np
import pytest
import xarray as xr
from scipy.linalg import expm
from scipy.optimize import brentq

import boringbar as bb
from boringbar.analysis.continuation import (
    ContinuationOptions,
    assemble,
    concat_branches,
    plan,
    start_state,
    summary,
)
from boringbar.cli.main import main
from boringbar.model.bar import ModalModel
from boringbar.model.dampers import NO_FRICTION, ImpactDamper
from boringbar.model.forcing import Harmonic
from boringbar.model.system import System, make_system
from boringbar.orbits import shooting as sh
from boringbar.orbits.attractors import SETTLED
from boringbar.orbits.continuation import continue_branch
from boringbar.plot.orbits import plot_continuation
from boringbar.plot.style import system_words
from boringbar.reference.linear import dynamic_stiffness, tip_frf
from boringbar.reference.masri_caughey import two_impact_orbit
from boringbar.simulate import State, simulate


def _fd_jacobian(fl, x):
    sc = np.maximum(np.abs(x), 1e-9)
    J = np.zeros((fl.N, fl.N))
    for i in range(fl.N):
        e = np.zeros(fl.N)
        e[i] = 1e-6 * sc[i]
        J[:, i] = (sh.advance(fl, x + e).x - sh.advance(fl, x - e).x) / (2 * e[i])
    return J, np.diag(sc)


def _check_map(system, forcing, fl, x, pr):
    """The orbit's saltation monodromy against the central difference of the map (1e-6),
    and the map against the exact kernel: one period of simulate from x (1e-9); that
    run."""
    Jfd, D = _fd_jacobian(fl, x)
    err = np.max(np.abs((pr.jacobian - Jfd) @ D)) / np.max(np.abs(pr.jacobian @ D))
    assert err < 1e-6
    one = simulate(system, forcing, duration_s=fl.period, dt_s=fl.period / 2000,
                   integrator="exact", initial=State(x, 0.0), steady_fraction=1.0)
    assert np.max(np.abs(one.final.x - pr.x)) <= 1e-9 * np.max(np.abs(x))
    return one


@pytest.mark.parametrize("friction", [False, True])
def test_saltation_monodromy_is_the_finite_difference_jacobian(friction):
    system = make_system("ball", "physical", gap_m=0.1e-3, friction=friction)
    forcing = Harmonic(20.0, ratio=1.0)
    fl = sh.make_flow(system, forcing)
    run = simulate(system, forcing, duration_s=100 * fl.period, dt_s=1e-6, integrator="exact")
    x, pr = sh.periodic_orbit(fl, run.final.x)
    kinds = [k for _, k in pr.events]
    assert "impact+" in kinds and "impact-" in kinds
    assert ("reversal" in kinds) == friction
    assert np.max(np.abs(pr.x - x)) <= 1e-12 * np.max(np.abs(x))
    one = _check_map(system, forcing, fl, x, pr)
    # the orbit's RMS (Gauss-Legendre per segment) is the kernel's exact integral
    assert abs(pr.rms_tip - one.rms_tip_m) <= 1e-9 * one.rms_tip_m


#: a 100 Hz mode of 5 kg at the tip: at a few newtons its cavity accelerates near
#: 3.5 mu_s g, so a rolling ball rolls, slips and meets both walls within a period
MEDIUM = ModalModel.from_tap_test(100.0, 0.02, tip_mass_kg=5.0, damper_ratio=0.6)


def _settled(system, forcing, fl, periods: int, step: float):
    """The exact integrator's state after ``periods`` whole forcing periods from rest."""
    dt = fl.period / math.ceil(fl.period / step)
    return simulate(system, forcing, duration_s=periods * fl.period, dt_s=dt,
                    integrator="exact").final.x


@pytest.mark.parametrize("force, gap, mu, stable", [(6.0, 0.03e-3, 0.5, True),
                                                    (3.0, 0.02e-3, 0.2, False)])
def test_a_rolling_ball_s_orbit_is_the_exact_integrators(force, gap, mu, stable):
    """The spin a state (docs/continuation.md, "A rolling ball"): an orbit that rolls,
    slips, reaches the roll's limit and hits both walls.  Its monodromy is the central
    difference of the map (measured 5.8e-10 and 4.2e-10), one period of the exact
    integrator from it lands on it (6.9e-16 and 2.9e-15), and the stable orbit is where a
    long run settles (1.6e-12: a brute-force attractor) while the unstable one has a
    multiplier outside the unit circle (4.25)."""
    ball = ImpactDamper.ball("carbide", gap_m=gap, friction=NO_FRICTION, motion="roll",
                             mu_static=mu, mu_kinetic=0.8 * mu)
    system, forcing = System(MEDIUM, ball, "physical"), Harmonic(force, ratio=1.0)
    fl = sh.make_flow(system, forcing)
    assert fl.N == 2 * fl.n + 3 and fl.roll
    start = _settled(system, forcing, fl, 300, 1e-5)
    x, pr = sh.periodic_orbit(fl, start)
    kinds = {k for _, k in pr.events}
    assert {"impact+", "impact-", "slip-zero"} <= kinds, kinds
    assert kinds & {"roll-limit+", "roll-limit-"}, kinds
    _check_map(system, forcing, fl, x, pr)
    largest = abs(sh.multipliers(pr)[0])
    if stable:
        assert largest < 1.0
        assert np.max(np.abs(start - x)) <= 1e-9 * np.max(np.abs(x))
    else:
        assert largest > 1.0


def test_a_slip_that_runs_out_and_back_inside_a_grid_step_is_seen():
    """The published bar's rolling ball at 20 N, ratio 1.00275 (gap 0.1 mm, rolling
    resistance): after y' turns at phase 0.0128 it overtakes its spin and falls back
    behind it 0.0101 periods later, inside one grid step of shooting (1/64 period) and of
    the exact integrator (0.0127 periods).  Both see the two ends of the slip (the tests
    of a function that turns back towards zero inside a step), agree to round-off
    (measured 3.6e-16), and RK4 converges to them at first order (4.5e-8, 4.0e-9 and
    5.8e-10 off at 1e5, 1e6 and 1e7 steps a period).  Missed, the floor's friction keeps
    its sign through the excursion, and the period ends 1.5e-4 away."""
    system = make_system("ball", "physical", gap_m=0.1e-3, friction=True, motion="roll")
    forcing = Harmonic(20.0, ratio=1.00275)
    fl = sh.make_flow(system, forcing)
    x, pr = sh.periodic_orbit(fl, _settled(system, forcing, fl, 300, 1e-6))
    window = 0.03 * fl.period
    shot = sh.advance(fl, x, duration=window)
    assert [k for _, k in shot.events] == ["reversal", "slip-zero", "slip-zero", "reversal"]
    t1, t2 = (t for t, k in shot.events if k == "slip-zero")
    assert t2 - t1 < fl.period / sh.GRID  # (the exact integrator's step: 0.0127 periods)
    exact = simulate(system, forcing, duration_s=window, dt_s=window / 300,
                     integrator="exact", initial=State(x, 0.0), steady_fraction=1.0)
    assert exact.metrics["events"] == 4
    scale = np.max(np.abs(x))
    assert np.max(np.abs(exact.final.x - shot.x)) <= 1e-12 * scale
    off = [np.max(np.abs(simulate(system, forcing, duration_s=window, dt_s=window / n,
                                  integrator="rk4", initial=State(x, 0.0),
                                  steady_fraction=1.0, record_every=0).final.x - shot.x))
           for n in (3000, 30000)]
    assert off[1] < 0.3 * off[0], off


def test_linear_bar_orbit_is_the_forced_response():
    system = make_system("solid", "physical")
    forcing = Harmonic(10.0, ratio=0.93)
    fl = sh.make_flow(system, forcing)
    x, pr = sh.periodic_orbit(fl, np.zeros(fl.N))
    bar = system.bar
    n = bar.n_modes
    # tip amplitude from phase-0 displacement and velocity: W(t) = Im(G F0 e^{i Omega t})
    w0, v0 = bar.psi_tip @ x[:n], bar.psi_tip @ x[n:]
    amp = np.hypot(w0, v0 / fl.omega)
    ref = abs(tip_frf(bar, fl.omega)) * forcing.amplitude_n
    assert abs(amp - ref) <= 1e-10 * ref
    wn = np.sqrt(bar.stiffness_n_m / bar.mass_kg)
    z = bar.damping_ratio
    lam = np.concatenate([-z * wn + 1j * wn * np.sqrt(1 - z**2),
                          -z * wn - 1j * wn * np.sqrt(1 - z**2)])
    expected = np.sort_complex(np.exp(lam * fl.period))
    got = np.sort_complex(sh.multipliers(pr))
    assert np.max(np.abs(got - expected)) <= 1e-10


def _second_order(system):
    """(M, C, K) of the linear bar as the reference FRF builds its dynamic stiffness
    Z(w) = K - w^2 M + i w C (reference/linear.py): Z(0), Z(w1) + Z(-w1), Z(w1) - Z(-w1),
    w1 the first natural frequency (so K - w1^2 M loses no digits)."""
    d = system.damper
    tmd = d if system.kind == "tmd" else None
    added = d.mass_kg if system.kind == "locked" else 0.0
    w1 = system.bar.natural_frequency_rad_s
    z0, zp, zm = dynamic_stiffness(system.bar, np.array([0.0, w1, -w1]), tmd, added)
    K = z0.real
    return (K - 0.5 * (zp + zm).real) / w1**2, ((zp - zm) / 2j).real / w1, K


def _eigenvalues(system):
    """lambda_i of M q'' + C q' + K q = 0 (the first-order companion form)."""
    M, C, K = _second_order(system)
    k = len(M)
    Minv = np.linalg.inv(M)
    A = np.block([[np.zeros((k, k)), np.eye(k)], [-Minv @ K, -Minv @ C]])
    return np.linalg.eigvals(A)


@pytest.mark.parametrize("bar", ["tmd", "locked"])
@pytest.mark.parametrize("ratio", [0.93, 1.07])
def test_tmd_and_locked_orbits_are_the_closed_form_forced_response(bar, ratio):
    """The TMD bar and the locked ball are linear: the periodic orbit is the steady
    response, tip amplitude |G(i Omega)| F0 with G the reference FRF (tip_frf with the
    absorber / the ball as an added mass), and the multipliers are exp(lambda_i T) of the
    eigenvalues of the second-order system built from the reference's dynamic stiffness."""
    system = (make_system("tmd", "physical") if bar == "tmd"
              else make_system("ball", "physical", locked=True))
    assert system.kind == bar
    forcing = Harmonic(10.0, ratio=ratio)
    fl = sh.make_flow(system, forcing)
    x, pr = sh.periodic_orbit(fl, np.zeros(fl.N))
    b, n = system.bar, system.bar.n_modes
    assert fl.N == 2 * n + (2 if bar == "tmd" else 0) and pr.events == []
    w0, v0 = b.psi_tip @ x[:n], b.psi_tip @ x[n:2 * n]
    amp = np.hypot(w0, v0 / fl.omega)
    G = (tip_frf(b, fl.omega, tmd=system.damper) if bar == "tmd"
         else tip_frf(b, fl.omega, added_mass_kg=system.damper.mass_kg))
    assert abs(amp - abs(G) * 10.0) <= 1e-10 * abs(G) * 10.0
    # the phase too: W(t) = Im(G F0 e^{i Omega t}), so W(0) = F0 Im G
    assert abs(w0 - 10.0 * G.imag) <= 1e-10 * abs(G) * 10.0
    expected = np.sort_complex(np.exp(_eigenvalues(system) * fl.period))
    got = np.sort_complex(sh.multipliers(pr))
    assert len(got) == fl.N
    assert np.max(np.abs(got - expected)) <= 1e-10


def test_tmd_branch_in_ratio_follows_the_frf():
    """Continued along the frequency ratio, every point of the TMD bar's branch has the
    tip amplitude |G(i Omega)| F0 of the reference FRF, and no bifurcation is reported."""
    system = make_system("tmd", "physical")
    fl = sh.make_flow(system, Harmonic(10.0, ratio=0.8))
    br = continue_branch(fl, "ratio", np.zeros(fl.N), 1.2, step=0.05, max_points=80)
    assert br.stop.startswith("end of range") and br.events == []
    n = system.bar.n_modes
    for pt in br.points:
        om = pt.value * fl.reference
        amp = np.hypot(fl.psi_tip @ pt.x[:n], fl.psi_tip @ pt.x[n:2 * n] / om)
        ref = abs(tip_frf(system.bar, om, tmd=system.damper)) * 10.0
        assert abs(amp - ref) <= 1e-9 * ref
        assert pt.stable


def test_continuation_refuses_a_parameter_the_bar_does_not_have():
    system = make_system("tmd", "physical")
    with pytest.raises(bb.ParameterError, match="gap-mm.*force-n, ratio"):
        plan(system, bb.ContinuationOptions(parameter="gap-mm", stop=1.0))
    fl = sh.make_flow(make_system("ball", "physical", locked=True), Harmonic(10.0, ratio=1.0))
    with pytest.raises(bb.ParameterError, match="restitution"):
        continue_branch(fl, "restitution", np.zeros(fl.N), 0.5)


def test_cli_continue_tmd_and_locked(tmp_path, capsys):
    for extra in (["--bar", "tmd"], ["--bar", "ball", "--locked"]):
        rc = main(["continue", *extra, "--parameter", "ratio", "--range", "0.9:1.1",
                   "--force-n", "10", "--max-points", "5", "--out", str(tmp_path), "--json"])
        assert rc == 0
        out = json.loads(capsys.readouterr().out)
        with xr.open_dataset(tmp_path / "continuation.nc") as ds:
            n_state = ds.sizes["state"]
        system = (make_system("tmd", "physical") if extra[1] == "tmd"
                  else make_system("ball", "physical", locked=True))
        assert n_state == sh.state_size(system)
        pts = out["branches"][0]["points"]
        assert len(pts) == 5 and all(p["stable"] for p in pts)
        om = pts[-1]["value"] * system.reference_frequency_rad_s
        G = (tip_frf(system.bar, om, tmd=system.damper) if extra[1] == "tmd"
             else tip_frf(system.bar, om, added_mass_kg=system.damper.mass_kg))
        assert abs(pts[-1]["strobe_tip_m"] - 10.0 * G.imag) <= 1e-8 * abs(G) * 10.0
    assert main(["continue", "--bar", "tmd", "--parameter", "gap-mm", "--range", "0.5:0.4",
                 "--out", str(tmp_path)]) == 2


def _masri_caughey(force=30.0):
    system = make_system("ball", "physical", n_modes=1, friction=False, gap_m=0.5e-3)
    forcing = Harmonic(force, ratio=1.0)
    fl = sh.make_flow(system, forcing)
    bar, ball = system.bar, system.damper
    orbit = next(o for o in two_impact_orbit(
        bar.mass_kg[0], bar.stiffness_n_m[0], bar.damping_n_s_m[0],
        bar.psi_tip[0], bar.psi_damper[0],
        ball.mass_kg, ball.gap_m, ball.restitution, force, fl.omega) if o.admissible and o.stable)
    h = 1e-9
    dy0 = float(orbit.relative_displacement(h) - orbit.relative_displacement(-h)) / (2 * h)
    x0 = np.array([float(orbit.modal_displacement(0.0)), float(orbit.modal_velocity(0.0)),
                   float(orbit.relative_displacement(0.0)), dy0])
    return fl, orbit, x0


def test_newton_converges_to_the_masri_caughey_orbit():
    fl, orbit, x0 = _masri_caughey()
    x, pr = sh.periodic_orbit(fl, x0 * (1 + 1e-3 * np.array([1, -1, 1, -1])))
    t_plus = next(t for t, k in pr.events if k == "impact+")
    assert abs((fl.omega * t_plus) % (2 * np.pi) - orbit.phase) < 1e-9
    speed = abs(x[3] + fl.psi_d[0] * x[1])  # the ball's absolute speed in flight
    assert abs(speed - orbit.ball_speed) < 1e-9 * orbit.ball_speed
    # P is the half-period impact map applied twice: its multipliers are their squares
    got = np.sort_complex(sh.multipliers(pr))
    expected = np.sort_complex(np.asarray(orbit.multipliers) ** 2)
    assert np.max(np.abs(got - expected)) < 1e-7


def _closed_form_crossing(fl, orbit, lo, hi, along="force"):
    """The F0 (or ratio) where the closed-form orbit (the root nearest in phase) loses
    stability."""
    sysm = orbit.system

    def unstable(v):
        force, omega = (v, sysm.omega) if along == "force" else (30.0, v * fl.reference)
        orbits = two_impact_orbit(sysm.mass, sysm.stiffness, sysm.damping, sysm.psi_tip,
                                  sysm.psi_ball, sysm.ball_mass, sysm.gap, sysm.restitution,
                                  force, omega)
        o = min(orbits, key=lambda o: abs(o.phase - orbit.phase))
        return np.max(np.abs(o.multipliers)) > 1.0
    assert unstable(lo) != unstable(hi)
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if unstable(mid) == unstable(lo) else (lo, mid)
    return 0.5 * (lo + hi)


def test_continuation_in_force_finds_the_closed_form_stability_change():
    fl, orbit, x0 = _masri_caughey()
    br = continue_branch(fl, "force-n", x0, 27.0, step=0.05, max_points=60)
    assert br.stop.startswith("end of range")
    changes = [v for k, v in br.events if k in ("fold", "period-doubling", "neimark-sacker")]
    assert len(changes) == 1
    expected = _closed_form_crossing(fl, orbit, 27.0, 30.0)
    assert abs(changes[0] - expected) < 1e-8 * expected
    assert br.points[0].stable and not br.points[-1].stable


def _flight_margin(orbit):
    """min over the flight's interior extrema of y of (delta/2 - |y|) / (delta/2), from the
    closed form alone: after the + wall impact the ball flies at -V, so
    y' = -V - psi_d u'(t) (u' the closed form's modal velocity); inf without an extremum."""
    sysm = orbit.system
    t0, th = orbit.impact_time, sysm.half_period

    def yd(t):
        return -orbit.ball_speed - sysm.psi_ball * orbit.modal_velocity(t)
    t = t0 + np.linspace(0.0, th, 4001)[1:-1]
    v = yd(t)
    best = np.inf
    for i in np.flatnonzero(v[:-1] * v[1:] < 0):
        tz = brentq(yd, t[i], t[i + 1], xtol=1e-16 * th)
        y = float(orbit.relative_displacement(tz))
        best = min(best, (0.5 * sysm.gap - abs(y)) / (0.5 * sysm.gap))
    return best


def test_a_grazing_is_located_where_the_closed_form_orbit_touches_a_wall_in_flight():
    """One mode, frictionless ball, gap 0.5 mm, e = 0.7, ratio 1, the closed form's
    symmetric two-impact orbit of larger phase (unstable, |mu| ~ 4.3, which shooting
    follows all the same).  As F0 grows, the bar at z_d overtakes the ball in flight: y
    has an interior extremum that reaches the wall at F0 = 172.19207 N, where the orbit
    stops being admissible.  That value comes from the closed form alone (the impact
    phase equation, the impulse-train response and the straight flight: no integration
    and no shooting), bisected to 1e-14 on the extremum's distance from the wall.  The
    continued branch must end with a ``grazing`` there: before the shooting module
    searched each grid step for an extremum beyond a wall, the incursion was missed until
    it covered a grid point and the grazing came out 2.8e-5 relative too late."""
    system = make_system("ball", "physical", n_modes=1, friction=False, gap_m=0.5e-3)
    bar, ball = system.bar, system.damper
    fl0 = sh.make_flow(system, Harmonic(165.0, ratio=1.0))

    def orbit(force):
        return max(two_impact_orbit(bar.mass_kg[0], bar.stiffness_n_m[0], bar.damping_n_s_m[0],
                                    bar.psi_tip[0], bar.psi_damper[0], ball.mass_kg, ball.gap_m,
                                    ball.restitution, force, fl0.omega),
                   key=lambda o: o.phase)
    lo, hi = 165.0, 180.0
    assert orbit(lo).admissible and _flight_margin(orbit(lo)) > 0.05
    assert not orbit(hi).admissible and _flight_margin(orbit(hi)) < 0
    while hi - lo > 1e-14 * hi:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if _flight_margin(orbit(mid)) > 0 else (lo, mid)
    grazing = 0.5 * (lo + hi)
    o = orbit(165.0)
    h = 1e-9
    x0 = np.array([float(o.modal_displacement(0.0)), float(o.modal_velocity(0.0)),
                   float(o.relative_displacement(0.0)),
                   float(o.relative_displacement(h) - o.relative_displacement(-h)) / (2 * h)])
    br = continue_branch(fl0, "force-n", x0, 180.0, step=0.05, max_points=60)
    assert [k for k, _ in br.events] == ["grazing"], (br.stop, br.events)
    assert abs(br.events[0][1] - grazing) <= 1e-9 * grazing, (br.events, grazing)
    assert br.points[-1].value == br.events[0][1] and "grazing" in br.stop
    assert [k for _, k in br.points[-1].events] == ["impact-", "impact+"]


def test_continuation_dataset_and_summary_from_a_settled_simulation():
    system = make_system("ball", "physical", gap_m=0.1e-3, friction=True)
    ds = bb.continuation(system, Harmonic(20.0, ratio=1.0), options=bb.ContinuationOptions(
        parameter="ratio", stop=1.02, step=0.05, max_points=6))
    s = summary(ds)
    points = s["branches"][0]["points"]
    assert len(points) >= 2 and points[0]["value"] == pytest.approx(1.0)
    assert all(p["rms_tip_m"] > abs(p["strobe_tip_m"]) / 10 for p in points)
    assert all(len(p["multipliers_abs"]) == 6 for p in points)
    assert [p["stable"] for p in points] == [max(p["multipliers_abs"]) < 1 for p in points]
    assert ds.attrs["parameter"] == "ratio" and "wall_time_s" in s


def test_cli_continue_writes_its_files_and_refuses_bad_ranges(tmp_path, capsys):
    rc = main(["continue", "--gap-mm", "0.5", "--friction", "off", "--modes", "1",
               "--range", "30:29", "--start-from", "masri-caughey", "--max-points", "4",
               "--out", str(tmp_path), "--json"])
    assert rc == 0
    out = json.loads(capsys.readouterr().out)
    assert len(out["branches"][0]["points"]) == 4 and "wall_time_s" in out
    assert (tmp_path / "continuation.png").stat().st_size > 0
    assert (tmp_path / "continuation.nc").exists()
    assert main(["continue", "--range", "1:x", "--out", str(tmp_path)]) == 2


def test_continuation_in_ratio_finds_the_closed_form_stability_change():
    fl, orbit, x0 = _masri_caughey()
    br = continue_branch(fl, "ratio", x0, 1.04, step=0.05, max_points=60)
    changes = [v for k, v in br.events if k in ("fold", "period-doubling", "neimark-sacker")]
    assert len(changes) == 1, (br.stop, br.events)
    expected = _closed_form_crossing(fl, orbit, 1.0, 1.04, along="ratio")
    assert abs(changes[0] - expected) < 1e-8 * expected
    assert br.points[0].stable and not br.points[-1].stable


def test_a_branch_refused_at_its_start_is_an_empty_branch_with_its_reason():
    system = make_system("ball", "physical", gap_m=0.1e-3, friction=True)
    p = plan(system, bb.ContinuationOptions(parameter="ratio", stop=1.02))
    empty = {"value": [], "state": [], "strobe_tip_m": [], "rms_tip_m": [],
             "multipliers": [], "stable": [], "events": [],
             "stop": "refused at the start: Newton did not converge at the start value",
             "start": 1.0}
    ds = assemble(p, [empty])
    assert ds.sizes["point"] == 0 and ds.sizes["state"] == 6
    assert "refused at the start" in json.loads(ds.attrs["stop_reasons"])[0]
    assert summary(ds)["branches"][0]["points"] == []


def test_branches_of_different_lengths_stack_with_padding():
    system = make_system("ball", "physical", gap_m=0.5e-3, friction=False, n_modes=1)
    p = plan(system, bb.ContinuationOptions(parameter="force-n", stop=5.0))

    def result(n, events):
        return {"value": list(30.0 - np.arange(n)), "state": [np.full(4, i) for i in range(n)],
                "strobe_tip_m": [1e-4] * n, "rms_tip_m": [1e-4] * n,
                "multipliers": [np.array([0.5, 0.4, 0.3 + 0.1j, 0.3 - 0.1j])] * n,
                "stable": [True] * n, "events": events, "stop": f"stop {n}", "start": 30.0}
    parts = [assemble(p, [result(3, [("fold", 29.0)])]),
             assemble(p, [result(5, [("grazing", 27.0), ("fold", 26.0)])]),
             assemble(p, [result(0, [])])]
    ds = concat_branches(parts)
    assert dict(ds.sizes) == {"branch": 3, "point": 5, "state": 4, "multiplier": 4, "event": 2}
    assert "state" in ds.data_vars and not ds.coords
    s = summary(ds)
    assert [len(b["points"]) for b in s["branches"]] == [3, 5, 0]
    assert [b["events"] for b in s["branches"]][0] == [{"kind": "fold", "value": 29.0}]
    assert [b["stop"] for b in s["branches"]] == ["stop 3", "stop 5", "stop 0"]
    assert plot_continuation(ds) is not None  # the padding is not drawn


def test_a_newton_solution_is_accepted_only_with_a_small_residual():
    x = np.array([1.0, -2.0, 0.5])
    sh.check_residual(np.full(3, 1e-12), x)  # 5e-13 of max |x|: accepted
    with pytest.raises(sh.OrbitRefused, match="residual"):
        sh.check_residual(np.array([0.0, 0.4, 0.0]), x, "the corrector")


def test_a_simulated_start_settles_on_until_its_state_returns():
    """The physical ball with friction at 0.1 mm, 20 N, ratio 1: 100 periods from rest leave
    it in its transient (its state 2.9e-2 of its size from itself one period later with
    OpenBLAS's SkylakeX kernels, 6.2e-4 with Haswell's; Newton refused from the first).
    The start runs on, 100 periods a stretch, until the state returns within SETTLED
    (measured 3.0e-6 and 5.6e-8 after 200 periods), and Newton converges from it."""
    system = make_system("ball", "physical", gap_m=0.1e-3, friction=True)
    forcing = Harmonic(20.0, ratio=1.0)
    fl = sh.make_flow(system, forcing)
    x = start_state(system, ContinuationOptions(force_n=20.0, settle_periods=100), fl)
    back = sh.advance(fl, x).x
    assert np.max(np.abs(back - x)) <= SETTLED * np.max(np.abs(x))
    xp, _ = sh.periodic_orbit(fl, x, rms=False)
    assert np.max(np.abs(xp - x)) <= 1e-3 * np.max(np.abs(x))


def _settled_orbit(friction: bool, force: float = 20.0):
    system = make_system("ball", "physical", gap_m=0.1e-3, friction=friction)
    fl = sh.make_flow(system, Harmonic(force, ratio=1.0))
    start = start_state(system, ContinuationOptions(force_n=force), fl)
    x, _ = sh.periodic_orbit(fl, start, rms=False)
    return fl, x


@pytest.mark.parametrize(("friction", "phase", "k"), [(False, 0.0, 1), (True, 1.3, 2)])
def test_the_force_derivative_is_the_finite_difference_one(friction, phase, k):
    """dP^k/dF0 from the augmented Jacobian (impacts, and with friction reversals, at a
    moved section and over two periods) against central differences of the map of step
    1e-4 N: 1e-8 (the differences' own error, truncation and rounding, 1e-10 to 4e-9)."""
    fl, x = _settled_orbit(friction)
    fl = dataclasses.replace(fl, phase=phase)
    x = sh.carry(dataclasses.replace(fl, phase=0.0), x, phase)
    pr = sh.advance(fl, x, k)
    h = 1e-4
    fd = (sh.advance(dataclasses.replace(fl, amplitude=fl.amplitude + h), x, k).x
          - sh.advance(dataclasses.replace(fl, amplitude=fl.amplitude - h), x, k).x) / (2 * h)
    assert len(pr.events) >= 2 * k
    assert np.max(np.abs(fd - pr.force_derivative)) <= 1e-8 * np.max(np.abs(fd))


def test_events_on_the_closed_form_are_where_expm_puts_them():
    """Every event time found by Brent's method on the modes' closed form
    (shooting.Relative) against Brent's method on expm(A s) z: within 1e-13 of the grid
    step, with friction reversals and impacts."""
    fl, x = _settled_orbit(True)
    A = sh.augmented(fl, 1.0)
    rel = sh.Relative(fl, A)
    j = 2 * fl.n

    def g(z):  # y - half, y + half, y' (the sliding ball's reversal)
        return np.array([z[j] - fl.half, z[j] + fl.half, z[j + 1]])

    def g_exact(s, z, i):
        return g(expm(A * s) @ z)[i]
    z = np.concatenate([x, [0.0, 1.0, 1.0]])
    h = fl.period / sh.GRID
    checked = 0
    for _ in range(4 * sh.GRID):
        zn = expm(A * h) @ z
        for i in (0, 1, 2):
            if g(z)[i] * g(zn)[i] < 0:
                closed = brentq(rel.event(z, i), 0.0, h, xtol=1e-18, rtol=1e-15)
                exact = brentq(g_exact, 0.0, h, args=(z, i), xtol=1e-18, rtol=1e-15)
                assert abs(closed - exact) <= 1e-13 * h
                checked += 1
        z = zn
    assert checked >= 2


@pytest.mark.parametrize(("preset", "modes"), [("physical", 1), ("paper", 2), ("physical", 3)])
def test_the_carrying_force_is_docs_formula(preset, modes):
    """F_req, read off the core's regime matrices, against docs/model.md's closed form:
    psi_d . a_free / (1 / m + s sum psi_d^2 / M), a_free the bar's modal accelerations
    without the ball (s: the reaction's sign, -1 as printed under the paper preset)."""
    system = make_system("ball", preset, n_modes=modes, gap_m=0.5e-3, friction=True)
    fl = sh.make_flow(system, Harmonic(10.0, 1.0))
    rng = np.random.default_rng(modes)
    # the last state is a diverging Newton iterate's, where y'' dwarfs kappa
    for size in (1.0, 1.0, 1.0, 1.0, 1e20):
        x = size * rng.standard_normal(fl.N) * np.concatenate([np.full(2 * fl.n, 1e-5),
                                                               [1e-4, 1e-2]])
        t = float(rng.uniform(0, 1e-2))
        n = fl.n
        a_free = (-fl.K * x[:n] - fl.C * x[n:2 * n]
                  + fl.psi_tip * fl.amplitude * np.sin(fl.omega * t)) / fl.M
        want = fl.psi_d @ a_free / (1.0 / fl.m + fl.s * np.sum(fl.psi_d**2 / fl.M))
        assert sh.carrying_force(fl, x, t) == pytest.approx(want, rel=1e-12, abs=1e-15)
        z = np.concatenate([x, [np.sin(fl.omega * t), np.cos(fl.omega * t), 1.0]])
        for sdir in (-1.0, 1.0):  # from the regime a friction switch leaves
            got = sh.carrying_force_in(sh.augmented(fl, sdir), z, -fl.fc * sdir, fl.n)
            assert got == pytest.approx(want, rel=1e-12, abs=1e-15)


def test_cli_continue_takes_a_rolling_ball(tmp_path, capsys):
    """`boringbar continue --ball-motion roll`: the orbits carry the spin (2n + 3 states),
    the title says the ball rolls, and the return check holds on the stable points."""
    rc = main(["continue", "--gap-mm", "0.1", "--ball-motion", "roll", "--force-n", "20",
               "--parameter", "ratio", "--range", "1.0:1.0015", "--max-points", "3",
               "--no-switch", "--seeds", "0", "--out", str(tmp_path), "--json"])
    assert rc == 0
    out = json.loads(capsys.readouterr().out)
    points = out["branches"][0]["points"]
    assert len(points) == 3 and all(p["stable"] for p in points)
    assert all(len(p["multipliers_abs"]) == 2 * 2 + 3 for p in points)
    assert not out["return_check"]["failed"]
    with xr.open_dataset(tmp_path / "continuation.nc") as ds:
        assert ds.sizes["state"] == 2 * 2 + 3
    assert (tmp_path / "continuation.png").stat().st_size > 0
    # the closed-form start is a sliding ball's orbit: refused for a rolling one
    assert main(["continue", "--gap-mm", "0.5", "--friction", "off", "--modes", "1",
                 "--ball-motion", "roll", "--mu-static", "0", "--mu-kinetic", "0",
                 "--range", "30:29", "--start-from", "masri-caughey",
                 "--out", str(tmp_path / "mc")]) == 2
    assert "this system has a rolling ball" in capsys.readouterr().err
    assert not (tmp_path / "mc").exists()
    # one mode in each of two planes is two modes: the message names the planes
    assert main(["continue", "--gap-mm", "0.5", "--friction", "off", "--modes", "1",
                 "--planes", "2", "--range", "30:29", "--start-from", "masri-caughey",
                 "--out", str(tmp_path / "mc")]) == 2
    assert capsys.readouterr().err.rstrip().endswith("this system has two bending planes")
    words = system_words(make_system("ball", motion="roll", contact="hertz").to_dict())
    assert words.replace("\u00a0", " ").endswith(", rolling (mu_s 0.2, mu_k 0.15), Hertz contact")

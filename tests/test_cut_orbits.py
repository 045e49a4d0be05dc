"""Chatter orbits of the regenerative cut (boringbar.orbits.cut_orbits, cut_branch):
checked against truths that are not the code's own.

- The Hopf point and its frequency against the frequency-domain characteristic equation
  (reference.stability), to 1e-6, at several speeds, for the solid and the TMD bar;
  the discretisation's error falls at fourth order.
- A linear cutting law's branch stands vertical at the Hopf depth until the tool leaves
  the cut, at the closed-form amplitude h_m / (2 |sin(w tau / 2)|).
- With one revolution of memory, the branch beyond follows the describing function of
  the clipped chip: b(A) = b_lim / N(a), a = 2 A |sin(w tau / 2)|,
  N(a) = (pi / 2 + beta + sin(beta) cos(beta)) / pi, beta = asin(h_m / a).
- In the cut, a linear law's Floquet multipliers against exp(lambda T) of the delay
  equation's characteristic roots.
- The Jacobian against central differences; a stable orbit's amplitude against a
  simulated cut (the compiled RK4 integrator) that settles on it; the compiled cut
  started on a stable orbit with its own history stays on it, and knocked off it comes
  back at the rate of the orbit's largest nontrivial Floquet multiplier.
"""

from __future__ import annotations

import cmath
import json
import math
from dataclasses import replace

import numpy as np
import pytest
import xarray as xr

import boringbar as bb
from boringbar.cli.main import main
from boringbar.orbits import cut_branch as cb
from boringbar.orbits import cut_orbits as co
from boringbar.orbits.cut_return import follow
from boringbar.reference.stability import limit_at_speeds
from boringbar.simulate import CutStepper

CARBIDE = "examples/systems/carbide_ld10_tungsten.toml"


@pytest.fixture(scope="module")
def bars():
    v = bb.variants(bb.load_system(CARBIDE))
    return {"solid": v["solid"], "ball": v["ball"], "tmd": bb.make_system("tmd", "physical"),
            "ball-free": bb.make_system("ball", "physical", gap_m=0.1e-3, friction=False)}


def _hopf(system, rpm, steps=co.STEPS, **cut):
    forcing = bb.Regenerative(depth_m=1e-5, rpm=rpm, **cut)
    model = co.cut_model(system, forcing)
    return model, cb.hopf_orbit(system, forcing, model, None, steps)


@pytest.mark.parametrize("bar, rpm", [("solid", 700.0), ("solid", 1200.0), ("solid", 4321.0),
                                      ("tmd", 900.0), ("tmd", 2600.0)])
def test_the_hopf_point_meets_the_characteristic_equation(bars, bar, rpm):
    system = bars[bar]
    model, o = _hopf(system, rpm)
    b, f = limit_at_speeds(system, rpm, model.law.kr_pa, with_frequency=True)
    assert o.depth == pytest.approx(float(b), rel=1e-6)
    assert 1.0 / o.period == pytest.approx(float(f), rel=1e-6)


def test_the_hopf_point_converges_at_fourth_order(bars):
    system, rpm = bars["solid"], 1200.0
    b, _ = limit_at_speeds(system, rpm, 850e6, with_frequency=True)
    err = [abs(_hopf(system, rpm, m)[1].depth / float(b) - 1.0) for m in (80, 160, 320)]
    orders = np.log2(np.array(err[:-1]) / np.array(err[1:]))
    assert np.all((orders > 3.7) & (orders < 4.5)), (err, orders)


def test_the_jacobian_matches_central_differences(bars):
    model, o = _hopf(bars["tmd"], 1500.0, steps=60)
    o = replace(o, x=o.x + 1e-7 * np.sin(np.arange(o.x.size)).reshape(o.x.shape))
    jac = co.jacobian(model, o).toarray()
    y = o.unknowns()
    for col in (0, 3, 7, y.size // 2 + 1, y.size - 3, y.size - 2, y.size - 1):
        h = 1e-6 * max(abs(y[col]), 1e-9)
        up, down = y.copy(), y.copy()
        up[col] += h
        down[col] -= h
        fd = (co.residual(model, o.at(up)) - co.residual(model, o.at(down))) / (2 * h)
        # the nodes' columns are exact (forward mode); T's and b's are differences too
        tol = 1e-6 if col < y.size - 2 else 1e-4
        assert np.max(np.abs(fd - jac[:, col])) <= tol * np.max(np.abs(fd)), col


@pytest.fixture(scope="module")
def linear_branch(bars):
    forcing = bb.Regenerative(depth_m=1e-5, rpm=1200.0)
    return cb.trace(bars["solid"], forcing, (0.0, 1e-3), max_points=16)


def test_a_linear_law_branch_stands_vertical_until_the_tool_leaves_the_cut(linear_branch):
    hopf = linear_branch.events[0]
    leave = [e for e in linear_branch.events if e.detail == "tool-leaves-cut"]
    assert hopf.kind == "hopf" and len(leave) == 1
    in_cut = [p for p in linear_branch.points if p.min_chip > 1e-9]  # the grazing one aside
    assert len(in_cut) >= 5
    for p in in_cut:
        assert p.orbit.depth == pytest.approx(hopf.depth, rel=1e-9)
        assert np.abs(cb.nontrivial(p.multipliers)).max() == pytest.approx(1.0, abs=1e-6)
    w = 2.0 * math.pi * leave[0].frequency_hz
    closed = 0.1e-3 / (2.0 * abs(math.sin(w * 60.0 / 1200.0 / 2.0)))
    assert leave[0].amplitude == pytest.approx(closed, rel=1e-6)
    assert leave[0].depth == pytest.approx(hopf.depth, rel=1e-9)
    assert not [e for e in linear_branch.events if e.kind == "fold"]


@pytest.mark.parametrize("bar, rpm, scale", [("solid", 1200.0, 1.0), ("solid", 3000.0, 1.3),
                                             ("tmd", 6000.0, 0.95)])
def test_in_speed_the_hopf_point_is_where_the_lobes_cross_the_depth(bars, bar, rpm, scale):
    """At a fixed depth the Hopf point in speed sits where the frequency-domain limit
    equals that depth, at its chatter frequency, each to 1e-6."""
    system = bars[bar]
    depth = scale * float(limit_at_speeds(system, rpm, 850e6))
    forcing = bb.Regenerative(depth_m=depth, rpm=rpm)
    model = co.cut_model(system, forcing)
    o = cb.speed_hopf_orbit(system, forcing, model, (0.5 * rpm, 2.0 * rpm), None)
    assert o.free == "tau" and o.depth == depth
    b, f = limit_at_speeds(system, o.rpm, 850e6, with_frequency=True)
    assert float(b) == pytest.approx(depth, rel=1e-6)
    assert 1.0 / o.period == pytest.approx(float(f), rel=1e-6)


def test_the_jacobian_in_the_delay_matches_central_differences(bars):
    model, o = _hopf(bars["solid"], 1500.0, steps=60)
    o = replace(o, free="tau")
    jac = co.jacobian(model, o).toarray()
    y = o.unknowns()
    h = 1e-6 * y[-1]
    fd = (co.residual(model, o.at(y + h * np.eye(y.size)[-1]))
          - co.residual(model, o.at(y - h * np.eye(y.size)[-1]))) / (2 * h)
    assert np.max(np.abs(fd - jac[:, -1])) <= 1e-4 * np.max(np.abs(fd))
    assert np.max(np.abs(fd)) > 0


@pytest.fixture(scope="module")
def speed_branch(bars):
    """The solid bar's branch in speed at its limit at 1200 rpm (one revolution of
    memory): from the lobe's left flank's Hopf point to its right flank's."""
    depth = float(limit_at_speeds(bars["solid"], 1200.0, 850e6))
    forcing = bb.Regenerative(depth_m=depth, rpm=1150.0, revolutions=1)
    return cb.trace(bars["solid"], forcing, (1000.0, 1400.0), free="tau"), depth


def test_in_speed_a_linear_law_branch_joins_the_lobe_s_two_flanks(bars, speed_branch):
    """In the cut the branch stands vertical at each flank's Hopf speed; the tool leaves
    the cut at h_m / (2 |sin(w tau / 2)|) there; between, the clipped chip's describing
    function holds: b N(a) is the frequency-domain limit at the orbit's speed and the
    orbit's frequency its chatter frequency."""
    br, depth = speed_branch
    hopf = [e for e in br.events if e.kind == "hopf"]
    leave = [e for e in br.events if e.detail == "tool-leaves-cut"]
    assert len(hopf) == 2 and len(leave) == 2 and "second Hopf" in br.stop
    assert hopf[0].rpm < 1200.0 and hopf[1].rpm == pytest.approx(1200.0, rel=1e-6)
    for h, g in zip(hopf, leave, strict=True):
        assert float(limit_at_speeds(bars["solid"], h.rpm, 850e6)) == pytest.approx(depth,
                                                                                 rel=1e-6)
        w = 2.0 * math.pi * g.frequency_hz
        closed = 0.1e-3 / (2.0 * abs(math.sin(w * 60.0 / g.rpm / 2.0)))
        assert g.amplitude == pytest.approx(closed, rel=1e-6)
        assert g.rpm == pytest.approx(h.rpm, rel=1e-9)
    in_cut = [p for p in br.points if p.min_chip > 1e-9]
    assert all(min(abs(p.orbit.rpm / h.rpm - 1) for h in hopf) < 1e-9 for p in in_cut)
    out = [p for p in br.points if p.min_chip < 0]
    assert len(out) >= 10 and max(p.orbit.rpm for p in out) > hopf[0].rpm + 10.0
    for p in out:
        w, tau = 2.0 * math.pi / p.orbit.period, 60.0 / p.orbit.rpm
        beta = math.asin(0.1e-3 / (2.0 * p.amplitude * abs(math.sin(w * tau / 2.0))))
        gain = (math.pi / 2 + beta + math.sin(beta) * math.cos(beta)) / math.pi
        b, f = limit_at_speeds(bars["solid"], p.orbit.rpm, 850e6, with_frequency=True)
        assert depth * gain == pytest.approx(float(b), rel=1e-3)
        assert 1.0 / p.orbit.period == pytest.approx(float(f), rel=1e-6)


def characteristic_roots(system, depth: float, rpm: float, kr: float) -> list:
    """Roots (upper half-plane) of a one-mode bar's cut in the cut, m s^2 + c s + k +
    psi^2 Kr b (1 - exp(-s tau)) = 0: Newton's method from starts over 0.2-3 times the
    natural frequency, on the imaginary axis and left of it."""
    bar = system.bar
    m, c, k = bar.mass_kg[0], bar.damping_n_s_m[0], bar.stiffness_n_m[0]
    kb, tau = bar.psi_tip[0] ** 2 * kr * depth, 60.0 / rpm

    def f(s):
        return m * s * s + c * s + k + kb * (1 - cmath.exp(-s * tau))

    def df(s):
        return 2 * m * s + c + kb * tau * cmath.exp(-s * tau)

    roots = []
    for w in np.linspace(0.2, 3.0, 300) * bar.natural_frequency_rad_s:
        for sr in (0.0, -50.0):
            s = complex(sr, w)
            try:
                for _ in range(100):
                    s -= f(s) / df(s)
            except (OverflowError, ZeroDivisionError):
                continue
            if abs(f(s)) < 1e-9 * k and s.imag > 0 and all(abs(s - r) > 1e-6 * abs(s)
                                                           for r in roots):
                roots.append(s)
    return roots


def test_in_the_cut_the_multipliers_are_the_characteristic_roots_over_a_period():
    """In the cut a linear law's orbit is a solution of a linear delay equation, whose
    monodromy over the orbit's period T has the multipliers exp(lambda T) of the
    characteristic roots lambda (the Hopf pair's two at 1)."""
    system = bb.make_system("solid", n_modes=1)
    forcing = bb.Regenerative(depth_m=1e-5, rpm=1200.0)
    p = cb.trace(system, forcing, (0.0, 1e-2), max_points=3).points[1]
    assert p.min_chip > 0
    mu = co.multipliers(co.cut_model(system, forcing), p.orbit, count=8)
    lam = characteristic_roots(system, p.orbit.depth, 1200.0, forcing.kr_pa)
    ref = np.array([cmath.exp(r * p.orbit.period) for r in lam])
    ref = np.concatenate([ref, ref.conj()])
    ref = ref[np.argsort(-np.abs(ref))][:8]
    # each root's exp(lambda T) among the multipliers, and the same count (a pair's two
    # members have equal real parts, so an ordering by them is round-off's)
    assert len(mu) == len(ref)
    assert max(np.min(np.abs(mu - r)) for r in ref) < 1e-6
    assert max(np.min(np.abs(ref - m)) for m in mu) < 1e-6


def test_a_torus_point_takes_a_whole_complex_pair_out_of_the_unit_circle():
    """The published solid bar at 1200 rpm loses its bounded chatter's stability at
    Neimark-Sacker points.  Multipliers come in conjugate pairs, so the number outside
    the unit circle is even all along (no real one leaves there), and the phase shift's
    multiplier, near 1, is never counted; the first pair passes 1 + 2e-4 (the band of a
    clipped chip's orbit) at 0.1392 mm."""
    system = bb.make_system("solid", "physical")
    br = cb.trace(system, bb.Regenerative(depth_m=1e-5, rpm=1200.0), (0.0, 1e-3),
                  max_points=50)
    ns = [e for e in br.events if e.kind == "neimark-sacker"]
    assert ns and ns[0].depth == pytest.approx(0.1392e-3, rel=2e-3)
    for p in br.points:
        assert p.unstable % 2 == 0
        mu = p.multipliers[np.abs(p.multipliers.imag) > 1e-9 * np.abs(p.multipliers)]
        assert all(np.min(np.abs(mu - np.conj(m))) < 1e-8 for m in mu)


@pytest.mark.slow
def test_a_tmd_bar_s_neutral_surface_modes_are_not_read_as_tori():
    """Beyond the tool's leaving, the published TMD bar at 500 rpm has multipliers on the
    unit circle (the surface left uncut, carried on) that the clipped chip's
    discretisation scatters by about 1e-4 from orbit to orbit: within the clipped band
    they are not counted, where a band of 1e-6 read dozens of Neimark-Sacker points."""
    br = cb.trace(bb.make_system("tmd", "physical"), bb.Regenerative(depth_m=1e-5, rpm=500.0),
                  (0.0, 5e-3), max_points=75)
    beyond = [p for p in br.points if p.min_chip < 0]
    assert len(beyond) > 50 and beyond[-1].orbit.depth > 1.7e-3
    near = [m for p in beyond for m in cb.nontrivial(p.multipliers)
            if 0 < abs(m) - 1 < cb.CLIPPED]
    assert near  # the scatter is there ...
    assert all(p.unstable == 0 for p in beyond)  # ... and not counted
    assert not [e for e in br.events if e.kind == "neimark-sacker"]


@pytest.fixture(scope="module")
def one_revolution(bars):
    """The solid bar's branch with one revolution of memory (30 points, through the
    tool's leaving the cut) and its cut."""
    forcing = bb.Regenerative(depth_m=1e-5, rpm=1200.0, revolutions=1)
    return cb.trace(bars["solid"], forcing, (0.0, 1e-3), max_points=30), forcing


def test_beyond_leaving_the_branch_follows_the_clipped_chip_describing_function(one_revolution):
    br, _ = one_revolution
    hopf = br.events[0].depth
    leave = next(e for e in br.events if e.detail == "tool-leaves-cut")
    half_sin = 0.1e-3 / (2.0 * leave.amplitude)
    out = [p for p in br.points if p.min_chip < 0]
    assert len(out) >= 10 and out[-1].amplitude > 2 * leave.amplitude
    for p in out:
        beta = math.asin(0.1e-3 / (2.0 * p.amplitude * half_sin))
        gain = (math.pi / 2 + beta + math.sin(beta) * math.cos(beta)) / math.pi
        assert p.orbit.depth == pytest.approx(hopf / gain, rel=1e-3)
        assert p.unstable == 0  # the clipped chip bounds the chatter: stable orbits


@pytest.mark.parametrize("index", [-8, -20])
def test_a_stable_orbit_draws_a_knocked_cut_back_at_its_multiplier_s_rate(bars, one_revolution,
                                                                          index):
    """The return check: the compiled RK4 cut started on a stable orbit with the orbit's
    own history stays on it (within the two discretisations' difference), and knocked 1 %
    off it comes back, its departure shrinking each period by the orbit's largest
    nontrivial multiplier."""
    br, forcing = one_revolution
    p = br.points[index]
    assert p.unstable == 0 and p.min_chip < 0
    on = follow(bars["solid"], forcing, p.orbit, 1200)
    assert np.max(np.abs(on - p.amplitude)) < 1e-4 * p.amplitude
    off = follow(bars["solid"], forcing, p.orbit, 1200, knock=0.01)
    dev = np.abs(off - on) / p.amplitude
    assert dev[0] > 5e-3 and dev[-1] < 1e-5
    k = 4 * np.arange(1, len(dev) + 1)  # periods, four a window
    keep = (k > 100) & (dev > 1e-7)
    rate = np.polyfit(k[keep], np.log(dev[keep]), 1)[0]
    mu = np.abs(cb.nontrivial(p.multipliers)).max()
    assert rate == pytest.approx(math.log(mu), rel=0.03)


def test_a_stable_tmd_orbit_holds_a_cut_started_on_it(bars):
    """The return check on a TMD bar (the absorber's displacement is the kernel's
    auxiliary coordinate): the compiled cut started on a stable orbit beyond the tool's
    leaving stays on it, and knocked 1 % off it comes back.  (Its return mixes several
    multipliers of nearly equal modulus, the slowest a complex pair, so its rate is not
    compared with one.)"""
    system = bars["tmd"]
    forcing = bb.Regenerative(depth_m=1e-5, rpm=1200.0, revolutions=1)
    p = cb.trace(system, forcing, (0.0, 5e-3), max_points=30).points[-8]
    assert p.unstable == 0 and p.min_chip < 0
    on = follow(system, forcing, p.orbit, 1200)
    assert np.max(np.abs(on - p.amplitude)) < 1e-4 * p.amplitude
    off = follow(system, forcing, p.orbit, 1200, knock=0.01)
    dev = np.abs(off - on) / p.amplitude
    assert dev[0] > 5e-3 and dev[-1] < 1e-5


def test_a_stable_orbit_is_where_a_simulated_cut_settles(bars):
    """The compiled RK4 cut, knocked from the steady cut to about the orbit's amplitude,
    settles on the branch's amplitude at that depth."""
    forcing = bb.Regenerative(depth_m=1e-5, rpm=1200.0, revolutions=1)
    br = cb.trace(bars["solid"], forcing, (0.0, 1e-3), max_points=30)
    p = br.points[-8]
    assert p.unstable == 0 and p.min_chip < 0
    cut = bb.Regenerative(depth_m=p.orbit.depth, rpm=1200.0, revolutions=1, start="static")
    # the orbit's slowest multiplier is about 0.995 a period: 8 s (2000 periods) settle it
    run = bb.simulate(bars["solid"], cut, duration_s=8.0, dt_s=2e-6,
                      initial=bb.Initial(tip_displacement_m=p.amplitude), record_every=5)
    w = run.to_xarray()["tip_displacement_m"].values
    tail = w[-len(w) // 16:]
    assert 0.5 * (tail.max() - tail.min()) == pytest.approx(p.amplitude, rel=2e-3)


def test_a_friction_ball_leaves_its_host_where_it_first_slips(bars):
    forcing = bb.Regenerative(depth_m=1e-5, rpm=1200.0)
    br = cb.trace(bars["ball"], forcing, (0.0, 1e-3), max_points=10)
    slip = [e for e in br.events if e.detail == "ball-slips"]
    assert len(slip) == 1 and "slips" in br.stop
    ball, bar = bars["ball"].damper, bars["ball"].bar
    # in the cut the orbit is a harmonic: the cavity's acceleration peaks at w^2 times its
    # amplitude, which is the tip's times |psi_d . u| / |psi_tip . u| of the mode shape
    model = co.cut_model(bars["ball"], forcing)
    o, _ = cb.fixed_amplitude(model, cb.hopf_orbit(bars["ball"], forcing, model, None),
                              slip[0].amplitude)
    w = 2 * math.pi * slip[0].frequency_hz
    n = bar.n_modes
    u = o.x[:, :n] @ bar.psi_damper
    assert 0.5 * (u.max() - u.min()) * w**2 == pytest.approx(
        ball.friction_force_n / ball.mass_kg, rel=1e-3)


def test_a_frictionless_ball_branch_ends_where_the_ball_reaches_a_wall(bars):
    system = bars["ball-free"]
    br = cb.trace(system, bb.Regenerative(depth_m=1e-5, rpm=1500.0), (0.0, 1e-3),
                  max_points=40)
    wall = [e for e in br.events if e.detail == "ball-wall"]
    assert len(wall) == 1 and "wall" in br.stop
    last = br.points[-1]
    assert abs(last.ball_margin) < 0.2  # the last point is the step past the wall


def test_continue_cut_writes_the_map_of_each_bar(tmp_path, capsys):
    """The command line end to end on the published bar: the files, and each bar's Hopf
    point in the JSON (mm) at its frequency-domain limit."""
    out = tmp_path / "map"
    rc = main(["continue", "--cut", "--rpm", "1500", "--parameter", "depth-mm", "--range",
               "0:1", "--bar", "solid", "--bar", "tmd", "--max-points", "6", "--json",
               "--out", str(out)])
    assert rc == 0
    summary = json.loads(capsys.readouterr().out)
    for name in ("chatter_orbits.nc", "chatter_orbits.json", "chatter_orbits.png"):
        assert (out / name).stat().st_size > 0
    assert [c["case"] for c in summary["cases"]] == ["solid", "tmd"]
    for c in summary["cases"]:
        hopf = c["events"][0]
        assert hopf["kind"] == "hopf" and c["points"] >= 6
        b = limit_at_speeds(bb.make_system(c["case"], "physical"), 1500.0, 850e6)
        assert hopf["depth_mm"] == pytest.approx(float(b) * 1e3, rel=1e-6)
    assert "RK4" in summary["method"]
    with xr.open_dataset(out / "chatter_orbits.nc") as ds:
        assert ds.attrs["preset"] == "physical"  # each file says what it is


def test_continue_cut_in_speed_writes_the_map_and_refuses_a_range_without_a_crossing(
        tmp_path, capsys):
    out = tmp_path / "speed"
    base = ["continue", "--cut", "--parameter", "rpm", "--bar", "solid", "--revolutions",
            "1", "--max-points", "8", "--json"]
    depth = float(limit_at_speeds(bb.make_system("solid", "physical"), 1500.0, 850e6)) * 1.2
    rc = main([*base, "--depth-mm", f"{depth * 1e3:.9g}", "--range", "1300:1700", "--rpm",
               "1500", "--out", str(out)])
    assert rc == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["parameter"] == "rpm" and summary["depth_mm"] == pytest.approx(depth * 1e3)
    hopf = summary["cases"][0]["events"][0]
    b = limit_at_speeds(bb.make_system("solid", "physical"), hopf["rpm"], 850e6)
    assert hopf["kind"] == "hopf" and float(b) == pytest.approx(depth, rel=1e-6)
    assert len(set(summary["cases"][0]["depth_mm"])) == 1
    assert "in speed" in summary["method"]
    with xr.open_dataset(out / "chatter_orbits.nc") as ds:
        assert ds.attrs["parameter"] == "rpm" and ds["rpm"].size >= 8
    empty = tmp_path / "none"
    rc = main([*base, "--depth-mm", "1e-4", "--range", "1300:1700", "--out", str(empty)])
    assert rc == 2 and not empty.exists()
    err = capsys.readouterr().err.strip()
    assert "crosses the depth" in err and "\n" not in err
    rc = main(["continue", "--cut", "--bar", "solid", "--rpm", "1200", "--range", "0:0.01",
               "--out", str(empty)])
    assert rc == 2 and not empty.exists()
    assert "outside the depth range" in capsys.readouterr().err


def test_the_return_check_refuses_what_it_cannot_start(bars, one_revolution):
    br, forcing = one_revolution
    o = br.points[-8].orbit
    with pytest.raises(bb.ParameterError, match="solid or TMD"):
        follow(bars["ball"], forcing, o, 10)
    with pytest.raises(bb.ParameterError, match="periods"):
        follow(bars["solid"], forcing, o, 0)
    cut = bb.Regenerative(depth_m=o.depth, rpm=1200.0, revolutions=1, start="static")
    stepper = CutStepper(bars["solid"], cut, dt_s=1e-6, window_steps=100)
    with pytest.raises(bb.ParameterError, match="x must be"):
        stepper.start_from(np.zeros(3), lambda t: (0 * t, 0 * t))
    with pytest.raises(bb.ParameterError, match="finite"):
        stepper.start_from(np.zeros(6), lambda t: (0 * t, np.nan))
    stepper.advance()
    with pytest.raises(bb.ParameterError, match="already run"):
        stepper.start_from(np.zeros(6), lambda t: (0 * t, 0 * t))


def test_a_branch_s_dense_factorisations_run_on_one_blas_thread(monkeypatch):
    """The correctors factorise up to 1700 unknowns densely: OpenBLAS's second thread gains
    nothing there and spins a core that the other step of a study, or the user, needs."""
    from threadpoolctl import threadpool_info

    seen = []
    real = co.scipy.linalg.lu_factor

    def recording(*args, **kwargs):
        seen.append({i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"})
        return real(*args, **kwargs)

    monkeypatch.setattr(co.scipy.linalg, "lu_factor", recording)
    solid = bb.make_system("solid")
    cb.trace(solid, bb.Regenerative(depth_m=1e-5, rpm=1200.0), (0.0, 1e-3), max_points=3)
    assert seen and all(s == {1} for s in seen), seen

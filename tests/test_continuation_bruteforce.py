"""Continuation against brute force: where the exact integrator's forward and backward
sweeps (``bb.bifurcation``) settle on the same period-1 orbit, the continued branch is
that orbit to 1e-8 relative; where they disagree, the branch's stability change bounds
the range of agreement."""

import dataclasses
import json

import numpy as np
import xarray as xr

import boringbar as bb
from boringbar.analysis.continuation import ContinuationOptions, start_state
from boringbar.cli.main import main
from boringbar.model.forcing import Harmonic
from boringbar.model.system import make_system
from boringbar.orbits import shooting as sh
from boringbar.orbits.branch import flow_with
from boringbar.orbits.continuation import continue_branch, switch_period_doubling
from boringbar.reference.masri_caughey import ImpactSystem, phase_equation, two_impact_orbit
from boringbar.simulate import Integration, State, simulate


def _one_mode_case():
    """The one-mode physical bar, frictionless ball, gap 0.5 mm, ratio 1: brute force
    from rest settles on the symmetric two-impact orbit above ~30 N."""
    return make_system("ball", "physical", gap_m=0.5e-3, friction=False, n_modes=1)


def _sweep(system, values, duration_s=1.0):
    """Forward and backward exact sweeps, the last 20 % of each run sampled."""
    return bb.bifurcation(system, bb.BifurcationOptions("force", tuple(values), values[0], 1.0),
                          integration=Integration(duration_s, 1e-6, "exact", 0.2))


def _branch_at(fl, br, value):
    """The branch's orbit at exactly ``value``: Newton from the nearest branch point."""
    near = min(br.points, key=lambda p: abs(p.value - value))
    return sh.periodic_orbit(flow_with(fl, "force-n", value, fl), near.x)


def test_stable_branch_is_the_brute_force_orbit_where_both_sweeps_agree():
    system = _one_mode_case()
    values = (31.0, 33.0, 35.0)
    ds = _sweep(system, values)
    fl = sh.make_flow(system, Harmonic(values[0], ratio=1.0))
    x0 = start_state(system, ContinuationOptions(force_n=values[0], start="masri-caughey"), fl)
    br = continue_branch(fl, "force-n", x0, 35.5, step=0.2, max_points=40, max_step=0.3)
    assert br.stop.startswith("end of range"), br.stop
    agreed = 0
    for j, v in enumerate(values):
        sides = [ds.sel(direction=d).isel(value=j) for d in ("forward", "backward")]
        if not all(int(s["period"]) == 1 for s in sides):
            continue
        x, pr = _branch_at(fl, br, v)
        assert np.all(np.abs(sh.multipliers(pr)) < 1.0)
        w = fl.psi_tip @ x[:fl.n]
        for s in sides:
            samples = s["tip_displacement_m"].values
            samples = samples[np.isfinite(samples)]
            assert len(samples) > 50
            assert np.max(np.abs(samples - w)) <= 1e-8 * abs(w), (v, samples[-1], w)
        agreed += 1
    assert agreed >= 2


def _three_impact_orbit(ratio=0.97, phase=np.pi):
    """The asymmetric three-impact period-1 orbit at F0 = 30 N (one mode, gap 0.5 mm): the
    exact integrator from the two-impact orbit at ratio 0.98, 500.5 periods, so the state
    is at forcing phase pi.  Which of the orbit's two mirror images (+ + - or + - - from the
    section) the transient ends on is decided at round-off level (a 1e-12 relative change
    of the start flips it): one has an impact 0.007 rad after pi, and the branch moves its
    section; callers read each point's own section phase (Point.phase)."""
    system = _one_mode_case()
    fl = sh.make_flow(system, Harmonic(30.0, ratio=ratio))
    x98 = start_state(system, ContinuationOptions(force_n=30.0, ratio=0.98,
                                                  start="masri-caughey"), fl)
    run = simulate(system, Harmonic(30.0, ratio=ratio),
                   duration_s=(500 + phase / (2 * np.pi)) * fl.period, dt_s=fl.period / 4000,
                   integrator="exact", initial=State(x98, 0.0))
    return system, dataclasses.replace(fl, phase=phase), run.final.x


def test_branch_switching_at_period_doubling_gives_a_period_two_orbit():
    system, fl, x0 = _three_impact_orbit()
    br = continue_branch(fl, "ratio", x0, 0.969, step=0.05, max_points=12, max_step=0.1)
    assert [k for k, _ in br.events] == ["period-doubling"], (br.stop, br.events)
    two = switch_period_doubling(fl, "ratio", br, 0.975, step=0.002, max_points=6)
    p_pd = two.origin.value
    assert two.periods == 2 and two.events[0] == ("period-doubling", p_pd)
    assert np.min(np.abs(two.origin.multipliers + 1.0)) < 1e-8  # located: a -1 multiplier
    assert len(two.points) == 6
    gaps = []
    for pt in two.points:
        # on the point's own section: the period-1 branch may have moved it off pi
        f = flow_with(dataclasses.replace(fl, phase=pt.phase), "ratio", pt.value, fl)
        once, twice = sh.advance(f, pt.x).x, sh.advance(f, pt.x, 2).x
        size = np.max(np.abs(pt.x))
        assert np.max(np.abs(twice - pt.x)) <= 1e-10 * size  # P^2 x = x
        gaps.append(np.max(np.abs(once - pt.x)) / size)
        # the exact kernel agrees: back after two periods, elsewhere after one
        run = simulate(system, Harmonic(30.0, ratio=pt.value), duration_s=2 * f.period,
                       dt_s=f.period / 4000, integrator="exact",
                       initial=State(pt.x, f.phase / f.omega), steady_fraction=1.0)
        assert np.max(np.abs(run.final.x - pt.x)) <= 1e-8 * size
    assert min(gaps) > 1e-3  # P x != x: a genuine period-2 orbit
    # it emanates from the doubling (a pitchfork of P^2): with the first step halved the
    # first orbit's distance from the period-1 orbit halves, its parameter's from the
    # doubling point is quartered
    near = [switch_period_doubling(fl, "ratio", br, 0.975, step=s, max_points=1).points[0]
            for s in (0.001, 0.0005)]
    sep = [np.max(np.abs(sh.advance(flow_with(dataclasses.replace(fl, phase=q.phase), "ratio",
                                              q.value, fl), q.x).x - q.x))
           for q in near]
    assert 1.8 < sep[0] / sep[1] < 2.2
    assert 3.5 < (near[0].value - p_pd) / (near[1].value - p_pd) < 4.5
    assert near[1].value < p_pd  # a supercritical doubling: towards the unstable side


def _closed_form_phase(system, fl, force):
    """The + wall impact's forcing phase of the admissible two-impact orbit (closed form)."""
    bar, ball = system.bar, system.damper
    return next(o.phase for o in two_impact_orbit(
        bar.mass_kg[0], bar.stiffness_n_m[0], bar.damping_n_s_m[0],
        bar.psi_tip[0], bar.psi_damper[0],
        ball.mass_kg, ball.gap_m, ball.restitution, force, fl.omega) if o.admissible)


def test_a_change_of_the_event_sequence_is_located_where_the_closed_form_puts_it():
    # the section at the phase of the closed-form + wall impact at 33 N: continued from
    # 30 N, the impact crosses the section (the sequence (+, -) becomes (-, +)) at 33 N
    system = _one_mode_case()
    fl = sh.make_flow(system, Harmonic(30.0, ratio=1.0))
    phase = _closed_form_phase(system, fl, 33.0)
    x0 = start_state(system, ContinuationOptions(force_n=30.0, start="masri-caughey"), fl)
    run = simulate(system, Harmonic(30.0, ratio=1.0), duration_s=fl.period * phase / (2 * np.pi),
                   dt_s=fl.period / 20000, integrator="exact", initial=State(x0, 0.0),
                   steady_fraction=1.0)
    br = continue_branch(dataclasses.replace(fl, phase=phase), "force-n", run.final.x, 36.0,
                         step=0.1, max_points=40, max_step=0.3, move_section=False)
    assert [k for k, _ in br.events] == ["section"], (br.stop, br.events)
    located = br.events[0][1]
    assert br.points[-1].value == located and located < 33.0
    assert abs(located - 33.0) < 1e-6 * 33.0, located


def test_the_section_moves_away_from_an_impact_and_the_branch_goes_on():
    """The same branch with the section moving (the default): the impact never reaches
    the section, the branch reaches the end of its range, and every point, carried to
    phase 0, is the closed-form two-impact orbit at its F0 (1e-8 relative)."""
    system = _one_mode_case()
    fl = sh.make_flow(system, Harmonic(30.0, ratio=1.0))
    phase = _closed_form_phase(system, fl, 33.0)
    fl = dataclasses.replace(fl, phase=phase)
    x0 = _orbit_state(_closed_form(system, 1.0, 30.0)[1], phase)
    br = continue_branch(fl, "force-n", x0, 36.0, step=0.1, max_points=40, max_step=0.3)
    assert br.stop.startswith("end of range") and br.events == [], (br.stop, br.events)
    assert br.section_moves >= 1 and {p.phase for p in br.points} != {phase}
    for pt in br.points[1:]:
        at = flow_with(dataclasses.replace(fl, phase=pt.phase), "force-n", pt.value, fl)
        x = sh.carry(at, pt.x, 0.0)
        orbit = next(o for o in two_impact_orbit(
            *dataclasses.astuple(_closed_form(system, 1.0, pt.value)[0])) if o.admissible)
        ref = _orbit_state(orbit, 0.0)
        assert np.max(np.abs(x - ref)) <= 1e-8 * np.max(np.abs(ref)), (pt.value, x, ref)


def test_cli_overlay_draws_the_brute_force_diagram_of_the_same_case(tmp_path, capsys):
    argv = ["continue", "--preset", "physical", "--gap-mm", "0.5", "--friction", "off",
            "--modes", "1", "--range", "31:30", "--start-from", "masri-caughey",
            "--max-points", "3", "--integrator", "exact", "--duration-s", "0.2",
            "--out", str(tmp_path), "--json"]
    assert main([*argv, "--overlay", "3"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["files"]["overlay"] == str(tmp_path / "overlay.nc")
    with xr.open_dataset(tmp_path / "overlay.nc") as bf:
        assert bf["value"].values.tolist() == [31.0, 30.5, 30.0]
        assert bf.sizes["direction"] == 2
        # the sweep's strobe samples at 31 N sit on the branch's first point
        w = bf["tip_displacement_m"].sel(direction="forward").isel(value=0).values
        w = w[np.isfinite(w)]
    assert abs(w[-1] - out["branches"][0]["points"][0]["strobe_tip_m"]) < 1e-3 * abs(w[-1])
    assert (tmp_path / "continuation.png").stat().st_size > 0
    assert main([*argv[:-3], "--parameter", "restitution", "--range", "0.7:0.6",
                 "--overlay", "--out", str(tmp_path)]) == 2
    assert main([*argv, "--overlay", "1"]) == 2


def _small_gap_case():
    """One mode, frictionless ball, gap 0.1 mm, e = 0.7, F0 = 10 N, swept in the ratio."""
    return make_system("ball", "physical", gap_m=0.1e-3, friction=False, n_modes=1,
                       restitution=0.7)


def _closed_form(system, ratio, force=10.0):
    """The ImpactSystem of the case and its stable admissible two-impact orbit (or None)."""
    bar, ball = system.bar, system.damper
    args = (bar.mass_kg[0], bar.stiffness_n_m[0], bar.damping_n_s_m[0], bar.psi_tip[0],
            bar.psi_damper[0],
            ball.mass_kg, ball.gap_m, ball.restitution, force,
            ratio * system.reference_frequency_rad_s)
    orbits = [o for o in two_impact_orbit(*args) if o.admissible and o.stable]
    return ImpactSystem(*args), (orbits[0] if orbits else None)


def _orbit_state(orbit, phase):
    """(u, u', y, y') of a closed-form orbit at forcing phase ``phase``."""
    t, h = phase / orbit.system.omega, 1e-9
    dy = (orbit.relative_displacement(t + h) - orbit.relative_displacement(t - h)) / (2 * h)
    return np.array([float(orbit.modal_displacement(t)), float(orbit.modal_velocity(t)),
                     float(orbit.relative_displacement(t)), float(dy)])


def _bisect(f, lo, hi, tol=1e-15):
    """The sign change of f in [lo, hi]."""
    flo = f(lo) > 0
    while hi - lo > tol * hi:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if (f(mid) > 0) == flo else (lo, mid)
    return 0.5 * (lo + hi)


def test_the_coexistence_range_is_bounded_by_the_fold_and_the_linear_grazing():
    """Gap 0.1 mm, F0 = 10 N, ratio 0.60 -> 0.98 and back (exact, 0.5 s runs).  Forward
    from rest the ball never hits: the bar's motion is linear and y = -psi_d u, whose
    amplitude psi_d psi_L F0 / |K - M Omega^2 + i C Omega| reaches delta/2 at the ratio
    r_g (closed form).  Backward, the sweep rides the stable symmetric two-impact orbit
    down to where it dies at a fold: the two roots of the Masri-Caughey phase equation
    a cos phi + b sin phi = delta merge where sqrt(a^2 + b^2) = delta, at r_f (closed
    form).  So the two attractors coexist on [r_f, r_g], and the sweeps' jumps must
    bracket both values; continuation must find a fold at r_f (1e-9 relative) and no
    other stability change above it, and its stable branch must be the backward sweep's
    orbit (1e-8 relative).  The other end of the range is not a fold: the orbit without
    impacts is not isolated (the free ball's position is neutral), so shooting cannot
    follow it (docs/continuation.md)."""
    system = _small_gap_case()
    r_f, r_g = _fold_and_linear_grazing(system)
    values = tuple(np.round(np.arange(0.60, 0.985, 0.01), 2))
    ds = bb.bifurcation(system, bb.BifurcationOptions("ratio", values, 10.0, 1.0),
                        integration=Integration(0.5, 1e-6, "exact", 0.2))
    impacts = {d: ds["impacts_per_cycle"].sel(direction=d).values for d in ("forward", "backward")}
    period = {d: ds["period"].sel(direction=d).values for d in ("forward", "backward")}
    v = np.asarray(values)
    # forward: no impact below r_g, impacts above
    assert np.all(impacts["forward"][v < r_g] == 0) and np.all(impacts["forward"][v > r_g] > 0)
    # backward: the period-1 two-impact orbit from 0.92 down to r_f, not below
    two = (period["backward"] == 1) & (np.round(impacts["backward"]) == 2)
    assert np.all(two[(v > r_f) & (v <= 0.92)]) and not np.any(two[v < r_f])
    assert 0.62 < r_f < 0.63 and 0.96 < r_g < 0.97  # where the brute force jumped
    # continuation from the closed form at 0.8 (section at phase 1.6, off the impacts)
    fl = sh.make_flow(system, Harmonic(10.0, ratio=0.8))
    fl = dataclasses.replace(fl, phase=1.6)
    x0 = _orbit_state(_closed_form(system, 0.8)[1], 1.6)
    br = continue_branch(fl, "ratio", x0, 0.55, step=0.05, max_points=40)
    changes = [(k, p) for k, p in br.events if k != "grazing"]
    assert changes[0][0] == "fold" and abs(changes[0][1] - r_f) <= 1e-9 * r_f, br.events
    turn = int(np.argmin([p.value for p in br.points]))  # the point nearest the fold
    assert all(p.stable for p in br.points[:turn]) and not br.points[-1].stable
    assert br.points[-1].value > br.points[turn].value >= r_f * (1 - 1e-12)
    # the stable symmetric branch (from phase 0, 0.88 down to 0.64; it loses its
    # stability between 0.88 and 0.89, where the sweep goes on on an asymmetric
    # two-impact orbit) is the backward sweep's orbit
    fl0 = sh.make_flow(system, Harmonic(10.0, ratio=0.88))
    x88 = _orbit_state(_closed_form(system, 0.88)[1], 0.0)
    up = continue_branch(fl0, "ratio", x88, 0.635, step=0.05, max_points=60, max_step=0.05)
    assert _strobe_check(fl0, up, ds.sel(direction="backward"), 0.64, 0.88) == 25


def _fold_and_linear_grazing(system, force=10.0):
    """(r_f, r_g) of the small-gap case in closed form: the ratio where the two roots of
    the phase equation merge (sqrt(a^2 + b^2) = delta), and the ratio where the linear
    relative amplitude psi_d psi_L F0 / |K - M Omega^2 + i C Omega| reaches delta/2."""
    bar = system.bar

    def merge(r):
        a, b, c = phase_equation(_closed_form(system, r, force)[0])
        return float(np.hypot(a, b) - c)

    def relative_amplitude(r):
        om = r * system.reference_frequency_rad_s
        return abs(bar.psi_damper[0] * bar.psi_tip[0] * force
                   / complex(bar.stiffness_n_m[0] - bar.mass_kg[0] * om**2,
                             bar.damping_n_s_m[0] * om))
    return (_bisect(merge, 0.5, 0.8),
            _bisect(lambda r: relative_amplitude(r) - 0.5 * system.damper.gap_m, 0.8, 1.0))


def _strobe_check(fl0, br, sweep, lo, hi):
    """Assert that at each swept ratio in [lo, hi] the branch's orbit (Newton there from
    the nearest point, on that point's section, carried to phase 0) is stable and every
    strobe sample of ``sweep`` is on it within 1e-8; the number of ratios checked."""
    checked = 0
    for j, r in enumerate(sweep["value"].values):
        if not lo <= r <= hi:
            continue
        near = min(br.points, key=lambda p: abs(p.value - r))  # its section may have moved
        at = flow_with(dataclasses.replace(fl0, phase=near.phase), "ratio", r, fl0)
        x, pr = sh.periodic_orbit(at, near.x)
        assert np.all(np.abs(sh.multipliers(pr)) < 1.0)
        w = fl0.psi_tip @ sh.carry(at, x, 0.0)[:fl0.n]
        s = sweep["tip_displacement_m"].isel(value=j).values
        s = s[np.isfinite(s)]
        assert len(s) > 20 and np.max(np.abs(s - w)) <= 1e-8 * abs(w), (r, s[-1], w)
        checked += 1
    return checked


def test_a_plus_one_multiplier_without_a_turn_is_a_branch_point_not_a_fold():
    """Gap 0.1 mm, e = 0.3, F0 = 30 N: the stable symmetric two-impact orbit loses its
    stability at ratio 0.8320207 (closed form: the largest |multiplier| of the impact map
    reaches 1, bisected) to a real multiplier +1 while the branch goes on (a symmetry-
    breaking pitchfork: the sweeps beyond it sit on the two mirror-image asymmetric
    orbits).  Continuation must call it a branch point, not a fold, where the closed form
    puts it (1e-9; 2.5e-11 seen: the bordered test function's zero, sampled where the
    corrector's matrix is not yet singular), and give the other branch's direction from
    the algebraic bifurcation equation on the null space of [G_x, G_p]: at this pitchfork
    the eigenvector of the +1 multiplier, with p fixed."""
    system = make_system("ball", "physical", gap_m=0.1e-3, friction=False, n_modes=1,
                         restitution=0.3)
    orbit = _closed_form(system, 0.7, 30.0)[1]
    ph = (orbit.phase + np.pi / 2) % np.pi  # the section half-way between the impacts
    fl = dataclasses.replace(sh.make_flow(system, Harmonic(30.0, ratio=0.7)), phase=ph)
    br = continue_branch(fl, "ratio", _orbit_state(orbit, ph), 0.9, step=0.05, max_points=40)
    assert [k for k, _ in br.events] == ["branch-point"], (br.stop, br.events)

    def stable(r):
        sysm = _closed_form(system, r, 30.0)[0]
        near = min((o for o in two_impact_orbit(
            sysm.mass, sysm.stiffness, sysm.damping, sysm.psi_tip, sysm.psi_ball,
            sysm.ball_mass, sysm.gap, sysm.restitution, sysm.force, sysm.omega)
            if o.admissible), key=lambda o: abs(o.phase - orbit.phase))
        return 1.0 if np.max(np.abs(near.multipliers)) < 1.0 else -1.0
    expected = _bisect(stable, 0.82, 0.84, 1e-13)
    assert abs(br.events[0][1] - expected) <= 1e-9 * expected, (br.events, expected)
    bp = br.branch_points[0]
    assert bp.y[-1] == br.events[0][1]
    at = flow_with(dataclasses.replace(fl, phase=bp.phase), "ratio", bp.y[-1], fl)
    pr = sh.advance(at, bp.y[:-1])
    mu, vecs = np.linalg.eig(pr.jacobian)
    v = np.real(vecs[:, np.argmin(np.abs(mu - 1.0))])
    other = bp.other[:-1] * bp.scale[:-1]
    assert np.min(np.abs(mu - 1.0)) < 1e-7
    assert abs(other @ v) / np.linalg.norm(other) > 1 - 1e-8
    assert abs(bp.other[-1]) < 1e-6
    values = [p.value for p in br.points]
    assert values == sorted(values) and values[-1] > expected  # no turn


def test_a_turn_the_multipliers_hide_is_still_a_fold():
    """Physical preset, two modes, frictionless, gap 0.1 mm, ratio 1, down from the
    settled orbit at 30 N in 20 coarse steps: near 21.94 N the branch turns while three
    multipliers move at once (a complex pair outside splits, a real one inside joins a
    pair), so no multiplier pair shows the +1 crossing; the turn of the tangent must
    still be a fold, at the smallest F0 a fine continuation of the same branch reaches
    (from the coarse point before the turn, 60 steps over 0.5 N).  Where that point lies
    above 21.984 N the fine branch first meets a branch point: a real multiplier through
    +1 while F0 keeps falling (measured: 0.961 at 21.9878 N, 1.016 at 21.9828 N)."""
    system = make_system("ball", "physical", gap_m=0.1e-3, friction=False)
    o = ContinuationOptions(parameter="force-n", stop=5.0, force_n=30.0)
    fl = sh.make_flow(system, Harmonic(30.0, ratio=1.0))
    x0 = start_state(system, o, fl)
    coarse = continue_branch(fl, "force-n", x0, 5.0, step=0.05, max_points=20, min_step=1e-4)
    folds = [v for k, v in coarse.events if k == "fold"]
    assert len(folds) == 1, coarse.events
    before = next(i for i, p in enumerate(coarse.points) if p.value < folds[0] + 0.1)
    a = coarse.points[before]
    fine = continue_branch(flow_with(fl, "force-n", a.value, fl), "force-n", a.x, a.value - 0.5,
                           step=0.01, max_points=60, max_step=0.01, min_step=1e-5)
    p = [q.value for q in fine.points]
    assert p[-1] > min(p)  # it turned back
    # the fine branch never goes below the fold, and comes within 2e-5 of it (its points
    # are 0.01 of 0.5 N apart in arclength; at steps of 0.002, 1.4e-7 was seen)
    assert folds[0] <= min(p) <= folds[0] * (1 + 2e-5), (folds, min(p))
    # the fine branch locates the same fold from other points
    kinds = [k for k, _ in fine.events]
    assert kinds[-1] == "fold" and set(kinds[:-1]) <= {"branch-point"}, fine.events
    assert abs(fine.events[-1][1] - folds[0]) <= 1e-10 * folds[0]
    # a branch point before it (where the fine branch starts above it) is a real
    # multiplier through +1 while the parameter keeps falling: no turn there
    for value in (v for k, v in fine.events if k == "branch-point"):
        i = next(i for i, q in enumerate(fine.points) if q.value < value)
        before, after = fine.points[i - 1], fine.points[i]
        assert before.value > value > after.value > min(p)
        outside = [np.sort_complex(q.multipliers[np.abs(q.multipliers) > 1.0])
                   for q in (before, after)]
        assert len(outside[1]) == len(outside[0]) + 1
        new = [m for m in outside[1] if abs(m.imag) < 1e-12 and m.real > 1.0]
        assert new and min(m.real for m in new) < 1.05, outside

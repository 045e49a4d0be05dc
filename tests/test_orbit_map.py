"""The orbit map (boringbar.orbits.orbit_map, boringbar.orbits.attractors): the range covered, the
stop reasons, branch switching at a pitchfork against the symmetry, brute-force seeds,
and the issue's case (paper preset, gap 0.1 mm, frictionless, ratio 1, F0 5-35 N)
against the exact integrator's settled orbits."""

import dataclasses
import json

import numpy as np
import pytest

import boringbar as bb
from boringbar.analysis.continuation import (
    ContinuationOptions,
    continuation,
    start_state,
    summary,
    system_at,
)
from boringbar.cli.continuation import _branch_line
from boringbar.cli.main import main
from boringbar.model.forcing import Harmonic
from boringbar.model.system import make_system
from boringbar.orbits import shooting as sh
from boringbar.orbits.attractors import RETURN_TOL, periodic_attractors, return_distance, same_orbit
from boringbar.orbits.branch import flow_with
from boringbar.orbits.continuation import continue_branch
from boringbar.orbits.orbit_map import (
    MapBranch,
    MapOptions,
    OrbitMap,
    attractor_check,
    cross_grazing,
    switch_branch_point,
)
from boringbar.reference.masri_caughey import two_impact_orbit
from boringbar.report.html import _branch_row
from boringbar.simulate import simulate


def _issue_case():
    return make_system("ball", "paper", gap_m=0.1e-3, friction=False)


def _issue_branch():
    system = _issue_case()
    fl = sh.make_flow(system, Harmonic(5.0, ratio=1.0))
    x0 = start_state(system, ContinuationOptions(force_n=5.0), fl)
    return system, fl, continue_branch(fl, "force-n", x0, 35.0)


def test_the_first_branch_stops_at_a_grazing_and_the_map_goes_on_across_it():
    """From 5 N the default steps reach the grazing at 26.53 N (the stop names it and its
    value), not a point budget; across it the orbit with one more impact reaches 35 N."""
    _, fl, br = _issue_branch()
    assert br.stop.startswith("the event sequence changes at force-n = 26.531"), \
        br.stop
    assert [k for k, _ in br.events] == ["branch-point", "grazing"]
    assert len(br.points) < 100
    on = cross_grazing(fl, br, (5.0, 35.0))
    assert on.stop.startswith("end of range at force-n = 35"), on.stop
    assert on.events[0] == ("grazing", br.points[-1].value)
    before = sum(k.startswith("impact") for _, k in br.points[-1].events)
    after = sum(k.startswith("impact") for _, k in on.points[0].events)
    assert after != before


def test_a_fold_that_leaves_the_range_is_the_stop_reason():
    """Gap 0.1 mm, e = 0.7, 10 N, from the closed-form orbit at ratio 0.8 down: the branch
    folds at the closed-form fold (0.62685) and goes back up out of the range at 0.8."""
    system = make_system("ball", "physical", gap_m=0.1e-3, friction=False, n_modes=1)
    fl = dataclasses.replace(sh.make_flow(system, Harmonic(10.0, ratio=0.8)), phase=1.6)
    bar, ball = system.bar, system.damper
    orbit = next(o for o in two_impact_orbit(
        bar.mass_kg[0], bar.stiffness_n_m[0], bar.damping_n_s_m[0],
        bar.psi_tip[0], bar.psi_damper[0],
        ball.mass_kg, ball.gap_m, ball.restitution, 10.0, fl.omega) if o.admissible and o.stable)
    t, h = 1.6 / fl.omega, 1e-9
    x0 = np.array([float(orbit.modal_displacement(t)), float(orbit.modal_velocity(t)),
                   float(orbit.relative_displacement(t)),
                   float(orbit.relative_displacement(t + h)
                         - orbit.relative_displacement(t - h)) / (2 * h)])
    br = continue_branch(fl, "ratio", x0, 0.55)
    assert br.stop.startswith("fold at ratio = 0.626854302"), br.stop
    assert "left the range at ratio = 0.8" in br.stop


def test_switching_at_the_pitchfork_gives_the_two_mirror_image_orbits():
    """Gap 0.1 mm, e = 0.3, 30 N: past the branch point of the symmetric orbit (ratio
    0.8320207, the closed form's) the two children are asymmetric period-1 orbits (not
    symmetric: x(T/2) != -x(0)) and mirror images of each other (the symmetry
    y -> -y, u -> -u, t -> t + T/2 maps one onto the other), checked at one ratio by
    the exact map alone."""
    system = make_system("ball", "physical", gap_m=0.1e-3, friction=False, n_modes=1,
                         restitution=0.3)
    bar, ball = system.bar, system.damper
    fl0 = sh.make_flow(system, Harmonic(30.0, ratio=0.7))
    orbit = next(o for o in two_impact_orbit(
        bar.mass_kg[0], bar.stiffness_n_m[0], bar.damping_n_s_m[0],
        bar.psi_tip[0], bar.psi_damper[0],
        ball.mass_kg, ball.gap_m, ball.restitution, 30.0, fl0.omega) if o.admissible and o.stable)
    ph = (orbit.phase + np.pi / 2) % np.pi
    fl = dataclasses.replace(fl0, phase=ph)
    t, h = ph / fl.omega, 1e-9
    x0 = np.array([float(orbit.modal_displacement(t)), float(orbit.modal_velocity(t)),
                   float(orbit.relative_displacement(t)),
                   float(orbit.relative_displacement(t + h)
                         - orbit.relative_displacement(t - h)) / (2 * h)])
    br = continue_branch(fl, "ratio", x0, 0.9, max_points=40)
    bp = br.branch_points[0]
    o = MapOptions(max_points=8)
    kids = [switch_branch_point(fl, "ratio", br, bp, s, (0.7, 0.9), o) for s in (1.0, -1.0)]
    assert all(len(k.points) == 8 for k in kids), [k.stop for k in kids]
    r = kids[0].points[-1].value
    states = []
    for k in kids:
        near = min(k.points, key=lambda p: abs(p.value - r))
        at = flow_with(dataclasses.replace(fl, phase=near.phase), "ratio", r, fl)
        x, _ = sh.periodic_orbit(at, near.x)
        x0 = sh.carry(at, x, 0.0)
        half = sh.carry(dataclasses.replace(at, phase=0.0), x0, np.pi)
        size = np.max(np.abs(x0))
        assert np.max(np.abs(half + x0)) > 1e-3 * size  # not symmetric
        states.append((x0, half))
    # the mirror image of child 0 at phase 0 is minus its state at phase pi: child 1's
    assert np.max(np.abs(states[1][0] + states[0][1])) < 1e-8 * np.max(np.abs(states[1][0]))


def test_brute_force_attractors_are_distinct_and_merged():
    """At 10 N the exact integrator settles, from the spread of initial conditions, on
    the two mirror images of an asymmetric three-impact orbit (the issue's finding); they
    are kept apart, and each is one orbit with itself advanced a period."""
    system = _issue_case()
    forcing = Harmonic(10.0, ratio=1.0)
    found = periodic_attractors(system, forcing)
    assert len(found) == 2 and all(a.periods == 1 and a.impacts == 3 for a in found)
    fl = sh.make_flow(system, forcing)
    assert not same_orbit(fl, found[0], found[1])
    assert same_orbit(fl, found[0], dataclasses.replace(found[0], x=sh.advance(fl, found[0].x).x))


def test_cli_continue_without_switching_or_seeds_is_one_branch(tmp_path, capsys):
    argv = ["continue", "--gap-mm", "0.5", "--friction", "off", "--modes", "1",
            "--range", "30:29", "--start-from", "masri-caughey", "--max-points", "4",
            "--no-switch", "--seeds", "0", "--out", str(tmp_path), "--json"]
    assert main(argv) == 0
    out = json.loads(capsys.readouterr().out)
    assert len(out["branches"]) == 1
    b = out["branches"][0]
    assert b["parent"] is None and b["born"] == {"kind": "start", "value": 30.0}
    assert b["periods"] == 1 and out["attractor_check"] == []
    assert main([*argv[:-3], "--seeds", "-1", "--out", str(tmp_path)]) == 2
    assert main([*argv[:-3], "--max-step", "0.9", "--out", str(tmp_path)]) == 2


@pytest.mark.slow
def test_the_issue_case_map_holds_the_settled_orbits():
    """The issue's case through `bb.continuation` (switching on, 3 seeds): every
    brute-force attractor lies on a stable branch (1e-6), and at 10, 20 and 30 N the
    exact integrator from rest (600 periods) settles on an orbit whose strobe tip
    displacement is a stable branch's at that F0 to 1 %."""
    system = _issue_case()
    ds = bb.continuation(system, Harmonic(5.0, ratio=1.0),
                         options=ContinuationOptions(parameter="force-n", stop=35.0))
    checks = json.loads(ds.attrs["attractor_check"])
    assert len(checks) >= 3 and all(c["on_stable_branch"] for c in checks), checks
    fl = sh.make_flow(system, Harmonic(5.0, ratio=1.0))
    for force in (10.0, 20.0, 30.0):
        f = Harmonic(force, ratio=1.0)
        per = 2 * np.pi / f.omega(system.reference_frequency_rad_s)
        run = simulate(system, f, duration_s=600 * per, dt_s=per / np.ceil(per / 1e-6),
                       integrator="exact", strobe=True)
        w = run.final.x[: fl.n] @ fl.psi_tip
        tips = []
        for b in range(ds.sizes["branch"]):
            d = ds.isel(branch=b)
            v, st = d["value"].values, d["stable"].values.astype(bool)
            ok = np.isfinite(v) & st
            for i in np.flatnonzero(ok[:-1] & ok[1:]):
                if min(v[i], v[i + 1]) <= force <= max(v[i], v[i + 1]):
                    s = (force - v[i]) / (v[i + 1] - v[i])
                    tips.append(d["strobe_tip_m"].values[i] * (1 - s)
                                + d["strobe_tip_m"].values[i + 1] * s)
        assert any(abs(t - w) <= 0.01 * abs(w) for t in tips), (force, w, tips)


def test_the_attractor_check_finds_an_attractor_on_a_folded_branch_and_says_when_not():
    """The four-impact attractor brute force finds at 17.5 N (no seed there) lies on the
    stable stretch of the branch continued from the 20 N attractor, which folds at 16.57 N
    and so passes 17.5 N twice (1e-6; the check tries every stretch through the value).
    The three-impact attractor at 10 N is on no branch of that map, and the check says
    so."""
    system = _issue_case()
    fl = sh.make_flow(system, Harmonic(5.0, ratio=1.0))
    seed = periodic_attractors(system, Harmonic(20.0, ratio=1.0))[0]
    br = continue_branch(flow_with(fl, "force-n", 20.0, fl), "force-n", seed.x, 5.0,
                         bounds=(5.0, 35.0))
    # (past the fold the branch ends at the grazing at 26.53 N, or where its corrector
    # stalls just short of it, by the CPU's roundings: a square-root singularity)
    folds = [v for k, v in br.events if k == "fold"]
    assert folds == [pytest.approx(16.57, abs=0.01)] or "fold" in br.stop, br.events
    om = OrbitMap("force-n", 5.0, 35.0, [MapBranch(br, None, ("seed", 20.0), fl)])
    found = periodic_attractors(system, Harmonic(17.5, ratio=1.0))
    assert [a.impacts for a in found] == [4.0]
    c = attractor_check(om, 17.5, found[0].x, 1)
    assert c["on_stable_branch"] and c["branch"] == 0 and c["distance"] <= 1e-6, c
    other = periodic_attractors(system, Harmonic(10.0, ratio=1.0))[0]
    c = attractor_check(om, 10.0, other.x, 1)
    assert not c["on_stable_branch"] and c["branch"] is None


def _closed_form_state(system, force):
    """The Masri-Caughey symmetric two-impact orbit at phase 0 (one mode, no friction)."""
    bar, ball = system.bar, system.damper
    omega = Harmonic(force, ratio=1.0).omega(system.reference_frequency_rad_s)
    orbit = next(o for o in two_impact_orbit(
        bar.mass_kg[0], bar.stiffness_n_m[0], bar.damping_n_s_m[0], bar.psi_tip[0],
        bar.psi_damper[0], ball.mass_kg, ball.gap_m, ball.restitution, force, omega)
        if o.admissible)
    h = 1e-9
    return np.array([float(orbit.modal_displacement(0.0)), float(orbit.modal_velocity(0.0)),
                     float(orbit.relative_displacement(0.0)),
                     float(orbit.relative_displacement(h) - orbit.relative_displacement(-h))
                     / (2 * h)]), orbit


def test_the_return_check_passes_a_stable_closed_form_orbit_and_fails_an_unstable_one():
    """The closed-form two-impact orbit (physical bar, one mode, gap 0.5 mm, frictionless;
    its Neimark-Sacker point at 28.345 N, docs/continuation.md "Worked example"), polished
    by Newton: at 30 N (stable) the exact integrator comes back from a 1e-7 perturbation
    within 1e-6 after 200 periods; at 27 N (unstable) it does not."""
    system = make_system("ball", "physical", gap_m=0.5e-3, friction=False, n_modes=1)
    for force, stable in ((30.0, True), (27.0, False)):
        x0, _ = _closed_form_state(system, force)
        forcing = Harmonic(force, ratio=1.0)
        fl = sh.make_flow(system, forcing)
        x, pr = sh.periodic_orbit(fl, x0, rms=False)
        assert np.max(np.abs(x - x0)) <= 1e-6 * np.max(np.abs(x0))  # the closed form's orbit
        assert (np.max(np.abs(sh.multipliers(pr))) < 1.0) == stable
        d = return_distance(system, forcing, x, 0.0, 1)
        assert (d <= RETURN_TOL) == stable, (force, d)


def test_a_boundary_where_newton_jumped_to_another_orbit_is_not_a_grazing():
    """The three-impact branch from the 10 N attractor downwards, past its fold (7.6455 N)
    and up again, unstable: near 8.02 N the two-impact orbit born at 8.04 N coexists close
    by and Newton from a far start lands on it; that is not where the three-impact
    sequence ends (it went on, |mu| 404, at the value the branch used to stop at, 8.0158
    N).  The branch reaches the grazing where its third impact vanishes, 8.04234 N, and
    across it the orbit has two impacts."""
    system = _issue_case()
    fl = sh.make_flow(system, Harmonic(5.0, ratio=1.0))
    seed = periodic_attractors(system, Harmonic(10.0, ratio=1.0))[0]
    at = flow_with(fl, "force-n", 10.0, fl)
    br = continue_branch(at, "force-n", seed.x, 5.0, bounds=(5.0, 35.0))
    assert br.stop.startswith("the event sequence changes at force-n = 8.04234"), \
        br.stop
    on = cross_grazing(at, br, (5.0, 35.0))
    assert on.points and sum(k.startswith("impact") for _, k in on.points[0].events) == 2


def test_cli_range_lo_start_hi_maps_both_ways_and_checks_the_return(tmp_path, capsys):
    """--range LO:START:HI: the start orbit continued down to LO and up to HI (two roots
    born at START), every stable point returned under the exact integrator; LO:START:HI
    out of order, or four numbers, is one line and exit 2."""
    argv = ["continue", "--gap-mm", "0.5", "--friction", "off", "--modes", "1",
            "--range", "29.5:30:30.5", "--start-from", "masri-caughey", "--max-points", "3",
            "--no-switch", "--seeds", "0", "--out", str(tmp_path), "--json"]
    assert main(argv) == 0
    out = json.loads(capsys.readouterr().out)
    values = [[p["value"] for p in b["points"]] for b in out["branches"]]
    assert len(values) == 2 and all(b["born"] == {"kind": "start", "value": 30.0}
                                    for b in out["branches"])
    assert min(values[0] + values[1]) < 30.0 < max(values[0] + values[1])
    rc = out["return_check"]
    stable = sum(p["stable"] for b in out["branches"] for p in b["points"])
    assert rc["checked_count"] == stable > 0 and rc["failed"] == []
    assert rc["largest_relative"] <= RETURN_TOL
    for bad in ("30.5:30:29.5", "29:30:31:32"):
        assert main([*argv[:8], bad, *argv[9:-1]]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and "--range" in err[0], err


@pytest.mark.parametrize(("name", "value"), [("force-n", 12.0), ("ratio", 0.9),
                                             ("gap-mm", 0.3), ("restitution", 0.5),
                                             ("friction-force-n", 0.05),
                                             ("ball-mass-g", 20.0)])
def test_the_system_at_a_value_is_the_flow_the_branch_uses(name, value):
    """Seeds and the return check run the exact integrator on system_at(value); its flow
    is the branch's (flow_with) in every quantity the parameter moves."""
    system = make_system("ball", "physical", gap_m=0.5e-3, friction=True)
    o = ContinuationOptions(parameter=name, force_n=20.0, ratio=1.0)
    ref = sh.make_flow(system, Harmonic(20.0, ratio=1.0))
    want = flow_with(ref, name, value, ref)
    got = sh.make_flow(*system_at(system, o, value))
    for field in ("amplitude", "omega", "half", "e", "fc", "fs", "m", "meff", "v_impact"):
        assert getattr(got, field) == pytest.approx(getattr(want, field), rel=1e-12), field


def test_a_period_two_branch_ends_where_it_meets_its_period_one_parent():
    """The friction ball at gap 0.1 mm: a period-2 attractor at 38.45 N, continued down,
    reaches the period doubling (38.15 N) it was born at; past it the corrector finds the
    period-1 orbit traversed twice, a fixed point of P^2 too.  The branch ends there
    instead of following that orbit as if it were period 2, and every point it kept
    returns only after two periods; a period-2 continuation started on a period-1 orbit
    is refused by name."""
    system = make_system("ball", gap_m=0.1e-3)
    forcing = Harmonic(38.0, ratio=1.0)
    options = ContinuationOptions(parameter="force-n", stop=38.6, force_n=38.0, seeds=2,
                                  step=0.05, max_step=0.1, max_points=12)
    ds = bb.continuation(system, forcing, options=options)
    stops = json.loads(ds.attrs["stop_reasons"])
    down = [b for b in range(ds.sizes["branch"]) if int(ds["periods"][b]) == 2
            and stops[b].startswith("period 1 at force-n = ")]
    assert len(down) == 1, stops
    d = ds.isel(branch=down[0])
    kept = np.flatnonzero(np.isfinite(d["value"].values))
    end = float(stops[down[0]].split("= ")[1].split(":")[0])
    assert 38.0 < end < d["value"].values[kept].min() < 38.2  # just past the doubling
    base = sh.make_flow(system, forcing)
    for p in kept:
        fl = flow_with(base, "force-n", float(d["value"][p]), base)
        x = d["state"].values[p]  # carried to phase 0
        once, twice = sh.advance(fl, x, 1).x, sh.advance(fl, x, 2).x
        assert np.max(np.abs(once - x)) > 1e3 * np.max(np.abs(twice - x))
    wrong = bb.continuation(system, Harmonic(38.3333, ratio=1.0), options=dataclasses.replace(
        options, stop=37.0, force_n=38.3333, periods=2, switch=False, seeds=0))
    assert "the orbit found is of period 1, not 2" in json.loads(
        wrong.attrs["stop_reasons"])[0]


def test_a_map_whose_start_is_refused_says_why_once():
    """The paper preset's friction holds the ball at 30 N (gap 0.1 mm): the map's start
    is refused in both directions for the same reason, which its stop gives once."""
    system = make_system("ball", "paper", gap_m=0.1e-3)
    ds = bb.continuation(system, Harmonic(30.0, ratio=1.0), options=ContinuationOptions(
        parameter="force-n", stop=35.0, force_n=30.0, seeds=0, max_points=5))
    (stop,) = json.loads(ds.attrs["stop_reasons"])
    assert stop.count("stick phases are not linearised") == 1, stop


def test_a_map_names_each_branch_s_mirror_image(tmp_path):
    """Two seeds at 42.5 N (the paper preset, gap 0.5 mm, no friction) settle on an
    asymmetric orbit and its mirror image: two branches of the same RMS over the same
    range, distinct orbits, each named the other's mirror in the file, the summary and
    the report's row, so that a reader does not take them for a branch listed twice."""
    system = make_system("ball", "paper", gap_m=0.5e-3, friction=False)
    options = ContinuationOptions(parameter="force-n", stop=50.0, other_end=5.0, force_n=30.0,
                                  ratio=1.0, step=0.05, max_step=0.1, max_points=10, seeds=3,
                                  max_branches=8)
    ds = continuation(system, options=options)
    mirror = ds["mirror"].values
    pairs = [(i, int(j)) for i, j in enumerate(mirror) if j >= 0]
    assert pairs and all(mirror[j] == i for i, j in pairs)
    for i, j in pairs:
        np.testing.assert_allclose(ds["rms_tip_m"][i], ds["rms_tip_m"][j], rtol=1e-9)
        assert not np.allclose(ds["state"][i, 0], ds["state"][j, 0])
    branches = summary(ds)["branches"]
    i, j = pairs[0]
    assert branches[i]["mirror"] == j
    assert f"the mirror image of branch {j}" in _branch_line(i, branches[i], "force-n")
    assert f"mirror of {j}" in _branch_row("case", i, branches[i])[1]

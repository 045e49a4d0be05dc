"""The exact integrator in a regenerative cut (boringbar.simulate.kernels.run_exact).

In the cut, -Kr b W(t) joins the regime matrix and Kr b min_k [k h_m + W(t - k tau)]
is a known input: one cubic per step H = tau / ceil(tau / dt) (cubic Hermite of the
stored W, W'), propagated exactly (phi-functions), so the only error is the
interpolation's, O(H^4).  Tiers: the order measured (H halving against a fine H);
RK4 converging to the same answer (W, time of the first zero); the closed-form
truths of the linear cut (static deflection below the limit, the force reaching
zero above it); verdicts equal to RK4's away from the boundary; the energy balance
with the cutting force; a ball-damper cut with impacts and friction; the lobes, the
command line and study files.  Measured values are quoted beside each tolerance.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from boringbar import make_system, simulate
from boringbar.model.forcing import KR_ALUMINIUM, Regenerative
from boringbar.reference.stability import limit_at_speeds

KR = KR_ALUMINIUM
FEED = 0.1e-3
RPM = 1210.0  # tau / dt not a whole number
SAMPLE = 8e-5  # history sampling of the order study (s): a multiple of every dt below


def _limit(system, rpm: float) -> float:
    return float(limit_at_speeds(system, [rpm])[0])


def _cut(system, factor: float, rpm: float = RPM, integrator: str = "exact",
         dt_s: float = 1e-6, duration_s: float = 2.0, **kw):
    forcing = Regenerative(depth_m=factor * _limit(system, rpm), rpm=rpm, **kw)
    return simulate(system, forcing, duration_s=duration_s, dt_s=dt_s, integrator=integrator,
                    record_every=round(SAMPLE / dt_s))


def _w_error(run, ref) -> float:
    """max |W - W_ref| over the common history samples, relative to max |W_ref|."""
    n = min(len(run.history), len(ref.history))
    assert np.allclose(run.history[:n, 0], ref.history[:n, 0], rtol=0, atol=1e-12)
    w, w_ref = run.history[:n, 1], ref.history[:n, 1]
    return float(np.max(np.abs(w - w_ref)) / np.max(np.abs(w_ref)))


# --- the order of the scheme ------------------------------------------------------------
ORDER_STEPS = (16e-6, 8e-6, 4e-6)


@pytest.mark.parametrize("factor,duration", [(0.5, 0.3), (2.0, 0.9)])
def test_the_cut_is_fourth_order_in_the_history_step(factor, duration):
    """Errors of W (sampled every 80 us) against H = 1 us, solid bar at 1210 rpm.

    Measured, stable (0.5 x the analytic limit, 0.3 s): 2.4e-9, 1.5e-10, 1.0e-11
    (orders 3.99, 3.86); chattering (2 x, 0.9 s, just before the first zero at
    0.961 s, the growth amplifying every error): 1.5e-7, 9.1e-9, 4.7e-10 (orders
    4.02, 4.28).  Below H = 4 us the differences stop shrinking at about 1e-12
    (stable) and 1e-10 (chattering): the round-off of the one-step propagator,
    eps per step over 1e5 .. 1e6 steps, amplified by the growth."""
    system = make_system("solid")
    ref = _cut(system, factor, dt_s=1e-6, duration_s=duration, stop_at_zero=True)
    errs = [_w_error(_cut(system, factor, dt_s=dt, duration_s=duration, stop_at_zero=True), ref)
            for dt in ORDER_STEPS]
    orders = [math.log2(a / b) for a, b in zip(errs, errs[1:], strict=False)]
    assert all(3.5 < q < 4.6 for q in orders), (errs, orders)
    assert errs[-1] < 1e-9


def test_linear_delay_interpolation_is_second_order():
    """docs/model.md, section 4's option, honoured by the exact integrator: measured errors
    (against cubic at H = 1 us) 8.0e-4, 2.0e-4, 5.0e-5 at H = 8, 4, 2 us (orders 2.00,
    2.00; RK4 with linear interpolation at dt = 2 us: 4.3e-5)."""
    system = make_system("solid")
    ref = _cut(system, 2.0, dt_s=1e-6, duration_s=0.9)
    runs = [_cut(system, 2.0, dt_s=dt, duration_s=0.9, interpolation="linear")
            for dt in (8e-6, 4e-6, 2e-6)]
    errs = [_w_error(r, ref) for r in runs]
    assert all(1.8 < math.log2(a / b) < 2.2 for a, b in zip(errs, errs[1:], strict=False))
    assert runs[0].config()["delay_interpolation"] == "linear"


def test_rk4_converges_to_the_exact_cut():
    """RK4 (cubic history, dt = 2, 1, 0.5 us) against exact at H = 1 us, chattering cut
    up to its first zero.  W: measured 1.4e-8, 8.9e-10, 9.3e-11 (RK4's own fourth
    order, then the exact run's round-off floor of about 1e-10 shows).  The first
    zero, which RK4 finds at a stage (a multiple of dt / 2): measured exact
    0.9610041729 s, RK4 later by 8.3e-7, 3.3e-7, 7.7e-8 s (within dt)."""
    system = make_system("solid")
    ex = _cut(system, 2.0, stop_at_zero=True)
    t_ex = ex.cutting["first_zero_time_s"]
    assert t_ex == pytest.approx(0.961, abs=0.01)
    errs, dts = [], []
    for dt in (2e-6, 1e-6, 5e-7):
        rk = _cut(system, 2.0, integrator="rk4", dt_s=dt, stop_at_zero=True)
        errs.append(_w_error(rk, ex))
        dts.append(abs(rk.cutting["first_zero_time_s"] - t_ex))
        assert dts[-1] <= dt
    assert errs[0] < 5e-8 and errs[-1] < 5e-10
    assert errs[0] / errs[1] > 8 and errs[1] / errs[2] > 5  # measured 16.1, 9.6
    assert dts[-1] < dts[0]


def test_exact_history_step_beats_rk4_at_the_same_step():
    """At dt = H = 8 us the exact cut is 1e-8 from the reference, RK4 3e-6: RK4's own
    truncation error of the fast second mode dominates its interpolation's."""
    system = make_system("solid")
    ref = _cut(system, 2.0, dt_s=1e-6, duration_s=0.9)
    e_ex = _w_error(_cut(system, 2.0, dt_s=8e-6, duration_s=0.9), ref)
    e_rk = _w_error(_cut(system, 2.0, integrator="rk4", dt_s=8e-6, duration_s=0.9), ref)
    assert e_ex < 1e-7 and e_rk > 100 * e_ex  # measured 9.1e-9, 3.3e-6


# --- closed-form truths of the linear cut (as tests/test_chatter.py for RK4) -----------
def test_below_the_limit_the_cut_settles_to_the_static_deflection():
    system = make_system("solid")
    bar = system.bar
    run = _cut(system, 0.5, rpm=1200.0, dt_s=4e-6)
    b = 0.5 * _limit(system, 1200.0)
    w_static = KR * b * FEED * float(np.sum(bar.psi_tip**2 / bar.stiffness_n_m))
    c = run.cutting
    assert c["static_deflection_m"] == pytest.approx(w_static, rel=1e-12)
    assert not c["chatter"] and c["steps_with_zero_force"] == 0
    assert run.metrics["mean_tip_m"] == pytest.approx(w_static, rel=1e-5)
    assert float(bar.psi_tip @ run.final.x[:bar.n_modes]) == pytest.approx(w_static, rel=1e-5)
    assert c["mean_force_n"] == pytest.approx(KR * b * FEED, rel=1e-6)
    t, W = run.history[:, 0], run.history[:, 1]
    assert np.ptp(W[t > 1.9]) < 1e-5 * np.ptp(W[t < 0.1])
    assert abs(run.energy["balance_relative"]) < 1e-9


def test_above_the_limit_the_force_reaches_zero_as_with_rk4():
    """Measured at 1200 rpm, 2 x the limit, 0.5 s: first zero 0.2516416 s (RK4 at
    1 us: 0.251642), h = 0 in 102780 steps of 1 us (RK4: 102780), RMS equal to 7.6e-7,
    peak force to 9.8e-5 (RK4 samples it at its stages), balance -1.6e-12 (RK4
    -2.9e-12)."""
    system = make_system("solid")
    ex = _cut(system, 2.0, rpm=1200.0, duration_s=0.5)
    rk = _cut(system, 2.0, rpm=1200.0, duration_s=0.5, integrator="rk4")
    c, d = ex.cutting, rk.cutting
    assert c["chatter"] and c["first_zero_time_s"] == pytest.approx(0.2516, abs=1e-3)
    assert abs(c["first_zero_time_s"] - d["first_zero_time_s"]) < 1e-6
    assert c["steps_with_zero_force"] == pytest.approx(d["steps_with_zero_force"], rel=1e-3)
    assert ex.metrics["rms_tip_m"] == pytest.approx(rk.metrics["rms_tip_m"], rel=1e-5)
    assert c["max_force_n"] == pytest.approx(d["max_force_n"], rel=1e-3)
    assert c["bounded_chatter"] and c["amplitude_m"] > FEED
    assert abs(ex.energy["balance_relative"]) < 1e-9 and ex.energy["work_force_j"] > 0


@pytest.mark.parametrize("rpm", [900.0, 1250.0, 1550.0])
def test_verdicts_equal_rk4_away_from_the_boundary(rpm):
    """0.8 x the analytic limit is stable, 2 x chatters (the 2 s time-domain limit lies
    1.07 .. 1.51 x above the analytic one, tests/test_chatter.py), for both."""
    system = make_system("solid")
    for factor in (0.8, 2.0):
        verdicts = {integ: _cut(system, factor, rpm=rpm, integrator=integ, dt_s=dt,
                                stop_at_zero=True).cutting["chatter"]
                    for integ, dt in (("exact", 4e-6), ("rk4", 1e-6))}
        assert verdicts == {"exact": factor > 1, "rk4": factor > 1}


@pytest.mark.parametrize("bar", ["tmd", "locked"])
def test_other_linear_bars_match_rk4(bar):
    """Cuts at 1.5 x the host's analytic limit over 0.3 s (the start's transient, no
    zero yet) against RK4 at 0.25 us: W equal to measured 1.3e-11 (tmd), 3.8e-12
    (locked); balance -5.9e-12, -5.3e-12."""
    system = (make_system("ball", locked=True, friction=False) if bar == "locked"
              else make_system(bar))
    ex = _cut(system, 1.5, rpm=1200.0, duration_s=0.3, dt_s=2e-6)
    rk = _cut(system, 1.5, rpm=1200.0, duration_s=0.3, dt_s=2.5e-7, integrator="rk4")
    assert _w_error(ex, rk) < 1e-8
    assert abs(ex.energy["balance_relative"]) < 1e-9


# --- a ball damper in the cut ---------------------------------------------------------
@pytest.fixture(scope="module")
def ball_cuts():
    """The physical preset with a 10 um gap at 3 x the bare bar's limit (1200 rpm): the
    start's transient throws the ball at the walls 13 times in the first 14 ms, with
    rolling friction between impacts."""
    system = make_system("ball", gap_m=10e-6)
    depth = 3.0 * float(limit_at_speeds(system.bar, [1200.0])[0])

    def run(integrator, dt):
        return simulate(system, Regenerative(depth_m=depth, rpm=1200.0), duration_s=0.02, dt_s=dt,
                        integrator=integrator, steady_fraction=1.0)

    return {key: run(*key) for key in (("exact", 1e-6), ("exact", 2e-6), ("rk4", 2.5e-7),
                                       ("rk4", 6.25e-8))}


def test_ball_cut_is_independent_of_the_history_step(ball_cuts):
    """Impacts are located exactly whatever H: measured 1e-14 s between H = 1 and 2 us."""
    a, b = ball_cuts["exact", 1e-6], ball_cuts["exact", 2e-6]
    assert a.metrics["impacts_total"] == b.metrics["impacts_total"] == 13
    assert np.max(np.abs(a.impacts[:, 0] - b.impacts[:, 0])) < 1e-10
    for r in (a, b):
        assert abs(r.energy["balance_relative"]) < 1e-9  # measured 4e-12
        assert r.metrics["max_abs_aux_all_m"] <= 5e-6 * (1 + 1e-12)
        assert r.metrics["events"] > 13  # impacts and friction switches


def rk4_cut_errors(cuts: dict) -> list[tuple[float, float, float]]:
    """RK4's errors against the exact cut ``cuts["exact", 1e-6]`` at dt = 0.25 and
    0.0625 us (``cuts["rk4", dt]``), each run with the exact run's impacts: the largest
    difference of impact times (s), the relative ones of the impact loss and of the RMS
    of W."""
    ex = cuts["exact", 1e-6]
    errs = []
    for dt in (2.5e-7, 6.25e-8):
        rk = cuts["rk4", dt]
        assert rk.metrics["impacts_total"] == ex.metrics["impacts_total"]
        errs.append((np.max(np.abs(rk.impacts[:, 0] - ex.impacts[:, 0])),
                     abs(rk.energy["dissipated_impacts_j"]
                         / ex.energy["dissipated_impacts_j"] - 1),
                     abs(rk.metrics["rms_tip_m"] / ex.metrics["rms_tip_m"] - 1)))
    return errs


def test_rk4_converges_to_the_exact_ball_cut(ball_cuts):
    """RK4 detects impacts at step ends (first order): impact times differ from the
    exact ones by at most 6.9e-5 s at dt = 0.25 us and 6.1e-6 s at 62.5 ns; the impact
    loss by 1.3e-3 and 8.6e-5 relative, the RMS of W by 1.6e-4 and 1.5e-5."""
    (t1, d1, r1), (t2, d2, r2) = rk4_cut_errors(ball_cuts)
    assert t2 < 2e-5 and d2 < 5e-4 and r2 < 5e-5
    assert t2 < t1 and d2 < d1 and r2 < r1


def test_stuck_ball_with_the_printed_reaction_in_a_cut():
    """The paper preset's ball sticks to the bar (printed, non-reciprocal friction
    reaction) through a chattering cut (3 x the bare bar's limit, 0.2 s): the work of
    the printed reaction is integrated with the cutting force, the balance closes
    (measured 3.6e-13), and RK4's first zero, shifted by its sgn() chatter, converges
    to the exact one: measured 0.1951696 s exact, RK4 -2.0e-3 s at 1 us, -4.9e-6 s at
    0.125 us."""
    system = make_system("ball", "paper")
    depth = 3.0 * float(limit_at_speeds(system.bar, [1200.0])[0])

    def run(integrator, dt):
        return simulate(system, Regenerative(depth_m=depth, rpm=1200.0), duration_s=0.2, dt_s=dt,
                        integrator=integrator)

    ex = run("exact", 1e-6)
    assert abs(ex.energy["balance_relative"]) < 1e-9
    assert ex.energy["work_nonreciprocal_friction_j"] > 0
    assert ex.metrics["stick_time_s"] == pytest.approx(0.16, rel=1e-9)  # the steady window
    t_ex = ex.cutting["first_zero_time_s"]
    assert t_ex == pytest.approx(0.1952, abs=1e-3)
    d = [abs(run("rk4", dt).cutting["first_zero_time_s"] - t_ex) for dt in (1e-6, 1.25e-7)]
    assert d[1] < 2e-5 and d[1] < 0.1 * d[0]


# --- selectable everywhere --------------------------------------------------------------
def test_lobes_run_exactly_and_agree_with_rk4():
    from boringbar.analysis.cases import Case
    from boringbar.analysis.lobes import LobesOptions, lobes
    from boringbar.execute import Execution
    from boringbar.simulate import Integration

    cases = [Case("solid", make_system("solid"), "solid")]
    options = LobesOptions([1250.0], method="search", criterion="zero", max_depth_m=0.5e-3)
    ex = lobes(cases, options, integration=Integration(0.5, 2e-6, "exact"),
               execution=Execution(workers=1))
    rk = lobes(cases, options, integration=Integration(0.5, 2e-6),
               execution=Execution(workers=1))
    # "auto" (the default) takes RK4 in a cut
    assert ex.attrs["integrator_used"] == "exact" and rk.attrs["integrator_used"] == "rk4"
    np.testing.assert_array_equal(ex["limit_depth_m"].values, rk["limit_depth_m"].values)


def test_cli_simulate_a_cut_exactly(tmp_path, capsys):
    import xarray as xr
    from cli_output import json_out

    from boringbar.cli.main import main

    out = tmp_path / "cut"
    assert main(["simulate", "--bar", "solid", "--rpm", "1200", "--depth-mm", "0.05",
                 "--duration-s", "0.1", "--integrator", "exact", "--out", str(out),
                 "--json"]) == 0
    s = json_out(capsys)
    assert s["integrator"] == "exact" and s["cutting"]["chatter"] is False
    assert s["cutting"]["delay_interpolation"] == "cubic"
    assert abs(s["energy"]["balance_relative"]) < 1e-9
    with xr.open_dataset(out / "run.nc") as ds:
        assert json.loads(ds.attrs["config"])["integrator"] == "exact"
        assert float(ds["force_n"].max()) > 0


def test_cli_lobes_exact(tmp_path, capsys):
    import xarray as xr

    from boringbar.cli.main import main

    out = tmp_path / "lobes"
    assert main(["lobes", "--bar", "solid", "--rpm", "1250", "--method", "search",
                 "--examples", "--duration-s", "0.2", "--dt-s", "4e-6", "--max-depth-mm",
                 "0.5", "--integrator", "exact", "--criterion", "zero", "--out", str(out)]) == 0
    with xr.open_dataset(out / "lobes.nc") as ds:
        assert ds.attrs["integrator"] == "exact"
        assert float(ds["limit_depth_m"].max()) > 0
    with xr.open_dataset(out / "examples.nc") as ex:
        assert {c["integrator"] for c in json.loads(ex.attrs["configs"])} == {"exact"}


def test_study_file_with_an_exact_cut_loads(tmp_path):
    from boringbar.studies.load import load_study
    from boringbar.studies.registry import ANALYSES

    path = tmp_path / "s.toml"
    path.write_text('[study]\nanalysis = "lobes"\n[run]\nintegrator = "exact"\n'
                    '[analysis]\ncriterion = "zero"\n')
    study = load_study(path)
    assert ANALYSES["lobes"].plan(study).context["integration"].integrator == "exact"
    path.write_text('[study]\nanalysis = "sensitivity"\n[run]\nintegrator = "exact"\n'
                    '[analysis]\ncuts = true\n')
    assert ANALYSES["sensitivity"].plan(load_study(path)).points


# --- slow: the time-domain limit -------------------------------------------------------
@pytest.mark.slow
def test_exact_time_domain_limit_equals_rk4s_on_the_published_grid():
    """The published verdict (2 s from rest) bisected at the 15 published speeds from the
    same bracket as tests/test_chatter.py, exact (H = 2 us) and RK4 (dt = 1 us): the
    exact limits pass the same checks (below analytic x 0.99 stable, within 4 % of the
    growth-rate prediction) and equal RK4's to the bisection's resolution."""
    import test_chatter as tc

    from boringbar.analysis.lobes import PUBLISHED_RPM

    system = make_system("solid")
    speeds = tuple(PUBLISHED_RPM)
    rk = tc.solid_limits(speeds, 2.0)

    def chatters(depth, rpm):
        f = Regenerative(depth_m=depth, rpm=rpm, stop_at_zero=True)
        return simulate(system, f, duration_s=2.0, dt_s=2e-6, integrator="exact").cutting["chatter"]

    def one(r):
        lo, hi = r["analytic"] * (1 - tc.SMALL), r["predicted"] * (1 + tc.PRED_TOL)
        out = dict(r, lo_chatters=chatters(lo, r["rpm"]), hi_chatters=chatters(hi, r["rpm"]))
        while hi - lo > tc.RESOLUTION:
            mid = 0.5 * (lo + hi)
            if chatters(mid, r["rpm"]):
                hi = mid
            else:
                lo = mid
        return dict(out, lo=lo, hi=hi, limit=0.5 * (lo + hi))

    with tc.ThreadPoolExecutor(tc.WORKERS) as pool:
        ex = list(pool.map(one, rk))
    tc.check_limits(ex)
    for e, r in zip(ex, rk, strict=True):
        assert abs(e["limit"] - r["limit"]) <= tc.RESOLUTION, (e["rpm"], e["limit"], r["limit"])

"""Cutting laws, force noise and a boring job's speeds (docs/model.md, sections 4.3-4.5).

The kernel's Kienzle law and noise against the slow reference (tests/naive.py); the
linear law bit for bit whatever the new slots say when they are off; closed forms of a
long stable cut (the force settles to the law at the feed, the tip to F(h_m) / k);
the law linearised at the feed is the linear law with the slope Kr_eff, which the
analytic lobes take; the noise's statistics, determinism and continuation across
kernel calls; what is refused; boring speeds from the bar's diameter.
"""

from __future__ import annotations

import math

import naive
import numpy as np
import pytest
from cli_output import assert_one_line_error, json_out

import boringbar as bb
from boringbar import Initial, make_system, simulate
from boringbar.analysis.lobes import LobesOptions, lobes
from boringbar.analysis.speeds import BORE_RATIO, boring_speeds
from boringbar.cli.main import main
from boringbar.model.bar import ModalModel
from boringbar.model.cutting import (
    DEFAULT_CUTTING_SPEED_M_S,
    H_REF_M,
    KR_ALUMINIUM,
    RADIAL_RATIO,
    WORKPIECES,
    CuttingLaw,
    cutting_law,
)
from boringbar.model.forcing import Regenerative
from boringbar.reference.stability import limit_at_speeds
from boringbar.simulate import Integration, pack_cut
from boringbar.simulate import layout as L
from boringbar.simulate.kernels import Records, Steps, run_exact, run_rk4
from boringbar.studies.load import study_from_dict
from boringbar.studies.schema import StudyError

FEED = 0.1e-3
DT = 1e-6
RPM_FAST = 60.0 / 3000e-6  # tau = 3000 steps


def static_deflection(system, force_n: float) -> float:
    """W_s = F sum psi_L^2 / K: the tip under a static force F at the tip (m)."""
    bar = system.bar
    return force_n * float(np.sum(bar.psi_tip**2 / bar.stiffness_n_m))


def cut_params(system, forcing) -> np.ndarray:
    return pack_cut(system, forcing, DT, 0.0)


def fresh_met() -> np.ndarray:
    met = np.zeros(L.MET_SIZE)
    met[L.STEADY_MAX_W], met[L.STEADY_MIN_W], met[L.FIRST_ZERO_T] = -np.inf, np.inf, -1.0
    return met


def scratch(met: np.ndarray) -> Records:
    """Records that keep no history, no strobe and one impact and stick row, with ``met``."""
    return Records(np.zeros((0, 6)), np.zeros((1, 3)), np.zeros((1, 2)), np.zeros((0, 5)), met)


def kernel_in_chunks(p, x0, n_steps: int, chunks) -> tuple[np.ndarray, np.ndarray]:
    """The kernel called once per chunk length in ``chunks`` on one history buffer."""
    x, met = np.array(x0, dtype=float), fresh_met()
    buf = np.zeros((int(math.ceil(p[L.N_REV] * p[L.TAU] / DT)) + 3, 2))
    done = 0
    for k in chunks:
        run_rk4(p, x, Steps(done * DT, DT, k, 0), scratch(met), buf)
        done += k
    assert done == n_steps
    return x, met


# --- the laws ---------------------------------------------------------------------------
def test_kienzle_law_in_si_is_the_catalogues_law_in_mm():
    law = CuttingLaw.kienzle("steel")
    w = WORKPIECES["steel"]
    b, h = 2e-3, 0.15e-3
    # the catalogue: F_c = kc1.1 b h^(1 - mc), b and h in mm, kc1.1 in N/mm^2
    catalogue = (w.kc11_pa / 1e6) * (b * 1e3) * (h * 1e3) ** (1 - w.mc)
    assert law.force_n(b, h) == pytest.approx(RADIAL_RATIO * catalogue, rel=1e-13)
    assert law.force_n(b, 0.0) == 0.0 and law.force_n(b, -1e-5) == 0.0
    # the core's coefficient: F = KR_B h^(1 - mc)
    assert law.kernel_coefficient(b) * h ** (1 - w.mc) == pytest.approx(law.force_n(b, h),
                                                                        rel=1e-13)
    # the slope at the feed, against a central difference
    d = 1e-9
    slope = (law.force_n(b, FEED + d) - law.force_n(b, FEED - d)) / (2 * d) / b
    assert law.linear_coefficient_pa(FEED) == pytest.approx(slope, rel=1e-7)
    assert law.linear_coefficient_pa(FEED) == pytest.approx(
        (1 - w.mc) * RADIAL_RATIO * w.kc11_pa * (FEED / H_REF_M) ** -w.mc, rel=1e-15)
    # the linear law's slope is Kr itself
    assert CuttingLaw.linear().linear_coefficient_pa(FEED) == KR_ALUMINIUM


def test_every_material_has_constants_speeds_and_a_source():
    assert {"steel", "aluminium", "cast-iron", "titanium"} <= set(WORKPIECES)
    for name, w in WORKPIECES.items():
        assert 300e6 <= w.kc11_pa <= 3000e6 and 0.1 <= w.mc <= 0.4, name
        low, high = w.cutting_speed_m_s
        assert 0 < low < high < 20.0, name  # m/s: at most 1200 m/min
        assert "group" in w.source and w.speed_source, name
        law = CuttingLaw.kienzle(name)
        assert law.workpiece == name and law.source == w.source
    own = CuttingLaw.kienzle(kc11_pa=1.6e9, mc=0.25, radial_ratio=0.4)
    assert own.coefficient_pa == pytest.approx(0.4 * 1.6e9) and own.workpiece is None


def test_unknown_materials_and_mixed_laws_are_refused():
    with pytest.raises(bb.ParameterError, match=r"workpiece = 'brass'.*steel, alloy-steel"):
        Regenerative(depth_m=1e-4, rpm=1000.0, workpiece="brass")
    with pytest.raises(bb.ParameterError, match="brass"):
        CuttingLaw.kienzle("brass")
    with pytest.raises(bb.ParameterError, match="brass"):
        LobesOptions(rpm=(1000.0,), workpiece="brass")
    with pytest.raises(bb.ParameterError, match=r"kr_pa = .* workpiece = 'steel'.*give one"):
        Regenerative(depth_m=1e-4, rpm=1000.0, kr_pa=900e6, workpiece="steel")
    with pytest.raises(bb.ParameterError, match="kc11_pa and mc"):
        CuttingLaw.kienzle(kc11_pa=1.5e9)
    with pytest.raises(bb.ParameterError, match="brings its own"):
        CuttingLaw.kienzle("steel", mc=0.3)
    with pytest.raises(bb.ParameterError, match=r"mc = 1\.0"):
        CuttingLaw.kienzle(kc11_pa=1.5e9, mc=1.0)
    for bad in ({"force_noise": 1.0}, {"force_noise": -0.1}, {"noise_interval_s": 0.0},
                {"noise_seed": 1.5}, {"noise_seed": -1}):
        with pytest.raises(bb.ParameterError, match=next(iter(bad))):
            Regenerative(depth_m=1e-4, rpm=1000.0, **bad)


# --- the kernel ---------------------------------------------------------------------------
def test_kernel_matches_slow_reference_with_kienzle_and_noise():
    """Kienzle's law (steel) with 20 % noise on 37-step intervals: the kernel's W, W' and
    force in every step against tests/naive.py, through a chattering cut (h = 0 from
    7.4 ms on, where the law's power meets 0)."""
    system = make_system("solid")
    forcing = Regenerative(depth_m=1e-3, rpm=RPM_FAST, workpiece="steel", force_noise=0.2,
                           noise_interval_s=37e-6, noise_seed=11)
    n_steps = 8000
    run = simulate(system, forcing, duration_s=n_steps * DT, dt_s=DT, record_every=1)
    p = cut_params(system, forcing)
    _, X, force, first_zero, zero_steps = naive.regenerative_run(p, run.initial.x, DT, n_steps)
    n = system.bar.n_modes
    ref = np.column_stack([naive.tip(p, X[1:]), X[1:, n:2 * n] @ system.bar.psi_tip, force])
    got = run.history[:, [1, 2, 5]]
    err = np.max(np.abs(got - ref) / np.max(np.abs(ref), axis=0))
    assert err < 1e-10, f"kernel vs reference {err:.2e}"  # measured 2e-15
    c = run.cutting
    assert c["first_zero_time_s"] == pytest.approx(first_zero, abs=1e-12)
    assert c["steps_with_zero_force"] == zero_steps > 100


def test_off_law_and_noise_slots_leave_the_linear_cut_bit_for_bit():
    """Kienzle's law with m_c = 0 and K = Kr is the linear law, and noise of std 0 (with
    any seed and interval) no noise: the same bits as the published cut."""
    system = make_system("solid")
    kw = {"depth_m": 1e-3, "rpm": RPM_FAST}
    runs = [simulate(system, Regenerative(**f, **kw), duration_s=0.01, record_every=1)
            for f in ({}, {"workpiece": CuttingLaw.kienzle(kc11_pa=KR_ALUMINIUM, mc=0.0,
                                                          radial_ratio=1.0)},
                      {"noise_seed": 99, "noise_interval_s": 3e-5})]
    for r in runs[1:]:
        np.testing.assert_array_equal(r.history, runs[0].history)
        np.testing.assert_array_equal(r.final.x, runs[0].final.x)
        assert r.metrics == runs[0].metrics


def test_noise_is_deterministic_and_continues_across_kernel_calls():
    system = make_system("solid")
    forcing = Regenerative(depth_m=1e-3, rpm=RPM_FAST, workpiece="steel", force_noise=0.05,
                           noise_interval_s=53e-6, noise_seed=7)
    p = cut_params(system, forcing)
    x0 = np.zeros(2 * system.bar.n_modes + 2)
    n = 12000
    x1, met1 = kernel_in_chunks(p, x0, n, [n])
    x2, met2 = kernel_in_chunks(p, x0, n, [1, 52, 4000, 3947, 4000])  # cuts mid-interval
    np.testing.assert_array_equal(x1, x2)
    for slot in (L.MAX_FORCE, L.N_ZERO_STEPS, L.FIRST_ZERO_T, L.W_FORCE, L.STEPS_DONE):
        assert met1[slot] == met2[slot]
    p_again = cut_params(system, forcing)
    np.testing.assert_array_equal(kernel_in_chunks(p_again, x0, n, [n])[0], x1)
    p_other = p.copy()
    p_other[L.NOISE_SEED] = 8
    assert not np.array_equal(kernel_in_chunks(p_other, x0, n, [n])[0], x1)


def test_the_realised_force_has_the_noise_statistics():
    """A long stable cut (5 % of the limit, static start): the force over F(h_m) is
    1 + eps, one sample an interval, eps drawn as tests/naive.py draws it."""
    system = make_system("solid")
    law = CuttingLaw.kienzle("cast-iron")
    b = 0.05 * float(limit_at_speeds(system, [1200.0], law.linear_coefficient_pa(FEED))[0])
    std, interval = 0.05, 100
    forcing = Regenerative(depth_m=b, rpm=1200.0, workpiece="cast-iron", start="static",
                           force_noise=std, noise_interval_s=interval * DT, noise_seed=3)
    run = simulate(system, forcing, duration_s=1.0, record_every=interval)
    ratio = run.history[:, 5] / law.force_n(b, FEED)
    p = cut_params(system, forcing)
    steps = np.arange(1, len(ratio) + 1) * interval - 1  # the step each row ends
    expected = np.array([naive.noise_gain(p, DT, int(k)) for k in steps])
    # the chip's own variation (the bar's response to the noise, fed back) is far below
    # the noise at 5 % of the limit: measured 2 % of std at most
    assert np.max(np.abs(ratio - expected)) < 0.05 * std
    samples = len(ratio)
    assert abs(np.mean(ratio) - 1.0) < 4 * std / math.sqrt(samples)
    assert np.std(ratio) == pytest.approx(std, rel=0.05)


# --- closed forms of a stable Kienzle cut ---------------------------------------------------
def test_a_stable_kienzle_cut_settles_to_the_law_at_the_feed():
    """Below the limit the chip settles to h_m: the force to F(h_m) = K b h_m (h_m /
    1 mm)^(-m_c) and the tip to the static deflection F(h_m) sum psi^2 / K."""
    system = make_system("solid")
    law = CuttingLaw.kienzle("titanium")
    b = 0.3 * float(limit_at_speeds(system, [1200.0], law.linear_coefficient_pa(FEED))[0])
    forcing = Regenerative(depth_m=b, rpm=1200.0, workpiece="titanium", start="static")
    run = simulate(system, forcing, duration_s=1.0, initial=Initial(tip_velocity_m_s=1e-3),
                   record_every=100)
    f_feed = law.force_n(b, FEED)
    c = run.cutting
    assert c["force_at_feed_n"] == f_feed
    assert c["static_deflection_m"] == pytest.approx(static_deflection(system, f_feed),
                                                     rel=1e-12)
    assert not c["chatter"]
    assert run.history[-1, 5] == pytest.approx(f_feed, rel=1e-6)
    assert c["mean_force_n"] == pytest.approx(f_feed, rel=1e-4)
    assert run.metrics["mean_tip_m"] == pytest.approx(c["static_deflection_m"], rel=1e-4)


def test_the_law_linearised_at_the_feed_is_the_linear_law_with_its_slope():
    """A small vibration about the steady cut obeys the linear law with Kr_eff = dF/dh / b
    at h_m (what the analytic lobes take): a Kienzle cut's W - W_s follows a linear cut's
    with Kr_eff to the order of the vibration over h_m, and not a linear cut's with the
    secant F(h_m) / (b h_m)."""
    system = make_system("solid")
    law = CuttingLaw.kienzle("steel")
    kr_eff = law.linear_coefficient_pa(FEED)
    b = 0.8 * float(limit_at_speeds(system, [1200.0], kr_eff)[0])
    kick = Initial(tip_velocity_m_s=2e-3)  # |W - W_s| about 6e-7 m, 0.6 % of h_m

    def deviation(**law_kw):
        f = Regenerative(depth_m=b, rpm=1200.0, start="static", **law_kw)
        r = simulate(system, f, duration_s=0.2, initial=kick, record_every=10)
        return r.history[:, 1] - r.cutting["static_deflection_m"]

    kienzle = deviation(workpiece="steel")
    slope = deviation(kr_pa=kr_eff)
    secant = deviation(kr_pa=law.force_n(b, FEED) / (b * FEED))
    scale = np.max(np.abs(slope))
    assert np.max(np.abs(kienzle - slope)) < 1e-3 * scale  # measured 2e-5
    assert np.max(np.abs(kienzle - secant)) > 0.1 * scale  # measured 0.36


def test_the_analytic_lobes_take_the_slope_at_the_feed():
    system = make_system("solid")
    opts = LobesOptions(rpm=(1100.0, 1200.0), workpiece="steel", max_depth_m=0.5e-3)
    kr_eff = CuttingLaw.kienzle("steel").linear_coefficient_pa(FEED)
    assert opts.analytic_kr_pa == kr_eff
    assert LobesOptions().analytic_kr_pa == KR_ALUMINIUM
    ds = lobes([system], opts, integration=Integration(duration_s=0.05))
    np.testing.assert_array_equal(ds["analytic_limit_m"].values[0],
                                  limit_at_speeds(system, list(opts.rpm), kr_eff))
    assert ds.attrs["analytic_kr_pa"] == kr_eff and "steel" in ds.attrs["cutting_law"]
    assert "kr_pa" not in ds.attrs and ds.attrs["workpiece"] == "steel"


# --- what is refused --------------------------------------------------------------------------
def test_the_exact_integrator_refuses_kienzle_and_noise():
    system = make_system("solid")
    for kw, what in (({"workpiece": "steel"}, "Kienzle"), ({"force_noise": 0.02}, "noise")):
        with pytest.raises(bb.ParameterError, match=rf"integrator = 'exact'.*{what}"):
            simulate(system, Regenerative(depth_m=1e-4, rpm=1200.0, **kw), duration_s=0.01,
                     integrator="exact")
    # a lobe study refuses it before its first run
    with pytest.raises(bb.ParameterError, match="integrator = 'exact'"):
        lobes([system], LobesOptions(rpm=(1200.0,), workpiece="steel"),
              integration=Integration(integrator="exact"))
    # the core refuses them too
    p = cut_params(system, Regenerative(depth_m=1e-4, rpm=1200.0))
    p[L.CUT_MC] = 0.2
    x = np.zeros(2 * system.bar.n_modes + 2)
    with pytest.raises(ValueError, match="CUT_MC"):
        run_exact(p, x, Steps(0.0, DT, round(1e-3 / DT), 0), scratch(fresh_met()))


@pytest.mark.parametrize("slot, value, message", [
    ("CUT_MC", 1.0, "CUT_MC"), ("CUT_MC", -0.1, "CUT_MC"), ("NOISE_STD", 1.5, "NOISE_STD"),
    ("NOISE_SEED", 0.5, "NOISE_SEED"), ("NOISE_INTERVAL", 0.0, "NOISE_INTERVAL")])
def test_the_core_checks_the_law_and_noise_slots(slot, value, message):
    system = make_system("solid")
    p = cut_params(system, Regenerative(depth_m=1e-4, rpm=1200.0, force_noise=0.01))
    p[getattr(L, slot)] = value
    buf = np.zeros((int(math.ceil(3 * p[L.TAU] / DT)) + 3, 2))
    with pytest.raises(ValueError, match=message):
        run_rk4(p, np.zeros(2 * system.bar.n_modes + 2), Steps(0.0, DT, 10, 0),
                scratch(fresh_met()), buf)


# --- boring speeds -------------------------------------------------------------------------
def test_boring_speeds_come_from_the_bore_and_the_materials_cutting_speeds():
    system = make_system("solid")
    d_max = max(s.diameter_m for s in system.spec.bar.sections)  # 25 mm
    job = boring_speeds(system, "steel", n=20)
    bore = BORE_RATIO * d_max
    assert job.bore_diameter_m == pytest.approx(bore)
    low, high = WORKPIECES["steel"].cutting_speed_m_s
    assert job.cutting_speed_range_m_s == (low, high)
    # rpm = 1000 v_c / (pi D_mm) with v_c in m/min: 150 m/min in a 31.25 mm bore, 1528 rpm
    assert job.rpm[0] == round(1000 * low * 60 / (math.pi * bore * 1e3)) == 1528
    assert job.rpm[-1] == round(1000 * high * 60 / (math.pi * bore * 1e3))
    assert len(job.rpm) == 20 and np.all(np.diff(job.rpm) > 0)
    np.testing.assert_allclose(job.cutting_speed_m_s, math.pi * bore * np.array(job.rpm) / 60)
    # the system file alone gives the same; no workpiece: the default range
    assert boring_speeds(system.spec, "steel", n=20) == job
    assert boring_speeds(system).cutting_speed_range_m_s == DEFAULT_CUTTING_SPEED_M_S
    assert boring_speeds(system, "titanium").rpm[-1] < job.rpm[0]
    law = cutting_law(KR_ALUMINIUM, "aluminium")
    assert boring_speeds(system, law).cutting_speed_range_m_s == \
        WORKPIECES["aluminium"].cutting_speed_m_s


def test_a_bar_without_a_diameter_has_no_boring_speeds():
    tap = ModalModel.from_tap_test(500.0, 0.02, tip_stiffness_n_m=1.5e6)
    with pytest.raises(bb.ParameterError, match="tap-test"):
        boring_speeds(make_system("solid", modal=tap), "steel")
    with pytest.raises(bb.ParameterError, match="brass"):
        boring_speeds(make_system("solid"), "brass")


# --- the command line and study files --------------------------------------------------------
def test_cli_takes_a_workpiece_for_the_analytic_lobes_and_a_cut(tmp_path, capsys):
    out = tmp_path / "a"
    assert main(["lobes", "--analytic", "--bar", "solid", "--workpiece", "steel", "--rpm",
                 "1000,1200", "--out", str(out), "--json"]) == 0
    s = json_out(capsys)
    assert s["kr_pa"] == CuttingLaw.kienzle("steel").linear_coefficient_pa(FEED)
    assert "Kienzle" in s["cutting_law"]
    out = tmp_path / "s"
    assert main(["simulate", "--bar", "solid", "--rpm", "1200", "--depth-mm", "0.05",
                 "--workpiece", "cast-iron", "--duration-s", "0.02", "--out", str(out),
                 "--json"]) == 0
    c = json_out(capsys)["cutting"]
    assert "cast-iron" in c["cutting_law"]
    assert c["force_at_feed_n"] == CuttingLaw.kienzle("cast-iron").force_n(0.05e-3, FEED)


@pytest.mark.parametrize("argv, name", [
    (["lobes", "--analytic", "--workpiece", "brass"], "--workpiece"),
    (["lobes", "--bar", "solid", "--workpiece", "steel", "--kr-mpa", "900"], "--kr-mpa"),
    (["simulate", "--rpm", "1200", "--depth-mm", "0.05", "--workpiece", "brass"],
     "--workpiece"),
    (["simulate", "--workpiece", "steel"], "--workpiece"),
    (["simulate", "--rpm", "1200", "--depth-mm", "0.05", "--workpiece", "steel",
      "--integrator", "exact"], "exact"),
    (["lobes", "--bar", "solid", "--workpiece", "steel", "--integrator", "exact"], "exact"),
])
def test_cli_refuses_a_bad_workpiece_in_one_line(tmp_path, capsys, argv, name):
    out = tmp_path / "out"
    assert_one_line_error(main, [*argv, "--out", str(out)], out, name, capsys)


def _lobes_study(forcing: dict, run: dict | None = None) -> dict:
    return {"study": {"analysis": "lobes"}, "forcing": {"feed_mm": 0.1, **forcing},
            "bar": {"kind": "solid"}, "run": {"duration_s": 0.05, **(run or {})},
            "grid": {"rpm": [1000.0, 1200.0]}}


def test_study_files_take_a_workpiece():
    study = study_from_dict(_lobes_study({"workpiece": "titanium"}))
    assert study.value("workpiece") == "titanium"
    with pytest.raises(StudyError, match=r"forcing\.workpiece.*brass"):
        study_from_dict(_lobes_study({"workpiece": "brass"}))
    with pytest.raises(StudyError, match=r"kr_mpa.*workpiece.*give one"):
        study_from_dict(_lobes_study({"workpiece": "steel", "kr_mpa": 900.0}))
    with pytest.raises(StudyError, match=r"workpiece.*rk4"):
        study_from_dict(_lobes_study({"workpiece": "steel"}, {"integrator": "exact"}))
    # a study without a workpiece keeps its configuration (and its hash) as before
    assert "workpiece" not in study_from_dict(_lobes_study({})).to_dict()["forcing"]

"""The compliant (Hertz) contact of the ball with its plugs (docs/model.md, section 2.6).

Truths that do not come from our code: Hunt and Crossley's small-damping limit
e = 1 - (2/3) alpha, an independent fixed-step integration of the dimensionless
contact, Hertz's closed-form duration and peak force of an elastic impact (Johnson),
the restitution each contact must restore, the energy balance with the contact's
elastic energy, and convergence to the impact law as the stiffness rises, at the order
the contact's duration sets (K^-2/5).
"""

from __future__ import annotations

import json
import math
import tomllib

import numpy as np
import pytest
from cli_output import assert_one_line_error

import boringbar as bb
from boringbar._validate import ParameterError
from boringbar.cli.main import main
from boringbar.model.bar import ModalModel
from boringbar.model.contact import hertz_contact_time_s, hertz_peak_force_n
from boringbar.model.dampers import NO_FRICTION, ImpactDamper
from boringbar.model.system import System, make_system
from boringbar.model.system_file import SystemFileError, parse_system, published_file_text
from boringbar.orbits.shooting import make_flow
from boringbar.simulate import Initial, pack, setup_run, simulate_batch
from boringbar.simulate import layout as L
from boringbar.simulate.kernels import (
    Records,
    Steps,
    hunt_crossley_alpha,
    hunt_crossley_restitution,
    regime_matrix,
    run_exact,
    run_rk4,
)

GAP = 0.5e-3


def records(su) -> Records:
    """The arrays a packed run writes, its contact rows among them."""
    return Records(su.rec, su.imp, su.stick, su.stb, su.met, contact=su.contact)
SPEED = 0.5  # m/s, the ball's start relative to the bar


def free_pair(restitution, *, dt_s=1e-7, stiffness=None, bar=None, duration_s=8e-4,
              contact="hertz", integrator="rk4"):
    """A ball thrown at 0.5 m/s across its gap at a bar that barely resists (a 2 Hz mode
    of 0.5 kg, undamped): during a contact of some 70 us the pair is two free masses."""
    bar = bar or ModalModel.from_tap_test(2.0, 0.0, tip_mass_kg=0.5)
    ball = ImpactDamper.ball("carbide", gap_m=GAP, restitution=restitution,
                             friction=NO_FRICTION, contact=contact,
                             contact_stiffness_n_m1_5=stiffness)
    system = System(bar, ball, "physical")
    run = bb.simulate(system, bb.Harmonic(amplitude_n=0.0, ratio=1.0), duration_s=duration_s,
                      dt_s=dt_s, initial=Initial(ball_velocity_m_s=SPEED), steady_fraction=1.0,
                      record_every=0, integrator=integrator)
    meff = 1.0 / (1.0 / ball.mass_kg + float((bar.psi_damper**2 / bar.mass_kg).sum()))
    return run, meff, ball.hertz_stiffness_n_m1_5


# --- Hunt and Crossley's damping for a restitution ----------------------------------------
def test_small_damping_gives_hunt_and_crossleys_limit():
    for alpha in (1e-3, 1e-4):
        e = hunt_crossley_restitution(alpha)
        assert abs((1.0 - e) / alpha - 2.0 / 3.0) < 2 * alpha


def test_alpha_restores_e_in_an_independent_integration():
    """alpha(e) from the package, e(alpha) again by a fixed-step RK4 written here."""
    for e in (0.9, 0.7, 0.3):
        alpha, h, x, v = hunt_crossley_alpha(e), 2e-4, 0.0, 1.0

        def acc(x, v, a=alpha):
            return -max(x, 0.0) ** 1.5 * max(0.0, 1.0 + a * v)

        while not (x < 0.0 and v < 0.0):
            k1 = (v, acc(x, v))
            k2 = (v + h / 2 * k1[1], acc(x + h / 2 * k1[0], v + h / 2 * k1[1]))
            k3 = (v + h / 2 * k2[1], acc(x + h / 2 * k2[0], v + h / 2 * k2[1]))
            k4 = (v + h * k3[1], acc(x + h * k3[0], v + h * k3[1]))
            x += h / 6 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0])
            v += h / 6 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1])
        assert abs(-v - e) < 1e-6


# --- one contact against the closed forms ------------------------------------------------
def test_an_elastic_impact_lasts_and_peaks_as_hertz_says():
    run, meff, k = free_pair(1.0)
    (start, wall, vin, duration, peak, vout), = run.contacts
    assert wall == 1.0 and start == pytest.approx(GAP / 2 / SPEED, rel=1e-6)
    assert vin == pytest.approx(SPEED, rel=1e-6)
    assert duration == pytest.approx(hertz_contact_time_s(meff, k, vin), rel=1e-6)
    assert peak == pytest.approx(hertz_peak_force_n(meff, k, vin), rel=1e-4)
    assert vout == pytest.approx(vin, rel=1e-6)


@pytest.mark.parametrize("e", [0.9, 0.7, 0.5, 0.2])
def test_each_contact_restores_the_restitution(e):
    run, meff, _ = free_pair(e)
    (_, _, vin, duration, _, vout), = run.contacts
    assert vout / vin == pytest.approx(e, abs=1e-6)
    assert 5e-5 < duration < 1e-4
    # the pair's energy: the contact's damping takes what the impact law's loss is
    assert abs(run.energy["balance_relative"]) < 1e-7
    assert run.energy["dissipated_impacts_j"] == pytest.approx(
        0.5 * (1 - e * e) * meff * vin**2, rel=1e-5)


def test_the_impact_law_is_the_limit_of_a_stiffening_contact_at_order_two_fifths():
    """The ball's position after one impact against the exact impact law: the contact
    shifts it by an amount proportional to the contact's duration, K^-2/5."""
    bar = ModalModel.from_tap_test(500.0, 0.01, tip_stiffness_n_m=3e6, damper_ratio=0.6)
    ref, meff, k0 = free_pair(0.7, bar=bar, duration_s=1.5e-3, contact="impact",
                              integrator="exact")
    errors = []
    for scale in (10.0, 100.0, 1000.0):
        tc = hertz_contact_time_s(meff, k0 * scale, SPEED)
        dt = 1.5e-3 / math.ceil(1.5e-3 / (tc / 400))
        run, _, _ = free_pair(0.7, bar=bar, duration_s=1.5e-3, stiffness=k0 * scale, dt_s=dt)
        errors.append(abs(run.final.x[2] - ref.final.x[2]))  # y, the ball
    orders = np.log10(np.array(errors[:-1]) / errors[1:])
    assert np.all(np.abs(orders - 0.4) < 0.02), orders


# --- a run of the published bar -----------------------------------------------------------
def test_a_hertz_run_balances_its_energy_and_reports_its_contacts():
    system = make_system("ball", gap_m=GAP, contact="hertz")
    run = bb.simulate(system, bb.Harmonic(amplitude_n=20.0, ratio=1.0), duration_s=0.05,
                      dt_s=5e-7, integrator="auto")
    assert run.integrator == "rk4"
    assert abs(run.energy["balance_relative"]) < 1e-6
    c = run.summary()["contact"]
    assert c["n_impacts"] == len(run.contacts) > 0
    assert c["n_impacts"] == run.metrics["impacts_plus"] + run.metrics["impacts_minus"]
    assert 2e-5 < c["duration_median_s"] < 2e-4 and c["peak_force_max_n"] > 0
    assert c["max_force_whole_run_n"] >= c["peak_force_max_n"]
    ds = run.to_xarray()
    assert ds["contact_duration_s"].size == len(run.contacts)
    assert "contact" not in bb.simulate(make_system("ball", gap_m=GAP),
                                        bb.Harmonic(amplitude_n=20.0), duration_s=0.01,
                                        integrator="rk4").summary()


def test_a_run_in_two_calls_is_one_run_through_a_contact():
    """The contact under way is kept in met between calls, with its damping.  (A free
    vibration: a harmonic force's phase is re-synchronised counting a call's own steps.)"""
    system = make_system("ball", gap_m=GAP, contact="hertz")
    forcing = bb.Harmonic(amplitude_n=0.0)
    start = Initial(tip_velocity_m_s=1.0)
    whole = setup_run(system, forcing, 0.01, 1e-6, start, 0, 1.0, False, "rk4")
    run_rk4(whole.p, whole.x, Steps(0.0, 1e-6, 10_000, 0), records(whole))
    rows = whole.contact[:int(whole.met[L.N_CONTACT_REC])]
    split = int(round((rows[1, 0] + rows[1, 3] / 2) / 1e-6))  # inside the second contact
    parts = setup_run(system, forcing, 0.01, 1e-6, start, 0, 1.0, False, "rk4")
    for t0, steps in ((0, split), (split, 10_000 - split)):
        run_rk4(parts.p, parts.x, Steps(t0 * 1e-6, 1e-6, steps, 0), records(parts))
    assert np.array_equal(parts.x, whole.x)
    assert parts.met[L.N_CONTACT_REC] == len(rows) and len(rows) > 2
    # (a time is t0 + k dt, rounded once per call: the rows' times agree to round-off)
    np.testing.assert_allclose(parts.contact[:len(rows)], rows, rtol=1e-13, atol=0)


# --- bad input ----------------------------------------------------------------------------
@pytest.mark.parametrize("argv, name", [
    (["--contact-stiffness", "0"], "--contact-stiffness"),
    (["--contact-stiffness", "-1e10"], "--contact-stiffness"),
    (["--integrator", "exact"], "integrator = 'exact'"),
    (["--restitution", "0.01"], "restitution"),
    (["--contact-stiffness", "1e15"], "dt_s"),
])
def test_the_command_line_refuses_a_bad_contact(argv, name, tmp_path, capsys):
    out = tmp_path / "out"
    assert_one_line_error(main, ["simulate", "--contact", "hertz", *argv, "--out", str(out)],
                          out, name, capsys)


def test_a_hertz_stiffness_given_to_the_impact_law_is_refused(tmp_path, capsys):
    out = tmp_path / "out"
    assert_one_line_error(main, ["simulate", "--contact-stiffness", "2e10", "--out", str(out)],
                          out, "contact_stiffness_n_m1_5 = 20000000000.0 is a Hertz", capsys)
    with pytest.raises(ParameterError, match="--contact hertz"):
        make_system("ball", contact="impact", contact_stiffness_n_m1_5=2e10)


def test_python_refuses_a_bad_contact():
    with pytest.raises(ParameterError, match="contact_stiffness_n_m1_5"):
        ImpactDamper(contact="hertz", contact_stiffness_n_m1_5=0.0)
    with pytest.raises(ParameterError, match="ball contact"):
        ImpactDamper(contact="soft")
    with pytest.raises(ParameterError, match="integrator = 'exact'"):
        free_pair(0.7, integrator="exact")
    with pytest.raises(ParameterError, match="contact = 'hertz'"):
        make_flow(make_system("ball", contact="hertz"), bb.Harmonic(amplitude_n=10.0))


def test_a_system_file_gives_the_contact():
    d = tomllib.loads(published_file_text())
    d["ball"].update(contact="hertz", contact_stiffness_n_m1_5=2e10, plug_material="carbide")
    spec = parse_system(d)
    system = make_system("ball", spec=spec)
    assert system.damper.contact == "hertz" and system.damper.hertz_stiffness_n_m1_5 == 2e10
    assert System.from_dict(system.to_dict()).damper == system.damper
    for key, value in (("contact_stiffness_n_m1_5", 0), ("contact", "soft"),
                       ("plug_material", "glass")):
        bad = tomllib.loads(published_file_text())
        bad["ball"].update({"contact": "hertz", key: value})
        with pytest.raises(SystemFileError, match=f"ball.{key}"):
            parse_system(bad)


def test_the_materials_stiffen_the_contact_as_hertz_says():
    carbide = ImpactDamper.ball("carbide", contact="hertz")
    steel = ImpactDamper.ball("steel", contact="hertz")
    # 4/3 E* sqrt(R): carbide (580 GPa, 0.22) and steel (200 GPa, 0.29) on a steel plug
    e_star = 1 / ((1 - 0.22**2) / 580e9 + (1 - 0.29**2) / 200e9)
    assert carbide.hertz_stiffness_n_m1_5 == pytest.approx(4 / 3 * e_star * math.sqrt(7.5e-3))
    assert steel.hertz_stiffness_n_m1_5 < carbide.hertz_stiffness_n_m1_5


def test_the_core_refuses_a_contact_where_it_has_none():
    system = make_system("ball", gap_m=GAP, contact="hertz")
    p = pack(system, 3000.0, 10.0, 1e-6)
    assert p[L.CONTACT_K] > 0
    with pytest.raises(ValueError, match="CONTACT_K"):
        regime_matrix(p, 0.0)
    su = setup_run(make_system("ball", gap_m=GAP), bb.Harmonic(amplitude_n=10.0), 0.001, 1e-6,
                   None, 0, 1.0, False, "exact")
    su.p[L.CONTACT_K] = 1e10
    with pytest.raises(ValueError, match="CONTACT_K"):
        run_exact(su.p, su.x, Steps(0.0, 1e-6, 1000, 0), records(su))
    for bad in (-1.0, math.nan, math.inf):
        q = p.copy()
        q[L.CONTACT_K] = bad
        with pytest.raises(ValueError, match="CONTACT_K"):
            run_rk4(q, np.zeros(6), Steps(0.0, 1e-6, 10, 0),
                    Records(np.zeros((0, 6)), np.zeros((10, 3)), np.zeros((10, 2)),
                            np.zeros((0, 5)), np.zeros(L.MET_SIZE)))


def test_a_batch_counts_a_hertz_contacts_impacts_and_says_it_kept_no_rows():
    system = make_system("ball", gap_m=GAP, contact="hertz")
    forcing = bb.Harmonic(amplitude_n=20.0)
    start = Initial(tip_velocity_m_s=1.0)
    one = bb.simulate(system, forcing, duration_s=0.03, record_every=0, integrator="rk4",
                      initial=start)
    batch, = simulate_batch([(system, forcing, start)], duration_s=0.03)
    assert batch.metrics["impacts_total"] == one.metrics["impacts_total"] > 0
    assert batch.final.x.tolist() == one.final.x.tolist()
    c = batch.summary()["contact"]
    assert c["rows_kept"] is False and c["n_impacts"] is None
    assert c["max_force_whole_run_n"] == one.summary()["contact"]["max_force_whole_run_n"]


def test_a_cut_with_a_hertz_ball_reports_its_contacts(tmp_path, capsys):
    out = tmp_path / "cut"
    assert main(["simulate", "--gap-mm", "0.1", "--contact", "hertz", "--rpm", "3000",
                 "--depth-mm", "0.3", "--duration-s", "0.1", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "Hertz contact" in text and "peak force" in text
    summary = json.loads((out / "summary.json").read_text())
    assert summary["contact"]["n_impacts"] > 0 and summary["integrator"] == "rk4"

"""Basins of attraction and sensitivity studies (docs/model.md, section 6).

Known truths: a linear bar has one attractor; the closed-form symmetric
two-impact orbit (Masri-Caughey, 30 N at Omega = omega_n, one mode, no
friction; stable, multiplier 0.915 per half period) attracts the grid cells
around its own state with the pattern '2 symmetric'.
"""

from __future__ import annotations

import json
import math
from dataclasses import replace

import numpy as np
import pytest

from boringbar import Harmonic, Initial, make_system, simulate
from boringbar._validate import ParameterError
from boringbar.analysis.basins import BasinOptions, BasinTolerance, basins, signature
from boringbar.analysis.basins import summary as basin_summary
from boringbar.analysis.sensitivity import (
    Cuts,
    SensitivityOptions,
    above_spread,
    sensitivity,
    summary,
)
from boringbar.execute import Execution
from boringbar.reference.masri_caughey import two_impact_orbit
from boringbar.simulate import Integration

SMALL = BasinOptions((-1.5e-3, 1.5e-3, 4), (-1.5, 1.5, 4), force_n=10.0, ratio=1.01)
SHORT = Integration(duration_s=0.3)


def published_point():
    return make_system("ball", "paper", gap_m=0.5e-3, friction=False), Harmonic(10.0, 1.01)


def test_fractions_sum_to_one_and_serial_equals_parallel():
    system, forcing = published_point()
    assert SMALL.forcing == forcing
    serial = basins(system, SMALL, integration=SHORT, execution=Execution(workers=1))
    parallel = basins(system, SMALL, integration=SHORT, execution=Execution(workers=2))
    assert serial["fraction"].sum() == pytest.approx(1.0, abs=1e-12)
    assert int(serial["count"].sum()) == 16
    assert set(np.unique(serial["attractor"])) == set(serial["attractor_id"].values)
    summary = basin_summary(parallel)
    assert (serial.attrs.pop("workers"), parallel.attrs.pop("workers")) == (1, 2)
    serial.attrs.pop("wall_time_s"), parallel.attrs.pop("wall_time_s")
    assert serial.identical(parallel), "serial and parallel basins differ"
    json.dumps(summary)
    assert sum(a["fraction"] for a in summary["attractors"]) == pytest.approx(1.0)
    assert set(summary["attractors"][0]["representative"]) == {"tip_displacement_m",
                                                               "tip_velocity_m_s"}


def test_linear_bar_has_one_attractor():
    ds = basins(make_system("solid", "paper"),
                BasinOptions((-1.5e-3, 1.5e-3, 3), (-1.5, 1.5, 3), force_n=10.0, ratio=1.01),
                integration=SHORT)
    assert ds.sizes["attractor_id"] == 1
    assert float(ds["fraction"][0]) == 1.0
    assert int(ds["attractor_period"][0]) == 1
    assert ds["attractor_pattern"].values[0] == ""  # no ball, no impact pattern


def test_two_impact_orbit_attracts_its_neighbourhood():
    system = make_system("ball", "physical", n_modes=1, friction=False, gap_m=0.5e-3)
    bar, ball = system.bar, system.damper
    orbit = next(o for o in two_impact_orbit(
        bar.mass_kg[0], bar.stiffness_n_m[0], bar.damping_n_s_m[0],
        bar.psi_tip[0], bar.psi_damper[0],
        ball.mass_kg, ball.gap_m, ball.restitution, 30.0, bar.natural_frequency_rad_s)
        if o.admissible and o.stable)
    w0 = float(orbit.tip(0.0))
    v0 = bar.psi_tip[0] * float(orbit.modal_velocity(0.0))
    h = 1e-9  # y' at t = 0 (mid-flight) by a central difference of the closed form
    y0 = float(orbit.relative_displacement(0.0))
    dy0 = float(orbit.relative_displacement(h) - orbit.relative_displacement(-h)) / (2 * h)
    ds = basins(system, BasinOptions((1.1 * w0, 0.9 * w0, 3), (1.5 * v0, 0.5 * v0, 3), y0,
                                     dy0, force_n=30.0, ratio=1.0),
                integration=SHORT, execution=Execution(workers=2))
    symmetric = [a for a in ds["attractor_id"].values
                 if ds["attractor_pattern"].values[a] == "2 symmetric"]
    assert len(symmetric) == 1
    a = symmetric[0]
    assert float(ds["fraction"][a]) >= 0.5
    assert int(ds["attractor_period"][a]) == 1
    assert float(ds["attractor_rms_tip_m"][a]) == pytest.approx(orbit.rms_tip(), rel=0.01)
    cell = np.argwhere(ds["attractor"].values == a)[0]
    w = float(ds["signature_tip_m"].values[cell[0], cell[1], 0])
    v = float(ds["signature_tip_velocity_m_s"].values[cell[0], cell[1], 0])
    amp = math.sqrt(2) * orbit.rms_tip()
    omega = bar.natural_frequency_rad_s
    assert abs(w - w0) < 0.02 * amp and abs(v - v0) < 0.02 * amp * omega


def test_signature_is_invariant_to_where_the_cycle_starts():
    cycle = np.array([[1.0, 0.2], [-0.5, 0.7], [0.3, -0.9]])
    strobe = np.tile(cycle, (20, 1))
    k, centres = signature(strobe, 1.0, 1.0)
    k2, centres2 = signature(strobe[1:], 1.0, 1.0)
    assert k == k2 == 3
    np.testing.assert_array_equal(centres, centres2)
    rng = np.random.default_rng(0)
    k3, last = signature(rng.normal(size=(60, 2)), 1.0, 1.0)
    assert k3 == 0 and last.shape == (8, 2)


def test_bad_grid_and_tolerances_are_refused():
    system, forcing = published_point()
    with pytest.raises(ParameterError, match="displacement_m count"):
        BasinOptions(displacement_m=(-1e-3, 1e-3, 0))
    with pytest.raises(ParameterError, match="velocity"):
        BasinOptions(velocity_m_s=(1.0, -1.0, 3))
    with pytest.raises(ParameterError, match="tol.match"):
        BasinTolerance(match=0.0)
    with pytest.raises(ParameterError, match="must be a System"):
        basins(forcing, BasinOptions())


@pytest.mark.parametrize("kind, values", [("restitution", (0.6, 0.7, 0.8)),
                                          ("ball", ("carbide", "steel")),
                                          ("friction_number", (0.2, 0.8)),
                                          ("initial", ((0.5e-3, 0.5), (1e-3, 1.0)))])
def test_sensitivity_gives_one_result_per_value(kind, values):
    ds = sensitivity(SensitivityOptions(kind, values, ratios=(1.0, 1.01)), preset="paper",
                     integration=Integration(duration_s=0.05))
    assert ds["rms_tip_m"].dims[0] == kind
    assert ds.sizes[kind] == len(values)
    assert ds["rms_tip_m"].shape == (len(values), 1, 2)
    assert np.all(np.isfinite(ds["rms_tip_m"]))


def test_sensitivity_from_starts_repeats_each_run_from_the_ball_across_the_cavity():
    """starts = 3: each value's runs again with the ball at rest at the centres of three
    bins across the 0.5 mm cavity (-1/6, 0, 1/6 mm), the bar at rest; each the same bits
    as that start's own simulate, and the study's own runs those of a study without
    starts."""
    kw = dict(preset="paper", gap_m=0.5e-3, integration=Integration(duration_s=0.05))
    options = SensitivityOptions("restitution", (0.6, 0.8), ratios=(1.0, 1.01), starts=3)
    ds = sensitivity(options, **kw)
    assert ds["rms_tip_m_starts"].dims == ("restitution", "start", "force_n", "ratio")
    assert ds["rms_tip_m_starts"].shape == (2, 3, 1, 2)
    np.testing.assert_allclose(ds["ball_position_start_m"], [-0.5e-3 / 3, 0.0, 0.5e-3 / 3],
                               atol=1e-18)
    plain = sensitivity(replace(options, starts=0), **kw)
    assert np.array_equal(ds["rms_tip_m"], plain["rms_tip_m"])
    for i, e in enumerate((0.6, 0.8)):
        system = make_system("ball", "paper", gap_m=0.5e-3, restitution=e)
        for k, y in enumerate(ds["ball_position_start_m"].values):
            run = simulate(system, Harmonic(10.0, 1.01), duration_s=0.05, record_every=0,
                           initial=Initial(ball_position_m=float(y)))
            assert ds["rms_tip_m_starts"].values[i, k, 0, 1] == run.metrics["rms_tip_m"]
    s = summary(ds)
    assert len(s["harmonic"][0]["starts"]["rms_tip_m"]) == 3
    with pytest.raises(ParameterError, match="starts"):
        SensitivityOptions("initial", starts=4)
    with pytest.raises(ParameterError, match="starts"):
        SensitivityOptions("ball", starts=1)


def test_above_spread_is_the_difference_of_means_beyond_twice_its_standard_error():
    assert above_spread([1.0, 2.0, 3.0], [0.0, 0.0, 0.0]) == (True, 2.0, pytest.approx(
        math.sqrt(1.0 / 3.0)))
    assert above_spread([1.0, 3.0], [2.0, 2.0])[0] is False  # equal means
    assert above_spread([1.0, 4.0], [1.0, 2.0])[0] is False  # 1 against 2 x 1.12
    assert above_spread([2.0], [1.0]) == (True, 1.0, 0.0)  # one value each: plain


def test_sensitivity_of_cuts():
    cuts = Cuts(rpm=1200.0, depths_m=(0.05e-3, 0.10e-3), duration_s=0.05)
    ds = sensitivity(SensitivityOptions("restitution", (0.6, 0.8), cuts=cuts), preset="paper")
    assert ds["chatter"].dims == ("restitution", "depth_m")
    assert ds["chatter"].shape == (2, 2) and ds["chatter"].dtype == bool
    assert np.all(ds["amplitude_m"] >= 0)
    with pytest.raises(ParameterError, match="kind"):
        SensitivityOptions("gap", (1e-4,))


@pytest.mark.slow
def test_published_basin_30_by_30():
    """The published grid at 10 N, r = 1.01, gap 0.5 mm, no friction (900 runs of 2 s)."""
    system, forcing = published_point()
    ds = basins(system, BasinOptions(force_n=forcing.amplitude_n, ratio=forcing.ratio))
    assert ds["attractor"].shape == (30, 30)
    assert float(ds["fraction"].sum()) == pytest.approx(1.0, abs=1e-12)
    json.dumps(basin_summary(ds))


def test_sensitivity_refuses_fixing_the_varied_parameter():
    from boringbar._validate import ParameterError
    from boringbar.analysis.sensitivity import SensitivityOptions, sensitivity

    with pytest.raises(ParameterError, match="restitution"):
        sensitivity(SensitivityOptions("restitution", [0.6, 0.7]), overrides={"restitution": 0.8},
                    integration=Integration(duration_s=0.01))

"""The default integrator, "auto" (docs/model.md, section 5.3), and the friction readings
chosen one at a time (make_system's friction_reading and friction_reaction)."""

from dataclasses import replace

import pytest

from boringbar import Harmonic, Regenerative, make_system, simulate
from boringbar._validate import ParameterError
from boringbar.analysis.cases import published_cases
from boringbar.analysis.sweep import SweepOptions, sweep
from boringbar.model.dampers import Friction
from boringbar.simulate import Integration, resolve_integrator


@pytest.mark.parametrize(("preset", "bar", "cutting", "want"), [
    ("physical", "ball", False, "exact"),
    ("physical", "solid", False, "exact"),
    ("physical", "tmd", False, "exact"),
    ("physical", "ball", True, "rk4"),      # cuts stay on RK4
    ("paper", "ball", False, "rk4"),        # the published scheme
    ("paper", "solid", True, "rk4"),
])
def test_auto_takes_exact_for_physical_harmonic_runs_only(preset, bar, cutting, want):
    system = make_system(bar, preset)
    assert resolve_integrator("auto", system, cutting) == want
    for forced in ("rk4", "exact"):
        assert resolve_integrator(forced, system, cutting) == forced


def test_auto_takes_exact_for_true_stick_slip_even_under_paper():
    system = make_system("ball", "paper", static_ratio=1.5)
    assert resolve_integrator("auto", system) == "exact"
    with pytest.raises(ParameterError, match="static_ratio"):
        simulate(system, Harmonic(10.0, 1.0), duration_s=0.01, integrator="rk4")


def test_bad_integrator_names_the_choices():
    with pytest.raises(ParameterError, match="integrator"):
        resolve_integrator("euler", make_system())
    with pytest.raises(ParameterError, match="integrator"):
        Integration(integrator="euler")


def test_a_run_records_the_integrator_that_ran():
    physical, paper = make_system("solid", "physical"), make_system("solid", "paper")
    assert simulate(physical, Harmonic(10.0, 1.0), duration_s=0.01).integrator == "exact"
    assert simulate(paper, Harmonic(10.0, 1.0), duration_s=0.01).integrator == "rk4"
    cut = Regenerative(rpm=1200.0, depth_m=0.01e-3)
    assert simulate(physical, cut, duration_s=0.01).integrator == "rk4"


def test_auto_sweep_is_exact_for_physical_and_batched_rk4_for_paper():
    """Each case of a mixed sweep takes its own integrator and equals the sweep forced
    to that integrator, bit for bit (the batched RK4 path included)."""
    options = SweepOptions(ratios=(0.98, 1.0), forces_n=(10.0,))
    cases = [replace(c, label=f"{preset} {c.label}") for preset in ("paper", "physical")
             for c in published_cases(("solid", "ball"), (0.1e-3,), (True,), preset=preset)]
    auto = sweep(cases, options, integration=Integration(duration_s=0.05))
    assert list(auto["integrator"].values) == ["rk4", "rk4", "exact", "exact"]
    assert auto.attrs["integrator"] == "auto"
    for name, rows in (("rk4", slice(0, 2)), ("exact", slice(2, 4))):
        forced = sweep(cases[rows], options,
                       integration=Integration(duration_s=0.05, integrator=name))
        assert (auto["rms_tip_m"].values[rows] == forced["rms_tip_m"].values).all()
        assert (auto["pattern"].values[rows] == forced["pattern"].values).all()


def test_friction_readings_one_at_a_time():
    """The published number read as the paper computed it (20.4 N for the 26 g ball,
    0.6 m g / 0.0075) under the physical preset, and the reaction corrected under paper."""
    paper = make_system("ball", "paper")
    assert paper.damper.friction == Friction("paper-number", 0.6, "printed", 1.0)
    assert set(paper.readings) == {"calibrated-stiffness", "paper-friction-force",
                                   "printed-bar-reaction"}
    corrected = make_system("ball", "paper", friction_reaction="reciprocal")
    assert corrected.damper.friction.reaction == "reciprocal"
    assert "printed-bar-reaction" not in corrected.readings
    assert corrected.damper.friction_force_n == paper.damper.friction_force_n
    heavy = make_system("ball", "physical", friction_reading="paper",
                        friction_reaction="reciprocal")
    m = heavy.damper.mass_kg
    assert heavy.damper.friction_force_n == pytest.approx(0.6 * m * 9.81 / 0.0075, rel=1e-3)
    assert heavy.damper.friction_force_n == pytest.approx(20.4, rel=0.01)
    assert heavy.readings == ("paper-friction-force",)
    light = make_system("ball", "paper", friction_reading="rolling")
    assert light.damper.friction_force_n == pytest.approx(heavy.damper.friction_force_n * 1e-3)
    steel = make_system("ball", "physical", ball="steel", friction_reading="paper")
    assert steel.damper.friction_force_n == pytest.approx(
        0.6 * steel.damper.mass_kg * 9.81 / 0.0075, rel=1e-3)
    with pytest.raises(ParameterError, match="friction_reading"):
        make_system("ball", friction_reading="metres")

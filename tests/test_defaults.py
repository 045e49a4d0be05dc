"""Defaults that follow the bar: lobe speeds from its first natural frequency, depth
limits to 1 % of themselves, sweep windows that hold a tuned mass damper's two peaks,
and the published study's own grids where it gives them."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scipy.signal import argrelextrema

from boringbar._validate import ParameterError
from boringbar.analysis.cases import Case, parse_range, published_cases
from boringbar.analysis.lobes import (
    DEPTH_FLOOR,
    PUBLISHED_DEPTH_STEP,
    PUBLISHED_RPM,
    LobesOptions,
    lobes,
    plan,
)
from boringbar.analysis.speeds import (
    LOBE_NUMBERS,
    SPEEDS_PER_LOBE,
    boring_speeds,
    default_speeds,
    lobe_speeds,
)
from boringbar.analysis.sweep import PUBLISHED_RATIOS, SweepOptions, default_ratios, tmd_window
from boringbar.analysis.sweep import plan as sweep_plan
from boringbar.cli.main import build_parser
from boringbar.execute import Execution
from boringbar.model.bar import ModalModel
from boringbar.model.dampers import TunedMassDamper
from boringbar.model.system import System, make_system
from boringbar.model.system_file import load_system
from boringbar.reference.linear import tip_frf
from boringbar.reference.stability import limit_at_speeds
from boringbar.report.paper import published_steps
from boringbar.simulate import Integration

EXAMPLES = Path(__file__).resolve().parents[1] / "examples" / "systems"
CARBIDE = load_system(EXAMPLES / "carbide_ld10_tungsten.toml")
STEEL_TMD = load_system(EXAMPLES / "steel_coolant_tmd.toml")


# --- lobe speeds ------------------------------------------------------------------------
def test_lobe_speeds_span_lobes_one_to_five_evenly_in_the_lobe_number():
    f1 = 251.6
    rpm = np.array(lobe_speeds([f1]))
    assert np.all(np.diff(rpm) > 0) and np.all(rpm == np.round(rpm))
    k = 60 * f1 / rpm  # the lobe number of each speed
    assert k.max() == pytest.approx(LOBE_NUMBERS[1], abs=0.01)
    assert k.min() == pytest.approx(LOBE_NUMBERS[0], abs=0.01)
    assert np.diff(k[::-1]) == pytest.approx(1 / SPEEDS_PER_LOBE, abs=2e-3)
    for lobe in range(1, 6):  # every lobe between two pockets gets its speeds
        assert np.count_nonzero((k > lobe) & (k < lobe + 1)) >= SPEEDS_PER_LOBE - 1


def test_two_bars_share_one_axis_dense_enough_for_the_stiffer():
    rpm = np.array(lobe_speeds([250.0, 500.0]))
    assert rpm[0] == round(60 * 250.0 / LOBE_NUMBERS[1])
    assert rpm[-1] == round(60 * 500.0 / LOBE_NUMBERS[0])
    # whole rpm: at 2500 rpm half a rev/min moves k = 12 by 0.0024
    assert np.max(np.diff(60 * 500.0 / rpm[::-1])) <= 1.05 / SPEEDS_PER_LOBE


def test_the_lobe_speeds_draw_each_analytic_lobe_not_a_straight_line():
    """On the speeds of lobes 1 to 5 (lobe_speeds, the default of a bar known by its modes
    alone) the carbide bar's analytic lobes (the frequency-domain truth) keep their
    shape: in each lobe the lowest sampled limit is within 10 % of the lobe's true
    minimum, and the sampled curve rises from it on both sides (a straight line between
    two speeds would hide the minimum)."""
    system = make_system("solid", spec=CARBIDE)
    f1 = system.reference_frequency_rad_s / (2 * math.pi)
    rpm = np.array(lobe_speeds([f1]))
    assert rpm[0] == pytest.approx(60 * f1 / 6.1, abs=1) and len(rpm) > 50
    coarse = limit_at_speeds(system, rpm)
    fine_rpm = 60 * f1 / np.linspace(1.0, 6.0, 20001)
    fine = limit_at_speeds(system, fine_rpm)
    for lobe in range(1, 6):
        on = (60 * f1 / rpm > lobe) & (60 * f1 / rpm < lobe + 1)
        true = np.nanmin(fine[(60 * f1 / fine_rpm > lobe) & (60 * f1 / fine_rpm < lobe + 1)])
        low = np.nanmin(coarse[on])
        assert true <= low <= 1.10 * true, lobe
        j = int(np.nanargmin(coarse[on]))
        assert 0 < j < on.sum() - 1  # the minimum has a speed on either side, higher
    assert len(argrelextrema(coarse, np.less)[0]) >= 5


def test_a_system_file_bar_s_default_speeds_are_a_boring_job_s():
    """A bar with a diameter takes a boring job's speeds: the cutting speeds of carbide
    inserts over its bore (boring_speeds), at least four a lobe where the lobes crowd."""
    system = make_system("solid", spec=CARBIDE)
    rpm = np.array(default_speeds([Case.of(system)]))
    job = boring_speeds(system)
    assert rpm[0] == job.rpm[0] and rpm[-1] == job.rpm[-1]
    f1 = system.reference_frequency_rad_s / (2 * math.pi)
    lobes_spanned = 60 * f1 * (1 / rpm[0] - 1 / rpm[-1])
    assert len(rpm) >= min(4 * lobes_spanned, 200)
    tap = make_system("solid", modal=ModalModel.from_tap_test(
        f1, tip_stiffness_n_m=2e6))  # a bar known by its modes alone
    assert default_speeds([Case.of(tap)]) == lobe_speeds([f1])


def test_lobes_without_speeds_take_the_bars_and_the_published_grid_stays_explicit():
    cases = published_cases(("solid", "tmd"))
    p = plan(cases, LobesOptions(), Integration())
    assert p.context["options"].rpm == default_speeds(cases)
    assert LobesOptions(PUBLISHED_RPM, "scan").depth_step_m == PUBLISHED_DEPTH_STEP
    for quick in (False, True):
        for step in published_steps(quick):
            if step.argv[0] != "lobes":
                continue
            args = build_parser("lobes").parse_args([*step.argv, "--out", "x"])
            assert args.depth_step_mm == 0.01, step.key
            if not quick:
                assert np.array_equal(parse_range(args.rpm, "--rpm"), PUBLISHED_RPM)


# --- depth limits to 1 % ----------------------------------------------------------------
def test_the_default_depth_grid_is_geometric_from_a_micrometre():
    o = LobesOptions(rpm=(1200.0,))
    assert o.method == "search" and o.depth_step_m is None
    d = o.depths(np.arange(1, o.max_index + 1))
    assert d[0] == DEPTH_FLOOR and d[-1] <= o.max_depth_m < d[-1] * 1.01
    assert d[1:] / d[:-1] == pytest.approx(1.01, rel=1e-12)
    for depth in (3e-5, 1.234e-4, 2.9e-3):
        i = o.index_below(depth)
        assert o.depth(i) <= depth < o.depth(i + 1)


def test_the_search_finds_the_limit_to_one_percent_and_agrees_with_a_fine_grid():
    """At one speed of the solid bar, under the published criterion: the relative search
    brackets the limit within 1 %, above the analytic limit (a finite run can only place
    it higher), and inside the bracket a search on a 0.1 micrometre linear grid finds."""
    cases = [Case.of(make_system("solid"), "solid")]
    integ = Integration(duration_s=0.5)
    rel = lobes(cases, LobesOptions(rpm=(1200.0,), max_depth_m=0.5e-3, criterion="zero"),
                integration=integ, execution=Execution("serial"))
    lim, first = float(rel["limit_depth_m"][0, 0]), float(rel["first_unstable_depth_m"][0, 0])
    assert first / lim == pytest.approx(1.01, rel=1e-9)
    assert lim >= 0.99 * float(rel["analytic_limit_m"][0, 0])
    fine = lobes(cases, LobesOptions(rpm=(1200.0,), depth_step_m=1e-7, max_depth_m=0.5e-3,
                                     criterion="zero"),
                 integration=integ, execution=Execution("serial"))
    f_lim = float(fine["limit_depth_m"][0, 0])
    f_first = float(fine["first_unstable_depth_m"][0, 0])
    assert lim <= f_first and f_lim <= first  # the two brackets overlap
    assert rel.attrs["depth_grid"].startswith("depth_tolerance = 0.01")


def test_a_scan_keeps_the_published_step_and_a_grid_is_one_or_the_other():
    o = LobesOptions(rpm=(1200.0,), method="scan")
    assert o.depth_step_m == PUBLISHED_DEPTH_STEP and o.max_index == 300
    assert o.depth(7) == 7 * PUBLISHED_DEPTH_STEP and o.depth_tolerance is None
    assert LobesOptions(method="scan", depth_tolerance=0.05).depth_step_m is None
    with pytest.raises(ParameterError, match="depth_step_m = 1e-05 and depth_tolerance = "
                                             "0.01: give one"):
        LobesOptions(depth_step_m=1e-5, depth_tolerance=0.01)
    with pytest.raises(ParameterError, match=r"depth_tolerance = 0.0 is outside"):
        LobesOptions(depth_tolerance=0.0)


# --- sweep windows ----------------------------------------------------------------------
def _peaks(system: System) -> np.ndarray:
    """Omega/omega_n of the local maxima of |G|, the tip FRF in closed form."""
    r = np.linspace(0.3, 1.8, 30001)
    g = np.abs(tip_frf(system.bar, r * system.reference_frequency_rad_s, tmd=system.damper))
    return r[argrelextrema(g, np.greater)[0]]


@pytest.mark.parametrize("mass", [0.01, 0.04, 0.1])
@pytest.mark.parametrize("design", ["den-hartog", "sims"])
def test_the_tmd_window_holds_both_peaks_of_the_frf(mass, design):
    """Den Hartog's tuning gives two peaks; Sims' (tuned for chatter, not for the FRF)
    may merge them into one. Every peak near the first mode lies in the window, with
    room beside it."""
    system = make_system("tmd", spec=STEEL_TMD, tmd_mass_kg=mass, tmd_design=design)
    lo, hi = tmd_window(system)
    peaks = _peaks(system)
    near = peaks[(peaks > 0.5) & (peaks < 1.5)]
    assert len(near) == (2 if design == "den-hartog" else len(near)) >= 1, near
    assert lo < near[0] * 0.97 and near[-1] * 1.03 < hi


@pytest.mark.parametrize("mass", [0.01, 0.04, 0.2])
def test_the_peaks_lie_near_and_between_the_undamped_coupled_frequencies(mass):
    """The rule behind the window: whatever the absorber's damping, |G| peaks between
    the two undamped natural frequencies of bar and absorber (it starts at them with no
    damping and merges to the locked frequency with much), or, as any damped resonance,
    a little beyond one: measured over 200 dampings, at most 0.25, 0.56, 1.2 and 2.3 %
    for mu = 0.044, 0.18, 0.44 and 0.88 (0.01 to 0.2 kg), inside the window's 5 %."""
    host = make_system("tmd", spec=STEEL_TMD, tmd_mass_kg=mass)
    for damping in np.geomspace(0.1, 3000.0, 12):
        tmd = TunedMassDamper(host.damper.mass_kg, host.damper.stiffness_n_m, damping,
                              host.damper.position_m, "given")
        system = System(host.bar, tmd, host.preset, host.readings)
        lo, hi = tmd_window(system)
        w1, w2 = lo / 0.95, hi / 1.05
        for r in _peaks(system):
            if r < 1.5:
                assert w1 * (1 - 0.025) <= r <= w2 * (1 + 0.025), (damping, r, w1, w2)


def test_the_default_window_is_published_without_a_tmd_and_wider_with_one():
    assert default_ratios(published_cases(("solid", "ball"))) == PUBLISHED_RATIOS
    cases = [Case.of(make_system(k, spec=STEEL_TMD)) for k in ("solid", "tmd")]
    ratios = default_ratios(cases)
    assert ratios[0] <= 0.73 and ratios[-1] >= 1.1 and set(PUBLISHED_RATIOS) <= set(ratios)
    assert np.diff(ratios) == pytest.approx(0.01)
    p = sweep_plan(cases, SweepOptions(), Integration())
    assert p.context["options"].ratios == ratios

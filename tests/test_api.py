"""The public API (``import boringbar as bb``): every name documented, every argument
named in its docstring, none silently swallowed (python-control's API walk)."""

from __future__ import annotations

import inspect
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from cli_output import assert_one_line_error

import boringbar as bb
from boringbar.cli.main import main
from boringbar.simulate import HISTORY_ROWS
from boringbar.simulate.run_limits import check_steady

#: functions that take **kwargs, and where those go (each must refuse unknown names)
FORWARDED = {"published_cases": "make_system"}


def _public_callables():
    for name in bb.__all__:
        obj = getattr(bb, name)
        if callable(obj):
            yield name, obj


def _documented_text(obj) -> str:
    doc = inspect.getdoc(obj) or ""
    if inspect.isclass(obj) and obj.__init__ is not object.__init__:
        doc += "\n" + (inspect.getdoc(obj.__init__) or "")
    return doc


def test_every_public_name_exists_and_is_exported_once():
    assert len(set(bb.__all__)) == len(bb.__all__)
    for name in bb.__all__:
        assert hasattr(bb, name), name


@pytest.mark.parametrize("name, obj", list(_public_callables()))
def test_every_argument_is_documented(name, obj):
    doc = _documented_text(obj)
    assert doc.strip(), f"{name} has no docstring"
    try:
        params = inspect.signature(obj).parameters
    except (TypeError, ValueError):
        return
    missing = [p for p in params
               if p != "self" and not re.search(rf"\b{re.escape(p)}\b", doc)]
    assert not missing, f"{name}: arguments not named in its docstring: {missing}"


@pytest.mark.parametrize("name, obj", list(_public_callables()))
def test_no_argument_is_silently_swallowed(name, obj):
    try:
        params = inspect.signature(obj).parameters.values()
    except (TypeError, ValueError):
        return
    var = [p.name for p in params if p.kind in (p.VAR_KEYWORD, p.VAR_POSITIONAL)]
    assert not var or name in FORWARDED, f"{name} takes *{var} and says nowhere where they go"


def test_forwarded_keywords_refuse_unknown_names():
    with pytest.raises(TypeError, match="no_such_option"):
        bb.published_cases(bars=("solid",), no_such_option=1.0)


def test_options_validate_themselves():
    with pytest.raises(bb.ParameterError, match="dt_s"):
        bb.Integration(dt_s=-1.0)
    with pytest.raises(bb.ParameterError, match="steady_fraction"):
        bb.Integration(steady_fraction=0.0)
    with pytest.raises(bb.ParameterError, match="integrator"):
        bb.Integration(integrator="euler")
    with pytest.raises(bb.ParameterError, match="executor"):
        bb.Execution(executor="gpu")
    with pytest.raises(bb.ParameterError, match="workers"):
        bb.Execution(workers=0)
    with pytest.raises(bb.ParameterError, match=r"ratios\[1\]"):
        bb.SweepOptions(ratios=(1.0, -1.0))
    with pytest.raises(bb.ParameterError, match="ratios is empty"):
        bb.SweepOptions(ratios=())
    # a string is true to Python: "off" must not read as friction on
    with pytest.raises(bb.ParameterError, match="friction = 'off' must be True or False"):
        bb.make_system("ball", friction="off")
    with pytest.raises(bb.ParameterError, match="locked = 1 must be True or False"):
        bb.make_system("ball", locked=1)
    assert bb.make_system("ball", friction=np.bool_(False)).damper.friction_force_n == 0
    # another bar's argument would do nothing: refused, as the command line refuses it
    with pytest.raises(bb.ParameterError, match="gap_m = 0.0001 applies to the ball bar"):
        bb.make_system("solid", gap_m=1e-4)
    with pytest.raises(bb.ParameterError, match="tmd_mass_kg = 0.1 applies to the tmd bar"):
        bb.make_system("ball", tmd_mass_kg=0.1)


def test_a_run_is_frozen():
    run = bb.simulate(bb.make_system("solid", "paper"), bb.Harmonic(10.0, 1.0),
                      duration_s=5e-3, record_every=10)
    with pytest.raises(AttributeError):
        run.dt_s = 2e-6
    ds = run.to_xarray()
    assert ds["tip_displacement_m"].attrs["units"] == "m"


def test_import_loads_no_heavy_library_and_every_name_resolves():
    """``import boringbar`` leaves the figures, the optimiser, xarray and the analyses
    to first use; every public name then resolves to what its module holds."""
    code = ("import sys, boringbar as bb; "
            "heavy = ('matplotlib', 'optuna', 'xarray', 'numba', 'scipy.optimize', "
            "'boringbar.analysis.sweep', 'boringbar.studies.runner'); "
            "print(*[m for m in heavy if m in sys.modules])")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert out.stdout.split() == []
    assert bb.simulate.__module__ == "boringbar.simulate.engine" and callable(bb.simulate)
    for name, obj in _public_callables():
        assert obj.__name__ == name, name
    assert bb.sweep is __import__("boringbar.analysis.sweep", fromlist=["sweep"]).sweep
    with pytest.raises(AttributeError, match="no attribute 'nonsense'"):
        bb.nonsense  # noqa: B018


def test_a_default_run_keeps_a_bounded_history_to_plot_and_write():
    """simulate records about HISTORY_ROWS rows by default, whatever the duration, the
    same numbers as without them; record_every=0 keeps none, and says how to get it."""
    system = bb.make_system("ball", "physical")
    for duration in (0.1, 2.0):
        run = bb.simulate(system, bb.Harmonic(20.0, 1.0), duration_s=duration)
        rows = run.history.shape[0]
        assert HISTORY_ROWS <= rows < 2 * HISTORY_ROWS
        assert run.to_xarray().sizes["time_s"] == rows
        assert len(run.plot().axes) == 4
    bare = bb.simulate(system, bb.Harmonic(20.0, 1.0), duration_s=2.0, record_every=0)
    assert bare.history is None and np.array_equal(bare.final.x, run.final.x)
    with pytest.raises(ValueError, match="record_every=None"):
        bare.to_xarray()


def test_a_ball_run_s_figure_marks_the_impacts_its_sampled_record_may_miss():
    """The zoom on the ball's row marks each impact of the run's log in it at the wall it
    struck (the sampled record may pass between an impact's samples)."""
    system = bb.make_system("ball", "physical")
    run = bb.simulate(system, bb.Harmonic(20.0, 1.0), duration_s=0.5)
    ds = run.to_xarray()
    zoom = run.plot().axes[3]
    marks, = (line for line in zoom.get_lines() if line.get_label().startswith("impacts"))
    t0 = zoom.get_xlim()[0]
    shown = ds["impact_time_s"].values >= t0 - 1e-12
    assert shown.sum() >= 2
    np.testing.assert_array_equal(marks.get_xdata(), ds["impact_time_s"].values[shown])
    half = system.damper.gap_m / 2 * 1e3
    np.testing.assert_allclose(np.abs(marks.get_ydata()), half)
    assert "long_name" in ds["impact_wall"].attrs


def test_the_analyses_take_a_system_a_list_or_a_mapping():
    """sweep and lobes take what a user has: one System, a list of them or a mapping
    of label to System, labelled from the system; anything else is a TypeError that
    says what is expected, and a Case that mislabels its system is refused."""
    ball = bb.make_system("ball", "physical", gap_m=0.2e-3, friction=True)
    solid = bb.make_system("solid", "physical")
    quick = bb.Integration(duration_s=0.05)
    options = bb.SweepOptions(ratios=(1.0,), forces_n=(10.0,))
    one = bb.sweep(ball, options, integration=quick)
    assert list(one.case.values) == ["ball gap=0.2mm friction=on"]
    many = bb.sweep([ball, solid], options, integration=quick)
    assert list(many.case.values) == ["ball gap=0.2mm friction=on", "solid"]
    named = bb.sweep({"mine": ball, "plain": solid}, options, integration=quick)
    assert list(named.case.values) == ["mine", "plain"]
    assert np.array_equal(named.rms_tip_m.values, many.rms_tip_m.values)
    lobes = bb.lobes(solid, bb.LobesOptions(rpm=(1200.0,), method="search"),
                     integration=bb.Integration(duration_s=0.2))
    assert list(lobes.case.values) == ["solid"] and lobes.limit_depth_m.values[0, 0] > 0
    for bad in (3, "ball", {"x": 3}):
        with pytest.raises(TypeError, match="must be a System"):
            bb.sweep(bad, options, integration=quick)
    with pytest.raises(bb.ParameterError, match="given twice"):
        bb.sweep([ball, ball], options, integration=quick)
    with pytest.raises(bb.ParameterError, match="gap_m = 0.0009, but its system has gap_m"):
        bb.Case("mine", ball, "ball", gap_m=0.9e-3, friction="on")
    with pytest.raises(bb.ParameterError, match="friction = 'off', but its system"):
        bb.Case("mine", ball, "ball", gap_m=0.2e-3, friction="off")


def test_a_steady_part_shorter_than_one_period_is_refused(tmp_path, capsys):
    """1 ms of a 525 Hz forcing has no steady RMS: the command line says how long a run
    must be (simulate itself takes it: a state advanced by part of a period)."""
    with pytest.raises(bb.ParameterError, match=r"shorter than one forcing period "
                                                r"\(0.0019 s\): give duration_s >= 0.00238 s"):
        check_steady(1e-3, 0.8, 1 / 525.23)
    check_steady(2.4e-3, 0.8, 1 / 525.23)
    argv = ["simulate", "--force-n", "20", "--duration-s", "0.001"]
    assert_one_line_error(main, [*argv, "--out", str(tmp_path / "o")], tmp_path / "o",
                          "--duration-s = 0.001 s leaves a steady part of 0.0008 s", capsys)


def test_a_run_too_short_to_be_steady_reports_no_steady_values():
    """simulate takes 1 ms of a 525 Hz forcing (a state advanced by part of a period),
    but its summary gives no steady RMS, peak or pattern, and warns why; its notebook
    table says so; two periods' worth report them."""
    bar, forcing = bb.make_system("ball"), bb.Harmonic(amplitude_n=20.0, ratio=1.0)
    short = bb.simulate(bar, forcing, duration_s=1e-3)
    with pytest.warns(RuntimeWarning, match=r"holds 0.42 of a forcing period"):
        s = short.summary()
    assert s["steady_periods"] == pytest.approx(0.8e-3 * 525.225, rel=1e-3)
    assert s["rms_tip_m"] is None and s["max_abs_tip_m"] is None and s["pattern"] is None
    assert "shorter than one period" in short._repr_html_()
    assert short.rms_tip_m is None and short.pattern is None and not short.steady
    long = bb.simulate(bar, forcing, duration_s=2.5 / 525.225 / 0.8)
    assert long.summary()["steady_periods"] >= 1.0 and long.summary()["rms_tip_m"] > 0
    # the analyses refuse such runs before starting, as the command line does
    with pytest.raises(bb.ParameterError, match=r"Integration.duration_s = 0.001 s leaves a "
                                                r"steady part of 0.0008 s"):
        bb.sweep(bar, bb.SweepOptions(ratios=(1.0,), forces_n=(10.0,)),
                 integration=bb.Integration(duration_s=1e-3))
    short_runs = bb.Integration(duration_s=1e-3)
    for refused in (lambda: bb.basins(bar, bb.BasinOptions(), integration=short_runs),
                    lambda: bb.bifurcation(bar, bb.BifurcationOptions(), integration=short_runs)):
        with pytest.raises(bb.ParameterError, match=r"shorter than one forcing period"):
            refused()
    with pytest.raises(bb.ParameterError, match=r"DesignOptions.duration_s = 0.001 s"):
        bb.design(bb.DesignOptions(bar="ball", variables=(bb.Variable("gap_m", 1e-4, 5e-4),),
                                   duration_s=1e-3, trials=2))


def test_lobe_speeds_must_increase_as_on_the_command_line():
    with pytest.raises(bb.ParameterError, match=r"rpm = \(1600.0, 900.0\) must increase"):
        bb.LobesOptions(rpm=(1600.0, 900.0))
    with pytest.raises(bb.ParameterError, match="each speed once"):
        bb.LobesOptions(rpm=(900.0, 900.0))
    assert bb.LobesOptions(rpm=(900.0, 1000.0)).rpm == (900.0, 1000.0)


def test_a_run_shows_itself_in_a_notebook():
    """Run._repr_html_: what was run and its results in mm, escaped HTML."""
    run = bb.simulate(bb.make_system("ball", "physical"), bb.Harmonic(20.0, 1.0), duration_s=0.2)
    page = run._repr_html_()
    assert page.startswith("<table>") and page.endswith("</table>")
    assert f"{run.rms_tip_m * 1e3:.4g} mm" in page and "F0 = 20 N" in page
    assert "max |tip|" in page and "20000 rows" in page
    cut = bb.simulate(bb.make_system("solid", "paper"), bb.Regenerative(depth_m=0.05e-3, rpm=1200),
                      duration_s=0.2, record_every=0)
    assert "cut at 1200 rpm, depth 0.05 mm" in cut._repr_html_()
    assert "none (record_every=0)" in cut._repr_html_()


def test_variants_are_the_files_bars_side_by_side():
    """bb.variants gives the bars a system file describes, keyed by kind, and an
    analysis labels its cases with those keys."""
    spec = bb.load_system(Path(__file__).parents[1] / "examples" / "systems" /
                          "steel_coolant_tmd.toml")
    v = bb.variants(spec)
    assert list(v) == ["solid", "tmd"]  # this file has an absorber and no ball
    assert v["tmd"].kind == "tmd" and v["solid"].damper is None
    assert list(bb.variants()) == ["solid", "ball", "tmd"]  # the published bar
    ds = bb.sweep(v, bb.SweepOptions(ratios=(1.0,), forces_n=(10.0,)),
                  integration=bb.Integration(duration_s=0.05))
    assert list(ds["case"].values) == ["solid", "tmd"]

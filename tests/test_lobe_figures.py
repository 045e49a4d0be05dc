"""The lobe figures a designer reads (plot_bar.plot_lobes, plot_bar.plot_analytic_lobes):
every bar on one linear depth scale from 0, tick labels where the curves are, the legend
off the data, and the user's speed marked with each bar's depth there read out.

Each figure is drawn for one bar and for three, from real results (short cuts, a coarse
depth grid: the physics of lobes is tested elsewhere)."""

import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.text import Annotation

from boringbar._validate import ParameterError
from boringbar.analysis.cases import published_cases
from boringbar.analysis.lobes import LobesOptions, lobes
from boringbar.execute import Execution
from boringbar.plot import plot_lobes as plot_lobes_of_plot
from boringbar.plot.lobes import plot_analytic_lobes, plot_lobes
from boringbar.plot.palette import LOBE_CAP, lobe_depth_top, speed_axis
from boringbar.reference.stability import (
    GRID_SPAN,
    limit_at_speeds,
    linear_host,
    lobes_of_receptance,
    natural_frequencies,
    sampled_limits,
    system_receptance,
)
from boringbar.simulate import Integration

SPEEDS = (1000.0, 1100.0, 1200.0, 1300.0)
AT = 1200.0


def _cases(bars):
    """The published ``bars``, the ball with a 0.5 mm gap and no friction: one case each."""
    return published_cases(bars, gaps_m=(0.5e-3,), frictions=(False,))


def _simulated(bars):
    """Lobes of the published ``bars`` over :data:`SPEEDS`, 0.3 s cuts, 0.05 mm steps."""
    cases = _cases(bars)
    options = LobesOptions(rpm=SPEEDS, method="scan", depth_step_m=0.05e-3,
                           max_depth_m=1.0e-3)
    return lobes(cases, options, integration=Integration(duration_s=0.3),
                 execution=Execution("serial"))


@pytest.fixture(scope="module", params=[("solid",), ("solid", "tmd", "ball")],
                ids=["1 bar", "3 bars"])
def simulated(request):
    ds = _simulated(request.param)
    ds.attrs["at_rpm"] = AT  # as boringbar lobes --at-rpm records it
    return ds


def _analytic_curves(bars, rpm, at=None) -> list[dict]:
    """What ``boringbar lobes --analytic`` hands plot_analytic_lobes for the published
    ``bars`` (one curve per distinct FRF is the command's business, not the figure's)."""
    curves = []
    for case in _cases(bars):
        wn = natural_frequencies(*linear_host(case.system))
        w = np.geomspace(GRID_SPAN[0] * wn.min(), GRID_SPAN[1] * wn.max(), 20000)
        g = system_receptance(case.system, w)
        c = {"label": case.label, "name": case.label, "kind": case.system.kind,
             "lobes": lobes_of_receptance(w, g), "rpm": rpm,
             "limit_m": sampled_limits(w, g, rpm)["limit"]}
        if at is not None:
            c["depth_at_rpm_m"] = float(limit_at_speeds(case.system, [at])[0])
        curves.append(c)
    return curves


@pytest.fixture(scope="module", params=[("solid",), ("solid", "tmd", "ball")],
                ids=["1 bar", "3 bars"])
def analytic(request):
    rpm = np.union1d(np.geomspace(900.0, 36000.0, 800), [AT])
    curves = _analytic_curves(request.param, rpm, AT)
    return plot_analytic_lobes(curves, (900.0, 36000.0), at_rpm=AT), curves


def _drawn(fig):
    FigureCanvasAgg(fig).draw()
    return [ax for ax in fig.axes if ax.get_visible()]


def _data_area_free_of(fig, axes, box) -> bool:
    """Whether ``box`` (display units) stays off every axes' data area."""
    return all(not box.overlaps(ax.get_window_extent()) for ax in axes)


def _labelled_y_ticks(ax) -> list[float]:
    return [t.get_position()[1] for t in ax.get_yticklabels()
            if t.get_text().strip() and ax.get_ylim()[0] <= t.get_position()[1]
            <= ax.get_ylim()[1]]


def _readouts(fig) -> list[str]:
    return [a.get_text() for ax in fig.axes for a in ax.texts if isinstance(a, Annotation)]


def _speed_lines(ax, at: float) -> list:
    return [ln for ln in ax.get_lines()
            if len(ln.get_xdata()) == 2 and np.allclose(ln.get_xdata(), at)
            and tuple(ln.get_ydata()) == (0, 1)]  # an axvline: axes-fraction y


# --- the simulated lobes ---------------------------------------------------------------
def test_simulated_lobes_share_one_linear_depth_scale_from_zero(simulated):
    fig = plot_lobes(simulated)
    axes = _drawn(fig)
    assert len(axes) == simulated.sizes["case"]
    assert len({ax.get_ylim() for ax in axes}) == 1  # one depth scale
    for ax in axes:
        assert ax.get_yscale() == "linear" and ax.get_ylim()[0] == 0.0
        assert ax.get_ylabel() in ("depth of cut b (mm)", "")
    top = axes[0].get_ylim()[1]
    limits = simulated["limit_depth_m"].values * 1e3
    assert np.nanmax(limits) < top  # every limit shown ...
    assert top <= 1.3 * np.nanmax(np.r_[limits.ravel(), simulated["first_unstable_depth_m"]
                                        .values.ravel() * 1e3,
                                        np.where(simulated["verdict"].values == 1,
                                                 simulated["depth_m"].values * 1e3,
                                                 np.nan).ravel()]) or "cut at" in \
        fig._suptitle.get_text()  # ... and the axis ends near them (or says it is cut)
    ticks = _labelled_y_ticks(axes[0])
    assert len(ticks) >= 4 and max(ticks) >= 0.5 * top  # labelled over the whole range
    if len(axes) == 1:  # (a stiffer bar beside it may set the scale)
        assert min(t for t in ticks if t > 0) <= np.nanmax(limits)  # a label below them


def test_simulated_lobes_legend_is_off_the_data(simulated):
    fig = plot_lobes(simulated)
    axes = _drawn(fig)
    (legend,) = fig.legends
    assert _data_area_free_of(fig, axes, legend.get_window_extent())
    for text in fig.findobj(Annotation):  # the readouts too
        assert _data_area_free_of(fig, axes, text.get_window_extent())


def test_simulated_lobes_mark_the_users_speed_with_each_limit_there(simulated):
    fig = plot_lobes(simulated)
    axes = _drawn(fig)
    j = list(simulated["rpm"].values).index(AT)
    readouts = _readouts(fig)
    assert len(readouts) == len(axes)
    for ax, text, limit in zip(axes, readouts, simulated["limit_depth_m"].values[:, j],
                               strict=True):
        assert len(_speed_lines(ax, AT)) == 1
        assert text == "your speed 1200 rpm: " + ("no chatter up to 1 mm" if np.isnan(limit)
                                                  else f"{limit * 1e3:.3g} mm")
    labels = [t.get_text() for t in fig.legends[0].get_texts()]
    assert "your speed 1200 rpm" in labels
    # at_rpm given overrides the file's; a speed off the grid is refused, not interpolated
    assert "your speed 1100 rpm" in _readouts(plot_lobes(simulated, at_rpm=1100.0))[0]
    with pytest.raises(ParameterError, match="at_rpm = 1150.0 rev/min is not one of"):
        plot_lobes(simulated, at_rpm=1150.0)


def test_simulated_lobes_without_a_speed_have_no_speed_line(simulated):
    ds = simulated.copy()
    ds.attrs = {k: v for k, v in ds.attrs.items() if k != "at_rpm"}
    fig = plot_lobes(ds)
    axes = _drawn(fig)
    assert not _readouts(fig) and not any(_speed_lines(ax, AT) for ax in axes)
    assert plot_lobes_of_plot is plot_lobes  # boringbar.plot.plot_lobes draws it still


# --- the analytic lobes ----------------------------------------------------------------
def test_analytic_lobes_one_axes_linear_depth_from_zero_labelled_where_the_curves_are(
        analytic):
    fig, curves = analytic
    (ax,) = _drawn(fig)  # one axes: one scale
    assert ax.get_yscale() == "linear" and ax.get_ylim()[0] == 0.0
    floors = [np.nanmin(c["lobes"]["b_lim"]) * 1e3 for c in curves]
    top = ax.get_ylim()[1]
    assert max(floors) < top <= max(LOBE_CAP * min(floors), 2 * max(floors)) + 1e-12
    ticks = _labelled_y_ticks(ax)
    assert len(ticks) >= 4 and min(t for t in ticks if t > 0) < 3 * max(floors)
    # the speeds span 40 times: a log axis labelled over the whole range
    assert ax.get_xscale() == "log"
    x = [float(t.get_text()) for t in ax.get_xticklabels() if t.get_text()
         and ax.get_xlim()[0] <= t.get_position()[0] <= ax.get_xlim()[1]]
    assert min(x) <= 1000 and max(x) >= 30000 and len(x) >= 8
    assert "peaks up to" in fig._suptitle.get_text()  # lobe 1's peak is above the axis


def test_analytic_lobes_legend_and_readout_are_off_the_data(analytic):
    fig, _ = analytic
    axes = _drawn(fig)
    (legend,) = fig.legends
    assert _data_area_free_of(fig, axes, legend.get_window_extent())
    (readout,) = fig.findobj(Annotation)
    assert _data_area_free_of(fig, axes, readout.get_window_extent())


def test_analytic_lobes_read_out_each_bars_depth_at_the_users_speed(analytic):
    fig, curves = analytic
    (ax,) = _drawn(fig)
    assert len(_speed_lines(ax, AT)) == 1
    (text,) = _readouts(fig)
    lines = text.split("\n")
    assert lines[0] == "your speed 1200 rpm"
    assert lines[1:] == [f"{c['name']}: {c['depth_at_rpm_m'] * 1e3:.3g} mm" for c in curves]
    dots = [ln for ln in ax.get_lines() if list(ln.get_xdata()) == [AT]]
    assert [d.get_ydata()[0] for d in dots] == pytest.approx(
        [c["depth_at_rpm_m"] * 1e3 for c in curves])
    if len(curves) == 3:  # each bar in its own colour and line
        styles = {(ln.get_color(), ln.get_linestyle()) for ln in ax.get_lines()
                  if ln.get_label() in {c["label"] for c in curves}}
        assert len(styles) == 3


# --- the rules both figures (and the page) follow ---------------------------------------
def test_the_depth_axis_fits_the_curves_and_cuts_only_a_peak_far_above_the_pockets():
    assert lobe_depth_top([[0.1, 0.2, 0.4]], [0.1]) == (pytest.approx(0.46), None)
    top, peak = lobe_depth_top([[0.03, 0.05, 1.9]], [0.03])  # lobe 1's peak
    assert top == pytest.approx(LOBE_CAP * 0.03) and peak == 1.9
    # a stiff bar beside a soft one: both bars' pockets and their rise stay in view
    top, _ = lobe_depth_top([[0.03, 2.0], [0.6, 2.2]], [0.03, 0.6])
    assert top == pytest.approx(1.2)
    assert lobe_depth_top([[np.nan, np.inf]], [np.nan]) == (1.0, None)


def test_the_speed_axis_is_log_and_labelled_at_both_ends_over_a_wide_range():
    log, ticks, (left, right) = speed_axis(1200.0, 17085.0)
    assert log and (left, right) == (1000.0, 20000.0)
    assert {1000.0, 1500.0, 2000.0, 10000.0, 15000.0, 20000.0} <= set(ticks)
    log, ticks, (left, right) = speed_axis(1000.0, 1400.0)
    assert not log and ticks is None and left < 1000.0 and right > 1400.0


def test_a_limit_line_breaks_across_a_gap_no_cut_ran(simulated):
    """A speed far beyond the others (--at-rpm outside the grid): no line across the gap,
    which would show limits no cut measured; a speed within the grid keeps it whole."""
    def limit_line(rpm):
        fig = plot_lobes(simulated.assign_coords(rpm=rpm))
        return next(ln for ln in fig.axes[0].get_lines() if ln.get_color() == "black"
                    and ln.get_marker() == ".")

    line = limit_line([1000.0, 1100.0, AT, 3000.0])
    assert list(line.get_xdata()[:3]) == [1000, 1100, AT] and line.get_xdata()[-1] == 3000
    assert np.isnan(line.get_ydata()[3])
    assert not np.isnan(limit_line([1000.0, 1100.0, 1150.0, AT]).get_ydata()).any()


def test_lobes_at_one_speed_draw_the_analytic_curve_about_it():
    """One speed: the analytic curve spans 10 % either side of it (not 200 copies of the
    speed, which drew nothing while the legend listed it)."""
    cases = _cases(("solid",))
    ds = lobes(cases, LobesOptions(rpm=(AT,), method="scan", depth_step_m=0.05e-3,
                                   max_depth_m=1.0e-3),
               integration=Integration(duration_s=0.3), execution=Execution("serial"))
    fine = ds["fine_rpm"].values
    assert fine[0] == pytest.approx(0.9 * AT) and fine[-1] == pytest.approx(1.1 * AT)
    assert np.all(np.diff(fine) > 0) and np.isfinite(ds["analytic_curve_m"].values).all()
    lines = plot_lobes(ds).axes[0].get_lines()
    assert any(len(np.unique(line.get_xdata())) > 100 for line in lines)

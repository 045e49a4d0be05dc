"""The figures' shared style (boringbar.plot.style): the palette that tells the bars
apart, titles that name the bar and fit the figure, lengths in mm.

The report's own figures are checked against what the page shows in
tests/test_paper.py (text size at the width a browser draws them)."""

import json
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from matplotlib.text import Text

from boringbar.analysis.cases import Case
from boringbar.analysis.sweep import SweepOptions, sweep
from boringbar.execute import Execution
from boringbar.model.system import make_system
from boringbar.model.system_file import load_system
from boringbar.plot import plot_sweep
from boringbar.plot.design import plot_design, plot_design_comparison
from boringbar.plot.style import (
    BAR_STYLE,
    OKABE_ITO,
    bar_name,
    method_words,
    smallest_text_px,
    wrap_title,
)
from boringbar.simulate import Integration

EXAMPLES = Path(__file__).resolve().parent.parent / "examples" / "systems"
SHORT = Integration(duration_s=0.02, dt_s=1e-6, integrator="rk4")


def _sweep(spec=None, bars=("solid", "tmd")):
    cases = [Case.of(make_system(b, "physical", spec=spec)) for b in bars]
    return sweep(cases, SweepOptions(ratios=(0.98, 1.02), forces_n=(10.0,)),
                 integration=SHORT, execution=Execution("serial"))


@pytest.fixture(scope="module")
def own_bar_sweep():
    """A sweep of a system file's solid and TMD bars: one panel, no ball case."""
    return _sweep(load_system(EXAMPLES / "steel_coolant_tmd.toml"))


def _inside(fig, text: Text) -> bool:
    """Whether ``text`` is drawn wholly within the figure."""
    box, page = text.get_window_extent(), fig.bbox
    return (box.x0 >= page.x0 - 0.5 and box.x1 <= page.x1 + 0.5
            and box.y0 >= page.y0 - 0.5 and box.y1 <= page.y1 + 0.5)


def test_the_bar_is_the_system_files_name_or_the_published_bar(own_bar_sweep):
    assert bar_name(own_bar_sweep.attrs) == "steel-25mm-coolant-tmd"
    assert bar_name({"systems": json.dumps({"solid": {"system_file": {"name": "published"}}})}) \
        == "published bar"
    assert bar_name({"title": "{not json"}) == "published bar"  # nothing names a file


def test_single_panel_sweep_title_names_the_bar_and_is_not_clipped(own_bar_sweep):
    fig = plot_sweep(own_bar_sweep)
    fig.draw_without_rendering()
    title = fig._suptitle
    assert title.get_text().startswith("steel-25mm-coolant-tmd, physical preset: tip RMS")
    assert _inside(fig, title), title.get_window_extent()
    assert len(fig.axes) == 1


def test_solid_ball_and_tmd_are_told_apart_by_colour_and_line():
    styles = {(s["color"], s["ls"]) for k, s in BAR_STYLE.items() if k != "locked"}
    assert len({c for c, _ in styles}) == 3 and len({ls for _, ls in styles}) == 3
    assert {c for c, _ in styles} <= set(OKABE_ITO.values())
    ds = _sweep(bars=("solid", "tmd", "ball"))
    fig = plot_sweep(ds)
    lines = {ln.get_label(): (ln.get_color(), ln.get_linestyle()) for ax in fig.axes
             for ln in ax.get_lines() if not ln.get_label().startswith("_")}
    assert lines["solid bar"][0] == BAR_STYLE["solid"]["color"]
    assert lines["TMD bar"][0] == BAR_STYLE["tmd"]["color"]
    assert lines["ball-damped bar"][0] == BAR_STYLE["ball"]["color"]


def test_a_long_title_wraps_within_its_width():
    text = "published bar, paper preset: " + "word " * 60
    for line in wrap_title(text, 7.2, 11).split("\n"):
        assert len(line) * 0.52 * 11 <= 7.2 * 72
    assert "F0 = 10 N" in wrap_title("x " * 40 + "F0 = 10 N", 2.0, 11)  # kept on one line


def _design_dataset(objectives="rms_band") -> xr.Dataset:
    """A design file as read back from NetCDF (one objective: a plain string)."""
    rng = np.random.default_rng(0)
    stat = rng.uniform(2e-4, 4e-4, (5, 1))
    system = {"kind": "ball", "system_file": {"name": "published"}}
    return xr.Dataset(
        {"gap_m": ("trial", np.linspace(0.1e-3, 0.9e-3, 5)),
         "ball_material": ("trial", np.array(["carbide", "steel", "tungsten", "steel",
                                              "carbide"])),
         "statistic": (("trial", "objective"), stat),
         "error": (("trial", "objective"), stat * 0.01),
         "published_statistic": ("objective", [3e-4]),
         "pareto": ("trial", np.zeros(5, bool))},
        coords={"trial": np.arange(5), "objective": [objectives]},
        attrs={"objectives": objectives, "statistic": "mean", "band": "worst", "best_trial": 1,
               "sampler": "tpe", "samples": 4, "bar": "ball", "preset": "paper",
               "published_system": json.dumps(system)})


def test_design_figures_are_in_mm():
    ds = _design_dataset()
    fig = plot_design(ds)
    visible = [ax for ax in fig.axes if ax.get_visible()]
    assert len(visible) == 2  # one panel a variable; no Pareto panel for one objective
    assert visible[0].get_xlabel() == "gap (mm)"
    assert visible[0].get_ylabel() == "mean of worst tip RMS over the band (mm)"
    best = next(ln for ln in visible[0].get_lines() if ln.get_label() == "best")
    assert best.get_ydata()[0] == pytest.approx(ds["statistic"].values[1, 0] * 1e3)
    assert best.get_xdata()[0] == pytest.approx(ds["gap_m"].values[1] * 1e3)  # SI data, mm axis
    assert fig._suptitle.get_text().startswith("published bar, paper preset: design search")
    cmp = {"x": np.linspace(0.98, 1.02, 3), "quantity": "rms_tip_m", "force_n": 10.0,
           "bar": "ball", "curves": {"best design": np.array([1e-4, 2e-4, 1e-4]),
                                     "file's design": np.array([2e-4, 3e-4, 2e-4]),
                                     "bare bar": np.array([3e-4, 4e-4, 3e-4])}}
    ax = plot_design_comparison(cmp, ds.attrs).axes[0]
    assert ax.get_ylabel() == "tip RMS (mm), F0 = 10 N"
    assert ax.get_lines()[0].get_ydata()[1] == pytest.approx(0.2)


def test_smallest_text_px_reads_the_drawn_text(own_bar_sweep):
    fig = plot_sweep(own_bar_sweep)
    px = smallest_text_px(fig, shown_width_px=fig.get_figwidth() * 72)  # 1 px a point
    smallest = min(t.get_fontsize() for t in fig.findobj(Text)
                   if t.get_visible() and t.get_text().strip())
    assert px == pytest.approx(smallest)
    assert 650 / (72 * 7.2) * smallest >= 10  # readable in one of the report's columns


def test_a_verdict_s_method_in_a_title_is_a_few_words():
    """The converged verdict's title says what a cut must do to be chatter-free, from which
    knocks, and how it is integrated; the rest of the method (caps, confidence) stays in
    the file's method_text, which a title takes as it is for another criterion."""
    a = {"criterion": "growth", "tolerance_m": 1e-5, "knock_m": 1e-6, "knocks_m": "[]",
         "integrator_used": "rk4", "dt_s": 2e-6, "method_text": "x" * 400}
    assert method_words(a) == ("converged verdict: settled within 10 um p-p with the tool in "
                               "the cut, after a 1 um knock; RK4, dt = 2 us")
    two = method_words({**a, "knocks_m": "[2e-05]"})
    assert "after knocks of 1 and 20 um;" in two
    assert method_words({**a, "criterion": "zero"}) == a["method_text"]

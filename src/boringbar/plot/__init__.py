"""Figures (matplotlib, at the edge of the package): one module per analysis, each
function returning a ``matplotlib.figure.Figure``, plus the shared palette and style.

Figures are built as Figure objects and rendered by the Agg canvas, without pyplot, so
no global backend or figure state is touched (safe in threads, in notebooks, on headless
machines); :func:`boringbar.io.save_figure_atomic` saves one.  A multi-panel figure is
drawn into ``fig`` when given (a Figure, or a SubFigure from ``Figure.subfigures`` to
place it beside others).  The core never imports matplotlib: ``import boringbar`` loads
this package only when ``bb.plot`` or a ``Run.plot()`` is first used.
"""

from boringbar.plot.bar import plot_frf_fit, plot_modes, plot_stabilisation
from boringbar.plot.basins import plot_basins
from boringbar.plot.bifurcation import plot_bifurcation
from boringbar.plot.chatter import plot_chatter_map
from boringbar.plot.design import (
    plot_best,
    plot_cut_comparison,
    plot_depth_comparison,
    plot_design,
    plot_design_comparison,
)
from boringbar.plot.lobes import plot_analytic_lobes, plot_lobes
from boringbar.plot.orbits import plot_continuation
from boringbar.plot.run import plot_lobe_examples, plot_run
from boringbar.plot.sweep import plot_sweep
from boringbar.plot.variations import plot_ladder, plot_sensitivity

__all__ = [
    "plot_analytic_lobes",
    "plot_basins",
    "plot_best",
    "plot_bifurcation",
    "plot_chatter_map",
    "plot_continuation",
    "plot_cut_comparison",
    "plot_depth_comparison",
    "plot_design",
    "plot_design_comparison",
    "plot_frf_fit",
    "plot_ladder",
    "plot_lobe_examples",
    "plot_lobes",
    "plot_modes",
    "plot_run",
    "plot_sensitivity",
    "plot_stabilisation",
    "plot_sweep",
]

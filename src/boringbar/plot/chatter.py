"""The chatter amplitude map's figure (:func:`plot_chatter_map`; matplotlib, the edge of
the package, as :mod:`boringbar.plot`).

One panel per case: the settled tip peak-to-peak of every (speed, depth) cell, the worst
over the starts, on one logarithmic colour scale for every case; the tolerance's contour;
the chatter-free depth, the onset and the linear host's analytic limit as lines; the
cells where the tool leaves the cut crossed, the undecided ones marked.
"""

from __future__ import annotations

import json
import math
import textwrap

import numpy as np
from matplotlib import colormaps
from matplotlib import patheffects as pe
from matplotlib.collections import LineCollection
from matplotlib.colors import LogNorm
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from boringbar.analysis.chatter_map import UNDECIDED
from boringbar.analysis.verdict import DECAYING
from boringbar.plot.style import (
    COLUMN_WIDTH_IN,
    DARK_GREY,
    GREY,
    OKABE_ITO,
    case_title,
    method_words,
    set_title,
)

#: The colour scale's sequence (light: small vibration, dark: large) and the fill of a
#: cell whose vibration is not known (undecided, or a linear bar not run on).
COLOUR_MAP = "YlOrRd"
UNKNOWN_COLOUR = "#c8c8c8"
#: The scale's floor, as a fraction of the tolerance: a knock that dies out (0) and
#: vibration far within the budget share its lightest colour.
FLOOR_FRACTION = 0.01
#: The lines over the map.
LINES = {
    "free": dict(color="black", lw=1.6, marker="o", ms=3.5, mfc="white", mew=1.0),
    "onset": dict(color="black", lw=1.2, ls="--", marker="_", ms=7),
    "small_alone": dict(color="black", lw=1.3, ls=":"),
    "free_to_top": dict(color="black", ls="none", marker="^", ms=5.5, mfc="white", mew=1.0),
    "host": dict(color=GREY, lw=0.9, ls="-."),
    "tolerance": dict(color=OKABE_ITO["blue"], lw=1.3),
}
#: Most cases stacked in one column; more take two columns.
MAX_ROWS = 3
_OUTLINE = [pe.withStroke(linewidth=2.6, foreground="white")]


def worst_pp_m(ds) -> np.ndarray:
    """The largest settled tip peak-to-peak over the starts (m; case x rpm x depth), NaN
    where no start's is known.  A start still decaying when its run ended (below the
    tolerance, every amplitude falling at the verdict's confidence) dies out: 0."""
    pp = np.where(ds["settled_status"].values == DECAYING, 0.0, ds["settled_pp_m"].values)
    known = np.isfinite(pp).any(axis=-1)
    return np.where(known, np.nanmax(np.where(np.isfinite(pp), pp, -np.inf), axis=-1), np.nan)


def colour_norm(ds) -> LogNorm:
    """One logarithmic scale (um) for every case: from FLOOR_FRACTION of the tolerance to
    the largest settled peak-to-peak (at least ten tolerances)."""
    tol_um = ds.attrs["tolerance_m"] * 1e6
    pp = worst_pp_m(ds) * 1e6
    top = float(np.nanmax(pp)) if np.isfinite(pp).any() else 0.0
    return LogNorm(FLOOR_FRACTION * tol_um, max(10 * tol_um, top))


def plot_chatter_map(ds, *, fig=None) -> Figure:
    """The chatter map of :func:`~boringbar.analysis.chatter_map.chatter_map`, as a
    Figure (drawn into ``fig`` when given).

    One panel per case, depth of cut (mm) against spindle speed (rpm), every case on one
    depth axis and one colour scale: each cell coloured by its settled tip peak-to-peak
    (um, log scale; the worst over the starts; grey where none is known), crossed where
    the tool leaves the cut, marked "?" where undecided; the contour where the settled
    peak-to-peak is the tolerance; the chatter-free depth (circles: every depth up to it
    is chatter-free; dotted: the same from the small knock alone, where there are large
    knocks), the onset (dashed: a small knock starts to grow) and the linear host's
    analytic limit (dash-dot: for a ball, the bare bar, without its ball).
    """
    n = ds.sizes["case"]
    ncol = 1 if n <= MAX_ROWS else 2  # a map's speeds want the figure's whole width
    nrow = math.ceil(n / ncol)
    if fig is None:
        fig = Figure(figsize=(COLUMN_WIDTH_IN, 3.0 * nrow + 2.6), layout="constrained")
    axes = np.atleast_1d(fig.subplots(nrow, ncol, sharex=True, sharey=True,
                                      squeeze=False).ravel())
    norm = colour_norm(ds)
    cmap = colormaps[COLOUR_MAP].with_extremes(bad=UNKNOWN_COLOUR, under=colormaps[
        COLOUR_MAP](0.0))
    for i in range(n):
        mesh = _panel(axes[i], ds, i, norm, cmap)
        if i // ncol == nrow - 1 or i + ncol >= n:
            axes[i].set_xlabel("spindle speed (rpm)")
            axes[i].tick_params(labelbottom=True)
        if i % ncol == 0:
            axes[i].set_ylabel("depth of cut b (mm)")
    for ax in axes[n:]:
        ax.set_visible(False)
    _colour_bar(fig, axes[:n], mesh, ds)
    _legend(fig, ds)
    a = ds.attrs
    set_title(fig, "chatter amplitude map", a,
              f"{method_words(a)}; {a['cutting_law']}, feed {a['feed_m'] * 1e3:g} mm/rev")
    return fig


def _panel(ax, ds, i: int, norm, cmap):
    """One case's map and lines; returns the mesh (for the colour bar)."""
    rpm = ds["rpm"].values
    depth_mm = ds["depth_m"].values * 1e3
    pp_um = worst_pp_m(ds)[i] * 1e6
    shown = np.where(pp_um > 0, pp_um, norm.vmin * 0.5)  # 0: below the floor, not "bad"
    mesh = ax.pcolormesh(rpm, depth_mm, shown.T, shading="nearest", norm=norm, cmap=cmap,
                         rasterized=True)
    _tolerance_contour(ax, ds, i, rpm, depth_mm, pp_um)
    _cell_marks(ax, ds, i, rpm, depth_mm)
    _lines(ax, ds, i, rpm)
    y = cell_edges(depth_mm)
    ax.set_ylim(y[0], y[-1])
    ax.set_title(_panel_title(ds, i), fontsize="small")
    return mesh


def cell_edges(centres: np.ndarray) -> np.ndarray:
    """The edges of cells around ``centres`` (midway between them, the ends a half-step
    out), as ``pcolormesh(shading="nearest")`` draws them."""
    if centres.size < 2:
        return np.array([0.5, 1.5]) * centres[0]
    mid = 0.5 * (centres[1:] + centres[:-1])
    return np.concatenate([[2 * centres[0] - mid[0]], mid, [2 * centres[-1] - mid[-1]]])


def _tolerance_contour(ax, ds, i, rpm, depth_mm, pp_um) -> None:
    """The outline of the cells beyond the tolerance: every edge between a cell within it
    and one beyond it (a cell whose tool leaves the cut is beyond; an unknown one is
    neither)."""
    tol_um = ds.attrs["tolerance_m"] * 1e6
    left = ds["left_cut"].values[i].any(axis=-1)
    beyond = np.where(np.isfinite(pp_um), (pp_um > tol_um).astype(float), np.nan)
    beyond[left] = 1.0
    x, y = cell_edges(rpm), cell_edges(depth_mm)
    change_up = np.abs(np.diff(beyond, axis=1)) == 1  # between depth k and k + 1
    change_right = np.abs(np.diff(beyond, axis=0)) == 1  # between speed j and j + 1
    segments = [((x[j], y[k + 1]), (x[j + 1], y[k + 1])) for j, k in np.argwhere(change_up)]
    segments += [((x[j + 1], y[k]), (x[j + 1], y[k + 1])) for j, k in np.argwhere(change_right)]
    style = LINES["tolerance"]
    ax.add_collection(LineCollection(segments, colors=style["color"], linewidths=style["lw"],
                                     capstyle="projecting", zorder=2.5))


def _cell_marks(ax, ds, i, rpm, depth_mm) -> None:
    """x where the tool leaves the cut (from any start), ? where the cell is undecided."""
    rr, dd = np.meshgrid(rpm, depth_mm, indexing="ij")
    left = ds["left_cut"].values[i].any(axis=-1)
    undecided = ds["chatter_free"].values[i] == UNDECIDED
    ms = float(np.clip(90.0 / max(depth_mm.size, rpm.size), 2.5, 6.0))
    ax.plot(rr[left], dd[left], ls="none", marker="x", ms=ms, mew=0.9, color="white",
            path_effects=[pe.withStroke(linewidth=1.8, foreground=DARK_GREY)])
    ax.plot(rr[undecided], dd[undecided], ls="none", marker="$?$", ms=ms * 1.4,
            color="black")


def _lines(ax, ds, i, rpm) -> None:
    """The chatter-free depth, the onset and the linear host's analytic limit."""
    host = ds["host_analytic_curve_m"].values[i] * 1e3
    ax.plot(ds["fine_rpm"].values, host, **LINES["host"])
    onset = ds["onset_depth_m"].values[i] * 1e3
    ax.plot(rpm, np.where(onset > 0, onset, np.nan), **LINES["onset"])
    free = ds["chatter_free_depth_m"].values[i] * 1e3
    if ds.sizes["start"] > 1:
        alone = ds["chatter_free_depth_by_start_m"].values[i, :, 0] * 1e3
        ax.plot(rpm, np.where(alone > 0, alone, np.nan), **LINES["small_alone"])
    ax.plot(rpm, np.where(free > 0, free, np.nan), **LINES["free"], path_effects=_OUTLINE)
    top = np.isnan(ds["first_not_free_depth_m"].values[i])  # chatter-free to the deepest
    ax.plot(rpm[top], free[top], **LINES["free_to_top"], zorder=3)


def _panel_title(ds, i: int) -> str:
    title = case_title(ds["case"].values[i], str(ds["bar"].values[i]),
                       float(ds["gap_m"].values[i]), str(ds["friction"].values[i]))
    free = ds["chatter_free_depth_m"].values[i]
    mcf = float(ds["min_chatter_free_depth_m"].values[i])
    if not math.isfinite(mcf):
        return title
    j = int(np.nanargmin(free))
    top = float(ds["depth_m"].values[-1])
    if mcf >= top:
        return f"{title}\nchatter-free at every depth up to {top * 1e3:.3g} mm"
    return (f"{title}\nmin chatter-free depth {mcf * 1e3:.3g} mm at "
            f"{ds['rpm'].values[j]:g} rpm")


def _colour_bar(fig, axes, mesh, ds) -> None:
    """The colour scale beside the panels, the tolerance marked on it."""
    tol_um = ds.attrs["tolerance_m"] * 1e6
    bar = fig.colorbar(mesh, ax=list(axes), location="right", extend="min", shrink=0.9,
                       pad=0.02)
    bar.set_label(f"settled tip peak-to-peak (um), worst of {_n_starts(ds)}",
                  fontsize="small")
    bar.ax.axhline(tol_um, color=LINES["tolerance"]["color"], lw=2.0)
    bar.ax.tick_params(labelsize="small")


def _n_starts(ds) -> str:
    n = len(json.loads(ds.attrs["starts"]))
    return "1 start" if n == 1 else f"{n} starts"


def _legend(fig, ds) -> None:
    """What the lines, marks and grey cells mean, below the panels."""
    balls = [str(b) == "ball" for b in ds["bar"].values]
    tol_um = ds.attrs["tolerance_m"] * 1e6
    host = ("analytic limit of small vibrations: the ball held by its friction, or "
            "without friction not acting" if all(balls)
            else "analytic limit; for a ball, of small vibrations (System.linear_host)"
            if any(balls) else "analytic limit of the linear bar")
    entries = [
        (Line2D([], [], **LINES["free"]), "chatter-free depth (and every depth below)"),
        *([(Line2D([], [], **LINES["small_alone"]), "the same from the small knock alone")]
          if ds.sizes["start"] > 1 else []),
        (Line2D([], [], **LINES["free_to_top"]), "chatter-free at every depth of the grid"),
        (Line2D([], [], **LINES["onset"]), "onset: a small knock starts to grow"),
        (Line2D([], [], **LINES["host"]), host),
        (Line2D([], [], **LINES["tolerance"]), f"outline of p-p > tolerance ({tol_um:g} um)"),
        (Line2D([], [], ls="none", marker="x", color="white", mew=0.9, path_effects=[
            pe.withStroke(linewidth=1.8, foreground=DARK_GREY)]), "the tool leaves the cut"),
        (Patch(facecolor=colormaps[COLOUR_MAP](0.0), edgecolor="0.6"),
         f"dies out, or p-p <= {FLOOR_FRACTION * tol_um:g} um"),
        (Patch(facecolor=UNKNOWN_COLOUR), "not known (?: undecided)"),
    ]
    # labels wrapped to half the report's column, so two columns of them fit its width
    fig.legend([h for h, _ in entries], [textwrap.fill(t, 44) for _, t in entries],
               loc="outside lower center", ncol=2, fontsize="small", frameon=False)

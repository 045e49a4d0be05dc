"""Figures of continued periodic orbits: branches, their stability and events, over
a brute-force bifurcation diagram (the edge of the package)."""

from __future__ import annotations

import json
import textwrap

import numpy as np
from matplotlib import colormaps
from matplotlib.figure import Figure

from boringbar.plot.style import (
    COLUMN_WIDTH_IN,
    CYCLE,
    DARK_GREY,
    OKABE_ITO,
    legend_below,
    series_colour,
    set_title,
    system_words,
)

#: Marker of each continuation event kind.
EVENT_MARKERS = {"fold": "s", "branch-point": "^", "period-doubling": "D", "neimark-sacker": "*",
                 "grazing": "x", "section": "+"}


def plot_continuation(ds, *, overlay=None, fig=None) -> Figure:
    """Continued branches of :func:`~boringbar.analysis.continuation.continuation`: the
    strobe tip displacement W (mm, top) and the tip RMS (mm, bottom) against the
    parameter, one colour a branch of the map, stable stretches solid, unstable dashed,
    events marked on the curve, titled by the bar, its preset and the case.  ``overlay``: a
    bifurcation Dataset (:func:`~boringbar.analysis.bifurcation.bifurcation`) of the same
    case, its Poincare samples drawn as dark dots on top of the branches."""
    if fig is None:
        fig = Figure(figsize=(COLUMN_WIDTH_IN, 5.3), layout="constrained")
    top, bottom = fig.subplots(2, 1, sharex=True, height_ratios=(3, 1.5))
    if overlay is not None:
        for d in overlay["direction"].values:
            sel = overlay.sel(direction=d)
            w = sel["tip_displacement_m"].values * 1e3
            xx = np.broadcast_to(sel["value"].values[:, None], w.shape)
            ok = np.isfinite(w)
            top.scatter(xx[ok], w[ok], s=6, color=DARK_GREY, lw=0, rasterized=True, zorder=5)
        top.scatter([], [], s=12, color=DARK_GREY, label="brute force (strobe samples)")
    styles = set()
    for b in range(ds.sizes["branch"]):
        d = ds.isel(branch=b)
        v = d["value"].values
        ok = np.isfinite(v)
        stable = d["stable"].values.astype(bool)
        styles |= set(stable[ok].tolist())
        colour = branch_colour(b, ds.sizes["branch"])
        for ax, name in ((top, "strobe_tip_m"), (bottom, "rms_tip_m")):
            y = d[name].values * 1e3
            _stability_lines(ax, v[ok], y[ok], stable[ok], color=colour)
        if ok.any() and ds.sizes["branch"] <= MAX_BRANCH_KEYS:
            top.plot([], [], color=colour, lw=3,
                     label=f"branch {b} (period {int(d['periods'])})" if "periods" in d
                     else f"branch {b}")
        _events(top, d, v[ok])
    for is_stable in sorted(styles, reverse=True):  # one key for the line styles
        top.plot([], [], color=DARK_GREY, lw=1.6, ls="-" if is_stable else "--",
                 label="stable" if is_stable else "unstable")
    top.set_ylabel("tip displacement W (mm)\nat $\\Omega t = 0$ mod $2\\pi$")
    bottom.set_ylabel("tip RMS (mm)")
    bottom.set_xlabel(PARAMETER_NAMES.get(ds.attrs.get("parameter"), ds.attrs.get("parameter")))
    for ax in (top, bottom):
        ax.grid(alpha=0.3)
    # the branches, then the events and the line styles
    legend_below(fig, [top], ncol=3, order=lambda k: (not k.startswith("branch "),
                                                      k in ("stable", "unstable")))
    if not np.isfinite(ds["value"].values).any():  # every branch refused at its start
        reasons = json.loads(ds.attrs.get("stop_reasons", "[]"))
        top.text(0.5, 0.5, "\n".join(textwrap.wrap("; ".join(dict.fromkeys(reasons)), 90)),
                 transform=top.transAxes, ha="center", va="center", fontsize="small",
                 bbox={"fc": "white", "ec": "none", "alpha": 0.85}, zorder=6)
    system = json.loads(ds.attrs.get("config", "{}")).get("system") or {}
    parameter = PARAMETER_NAMES.get(ds.attrs.get("parameter"), str(ds.attrs.get("parameter")))
    set_title(fig, "periodic orbits continued in " + parameter.split(" (")[0], ds.attrs,
              system_words(system))
    return fig


def branch_colour(b: int, count: int):
    """Branch b's colour among ``count``: the colour-blind cycle (plot_style) while it
    suffices, else one of twenty (tab20), so that a map's branches do not share colours
    until twenty (the cycle repeats after eight)."""
    return series_colour(b) if count <= len(CYCLE) else colormaps["tab20"](b % 20)


#: Branches are keyed by number and period in the legend up to this many.
MAX_BRANCH_KEYS = 10


#: Axis labels of the continuation parameters.
PARAMETER_NAMES = {"force-n": "F0 (N)", "ratio": "$\\Omega/\\omega_n$", "gap-mm": "gap (mm)",
                   "restitution": "restitution e", "friction-force-n": "friction force (N)",
                   "ball-mass-g": "ball mass (g)"}


def _sorted(x, y):
    order = np.argsort(x)
    return x[order], y[order]


def _stability_lines(ax, x, y, stable, color: str = "C0") -> None:
    """Consecutive stretches of one stability: solid if stable, dashed if not (one colour
    a branch)."""
    start = 0
    for i in range(1, len(x) + 1):
        if i == len(x) or stable[i] != stable[start]:
            j = min(i + 1, len(x))
            ax.plot(x[start:j], y[start:j], color=color, lw=1.6,
                    ls="-" if stable[start] else "--")
            start = i


def _events(ax, d, v) -> None:
    """The branch ``d``'s events on its curve (``v`` its finite parameter values): an event
    outside them (a child's birth, which it inherits, short of its first point) is drawn
    on the branch that passes through it."""
    y = d["strobe_tip_m"].values[np.isfinite(d["value"].values)] * 1e3
    for kind, value in zip(d["event_kind"].values, d["event_value"].values, strict=True):
        if not str(kind) or not np.isfinite(value):  # padding of a stacked branch
            continue
        if not (v.size and v.min() <= value <= v.max()):
            continue
        ax.plot([value], [np.interp(value, *_sorted(v, y))], ls="none",
                marker=EVENT_MARKERS.get(str(kind), "o"), ms=9, mfc="none",
                color=OKABE_ITO["black"], mew=1.4, label=str(kind))

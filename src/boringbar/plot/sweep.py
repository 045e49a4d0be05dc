"""The frequency sweep's figure: the tip's RMS over the frequency ratio, each case's
impact pattern as its marker."""

from __future__ import annotations

import math
import re

import numpy as np
from matplotlib.figure import Figure

from boringbar.plot.style import (
    BAR_STYLE,
    COLUMN_WIDTH_IN,
    PATTERN_STYLE,
    pattern_class,
    set_title,
    zero_based,
)

# --- a sweep ---------------------------------------------------------------------

def plot_sweep(ds, force: float | None = None, *, fig=None) -> Figure:
    """Tip RMS against Omega/omega_n at one ``force`` (N; may be omitted when
    ``ds`` holds one force), in the layout of the published figures.

    Each figure has one panel per (gap x friction) of the ball cases, rows
    by gap and columns by friction (2 x 2 for the published study), each
    showing the solid bar, the TMD bar and that ball case; every ball point
    is marked by its impact-pattern class (legend below the panels), with
    the number of impacts per period, n (or n/k per k periods), written
    beside the n-symmetric and n-asymmetric ones.
    Without ball cases there is one panel.
    """
    forces = [float(f) for f in np.atleast_1d(ds["force_n"].values)]
    if force is None:
        if len(forces) != 1:
            raise ValueError(f"force = None: the sweep holds {len(forces)} forces "
                             f"({', '.join(f'{f:g}' for f in forces)} N); give one")
        force = forces[0]
    return _sweep_figure(ds.sel(force_n=float(force)), float(force), ds.attrs, fig)


def _sweep_figure(ds, force: float, attrs: dict, fig=None) -> Figure:
    bars = [str(b) for b in ds["bar"].values]
    gaps = ds["gap_m"].values
    fric = [str(v) for v in ds["friction"].values]
    balls = [i for i, b in enumerate(bars) if b == "ball"]
    gap_rows = sorted({float(gaps[i]) for i in balls}, reverse=True) or [math.nan]
    fric_cols = [v for v in ("off", "on") if any(fric[i] == v for i in balls)] or ["n/a"]
    rms = ds["rms_tip_m"].values * 1e3
    nr, nc = len(gap_rows), len(fric_cols)
    if fig is None:
        fig = Figure(figsize=(COLUMN_WIDTH_IN, 2.5 * nr + 1.9), layout="constrained")
    axes = np.atleast_2d(fig.subplots(nr, nc, sharex=True, sharey=True, squeeze=False))
    seen: set[str] = set()
    for r, gap in enumerate(gap_rows):
        for c, fr in enumerate(fric_cols):
            ax = axes[r, c]
            mine = [i for i in balls if float(gaps[i]) == gap and fric[i] == fr]
            _sweep_panel(ax, ds, [i for i, b in enumerate(bars) if b in ("solid", "tmd")]
                         + mine, seen)
            if balls:
                ax.set_title(f"gap {gap * 1e3:g} mm, friction {fr}", fontsize="medium")
            if r == nr - 1:
                ax.set_xlabel(r"frequency ratio $\Omega/\omega_n$")
            if c == 0:
                ax.set_ylabel("tip RMS (mm)")
    # once, after every panel is drawn: the panels share y, and a limit set while
    # drawing would freeze it before the later panels' larger values
    zero_based(axes[0, 0], rms)
    _sweep_legend(fig, axes[0, 0], seen)
    set_title(fig, f"tip RMS against frequency ratio, F0 = {force:g} N", attrs,
              f"{attrs.get('duration_s', math.nan):g} s runs, "
              f"dt = {attrs.get('dt_s', math.nan):g} s")
    return fig


def _sweep_panel(ax, ds, cases: list[int], seen: set[str]) -> None:
    """The solid, TMD and ball cases ``cases`` of one sweep panel, each bar in its own
    colour and line; every ball point marked by its pattern class (added to ``seen``)
    and its impacts per period written beside the n-symmetric and n-asymmetric ones."""
    ratio = ds["ratio"].values
    for i in cases:
        kind = str(ds["bar"].values[i])
        style = BAR_STYLE[kind]
        y = ds["rms_tip_m"].values[i] * 1e3
        ax.plot(ratio, y, color=style["color"], ls=style["ls"], lw=1.4,
                marker="." if kind != "ball" else None, label=style["label"])
        if kind != "ball":
            continue
        for x, v, name in zip(ratio, y, ds["pattern"].values[i], strict=True):
            cls = pattern_class(name)
            marker, colour = PATTERN_STYLE.get(cls, ("o", "black"))
            seen.add(cls)
            ax.plot([x], [v], ls="none", marker=marker, color=colour, ms=7,
                    markeredgecolor="black", markeredgewidth=0.6)
            if cls in ("symmetric", "asymmetric"):  # n (per k periods) beside it
                n = re.sub(r"^(\d+)\D*(?:period (\d+)\))?$", r"\1/\2", str(name)).rstrip("/")
                ax.annotate(n, (x, v), xytext=(5, 4), textcoords="offset points",
                            fontsize="small")
    ax.grid(alpha=0.3)


def _sweep_legend(fig, ax, seen: set[str]) -> None:
    """The bars' lines, then the pattern markers seen, below the panels."""
    handles, labels = ax.get_legend_handles_labels()
    for cls in (k for k in PATTERN_STYLE if k in seen):
        marker, colour = PATTERN_STYLE[cls]
        handles.append(ax.plot([], [], ls="none", marker=marker, color=colour, ms=7,
                               markeredgecolor="black", markeredgewidth=0.6)[0])
        labels.append(f"pattern: n {cls}" if cls in ("symmetric", "asymmetric")
                      else f"pattern: {cls or 'none (locked ball)'}")
    fig.legend(handles, labels, loc="outside lower center", ncol=2 if len(labels) > 3 else 3,
               fontsize="small", frameon=False)



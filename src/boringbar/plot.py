"""Figures of runs and sweeps (matplotlib; the edge of the package).

Only the command line and users import this module; the core never imports
matplotlib.  Figures are built as ``matplotlib.figure.Figure`` objects and
rendered by the Agg canvas, without pyplot, so no global backend or figure
state is touched (safe in threads, in notebooks, on headless machines).
"""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from boringbar.io import save_figure_atomic

#: Marker and colour per impact-pattern class (patterns.PATTERN_LABELS).
PATTERN_STYLE = {
    "no impact": ("o", "#9e9e9e"),
    "symmetric": ("s", "#1f77b4"),
    "asymmetric": ("^", "#ff7f0e"),
    "sticking": ("D", "#2ca02c"),
    "no impact with sticking": ("v", "#8c564b"),
    "non-uniform": ("X", "#d62728"),
    "": ("o", "black"),  # no pattern (locked ball)
}


def pattern_class(name: str) -> str:
    """'2 symmetric' -> 'symmetric', '3 asymmetric (period 2)' -> 'asymmetric'."""
    return re.sub(r"^\d+\s+|\s*\(period \d+\)$", "", str(name)).strip()


# --- one run ---------------------------------------------------------------------

def plot_run(run_or_ds, path, zoom_periods: float = 5) -> Path:
    """Time traces of one run, saved to ``path``.

    ``run_or_ds``: a :class:`~boringbar.simulate.Run` simulated with
    ``record_every`` or its ``history_dataset()``.  Two rows sharing time:
    tip displacement W (mm); below it the ball's displacement y relative to
    the bar (mm) with the walls at +-delta/2 dashed (ball bar), the absorber
    stroke (mm) (TMD bar), or the force at the tip (N) (solid bar, locked ball).
    The left column is the whole record (a dotted line marks the start of the
    steady part, over which RMS and pattern are computed); the right column
    zooms on its last ``zoom_periods`` forcing periods, where the impact
    pattern can be seen.
    """
    ds = run_or_ds.history_dataset() if hasattr(run_or_ds, "history_dataset") else run_or_ds
    summary = json.loads(ds.attrs.get("summary", "{}"))
    config = json.loads(ds.attrs.get("config", "{}"))
    damper = (config.get("system") or {}).get("damper") or {}
    kind = summary.get("bar", "?")
    t = ds["time"].values
    w = ds["tip_displacement"].values * 1e3
    if kind == "ball" and "y" in ds:
        lower, lower_label, colour = ds["y"].values * 1e3, "ball displacement y\nrelative to " \
            "bar (mm)", "#2ca02c"
    elif kind == "tmd" and "absorber_stroke" in ds:
        lower, lower_label, colour = (ds["absorber_stroke"].values * 1e3,
                                      "absorber stroke (mm)", "#9467bd")
    else:
        lower, lower_label, colour = ds["force"].values, "tip force f (N)", "#8c564b"

    fig = Figure(figsize=(12, 6.5), layout="constrained")
    axes = fig.subplots(2, 2, sharex="col", sharey="row", width_ratios=(3, 1))
    freq = summary.get("forcing_frequency_hz") or 0.0
    t_zoom = t[-1] - zoom_periods / freq if freq > 0 and t.size else -np.inf
    zoom = t >= t_zoom
    for col, sel in enumerate((slice(None), zoom)):
        axes[0, col].plot(t[sel], w[sel], lw=0.6 if col == 0 else 1.0, color="#1f77b4")
        axes[1, col].plot(t[sel], lower[sel], lw=0.6 if col == 0 else 1.0, color=colour)
        axes[1, col].set_xlabel("time t (s)")
        if t[sel].size:
            axes[0, col].set_xlim(t[sel][0], t[sel][-1])
    axes[0, 0].set_ylabel("tip displacement W (mm)")
    axes[1, 0].set_ylabel(lower_label)
    axes[0, 1].set_title(f"last {zoom_periods:g} periods", fontsize="medium")

    rms = summary.get("rms_tip_m")
    if rms is not None:
        for ax in axes[0]:
            ax.axhline(rms * 1e3, color="#555555", lw=0.9, ls="-.",
                       label=f"steady RMS = {rms * 1e3:.4g} mm" if ax is axes[0, 0] else None)
    if kind == "ball":
        half = damper.get("gap_m", math.nan) / 2 * 1e3
        for ax in axes[1]:
            for s in (1, -1):
                ax.axhline(s * half, color="black", ls="--", lw=1.0,
                           label=r"walls at $\pm\delta/2$" if s == 1 and ax is axes[1, 0]
                           else None)
        axes[1, 0].set_ylim(-1.25 * half, 1.25 * half)
    steady = config.get("steady_start_s")
    if steady is not None:
        for ax in axes[:, 0]:
            ax.axvline(steady, color="#555555", ls=":", lw=1.2,
                       label="start of steady part" if ax is axes[0, 0] else None)
    for ax in axes.flat:
        ax.grid(alpha=0.3)
    handles, labels = [], []
    for ax in axes[:, 0]:
        h, lab = ax.get_legend_handles_labels()
        handles += h
        labels += lab
    if handles:
        fig.legend(handles, labels, loc="outside lower center", ncol=len(labels),
                   fontsize="small", frameon=False)
    fig.suptitle(_run_title(summary, damper))
    return save_figure_atomic(fig, path)


def _run_title(summary: dict, damper: dict) -> str:
    kind = summary.get("bar", "?")
    name = "ball bar (ball locked)" if kind == "locked" else f"{kind} bar"
    line1 = (f"{name}, {summary.get('preset', '?')} preset: "
             f"F0 = {summary.get('force_n', math.nan):g} N, "
             f"$\\Omega/\\omega_n$ = {summary.get('ratio', math.nan):.4g} "
             f"({summary.get('forcing_frequency_hz', math.nan):.1f} Hz)")
    parts = []
    if kind in ("ball", "locked") and damper:
        parts.append(f"gap {damper.get('gap_m', math.nan) * 1e3:g} mm")
        parts.append(f"friction {damper.get('friction_force_n', 0.0):.3g} N")
        parts.append(f"e = {damper.get('restitution', math.nan):g}")
    if summary.get("pattern"):
        ipc = summary.get("impacts_per_cycle")
        parts.append(f"pattern: {summary['pattern']}"
                     + (f" ({ipc:.3g} impacts/period)" if ipc is not None else ""))
    if kind == "tmd":
        parts.append(f"absorber: {damper.get('design', '?')} design")
    lines = [line1, ", ".join(parts)]
    if summary.get("readings"):
        lines.append("published readings: " + ", ".join(summary["readings"]))
    return "\n".join(x for x in lines if x)


# --- a sweep ---------------------------------------------------------------------

def plot_sweep(ds, path, force=None) -> list[Path]:
    """Tip RMS against Omega/omega_n in the layout of the published figures.

    One figure per force.  With ``force`` given, only that force is drawn,
    to ``path``.  With ``force=None`` and one force in ``ds`` the figure goes
    to ``path``; with several forces, one file per force, named ``path``
    with ``_F<force>N`` before the suffix (``sweep_F10N.png``,
    ``sweep_F20N.png``).  Returns the paths written.

    Each figure has one panel per (gap x friction) of the ball cases, rows
    by gap and columns by friction (2 x 2 for the published study), each
    showing the solid bar, the TMD bar and that ball case; every ball point
    is marked by its impact-pattern class (legend below the panels), with
    the number of impacts per period, n (or n/k per k periods), written
    beside the n-symmetric and n-asymmetric ones.
    Without ball cases there is one panel.
    """
    path = Path(path)
    forces = [float(f) for f in np.atleast_1d(ds["force"].values)]
    if force is not None:
        targets = [(float(force), path)]
    elif len(forces) == 1:
        targets = [(forces[0], path)]
    else:
        targets = [(f, path.with_name(f"{path.stem}_F{f:g}N{path.suffix}")) for f in forces]
    written = []
    for f, p in targets:
        written.append(save_figure_atomic(_sweep_figure(ds.sel(force=f), f, ds.attrs), p))
    return written


def _sweep_figure(ds, force: float, attrs: dict) -> Figure:
    bars = [str(b) for b in ds["bar"].values]
    gaps = ds["gap"].values
    fric = [str(v) for v in ds["friction"].values]
    balls = [i for i, b in enumerate(bars) if b == "ball"]
    gap_rows = sorted({float(gaps[i]) for i in balls}, reverse=True) or [math.nan]
    fric_cols = [v for v in ("off", "on") if any(fric[i] == v for i in balls)] or ["n/a"]
    refs = [i for i, b in enumerate(bars) if b in ("solid", "tmd")]
    ratio = ds["ratio"].values
    rms = ds["rms_tip_m"].values * 1e3
    pattern = ds["pattern"].values

    nr, nc = len(gap_rows), len(fric_cols)
    fig = Figure(figsize=(5.2 * nc + 0.6, 3.8 * nr + 1.3), layout="constrained")
    axes = np.atleast_2d(fig.subplots(nr, nc, sharex=True, sharey=True, squeeze=False))
    seen_patterns = set()
    for r, gap in enumerate(gap_rows):
        for c, fr in enumerate(fric_cols):
            ax = axes[r, c]
            for i in refs:
                style = {"solid": dict(color="#555555", ls="-", marker="."),
                         "tmd": dict(color="#9467bd", ls="--", marker=".")}[bars[i]]
                ax.plot(ratio, rms[i], lw=1.2, label=f"{bars[i]} bar" if bars[i] == "solid"
                        else "TMD bar", **style)
            for i in balls:
                if float(gaps[i]) != gap or fric[i] != fr:
                    continue
                ax.plot(ratio, rms[i], color="black", lw=0.8, label="ball-damped bar")
                for x, y, name in zip(ratio, rms[i], pattern[i], strict=True):
                    cls = pattern_class(name)
                    marker, colour = PATTERN_STYLE.get(cls, ("o", "black"))
                    seen_patterns.add(cls)
                    ax.plot([x], [y], ls="none", marker=marker, color=colour, ms=7,
                            markeredgecolor="black", markeredgewidth=0.5)
                    if cls in ("symmetric", "asymmetric"):  # n (per k periods) beside it
                        n = re.sub(r"^(\d+)\D*(?:period (\d+)\))?$", r"\1/\2",
                                   str(name)).rstrip("/")
                        ax.annotate(n, (x, y), xytext=(5, 5), textcoords="offset points",
                                    fontsize=7, color=colour)
            if balls:
                ax.set_title(f"gap {gap * 1e3:g} mm, friction {fr}", fontsize="medium")
            ax.grid(alpha=0.3)
            if r == nr - 1:
                ax.set_xlabel(r"frequency ratio $\Omega/\omega_n$")
            if c == 0:
                ax.set_ylabel("tip RMS (mm)")
            ax.set_ylim(bottom=0)

    handles, labels = axes[0, 0].get_legend_handles_labels()
    for cls in (k for k in PATTERN_STYLE if k in seen_patterns):
        marker, colour = PATTERN_STYLE[cls]
        handles.append(axes[0, 0].plot([], [], ls="none", marker=marker, color=colour, ms=7,
                                       markeredgecolor="black", markeredgewidth=0.5)[0])
        labels.append(f"pattern: n {cls}" if cls in ("symmetric", "asymmetric")
                      else f"pattern: {cls or 'none (locked ball)'}")
    ncol = len(labels) if len(labels) <= 6 else math.ceil(len(labels) / 2)
    fig.legend(handles, labels, loc="outside lower center", ncol=ncol,
               fontsize="small", frameon=False)
    fig.suptitle(f"Tip RMS against frequency ratio, F0 = {force:g} N "
                 f"({attrs.get('preset', '?')} preset; {attrs.get('duration_s', math.nan):g} s "
                 f"runs, dt = {attrs.get('dt_s', math.nan):g} s)")
    return fig

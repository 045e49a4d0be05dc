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

def plot_run(run_or_ds, path) -> Path:
    """Time traces of one run, saved to ``path``.

    ``run_or_ds``: a :class:`~boringbar.simulate.Run` simulated with
    ``record_every`` or its ``history_dataset()``.  Two panels sharing time:
    tip displacement W (mm); below it the ball's displacement y relative to
    the bar (mm) with the walls at +-delta/2 dashed (ball bar), the absorber
    stroke (mm) (TMD bar), or the cutting force (N) (solid bar, locked ball).
    A dotted line marks the start of the steady part over which the RMS and
    the pattern are computed.
    """
    ds = run_or_ds.history_dataset() if hasattr(run_or_ds, "history_dataset") else run_or_ds
    summary = json.loads(ds.attrs.get("summary", "{}"))
    config = json.loads(ds.attrs.get("config", "{}"))
    damper = (config.get("system") or {}).get("damper") or {}
    kind = summary.get("bar", "?")
    t = ds["time"].values

    fig = Figure(figsize=(10, 6.5), layout="constrained")
    ax_w, ax_2 = fig.subplots(2, 1, sharex=True)
    ax_w.plot(t, ds["tip_displacement"].values * 1e3, lw=0.6, color="#1f77b4")
    ax_w.set_ylabel("tip displacement W (mm)")
    rms = summary.get("rms_tip_m")
    if rms is not None:
        ax_w.axhline(rms * 1e3, color="#555555", lw=0.8, ls="-.",
                     label=f"steady RMS = {rms * 1e3:.4g} mm")

    if kind == "ball" and "y" in ds:
        half = damper.get("gap_m", math.nan) / 2 * 1e3
        ax_2.plot(t, ds["y"].values * 1e3, lw=0.6, color="#2ca02c")
        for s in (1, -1):
            ax_2.axhline(s * half, color="black", ls="--", lw=1.0,
                         label=r"walls $\pm\delta/2$" if s == 1 else None)
        ax_2.set_ylim(-1.25 * half, 1.25 * half)
        ax_2.set_ylabel("ball displacement y\nrelative to bar (mm)")
    elif kind == "tmd" and "absorber_stroke" in ds:
        ax_2.plot(t, ds["absorber_stroke"].values * 1e3, lw=0.6, color="#9467bd")
        ax_2.set_ylabel("absorber stroke (mm)")
    else:
        ax_2.plot(t, ds["force"].values, lw=0.6, color="#8c564b")
        ax_2.set_ylabel("cutting force f (N)")
    ax_2.set_xlabel("time t (s)")

    steady = config.get("steady_start_s")
    if steady is not None:
        for ax in (ax_w, ax_2):
            ax.axvline(steady, color="#555555", ls=":", lw=1.0,
                       label="start of steady part" if ax is ax_w else None)
    for ax in (ax_w, ax_2):
        ax.grid(alpha=0.3)
        if ax.get_legend_handles_labels()[0]:
            ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize="small",
                      frameon=False)
    ax_w.set_xlim(t[0] if t.size else 0, t[-1] if t.size else 1)
    fig.suptitle(_run_title(summary, damper))
    return save_figure_atomic(fig, path)


def _run_title(summary: dict, damper: dict) -> str:
    kind = summary.get("bar", "?")
    line1 = (f"{kind} bar, {summary.get('preset', '?')} preset: "
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
    if summary.get("readings"):
        parts.append("readings: " + ", ".join(summary["readings"]))
    return line1 + ("\n" + ", ".join(parts) if parts else "")


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
    is marked by its impact-pattern class (legend below the panels).
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
        labels.append(f"pattern: {cls or 'none (locked)'}")
    fig.legend(handles, labels, loc="outside lower center", ncol=min(len(labels), 5),
               fontsize="small", frameon=False)
    fig.suptitle(f"Tip RMS against frequency ratio, F0 = {force:g} N "
                 f"({attrs.get('preset', '?')} preset; {attrs.get('duration_s', math.nan):g} s "
                 f"runs, dt = {attrs.get('dt_s', math.nan):g} s)")
    return fig

"""Figures of runs, sweeps, lobe examples, bifurcation diagrams and basins (matplotlib;
the edge of the package); the lobes themselves are drawn by :mod:`boringbar.plot_bar`
(:func:`plot_lobes` is imported here too).

Only the command line and users import this module; the core never imports
matplotlib.  Figures are built as ``matplotlib.figure.Figure`` objects and
rendered by the Agg canvas, without pyplot, so no global backend or figure
state is touched (safe in threads, in notebooks, on headless machines).  Each
``plot_*`` function returns its Figure; :func:`boringbar.io.save_figure_atomic` saves it.
A multi-panel figure is drawn into ``fig`` when given (a Figure, or a SubFigure from
``Figure.subfigures`` to place it beside others); the single-panel ladder into ``ax``.
"""

from __future__ import annotations

import json
import math
import re

import numpy as np
from matplotlib.colors import BoundaryNorm, ListedColormap
from matplotlib.figure import Figure
from matplotlib.patches import Patch

from boringbar.plot_bar import plot_lobes  # noqa: F401 (boringbar.plot.plot_lobes)
from boringbar.plot_style import (
    BAR_STYLE,
    COLUMN_WIDTH_IN,
    GREY,
    OKABE_ITO,
    bar_colour,
    case_title,
    legend_below,
    series_colour,
    set_title,
    system_words,
    wrap_title,
    zero_based,
)
from boringbar.simulate import FIGURES

#: Marker and colour per impact-pattern class (patterns.PATTERN_LABELS): the shapes
#: tell the classes apart without colour, the colours (Okabe-Ito) without shape.
PATTERN_STYLE = {
    "no impact": ("o", GREY),
    "symmetric": ("s", OKABE_ITO["sky blue"]),
    "asymmetric": ("^", OKABE_ITO["orange"]),
    "sticking": ("D", OKABE_ITO["yellow"]),
    "no impact with sticking": ("v", OKABE_ITO["reddish purple"]),
    "non-uniform": ("X", OKABE_ITO["black"]),
    "": ("o", "white"),  # no pattern (locked ball)
}


def pattern_class(name: str) -> str:
    """'2 symmetric' -> 'symmetric', '3 asymmetric (period 2)' -> 'asymmetric'."""
    return re.sub(r"^\d+\s+|\s*\(period \d+\)$", "", str(name)).strip()


# --- one run ---------------------------------------------------------------------

def plot_run(run_or_ds, zoom_periods: float = 5, *, fig=None) -> Figure:
    """Time traces of one run, as a Figure (save it with :func:`boringbar.io.save_figure_atomic`).

    ``run_or_ds``: a :class:`~boringbar.simulate.Run` simulated with
    ``record_every`` or its ``to_xarray()``.  Two rows sharing time:
    tip displacement W (mm); below it the ball's displacement y relative to
    the bar (mm) with the walls at +-delta/2 dashed (ball bar), the absorber
    stroke (mm) (TMD bar), or the force at the tip (N) (solid bar, locked ball).
    A regenerative cut is drawn by :func:`_cut_figure` instead: tip
    displacement and cutting force, the chatter verdict in the title.
    The left column is the whole record (a dotted line marks the start of the
    steady part, over which RMS and pattern are computed); the right column
    zooms on its last ``zoom_periods`` forcing periods, where the impact
    pattern can be seen.
    """
    ds = run_or_ds.to_xarray() if hasattr(run_or_ds, "to_xarray") else run_or_ds
    summary = json.loads(ds.attrs.get("summary", "{}"))
    config = json.loads(ds.attrs.get("config", "{}"))
    if "cutting" in summary:
        return _cut_figure(ds, summary, config, fig=fig)
    damper = (config.get("system") or {}).get("damper") or {}
    kind = summary.get("bar", "?")
    t = ds["time_s"].values
    w = ds["tip_displacement_m"].values * 1e3
    lower, lower_label, colour = _run_lower(ds, kind)
    if fig is None:
        fig = Figure(figsize=(12, 6.5), layout="constrained")
    axes = fig.subplots(2, 2, sharex="col", sharey="row", width_ratios=(3, 1))
    freq = summary.get("forcing_frequency_hz") or 0.0
    t_zoom = t[-1] - zoom_periods / freq if freq > 0 and t.size else -np.inf
    zoom = t >= t_zoom
    for col, sel in enumerate((slice(None), zoom)):
        axes[0, col].plot(t[sel], w[sel], lw=0.6 if col == 0 else 1.0,
                          color=CUT_COLOURS["tip"])
        axes[1, col].plot(t[sel], lower[sel], lw=0.6 if col == 0 else 1.0, color=colour)
        axes[1, col].set_xlabel("time t (s)")
        if t[sel].size:
            axes[0, col].set_xlim(t[sel][0], t[sel][-1])
    axes[0, 0].set_ylabel("tip displacement W (mm)")
    axes[1, 0].set_ylabel(lower_label)
    axes[0, 1].set_title(f"last {zoom_periods:g} periods", fontsize="medium")
    _run_guides(axes, summary.get("rms_tip_m"), damper.get("gap_m") if kind == "ball" else None,
                config.get("steady_start_s"))
    for ax in axes.flat:
        ax.grid(alpha=0.3)
    legend_below(fig, axes[:, 0])
    what, details = _run_title(summary, damper)
    set_title(fig, what, {**ds.attrs, "preset": summary.get("preset", "?")}, details)
    return fig


def _run_lower(ds, kind: str) -> tuple[np.ndarray, str, str]:
    """The lower row of a run's figure: (values, axis label, colour): the ball's
    displacement relative to the bar, the absorber's stroke, or the tip force."""
    if kind == "ball" and "y_m" in ds:
        return ds["y_m"].values * 1e3, "ball displacement y\nrelative to bar (mm)", \
            bar_colour("ball")
    if kind == "tmd" and "absorber_stroke_m" in ds:
        return ds["absorber_stroke_m"].values * 1e3, "absorber stroke (mm)", bar_colour("tmd")
    return ds["force_n"].values, "tip force f (N)", CUT_COLOURS["force"]


def _run_guides(axes, rms, gap, steady) -> None:
    """The steady RMS on the tip's row, the walls at +-gap/2 on the ball's row (``gap``
    None: no ball) and the start of the steady part on the whole record."""
    if rms is not None:
        for ax in axes[0]:
            ax.axhline(rms * 1e3, color="#555555", lw=0.9, ls="-.",
                       label=f"steady RMS = {rms * 1e3:.4g} mm" if ax is axes[0, 0] else None)
    if gap is not None:
        half = gap / 2 * 1e3
        for ax in axes[1]:
            for s in (1, -1):
                ax.axhline(s * half, color="black", ls="--", lw=1.0,
                           label=r"walls at $\pm\delta/2$" if s == 1 and ax is axes[1, 0]
                           else None)
        axes[1, 0].set_ylim(-1.25 * half, 1.25 * half)
    if steady is not None:
        for ax in axes[:, 0]:
            ax.axvline(steady, color="#555555", ls=":", lw=1.2,
                       label="start of steady part" if ax is axes[0, 0] else None)


def _run_title(summary: dict, damper: dict) -> tuple[str, str]:
    """(what, details) of a run's title."""
    kind = summary.get("bar", "?")
    name = "ball bar (ball locked)" if kind == "locked" else f"{kind} bar"
    line1 = (f"{name}, F0 = {summary.get('force_n', math.nan):g} N, "
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
    lines = [", ".join(parts)]
    if summary.get("readings"):
        lines.append("published readings: " + ", ".join(summary["readings"]))
    return line1, "\n".join(x for x in lines if x)


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


# --- a cut -----------------------------------------------------------------------

#: Colours of the cut figures: tip, force, the first zero of the force.
CUT_COLOURS = {"tip": OKABE_ITO["blue"], "force": OKABE_ITO["orange"],
               "zero": OKABE_ITO["vermillion"]}


def _cut_figure(ds, summary: dict, config: dict, zoom_cycles: float = 30, *,
                fig=None) -> Figure:
    """Tip displacement W (mm) and cutting force f (N) against time for one
    cut; the right column zooms on the last ``zoom_cycles`` periods of the
    bar's first mode (about the chatter period)."""
    cut = summary["cutting"]
    forcing = config.get("forcing") or {}
    t = ds["time_s"].values
    rows = ((ds["tip_displacement_m"].values * 1e3, "tip displacement W (mm)", "tip"),
            (ds["force_n"].values, "cutting force f (N)", "force"))
    if fig is None:
        fig = Figure(figsize=(12, 6.5), layout="constrained")
    axes = fig.subplots(2, 2, sharex="col", sharey="row", width_ratios=(3, 1))
    fn = summary.get("natural_frequency_hz") or 0.0
    span = zoom_cycles / fn if fn > 0 else math.inf
    zoom = t >= (t[-1] - span if t.size else 0.0)
    for col, sel in enumerate((slice(None), zoom)):
        for row, (y, _, key) in enumerate(rows):
            axes[row, col].plot(t[sel], y[sel], lw=0.6 if col == 0 else 1.0,
                                color=CUT_COLOURS[key])
        axes[1, col].set_xlabel("time t (s)")
        if t[sel].size > 1:
            axes[0, col].set_xlim(t[sel][0], t[sel][-1])
    for row, (_, label, _) in enumerate(rows):
        axes[row, 0].set_ylabel(label)
    if math.isfinite(span):
        axes[0, 1].set_title(f"last {span * 1e3:.0f} ms ({zoom_cycles:g} periods of "
                             f"{fn:.0f} Hz)", fontsize="medium")
    # files written before the cut named its law: the linear law, Kr b h_m
    kr = forcing.get("kr_pa") or math.nan
    mean_force = cut.get("force_at_feed_n",
                         kr * cut["depth_m"] * forcing.get("feed_m", math.nan))
    law = cut.get("cutting_law") or f"Kr {kr / 1e6:g} MPa"
    for col in (0, 1):
        _cut_guides(axes[:, col], cut["static_deflection_m"], mean_force,
                    cut["first_zero_time_s"], labels=col == 0, values=True)
    for ax in axes.flat:
        ax.grid(alpha=0.3)
    legend_below(fig, axes)
    what = (f"{summary.get('bar', '?')} bar, cut at {cut['rpm']:g} rpm, "
            f"depth {cut['depth_m'] * 1e3:g} mm ({law}, "
            f"feed {forcing.get('feed_m', math.nan) * 1e3:g} mm/rev, "
            f"{'static start' if cut['start'] == 'static' else 'from rest'})")
    set_title(fig, what, {**ds.attrs, "preset": summary.get("preset", "?")},
              _cut_verdict(cut, summary.get("duration_s")))
    return fig


def _cut_verdict(cut: dict, duration=None) -> str:
    """'CHATTER: ...' or 'stable: ...', with the bounded-chatter verdict."""
    if cut["chatter"]:
        text = (f"CHATTER: the cutting force first reaches zero at "
                f"t = {cut['first_zero_time_s']:.4g} s")
    else:
        text = "stable: the cutting force never reaches zero" + (
            f" in {duration:g} s" if duration else "")
    amp, thr = cut["amplitude_m"] * 1e3, cut["bounded_threshold_m"] * 1e3
    rel = ">" if cut["bounded_chatter"] else "<="
    return text + f"; steady amplitude {amp:.3g} mm {rel} {thr:.3g} mm (bounded criterion)"


def _cut_guides(axes, static_m: float, mean_force: float, first_zero, labels: bool = True,
                values: bool = False):
    """Static deflection, mean force Kr b h_m, zero force and the first zero;
    ``values``: their values in the legend labels."""
    lab = (lambda text: text) if labels else (lambda text: None)
    axes[0].axhline(static_m * 1e3, color="#555555", ls="--", lw=0.9,
                    label=lab("static deflection under the mean force"
                              + (f" ({static_m * 1e3:.3g} mm)" if values else "")))
    axes[1].axhline(mean_force, color="#555555", ls="-.", lw=0.9,
                    label=lab("mean force Kr b h_m"
                              + (f" = {mean_force:.3g} N" if values else "")))
    if first_zero is not None and math.isfinite(first_zero):  # else zero would squash f
        axes[1].axhline(0.0, color="black", lw=0.8)
        for k, ax in enumerate(axes):
            ax.axvline(first_zero, color=CUT_COLOURS["zero"], ls=":", lw=1.3,
                       label=lab("first zero of the force") if k == 0 else None)


# --- lobe examples (the lobes themselves: plot_bar.plot_lobes) ----------------------

def plot_lobe_examples(ds, *, fig=None) -> Figure:
    """Tip displacement W (mm) and cutting force f (N) against time for the
    example grid points of a lobe study (dims example x time, as written by
    ``boringbar lobes --examples``), one column per example; as a Figure."""
    t = ds["time_s"].values
    n = ds.sizes["example"]
    if fig is None:
        fig = Figure(figsize=(COLUMN_WIDTH_IN if n > 1 else 0.6 * COLUMN_WIDTH_IN, 5.6),
                     layout="constrained")
    axes = np.asarray(fig.subplots(2, n, sharex=True, squeeze=False))
    panel_in = fig.get_figwidth() / n
    duration = float(t[-1]) if t.size else None
    for k, name in enumerate(ds["example"].values):
        ex = ds.isel(example=k)
        axes[0, k].plot(t, ex["tip_displacement_m"].values * 1e3, lw=0.5,
                        color=CUT_COLOURS["tip"])
        axes[1, k].plot(t, ex["force_n"].values, lw=0.5, color=CUT_COLOURS["force"])
        fz = float(ex["first_zero_time_s"].values)
        _cut_guides(axes[:, k], float(ex["static_deflection_m"].values),
                    float(ex["mean_force_n"].values), fz)
        if bool(ex["chatter"].values):
            verdict = f"chatter: the force first reaches zero at t = {fz:.3g} s"
        else:
            verdict = "the force never reaches zero" + (f" in {duration:.2g} s" if duration
                                                        else "")
        axes[0, k].set_title(wrap_title(f"{name} grid point: {float(ex['rpm'].values):g} rpm, "
                                        f"depth {float(ex['depth_m'].values) * 1e3:g} mm\n"
                                        f"{verdict}", panel_in, 8.33), fontsize="small",
                             color=CUT_COLOURS["zero"] if bool(ex["chatter"].values)
                             else OKABE_ITO["bluish green"])
        axes[1, k].set_xlabel("time t (s)")
        if t.size > 1:
            axes[0, k].set_xlim(t[0], t[-1])
    axes[0, 0].set_ylabel("tip displacement W (mm)")
    axes[1, 0].set_ylabel("cutting force f (N)")
    for ax in axes.flat:
        ax.grid(alpha=0.3)
    legend_below(fig, axes, ncol=2)
    a = ds.attrs
    case = case_title(a.get("case", "?"), a.get("bar", "?"), a.get("gap_m", math.nan),
                      a.get("friction", "?"))
    set_title(fig, f"lobe examples, {case}", a,
              "rerun with history, not stopped at the first zero of the force")
    return fig


# --- bifurcation diagram ---------------------------------------------------------

#: Marker styles of the continuation directions: backward drawn smaller and a
#: little to the right, so points where both agree show both colours.
DIRECTION_STYLE = {
    "forward": dict(color=OKABE_ITO["blue"], s=9, offset=0.0),
    "backward": dict(color=OKABE_ITO["orange"], s=3, offset=0.25),
}
HYSTERESIS_COLOUR = "#F9F3B0"  # Okabe-Ito's yellow, lightened behind the samples
#: Axis label and display scale (per SI unit) of the bifurcation parameters.
PARAMETER_AXES = {
    "force": ("force amplitude F0 (N)", 1.0),
    "ratio": (r"frequency ratio $\Omega/\omega_n$", 1.0),
    "gap": (r"gap $\delta$ (mm)", 1e3),
    "restitution": ("coefficient of restitution e", 1.0),
}


def _verdict_code(verdict: str) -> str:
    """'period-2' -> '2', 'transient' -> 't', 'quasi-periodic' -> 'q', ..."""
    if verdict.startswith("period-"):
        return verdict[len("period-"):]
    return {"transient": "t", "quasi-periodic": "q", "chaotic-like": "c"}.get(verdict, "?")


def plot_bifurcation(ds, *, fig=None) -> Figure:
    """Bifurcation diagram of :func:`~boringbar.analysis.bifurcation.bifurcation`,
    as a Figure.

    Top: the stroboscopic Poincare samples of the tip displacement W (mm)
    against the parameter, forward (blue) and backward (red, smaller, offset a
    quarter step to the right); the ranges in ``ds.attrs["hysteresis_ranges"]``
    (JSON, as ``boringbar bifurcation`` writes them) shaded.  Middle: each
    run's verdict (period k, t transient, q quasi-periodic, c chaotic-like,
    ? undetermined).  Bottom: the tip RMS (mm) of each run.
    """
    param = ds.attrs.get("parameter", "?")
    xlabel, k = PARAMETER_AXES.get(param, (f"{param} ({ds.attrs.get('units', '')})", 1.0))
    x = ds["value"].values * k
    step = float(np.min(np.abs(np.diff(x)))) if x.size > 1 else 1.0
    directions = [str(d) for d in ds["direction"].values]
    if fig is None:
        fig = Figure(figsize=(COLUMN_WIDTH_IN, 5.9), layout="constrained")
    top, mid, bottom = fig.subplots(3, 1, sharex=True, height_ratios=(3.4, 0.7, 1.5))
    ranges = json.loads(ds.attrs.get("hysteresis_ranges", "null") or "null") or []
    for n, (a, b) in enumerate(ranges):
        for ax in (top, mid, bottom):
            ax.axvspan(a * k - 0.5 * step, b * k + 0.5 * step, color=HYSTERESIS_COLOUR,
                       lw=0, zorder=0,  # one legend entry for every range
                       label="forward and backward differ" if ax is top and not n else None)
    for row, d in enumerate(directions):
        style = DIRECTION_STYLE.get(d, dict(color="black", s=4, offset=0.0))
        sel = ds.sel(direction=d)
        xd = x + style["offset"] * step
        w = sel["tip_displacement_m"].values * 1e3
        xx = np.broadcast_to(xd[:, None], w.shape)
        ok = np.isfinite(w)
        top.scatter(xx[ok], w[ok], s=style["s"], color=style["color"], lw=0, alpha=0.6,
                    rasterized=True)
        top.scatter([], [], s=25, color=style["color"], label=f"{d} sweep")
        bottom.plot(xd, sel["rms_tip_m"].values * 1e3, marker="o", ms=3, lw=1.0,
                    color=style["color"], label=d)
        for xi, verdict in zip(x, sel["verdict"].values, strict=True):
            mid.text(xi, 1 - row, _verdict_code(str(verdict)), ha="center", va="center",
                     fontsize="small", color=style["color"])
    top.set_ylabel("tip displacement W (mm)\nat $\\Omega t = 0$ mod $2\\pi$")
    mid.set_ylim(-0.7, 1.7)
    mid.set_yticks([1, 0][:len(directions)], directions)
    mid.tick_params(axis="y", length=0, labelsize="small")
    mid.set_ylabel("verdict", fontsize="small")
    bottom.set_ylabel("tip RMS (mm)")
    bottom.set_xlabel(xlabel)
    bottom.set_ylim(bottom=0)
    pad = 0.6 * step
    bottom.set_xlim(x.min() - pad, x.max() + pad)
    for ax in (top, bottom):
        ax.grid(alpha=0.3)
    _bifurcation_legend(fig, top, agree="backward" in directions and not ranges)
    set_title(fig, *_bifurcation_title(ds, param))
    return fig


def _bifurcation_legend(fig, top, agree: bool) -> None:
    """The directions (and the hysteresis shading) of ``top``, whether the directions
    ``agree`` everywhere, and what the verdict codes mean, below the panels."""
    handles, labels = top.get_legend_handles_labels()
    if agree:
        handles.append(top.plot([], [], ls="none")[0])
        labels.append("forward and backward agree at every value")
    handles.append(top.plot([], [], ls="none")[0])
    labels.append("verdicts: k = period k, t transient,\nq quasi-periodic, c chaotic-like, "
                  "? undetermined")
    fig.legend(handles, labels, loc="outside lower center", ncol=2, fontsize="small",
               frameon=False)


def _dropped_percent(attrs) -> float:
    """The dropped first part of each run, in %: 1 - steady_fraction (files written
    before steady_fraction: their ``drop``)."""
    if "steady_fraction" in attrs:
        return 100 * (1.0 - attrs["steady_fraction"])
    return 100 * attrs.get("drop", math.nan)


def _bifurcation_title(ds, param: str) -> tuple[str, dict, str]:
    """(what, attributes, details) of a bifurcation diagram's title."""
    config = json.loads(ds.attrs.get("config", "{}"))
    systems = config.get("systems") or [{}]
    words = system_words(systems[0])
    if param == "gap":
        words = re.sub(r", gap [^,]*", "", words)
    elif param == "restitution":
        words = re.sub(r", e = .*$", "", words)
    base = config.get("base_forcing") or {}
    fixed = []
    if param != "force":
        fixed.append(f"F0 = {base.get('amplitude_n', math.nan):g} N")
    if param != "ratio":
        fixed.append(f"$\\Omega/\\omega_n$ = {base.get('ratio', math.nan):g}")
    attrs = {**ds.attrs, "preset": systems[0].get("preset", ds.attrs.get("preset", "?"))}
    return (f"bifurcation diagram, {words}, {', '.join(fixed)}", attrs,
            f"continuation forward then backward; {ds.attrs.get('duration_s', math.nan):g} s "
            f"runs, first {_dropped_percent(ds.attrs):g} % dropped, "
            f"dt = {ds.attrs.get('dt_s', math.nan):g} s")


# --- basins of attraction --------------------------------------------------------

#: Attractors beyond this many (the palette's distinct colours) are drawn together in grey.
MAX_ATTRACTOR_COLOURS = 8
OTHER_COLOUR = GREY


def _attractor_colours(n: int) -> list:
    return [series_colour(i) for i in range(min(n, MAX_ATTRACTOR_COLOURS))] + \
        [OTHER_COLOUR] * max(0, n - MAX_ATTRACTOR_COLOURS)


def _attractor_label(ds, a: int) -> str:
    k = int(ds["attractor_period"].values[a])
    pattern = str(ds["attractor_pattern"].values[a]) or "no pattern"
    motion = f"period {k}" if k else "non-periodic"
    rms = float(ds["attractor_rms_tip_m"].values[a]) * 1e3
    return (f"{a}: {pattern}, {motion}, RMS {rms:.3g} mm, "
            f"{100 * float(ds['fraction'].values[a]):.1f} %")


def plot_basins(ds, *, fig=None) -> Figure:
    """Basins of attraction of :func:`~boringbar.analysis.basins.basins`, as a
    Figure.

    Left: initial tip displacement (mm) x initial tip velocity (m/s), each cell
    coloured by its attractor; the legend gives each attractor's impact
    pattern, Poincare period, tip RMS and basin fraction; the attractor id is
    written at its representative cell.  Right: if ``ds`` holds
    ``poincare_from_tip_m`` (as ``boringbar basins`` writes it), the Poincare
    map (W, W' once per forcing period) of that run, with every periodic
    attractor's Poincare points as open markers in its colour.
    """
    w0 = ds["displacement_m"].values * 1e3
    v0 = ds["velocity_m_s"].values
    label = ds["attractor"].values  # (displacement, velocity)
    n = ds.sizes["attractor_id"]
    colours = _attractor_colours(n)
    has_map = "poincare_from_tip_m" in ds
    if fig is None:
        fig = Figure(figsize=(COLUMN_WIDTH_IN, 5.4 if has_map else 6.4), layout="constrained")
    axes = np.atleast_1d(fig.subplots(1, 2 if has_map else 1,
                                      width_ratios=(1, 1) if has_map else None))
    ax = axes[0]
    ax.pcolormesh(w0, v0, label.T, shading="nearest", cmap=ListedColormap(colours),
                  norm=BoundaryNorm(np.arange(n + 1) - 0.5, n), rasterized=True)
    for a in range(min(n, MAX_ATTRACTOR_COLOURS)):
        rw = float(ds["representative_tip_displacement_m"].values[a]) * 1e3
        rv = float(ds["representative_tip_velocity_m_s"].values[a])
        ax.annotate(str(a), (rw, rv), ha="center", va="center", fontsize=9,
                    fontweight="bold", color="white",
                    bbox=dict(boxstyle="circle,pad=0.15", fc="black", ec="none", alpha=0.6))
    ax.set_xlabel("initial tip displacement $W_0$ (mm)")
    ax.set_ylabel("initial tip velocity $W'_0$ (m/s)")
    ax.set_title(f"basins: {ds.sizes['displacement_m']} x {ds.sizes['velocity_m_s']} initial "
                 f"conditions,\n{n} attractor{'s' if n != 1 else ''}", fontsize="small")
    handles = [Patch(color=colours[a], label=_attractor_label(ds, a))
               for a in range(min(n, MAX_ATTRACTOR_COLOURS))]
    if n > MAX_ATTRACTOR_COLOURS:
        rest = float(ds["fraction"].values[MAX_ATTRACTOR_COLOURS:].sum())
        handles.append(Patch(color=OTHER_COLOUR, label=f"{n - MAX_ATTRACTOR_COLOURS} "
                                                      f"more attractors, {100 * rest:.1f} %"))
    if has_map:
        _poincare_panel(axes[1], ds, colours, ax)
    fig.legend(handles=handles, loc="outside lower center",
               ncol=1 if len(handles) <= 3 else 2, fontsize="small", frameon=False,
               title="attractor: impact pattern, Poincare period, tip RMS, basin fraction",
               title_fontsize="small")
    forcing = json.loads(ds.attrs.get("forcing", "{}"))
    system = json.loads(ds.attrs.get("system", "{}"))
    set_title(fig, f"basins of attraction, {system_words(system)}", ds.attrs,
              f"F0 = {forcing.get('amplitude_n', math.nan):g} N, $\\Omega/\\omega_n$ = "
              f"{forcing.get('ratio', math.nan):g}; {ds.attrs.get('duration_s', math.nan):g} s "
              f"runs, first {_dropped_percent(ds.attrs):g} % dropped, "
              f"dt = {ds.attrs.get('dt_s', math.nan):g} s")
    return fig


def _poincare_panel(ax, ds, colours, basin_ax) -> None:
    info = json.loads(ds.attrs.get("poincare_from", "{}"))
    w = ds["poincare_from_tip_m"].values * 1e3
    v = ds["poincare_from_tip_velocity_m_s"].values
    ok = np.isfinite(w) & np.isfinite(v)
    few = ok.sum() < 200 or info.get("period", 0)
    ax.scatter(w[ok], v[ok], s=18 if few else 3, color="black", lw=0, zorder=3,
               label=f"from $W_0$ = {info.get('tip_displacement_m', math.nan) * 1e3:g} mm, "
                     f"$W'_0$ = {info.get('tip_velocity_m_s', math.nan):g} m/s")
    for a in range(min(ds.sizes["attractor_id"], MAX_ATTRACTOR_COLOURS)):
        k = int(ds["attractor_period"].values[a])
        if not k:
            continue
        cells = np.argwhere(ds["attractor"].values == a)
        if not len(cells):
            continue
        i, j = cells[0]
        cw = ds["signature_tip_m"].values[i, j, :k] * 1e3
        cv = ds["signature_tip_velocity_m_s"].values[i, j, :k]
        ax.scatter(cw, cv, s=110, facecolors="none", edgecolors=[colours[a]], lw=1.8,
                   zorder=2, label=f"attractor {a} (period {k})")
    basin_ax.plot([info.get("tip_displacement_m", math.nan) * 1e3],
                  [info.get("tip_velocity_m_s", math.nan)], marker="*", ms=15, color="white",
                  mec="black", mew=1.0, ls="none", zorder=5)
    ax.set_xlabel("tip displacement W (mm)")
    ax.set_ylabel("tip velocity W' (m/s)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize="small", loc="best")
    verdict = info.get("verdict", "?")
    ax.set_title(f"Poincare map ($\\Omega t = 0$ mod $2\\pi$) from the star:\n{verdict}, "
                 f"{int(ok.sum())} samples,\npattern {info.get('pattern') or '-'}, tip RMS "
                 f"{info.get('rms_tip_m', math.nan) * 1e3:.3g} mm", fontsize="small")


FIGURES["run"] = plot_run  # Run.plot()

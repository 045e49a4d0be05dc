"""Figures of one run (a harmonic run or a cut, their time histories and impacts) and of the
lobes' example cuts (the lobes themselves: :mod:`boringbar.plot.bar`)."""

from __future__ import annotations

import json
import math

import numpy as np
from matplotlib.figure import Figure

from boringbar.model.dampers import roll_words
from boringbar.model.oriented import geometry_words
from boringbar.plot.style import (
    COLUMN_WIDTH_IN,
    OKABE_ITO,
    bar_colour,
    case_title,
    legend_below,
    set_title,
    wrap_title,
)

# --- one run ---------------------------------------------------------------------

def plot_run(run_or_ds, zoom_periods: float = 5, *, fig=None) -> Figure:
    """Time traces of one run, as a Figure (save it with :func:`boringbar.io.save_figure_atomic`).

    ``run_or_ds``: a :class:`~boringbar.simulate.Run` simulated with
    ``record_every`` or its ``to_xarray()``.  Two rows sharing time:
    tip displacement W (mm); below it the ball's displacement y relative to
    the bar (mm) with the walls at +-delta/2 dashed (ball bar), the absorber
    stroke (mm) (TMD bar), or the force at the tip (N) (solid bar, locked ball).
    A rolling ball's run has a third row: its velocity y' and its spin r omega
    (mm/s), one line where it rolls without slip.
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
    spin = "ball_spin_m_s" in ds
    if fig is None:
        fig = Figure(figsize=(12, 8.5 if spin else 6.5), layout="constrained")
    axes = fig.subplots(3 if spin else 2, 2, sharex="col", sharey="row", width_ratios=(3, 1))
    freq = summary.get("forcing_frequency_hz") or 0.0
    t_zoom = t[-1] - zoom_periods / freq if freq > 0 and t.size else -np.inf
    zoom = t >= t_zoom
    for col, sel in enumerate((slice(None), zoom)):
        axes[0, col].plot(t[sel], w[sel], lw=0.6 if col == 0 else 1.0,
                          color=CUT_COLOURS["tip"])
        axes[1, col].plot(t[sel], lower[sel], lw=0.6 if col == 0 else 1.0, color=colour)
        if spin:
            _spin_row(axes[2, col], ds, sel, whole=col == 0)
        axes[-1, col].set_xlabel("time t (s)")
        if t[sel].size:
            axes[0, col].set_xlim(t[sel][0], t[sel][-1])
    axes[0, 0].set_ylabel("tip displacement W (mm)")
    axes[1, 0].set_ylabel(lower_label)
    axes[0, 1].set_title(f"last {zoom_periods:g} periods", fontsize="medium")
    _run_guides(axes, summary.get("rms_tip_m"), damper.get("gap_m") if kind == "ball" else None,
                config.get("steady_start_s"))
    if kind == "ball" and "impact_time_s" in ds:
        _impact_marks(axes[1, 1], ds, t_zoom, damper.get("gap_m"))
    for ax in axes.flat:
        ax.grid(alpha=0.3)
    if spin:
        axes[2, 0].set_ylabel("ball velocity y' and\nspin r$\\omega$ (mm/s)")
    legend_below(fig, [*axes[:, 0], axes[1, 1]], ncol=3 if spin else None)
    what, details = _run_title(summary, damper, (config.get("system") or {}).get("bar") or {})
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


def _spin_row(ax, ds, sel, whole: bool) -> None:
    """A rolling ball's velocity y' relative to the bar and its spin r omega (mm/s): they
    are one line where it rolls without slip, and apart by its slip where it slips
    (``whole``: the whole record's panel, which carries the labels)."""
    t = ds["time_s"].values[sel]
    lw = 0.6 if whole else 1.0
    ax.plot(t, ds["y_velocity_m_s"].values[sel] * 1e3, lw=lw, color=bar_colour("ball"),
            label="ball velocity y' relative to bar" if whole else None)
    ax.plot(t, ds["ball_spin_m_s"].values[sel] * 1e3, lw=lw, ls="--",
            color=OKABE_ITO["reddish purple"],
            label=r"spin r$\omega$ (on y' where the ball rolls without slip)" if whole
            else None)


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


def _impact_marks(ax, ds, t_from: float, gap) -> None:
    """The impacts of the run's log on the zoomed ball row, at the wall each struck: the
    record is sampled (HISTORY_ROWS rows a run), so its line may pass between an impact's
    samples and seem to stop short of the wall."""
    t = ds["impact_time_s"].values
    sel = t >= t_from
    if gap is None or not sel.any():
        return
    ax.plot(t[sel], ds["impact_wall"].values[sel] * gap / 2 * 1e3, ls="none", marker="x",
            ms=7, mew=1.5, color="black", label="impacts (the run's log)", zorder=4)


def _run_title(summary: dict, damper: dict, bar: dict) -> tuple[str, str]:
    """(what, details) of a run's title (``bar``: the modal model's record, for its
    planes)."""
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
        if damper.get("motion") == "roll":
            mus = (damper.get("mu_static", math.nan), damper.get("mu_kinetic", math.nan))
            parts.append(f"rolling ball ({roll_words(*mus)})")
        if damper.get("contact") == "hertz":
            parts.append("Hertz contact")
    if bar.get("cut_geometry"):
        parts.append("two planes: " + geometry_words(bar["cut_geometry"], kind))
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



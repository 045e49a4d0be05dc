"""Figures of one thing varied at a time: a sensitivity study (a parameter's values)
and the readings ladder (the published readings dropped one by one); matplotlib, the
edge of the package, as :mod:`boringbar.plot`."""

from __future__ import annotations

import json
import math
import re

import numpy as np
from matplotlib import colormaps
from matplotlib.figure import Figure

from boringbar.plot.style import (
    COLUMN_WIDTH_IN,
    GREY,
    TITLE_PT,
    bar_name,
    legend_below,
    series_colour,
    set_title,
    system_words,
    wrap_title,
    zero_based,
)

# --- sensitivity -----------------------------------------------------------------

def plot_sensitivity(ds, *, fig=None) -> Figure:
    """A sensitivity study (:func:`~boringbar.analysis.sensitivity.sensitivity`),
    as a Figure: one panel per force, tip RMS (mm) against Omega/omega_n,
    one line per value of the varied parameter (with its runs from several starts,
    ``rms_tip_m_starts``, a band of its colour from their least to their largest RMS,
    the line's own among them); with cuts (``cut_*`` variables,
    as ``boringbar sensitivity`` writes them) one more panel, the steady tip
    amplitude (mm) against depth of cut (mm), chatter (the force reaches zero)
    marked by filled crosses, no chatter by open circles.
    """
    kind = ds.attrs.get("sensitivity", "?")
    values = [str(v) for v in ds[kind].values]
    forces = ds["force_n"].values
    cuts = "cut_chatter" in ds
    # an ordered parameter in viridis (colour-blind safe, dark to light); else the palette
    ordered = kind in ("friction_number", "restitution")
    colours = [colormaps["viridis"](0.9 * i / max(len(values) - 1, 1)) if ordered
               else series_colour(i) for i in range(len(values))]
    n = len(forces) + cuts
    ncol = min(n, 2)
    if fig is None:
        fig = Figure(figsize=(COLUMN_WIDTH_IN, 3.1 * math.ceil(n / ncol) + 2.0),
                     layout="constrained")
    axes = np.atleast_1d(fig.subplots(math.ceil(n / ncol), ncol, squeeze=False).ravel())
    for ax in axes[n:]:
        ax.set_visible(False)
    ratio = ds["ratio"].values
    for j, force in enumerate(forces):
        ax = axes[j]
        for i, v in enumerate(values):
            ax.plot(ratio, ds["rms_tip_m"].values[i, j] * 1e3, marker="o",
                    ms=3.5 if ratio.size > 3 else 7, lw=1.2, color=colours[i],
                    label=_value_label(kind, v), alpha=0.85)
            if "rms_tip_m_starts" in ds:
                runs = np.vstack([ds["rms_tip_m"].values[i, j],
                                  ds["rms_tip_m_starts"].values[i, :, j]]) * 1e3
                ax.fill_between(ratio, runs.min(axis=0), runs.max(axis=0), color=colours[i],
                                alpha=0.18, lw=0)
        ax.set_xlabel(r"frequency ratio $\Omega/\omega_n$")
        ax.set_ylabel("tip RMS (mm)")
        zero_based(ax, np.concatenate([ds["rms_tip_m"].values[:, j].ravel(), *(
            [ds["rms_tip_m_starts"].values[:, :, j].ravel()] if "rms_tip_m_starts" in ds
            else [])]) * 1e3)
        ax.set_title(f"harmonic forcing, F0 = {force:g} N", fontsize="small")
        ax.grid(alpha=0.3)
    if cuts:
        _sensitivity_cuts(axes[n - 1], ds, colours)
    legend_below(fig, axes[:len(forces)], ncol=min(len(values), 2))
    what = "initial conditions" if kind == "initial" else kind.replace("_", " ")
    spread = (f"; bands: {ds.sizes['start'] + 1} starts, the ball at rest across the cavity"
              if "rms_tip_m_starts" in ds else "")
    set_title(fig, f"sensitivity to {what}, {_sensitivity_words(ds, kind)}", ds.attrs,
              f"{ds.attrs.get('duration_s', math.nan):g} s runs, "
              f"dt = {ds.attrs.get('dt_s', math.nan):g} s{spread}")
    return fig


def _sensitivity_cuts(ax, ds, colours) -> None:
    """The cuts of a sensitivity study: steady tip amplitude against depth, one line a
    value, chatter as filled crosses, no chatter as open circles."""
    depth = ds["depth_m"].values * 1e3
    for i, colour in enumerate(colours):
        amp = ds["cut_amplitude_m"].values[i] * 1e3
        chat = ds["cut_chatter"].values[i].astype(bool)
        ax.plot(depth, amp, lw=1.2, color=colour)
        ax.plot(depth[chat], amp[chat], ls="none", marker="X", ms=8, color=colour,
                mec="black", mew=0.5)
        ax.plot(depth[~chat], amp[~chat], ls="none", marker="o", ms=6, mfc="none",
                mec=colour, mew=1.3)
    ax.plot([], [], ls="none", marker="X", ms=8, color=GREY, mec="black", mew=0.5,
            label="chatter (force reaches zero)")
    ax.plot([], [], ls="none", marker="o", ms=6, mfc="none", mec=GREY, mew=1.3,
            label="no chatter")
    ax.legend(fontsize="small", loc="best")
    ax.set_xlabel("depth of cut b (mm)")
    ax.set_ylabel("steady tip amplitude (mm)")
    zero_based(ax, ds["cut_amplitude_m"].values * 1e3)
    ax.set_title(f"cuts at {ds.attrs.get('cut_rpm', math.nan):g} rpm", fontsize="small")
    ax.grid(alpha=0.3)


def _sensitivity_words(ds, kind: str) -> str:
    """The system of a sensitivity study in words, less what the study varies."""
    systems = json.loads(ds.attrs.get("systems", "{}"))
    words = system_words(next(iter(systems.values()), {}))
    if kind == "restitution":
        return re.sub(r", e = .*$", "", words)
    if kind == "ball":  # the friction force follows the ball's mass
        return re.sub(r" \(\w+\)|, friction [^,]*", "", words)
    if kind == "friction_number":
        return re.sub(r", friction [^,]*", "", words)
    return words


def _value_label(kind: str, value: str) -> str:
    if kind == "initial":  # 'W0=0.0005m W0'=0.5m/s y0=0m y0'=0m/s'
        nums = [float(x) for x in re.findall(r"=([-+0-9.eE]+)", value)]
        if len(nums) == 4:
            text = f"$W_0$ = {nums[0] * 1e3:g} mm, $W'_0$ = {nums[1]:g} m/s"
            if nums[2] or nums[3]:
                text += f", $y_0$ = {nums[2] * 1e3:g} mm, $y'_0$ = {nums[3]:g} m/s"
            return text
        return value
    name = {"ball": "ball", "friction_number": "friction number",
            "restitution": "e"}.get(kind, kind)
    return f"{name} = {value}" if kind != "ball" else f"{value} ball"


# --- the corrections ladder --------------------------------------------------------

def plot_ladder(ds, *, ax=None) -> Figure:
    """The readings ladder (:func:`~boringbar.report.corrections.readings_ladder`),
    as a Figure: tip RMS (mm) of each rung, from the paper preset to the
    physical one, one bar per gap, each labelled with its impact pattern; drawn on
    ``ax`` (a matplotlib Axes) if given, whose figure is returned."""
    rungs = [str(r) for r in ds["rung"].values]
    gaps = ds["gap_m"].values
    if ax is None:
        fig = Figure(figsize=(10, 5.2), layout="constrained")
        ax = fig.subplots()
    fig = ax.figure
    x = np.arange(len(rungs))
    width = 0.8 / len(gaps)
    for j, gap in enumerate(gaps):
        rms = ds["rms_tip_m"].values[:, j] * 1e3
        pos = x + (j - (len(gaps) - 1) / 2) * width
        ax.bar(pos, rms, width * 0.95, label=f"gap {gap * 1e3:g} mm", color=series_colour(j))
        for xi, r, pat in zip(pos, rms, ds["pattern"].values[:, j], strict=True):
            ax.text(xi, r, " " + str(pat), rotation=90, ha="center", va="bottom",
                    fontsize="small")
    ax.set_xticks(x, [f"{r}\n{ds['friction_force_n'].values[i, 0]:.3g} N, "
                      f"{ds['host_frequency_hz'].values[i]:.0f} Hz"
                      for i, r in enumerate(rungs)], fontsize="small")
    ax.set_ylabel("tip RMS (mm)")
    zero_based(ax, ds["rms_tip_m"].values * 1e3 * 1.6)
    ax.grid(axis="y", alpha=0.3)
    ax.legend(loc="upper left", fontsize="small")
    ax.set_title(wrap_title(f"{bar_name(ds.attrs)}: the published readings dropped one at a "
                            f"time; ball damper, friction on, F0 = "
                            f"{ds.attrs.get('force_n', math.nan):g} N, r = "
                            f"{ds.attrs.get('ratio', math.nan):g}\n(each rung keeps the changes "
                            f"to its left; {ds.attrs.get('duration_s', math.nan):g} s runs)",
                            fig.get_figwidth()), fontsize=TITLE_PT)
    return fig

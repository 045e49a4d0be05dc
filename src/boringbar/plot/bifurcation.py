"""The bifurcation diagram: the sampled steady states over a parameter, both directions of
the continuation, the patterns and the hysteresis band."""

from __future__ import annotations

import json
import math
import re

import numpy as np
from matplotlib.figure import Figure

from boringbar.plot.style import (
    COLUMN_WIDTH_IN,
    OKABE_ITO,
    dropped_percent,
    set_title,
    system_words,
)

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
            f"runs, first {dropped_percent(ds.attrs):g} % dropped, "
            f"dt = {ds.attrs.get('dt_s', math.nan):g} s")



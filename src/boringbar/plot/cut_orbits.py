"""The chatter orbit map: amplitude against depth of cut at one speed, or against speed
at one depth, each bar's branch from its Hopf point (the edge of the package)."""

from __future__ import annotations

import json

import numpy as np
from matplotlib.figure import Figure

from boringbar.plot.style import (
    BAR_STYLE,
    COLUMN_WIDTH_IN,
    OKABE_ITO,
    legend_below,
    set_title,
)

#: Marker of each event on the map.
CUT_EVENT_MARKERS = {"hopf": ("o", "Hopf point"), "fold": ("s", "fold"),
                     "tool-leaves-cut": ("v", "tool leaves the cut"),
                     "ball-wall": ("*", "ball reaches a wall"),
                     "ball-slips": ("P", "ball starts to slip"),
                     "period-doubling": ("D", "period doubling"),
                     "neimark-sacker": ("X", "Neimark-Sacker (torus)")}


def plot_cut_orbits(ds, *, fig=None) -> Figure:
    """The map of :func:`~boringbar.analysis.cut_continuation.cut_continuation`: half the
    tip's peak-to-peak (um) against depth (mm) or speed (rpm), a bar a colour, stable
    orbits solid and unstable dashed, events marked.  In depth, the steady cut lies along
    the axis (stable below its Hopf point), and where a branch folds back below its Hopf
    point the band between is shaded: there a knock can start chatter below the linear
    limit.  In speed, a dotted stretch of the axis marks where the steady cut is
    unstable, between a branch's two Hopf points."""
    if fig is None:
        fig = Figure(figsize=(COLUMN_WIDTH_IN, 4.6), layout="constrained")
    ax = fig.subplots()
    in_depth = ds.attrs.get("parameter", "depth") == "depth"
    for i, name in enumerate(ds["case"].values):
        d = ds.isel(case=i)
        style = BAR_STYLE.get(str(d["kind"].values), BAR_STYLE["solid"])
        _branch(ax, d, style["color"], f"{name}", in_depth)
    ax.set_xlabel("depth of cut b (mm)" if in_depth else "spindle speed (rpm)")
    ax.set_ylabel("chatter amplitude, half the tip's peak-to-peak (\u00b5m)")
    ax.set_ylim(bottom=0.0)
    ax.grid(alpha=0.3)
    ax.plot([], [], color="0.3", ls="-", label="stable")
    ax.plot([], [], color="0.3", ls="--", label="unstable")
    legend_below(fig, [ax], ncol=4)
    config = json.loads(ds.attrs.get("config", "{}"))
    law = config.get("forcing", {}).get("law", {})
    held = (f"at {float(ds.attrs['rpm']):g} rpm" if in_depth else
            f"at a depth of {float(ds.attrs['depth_m']) * 1e3:.4g} mm")
    set_title(fig, f"chatter orbits {held}", ds.attrs,
              f"{law.get('kind', 'linear')} cutting law; orbits continued in "
              f"{'depth' if in_depth else 'speed'} from each bar's Hopf point")
    return fig


def _branch(ax, d, color: str, label: str, in_depth: bool = True) -> None:
    x_name, x_event, unit = (("depth_m", "event_depth_m", 1e3) if in_depth
                             else ("rpm", "event_rpm", 1.0))
    b, a = d[x_name].values * unit, d["amplitude_m"].values * 1e6
    ok = np.isfinite(b)
    stable = d["stable"].values.astype(bool)
    hopf = [float(v) * unit for k, v in zip(d["event_kind"].values, d[x_event].values,
                                             strict=True) if str(k) == "hopf"]
    if hopf:  # from the Hopf point: the steady cut's amplitude 0, then the branch
        b, a = np.concatenate([[hopf[0]], b[ok]]), np.concatenate([[0.0], a[ok]])
        stable = np.concatenate([[stable[ok][0] if ok.any() else False], stable[ok]])
        if in_depth:
            ax.plot([0.0, hopf[0]], [0.0, 0.0], color=color, lw=3, alpha=0.5,
                    solid_capstyle="butt")
        elif len(hopf) > 1:  # in speed, the steady cut is unstable between the two
            ax.plot(hopf[:2], [0.0, 0.0], color=color, lw=4, ls=":", clip_on=False,
                    label="steady cut unstable (between Hopf points)")
    else:
        b, a, stable = b[ok], a[ok], stable[ok]
    # one line a stretch of equal stability (a segment's stability is its far end's), so
    # that the dashes of an unstable stretch show however short its steps
    ends = [0, *(np.flatnonzero(stable[2:] != stable[1:-1]) + 1), len(b) - 1]
    for k, (lo, hi) in enumerate(zip(ends[:-1], ends[1:], strict=True)):
        ax.plot(b[lo:hi + 1], a[lo:hi + 1], color=color, ls="-" if stable[hi] else "--",
                lw=1.8, label=label if k == 0 else None)
    folds = [float(v) * unit for k, v in zip(d["event_kind"].values, d[x_event].values,
                                              strict=True) if str(k) == "fold"]
    if in_depth and hopf and folds and min(folds) < hopf[0]:
        ax.axvspan(min(folds), hopf[0], color=color, alpha=0.12, lw=0,
                   label="a knock can start chatter (fold to Hopf)")
    for k, t, v, amp in zip(d["event_kind"].values, d["event_detail"].values,
                            d[x_event].values, d["event_amplitude_m"].values, strict=True):
        key = str(t) if str(t) in CUT_EVENT_MARKERS else str(k)
        if key not in CUT_EVENT_MARKERS or not np.isfinite(v):
            continue
        marker, name = CUT_EVENT_MARKERS[key]
        ax.plot([v * unit], [amp * 1e6], ls="none", marker=marker, ms=8, mfc="none", mew=1.4,
                color=OKABE_ITO["black"], label=name, zorder=5)

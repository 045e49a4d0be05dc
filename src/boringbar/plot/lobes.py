"""The stability lobes' figures: the simulated lobes of a lobes Dataset (verdicts,
limits, onset, settled vibration and the chance of chatter; :func:`plot_lobes`) and the
classical lobes of a frequency response (:func:`plot_analytic_lobes`), with the user's
speed marked and read out."""

from __future__ import annotations

import math
import textwrap

import numpy as np
from matplotlib.figure import Figure
from matplotlib.ticker import FixedLocator, MaxNLocator, NullFormatter, StrMethodFormatter

from boringbar._validate import ParameterError
from boringbar.plot.palette import lobe_depth_top, speed_axis
from boringbar.plot.style import (
    BAR_STYLE,
    COLUMN_WIDTH_IN,
    DARK_GREY,
    OKABE_ITO,
    TITLE_PT,
    case_title,
    method_words,
    series_colour,
    set_title,
    wrap_title,
)

# Both draw depth on a linear axis from 0 whose top follows the curves
# (palette.lobe_depth_top), their legend below the axes, and the user's speed, when given,
# as a vertical line with the depths there read out above the axes.

#: Marker styles of the lobe grid points.
LOBE_STYLE = {
    "stable": dict(marker="o", mfc="none", mec=OKABE_ITO["bluish green"],
                   color=OKABE_ITO["bluish green"], mew=1.2),
    "bounded": dict(marker="^", mfc="none", mec=OKABE_ITO["orange"], color=OKABE_ITO["orange"],
                    mew=1.2),
    "chatter": dict(marker="x", color=OKABE_ITO["vermillion"], mew=1.4),
    "undecided": dict(marker="s", mfc="none", mec="0.45", color="0.45", mew=1.0),
}
#: The vertical line at the user's speed.
SPEED_LINE = {"color": DARK_GREY, "ls": (0, (6, 2, 1, 2)), "lw": 1.3}
#: Height (points) of a line of "small" text: how much higher a title stands over a readout.
SMALL_LINE_PT = 11.0


def plot_lobes(ds, at_rpm: float | None = None, *, fig=None) -> Figure:
    """Stability lobes by simulated cuts, as a Figure: a panel per case, all on one
    depth scale (linear, mm, from 0) against spindle speed (rpm).

    Panels sharing both axes, not one axes: each grid point run is marked by its verdict
    (stable: open green circle; chatter, the force reaches zero: red cross; bounded
    chatter only: open orange triangle), and several bars' marks at one speed would
    cover each other.  One column up to three cases (a speed is one vertical line
    through them), two beyond.  Each panel: the limit line (the limiting chatter-free
    depth per speed under the dataset's criterion; broken across a gap in the speeds far
    wider than those beside it, where no cut ran), the linear bars' analytic limit over
    ``fine_rpm``, the minimum chatter-free depth starred and in the title; a caret on
    the top edge where the limit is above the axis.  The depth axis ends above the
    deepest stable point, limit or curve, or lower, near the cases' minimum chatter-free
    depths (:func:`~boringbar.plot.palette.lobe_depth_top`; the title then says where).
    Speeds spanning a wide range are on a log axis
    (:func:`~boringbar.plot.palette.speed_axis`).  The legend is below the panels.

    ``at_rpm`` (rev/min; default ``ds.attrs["at_rpm"]``, which ``boringbar lobes
    --at-rpm`` records): the user's speed, one of the grid's speeds: a vertical line
    through every panel, each case's limit there read out above its panel.
    """
    at_rpm = ds.attrs.get("at_rpm") if at_rpm is None else at_rpm
    rpm = ds["rpm"].values
    at = None if at_rpm is None else speed_index(rpm, float(at_rpm))
    n = ds.sizes["case"]
    ncol = 1 if n <= 3 else 2
    nrow = math.ceil(n / ncol)
    if fig is None:
        fig = Figure(figsize=(COLUMN_WIDTH_IN, 2.1 * nrow + 2.3), layout="constrained")
    axes = fig.subplots(nrow, ncol, sharex=True, sharey=True, squeeze=False).ravel()
    top, peak = _lobe_depth_top(ds)
    _speed_axes(axes[0], rpm, top)
    legend: dict[str, object] = {}
    for i in range(n):
        _lobe_panel(axes[i], ds, i, legend, at, top)
        if i + ncol >= n:  # the lowest panel of its column
            axes[i].set_xlabel("spindle speed (rpm)")
            axes[i].xaxis.set_tick_params(labelbottom=True)
        if i % ncol == 0:
            axes[i].set_ylabel("depth of cut b (mm)")
    for ax in axes[n:]:
        ax.set_visible(False)
    handles, labels = axes[0].get_legend_handles_labels()  # the user's speed
    legend.update(zip(labels, handles, strict=True))
    # two columns of labels at most 48 characters wide fit the report's column
    fig.legend(list(legend.values()), [textwrap.fill(k, 48) for k in legend],
               loc="outside lower center", ncol=min(len(legend), 2), fontsize="small",
               frameon=False)
    a = ds.attrs
    # files written before the lobes named their law: the linear law's Kr
    law = a.get("cutting_law") or f"Kr {a.get('kr_pa', math.nan) / 1e6:g} MPa"
    note = _cut_note(top, peak)
    set_title(fig, f"stability lobes by time-domain simulation ({a.get('method', '?')})", a,
              f"{method_words(a)}; {law}, feed {a.get('feed_m', math.nan) * 1e3:g} "
              "mm/rev" + (f"\n{note}" if note else ""))
    return fig


def _lobe_depth_top(ds) -> tuple[float, float | None]:
    """:func:`~boringbar.plot.palette.lobe_depth_top` (mm) of the limits, first unstable and
    onset depths, chatter-free points and analytic curves (the chatter points above the
    first unstable depth, a search's overshoot, may stay above the axis); a case's
    smallest limit is its minimum chatter-free depth, or, if it never chattered, the
    deepest cut it ran."""
    stable = np.where(ds["verdict"].values == 1, ds["depth_m"].values * 1e3, np.nan)
    shown = [stable, ds["limit_depth_m"].values * 1e3, ds["first_unstable_depth_m"].values * 1e3]
    for name in ("onset_depth_m", "analytic_curve_m", "limit_depth_quantile_m"):
        if name in ds:
            shown.append(ds[name].values * 1e3)
    deepest = np.nanmax(stable.reshape(stable.shape[0], -1), axis=1, initial=0.0)
    mcf = ds["min_chatter_free_depth_m"].values * 1e3
    return lobe_depth_top(shown, np.where(np.isfinite(mcf), mcf, deepest))


def _lobe_panel(ax, ds, i: int, legend: dict, at: int | None, top: float) -> None:
    """Case ``i``'s grid points, limit line (a caret on the axis's top edge ``top`` where
    the limit is above it) and analytic limit; its title, and with ``at`` (the index of
    the user's speed) its limit there read out above the panel."""
    rpm = ds["rpm"].values
    depth_mm = ds["depth_m"].values * 1e3
    v = ds["verdict"].values[i]
    rr, dd = np.meshgrid(rpm, depth_mm, indexing="ij")
    levels = np.flatnonzero((v >= 0).any(axis=0))
    deepest = depth_mm[levels[-1]] if levels.size else depth_mm[-1]
    ms = float(np.clip(150.0 / max(levels.size, 1), 2.0, 6.5))
    masks, names = _verdict_masks(ds, i)
    for key, mask in masks.items():
        if mask.any():
            h, = ax.plot(rr[mask], dd[mask], ls="none", ms=ms, **LOBE_STYLE[key])
            legend.setdefault(names[key], h)
    limit = ds["limit_depth_m"].values[i] * 1e3
    h, = ax.plot(*_broken(rpm, limit), color="black", lw=1.6, marker=".", ms=4, zorder=1.5)
    legend.setdefault("chatter-free depth" if ds.attrs.get("criterion") == "growth"
                      else "limit: last stable depth below the first chatter", h)
    if "onset_depth_m" in ds and str(ds["bar"].values[i]) == "ball":
        h, = ax.plot(*_broken(rpm, ds["onset_depth_m"].values[i] * 1e3), color="black",
                     lw=1.0, ls="--")
        legend.setdefault("onset: a small knock starts to grow (the ball off its walls)", h)
    above = ~(limit <= top)  # NaN: no chatter up to the deepest cut
    if above.any():
        h, = ax.plot(rpm[above], np.full(int(above.sum()), top), ls="none", marker=6, ms=8,
                     color="black", clip_on=False, zorder=5)
        legend.setdefault("limit above the axis (or no chatter up to the deepest cut)", h)
    if "analytic_curve_m" in ds and np.isfinite(ds["analytic_curve_m"].values[i]).any():
        h, = ax.plot(ds["fine_rpm"].values, ds["analytic_curve_m"].values[i] * 1e3,
                     color=OKABE_ITO["blue"], lw=1.0)
        legend.setdefault("analytic limit (linear, frequency domain)", h)
    if "limit_depth_quantile_m" in ds:
        _probability_contours(ax, ds, i, legend)
    ax.grid(alpha=0.3)
    title = case_title(ds["case"].values[i], str(ds["bar"].values[i]),
                       float(ds["gap_m"].values[i]), str(ds["friction"].values[i]))
    mcf = float(ds["min_chatter_free_depth_m"].values[i])
    if np.isfinite(limit).any() and math.isfinite(mcf):
        j = int(np.nanargmin(limit))
        ax.plot([rpm[j]], [limit[j]], ls="none", marker="*", ms=11, color="black",
                mfc="gold", zorder=5)
        sub = f"min chatter-free depth {mcf * 1e3:.3g} mm at {rpm[j]:g} rpm"
    else:
        sub = f"no chatter up to {deepest:.3g} mm"
    # over a readout the title stands a line higher, so the two never meet
    ax.set_title(f"{title}\n{sub}", fontsize="small",
                 pad=6.0 + (SMALL_LINE_PT if at is not None else 0.0))
    if at is not None:
        ran = np.flatnonzero(v[at] >= 0)
        depth = (f"{limit[at]:.3g} mm" if math.isfinite(limit[at]) else
                 f"no chatter up to {depth_mm[ran[-1]] if ran.size else 0.0:.3g} mm")
        _mark_speed(ax, rpm[at], f"{_speed_words(rpm[at])}: {depth}", label=i == 0)


def _probability_contours(ax, ds, i: int, legend: dict) -> None:
    """The chance of chatter of case ``i`` over its deterministic lobes: the depths where
    P(chatter) reaches 5 %, 50 % and 95 % over the draws, the band between the outer two
    shaded (docs/chatter_probability.md)."""
    rpm = ds["rpm"].values
    q = ds["limit_depth_quantile_m"].values[i] * 1e3
    colour = OKABE_ITO["reddish purple"]
    n = int(ds.attrs.get("draws", ds.sizes.get("draw", 0)))
    ax.fill_between(rpm, q[:, 0], q[:, -1], color=colour, alpha=0.15, lw=0, zorder=1)
    h, = ax.plot(rpm, q[:, 1], color=colour, lw=1.4, zorder=1.6)
    legend.setdefault(f"P(chatter) 50 % ({n} draws)", h)
    for k in (0, -1):
        h, = ax.plot(rpm, q[:, k], color=colour, lw=0.9, ls="--", zorder=1.6)
    legend.setdefault("P(chatter) 5 % and 95 %", h)


def _verdict_masks(ds, i: int) -> tuple[dict, dict]:
    """The grid points of case ``i`` by verdict, and their legend entries."""
    v = ds["verdict"].values[i]
    if ds.attrs.get("criterion") == "growth":
        onset = ds["onset"].values[i]
        return ({"stable": (v == 1) & (onset == 1), "bounded": (v == 1) & (onset != 1),
                 "chatter": v == 0, "undecided": v == 2},
                {"stable": "chatter-free: a small knock dies out",
                 "bounded": "chatter-free: the knock grows, the ball bounds it within the "
                            "tolerance",
                 "chatter": "chatter: the vibration grows past the tolerance or the tool "
                            "leaves the cut",
                 "undecided": "undecided: the longest run allowed came first"})
    vb = ds["verdict_bounded"].values[i]
    return ({"stable": (v == 1) & (vb == 1), "bounded": (v == 1) & (vb == 0), "chatter": v == 0},
            {"stable": "stable", "bounded": "bounded chatter only (force stays > 0)",
             "chatter": "chatter (force reaches zero)"})


def plot_analytic_lobes(curves, rpm_range, *, name: str = "published bar",
                        at_rpm: float | None = None, fig=None) -> Figure:
    """Classical stability lobes of tip FRFs, as a Figure: one panel, depth of cut
    (linear, mm, from 0) against spindle speed (rpm).

    One axes for every case: these are curves only, with no grid points to keep apart,
    and on one axes the bars' depths at a speed compare directly.  Each case: the lower
    envelope of its lobes (thick, in its bar's colour and line, :data:`BAR_STYLE`; the
    series' colours when kinds repeat or are not bars' kinds, as a measured FRF's), with
    one case also each lobe (thin), and its speed-independent limit (thin, dashed).  The
    depth axis ends above the highest envelope, or lower, near the speed-independent
    limits (:func:`~boringbar.plot.palette.lobe_depth_top`; the title then says where).
    Speeds spanning a wide range are on a log axis
    (:func:`~boringbar.plot.palette.speed_axis`).  The legend is below the axes.

    ``curves``: dicts with "label" (the legend's), "name" (the readout's, shorter),
    "kind" (a :data:`BAR_STYLE` key or None), "lobes" (``lobes_of_receptance``),
    "rpm" and "limit_m" (the envelope's speeds and depths, m), and with ``at_rpm``
    "depth_at_rpm_m".  ``at_rpm``: the user's speed (rev/min): a vertical line, each
    case's depth there (its "depth_at_rpm_m") marked on its envelope and read out above
    the axes beside the line.
    """
    fig = fig or Figure(figsize=(COLUMN_WIDTH_IN, 5.0), layout="constrained")
    ax = fig.subplots()
    kinds = [c["kind"] for c in curves]
    own = len(set(kinds)) == len(kinds) and all(k in BAR_STYLE for k in kinds)
    styles = [{"color": BAR_STYLE[k]["color"], "ls": BAR_STYLE[k]["ls"]} if own else
              {"color": series_colour(n), "ls": "-"} for n, k in enumerate(kinds)]
    floors, shown = [], []
    for c, style in zip(curves, styles, strict=True):
        if len(curves) == 1:  # one FRF: each of its lobes too
            _each_lobe(ax, c["lobes"], rpm_range, style["color"])
        ax.plot(c["rpm"], c["limit_m"] * 1e3, lw=2.0, label=c["label"], **style)
        floors.append(float(np.nanmin(c["lobes"]["b_lim"])) * 1e3)
        ax.axhline(floors[-1], color=style["color"], ls="--", lw=0.8)
        shown.append(c["limit_m"] * 1e3)
    top, peak = lobe_depth_top([*shown, floors], floors)
    _speed_axes(ax, np.asarray(rpm_range, dtype=float), top)
    ax.set_xlabel("spindle speed (rpm)")
    ax.set_ylabel("limiting depth of cut b (mm)")
    ax.grid(alpha=0.3)
    if at_rpm is not None:
        lines = [_speed_words(at_rpm)]
        for c, style in zip(curves, styles, strict=True):
            depth = c["depth_at_rpm_m"] * 1e3
            ax.plot([at_rpm], [depth], ls="none", marker="o", ms=6, mec="black", mew=0.6,
                    color=style["color"], zorder=5, clip_on=True)
            lines.append(f"{c['name']}: {depth:.3g} mm")
        _mark_speed(ax, at_rpm, "\n".join(lines))
    fig.legend(*ax.get_legend_handles_labels(), loc="outside lower center",
               ncol=1 if max(len(c["label"]) for c in curves) > 40 else 3,
               fontsize="small", frameon=False)
    note = _cut_note(top, peak)
    title = (f"{name}: stability lobes from the tip FRF\nfrequency domain; thin dashed: "
             "each case's speed-independent limit" + (f"\n{note}" if note else ""))
    fig.suptitle(wrap_title(title, fig.get_figwidth()), fontsize=TITLE_PT)
    return fig


def _each_lobe(ax, lobes, rpm_range, colour) -> None:
    """Each lobe of one FRF (thin) within ``rpm_range``."""
    lo, hi = rpm_range
    for j in range(len(lobes["lobe"])):
        r, b = lobes["rpm"][j], lobes["b_lim"][j]
        inside = (r >= lo) & (r <= hi)
        if inside.any():
            step = max(1, int(inside.sum()) // 400)  # enough points to draw it
            ax.plot(np.where(inside, r, np.nan)[::step], (b * 1e3)[::step], color=colour,
                    lw=0.4, alpha=0.35)


def _speed_axes(ax, rpm, top: float) -> None:
    """x over the speeds ``rpm`` (:func:`~boringbar.plot.palette.speed_axis`: a log axis when
    they span a wide range), depth from 0 to ``top`` (mm)."""
    log, ticks, ends = speed_axis(float(np.min(rpm)), float(np.max(rpm)))
    if log:
        ax.set_xscale("log")
        ax.xaxis.set_major_locator(FixedLocator(ticks))
        ax.xaxis.set_major_formatter(StrMethodFormatter("{x:g}"))
        ax.xaxis.set_minor_formatter(NullFormatter())
    ax.set_xlim(*ends)
    ax.set_ylim(0, top)
    # at least four labelled depths up the axis, wherever its top falls
    ax.yaxis.set_major_locator(MaxNLocator(nbins=6, steps=[1, 2, 2.5, 5, 10], min_n_ticks=4))


def _speed_words(at_rpm: float) -> str:
    """'your speed 1200 rpm'."""
    return f"your speed {at_rpm:g} rpm"


def speed_index(rpm, at_rpm: float, name: str = "at_rpm") -> int:
    """The index of ``at_rpm`` among the speeds ``rpm`` (within round-off): a depth is
    read where it was computed, never between two speeds."""
    hit = np.flatnonzero(np.isclose(np.asarray(rpm, dtype=float), at_rpm, rtol=1e-9, atol=0))
    if not hit.size:
        raise ParameterError(f"{name} = {at_rpm!r} rev/min is not one of the {len(rpm)} "
                             f"speeds of the lobes ({np.min(rpm):g} to {np.max(rpm):g} "
                             "rev/min): a depth is read only where it was computed "
                             "(boringbar lobes --at-rpm adds the speed to the grid)")
    return int(hit[0])


def _mark_speed(ax, at_rpm: float, readout: str, *, label: bool = True) -> None:
    """The user's speed on a lobe panel whose x limits are set: a vertical line (in the
    legend when ``label``) and ``readout``, the depths there, just above the axes
    beside the line, where it covers no curve and no point (centred on the line;
    starting or ending at it near the panel's edges, so it stays over the panel)."""
    ax.axvline(at_rpm, **SPEED_LINE, zorder=1.8, label=_speed_words(at_rpm) if label else None)
    where = ax.transAxes.inverted().transform(ax.transData.transform((at_rpm, 0.0)))[0]
    ax.annotate(readout, (at_rpm, 1.0), xycoords=("data", "axes fraction"), xytext=(0, 3),
                textcoords="offset points", va="bottom", fontsize="small", color=DARK_GREY,
                ha="left" if where < 0.25 else "right" if where > 0.75 else "center",
                annotation_clip=False)


def _cut_note(top: float, peak: float | None) -> str:
    """What a lobe figure leaves above its depth axis, for its title ('' if nothing)."""
    if peak is None:
        return ""
    return (f"depth axis cut at {top:.3g} mm, near the pockets (peaks up to {peak:.3g} mm "
            "above it)")


def _broken(x, y) -> tuple[np.ndarray, np.ndarray]:
    """``x``, ``y`` (``x`` increasing) with a NaN point in each gap more than three times
    as wide as the gaps beside it (a speed added far outside a grid): a line drawn
    across it would show limits no cut measured."""
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    gaps = np.diff(x)
    if gaps.size < 2:
        return x, y
    beside = np.maximum(np.r_[0.0, gaps[:-1]], np.r_[gaps[1:], 0.0])
    wide = np.flatnonzero(gaps > 3 * beside)
    return (np.insert(x, wide + 1, x[wide] + gaps[wide] / 2),
            np.insert(y, wide + 1, np.nan))

"""Figures of a design search: the trials against each variable, the Pareto front, and
the best design beside the published one in the first objective's own terms (the edge
of the package, as the rest of plot/): :func:`plot_best` picks the figure.

Lengths are drawn in mm and receptances in um/N, like every other figure, though the
design Dataset holds SI units."""

from __future__ import annotations

import math

import numpy as np
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.ticker import FuncFormatter

from boringbar.analysis.design_options import reading
from boringbar.plot.style import (
    BAR_STYLE,
    COLUMN_WIDTH_IN,
    GREY,
    OKABE_ITO,
    bar_colour,
    set_title,
)

#: objective -> (axis words, unit, factor from the file's SI value)
OBJECTIVE_AXES = {"rms_band": ("tip RMS over the band", "mm", 1e3),
                  "cut_amplitude": ("steady cut amplitude", "mm", 1e3),
                  "min_depth": ("min chatter-free depth", "mm", 1e3),
                  "frf_peak": ("FRF peak |G|", r"$\mu$m/N", 1e6),
                  "min_real": ("-min Re G", r"$\mu$m/N", 1e6)}
#: quantity of a comparison (boringbar.analysis.design.comparison) -> (axis label, factor)
COMPARISON_AXES = {"rms_tip_m": ("tip RMS (mm)", 1e3),
                   "receptance_m_n": (r"tip receptance |G| ($\mu$m/N)", 1e6),
                   "real_m_n": (r"tip receptance Re G ($\mu$m/N)", 1e6)}
#: the two designs of a comparison: (colour, line style, marker); the best takes its bar's
#: colour
DESIGN_STYLE = {"file's design": (OKABE_ITO["black"], "--", "s")}


def objective_axis(attrs: dict, objective: str) -> tuple[str, float]:
    """The axis label of a design objective's statistic (``attrs``: the design Dataset's
    attributes), and its factor from SI."""
    statistic = attrs["statistic"]
    if statistic == "chatter_probability":  # a probability: no unit, no factor
        return f"chatter probability ({objective.replace('_', ' ')})", 1.0
    words, unit, k = OBJECTIVE_AXES.get(objective, (objective.replace("_", " "), "SI", 1.0))
    if objective == "rms_band":  # the band's worst or mean, per sample
        words = f"{attrs.get('band', '')} {words}".strip()
    return f"{statistic} of {words} ({unit})", k


def variable_axis(name: str) -> tuple[str, float]:
    """The axis label of a design variable and its factor from SI: 'gap_m' -> ('gap
    (mm)', 1e3), 'tmd_frequency_ratio' -> ('TMD frequency ratio', 1.0)
    (:func:`~boringbar.analysis.design_options.reading`)."""
    words, unit, factor = reading(name)
    words = words.replace("tmd", "TMD")
    return (f"{words} ({unit})" if unit else words), factor


# --- design search -------------------------------------------------------------------------
def plot_design(ds, *, fig=None) -> Figure:
    """The first objective's statistic of every trial against each design variable (the
    best trial marked, the file's own design dashed); with several objectives, the
    Pareto front of the first two beside them. Two panels a row."""
    names = [k for k in ds.data_vars if ds[k].dims == ("trial",)
             and k not in ("wall_time_s", "pareto")]
    # a one-objective list comes back from a NetCDF file as a plain string
    objectives = [str(o) for o in np.atleast_1d(ds.attrs["objectives"])]
    panels = len(names) + (len(objectives) > 1)
    ncol = min(panels, 2)
    nrow = math.ceil(panels / ncol)
    fig = fig or Figure(figsize=(COLUMN_WIDTH_IN if ncol > 1 else 0.6 * COLUMN_WIDTH_IN,
                                 2.9 * nrow + 1.3), layout="constrained")
    axes = np.atleast_1d(fig.subplots(nrow, ncol, squeeze=False).ravel())
    for ax in axes[panels:]:
        ax.set_visible(False)
    ylabel, k = objective_axis(ds.attrs, objectives[0])
    stat, best = ds["statistic"].values[:, 0] * k, int(ds.attrs["best_trial"])
    colour = bar_colour(str(ds.attrs.get("bar", "")))
    for ax, name in zip(axes, names, strict=False):
        x = ds[name].values
        numeric = np.issubdtype(x.dtype, np.number)
        xlabel, kx = variable_axis(name)
        xs = x * kx if numeric else np.searchsorted(np.unique(x), x)
        ax.errorbar(xs, stat, yerr=ds["error"].values[:, 0] * k, fmt="o", ms=3.5, alpha=0.7,
                    lw=0.8, color=GREY, label="trials")
        ax.plot([xs[best]], [stat[best]], "*", color=colour, mec="black", mew=0.6, ms=15,
                label="best")
        ax.axhline(float(ds["published_statistic"].values[0]) * k, color=OKABE_ITO["black"],
                   ls="--", lw=1, label="file's design")
        if not numeric:
            ax.set_xticks(range(len(np.unique(x))), np.unique(x))
        ax.set_xlabel(xlabel)
        ax.set_ylabel(ylabel)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize="small")
    if len(objectives) > 1:
        _pareto_panel(axes[panels - 1], ds, objectives, colour)
    set_title(fig, f"design search, {ds.sizes['trial']} trials", ds.attrs,
              f"{ds.attrs['sampler']}, {ds.attrs['samples']} Monte Carlo samples each")
    return fig


def _pareto_panel(ax, ds, objectives, colour) -> None:
    kx, ky = objective_axis(ds.attrs, objectives[0]), objective_axis(ds.attrs, objectives[1])
    s = ds["statistic"].values[:, :2] * np.array([kx[1], ky[1]])
    front = ds["pareto"].values
    ax.plot(s[:, 0], s[:, 1], "o", ms=3.5, color=GREY, label="trials")
    order = np.argsort(s[front, 0])
    ax.plot(s[front, 0][order], s[front, 1][order], "o-", color=colour, ms=5,
            label="Pareto front")
    pub = ds["published_statistic"].values[:2] * np.array([kx[1], ky[1]])
    ax.plot([pub[0]], [pub[1]], "s", color=OKABE_ITO["black"], ms=8, label="file's design")
    near = np.concatenate([s[front], pub[None, :]])
    lo, hi = near.min(axis=0), near.max(axis=0)
    pad = 0.5 * (hi - lo) + 1e-30
    ax.set_xlim(lo[0] - pad[0], hi[0] + pad[0])  # the front, not the worst trials
    ax.set_ylim(lo[1] - pad[1], hi[1] + pad[1])
    ax.set_xlabel(kx[0])
    ax.set_ylabel(ky[0])
    ax.grid(alpha=0.3)
    ax.legend(fontsize="small")


def plot_best(cmp: dict, attrs: dict | None = None, *, fig=None) -> Figure:
    """The best design beside the file's own, in the first objective's own terms (``cmp``
    of :func:`boringbar.analysis.design.comparison`, its ``kind``): the chatter-free
    depth at the design's speeds (min_depth), the cut's chatter and amplitude over the
    samples (cut_amplitude), or the response (rms_band, frf_peak, min_real)."""
    draw = {"lobes": plot_depth_comparison, "cut": plot_cut_comparison,
            "response": plot_design_comparison}[cmp.get("kind", "response")]
    return draw(cmp, attrs, fig=fig)


def _best_style(cmp: dict) -> tuple:
    return bar_colour(cmp.get("bar", "")), "-", "o"


def plot_design_comparison(cmp: dict, attrs: dict | None = None, *, fig=None) -> Figure:
    """The best design's response beside the file's own design and the bare bar (``cmp``
    of :func:`boringbar.analysis.design.response_comparison`); ``attrs``, the design
    Dataset's attributes, name the bar and the preset in the title."""
    fig = fig or Figure(figsize=(COLUMN_WIDTH_IN, 4.0), layout="constrained")
    ax = fig.subplots()
    kind = cmp.get("bar", "")
    styles = {"best design": (bar_colour(kind), "-"), "file's design": (OKABE_ITO["black"], "--"),
              "bare bar": (BAR_STYLE["solid"]["color"], ":")}
    ylabel, k = COMPARISON_AXES[cmp["quantity"]]
    for name, y in cmp["curves"].items():
        colour, ls = styles.get(name, (OKABE_ITO["black"], "-"))
        ax.plot(cmp["x"], np.asarray(y) * k, ls, color=colour, lw=1.8,
                marker="o" if len(y) < 40 else None, ms=3.5, label=name)
    ax.set_xlabel(r"frequency ratio $\Omega/\omega_n$")
    ax.set_ylabel(ylabel + (f", F0 = {cmp['force_n']:g} N" if cmp.get("force_n") else ""))
    if cmp["quantity"] == "real_m_n":  # the objective is its most negative value: mark it
        for name, y in cmp["curves"].items():
            i = int(np.argmin(y))
            ax.plot([cmp["x"][i]], [y[i] * k], "v", color=styles.get(name, ("k",))[0], ms=7)
        ax.axhline(0.0, color=GREY, lw=0.8)
        # the designs' scale: the bare bar's resonance would flatten them
        designs = np.concatenate([np.asarray(y) * k for name, y in cmp["curves"].items()
                                  if name != "bare bar"])
        pad = 0.25 * (designs.max() - designs.min())
        ax.set_ylim(designs.min() - pad, designs.max() + pad)
    else:
        ax.set_yscale("log")
        ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))  # 0.2, not 2 x 10^-1
        ax.yaxis.set_minor_formatter(FuncFormatter(_minor_label))
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize="small")
    set_title(fig, "the best design against the file's own and the bare bar", attrs or {},
              cmp.get("nominal", "nominal values"))
    return fig


def plot_depth_comparison(cmp: dict, attrs: dict | None = None, *, fig=None) -> Figure:
    """min_depth's figure (``cmp`` of :func:`boringbar.analysis.design.depth_comparison`):
    each design's chatter-free depth at each design speed (bars side by side, the depth
    written on each), the first unstable depth above it (the bracket's top); a speed
    that did not chatter up to the search's maximum drawn to it, hatched; with several
    speeds, each design's minimum over them (the objective) dashed."""
    fig = fig or Figure(figsize=(COLUMN_WIDTH_IN, 4.0), layout="constrained")
    ax = fig.subplots()
    rpm = np.asarray(cmp["rpm"], dtype=float)
    x = np.arange(len(rpm))
    width = 0.35
    top = cmp["max_depth_m"] * 1e3
    styles = {"best design": _best_style(cmp), **DESIGN_STYLE}
    hatched = False
    for j, name in enumerate(cmp["limit_m"]):
        colour = styles[name][0]
        limit = np.asarray(cmp["limit_m"][name], dtype=float) * 1e3
        first = np.asarray(cmp["first_unstable_m"][name], dtype=float) * 1e3
        free = ~np.isfinite(limit)
        hatched |= bool(free.any())
        xs = x + (j - 0.5) * width
        low = cmp["min_depth_m"][name] * 1e3
        height = np.where(free, top, limit)
        bars = ax.bar(xs, height, width, color=colour, alpha=0.85 if j == 0 else 0.45,
                      edgecolor="black", lw=0.6, hatch=["//" if f else "" for f in free],
                      label=f"{name}: min {low:.3g} mm")
        ax.bar_label(bars, [f"{'>= ' if f else ''}{h:.3g}" for h, f in zip(height, free,
                                                                          strict=True)],
                     padding=6, fontsize="small")
        ok = np.isfinite(first) & ~free
        ax.errorbar(xs[ok], limit[ok], yerr=[np.zeros(ok.sum()), (first - limit)[ok]],
                    fmt="none", ecolor="black", capsize=3, lw=0.9)
        if len(rpm) > 1:
            ax.axhline(low, color=colour, ls=styles[name][1], lw=1.2)
    ax.set_xticks(x, [f"{r:g}" for r in rpm])
    ax.set_xlim(-0.8 if len(rpm) == 1 else -0.6, len(rpm) - (0.2 if len(rpm) == 1 else 0.4))
    ax.set_xlabel("design speed (rpm)")
    ax.set_ylabel("chatter-free depth of cut (mm)")
    ax.set_ylim(0, 1.2 * max(_finite_max(cmp, top), 1e-6))
    ax.grid(alpha=0.3, axis="y")
    fig.legend(loc="outside lower center", ncol=2, fontsize="small", frameon=False)
    crit = "the force reaches zero" if cmp.get("criterion") == "zero" else "bounded chatter"
    tol = cmp.get("depth_tolerance")
    set_title(fig, "chatter-free depth at the design speeds", attrs or {},
              f"{cmp.get('nominal', 'nominal values')}; the lobes' search"
              + (f" to {100 * tol:g} %" if tol else "") + f" (chatter: {crit}), "
              f"{cmp.get('duration_s', math.nan):g} s cuts; whisker: first unstable depth"
              + (f"; hatched: no chatter up to {top:g} mm" if hatched else ""))
    return fig


def _finite_max(cmp: dict, top: float) -> float:
    """The highest depth drawn (mm): the first unstable depths, or the search's maximum
    where a speed did not chatter."""
    values = [top if not np.isfinite(limit) else first
              for name in cmp["limit_m"]
              for limit, first in zip(np.asarray(cmp["limit_m"][name]) * 1e3,
                                      np.asarray(cmp["first_unstable_m"][name]) * 1e3,
                                      strict=True)]
    finite = [v for v in values if np.isfinite(v)]
    return max(finite) if finite else top


def plot_cut_comparison(cmp: dict, attrs: dict | None = None, *, fig=None) -> Figure:
    """cut_amplitude's figure (``cmp`` of :func:`boringbar.analysis.design.cut_comparison`):
    with the statistic chatter_probability, each design's probability of chatter with
    its Wilson interval beside the amplitudes; the amplitude of every sample's cut for
    the file's design and the best, each sample's pair joined (the same draws), a cut
    that chattered drawn as a cross, the statistic of each marked."""
    probability = cmp["statistic"] == "chatter_probability"
    fig = fig or Figure(figsize=(COLUMN_WIDTH_IN, 4.0), layout="constrained")
    axes = fig.subplots(1, 2, width_ratios=(1, 2)) if probability else [None, fig.subplots()]
    styles = {"best design": _best_style(cmp), **DESIGN_STYLE}
    names = ["file's design", "best design"]
    if probability:
        _chatter_panel(axes[0], cmp, names, styles)
    ax = axes[1]
    amplitude = {k: np.asarray(cmp["amplitude_m"][k], dtype=float) * 1e3 for k in names}
    chatter = {k: np.asarray(cmp["chatter"][k], dtype=float) for k in names}
    ax.plot([0, 1], np.vstack([amplitude[k] for k in names]), color=GREY, lw=0.7, alpha=0.6)
    for i, k in enumerate(names):
        hit = chatter[k] == 1
        ax.plot(np.full((~hit).sum(), i), amplitude[k][~hit], "o", color=styles[k][0],
                ms=5, mfc="none")
        ax.plot(np.full(hit.sum(), i), amplitude[k][hit], "x", color=styles[k][0], ms=7,
                mew=1.6)
        if not probability:
            ax.plot([i - 0.2, i + 0.2], [cmp["value"][k] * 1e3] * 2, color=styles[k][0], lw=2.2)
    ax.set_xticks([0, 1], names)
    ax.set_xlim(-0.5, 1.5)
    ax.set_ylabel("steady cut amplitude (mm)")
    positive = np.concatenate(list(amplitude.values()))
    positive = positive[positive > 0]
    if positive.size and positive.max() > 30 * positive.min():
        ax.set_yscale("log")
    ax.grid(alpha=0.3, axis="y")
    keys = [Line2D([], [], ls="none", marker="o", mfc="none", color=GREY, label="no chatter"),
            Line2D([], [], ls="none", marker="x", mew=1.6, color=GREY,
                   label="chatter (the cut's verdict)"),
            Line2D([], [], color=GREY, lw=0.7, label="one Monte Carlo draw, both designs")]
    if not probability:
        keys.append(Line2D([], [], color=GREY, lw=2.2, label=f"{cmp['statistic']} over the "
                                                              "samples"))
    fig.legend(handles=keys, loc="outside lower center", ncol=2, fontsize="small",
               frameon=False)
    where = (f"{cmp['rpm']:g} rpm, depth {cmp['depth_m'] * 1e3:g} mm, "
             if "rpm" in cmp else "")
    set_title(fig, "the cut: the best design and the file's", attrs or {},
              f"{where}{len(amplitude['best design'])} Monte Carlo samples")
    return fig


def _chatter_panel(ax, cmp: dict, names: list, styles: dict) -> None:
    """Each design's probability of chatter, with its Wilson interval."""
    level = round(100 * cmp.get("confidence", 0.95))
    for i, k in enumerate(names):
        flags = np.asarray(cmp["chatter"][k], dtype=float)
        p = float(np.mean(flags))
        ax.plot([i], [p], styles[k][2], color=styles[k][0], ms=8)
        if cmp["wilson"].get(k) is not None:
            lo, hi = cmp["wilson"][k]
            ax.errorbar([i], [p], yerr=[[p - lo], [hi - p]], color=styles[k][0], capsize=5,
                        lw=1.4)
        ax.annotate(f"{int(np.nansum(flags))} of {len(flags)}", (i, p), xytext=(8, 0),
                    textcoords="offset points", va="center", fontsize="small")
    ax.set_xticks([0, 1], [n.replace(" design", "") for n in names])
    ax.set_xlim(-0.6, 1.6)
    ax.set_ylim(-0.03, 1.03)
    ax.set_ylabel(f"P(chatter), Wilson {level} % interval")
    ax.grid(alpha=0.3, axis="y")


def _minor_label(value: float, _pos) -> str:
    """A log axis's minor tick labelled at 2, 3 and 5 times a power of ten only, so that
    the labels of a decade do not run into each other."""
    mantissa = value / 10 ** math.floor(math.log10(value)) if value > 0 else 0.0
    return f"{value:g}" if round(mantissa) in (2, 3, 5) else ""

"""Figures of a design search: the trials against each variable, the Pareto front, and
the best design beside the published one (the edge of the package, as plot.py).

Lengths are drawn in mm and receptances in um/N, like every other figure, though the
design Dataset holds SI units."""

from __future__ import annotations

import math

import numpy as np
from matplotlib.figure import Figure
from matplotlib.ticker import FuncFormatter

from boringbar.analysis.design_options import reading
from boringbar.plot_style import (
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
                   "receptance_m_n": (r"tip receptance |G| ($\mu$m/N)", 1e6)}


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


def plot_design_comparison(cmp: dict, attrs: dict | None = None, *, fig=None) -> Figure:
    """The best design's response beside the file's own design and the bare bar (``cmp``
    of :func:`boringbar.analysis.design.comparison`); ``attrs``, the design Dataset's
    attributes, name the bar and the preset in the title."""
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
    ax.set_yscale("log")
    ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))  # 0.2, not 2 x 10^-1
    ax.yaxis.set_minor_formatter(FuncFormatter(_minor_label))
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize="small")
    set_title(fig, "the best design against the file's own and the bare bar", attrs or {},
              "nominal values")
    return fig


def _minor_label(value: float, _pos) -> str:
    """A log axis's minor tick labelled at 2, 3 and 5 times a power of ten only, so that
    the labels of a decade do not run into each other."""
    mantissa = value / 10 ** math.floor(math.log10(value)) if value > 0 else 0.0
    return f"{value:g}" if round(mantissa) in (2, 3, 5) else ""

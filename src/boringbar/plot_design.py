"""Figures of a design search: the trials against each variable, the Pareto front, and
the best design beside the published one (the edge of the package, as plot.py)."""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure


# --- design search -------------------------------------------------------------------------
def plot_design(ds, *, fig=None) -> Figure:
    """The first objective's statistic of every trial against each design variable (the
    best trial marked, the file's own design dashed); with several objectives, the
    Pareto front of the first two beside them."""
    names = [k for k in ds.data_vars if ds[k].dims == ("trial",)
             and k not in ("wall_time_s", "pareto")]
    objectives = list(ds.attrs["objectives"])
    panels = len(names) + (len(objectives) > 1)
    fig = fig or Figure(figsize=(4.2 * panels, 3.8), layout="constrained")
    axes = np.atleast_1d(fig.subplots(1, panels))
    stat, best = ds["statistic"].values[:, 0], int(ds.attrs["best_trial"])
    for ax, name in zip(axes, names, strict=False):
        x = ds[name].values
        numeric = np.issubdtype(x.dtype, np.number)
        xs = x if numeric else np.searchsorted(np.unique(x), x)
        ax.errorbar(xs, stat, yerr=ds["error"].values[:, 0], fmt="o", ms=3, alpha=0.6, lw=0.6)
        ax.plot([xs[best]], [stat[best]], "*", color="#d84315", ms=14, label="best")
        ax.axhline(float(ds["published_statistic"].values[0]), color="0.3", ls="--", lw=1,
                   label="file's design")
        if not numeric:
            ax.set_xticks(range(len(np.unique(x))), np.unique(x))
        ax.set_xlabel(name)
        ax.set_ylabel(f"{ds.attrs['statistic']} of {objectives[0]}")
    axes[0].legend(fontsize=8)
    if len(objectives) > 1:
        _pareto_panel(axes[-1], ds, objectives)
    fig.suptitle(f"design search: {ds.sizes['trial']} trials ({ds.attrs['sampler']}, "
                 f"{ds.attrs['samples']} Monte Carlo samples each)", fontsize=10)
    return fig


def _pareto_panel(ax, ds, objectives) -> None:
    s, front = ds["statistic"].values, ds["pareto"].values
    ax.plot(s[:, 0], s[:, 1], "o", ms=3, color="0.6", label="trials")
    order = np.argsort(s[front, 0])
    ax.plot(s[front, 0][order], s[front, 1][order], "o-", color="#d84315", ms=5,
            label="Pareto front")
    pub = ds["published_statistic"].values
    ax.plot([pub[0]], [pub[1]], "s", color="#1565c0", ms=8, label="file's design")
    near = np.concatenate([s[front], pub[None, :2]])
    lo, hi = near.min(axis=0), near.max(axis=0)
    pad = 0.5 * (hi - lo) + 1e-30
    ax.set_xlim(lo[0] - pad[0], hi[0] + pad[0])  # the front, not the worst trials
    ax.set_ylim(lo[1] - pad[1], hi[1] + pad[1])
    ax.set_xlabel(f"{ds.attrs['statistic']} of {objectives[0]}")
    ax.set_ylabel(f"{ds.attrs['statistic']} of {objectives[1]}")
    ax.legend(fontsize=8)


def plot_design_comparison(cmp: dict, *, fig=None) -> Figure:
    """The best design's response beside the file's own design and the bare bar."""
    fig = fig or Figure(figsize=(7.0, 4.2), layout="constrained")
    ax = fig.subplots()
    styles = {"best design": ("#d84315", "-"), "file's design": ("#1565c0", "--"),
              "bare bar": ("0.4", ":")}
    for name, y in cmp["curves"].items():
        colour, ls = styles.get(name, ("k", "-"))
        ax.plot(cmp["x"], y, ls, color=colour, lw=1.6, marker="o" if len(y) < 40 else None,
                ms=3, label=name)
    ax.set_xlabel(cmp["xlabel"])
    ax.set_ylabel(cmp["ylabel"])
    ax.set_yscale("log")
    ax.legend(fontsize=8)
    ax.set_title("the best design against the file's own and the bare bar (nominal values)",
                 fontsize=9)
    return fig

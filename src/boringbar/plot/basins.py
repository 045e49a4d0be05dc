"""Basins of attraction: the attractor each start ends on, and the Poincare map from one
start."""

from __future__ import annotations

import json
import math

import numpy as np
from matplotlib.colors import BoundaryNorm, ListedColormap
from matplotlib.figure import Figure
from matplotlib.patches import Patch

from boringbar.plot.style import (
    COLUMN_WIDTH_IN,
    GREY,
    dropped_percent,
    series_colour,
    set_title,
    system_words,
)

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
              f"runs, first {dropped_percent(ds.attrs):g} % dropped, "
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


"""Figures of your own bar: its geometry and mode shapes, and a measured FRF against its
fit with the stabilisation diagram (the edge of the package).  Receptances are drawn in
um/N, lengths in mm; the lobes are :mod:`boringbar.plot.lobes`'."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure
from matplotlib.patches import Circle
from matplotlib.ticker import MaxNLocator

from boringbar.plot.style import (
    COLUMN_WIDTH_IN,
    DARK_GREY,
    GREY,
    OKABE_ITO,
    TITLE_PT,
    bar_colour,
    series_colour,
    system_label,
    wrap_title,
)

#: Receptance in the figures: um/N per m/N.
UM_PER_M = 1e6


# --- a bar's geometry and mode shapes -------------------------------------------------
def plot_modes(spec, cavity: bool, n_modes: int, title: str = "", *, fig=None) -> Figure:
    """The bar of the system file ``spec`` drawn to scale (sections, coolant bores,
    the cavity's section and its ball, the absorber) above its first ``n_modes``
    mode shapes (divided by their tip value), ball and absorber marked."""
    fig = fig or Figure(figsize=(8.0, 6.0), layout="constrained")
    geo, shp = fig.subplots(2, 1, sharex=True, height_ratios=(1, 2))
    bar = spec.stepped_bar(cavity)
    mm = 1e3
    for s in bar.sections:
        x = [s.start_m * mm, s.end_m * mm]
        geo.fill_between(x, -s.diameter_m / 2 * mm, s.diameter_m / 2 * mm, color="#b0bec5",
                         edgecolor="#455a64", lw=0.8)
        if s.inner_diameter_m > 0:
            geo.fill_between(x, -s.inner_diameter_m / 2 * mm, s.inner_diameter_m / 2 * mm,
                             color="white", edgecolor="#455a64", lw=0.5, ls="--")
    geo.axvline(0.0, color="black", lw=3)
    if cavity and spec.cavity is not None and spec.ball is not None:
        c, b = spec.cavity, spec.ball
        geo.add_patch(_circle((c.position_m * mm, 0.0), b.diameter_m / 2 * mm,
                              bar_colour("ball")))
        geo.annotate(f"ball {b.diameter_m * mm:g} mm {b.material}", (c.position_m * mm,
                     c.depth_m / 2 * mm), ha="center", va="bottom", fontsize=8)
    if spec.tmd is not None and not cavity:
        geo.plot([spec.tmd.position_m * mm], [0.0], "s", color=bar_colour("tmd"), ms=9,
                 label="absorber")
    geo.set_aspect("equal", adjustable="datalim")
    geo.set_ylabel("radius (mm)")
    geo.set_title(title or f"{system_label(spec.name)}: geometry and mode shapes")
    nodes, shapes, freqs = spec.mode_shapes(cavity, n_modes)
    for i in range(shapes.shape[1]):
        shp.plot(nodes * mm, shapes[:, i], color=series_colour(i),
                 label=f"mode {i + 1}: {freqs[i]:.1f} Hz")
    shp.axhline(0.0, color="0.6", lw=0.6)
    points = [("ball", spec.ball_position_m, bar_colour("ball"))] if cavity and spec.ball else []
    if spec.tmd is not None:
        points.append(("absorber", spec.absorber_position_m, bar_colour("tmd")))
    for name, z, colour in points:
        shp.axvline(z * mm, color=colour, ls=":", lw=1.0)
        shp.annotate(name, (z * mm, shp.get_ylim()[1]), color=colour, fontsize=8,
                     ha="center", va="top")
    shp.set_xlabel("z from the clamp (mm)")
    shp.set_ylabel("mode shape psi(z) / psi(tip)")
    shp.legend(fontsize=8, loc="lower left")
    return fig


def _circle(centre, radius, colour):
    return Circle(centre, radius, facecolor=colour, edgecolor="black", lw=0.6, alpha=0.8)


# --- measured FRFs ----------------------------------------------------------------------
def plot_frf_fit(frequency_hz, measured, fitted, fit, *, fig=None) -> Figure:
    """A measured tip receptance (points) against the fitted modal model (line), in um/N:
    magnitude on a log scale, real and imaginary parts; the fitted modes marked."""
    fig = fig or Figure(figsize=(8.0, 7.5), layout="constrained")
    mag, re, im = fig.subplots(3, 1, sharex=True)
    f = np.asarray(frequency_hz)
    step = max(1, len(f) // 1500)  # points enough to see the scatter
    measured, fitted = np.asarray(measured) * UM_PER_M, np.asarray(fitted) * UM_PER_M
    for ax, fn in ((mag, np.abs), (re, np.real), (im, np.imag)):
        ax.plot(f[::step], fn(measured[::step]), ".", ms=2.5, color=GREY, label="measured")
        ax.plot(f, fn(fitted), color=OKABE_ITO["vermillion"], lw=1.2, label="fitted modes")
        for fi in fit.frequency_hz:
            ax.axvline(fi, color=OKABE_ITO["blue"], lw=0.6, ls=":")
    mag.set_yscale("log")
    mag.set_ylabel(r"|H| ($\mu$m/N)")
    re.set_ylabel(r"Re H ($\mu$m/N)")
    im.set_ylabel(r"Im H ($\mu$m/N)")
    im.set_xlabel("frequency (Hz)")
    modes = ", ".join(f"{a:.1f} Hz / {z * 100:.2f} % / {k:.3g} N/m" for a, z, k in
                      zip(fit.frequency_hz, fit.damping_ratio, fit.modal_stiffness_n_m,
                          strict=True))
    mag.set_title(f"tip FRF: measured and fitted ({modes}); residual "
                  f"{fit.quality.get('relative_residual', math.nan):.2g}", fontsize=9)
    mag.legend(fontsize=8)
    return fig


def plot_stabilisation(diagram, fitted_hz=(), *, fig=None) -> Figure:
    """The stabilisation diagram of analysis.frf_fit (a ``Stabilisation``): each
    pole at its frequency and model order, by status (new, stable in frequency,
    stable), the poles of the columns that are modes filled, the modes' frequencies
    as vertical lines (solid: among ``fitted_hz``, dashed: not fitted), the measured
    |H| (um/N) behind on a log scale."""
    fig = fig or Figure(figsize=(COLUMN_WIDTH_IN, 5.0), layout="constrained")
    ax = fig.subplots()
    back = ax.twinx()
    f = diagram.frf.frequency_hz
    back.plot(f, np.abs(diagram.frf.receptance) * UM_PER_M, color=GREY, lw=0.9, alpha=0.6)
    back.set_yscale("log")
    back.set_ylabel(r"|H| ($\mu$m/N)", color=DARK_GREY)
    ax.set_zorder(back.get_zorder() + 1)  # the poles in front of the FRF
    ax.patch.set_visible(False)
    status, in_mode = diagram.status, diagram.mode >= 0
    mode_colour = OKABE_ITO["vermillion"]
    # a marker shape per status, so that colour is not needed to tell them apart
    styles = ((".", GREY), ("x", OKABE_ITO["sky blue"]), ("o", OKABE_ITO["blue"]))
    groups = [((status == code) & ~in_mode, *style, name) for code, (style, name)
              in enumerate(zip(styles, diagram.STATUS_NAMES, strict=True))]
    for mask, marker, colour, label in [*groups, (in_mode, "o", mode_colour,
                                                  "a mode's column")]:
        ax.plot(diagram.frequency_hz[mask], diagram.order[mask], marker, ms=4.5,
                color=colour, mfc=colour if colour == mode_colour else "none",
                ls="none", label=label)
    _mark_modes(ax, diagram, fitted_hz, mode_colour)
    ax.set_xlim(f[0], f[-1])
    ax.set_ylim(0, diagram.max_order + 3)
    ax.set_xlabel("frequency (Hz)")
    ax.set_ylabel("model order (pole pairs)")
    ax.yaxis.set_major_locator(MaxNLocator(integer=True))
    name = Path(diagram.frf.source.get("file", "measured FRF")).name
    s = diagram.summary()
    title = (f"{name}: stabilisation diagram of the {s['method']} poles\n"
             f"{len(s['modes'])} mode(s): columns stable at {s['min_stable_orders']}+ of "
             f"{s['max_order']} orders (frequency {s['stable_frequency']:.0%}, damping "
             f"{s['stable_damping']:.0%})")
    ax.set_title(wrap_title(title, fig.get_figwidth()), fontsize=TITLE_PT)
    ax.legend(fontsize="small", loc="lower right", framealpha=0.9)
    return fig


def _mark_modes(ax, diagram, fitted_hz, colour) -> None:
    """The diagram's modes as vertical lines (solid: fitted, dashed: not), each with
    its frequency and damping above the top order."""
    fitted = np.asarray(fitted_hz, dtype=float)
    labels = {True: "fitted mode", False: "mode not fitted"}
    for m in diagram.modes:
        used = bool(np.any(np.isclose(fitted, m.frequency_hz, rtol=1e-9)))
        ax.axvline(m.frequency_hz, color=colour, lw=0.7, ls="-" if used else "--",
                   alpha=0.7, zorder=1, label=labels.pop(used, None))
        ax.annotate(f"{m.frequency_hz:.1f} Hz\n{m.damping_ratio * 100:.2f} %",
                    (m.frequency_hz, diagram.max_order + 0.6), fontsize="small",
                    ha="center", va="bottom", color=colour, annotation_clip=False,
                    bbox={"fc": "white", "ec": "none", "pad": 0.5})

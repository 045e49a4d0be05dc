"""What every figure shares (every module of plot/): the
colour-blind-safe palette, the colour and line of each bar, the size of a figure meant for
one column of the report, the bar a figure is about, and its wrapped title.

The palette is Okabe and Ito's ("Color Universal Design", 2008): eight colours that
people with any of the common colour-vision deficiencies still tell apart. The solid bar,
the ball-damped bar and the TMD bar take three of them and three line styles, so a
figure reads in grey too. Figures are sized in inches for the report's column (about
650 px at a 1400 px window): a 7.2 in figure shown there draws matplotlib's 10 pt at
about 13 px and its "small" legends at about 11 px.
"""

from __future__ import annotations

import json
import math
import re
import textwrap

import numpy as np
from matplotlib.text import Text

from boringbar.model.system_file import PUBLISHED_NAME
from boringbar.plot.palette import BAR_STYLE, CYCLE, DARK_GREY, GREY, OKABE_ITO  # noqa: F401 (shared)

#: Width (in) of a figure shown in one of the report's two columns.
COLUMN_WIDTH_IN = 7.2
NBSP = "\u00a0"  # no break here: textwrap splits at ASCII whitespace only
#: The spaces a title keeps: around "=", and between a number and its unit.
_KEEP = re.compile(r"(?<= =)\s|\s(?==)|(?<=\d)\s(?=[A-Za-z%$])")
#: Title size (pt): matplotlib's "large" would wrap most titles at the column's width.
TITLE_PT = 11.0


def series_colour(i: int) -> str:
    """The ``i``-th colour of :data:`CYCLE` (it repeats after eight)."""
    return CYCLE[i % len(CYCLE)]


def bar_colour(kind: str) -> str:
    """The colour of a bar kind ("solid", "tmd", "ball", "locked"); black if unknown."""
    return BAR_STYLE.get(kind, {"color": OKABE_ITO["black"]})["color"]


def bar_name(attrs: dict) -> str:
    """The bar a result is about, from its attributes: the name of the system file its
    systems were built from ("published bar" for the published one, which the presets
    build from), several joined by " + "; "published bar" when the attributes name no
    system file (the corrections' ladder, which is the published bar by construction)."""
    names: list[str] = []
    for value in attrs.values():
        if isinstance(value, str) and value[:1] in "{[":
            try:
                _system_file_names(json.loads(value), names)
            except ValueError:  # a text attribute that only starts like JSON
                continue
    return " + ".join(system_label(n) for n in dict.fromkeys(names)) or "published bar"


def system_label(name: str) -> str:
    """A system file's name as a figure names it: "published bar" for the published one."""
    return "published bar" if name == PUBLISHED_NAME else name


def _system_file_names(obj, names: list[str]) -> None:
    """Append the name of every system file in a parsed JSON attribute."""
    if isinstance(obj, dict):
        spec = obj.get("system_file")
        if isinstance(spec, dict) and spec.get("name"):
            names.append(str(spec["name"]))
        for v in obj.values():
            if isinstance(v, dict | list):
                _system_file_names(v, names)
    elif isinstance(obj, list):
        for v in obj:
            _system_file_names(v, names)


def wrap_title(text: str, width_in: float, size_pt: float = TITLE_PT) -> str:
    """``text`` with each line wrapped to ``width_in`` inches at ``size_pt`` points (an
    average character of the sans-serif font is about 0.52 of its size wide), so that a
    title is never cut at the figure's edges; "a = b" and "0.5 mm" are not broken."""
    per_line = max(20, int(width_in * 72 / (0.52 * size_pt)))
    lines = (textwrap.fill(_KEEP.sub(NBSP, line), per_line, break_on_hyphens=False) or line
             for line in text.split("\n"))
    return "\n".join(lines).replace(NBSP, " ")


def set_title(fig, what: str, attrs: dict, details: str = "") -> None:
    """The figure's title: ``what``, then the bar (:func:`bar_name`) and the preset from
    ``attrs``, then ``details`` on its own line; wrapped to the figure's width."""
    preset = attrs.get("preset")
    line1 = f"{bar_name(attrs)}" + (f", {preset} preset" if preset else "") + f": {what}"
    width = fig.bbox.width / fig.dpi  # a SubFigure's own width, in inches
    text = line1 + ("\n" + details if details else "")
    fig.suptitle(wrap_title(text, width), fontsize=TITLE_PT)


def smallest_text_px(fig, shown_width_px: float) -> float:
    """The font size (CSS px) of the smallest text drawn in ``fig`` when the figure is
    shown ``shown_width_px`` wide (as a page scales its PNG): its smallest size in
    points times the shown pixels per inch over 72. Draws the figure first, so that
    tick labels exist; text in hidden axes and empty text are not counted."""
    fig.draw_without_rendering()
    sizes = [t.get_fontsize() for t in fig.findobj(Text) if t.get_visible()
             and t.get_text().strip() and (t.axes is None or t.axes.get_visible())]
    return min(sizes) * shown_width_px / (72 * fig.get_figwidth())


def system_words(system: dict) -> str:
    """'ball damper (carbide), gap 0.1 mm, friction off, e = 0.7' from System.to_dict(),
    with ', rolling (mu_s 0.2, mu_k 0.15)' and ', Hertz contact' where the ball has them."""
    kind = system.get("kind", "?")
    damper = system.get("damper") or {}
    if kind in ("ball", "locked"):
        fr = damper.get("friction_force_n", 0.0)
        words = (f"{'locked ball' if kind == 'locked' else 'ball damper'} "
                 f"({damper.get('material', '?')}), gap {damper.get('gap_m', math.nan) * 1e3:g} "
                 f"mm, friction {f'{fr:.3g} N' if fr else 'off'}, "
                 f"e = {damper.get('restitution', math.nan):g}")
        if damper.get("motion") == "roll":
            words += (f", rolling (mu_s{NBSP}{damper.get('mu_static', math.nan):g}, "
                      f"mu_k{NBSP}{damper.get('mu_kinetic', math.nan):g})")
        if damper.get("contact") == "hertz":
            words += ", Hertz contact"
        return words
    return {"solid": "solid bar", "tmd": "TMD bar"}.get(kind, str(kind))


def case_title(label: str, bar: str, gap: float, friction: str) -> str:
    """'ball gap=0.5mm friction=on' -> 'ball damper, gap 0.5 mm, friction on'."""
    if bar == "ball":
        return f"ball damper, gap {gap * 1e3:g} mm, friction {friction}"
    return {"solid": "solid bar", "tmd": "TMD bar"}.get(bar, str(label))


def legend_below(fig, axes, ncol: int | None = None, order=None) -> None:
    """One legend below the panels, each label once, from every axis in ``axes``, in the
    order drawn or sorted by the key ``order`` of a label; ``ncol`` columns (default: one
    row)."""
    entries: dict[str, object] = {}
    for ax in np.ravel(axes):
        for h, lab in zip(*ax.get_legend_handles_labels(), strict=True):
            entries.setdefault(lab, h)
    labels = list(entries) if order is None else sorted(entries, key=order)
    if labels:
        fig.legend([entries[k] for k in labels], labels, loc="outside lower center",
                   ncol=ncol or len(labels), fontsize="small", frameon=False)


def zero_based(ax, values) -> None:
    """y from 0 to a little above the largest finite value."""
    top = np.nanmax(values) if np.isfinite(values).any() else 0.0
    ax.set_ylim(0, 1.1 * top if top > 0 else 1.0)


#: Marker and colour per impact-pattern class (patterns.PATTERN_LABELS): the shapes
#: tell the classes apart without colour, the colours (Okabe-Ito) without shape.
PATTERN_STYLE = {
    "no impact": ("o", GREY),
    "symmetric": ("s", OKABE_ITO["sky blue"]),
    "asymmetric": ("^", OKABE_ITO["orange"]),
    "sticking": ("D", OKABE_ITO["yellow"]),
    "no impact with sticking": ("v", OKABE_ITO["reddish purple"]),
    "non-uniform": ("X", OKABE_ITO["black"]),
    "": ("o", "white"),  # no pattern (locked ball)
}


def pattern_class(name: str) -> str:
    """'2 symmetric' -> 'symmetric', '3 asymmetric (period 2)' -> 'asymmetric'."""
    return re.sub(r"^\d+\s+|\s*\(period \d+\)$", "", str(name)).strip()



def dropped_percent(attrs) -> float:
    """The dropped first part of each run, in %: 1 - steady_fraction (files written
    before steady_fraction: their ``drop``)."""
    if "steady_fraction" in attrs:
        return 100 * (1.0 - attrs["steady_fraction"])
    return 100 * attrs.get("drop", math.nan)


#: the integrators as a title names them
INTEGRATOR_WORDS = {"rk4": "RK4", "exact": "the exact integrator"}


def method_words(a: dict) -> str:
    """The converged verdict's method in a few words for a figure's title (the whole of
    it, every cap and confidence, is the file's ``method_text`` and the command's summary
    line); another criterion's method as it is."""
    if a.get("criterion") != "growth" or "tolerance_m" not in a or "knock_m" not in a:
        return a.get("method_text", "")
    dt = f", dt = {a['dt_s'] * 1e6:g} us" if "dt_s" in a else ""
    used = str(a.get("integrator_used", a.get("integrator", "?")))
    knocks = [float(a["knock_m"]), *json.loads(a.get("knocks_m", "[]"))]
    sizes = " and ".join(f"{k * 1e6:g}" for k in knocks)
    after = f"a {sizes} um knock" if len(knocks) == 1 else f"knocks of {sizes} um"
    return (f"converged verdict: settled within {a['tolerance_m'] * 1e6:g} um p-p with the "
            f"tool in the cut, after {after}; {INTEGRATOR_WORDS.get(used, used)}{dt}")

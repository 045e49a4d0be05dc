"""The design page's Bokeh figures: each built once per session with its data sources,
then redrawn by replacing the sources' data with a view's arrays (the browser
receives the new columns only, not a new figure).

Colours: the report's (:mod:`boringbar.plot.palette`, Okabe-Ito, colour-blind safe); the
pinned design is drawn in the same colour as the current one, dashed.
"""

from __future__ import annotations

import numpy as np
from bokeh.models import (
    BasicTicker,
    ColumnDataSource,
    FixedTicker,
    HoverTool,
    Legend,
    LegendItem,
    NumeralTickFormatter,
    Range1d,
    Span,
    Title,
)
from bokeh.plotting import figure

from boringbar.plot.palette import (
    BAR_STYLE,
    DARK_GREY,
    GREY,
    OKABE_ITO,
    lobe_depth_top,
    speed_axis,
)

#: one colour per bar, the report's (boringbar.plot.palette)
COLOURS = {**{k: v["color"] for k, v in BAR_STYLE.items()}, "wall": GREY}
LABELS = {k: v["label"] for k, v in BAR_STYLE.items()}
WALLS = {1.0: OKABE_ITO["reddish purple"], -1.0: OKABE_ITO["sky blue"]}
TOOLS = "pan,wheel_zoom,box_zoom,reset,save"
KINDS = ("solid", "ball", "tmd")
#: each bar in the lobes' readout (the ball bar's analytic curve is its linear host's)
READOUT = {"solid": "solid", "ball": "ball bar's onset (small vibrations, the ball off its walls)",
           "tmd": "TMD"}


def new_figure(title: str, x: str, y: str, **kw):
    fig = figure(title=title, x_axis_label=x, y_axis_label=y, tools=TOOLS,
                 sizing_mode="stretch_width", height=kw.pop("height", 260), **kw)
    fig.title.text_font_size = "13px"
    fig.toolbar.logo = None
    return fig


def shown(fig, renderer, visible: bool) -> None:
    """Show or hide ``renderer`` and its legend entry (a curve with nothing to draw)."""
    renderer.visible = visible
    for item in fig.legend.items:
        if renderer in item.renderers:
            item.visible = visible


def show_progress(bar, done: int, total: int) -> None:
    """A progress indicator at ``done`` of ``total`` (a total of 0 shows an empty bar)."""
    bar.max = max(total, 1)
    bar.value = min(done, bar.max)


def _empty(*names, name: str | None = None) -> ColumnDataSource:
    """An empty source of columns ``names`` (``name``: how a browser test finds it)."""
    return ColumnDataSource({n: [] for n in names}, name=name)


class BarFigure:
    """The bar to scale (mm): sections, bore, cavity, ball and absorber."""

    def __init__(self):
        self.fig = new_figure("bar to scale", "distance from the clamp (mm)", "radius (mm)",
                           height=220, match_aspect=True)
        self.steel = _empty("left", "right", "bottom", "top")
        self.holes = _empty("left", "right", "bottom", "top")
        self.ball = _empty("x", "y", "r")
        self.tmd = _empty("x", "y")
        self.fig.quad(source=self.steel, color="#BBBBBB", line_color="#444444")
        self.fig.quad(source=self.holes, color="white", line_color="#444444")
        self.fig.circle(source=self.ball, radius="r", color=COLOURS["ball"], alpha=0.8)
        self.fig.scatter(source=self.tmd, marker="square", size=14, color=COLOURS["tmd"],
                         legend_label="absorber")
        self.fig.legend.location = "bottom_left"

    def show(self, view: dict) -> None:
        s = view["sections"]
        self.steel.data = {"left": [x["z0"] for x in s], "right": [x["z1"] for x in s],
                           "bottom": [-x["d"] / 2 for x in s], "top": [x["d"] / 2 for x in s]}
        holes = [(x["z0"], x["z1"], x["bore"] / 2) for x in s if x["bore"] > 0]
        cav = view["cavity"]
        if cav is not None:
            holes.append((cav["z0"], cav["z1"], cav["depth"] / 2))
        self.holes.data = {"left": [h[0] for h in holes], "right": [h[1] for h in holes],
                           "bottom": [-h[2] for h in holes], "top": [h[2] for h in holes]}
        b = view["ball"]
        self.ball.data = {"x": [b["z"]], "y": [0.0], "r": [b["d"] / 2]} if b else \
            {"x": [], "y": [], "r": []}
        t = view["tmd"]
        self.tmd.data = {"x": [t["z"]], "y": [0.0]} if t else {"x": [], "y": []}


class ModesFigure:
    """The first mode shapes, tip deflection 1."""

    def __init__(self, n: int = 3):
        self.fig = new_figure("mode shapes", "distance from the clamp (mm)",
                           "deflection / tip deflection", height=200)
        palette = (OKABE_ITO["black"], OKABE_ITO["orange"], OKABE_ITO["reddish purple"])
        self.sources = [_empty("z", "w") for _ in range(n)]
        self.lines = [self.fig.line("z", "w", source=src, color=palette[i], line_width=2,
                                    legend_label=f"mode {i + 1}")
                      for i, src in enumerate(self.sources)]
        self.fig.legend.location = "top_left"

    def show(self, view: dict) -> None:
        sh = view["shapes"]
        for i, src in enumerate(self.sources):
            src.data = {"z": sh["z"], "w": sh["w"][i]} if i < len(sh["w"]) else \
                {"z": [], "w": []}
            shown(self.fig, self.lines[i], i < len(sh["w"]))


class RunFigures:
    """One run: tip and ball (or absorber) against time, impacts by phase, energies."""

    def __init__(self):
        self.tip = new_figure("tip displacement (last periods)", "time (ms)", "tip (mm)")
        self.aux = new_figure("ball between the walls", "time (ms)", "ball relative to bar (mm)",
                           x_range=self.tip.x_range)
        self.impacts = new_figure("impacts: phase in the forcing period", "forcing period (-)",
                               "phase (periods)", y_range=(0, 1))
        self.energy = new_figure("energy over the run (J)", "J", "", height=220,
                              y_range=["forcing work", "viscous", "impacts", "friction"])
        self.src = {k: _empty("t", "y", name=f"run-{k}") for k in ("tip", "aux", "pin_tip")}
        self.walls = (Span(dimension="width", line_color=COLOURS["wall"], line_dash="dashed"),
                      Span(dimension="width", line_color=COLOURS["wall"], line_dash="dashed"))
        self.tip.line("t", "y", source=self.src["tip"], color=COLOURS["ball"], line_width=1.5)
        self.pin_line = self.tip.line("t", "y", source=self.src["pin_tip"], color="#444444",
                                      line_dash="dashed", legend_label="pinned design")
        self.aux.line("t", "y", source=self.src["aux"], color=COLOURS["ball"])
        for s in self.walls:
            self.aux.add_layout(s)
        self.hits = _empty("cycle", "phase", "colour")
        self.impacts.scatter("cycle", "phase", source=self.hits, color="colour", size=5)
        self.bars = _empty("what", "joule")
        self.energy.hbar(y="what", right="joule", source=self.bars, height=0.6,
                         color=COLOURS["ball"])

    def show(self, view: dict, pinned: dict | None) -> None:
        colour = COLOURS[view["bar"]]
        self.src["tip"].data = {"t": view["t_ms"], "y": view["tip_mm"]}
        self.src["aux"].data = {"t": view["t_ms"], "y": view["aux_mm"]}
        self.tip.renderers[0].glyph.line_color = colour
        self.src["pin_tip"].data = {"t": pinned["t_ms"], "y": pinned["tip_mm"]} if pinned \
            else {"t": [], "y": []}
        shown(self.tip, self.pin_line, pinned is not None)
        self.aux.title.text = {"ball": "ball between the walls (dashed)",
                               "absorber": "absorber relative to the bar"}.get(
                                   view["aux"], "no damper")
        half = view["half_gap_mm"]
        for s, sign in zip(self.walls, (1, -1), strict=True):
            s.location, s.visible = (sign * half if half else 0.0), half is not None
        self.hits.data = {"cycle": view["impact_cycle"], "phase": view["impact_phase"],
                          "colour": [WALLS[w] for w in view["impact_wall"]]}
        e = view["energy"]
        self.bars.data = {"what": ["forcing work", "viscous", "impacts", "friction"],
                          "joule": [e.get("work_force_j", 0.0), e.get("dissipated_viscous_j", 0.0),
                                    e.get("dissipated_impacts_j", 0.0),
                                    e.get("dissipated_friction_j", 0.0)]}


class ResponseFigure:
    """Tip RMS against forcing frequency: the ball bar's simulated points, the solid
    and TMD bars' closed-form curves; the pinned design dashed."""

    def __init__(self):
        self.fig = new_figure("tip RMS response", "forcing frequency (Hz)", "tip RMS (mm)",
                           height=300)
        self.src, self.lines = {}, {}
        for kind in KINDS:
            for pin in ("", "pin_"):
                cols = ("f", "y", "pattern") if kind == "ball" else ("f", "y")
                src = self.src[pin + kind] = _empty(*cols, name=f"response-{pin}{kind}")
                self.lines[pin + kind] = self.fig.line(
                    "f", "y", source=src, color=COLOURS[kind], line_width=2,
                    line_dash="dashed" if pin else "solid",
                    legend_label=LABELS[kind] + (" (pinned)" if pin else ""))
                if kind == "ball":
                    self.fig.scatter("f", "y", source=src, color=COLOURS["ball"], size=7)
        self.fig.add_tools(HoverTool(tooltips=[("f", "@f{0.0} Hz"), ("RMS", "@y{0.0000} mm"),
                                               ("pattern", "@pattern")]))
        self.fig.legend.click_policy = "hide"
        self.fig.legend.location = "top_right"

    def show(self, view: dict, pinned: dict | None) -> None:
        for pin, v in (("", view), ("pin_", pinned)):
            for kind in ("solid", "tmd"):
                curve = (v or {}).get("curves", {}).get(kind)
                self._put(pin + kind, None if curve is None else {"f": v["f_hz"], "y": curve})
            has = v is not None and "ball_f_hz" in v
            self._put(pin + "ball", {"f": v["ball_f_hz"], "y": v["ball_rms_mm"],
                                     "pattern": v["ball_pattern"]} if has else None)

    def _put(self, key: str, data: dict | None) -> None:
        """A curve's data, or (None) no curve and no legend entry."""
        self.src[key].data = data or {k: [] for k in self.src[key].data}
        shown(self.fig, self.lines[key], data is not None)


class LobesFigure:
    """Chatter-free depth against spindle speed: analytic per bar (the ball bar's linear
    host), the ball bar's simulated points, and the design's speed: a vertical line, each
    bar's depth there marked on its curve and read out in a line above the plot (Bokeh
    draws no label outside the plot's frame, and inside it one would cover curves).
    Depth on a linear axis from 0 whose top follows the curves
    (:func:`~boringbar.plot.palette.lobe_depth_top`, the title saying where peaks are cut);
    speed on :func:`~boringbar.plot.palette.speed_axis`'s axis (log, labelled at 1, 1.5, 2,
    3, 5 and 7 of each decade); the legend below the plot, off the curves."""

    TITLE = "stability lobes (chatter-free below the curves)"

    def __init__(self):
        self.fig = new_figure(self.TITLE, "spindle speed (rpm, log scale)", "depth of cut (mm)",
                              height=400, x_axis_type="log", x_range=Range1d(900, 40000),
                              y_range=Range1d(0, 1))
        self.fig.xaxis.formatter = NumeralTickFormatter(format="0")
        self.src, self.lines, items = {}, {}, []
        for kind in KINDS:
            for pin in ("", "pin_"):
                src = self.src[pin + kind] = _empty("rpm", "b", name=f"lobes-{pin}{kind}")
                label = LABELS[kind] + (": onset, the ball off its walls" if kind == "ball"
                                        else "")
                self.lines[pin + kind] = self.fig.line(
                    "rpm", "b", source=src, color=COLOURS[kind], line_width=2,
                    line_dash="dashed" if pin else "solid")
                items.append(LegendItem(label=label + (" (pinned)" if pin else ""),
                                        renderers=[self.lines[pin + kind]]))
        self.sim = _empty("rpm", "b", name="lobes-simulated")
        self.sim_line = self.fig.line("rpm", "b", source=self.sim, color=COLOURS["ball"],
                                      line_width=3, line_dash="dotted")
        self.fig.scatter("rpm", "b", source=self.sim, color=COLOURS["ball"], size=8,
                         marker="diamond")
        items.append(LegendItem(label="ball damper, simulated cuts", renderers=[self.sim_line]))
        self.speed = Span(dimension="height", line_color=DARK_GREY, line_dash="dashdot",
                          line_width=1.5)
        self.fig.add_layout(self.speed)
        self.at = _empty("rpm", "b", "colour", name="lobes-at-rpm")
        at_dot = self.fig.scatter("rpm", "b", source=self.at, color="colour", size=9,
                                  line_color="black")
        items.append(LegendItem(label="your speed: depth there", renderers=[at_dot]))
        self.readout = Title(text="", text_font_size="13px", text_font_style="normal",
                             text_color=DARK_GREY, name="lobes-readout")
        self.fig.add_layout(self.readout, "above")
        self.fig.add_layout(Legend(items=items, orientation="horizontal", ncols=3,
                                   location="center", click_policy="hide",
                                   label_text_font_size="12px"), "below")
        shown(self.fig, self.sim_line, False)  # until the ball bar's cuts are simulated
        self.curves: list = []  #: (rpm, depth mm) of every analytic curve drawn
        self.depths: dict[str, float] = {}  #: the analytic depths at the design's speed (mm)
        self.simulated: float | None = None  #: the simulated ball bar's depth there (mm)

    def show(self, view: dict, pinned: dict | None) -> None:
        self.curves = []
        for pin, v in (("", view), ("pin_", pinned)):
            for kind in KINDS:
                curve = (v or {}).get("curves", {}).get(kind)
                key = pin + kind
                self.src[key].data = {"rpm": v["rpm"], "b": curve} if curve is not None \
                    else {"rpm": [], "b": []}
                shown(self.fig, self.lines[key], curve is not None)
                if curve is not None:
                    self.curves.append((v["rpm"], curve))
        at = self.speed.location = view["at_rpm"]
        self.depths = view["depth_at_mm"]
        self.at.data = {"rpm": [at] * len(self.depths), "b": list(self.depths.values()),
                        "colour": [COLOURS[k] for k in self.depths]}
        self._axes()

    def show_simulated(self, sim: dict | None) -> None:
        self.sim.data = {"rpm": sim["rpm"], "b": sim["limit_mm"]} if sim else \
            {"rpm": [], "b": []}
        shown(self.fig, self.sim_line, sim is not None)
        self.simulated = sim["depth_at_mm"] if sim else None
        if self.curves:
            self._axes()

    def _axes(self) -> None:
        """Both axes' ranges and ticks for the curves and simulated points drawn, the
        title's note of peaks cut, and the readout."""
        drawn = [*self.curves, *([(self.sim.data["rpm"], self.sim.data["b"])]
                                 if len(self.sim.data["rpm"]) else [])]
        log, ticks, (left, right) = speed_axis(min(float(np.min(r)) for r, _ in drawn),
                                               max(float(np.max(r)) for r, _ in drawn))
        self.fig.xaxis.ticker = FixedTicker(ticks=list(ticks)) if log else BasicTicker()
        self.fig.x_range.update(start=left, end=right, reset_start=left, reset_end=right)
        top, peak = lobe_depth_top([b for _, b in drawn], [np.min(b) for _, b in self.curves])
        self.fig.y_range.update(start=0, end=top, reset_start=0, reset_end=top)
        self.fig.title.text = self.TITLE + ("" if peak is None else
                                            f"; depth axis cut at {top:.3g} mm, near the "
                                            f"pockets (peaks up to {peak:.3g} mm above it)")
        self._read_out()

    def _read_out(self) -> None:
        """The depths at the design's speed, in the line above the plot."""
        parts = [f"{READOUT[k]} {d:.3g} mm" for k, d in self.depths.items()]
        if self.simulated is not None:
            parts.append("ball, simulated cuts " + (f"{self.simulated:.3g} mm"
                                                    if np.isfinite(self.simulated) else
                                                    "no chatter up to the deepest cut"))
        self.readout.text = (f"your speed {self.speed.location:g} rpm (dash-dot line): "
                             + ", ".join(parts) if self.depths else "")
